//! The GLB container: header, JSON chunk and binary chunk.

use std::borrow::Cow;
use std::io::{IoSlice, Write};

use super::extras::JsonText;
use super::layout::Layout;
use crate::{Error, Result};

/// The largest GLB file: its header stores lengths as 32-bit numbers.
pub const GLB_LIMIT: u64 = u32::MAX as u64;

/// The GLB container around a glTF JSON text (padded to 4 bytes) and a binary chunk (empty:
/// none): an [`Error::Export`] naming the limit when the file would pass `limit` bytes
/// ([`GLB_LIMIT`] when exporting; a smaller one in tests), never a truncated length.
pub fn glb_container(text: &[u8], bin: Vec<u8>, limit: u64) -> Result<Vec<u8>> {
    let write_text = |dst: &mut [u8]| dst.copy_from_slice(text);
    glb_file(text.len(), write_text, bin.len(), limit, |dst| {
        dst.copy_from_slice(&bin)
    })
}

/// The GLB file of a glTF JSON text of `text_len` bytes (padded to 4 bytes) and a binary
/// chunk of `bin_len` bytes (0: none) that `write_text` and `write_bin` write in place into
/// the file's zeroed bytes (at the same time, on the rayon pool), so that the file is
/// allocated once, at its size, and neither chunk copied. The zeroed
/// allocation costs no pass of its own: the allocator hands out fresh zero pages for a large
/// one, and they are first touched where the chunk is written. As [`glb_container`] past
/// `limit`.
pub(super) fn glb_file(
    text_len: usize,
    write_text: impl FnOnce(&mut [u8]) + Send,
    bin_len: usize,
    limit: u64,
    write_bin: impl FnOnce(&mut [u8]) + Send,
) -> Result<Vec<u8>> {
    let heads = Heads::new(text_len, bin_len, limit)?;
    let mut out = vec![0u8; heads.total as usize];
    let (head, rest) = out.split_at_mut(20);
    head.copy_from_slice(&heads.file);
    let (json, rest) = rest.split_at_mut(text_len);
    if bin_len > 0 {
        let (bin_head, bin) = rest.split_at_mut(8);
        bin_head.copy_from_slice(&heads.bin);
        rayon::join(|| write_text(json), || write_bin(bin));
    } else {
        write_text(json);
    }
    Ok(out)
}

/// The fixed bytes of a GLB file: its header with the JSON chunk's, and the binary chunk's.
struct Heads {
    /// The file's length.
    total: u64,
    /// `glTF`, version 2, the file's length, the JSON chunk's length and `JSON`.
    file: [u8; 20],
    /// The binary chunk's length and `BIN\0`.
    bin: [u8; 8],
}

impl Heads {
    /// The heads of a file of a JSON chunk of `text_len` bytes and a binary chunk of
    /// `bin_len` (0: none), or an [`Error::Export`] naming `limit` when the file would pass it.
    fn new(text_len: usize, bin_len: usize, limit: u64) -> Result<Heads> {
        let bin_chunk = if bin_len == 0 { 0 } else { 8 + bin_len as u64 };
        let total = 12 + 8 + text_len as u64 + bin_chunk;
        let limit = limit.min(GLB_LIMIT);
        if total > limit {
            return Err(Error::Export(format!(
                "the model needs a glb of {total} bytes, past the limit of {limit} bytes (a \
                 glb holds at most 4 GiB): lower the detail or split the model"
            )));
        }
        let len32 = |n: u64| {
            u32::try_from(n).map_err(|_| Error::Export(format!("a glb length of {n} bytes")))
        };
        let mut file = [0; 20];
        file[..4].copy_from_slice(b"glTF");
        file[4..8].copy_from_slice(&2u32.to_le_bytes());
        file[8..12].copy_from_slice(&len32(total)?.to_le_bytes());
        file[12..16].copy_from_slice(&len32(text_len as u64)?.to_le_bytes());
        file[16..20].copy_from_slice(b"JSON");
        let mut bin = [0; 8];
        bin[..4].copy_from_slice(&len32(bin_len as u64)?.to_le_bytes());
        bin[4..].copy_from_slice(b"BIN\0");
        Ok(Heads { total, file, bin })
    }
}

