//! Alpha-masked textures that keep their coverage at a distance.
//!
//! A PNG carries no mipmaps, so every client (three.js, Blender, a game engine) box-filters
//! its own chain: texel `(x, y)` of level `k + 1` is the mean of the four texels `(2x, 2y)`
//! .. `(2x + 1, 2y + 1)` of level `k`, alpha included. An alpha-tested card whose mean alpha
//! (its 1x1 level) is under the cutoff therefore vanishes with distance. [`choose_cutoff`]
//! picks the cutoff together with the texture: the largest of [`CUTOFFS`] whose
//! chain keeps the drawn area (the share of texels at or above the cutoff stays at least
//! [`KEEP`] of level 0's on every level) and under which the mean alpha stays at least
//! [`MARGIN`] above it. [`dilate_color`] fills the colour of the texels that are never drawn
//! with the colour of the nearest drawn ones (pull-push), so the filtered levels show no dark
//! or light halo at the silhouette; [`widen_alpha`] thickens a silhouette too sparse for any
//! cutoff.
//!
//! ```
//! use pge_lod::mask::{MARGIN, choose_cutoff, mean_alpha};
//!
//! // A 16 x 16 card, its left 10 columns opaque.
//! let alpha: Vec<u8> = (0..256).map(|i| if i % 16 < 10 { 255 } else { 0 }).collect();
//! let cutoff = choose_cutoff(&alpha, 16, 16).unwrap();
//! assert!(mean_alpha(&alpha) >= cutoff + MARGIN);
//! ```

use pge_engine::geometry::{GeometryError, Texture};

/// How far the mean alpha must stay above the cutoff: the 1x1 level is drawn with room for
/// 8-bit rounding and a client's own filter.
pub const MARGIN: f32 = 0.05;

/// The cutoffs [`choose_cutoff`] tries, the largest first: 0.5 is glTF's default (the
/// silhouette exactly where the texture's alpha crosses half), the lower ones draw the
/// filtered levels of sparse cards wider. Below 0.2 the texels a bilinear filter blends at a
/// silhouette's edge would be drawn a texel wide, so no lower cutoff is tried.
pub const CUTOFFS: [f32; 7] = [0.5, 0.45, 0.4, 0.35, 0.3, 0.25, 0.2];

/// The share of level 0's drawn area every level of the chain must keep.
pub const KEEP: f32 = 0.9;

/// The mean of alpha bytes, in `[0, 1]` (0 for none): a card's 1x1 level.
#[must_use]
pub fn mean_alpha(alpha: &[u8]) -> f32 {
    if alpha.is_empty() {
        return 0.0;
    }
    let sum: u64 = alpha.iter().map(|&a| u64::from(a)).sum();
    (sum as f64 / (alpha.len() as f64 * 255.0)) as f32
}

/// The alpha channel of RGBA pixels.
#[must_use]
pub fn alpha_of(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4).map(|p| p[3]).collect()
}

