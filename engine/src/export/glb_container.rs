//! The GLB container: header, JSON chunk and binary chunk.

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
    let bin_chunk = if bin_len == 0 { 0 } else { 8 + bin_len as u64 };
    let total = 12 + 8 + text_len as u64 + bin_chunk;
    let limit = limit.min(GLB_LIMIT);
    if total > limit {
        return Err(Error::Export(format!(
            "the model needs a glb of {total} bytes, past the limit of {limit} bytes (a glb \
             holds at most 4 GiB): lower the detail or split the model"
        )));
    }
    let len32 =
        |n: u64| u32::try_from(n).map_err(|_| Error::Export(format!("a glb length of {n} bytes")));
    let total32 = len32(total)?;
    let text32 = len32(text_len as u64)?;
    let bin32 = len32(bin_len as u64)?;
    let mut out = vec![0u8; total as usize];
    let (head, rest) = out.split_at_mut(20);
    head[..4].copy_from_slice(b"glTF");
    head[4..8].copy_from_slice(&2u32.to_le_bytes());
    head[8..12].copy_from_slice(&total32.to_le_bytes());
    head[12..16].copy_from_slice(&text32.to_le_bytes());
    head[16..20].copy_from_slice(b"JSON");
    let (json, rest) = rest.split_at_mut(text_len);
    if bin_len > 0 {
        let (bin_head, bin) = rest.split_at_mut(8);
        bin_head[..4].copy_from_slice(&bin32.to_le_bytes());
        bin_head[4..].copy_from_slice(b"BIN\0");
        rayon::join(|| write_text(json), || write_bin(bin));
    } else {
        write_text(json);
    }
    Ok(out)
}
