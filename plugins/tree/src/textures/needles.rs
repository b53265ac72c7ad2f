//! Needle sprays: a twig with needles on both sides, for conifers.

use super::leaves::LeafPixel;
use super::noise::{hash, unit};

/// leaves the twig, its length and its hash.
#[derive(Clone, Copy)]
struct Needle {
    dir: (f32, f32),
    t0: f32,
    len: f32,
    h: u32,
}

/// A needle spray: a twig up the middle of the card with needles leaving it on both sides
/// at about 50 degrees towards the tip, each a little different in angle and length (the
/// needles of both sides made once, not per pixel).
pub(super) struct Needles {
    sides: [Vec<Needle>; 2],
}

const NEEDLE_SPACING: f32 = 0.018;
const NEEDLE_COUNT: i64 = 52;

impl Needles {
    pub(super) fn new() -> Needles {
        let base = 50f32.to_radians();
        let side = |side: u32| {
            (0..=NEEDLE_COUNT as u32)
                .map(|i| {
                    let h = hash(i, side, 51);
                    let angle = base + (unit(h) - 0.5) * 0.35;
                    let t0 = i as f32 * NEEDLE_SPACING;
                    let taper = 1.0 - t0;
                    let len =
                        (0.34 + 0.12 * unit(h.rotate_left(9))) * (0.45 + 0.55 * taper.max(0.0));
                    Needle {
                        dir: angle.sin_cos(),
                        t0,
                        len,
                        h,
                    }
                })
                .collect()
        };
        Needles {
            sides: [side(0), side(1)],
        }
    }

    pub(super) fn pixel(&self, x: f32, v: f32) -> LeafPixel {
        let twig = x.abs() < 0.012 * (1.2 - v) && v < 0.97;
        if twig {
            return LeafPixel {
                inside: true,
                height: 0.8,
                shade: 0.75,
                roughness: 0.8,
            };
        }
        let needles = &self.sides[usize::from(x < 0.0)];
        let ax = x.abs();
        // The needle through this pixel starts at t0 = v - |x| cot(angle); look at the
        // nearest starts (cot 50 degrees = 0.8391).
        let guess = ((v - ax * 0.839_099_6) / NEEDLE_SPACING).round() as i64;
        for i in (guess - 2).max(1)..=(guess + 2).min(NEEDLE_COUNT) {
            let nd = needles[i as usize];
            let (dx, dy) = nd.dir;
            let (px, py) = (ax, v - nd.t0);
            let along = px * dx + py * dy;
            if along < 0.0 || along > nd.len {
                continue;
            }
            let across = (px * dy - py * dx).abs();
            let half = 0.0055 * (1.0 - 0.7 * along / nd.len);
            if across < half {
                let k = across / half;
                return LeafPixel {
                    inside: true,
                    height: 0.6 * (1.0 - k * k),
                    shade: 0.85 + 0.12 * (1.0 - k) + 0.03 * unit(nd.h),
                    roughness: 0.45,
                };
            }
        }
        LeafPixel {
            inside: false,
            height: 0.0,
            shade: 1.0,
            roughness: 0.6,
        }
    }
}