/// The box-filtered chain of a `width x height` alpha map down to 1x1, level 0 first, each
/// level as alpha in `[0, 1]`. A level's side is half the one before, rounded down (at least
/// 1); an odd side's last row or column joins the box before it, as clients that filter
/// non-power-of-two textures do.
#[must_use]
pub fn alpha_chain(alpha: &[u8], width: usize, height: usize) -> Vec<(usize, usize, Vec<f32>)> {
    let level0: Vec<f32> = alpha.iter().map(|&a| f32::from(a) / 255.0).collect();
    let mut chain = vec![(width, height, level0)];
    while let Some((w, h, last)) = chain.last() {
        let (w, h) = (*w, *h);
        if w <= 1 && h <= 1 {
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        // The source columns (and rows) of each texel of the next level.
        let span = |i: usize, n: usize, next: usize| {
            let lo = i * n / next;
            let hi = ((i + 1) * n / next).max(lo + 1);
            lo..hi
        };
        let mut next = vec![0.0f32; nw * nh];
        for (y, row) in next.chunks_exact_mut(nw).enumerate() {
            let ys = span(y, h, nh);
            for (x, out) in row.iter_mut().enumerate() {
                let xs = span(x, w, nw);
                let mut sum = 0.0;
                for sy in ys.clone() {
                    sum += last[sy * w + xs.start..sy * w + xs.end].iter().sum::<f32>();
                }
                *out = sum / (ys.len() * xs.len()) as f32;
            }
        }
        chain.push((nw, nh, next));
    }
    chain
}

/// The share of a level's texels drawn at `cutoff` (alpha at least the cutoff).
fn drawn(level: &[f32], cutoff: f32) -> f32 {
    let count = level.iter().filter(|&&a| a >= cutoff).count();
    count as f32 / level.len().max(1) as f32
}

/// The lowest share of level 0's drawn area that any level of the chain draws at `cutoff`
/// (1 when level 0 draws nothing).
#[must_use]
pub fn kept_area(chain: &[(usize, usize, Vec<f32>)], cutoff: f32) -> f32 {
    let Some((_, _, level0)) = chain.first() else {
        return 1.0;
    };
    let base = drawn(level0, cutoff);
    if base == 0.0 {
        return 1.0;
    }
    chain
        .iter()
        .map(|(_, _, level)| drawn(level, cutoff) / base)
        .fold(f32::INFINITY, f32::min)
}

/// The cutoff for an alpha map of `width x height` (alpha bytes, row by row): the largest of
/// [`CUTOFFS`] at least [`MARGIN`] under the mean alpha whose box-filtered chain keeps
/// [`KEEP`] of the drawn area on every level; failing that, the largest at least [`MARGIN`]
/// under the mean alpha (the card still never vanishes). `None` when the mean alpha is under
/// the lowest cutoff plus the margin: no cutoff keeps such a card (see [`widen_alpha`]).
#[must_use]
pub fn choose_cutoff(alpha: &[u8], width: usize, height: usize) -> Option<f32> {
    let mean = mean_alpha(alpha);
    let allowed: Vec<f32> = CUTOFFS
        .into_iter()
        .filter(|&c| mean >= c + MARGIN)
        .collect();
    let first = *allowed.first()?;
    let chain = alpha_chain(alpha, width, height);
    Some(
        allowed
            .into_iter()
            .find(|&c| kept_area(&chain, c) >= KEEP)
            .unwrap_or(first),
    )
}

/// Fills the colour of every texel whose alpha is under `drawn_from` with the colour of the
/// drawn texels nearest it (pull-push: the drawn colours averaged down a chain of halved
/// levels, then every undrawn texel takes its parent's colour on the way back up), so that
/// filtering never mixes in the colour of texels no one sees. Alpha is kept. A map with no
/// drawn texel is left as it is. The same pixels give the same bytes.
pub fn dilate_color(rgba: &mut [u8], width: usize, height: usize, drawn_from: u8) {
    if width == 0 || height == 0 || rgba.len() != width * height * 4 {
        return;
    }
    // Pull: the sum of the drawn texels' colour and their count under each texel of a chain
    // of levels halved (rounding up) down to one texel, starting at half the map's size
    // (the map's own texels are read where they are).
    let (w1, h1) = (width.div_ceil(2), height.div_ceil(2));
    let mut first = vec![[0.0f32; 4]; w1 * h1];
    for y in 0..height {
        let row = &rgba[y * width * 4..(y + 1) * width * 4];
        let sums = &mut first[(y / 2) * w1..(y / 2 + 1) * w1];
        for (x, p) in row.chunks_exact(4).enumerate() {
            if p[3] >= drawn_from {
                let d = &mut sums[x / 2];
                d[0] += f32::from(p[0]);
                d[1] += f32::from(p[1]);
                d[2] += f32::from(p[2]);
                d[3] += 1.0;
            }
        }
    }
    let mut levels: Vec<(usize, usize, Vec<[f32; 4]>)> = vec![(w1, h1, first)];
    loop {
        let (w, h, last) = levels.last().expect("a first level");
        let (w, h) = (*w, *h);
        if w == 1 && h == 1 {
            break;
        }
        let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
        let mut next = vec![[0.0f32; 4]; nw * nh];
        for y in 0..h {
            for x in 0..w {
                let s = last[y * w + x];
                let d = &mut next[(y / 2) * nw + x / 2];
                for c in 0..4 {
                    d[c] += s[c];
                }
            }
        }
        levels.push((nw, nh, next));
    }
    if levels.last().is_none_or(|(_, _, l)| l[0][3] == 0.0) {
        return;
    }
    // Push: from the top down, every texel's colour in place (its drawn texels' mean, or its
    // parent's when it has none).
    for k in (0..levels.len()).rev() {
        let (lower, upper) = levels.split_at_mut(k + 1);
        let (w, h, level) = &mut lower[k];
        let parent = upper.first().map(|(pw, _, p)| (*pw, p));
        for y in 0..*h {
            for x in 0..*w {
                let s = &mut level[y * *w + x];
                *s = if s[3] > 0.0 {
                    [s[0] / s[3], s[1] / s[3], s[2] / s[3], 1.0]
                } else {
                    match parent {
                        Some((pw, p)) => p[(y / 2) * pw + x / 2],
                        None => *s,
                    }
                };
            }
        }
    }
    let (w1, _, colors) = &levels[0];
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) * 4;
            if rgba[i + 3] < drawn_from {
                let c = colors[(y / 2) * w1 + x / 2];
                for k in 0..3 {
                    rgba[i + k] = (c[k] + 0.5) as u8;
                }
            }
        }
    }
}