/// A glb file ready to be written, its size checked against the limit: the JSON text and
/// the binary chunk's views, which still refer to the model's meshes and textures (shared,
/// not copied).
pub struct GlbFile {
    heads: Heads,
    json: JsonText,
    layout: Layout,
    /// The binary chunk's length (0: none): the views padded to 4 bytes, or 4 zero bytes for
    /// a tile whose buffer 0 would be empty.
    bin_len: usize,
}

impl GlbFile {
    /// The file of `json` and the views of `layout` in a binary chunk of `bin_len` bytes
    /// (0: none; at least the layout's), or an [`Error::Export`] past `limit` bytes.
    pub(super) fn new(
        json: JsonText,
        layout: Layout,
        bin_len: usize,
        limit: u64,
    ) -> Result<GlbFile> {
        let heads = Heads::new(json.len().next_multiple_of(4), bin_len, limit)?;
        Ok(GlbFile {
            heads,
            json,
            layout,
            bin_len,
        })
    }

    /// The file's length in bytes.
    #[must_use]
    pub fn len(&self) -> u64 {
        self.heads.total
    }

    /// Whether the file is empty (never: a glb has a header).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The file's bytes, written in place into one buffer of its size (in parallel).
    pub fn to_vec(&self) -> Result<Vec<u8>> {
        let text_len = self.json.len().next_multiple_of(4);
        let write_json = |dst: &mut [u8]| {
            self.json.write(dst);
            dst[self.json.len()..].fill(b' ');
        };
        glb_file(text_len, write_json, self.bin_len, GLB_LIMIT, |bin| {
            self.layout.write(bin)
        })
    }

    /// Writes the file to `out` without assembling it: the header, the JSON text's parts and
    /// the views straight from the meshes' and textures' memory where it holds their bytes,
    /// in vectored writes; the views it does not hold so (colours, and numbers on a
    /// big-endian host) are converted on the rayon pool while the ones before them are
    /// written by the calling thread. The same bytes as [`GlbFile::to_vec`].
    pub fn write_to(&self, out: &mut impl Write) -> std::io::Result<()> {
        const SPACES: &[u8] = b"   ";
        const ZEROS: &[u8] = &[0; 4];
        let mut head: Vec<Cow<'_, [u8]>> = vec![Cow::Borrowed(&self.heads.file)];
        head.extend(self.json.slices().map(Cow::Borrowed));
        let text_len = self.json.len().next_multiple_of(4);
        head.push(Cow::Borrowed(&SPACES[..text_len - self.json.len()]));
        if self.bin_len == 0 {
            return write_all(out, &head);
        }
        head.push(Cow::Borrowed(&self.heads.bin));
        let views = self.layout.view_count();
        let first = self.layout.first_converted();
        head.extend(self.layout.slices(0..first));
        let padding = self.bin_len.saturating_sub(self.layout.padded_len());
        let padding = Cow::Borrowed(&ZEROS[..padding.min(ZEROS.len())]);
        if first == views {
            head.push(padding);
            return write_all(out, &head);
        }
        // The conversion goes to the pool, the calling thread writes (in the pool or not: a
        // thread outside it does not hand the write over); with one thread, one after the
        // other.
        let mut tail = Vec::new();
        if rayon::current_num_threads() == 1 {
            write_all(out, &head)?;
            tail = self.layout.slices(first..views);
        } else {
            rayon::in_place_scope(|s| {
                s.spawn(|_| tail = self.layout.slices(first..views));
                write_all(out, &head)
            })?;
        }
        tail.push(padding);
        write_all(out, &tail)
    }
}

/// Writes `parts` to `out` in order, in vectored writes.
fn write_all(out: &mut impl Write, parts: &[Cow<'_, [u8]>]) -> std::io::Result<()> {
    let mut slices: Vec<IoSlice<'_>> = parts
        .iter()
        .filter(|p| !p.is_empty())
        .map(|p| IoSlice::new(p))
        .collect();
    let mut rest = slices.as_mut_slice();
    while !rest.is_empty() {
        match out.write_vectored(rest) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(n) => IoSlice::advance_slices(&mut rest, n),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
