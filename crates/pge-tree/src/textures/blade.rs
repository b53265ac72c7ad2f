//! One broad leaf's blade: its outline along the card and the pixel it draws (silhouette,
//! midrib and side veins, a domed height), which twigs ([`super::twig`]) lay out on a card.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use pge_engine::math;

use super::LeafShape;
use super::noise::{floor, smoothstep};

/// What a leaf texture holds at one pixel: inside the silhouette or not, a height (veins
/// sunk, the blade domed) and a shade (veins lighter).
pub(super) struct LeafPixel {
    pub(super) inside: bool,
    pub(super) height: f32,
    pub(super) shade: f32,
    pub(super) roughness: f32,
}

/// Half-width of an ovate blade at `t` along it (0 at the stalk end, 1 at the tip).
fn ovate(t: f32) -> f32 {
    if !(0.0..=1.0).contains(&t) {
        return 0.0;
    }
    0.44 * math::powf(math::sin(PI * math::powf(t, 0.8)).max(0.0), 0.85) * (1.0 - 0.25 * t)
}

/// Half-width of a blade of `shape` at `t` along it, for the shapes with a midrib.
pub(super) fn blade_half_width(shape: LeafShape, t: f32) -> f32 {
    if !(0.0..=1.0).contains(&t) {
        return 0.0;
    }
    match shape {
        LeafShape::Lobed => {
            // Oak: four to five rounded lobes a side, deep sinuses between them.
            let outline = 0.42
                * math::powf(math::sin(PI * math::powf(t, 0.85)).max(0.0), 0.6)
                * (1.0 - 0.15 * t);
            let lobes = 0.5 + 0.5 * math::cos(TAU * 4.5 * t - 0.6);
            outline * (0.55 + 0.45 * lobes.sqrt())
        }
        LeafShape::Lanceolate => {
            0.14 * math::powf(math::sin(PI * math::powf(t, 0.75)).max(0.0), 0.9)
        }
        _ => ovate(t),
    }
}

impl LeafPixel {
    /// A pixel outside every silhouette.
    pub(super) const CLEAR: LeafPixel = LeafPixel {
        inside: false,
        height: 0.0,
        shade: 1.0,
        roughness: 0.6,
    };
}

/// The pixel at `(x, v)` of one broad leaf filling its card: `x` across the card in
/// `[-0.5, 0.5]`, `v` from the stalk (0) to the far edge (1); `w` is the blade's half-width
/// in this row (shapes with a midrib: [`blade_half_width`] at `(v - 0.12) / 0.86`).
/// `Needles` draws nothing here (see [`super::needles`]).
pub(super) fn blade_pixel(shape: LeafShape, x: f32, v: f32, w: f32) -> LeafPixel {
    let outside = LeafPixel::CLEAR;
    let stalk = v < 0.13 && x.abs() < 0.014;
    match shape {
        LeafShape::Needles => outside,
        LeafShape::Palmate => {
            // Maple: five pointed lobes around the top of the stalk, main veins radiating
            // to their tips.
            let (dx, dy) = (x, v - 0.4);
            let r = (dx * dx + dy * dy).sqrt();
            // No lobe reaches 0.58 from the centre and the blade starts above 0.12: the rest
            // of the card is clear without finding the angle.
            if !stalk && (r >= 0.58 || v <= 0.12) {
                return outside;
            }
            let phi = atan2(dy, dx); // pi/2 is up the card.
            let lobe_axes = [PI / 2.0, PI / 2.0 - 0.95, PI / 2.0 + 0.95, -0.25, PI + 0.25];
            let lobe_len = [0.58, 0.5, 0.5, 0.36, 0.36];
            let (mut reach, mut vein) = (0.0f32, f32::MAX);
            for (axis, len) in lobe_axes.iter().zip(lobe_len) {
                let off = angle_diff(phi, *axis).abs();
                // Only the lobes within 0.62 rad reach this far round (the others are 0).
                if off < 0.62 {
                    let lobe = len * math::powf(1.0 - off / 0.62, 0.8);
                    let teeth = 1.0 - 0.06 * (0.5 + 0.5 * math::cos(off * 28.0));
                    reach = reach.max(lobe * teeth);
                }
                vein = vein.min(off * r);
            }
            let reach = reach.max(0.12);
            let inside = stalk || (r < reach && v > 0.12);
            if !inside {
                return outside;
            }
            let veins = 1.0 - smoothstep(0.004, 0.012, vein);
            let side = side_veins(dx.abs() + 0.3 * r, r, 0.09);
            let edge = r / reach;
            LeafPixel {
                inside,
                height: 0.6 * (1.0 - edge * edge) - 0.5 * veins - 0.2 * side,
                shade: if stalk {
                    1.0
                } else {
                    0.82 + 0.16 * veins + 0.05 * side - 0.1 * edge
                },
                roughness: 0.5 + 0.2 * veins,
            }
        }
        _ => {
            let inside = stalk || x.abs() < w;
            if !inside {
                return outside;
            }
            let across = x.abs() / w.max(1e-3);
            let midrib = 1.0 - smoothstep(0.006, 0.014, x.abs());
            let slope = if shape == LeafShape::Lanceolate {
                3.0
            } else {
                0.9
            };
            let spacing = if shape == LeafShape::Lanceolate {
                0.06
            } else {
                0.1
            };
            let side =
                side_veins(v - x.abs() * slope, x.abs(), spacing) * smoothstep(1.0, 0.8, across);
            let veins = midrib.max(side);
            LeafPixel {
                inside,
                height: 0.5 * (1.0 - across * across) - 0.5 * midrib - 0.3 * side,
                shade: if stalk {
                    1.0
                } else {
                    0.8 + 0.18 * veins - 0.1 * across
                },
                roughness: 0.5 + 0.2 * veins,
            }
        }
    }
}

