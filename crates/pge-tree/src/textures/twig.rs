//! Twig cards: a card that draws a small twig bearing several leaves at their real size, so
//! that one quad shows a mass of foliage and its silhouette covers most of the card (a card
//! of one leaf covers a third of it or less, and a client's own mipmaps lose it).
//!
//! The card's coordinates are those of [`super::leaves`]: `x` across in `[-0.5, 0.5]`, `v`
//! from the stalk end (0) to the far edge (1). The twig runs up the middle from the stalk
//! end; leaves leave it alternately left and right, lower ones wider, and one ends it.

use super::blade::{LeafPixel, blade_half_width, blade_pixel};
use super::noise::{hash, unit};
use super::{LeafShape, card_share};
use pge_engine::math;

/// One leaf on the card: where its stalk starts, the unit direction up its blade, its
/// length in card units, a shade and the box that holds it.
#[derive(Clone, Copy, Debug)]
struct Placed {
    base: (f32, f32),
    dir: (f32, f32),
    length: f32,
    shade: f32,
    /// `x` and `v` bounds: `[x0, x1, v0, v1]`.
    bounds: [f32; 4],
}

/// The leaves of a twig card and its twig.
pub(super) struct Twig {
    shape: LeafShape,
    leaves: Vec<Placed>,
    /// Where the twig ends (`v`), 0 for a single leaf (no twig).
    top: f32,
    /// The blade's half-width at `WIDTHS` steps along a leaf (see [`Twig::width`]).
    widths: Vec<f32>,
}

/// Steps of the table of blade half-widths.
const WIDTHS: usize = 1024;

/// Half the widest blade of `shape` across its own length.
fn half_width(shape: LeafShape) -> f32 {
    match shape {
        LeafShape::Lanceolate => 0.15,
        LeafShape::Lobed | LeafShape::Ovate => 0.45,
        _ => 0.5,
    }
}

impl Twig {
    /// The twig of `per_card` leaves of `shape` (1: the leaf alone, filling the card).
    pub(super) fn new(shape: LeafShape, per_card: u32) -> Twig {
        let f = card_share(per_card);
        let widths = (0..=WIDTHS)
            .map(|i| blade_half_width(shape, (i as f32 / WIDTHS as f32 - 0.12) / 0.86))
            .collect();
        if per_card <= 1 {
            return Twig {
                shape,
                leaves: vec![placed((0.0, 0.0), (0.0, 1.0), 1.0, 1.0)],
                top: 0.0,
                widths,
            };
        }
        // The terminal leaf ends the twig just under the card's far edge.
        let top = 0.985 - f;
        let sides = per_card - 1;
        let mut leaves = Vec::with_capacity(per_card as usize);
        for i in 0..sides {
            let h = hash(i, per_card, 0x7319);
            let t = (i as f32 + 0.5) / sides as f32;
            let v = 0.02 + (top - 0.02) * t;
            // Lower leaves spread wider: 70 degrees from the twig at the foot, 35 at the top.
            let angle = (70.0 - 35.0 * t + 8.0 * (unit(h) - 0.5)).to_radians();
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            let dir = (side * math::sin(angle), math::cos(angle));
            // As long as the share allows, shortened to stay inside the card.
            let wanted = f * (0.9 + 0.2 * unit(h.rotate_left(11)));
            let half = half_width(shape);
            let across = dir.0.abs() + half * dir.1.abs();
            let up = dir.1 + half * dir.0.abs();
            let fits = (0.49 / across).min((0.995 - v) / up.max(1e-3));
            let shade = 0.9 + 0.14 * unit(h.rotate_left(23));
            leaves.push(placed((0.0, v), dir, wanted.min(fits), shade));
        }
        leaves.push(placed((0.0, top), (0.0, 1.0), f, 1.0));
        Twig {
            shape,
            leaves,
            top,
            widths,
        }
    }

    /// The blade's half-width at `v` along a leaf in `[0, 1]` ([`blade_half_width`] at
    /// `(v - 0.12) / 0.86`, interpolated in a table: the sines and powers once per card, not
    /// once per pixel).
    fn width(&self, v: f32) -> f32 {
        let t = v.clamp(0.0, 1.0) * WIDTHS as f32;
        let i = (t as usize).min(WIDTHS - 1);
        let f = t - i as f32;
        self.widths[i] * (1.0 - f) + self.widths[i + 1] * f
    }

