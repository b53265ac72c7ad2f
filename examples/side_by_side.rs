//! Composes screenshots side by side, each cropped to the same rectangle (how the README's
//! `docs/thumbs/lod_levels.png` was made from three `pge preview --lod-level F
//! --screenshot` frames):
//!
//! ```text
//! cargo run --example side_by_side -- OUT.png X Y WIDTH HEIGHT IN.png...
//! ```

use anyhow::{Context, bail};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, x, y, w, h, inputs @ ..] = args.as_slice() else {
        bail!("usage: side_by_side OUT.png X Y WIDTH HEIGHT IN.png...");
    };
    let [x, y, w, h] = [x, y, w, h].map(|v| v.parse::<u32>());
    let (x, y, w, h) = (x?, y?, w?, h?);
    if inputs.is_empty() {
        bail!("no input images");
    }
    let mut sheet = image::RgbaImage::new(w * inputs.len() as u32, h);
    for (i, path) in inputs.iter().enumerate() {
        let img = image::open(path)
            .with_context(|| format!("{path}: cannot read"))?
            .to_rgba8();
        if x + w > img.width() || y + h > img.height() {
            bail!(
                "{path}: {}x{} is smaller than the crop",
                img.width(),
                img.height()
            );
        }
        let crop = image::imageops::crop_imm(&img, x, y, w, h).to_image();
        image::imageops::replace(&mut sheet, &crop, i64::from(w) * i as i64, 0);
    }
    sheet
        .save(out)
        .with_context(|| format!("{out}: cannot write"))?;
    Ok(())
}