/// Thickens the silhouette of a `width x height` RGBA map until its mean alpha is at least
/// `target`: each pass makes every texel as opaque as the most opaque of its eight
/// neighbours (the colour comes from [`dilate_color`] afterwards). Stops after `width.max(height)`
/// passes or when a pass changes nothing. Returns the passes made.
pub fn widen_alpha(rgba: &mut [u8], width: usize, height: usize, target: f32) -> usize {
    if rgba.len() != width * height * 4 {
        return 0;
    }
    let mut passes = 0;
    while mean_alpha(&alpha_of(rgba)) < target && passes < width.max(height) {
        let alpha = alpha_of(rgba);
        let mut changed = false;
        for y in 0..height {
            for x in 0..width {
                let mut most = alpha[y * width + x];
                for ny in y.saturating_sub(1)..(y + 2).min(height) {
                    for nx in x.saturating_sub(1)..(x + 2).min(width) {
                        most = most.max(alpha[ny * width + nx]);
                    }
                }
                let i = (y * width + x) * 4 + 3;
                changed |= rgba[i] != most;
                rgba[i] = most;
            }
        }
        passes += 1;
        if !changed {
            break;
        }
    }
    passes
}

/// A texture made ready for alpha masking by [`mask_texture`].
#[derive(Clone, Debug, PartialEq)]
pub struct Masked {
    /// The texture: the colour of the drawn texels dilated under the others (and, when
    /// `widened_from` is set, the silhouettes thickened).
    pub texture: Texture,
    /// The cutoff chosen with it ([`choose_cutoff`]).
    pub cutoff: f32,
    /// Its mean alpha, as written.
    pub mean_alpha: f32,
    /// The mean alpha it had when no cutoff could keep it and its silhouettes were thickened
    /// ([`widen_alpha`]); `None` when it was kept as it came.
    pub widened_from: Option<f32>,
}

