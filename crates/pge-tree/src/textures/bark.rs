//! Bark: the four styles' patterns as height, colour and roughness per pixel.

use rayon::prelude::*;

use super::BarkStyle;
use super::maps::{Maps, Srgb, Surface};
use super::noise::{Cells, Fractal, Lattice, centre, floor, hash, smoothstep, unit, wrap};
use super::{BarkParams, TextureSet};
use crate::TreeError;

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
/// noise tables are made once per call, the per-row terms once per row. Textures are mapped
/// with `u` (pixel columns) around the branch and `v` (rows) along it, so "vertical" below
/// is along the branch. Every style keeps its colour and roughness with its relief: low
/// ground (furrows, cracks) darker and rougher than the surface.
fn bark_pixels(style: BarkStyle, color: [f32; 4], n: usize) -> (Vec<f32>, Vec<u8>, Vec<u8>) {
    let c = [color[0], color[1], color[2]];
    let l = 0.3 * c[0] + 0.55 * c[1] + 0.15 * c[2];
    let grey = |k: f32| [l * k, l * k, l * k];
    match style {
        BarkStyle::Furrowed => {
            // Oak: rough, flat-topped ridges between deep V-shaped furrows that run along
            // the branch, joining and parting (the borders of cells four times taller than
            // wide, wandering around the branch with a low noise), each ridge its own width,
            // its edges ragged; ridge tops broken into blocks by short horizontal cracks.
            let warp = Fractal::new(3, 2, 2, 11).for_pixels(n);
            let ridges = Cells::new(9, 2, 12);
            let lumps = Fractal::new(12, 8, 3, 13).for_pixels(n);
            let fibre = Fractal::new(48, 4, 2, 14).for_pixels(n);
            let light = grey(1.7);
            fill_bark(n, |v| {
                let (warp, fibre) = (warp.row(v).values(), fibre.row(v).values());
                let lumps = lumps.row(v).values();
                let ridges = ridges
                    .row(v)
                    .many((0..n).map(|x| centre(x, n) + 0.1 * (warp[x] - 0.5)));
                #[inline(always)]
                move |x, _| {
                    let (f1, f2, id) = ridges.at(x);
                    let (lump, fibre) = (lumps[x], fibre[x]);
                    // The furrow's wall rises from its floor to the ridge's top over a width
                    // of the ridge's own, its edge ragged.
                    let width = 0.28 + 0.3 * unit(id);
                    let wall = ((f2 - f1 - 0.03 + 0.12 * (lump - 0.5)) / width).clamp(0.0, 1.0);
                    let wall = wall * (2.0 - wall);
                    // A ridge's cross-cracks: short breaks across it, in some of its blocks.
                    let phase = v * 6.0 + unit(id) + 0.3 * lump;
                    let block = floor(phase);
                    let cracked = unit(hash(id, block as u32, 15)) < 0.6;
                    let across = 0.5 - (phase - block as f32 - 0.5).abs();
                    let crack = if cracked {
                        1.0 - smoothstep(0.0, 0.045, across)
                    } else {
                        0.0
                    };
                    let top = 0.72 + 0.08 * unit(id.rotate_left(9)) + 0.14 * lump + 0.06 * fibre;
                    let height = wall * (top - 0.2 * crack);
                    let lit = mix(c, light, 0.6 * smoothstep(0.5, 0.9, height) * lump);
                    Sample {
                        height,
                        shade: mix([0.0; 3], lit, 0.1 + 0.95 * wall * wall * top),
                        roughness: 0.98 - 0.18 * height,
                    }
                }
            })
        }
        BarkStyle::Plated | BarkStyle::Scaly => {
            // Pine: irregular plates split by deep dark cracks, each plate its own tint and
            // tilt, flaking into layers of smaller scales; spruce: the same, smaller and
            // thinner.
            let (plates_x, plates_y, crack_width, scales_x, scales_y) = match style {
                BarkStyle::Plated => (5, 3, 0.28, 12, 9),
                _ => (11, 9, 0.2, 24, 18),
            };
            let warp_u = Lattice::new(5, 5, 21).for_pixels(n);
            let warp_v = Lattice::new(5, 5, 22).for_pixels(n);
            let plates = Cells::new(plates_x, plates_y, 23);
            let scales = Cells::new(scales_x, scales_y, 24);
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
                    let crack = ((f2 - f1) * (1.0 / crack_width)).min(1.0);
                    let crack = crack * (2.0 - crack);
                    let (g1, g2, sub) = scales.at(x);
                    let scale = smoothstep(0.0, 0.1, g2 - g1);
                    let grain = grain[x];
                    let height = crack
                        * (0.5
                            + 0.2 * unit(id)
                            + 0.3 * (1.0 - f1)
                            + 0.14 * scale
                            + 0.08 * unit(sub)
                            + 0.1 * grain);
                    let plate = mix(c, warm, unit(id.rotate_left(7)));
                    let plate = mix(plate, light, 0.25 * unit(sub));
                    Sample {
                        height,
                        shade: mix(
                            [0.0; 3],
                            plate,
                            0.1 + 0.9 * crack * (0.8 + 0.2 * scale) + 0.1 * grain,
                        ),
                        roughness: 0.95 - 0.2 * crack,
                    }
                }
            })
        }
        BarkStyle::Smooth => {
            // Beech, birch: smooth mottled skin with shallow horizontal wrinkles, a fine
            // grain, and lenticels: short dark horizontal slits with raised lips, one per
            // cell at a random place and length.
            let mottle = Fractal::new(6, 6, 3, 31).for_pixels(n);
            let wrinkles = Fractal::new(2, 26, 2, 33).for_pixels(n);
            let grain = Fractal::new(40, 64, 2, 34).for_pixels(n);
            let light = grey(1.25);
            let dark = [c[0] * 0.18, c[1] * 0.15, c[2] * 0.13];
            fill_bark(n, |v| {
                let mottle = mottle.row(v).values();
                let (wrinkles, grain) = (wrinkles.row(v).values(), grain.row(v).values());
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
                    let dy = ((gy - cy) - py) / 0.12;
                    let d = dx * dx + dy * dy;
                    let (slit, lip) = if unit(h.rotate_left(5)) < 0.75 {
                        (
                            1.0 - smoothstep(0.2, 0.6, d),
                            smoothstep(0.2, 0.7, d) * (1.0 - smoothstep(0.8, 1.6, d)),
                        )
                    } else {
                        (0.0, 0.0)
                    };
                    let skin = mix(c, light, 0.3 * mottle);
                    Sample {
                        height: 0.25 * mottle + 0.5 * wrinkles[x] + 0.26 * grain[x] + 0.3 * lip
                            - 0.4 * slit,
                        shade: mix(skin, dark, slit),
                        roughness: 0.55 + 0.35 * slit + 0.1 * mottle,
                    }
                }
            })
        }
        BarkStyle::Fibrous => {
            // Willow: long narrow strips along the branch between deep narrow furrows,
            // interlacing as they wander, each its own width, and fine fibres along them.
            let warp = Fractal::new(4, 2, 2, 41).for_pixels(n);
            let ridges = Cells::new(16, 1, 42);
            let fibres = Fractal::new(96, 3, 2, 43).for_pixels(n);
            let light = grey(1.4);
            fill_bark(n, |v| {
                let (warp, fibres) = (warp.row(v).values(), fibres.row(v).values());
                let ridges = ridges
                    .row(v)
                    .many((0..n).map(|x| centre(x, n) + 0.12 * (warp[x] - 0.5)));
                #[inline(always)]
                move |x, _| {
                    let (f1, f2, id) = ridges.at(x);
                    let fibres = fibres[x];
                    let width = 0.2 + 0.25 * unit(id);
                    let strip = ((f2 - f1 + 0.1 * (fibres - 0.5)) / width).clamp(0.0, 1.0);
                    let strip = strip * (2.0 - strip);
                    let height =
                        strip * (0.7 + 0.1 * unit(id)) + 0.3 * fibres * (0.3 + 0.7 * strip);
                    Sample {
                        height,
                        shade: mix(
                            [0.0; 3],
                            mix(c, light, 0.35 * fibres),
                            0.15 + 0.9 * height * height.sqrt(),
                        ),
                        roughness: 0.95 - 0.15 * height,
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
        BarkStyle::Furrowed => 16.0,
        BarkStyle::Plated | BarkStyle::Scaly => 15.5,
        BarkStyle::Smooth => 20.0,
        BarkStyle::Fibrous => 12.0,
    }
}

/// The bark set of `params`: its maps generated (as [`bark_maps`]) and encoded in the
/// params' format.
pub fn bark_set(params: &BarkParams) -> Result<TextureSet, TreeError> {
    bark_surface(params).encode_as("bark", params.format)
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
    use pge_engine::geometry::ImageFormat;
    use pge_engine::math;

    #[test]
    fn every_bark_style_has_relief_and_tiles() {
        let mut colors = Vec::new();
        for style in STYLES {
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
            colors.push(set.color.encoded.clone());
        }
        colors.dedup();
        assert_eq!(colors.len(), STYLES.len(), "different patterns");
    }

    #[test]
    fn a_set_is_its_maps_encoded() {
        for style in [BarkStyle::Plated, BarkStyle::Smooth] {
            for format in [crate::TextureFormat::Png, crate::TextureFormat::Jpeg] {
                let params = BarkParams {
                    format,
                    ..bark(style, 48)
                };
                let (set, maps) = (bark_set(&params).expect("set"), bark_maps(&params));
                assert_eq!(
                    set,
                    crate::encode_maps_as("bark", maps, format).expect("encodes"),
                    "{style:?}"
                );
            }
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

    const STYLES: [BarkStyle; 5] = [
        BarkStyle::Furrowed,
        BarkStyle::Plated,
        BarkStyle::Smooth,
        BarkStyle::Fibrous,
        BarkStyle::Scaly,
    ];

    /// A normal map's relief as the bark shows it, from its RGB bytes (decoded as glTF does:
    /// `2 * byte / 255 - 1`, then normalized): the mean tilt in degrees (the angle between
    /// the normal and +Z, the flat surface's), and the gradient energy around the branch and
    /// along it. The texture is mapped with `u` (columns, x) around the branch and `v` (rows,
    /// y) along it, and a normal's x (y) is the height's slope along x (y): the energy around
    /// is the sum over the pixels of the squared x components, the height's differences
    /// between neighbours in a row; along, of the squared y components, between neighbours
    /// in a column. Furrows that run along the branch change the height around it: the
    /// energy around is the larger.
    fn relief(normal: &[u8]) -> (f32, f64, f64) {
        let (mut tilt, mut around, mut along) = (0.0f64, 0.0f64, 0.0f64);
        let pixels = normal.len() / 3;
        for p in normal.chunks_exact(3) {
            let n = glam::Vec3::from_array([0, 1, 2].map(|i| f32::from(p[i]) / 255.0 * 2.0 - 1.0))
                .normalize();
            tilt += f64::from(math::acos(n.z.clamp(-1.0, 1.0)).to_degrees());
            around += f64::from(n.x * n.x);
            along += f64::from(n.y * n.y);
        }
        ((tilt / pixels as f64) as f32, around, along)
    }

    /// The RGB bytes of a decoded map.
    fn rgb(t: &pge_engine::geometry::Texture) -> Vec<u8> {
        decode(t)
            .pixels()
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect()
    }

    #[test]
    fn every_style_reads_in_relief_and_furrows_run_along_the_branch() {
        for style in STYLES {
            let maps = bark_maps(&bark(style, 512));
            let (tilt, around, along) = relief(&maps.normal);
            println!(
                "{style:?}: tilt {tilt:.1} degrees, around / along {:.2}",
                around / along
            );
            assert!(tilt >= 20.0, "{style:?}: mean tilt {tilt} degrees");
            if matches!(style, BarkStyle::Furrowed | BarkStyle::Fibrous) {
                assert!(
                    around >= 2.0 * along,
                    "{style:?}: gradient energy around {around}, along {along}"
                );
            }
            // The same in the heights themselves: squared differences along rows (around)
            // and along columns (along), wrapping.
            if matches!(style, BarkStyle::Furrowed | BarkStyle::Fibrous) {
                let (n, h) = (512, bark_surface(&bark(style, 512)).heights);
                let (mut du, mut dv) = (0.0f64, 0.0f64);
                for y in 0..n {
                    for x in 0..n {
                        let here = f64::from(h[y * n + x]);
                        du += (f64::from(h[y * n + (x + 1) % n]) - here).powi(2);
                        dv += (f64::from(h[(y + 1) % n * n + x]) - here).powi(2);
                    }
                }
                assert!(du >= 2.0 * dv, "{style:?}: heights around {du}, along {dv}");
            }
        }
    }

    #[test]
    fn relief_keeps_its_tilt_at_every_map_size() {
        // Features are a share of the tile, so a smaller map has steeper steps per texel and
        // the strength follows the size: the tilt stays near the 512 px map's.
        for style in [BarkStyle::Furrowed, BarkStyle::Plated] {
            let (at512, ..) = relief(&bark_maps(&bark(style, 512)).normal);
            let (at256, ..) = relief(&bark_maps(&bark(style, 256)).normal);
            assert!((at256 - at512).abs() < 5.0, "{style:?}: {at256} vs {at512}");
        }
    }

    #[test]
    fn furrows_are_darker_and_rougher_than_ridges() {
        for style in STYLES {
            let surface = bark_surface(&bark(style, 128));
            let mut order: Vec<usize> = (0..surface.heights.len()).collect();
            order.sort_by(|&a, &b| surface.heights[a].total_cmp(&surface.heights[b]));
            let quarter = order.len() / 4;
            let (low, high) = (&order[..quarter], &order[order.len() - quarter..]);
            let mean = |pixels: &[usize], f: &dyn Fn(usize) -> f32| {
                pixels.iter().map(|&i| f(i)).sum::<f32>() / pixels.len() as f32
            };
            let light = |i: usize| {
                let c = &surface.color[i * 3..i * 3 + 3];
                f32::from(c[0]) + f32::from(c[1]) + f32::from(c[2])
            };
            let rough = |i: usize| f32::from(surface.roughness[i * 3 + 1]);
            assert!(
                mean(low, &light) < mean(high, &light),
                "{style:?}: the lowest quarter is not darker"
            );
            assert!(
                mean(low, &rough) > mean(high, &rough),
                "{style:?}: the lowest quarter is not rougher"
            );
        }
    }

    #[test]
    fn jpeg_maps_keep_their_relief_and_colour() {
        for style in STYLES {
            let params = bark(style, 256);
            let maps = bark_maps(&params);
            let set = bark_set(&BarkParams {
                format: crate::TextureFormat::Jpeg,
                ..params
            })
            .expect("bark");
            for t in [&set.color, &set.normal, &set.roughness] {
                assert_eq!(t.format(), ImageFormat::Jpeg, "{style:?}: {}", t.name);
            }
            // The decoded normals' mean tilt within a degree of the exact map's, and every
            // normal within a few degrees of its own.
            let normal = rgb(&set.normal);
            let ((exact, ..), (jpeg, ..)) = (relief(&maps.normal), relief(&normal));
            assert!(
                (jpeg - exact).abs() < 1.0,
                "{style:?}: tilt {jpeg} vs {exact}"
            );
            let decode = |p: &[u8]| {
                glam::Vec3::from_array([0, 1, 2].map(|i| f32::from(p[i]) / 127.5 - 1.0)).normalize()
            };
            let error: f32 = maps
                .normal
                .chunks_exact(3)
                .zip(normal.chunks_exact(3))
                .map(|(a, b)| math::acos(decode(a).dot(decode(b)).clamp(-1.0, 1.0)).to_degrees())
                .sum::<f32>()
                / (256 * 256) as f32;
            println!("{style:?}: tilt {exact:.2} exact, {jpeg:.2} as JPEG, each off {error:.2}");
            assert!(
                error < 3.0,
                "{style:?}: normals off by {error} degrees on average"
            );
            // Colour and roughness within a few levels on average.
            let off = |a: &[u8], b: &[u8]| {
                a.iter()
                    .zip(b)
                    .map(|(a, b)| f32::from(a.abs_diff(*b)))
                    .sum::<f32>()
                    / a.len() as f32
            };
            assert!(off(&rgb(&set.color), &maps.color) < 4.0, "{style:?}");
            let rough = rgb(&set.roughness);
            let g = |px: &[u8]| px.chunks_exact(3).map(|p| p[1]).collect::<Vec<u8>>();
            assert!(off(&g(&rough), &g(&maps.roughness)) < 3.0, "{style:?}");
            // Grey: the metalness (B) is the roughness, cancelled by the metallic factor 0.
            assert!(rough.chunks_exact(3).all(|p| p[0] == p[1] && p[1] == p[2]));
        }
    }
}