    /// The card's pixel at `(x, v)`: the frontmost leaf there (the later, the nearer), else
    /// the twig, else clear.
    pub(super) fn pixel(&self, x: f32, v: f32) -> LeafPixel {
        for leaf in self.leaves.iter().rev() {
            let [x0, x1, v0, v1] = leaf.bounds;
            if x < x0 || x > x1 || v < v0 || v > v1 {
                continue;
            }
            let (dx, dv) = (x - leaf.base.0, v - leaf.base.1);
            let along = (dx * leaf.dir.0 + dv * leaf.dir.1) / leaf.length;
            let across = (dx * leaf.dir.1 - dv * leaf.dir.0) / leaf.length;
            if !(0.0..=1.0).contains(&along) || across.abs() > 0.5 {
                continue;
            }
            let mut p = blade_pixel(self.shape, across, along, self.width(along));
            if p.inside {
                p.shade *= leaf.shade;
                return p;
            }
        }
        // The twig, tapering from the stalk end to its top.
        let half = 0.011 - 0.005 * (v / self.top.max(1e-3));
        if v <= self.top && x.abs() < half {
            let k = x.abs() / half;
            return LeafPixel {
                inside: true,
                height: 0.7 * (1.0 - k * k),
                shade: 0.62,
                roughness: 0.8,
            };
        }
        LeafPixel::CLEAR
    }
}

/// A leaf with its bounding box.
fn placed(base: (f32, f32), dir: (f32, f32), length: f32, shade: f32) -> Placed {
    // The leaf's own square: its stalk edge's middle at `base`, `length` along `dir` and
    // `length` wide.
    let across = (dir.1, -dir.0);
    let corners = [-0.5f32, 0.5].map(|s| {
        [0.0f32, 1.0].map(|t| {
            (
                base.0 + (dir.0 * t + across.0 * s) * length,
                base.1 + (dir.1 * t + across.1 * s) * length,
            )
        })
    });
    let corners = corners.iter().flatten();
    let (mut x0, mut x1, mut v0, mut v1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for &(x, v) in corners {
        (x0, x1, v0, v1) = (x0.min(x), x1.max(x), v0.min(v), v1.max(v));
    }
    Placed {
        base,
        dir,
        length,
        shade,
        bounds: [x0, x1, v0, v1],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn coverage(twig: &Twig, n: usize) -> f32 {
        let mut inside = 0;
        for y in 0..n {
            for x in 0..n {
                let (u, v) = ((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
                inside += usize::from(twig.pixel(u - 0.5, v).inside);
            }
        }
        inside as f32 / (n * n) as f32
    }

    #[test]
    fn a_twig_covers_more_of_its_card_than_one_leaf_and_stays_inside_it() {
        for shape in [
            LeafShape::Ovate,
            LeafShape::Lobed,
            LeafShape::Lanceolate,
            LeafShape::Palmate,
        ] {
            let one = coverage(&Twig::new(shape, 1), 96);
            let twig = Twig::new(shape, 7);
            let seven = coverage(&twig, 96);
            assert!(seven > one, "{shape:?}: {seven} vs {one}");
            for leaf in &twig.leaves {
                let [x0, x1, v0, v1] = leaf.bounds;
                assert!(x0 >= -0.5 - 0.5 * leaf.length && x1 <= 0.5 + 0.5 * leaf.length);
                assert!(v0 >= -0.5 * leaf.length && v1 <= 1.0 + 0.5 * leaf.length);
                // The leaf's blade stays on the card: its tip is inside.
                let tip = (
                    leaf.base.0 + leaf.dir.0 * leaf.length,
                    leaf.base.1 + leaf.dir.1 * leaf.length,
                );
                assert!(
                    tip.0.abs() <= 0.5 && (0.0..=1.0).contains(&tip.1),
                    "{tip:?}"
                );
                assert!(leaf.length <= card_share(7) * 1.1 + 1e-6);
            }
            // Seven leaves, six of them on alternate sides.
            assert_eq!(twig.leaves.len(), 7);
            let left = twig.leaves.iter().filter(|l| l.dir.0 < -0.1).count();
            let right = twig.leaves.iter().filter(|l| l.dir.0 > 0.1).count();
            assert_eq!((left, right), (3, 3), "{shape:?}");
        }
        // The twig itself is drawn up the middle, under the leaves.
        let twig = Twig::new(LeafShape::Lanceolate, 5);
        assert!(twig.pixel(0.0, 0.01).inside);
    }
}