/// Secondary veins: thin lines where `along` is a multiple of `spacing`, fading with
/// distance `out` from the midrib.
fn side_veins(along: f32, out: f32, spacing: f32) -> f32 {
    let f = along / spacing;
    let f = f - floor(f) as f32;
    let d = f.min(1.0 - f) * spacing;
    (1.0 - smoothstep(0.002, 0.006, d)) * (1.0 - smoothstep(0.25, 0.5, out))
}

/// `a - b` wrapped to `[-pi, pi]`, for angles `a` in `[-pi, pi]` and `b` within `pi / 2`
/// of that range (the lobe axes).
fn angle_diff(a: f32, b: f32) -> f32 {
    let d = a - b;
    if d > PI {
        d - TAU
    } else if d < -PI {
        d + TAU
    } else {
        d
    }
}

/// The angle of `(x, y)` in `[-pi, pi]`, as `f32::atan2` within 1e-6 rad, from the
/// arctangent polynomial of Abramowitz and Stegun (4.4.49) on `[0, 1]` and the octant's
/// symmetries: a few multiply-adds where the library call costs as much as the rest of a
/// maple pixel.
fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi == 0.0 {
        return 0.0;
    }
    let z = lo / hi;
    let z2 = z * z;
    let poly = 0.002_866_225_7f32;
    let poly = poly * z2 - 0.016_165_737;
    let poly = poly * z2 + 0.042_909_614;
    let poly = poly * z2 - 0.075_289_64;
    let poly = poly * z2 + 0.106_562_64;
    let poly = poly * z2 - 0.142_089;
    let poly = poly * z2 + 0.199_935_51;
    let poly = poly * z2 - 0.333_331_45;
    let mut a = z + z * z2 * poly;
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 { -a } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn willow_blades_are_narrow_and_oak_outlines_have_sinuses() {
        assert!(
            blade_half_width(LeafShape::Lanceolate, 0.5) * 2.5
                < blade_half_width(LeafShape::Ovate, 0.5)
        );
        // The oak outline goes in and out: the half-width along the blade has several
        // local minima (the sinuses).
        let w: Vec<f32> = (1..100)
            .map(|i| blade_half_width(LeafShape::Lobed, i as f32 / 100.0))
            .collect();
        let sinuses = w.windows(3).filter(|s| s[1] < s[0] && s[1] < s[2]).count();
        assert!(sinuses >= 3, "{sinuses} sinuses");
        assert_eq!(blade_half_width(LeafShape::Ovate, -0.1), 0.0);
        assert!(blade_half_width(LeafShape::Ovate, 1.0) < 0.01);
    }

    #[test]
    fn the_polynomial_arctangent_is_the_library_one() {
        for i in -60..=60 {
            for j in -60..=60 {
                let (y, x) = (i as f32 / 37.0, j as f32 / 41.0);
                let want = if (x, y) == (0.0, 0.0) {
                    0.0
                } else {
                    math::atan2(y, x)
                };
                assert!((atan2(y, x) - want).abs() < 1e-6, "{y} {x}");
            }
        }
        for (a, b) in [
            (3.0f32, -0.25f32),
            (-3.0, PI + 0.25),
            (0.5, PI / 2.0),
            (-PI, PI),
        ] {
            let want = a - b - TAU * ((a - b) / TAU).round();
            assert!((angle_diff(a, b) - want).abs() < 1e-5, "{a} {b}");
            assert!(angle_diff(a, b).abs() <= PI + 1e-6);
        }
    }
}
