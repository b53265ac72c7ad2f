//! The `.usdz` package: a zip archive of stored (uncompressed) files, the layer first, each
//! file's data starting at a multiple of 64 bytes from the archive's start (the padding is an
//! extra field of the local header, id `0x1986` as USD's own writer uses), no dates (1980-01-01),
//! so that the bytes depend on the files alone.

use super::UsdFiles;
use crate::{Error, Result};

/// Alignment of every file's data in a `.usdz`.
pub const USDZ_ALIGNMENT: usize = 64;

/// The extra field id of the padding.
const PADDING_ID: u16 = 0x1986;

/// 1980-01-01 in DOS date form; the time is 00:00.
const DOS_DATE: u16 = (1 << 5) | 1;

/// The `.usdz` bytes of `files`: the layer as `layer_name` (e.g. `oak.usda`), then the
/// textures under their paths.
pub fn usdz_bytes(layer_name: &str, files: &UsdFiles) -> Result<Vec<u8>> {
    let mut entries: Vec<(&str, &[u8])> = vec![(layer_name, files.layer.as_bytes())];
    for (path, texture) in &files.textures {
        entries.push((path.as_str(), &texture.encoded));
    }
    stored_zip(&entries)
}

/// A zip archive of `entries` (name, data), stored, each file's data 64-byte aligned.
pub(super) fn stored_zip(entries: &[(&str, &[u8])]) -> Result<Vec<u8>> {
    let total: usize = entries
        .iter()
        .map(|(n, d)| 30 + 46 + 2 * n.len() + d.len() + 2 * USDZ_ALIGNMENT)
        .sum::<usize>()
        + 22;
    let too_big = || Error::Export("a .usdz package is limited to 4 GiB".into());
    let mut out = Vec::with_capacity(total);
    let mut central = Vec::new();
    for (name, data) in entries {
        let name_len = u16::try_from(name.len()).map_err(|_| too_big())?;
        let size = u32::try_from(data.len()).map_err(|_| too_big())?;
        let offset = u32::try_from(out.len()).map_err(|_| too_big())?;
        let crc = crc32fast::hash(data);
        // The data starts after the 30-byte header, the name and the padding field (4 bytes
        // of id and size, then zeros).
        let unpadded = out.len() + 30 + name.len();
        let mut pad = (USDZ_ALIGNMENT - unpadded % USDZ_ALIGNMENT) % USDZ_ALIGNMENT;
        if pad != 0 && pad < 4 {
            pad += USDZ_ALIGNMENT;
        }
        let fixed = |out: &mut Vec<u8>| {
            out.extend_from_slice(&10u16.to_le_bytes()); // version needed: 1.0, stored
            out.extend_from_slice(&0u16.to_le_bytes()); // flags
            out.extend_from_slice(&0u16.to_le_bytes()); // stored
            out.extend_from_slice(&0u16.to_le_bytes()); // time
            out.extend_from_slice(&DOS_DATE.to_le_bytes());
            out.extend_from_slice(&crc.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&name_len.to_le_bytes());
        };
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        fixed(&mut out);
        out.extend_from_slice(&(pad as u16).to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        if pad > 0 {
            out.extend_from_slice(&PADDING_ID.to_le_bytes());
            out.extend_from_slice(&((pad - 4) as u16).to_le_bytes());
            out.resize(out.len() + pad - 4, 0);
        }
        debug_assert_eq!(out.len() % USDZ_ALIGNMENT, 0);
        out.extend_from_slice(data);

        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&10u16.to_le_bytes()); // made by: 1.0, MS-DOS
        fixed(&mut central);
        central.extend_from_slice(&0u16.to_le_bytes()); // extra
        central.extend_from_slice(&0u16.to_le_bytes()); // comment
        central.extend_from_slice(&0u16.to_le_bytes()); // disk
        central.extend_from_slice(&0u16.to_le_bytes()); // internal attributes
        central.extend_from_slice(&0u32.to_le_bytes()); // external attributes
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let count = u16::try_from(entries.len()).map_err(|_| too_big())?;
    let central_offset = u32::try_from(out.len()).map_err(|_| too_big())?;
    let central_size = u32::try_from(central.len()).map_err(|_| too_big())?;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&central_size.to_le_bytes());
    out.extend_from_slice(&central_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    u32::try_from(out.len()).map_err(|_| too_big())?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u16_at(b: &[u8], at: usize) -> usize {
        usize::from(u16::from_le_bytes([b[at], b[at + 1]]))
    }

    fn u32_at(b: &[u8], at: usize) -> usize {
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize
    }

    /// Reads the archive back by its central directory: (name, data offset, data).
    fn read(zip: &[u8]) -> Vec<(String, usize, Vec<u8>)> {
        let end = zip.len() - 22;
        assert_eq!(u32_at(zip, end), 0x0605_4b50);
        let (count, mut at) = (u16_at(zip, end + 10), u32_at(zip, end + 16));
        let mut files = Vec::new();
        for _ in 0..count {
            assert_eq!(u32_at(zip, at), 0x0201_4b50);
            assert_eq!(u16_at(zip, at + 10), 0, "stored");
            let (crc, size) = (u32_at(zip, at + 16), u32_at(zip, at + 24));
            let name_len = u16_at(zip, at + 28);
            let local = u32_at(zip, at + 42);
            let name = String::from_utf8(zip[at + 46..at + 46 + name_len].to_vec()).expect("utf-8");
            assert_eq!(u32_at(zip, local), 0x0403_4b50);
            let start = local + 30 + u16_at(zip, local + 26) + u16_at(zip, local + 28);
            let data = zip[start..start + size].to_vec();
            assert_eq!(crc32fast::hash(&data) as usize, crc);
            files.push((name, start, data));
            at += 46 + name_len;
        }
        files
    }

    #[test]
    fn every_file_is_stored_whole_at_a_multiple_of_64() {
        let big = vec![7u8; 1000];
        for name_len in 1..70 {
            let name = "n".repeat(name_len);
            let entries: Vec<(&str, &[u8])> =
                vec![(&name, b"#usda 1.0\n"), ("a/b.png", &big), ("c.png", b"x")];
            let zip = stored_zip(&entries).expect("a zip");
            let files = read(&zip);
            assert_eq!(files.len(), 3);
            for ((name, start, data), (want_name, want)) in files.iter().zip(&entries) {
                assert_eq!(name, want_name);
                assert_eq!(start % USDZ_ALIGNMENT, 0, "{name} at {start}");
                assert_eq!(data.as_slice(), *want);
            }
        }
    }

    #[test]
    fn the_same_files_give_the_same_bytes() {
        let entries: Vec<(&str, &[u8])> = vec![("a.usda", b"#usda 1.0\n")];
        assert_eq!(
            stored_zip(&entries).expect("zip"),
            stored_zip(&entries).expect("zip")
        );
    }
}
