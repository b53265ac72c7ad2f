//! Bark: the four styles' patterns as height, colour and roughness per pixel.

use std::f32::consts::TAU;

use rayon::prelude::*;

use super::maps::{Maps, Srgb, Surface};
use super::noise::{Cells, Fractal, Lattice, centre, floor, hash, smoothstep, unit, wrap};
use super::{BarkParams, TextureSet};
use crate::TreeError;
use crate::options::BarkStyle;

/// What one bark pixel is made of: height in `[0, 1]`, a colour factor and roughness.
struct Sample {
    height: f32,
    shade: [f32; 3],
    roughness: f32,
}

/// `a` blended towards `b` by `t`.
fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

/// Fills the bark maps of an `n x n` tile in parallel rows: `row(v)` prepares what a row
/// shares and returns the sample at each pixel column `x` (at `u`) of it.
fn fill_bark<R, S>(n: usize, row: R) -> (Vec<f32>, Vec<u8>, Vec<u8>)
where
    R: Fn(f32) -> S + Sync,
    S: Fn(usize, f32) -> Sample,
{
    let mut heights = vec![0.0f32; n * n];
    let mut color = vec![0u8; n * n * 3];
    let mut rough = vec![0u8; n * n * 3];
    let srgb = Srgb::table();
    heights
        .par_chunks_mut(n)
        .zip(color.par_chunks_mut(n * 3))
        .zip(rough.par_chunks_mut(n * 3))
        .enumerate()
        .for_each(|(y, ((h, c), r))| {
            let sample = row(centre(y, n));
            for x in 0..n {
                let s = sample(x, centre(x, n));
                h[x] = s.height;
                for i in 0..3 {
                    c[x * 3 + i] = srgb.byte(s.shade[i]);
                }
                r[x * 3 + 1] = (s.roughness.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        });
    (heights, color, rough)
}

/// Each style's pattern over the `n x n` tile: heights, colour and roughness pixels. The
/// noise tables are made once per call, the per-row terms once per row.
fn bark_pixels(style: BarkStyle, color: [f32; 4], n: usize) -> (Vec<f32>, Vec<u8>, Vec<u8>) {
    let c = [color[0], color[1], color[2]];
    let l = 0.3 * c[0] + 0.55 * c[1] + 0.15 * c[2];
    let grey = |k: f32| [l * k, l * k, l * k];
    match style {
        BarkStyle::Furrowed => {
            // Oak: long ridges between deep vertical furrows. Cells 3.5 times taller than
            // wide, their borders wandering with a low noise, are the ridges; the furrows are
            // the borders (F2 - F1 small), with small cross-cracks on the ridges.
            let (warp, ridges) = (Lattice::new(4, 3, 11).for_pixels(n), Cells::new(8, 2, 12));
            let cracks = Cells::new(16, 6, 13);
            let fibre = Fractal::new(64, 6, 2, 14).for_pixels(n);
            let light = grey(1.5);
            fill_bark(n, |v| {
                let (warp, fibre) = (warp.row(v).values(), fibre.row(v).values());
                let ridges = ridges
                    .row(v)
                    .many((0..n).map(|x| centre(x, n) + 0.05 * (warp[x] - 0.5)));
                let cracks = cracks.row(v).many((0..n).map(|x| centre(x, n)));
                #[inline(always)]
                move |x, _| {
                    let (f1, f2, id) = ridges.at(x);
                    let ridge = smoothstep(0.02, 0.6, f2 - f1);
                    let (g1, g2, _) = cracks.at(x);
                    let crack = smoothstep(0.0, 0.1, g2 - g1);
                    let height = (0.7 * ridge.sqrt() + 0.12 * unit(id) * ridge + 0.16 * fibre[x])
                        * (0.94 + 0.06 * crack);
                    let top = mix(c, light, 0.35 * smoothstep(0.6, 0.95, height));
                    Sample {
                        height,
                        shade: mix([0.0; 3], top, 0.28 + 0.9 * height),
                        roughness: 0.97 - 0.12 * height,
                    }
                }
            })
        }
        BarkStyle::Plated => {
            // Pine: irregular flat plates split by narrow dark cracks, each plate its own
            // tint and tilt, flaking into smaller scales.
            let warp_u = Lattice::new(5, 5, 21).for_pixels(n);
            let warp_v = Lattice::new(5, 5, 22).for_pixels(n);
            let (plates, scales) = (Cells::new(5, 4, 23), Cells::new(12, 9, 24));
            let grain = Fractal::new(32, 32, 2, 25).for_pixels(n);
            let warm = [c[0] * 1.35, c[1] * 1.05, c[2] * 0.85];
            let light = grey(1.3);
            fill_bark(n, |v| {
                let (warp_u, warp_v) = (warp_u.row(v).values(), warp_v.row(v).values());
                let grain = grain.row(v).values();
                // The row's warped points, and both cellular noises at them.
                let (wu, wv): (Vec<f32>, Vec<f32>) = (0..n)
                    .map(|x| {
                        let u = centre(x, n);
                        (u + 0.04 * (warp_u[x] - 0.5), v + 0.04 * (warp_v[x] - 0.5))
                    })
                    .unzip();
                let (plates, scales) = (plates.many(&wu, &wv), scales.many(&wu, &wv));
                #[inline(always)]
                move |x, _| {
                    let (f1, f2, id) = plates.at(x);
                    let crack = smoothstep(0.0, 0.14, f2 - f1);
                    let (g1, g2, sub) = scales.at(x);
                    let scale = smoothstep(0.0, 0.08, g2 - g1);
                    let tilt = 0.15 * (1.0 - f1);
                    let grain = grain[x];
                    let height = crack
                        * (0.5
                            + 0.2 * unit(id)
                            + tilt
                            + 0.12 * scale
                            + 0.06 * unit(sub)
                            + 0.06 * grain);
                    let plate = mix(c, warm, unit(id.rotate_left(7)));
                    let plate = mix(plate, light, 0.25 * unit(sub));
                    Sample {
                        height,
                        shade: mix(
                            [0.0; 3],
                            plate,
                            0.15 + 0.85 * crack * (0.8 + 0.2 * scale) + 0.1 * grain,
                        ),
                        roughness: 0.9 - 0.15 * crack,
                    }
                }
            })
        }
        BarkStyle::Smooth => {
            // Beech, birch: smooth mottled bark with lenticels, short dark horizontal marks,
            // one per cell at a random place and length.
            let mottle = Fractal::new(6, 6, 3, 31).for_pixels(n);
            let light = grey(1.25);
            let dark = [c[0] * 0.18, c[1] * 0.15, c[2] * 0.13];
            fill_bark(n, |v| {
                let mottle = mottle.row(v).values();
                let gy = v * 22.0;
                let cy = floor(gy) as f32;
                #[inline(always)]
                move |x, u| {
                    let mottle = mottle[x];
                    let gx = u * 7.0;
                    let cx = floor(gx) as f32;
                    let h = hash(wrap(cx as i64, 7), wrap(cy as i64, 22), 32);
                    let (px, py) = (0.3 + 0.4 * unit(h), 0.3 + 0.4 * unit(h.rotate_left(11)));
                    let half = 0.15 + 0.3 * unit(h.rotate_left(22));
                    let dx = ((gx - cx) - px) / half;
                    let dy = ((gy - cy) - py) / 0.09;
                    let mark = if unit(h.rotate_left(5)) < 0.75 {
                        1.0 - smoothstep(0.6, 1.0, dx * dx + dy * dy)
                    } else {
                        0.0
                    };
                    let skin = mix(c, light, 0.3 * mottle);
                    Sample {
                        height: 0.55 + 0.25 * mottle - 0.35 * mark,
                        shade: mix(skin, dark, mark),
                        roughness: 0.55 + 0.3 * mark + 0.1 * mottle,
                    }
                }
            })
        }
        BarkStyle::Fibrous => {
            // Willow: interlaced fibrous ridges, long diamond-shaped furrows and fine
            // vertical fibres.
            let (warp, ridges) = (Lattice::new(3, 2, 41).for_pixels(n), Cells::new(11, 2, 42));
            let fibres = Fractal::new(96, 4, 3, 43);
            let light = grey(1.4);
            fill_bark(n, |v| {
                let (warp, fibres) = (warp.row(v).values(), fibres.row(v));
                let sway = 0.03 * (v * TAU * 2.0).sin();
                let wave = 0.01 * (v * 40.0).sin();
                let ridges = ridges
                    .row(v)
                    .many((0..n).map(|x| centre(x, n) + 0.06 * (warp[x] - 0.5) + sway));
                let wavy: Vec<f32> = (0..n).map(|x| centre(x, n) + wave).collect();
                let fibres = fibres.values_at(&wavy);
                #[inline(always)]
                move |x, _| {
                    let (f1, f2, id) = ridges.at(x);
                    let ridge = smoothstep(0.0, 0.35, f2 - f1);
                    let fibres = fibres[x];
                    let height =
                        0.55 * ridge + 0.35 * fibres * (0.4 + 0.6 * ridge) + 0.1 * unit(id);
                    Sample {
                        height,
                        shade: mix([0.0; 3], mix(c, light, 0.25 * fibres), 0.3 + 0.8 * height),
                        roughness: 0.93 - 0.1 * height,
                    }
                }
            })
        }
    }
}

/// Normal-map strength of each style at relief 1: the height change across one texel of a
/// 512 px map is multiplied by this (and scaled with the map size).
fn relief(style: BarkStyle) -> f32 {
    match style {
        BarkStyle::Furrowed => 7.0,
        BarkStyle::Plated => 6.0,
        BarkStyle::Smooth => 2.0,
        BarkStyle::Fibrous => 5.0,
    }
}

/// The bark set of `params`: its maps generated (as [`bark_maps`]) and PNG-encoded.
pub fn bark_set(params: &BarkParams) -> Result<TextureSet, TreeError> {
    bark_surface(params).encode("bark")
}

/// The bark maps of `params`: every pixel's sample in parallel rows, the normal map from
/// the height field (wrapping, as the texture tiles).
pub fn bark_maps(params: &BarkParams) -> Maps {
    bark_surface(params).maps()
}

fn bark_surface(params: &BarkParams) -> Surface {
    let n = params.size.clamp(16, 4096) as usize;
    let (heights, color, roughness) = bark_pixels(params.style, params.color, n);
    Surface {
        n,
        heights,
        strength: relief(params.style) * params.depth * n as f32 / 512.0,
        wrap: true,
        color,
        channels: 3,
        roughness,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::textures::encode_maps;
    use crate::textures::test_support::{bark, decode};

    #[test]
    fn every_bark_style_has_relief_and_tiles() {
        let mut colors = Vec::new();
        for style in [
            BarkStyle::Furrowed,
            BarkStyle::Plated,
            BarkStyle::Smooth,
            BarkStyle::Fibrous,
        ] {
            let set = bark_set(&bark(style, 64)).expect("bark");
            for t in [&set.color, &set.normal, &set.roughness] {
                assert_eq!((t.width, t.height), (64, 64));
            }
            let relief = bark_set(&BarkParams {
                depth: 4.0,
                ..bark(style, 64)
            })
            .expect("bark");
            let normal = decode(&relief.normal);
            // The normal map is not flat, and it points out of the surface everywhere.
            let tilted = normal
                .pixels()
                .filter(|p| (p[0] as i32 - 128).abs() > 12 || (p[1] as i32 - 128).abs() > 12)
                .count();
            assert!(tilted > 64 * 64 / 25, "{style:?}: {tilted} tilted texels");
            assert!(normal.pixels().all(|p| p[2] >= 128), "{style:?}");
            // Tiling: the last column (row) continues into the first as any column does into
            // the next.
            let img = decode(&set.color);
            let g = |x: u32, y: u32| i32::from(img.get_pixel(x % 64, y % 64)[1]);
            for (name, step) in [("around", (1, 0)), ("along", (0, 1))] {
                let diff = |x: u32, y: u32| (g(x, y) - g(x + step.0, y + step.1)).abs();
                let seam: i32 = (0..64)
                    .map(|k| {
                        if step.0 == 1 {
                            diff(63, k)
                        } else {
                            diff(k, 63)
                        }
                    })
                    .sum();
                let inner: i32 = (0..63)
                    .map(|i| {
                        (0..64)
                            .map(|k| if step.0 == 1 { diff(i, k) } else { diff(k, i) })
                            .sum::<i32>()
                    })
                    .sum::<i32>()
                    / 63;
                assert!(
                    seam <= 2 * inner + 64,
                    "{style:?} {name}: seam {seam}, inside {inner}"
                );
            }
            let rough = decode(&set.roughness);
            assert!(
                rough.pixels().all(|p| p[1] > 100 && p[2] == 0),
                "{style:?}: rough, not metal"
            );
            colors.push(set.color.png.clone());
        }
        colors.dedup();
        assert_eq!(colors.len(), 4, "four different patterns");
    }

    #[test]
    fn a_set_is_its_maps_encoded() {
        for style in [BarkStyle::Plated, BarkStyle::Smooth] {
            let params = bark(style, 48);
            let (set, maps) = (bark_set(&params).expect("set"), bark_maps(&params));
            assert_eq!(
                set,
                encode_maps("bark", maps).expect("encodes"),
                "{style:?}"
            );
        }
        let leaf = crate::LeafParams {
            shape: crate::LeafShape::Lobed,
            size: 48,
            per_card: 1,
        };
        let (set, maps) = (
            crate::leaf_set(&leaf).expect("set"),
            crate::leaf_maps(&leaf),
        );
        // The same maps; the alpha cutoff is the leaf set's own.
        let set = crate::TextureSet {
            alpha_cutoff: None,
            ..set
        };
        assert_eq!(set, encode_maps("leaf", maps).expect("encodes"));
    }

    #[test]
    fn furrows_run_along_the_branch() {
        // Oak furrows are vertical: heights change faster around the branch (x) than along
        // it (y).
        let set = bark_set(&bark(BarkStyle::Furrowed, 128)).expect("bark");
        let img = decode(&set.color);
        let (mut dx, mut dy) = (0i64, 0i64);
        for y in 0..127 {
            for x in 0..127 {
                let g = |x, y| i64::from(img.get_pixel(x, y)[1]);
                dx += (g(x + 1, y) - g(x, y)).abs();
                dy += (g(x, y + 1) - g(x, y)).abs();
            }
        }
        assert!(dx > dy * 3 / 2, "around {dx}, along {dy}");
    }
}
