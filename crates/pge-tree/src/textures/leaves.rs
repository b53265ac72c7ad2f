//! Leaves: silhouettes per shape, veins in the colour and normal maps.

use rayon::prelude::*;

use super::blade::LeafPixel;
use super::maps::{Maps, Srgb, Surface};
use super::needles::Needles;
use super::noise::Fractal;
use super::twig::Twig;
use super::{LeafParams, LeafShape, TextureSet};
use crate::TreeError;
use pge_lod::mask;

/// The leaf set of `params`: its maps generated (as [`leaf_maps`]) and PNG-encoded, with the
/// alpha cutoff chosen for its colour map ([`TextureSet::alpha_cutoff`]).
pub fn leaf_set(params: &LeafParams) -> Result<TextureSet, TreeError> {
    let (surface, cutoff) = leaf_surface(params);
    let mut set = surface.encode("leaf")?;
    set.alpha_cutoff = Some(cutoff);
    Ok(set)
}

/// The leaf maps of `params`: a near-white card (each leaf's vertex colour gives the hue)
/// with lighter veins, alpha 255 inside the silhouettes and 0 outside for masking, the
/// colour of the nearest leaf under the clear texels; the normal map of the domed blades and
/// their sunken veins; roughness.
pub fn leaf_maps(params: &LeafParams) -> Maps {
    leaf_surface(params).0.maps()
}

/// What a card draws: a twig of broad leaves or a spray of needle shoots.
enum Card {
    Twig(Twig),
    Needles(Needles),
}

impl Card {
    fn new(params: &LeafParams) -> Card {
        match params.shape {
            LeafShape::Needles => Card::Needles(Needles::new(params.per_card)),
            shape => Card::Twig(Twig::new(shape, params.per_card)),
        }
    }

    fn pixel(&self, x: f32, v: f32) -> LeafPixel {
        match self {
            Card::Twig(t) => t.pixel(x, v),
            Card::Needles(n) => n.pixel(x, v),
        }
    }
}

