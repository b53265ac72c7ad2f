//! Needle sprays: shoots densely covered in needles, for conifers. One shoot runs up the
//! card; a spray of several has side shoots leaving it alternately left and right. Needles
//! stand all round a real shoot, so seen from the side they leave it at different apparent
//! angles and lengths: each shoot draws three layers of needles on both sides, dense enough
//! that the band around the shoot reads as a mass, as a spruce or fir shoot does.

use super::blade::LeafPixel;
use super::card_share;
use super::noise::{hash, unit};
use pge_engine::math;

/// One layer of needles on one side of a shoot: the apparent angle from the shoot, the
/// apparent length (card units) and the offset of the first needle along the shoot.
#[derive(Clone, Copy)]
struct Layer {
    angle: f32,
    cot: f32,
    length: f32,
    offset: f32,
}

/// One needle: the sine and cosine of its angle from the shoot, its length and a hash for
/// its shade.
#[derive(Clone, Copy)]
struct Needle {
    sin: f32,
    cos: f32,
    len: f32,
    h: u32,
}

/// A shoot: where it starts, its unit direction and its length (card units), the box that
/// holds it with its needles, and its needles by side and layer (made once, not per pixel).
struct Shoot {
    base: (f32, f32),
    dir: (f32, f32),
    length: f32,
    bounds: [f32; 4],
    needles: [[Vec<Needle>; 3]; 2],
}

/// A spray of needle shoots (see the module docs).
pub(super) struct Needles {
    shoots: Vec<Shoot>,
    layers: [Layer; 3],
}

/// Needles along a shoot, card units between two of one layer on one side.
const SPACING: f32 = 0.03;
/// Half the width of a needle at its base, card units.
const HALF_WIDTH: f32 = 0.008;

impl Needles {
    /// A spray of `shoots` shoots (1: one shoot up the middle of the card).
    pub(super) fn new(shoots: u32) -> Needles {
        let layers = [
            (38.0f32, 0.8f32, 0.0f32),
            (58.0, 1.0, 0.33),
            (80.0, 0.7, 0.66),
        ]
        .map(|(degrees, length, offset)| {
            let angle = degrees.to_radians();
            Layer {
                angle,
                cot: math::cos(angle) / math::sin(angle),
                length,
                offset: offset * SPACING,
            }
        });
        let mut list = Vec::new();
        if shoots <= 1 {
            list.push(shoot((0.0, 0.02), (0.0, 1.0), 0.94, 0.5, &layers));
        } else {
            let f = card_share(shoots);
            let needle = 0.34 * f;
            // The main shoot up the middle, side shoots from its lower part, shorter
            // towards its tip.
            list.push(shoot((0.0, 0.01), (0.0, 1.0), 0.96, needle, &layers));
            let sides = shoots - 1;
            for i in 0..sides {
                let t = (i as f32 + 0.5) / sides as f32;
                let h = hash(i, shoots, 0x5e11);
                let v = 0.08 + 0.62 * t;
                let angle = (50.0 - 12.0 * t + 8.0 * (unit(h) - 0.5)).to_radians();
                let side = if i % 2 == 0 { 1.0 } else { -1.0 };
                let dir = (side * math::sin(angle), math::cos(angle));
                let reach = needle * 0.7;
                let fits = ((0.5 - reach) / dir.0.abs()).min((0.99 - reach - v) / dir.1);
                let length = (f * (1.1 - 0.4 * t)).min(fits).max(0.05);
                list.push(shoot((0.0, v), dir, length, needle, &layers));
            }
        }
        Needles {
            shoots: list,
            layers,
        }
    }

    /// The spray's pixel at `(x, v)` (card coordinates as [`super::leaves`]'): a shoot's
    /// twig, else a needle, else clear.
    pub(super) fn pixel(&self, x: f32, v: f32) -> LeafPixel {
        for s in self.shoots.iter().rev() {
            let [x0, x1, v0, v1] = s.bounds;
            if x < x0 || x > x1 || v < v0 || v > v1 {
                continue;
            }
            let (dx, dv) = (x - s.base.0, v - s.base.1);
            let along = dx * s.dir.0 + dv * s.dir.1;
            let across = dx * s.dir.1 - dv * s.dir.0;
            if let Some(p) = self.shoot_pixel(s, along, across) {
                return p;
            }
        }
        LeafPixel::CLEAR
    }

    /// The pixel `along` a shoot and `across` it (card units), if the shoot draws it.
    fn shoot_pixel(&self, s: &Shoot, along: f32, across: f32) -> Option<LeafPixel> {
        let twig = 0.009 * (1.15 - along / s.length);
        if (0.0..=s.length).contains(&along) && across.abs() < twig {
            return Some(LeafPixel {
                inside: true,
                height: 0.8,
                shade: 0.7,
                roughness: 0.8,
            });
        }
        let side = &s.needles[usize::from(across < 0.0)];
        let ax = across.abs();
        for (layer, needles) in self.layers.iter().zip(side) {
            // The needle through this pixel starts at along - |across| cot(angle).
            let start = along - ax * layer.cot - layer.offset;
            let guess = (start / SPACING).round() as i64;
            let first = (guess - 1).max(0) as usize;
            let last = ((guess + 1).max(-1) + 1) as usize;
            for (i, n) in needles
                .iter()
                .enumerate()
                .take(last.min(needles.len()))
                .skip(first)
            {
                let t0 = i as f32 * SPACING + layer.offset;
                let (px, py) = (ax, along - t0);
                let d = px * n.sin + py * n.cos;
                if d < 0.0 || d > n.len {
                    continue;
                }
                let off = (px * n.cos - py * n.sin).abs();
                let half = HALF_WIDTH * (1.0 - 0.6 * d / n.len);
                if off < half {
                    let q = off / half;
                    return Some(LeafPixel {
                        inside: true,
                        height: 0.6 * (1.0 - q * q),
                        shade: 0.84 + 0.12 * (1.0 - q) + 0.04 * unit(n.h.rotate_left(19)),
                        roughness: 0.45,
                    });
                }
            }
        }
        None
    }
}

/// A shoot with the box that holds it and its needles: along it every [`SPACING`] (from
/// each layer's offset) on both sides, each a little turned and of its own length, shorter
/// towards the tip; `needle` is their full length.
fn shoot(
    base: (f32, f32),
    dir: (f32, f32),
    length: f32,
    needle: f32,
    layers: &[Layer; 3],
) -> Shoot {
    let tip = (base.0 + dir.0 * length, base.1 + dir.1 * length);
    let reach = needle * 1.2;
    let needles = [0u32, 1].map(|side| {
        [0usize, 1, 2].map(|k| {
            let layer = layers[k];
            let count = ((length - layer.offset) / SPACING).floor().max(0.0) as u32 + 1;
            (0..count)
                .map(|i| {
                    let t0 = i as f32 * SPACING + layer.offset;
                    let h = hash(i, side * 4 + k as u32, 0x9ee1);
                    let taper = 1.0 - 0.45 * (t0 / length);
                    let turn = (unit(h.rotate_left(7)) - 0.5) * 0.2;
                    let (sin, cos) = math::sin_cos(layer.angle + turn);
                    Needle {
                        sin,
                        cos,
                        len: needle * layer.length * taper * (0.85 + 0.3 * unit(h)),
                        h,
                    }
                })
                .collect()
        })
    });
    Shoot {
        base,
        dir,
        length,
        bounds: [
            base.0.min(tip.0) - reach,
            base.0.max(tip.0) + reach,
            base.1.min(tip.1) - reach,
            base.1.max(tip.1) + reach,
        ],
        needles,
    }
}
