//! The GLB container: header, JSON chunk and binary chunk.

use crate::{Error, Result};

/// The largest GLB file: its header stores lengths as 32-bit numbers.
pub const GLB_LIMIT: u64 = u32::MAX as u64;

/// The GLB container around a glTF JSON text (padded to 4 bytes) and a binary chunk (empty:
/// none): an [`Error::Export`] naming the limit when the file would pass `limit` bytes
/// ([`GLB_LIMIT`] when exporting; a smaller one in tests), never a truncated length. The
/// binary chunk becomes the output, moved up behind the header and the JSON in place, rather
/// than copied into a second allocation of the whole file.
pub fn glb_container(text: &[u8], bin: Vec<u8>, limit: u64) -> Result<Vec<u8>> {
    let total = 12
        + 8
        + text.len() as u64
        + if bin.is_empty() {
            0
        } else {
            8 + bin.len() as u64
        };
    let limit = limit.min(GLB_LIMIT);
    if total > limit {
        return Err(Error::Export(format!(
            "the model needs a glb of {total} bytes, past the limit of {limit} bytes (a glb \
             holds at most 4 GiB): lower the detail or split the model"
        )));
    }
    let len32 =
        |n: u64| u32::try_from(n).map_err(|_| Error::Export(format!("a glb length of {n} bytes")));
    let mut head = Vec::with_capacity(28 + text.len());
    head.extend_from_slice(b"glTF");
    head.extend_from_slice(&2u32.to_le_bytes());
    head.extend_from_slice(&len32(total)?.to_le_bytes());
    head.extend_from_slice(&len32(text.len() as u64)?.to_le_bytes());
    head.extend_from_slice(b"JSON");
    head.extend_from_slice(text);
    if bin.is_empty() {
        return Ok(head);
    }
    head.extend_from_slice(&len32(bin.len() as u64)?.to_le_bytes());
    head.extend_from_slice(b"BIN\0");
    let mut out = bin;
    let bin_len = out.len();
    out.resize(total as usize, 0);
    out.copy_within(..bin_len, head.len());
    out[..head.len()].copy_from_slice(&head);
    Ok(out)
}