/// Readies an alpha-masked texture (a user's leaf PNG): its cutoff from its alpha
/// ([`choose_cutoff`]); when its mean alpha is too low for any cutoff, its silhouettes are
/// thickened until the lowest cutoff keeps it ([`widen_alpha`], reported in
/// [`Masked::widened_from`] for a warning); then the colour of the texels under half alpha
/// is dilated from the others ([`dilate_color`]) and the texture re-encoded as PNG under its
/// name. The same texture gives the same bytes.
pub fn mask_texture(texture: &Texture) -> Result<Masked, GeometryError> {
    let image = image::load_from_memory(&texture.encoded)
        .map_err(|e| GeometryError::Texture(format!("{}: {e}", texture.name)))?
        .to_rgba8();
    let (w, h) = (image.width() as usize, image.height() as usize);
    let mut rgba = image.into_raw();
    let before = mean_alpha(&alpha_of(&rgba));
    let (cutoff, widened_from) = match choose_cutoff(&alpha_of(&rgba), w, h) {
        Some(c) => (c, None),
        None => {
            let lowest = CUTOFFS[CUTOFFS.len() - 1];
            // A hair over the margin, so that 8-bit rounding in the client keeps it.
            widen_alpha(&mut rgba, w, h, lowest + MARGIN + 0.01);
            (lowest, Some(before))
        }
    };
    dilate_color(&mut rgba, w, h, 128);
    let mean = mean_alpha(&alpha_of(&rgba));
    let texture = Texture::from_rgba(texture.name.clone(), w as u32, h as u32, &rgba)?;
    Ok(Masked {
        texture,
        cutoff,
        mean_alpha: mean,
        widened_from,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `n x n` alpha map of a disc of radius `r` (in texture units) at the centre.
    fn disc(n: usize, r: f32) -> Vec<u8> {
        (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
                let d = ((x / n as f32 - 0.5).powi(2) + (y / n as f32 - 0.5).powi(2)).sqrt();
                if d < r { 255 } else { 0 }
            })
            .collect()
    }

    #[test]
    fn the_chain_is_box_filtered_down_to_one_texel() {
        let alpha = disc(64, 0.4);
        let chain = alpha_chain(&alpha, 64, 64);
        assert_eq!(chain.len(), 7);
        assert_eq!((chain[6].0, chain[6].1), (1, 1));
        let mean = mean_alpha(&alpha);
        assert!(
            (chain[6].2[0] - mean).abs() < 1e-4,
            "the 1x1 level is the mean"
        );
        // An odd side: 5 -> 2 -> 1, every texel counted.
        let odd = alpha_chain(&[255, 0, 255, 0, 255], 5, 1);
        assert_eq!(odd.iter().map(|l| l.0).collect::<Vec<_>>(), [5, 2, 1]);
        assert!((odd[1].2[0] - 0.5).abs() < 1e-6 && (odd[1].2[1] - 2.0 / 3.0).abs() < 1e-6);
        assert!((odd[2].2[0] - 7.0 / 12.0).abs() < 1e-6);
    }

    #[test]
    fn the_cutoff_keeps_the_mean_above_it_and_the_area_on_every_level() {
        // Discs of 13% to 79% of the card.
        for r in [0.2f32, 0.3, 0.4, 0.5] {
            let alpha = disc(128, r);
            let mean = mean_alpha(&alpha);
            let cutoff = choose_cutoff(&alpha, 128, 128);
            if mean < CUTOFFS[CUTOFFS.len() - 1] + MARGIN {
                assert_eq!(cutoff, None, "r {r}: mean {mean}");
                continue;
            }
            let cutoff = cutoff.expect("a cutoff");
            assert!(mean >= cutoff + MARGIN, "r {r}: {mean} vs {cutoff}");
            // The largest allowed cutoff that keeps the area; if none does, the largest.
            let chain = alpha_chain(&alpha, 128, 128);
            let allowed = CUTOFFS.iter().filter(|&&c| mean >= c + MARGIN);
            let keeping: Vec<f32> = allowed
                .clone()
                .copied()
                .filter(|&c| kept_area(&chain, c) >= KEEP)
                .collect();
            let want = keeping.first().or(allowed.clone().next()).copied();
            assert_eq!(Some(cutoff), want, "r {r}: {keeping:?}");
        }
        // Too sparse for any cutoff: 7% of the card.
        assert_eq!(choose_cutoff(&disc(64, 0.15), 64, 64), None);
        // Opaque: glTF's default.
        assert_eq!(choose_cutoff(&[255; 16], 4, 4), Some(0.5));
        // A card the default cutoff would lose at a distance gets a lower one.
        let sparse = disc(128, 0.33);
        assert!(mean_alpha(&sparse) < 0.5);
        assert!(choose_cutoff(&sparse, 128, 128).expect("cutoff") < 0.5);
    }

    #[test]
    fn dilation_leaves_no_dark_texel_under_a_transparent_one() {
        // Green opaque texels in a ring, black transparent ones elsewhere.
        let n = 32;
        let alpha = disc(n, 0.3);
        let mut rgba: Vec<u8> = alpha
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| {
                let inner = disc(n, 0.15)[i] == 255;
                if a == 255 && !inner {
                    [40, 200, 60, 255]
                } else {
                    [0, 0, 0, 0]
                }
            })
            .collect();
        let before = rgba.clone();
        dilate_color(&mut rgba, n, n, 128);
        for (p, q) in rgba.chunks_exact(4).zip(before.chunks_exact(4)) {
            assert_eq!(p[3], q[3], "alpha kept");
            if q[3] == 255 {
                assert_eq!(p, q, "drawn texels kept");
            } else {
                assert_eq!(&p[..3], &[40, 200, 60], "filled with the drawn colour");
            }
        }
        // Two colours: every filled texel lies between them.
        let mut two: Vec<u8> = (0..n * n)
            .flat_map(|i| match i % n {
                0 => [200, 0, 0, 255],
                31 => [0, 0, 200, 255],
                _ => [0, 0, 0, 0],
            })
            .collect();
        dilate_color(&mut two, n, n, 128);
        for p in two.chunks_exact(4) {
            assert!(u16::from(p[0]) + u16::from(p[2]) >= 199, "{p:?}");
        }
        // Nothing drawn: unchanged.
        let mut none = vec![0u8; 64];
        dilate_color(&mut none, 4, 4, 128);
        assert_eq!(none, vec![0u8; 64]);
    }

    #[test]
    fn a_user_texture_gets_its_cutoff_or_is_widened() {
        let n = 64;
        let dense: Vec<u8> = disc(n, 0.45)
            .iter()
            .flat_map(|&a| [30, 90, 20, a])
            .collect();
        let png = Texture::from_rgba("leaf", n as u32, n as u32, &dense).expect("png");
        let m = mask_texture(&png).expect("masked");
        assert_eq!(m.widened_from, None);
        assert!(m.mean_alpha >= m.cutoff + MARGIN);
        let back = image::load_from_memory(&m.texture.encoded)
            .expect("png")
            .to_rgba8();
        assert!(back.pixels().all(|p| p.0[..3] == [30, 90, 20]), "dilated");
        // A sparse one: widened, with the mean alpha it had.
        let sparse: Vec<u8> = disc(n, 0.1).iter().flat_map(|&a| [30, 90, 20, a]).collect();
        let png = Texture::from_rgba("leaf", n as u32, n as u32, &sparse).expect("png");
        let m = mask_texture(&png).expect("masked");
        let was = m.widened_from.expect("widened");
        assert!(was < 0.05, "{was}");
        assert!(
            m.mean_alpha >= m.cutoff + MARGIN,
            "{} {}",
            m.mean_alpha,
            m.cutoff
        );
        assert!(
            mask_texture(&Texture {
                encoded: vec![1, 2],
                ..png
            })
            .is_err()
        );
    }

    #[test]
    fn widening_raises_the_mean_alpha() {
        let n = 64;
        let alpha = disc(n, 0.1);
        let mut rgba: Vec<u8> = alpha.iter().flat_map(|&a| [0, 255, 0, a]).collect();
        assert!(mean_alpha(&alpha) < 0.05);
        let passes = widen_alpha(&mut rgba, n, n, 0.3);
        assert!(passes > 0);
        let widened = alpha_of(&rgba);
        assert!(mean_alpha(&widened) >= 0.3);
        assert!(choose_cutoff(&widened, n, n).is_some());
        // The original silhouette stays inside.
        for (a, b) in alpha.iter().zip(&widened) {
            assert!(b >= a);
        }
    }
}