/// The card's maps before the normal map, and the alpha cutoff chosen with its colour.
fn leaf_surface(params: &LeafParams) -> (Surface, f32) {
    let n = params.size.clamp(16, 4096) as usize;
    let mottle = Fractal::new(8, 8, 2, 61).for_pixels(n);
    let card = Card::new(params);
    let mut heights = vec![0.0f32; n * n];
    let mut color = vec![0u8; n * n * 4];
    let mut rough = vec![0u8; n * n * 3];
    let srgb = Srgb::table();
    heights
        .par_chunks_mut(n)
        .zip(color.par_chunks_mut(n * 4))
        .zip(rough.par_chunks_mut(n * 3))
        .enumerate()
        .for_each(|(y, ((h, c), r))| {
            let v = (y as f32 + 0.5) / n as f32;
            let mottle = mottle.row(v).values();
            for xi in 0..n {
                let u = (xi as f32 + 0.5) / n as f32;
                let p = card.pixel(u - 0.5, v);
                let mottle = 0.05 * (mottle[xi] - 0.5);
                let g = srgb.byte(p.shade + mottle);
                c[xi * 4..xi * 4 + 4].copy_from_slice(&[g, g, g, if p.inside { 255 } else { 0 }]);
                h[xi] = p.height;
                r[xi * 3 + 1] = (p.roughness.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        });
    let cutoff = mask_card(&mut color, n);
    let surface = Surface {
        n,
        heights,
        strength: 3.0 * n as f32 / 512.0,
        wrap: false,
        color,
        channels: 4,
        roughness: rough,
    };
    (surface, cutoff)
}

/// Chooses the alpha cutoff of an `n x n` RGBA card ([`mask::choose_cutoff`]; a card too
/// sparse for any is thickened first, [`mask::widen_alpha`]) and dilates the colour of its
/// leaves under its clear texels ([`mask::dilate_color`]). Returns the cutoff.
pub(super) fn mask_card(rgba: &mut [u8], n: usize) -> f32 {
    let cutoff = match mask::choose_cutoff(&mask::alpha_of(rgba), n, n) {
        Some(c) => c,
        None => {
            let lowest = mask::CUTOFFS[mask::CUTOFFS.len() - 1];
            // A hair over the margin, so that 8-bit rounding in a client keeps it.
            mask::widen_alpha(rgba, n, n, lowest + mask::MARGIN + 0.01);
            lowest
        }
    };
    mask::dilate_color(rgba, n, n, 128);
    cutoff
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::textures::test_support::decode;

    #[test]
    fn leaf_silhouettes_are_masks_of_their_shape() {
        let mut opaque = Vec::new();
        for shape in [
            LeafShape::Ovate,
            LeafShape::Lobed,
            LeafShape::Lanceolate,
            LeafShape::Palmate,
            LeafShape::Needles,
        ] {
            let set = leaf_set(&LeafParams {
                shape,
                size: 128,
                per_card: 1,
            })
            .expect("leaf");
            let img = decode(&set.color);
            assert!(
                img.pixels().all(|p| p[3] == 0 || p[3] == 255),
                "{shape:?}: a binary mask"
            );
            assert_eq!(
                img.get_pixel(64, 4)[3],
                255,
                "{shape:?}: the stalk is opaque"
            );
            assert_eq!(img.get_pixel(1, 1)[3], 0, "{shape:?}: the corner is clear");
            let n = img.pixels().filter(|p| p[3] == 255).count();
            opaque.push(n);
            let normal = decode(&set.normal);
            assert!(
                normal.pixels().any(|p| (p[0] as i32 - 128).abs() > 20),
                "{shape:?}: veins and dome in the normal map"
            );
        }
        // Willow leaves are narrow (one alone on a square card is too sparse for any
        // cutoff, so its silhouette is thickened a little), oak leaves lobed (less than the
        // ovate blade).
        assert!(opaque[2] < opaque[0], "{opaque:?}");
        assert!(opaque[1] < opaque[0], "{opaque:?}");
    }

    #[test]
    fn every_card_keeps_its_coverage_in_a_box_filtered_chain() {
        for shape in [
            LeafShape::Ovate,
            LeafShape::Lobed,
            LeafShape::Lanceolate,
            LeafShape::Palmate,
            LeafShape::Needles,
        ] {
            for per_card in [1, 3, 5, 7, 9, 12] {
                let set = leaf_set(&LeafParams {
                    shape,
                    size: 128,
                    per_card,
                })
                .expect("leaf");
                let img = decode(&set.color);
                let alpha = mask::alpha_of(img.as_raw());
                let mean = mask::mean_alpha(&alpha);
                let cutoff = set.alpha_cutoff.expect("a leaf set has a cutoff");
                assert!(
                    mean >= cutoff + mask::MARGIN,
                    "{shape:?} {per_card}: {mean}"
                );
                // Colour dilated: no clear texel darker than the darkest drawn one.
                let darkest = img.pixels().filter(|p| p[3] == 255).map(|p| p[0]).min();
                let darkest = darkest.expect("drawn texels");
                assert!(
                    img.pixels().all(|p| p[3] == 255 || p[0] >= darkest),
                    "{shape:?} {per_card}: a dark clear texel"
                );
            }
        }
    }

    #[test]
    fn veins_are_lighter_in_colour() {
        let set = leaf_set(&LeafParams {
            shape: LeafShape::Ovate,
            size: 256,
            per_card: 1,
        })
        .expect("leaf");
        let img = decode(&set.color);
        // Along the midrib vs a little beside it.
        let (mut rib, mut blade) = (0u32, 0u32);
        for y in 100..200 {
            rib += u32::from(img.get_pixel(128, y)[0]);
            blade += u32::from(img.get_pixel(140, y)[0]);
        }
        assert!(rib > blade, "midrib {rib} vs blade {blade}");
    }
}
