//! Every ring's frame and texture row, found once for the whole bark before the tubes are
//! written: the direction the ring faces, the side its seam (`u = 0`) lies on, and its `v`.
//!
//! The bark texture is wrapped a whole number of tiles around every branch (so the seam
//! does not show), the same number on every branch of a tree: the texture's features scale
//! with the branch's radius, as bark's plates and furrows do, and fade into the texture's
//! finer mipmaps on thin twigs. `v` runs along the branch at the same texel size as `u`
//! (the branch's circumference over the tiles), so texels stay square as the branch
//! tapers. Frames follow the branch by parallel transport, without twist. A lateral
//! carries on its parent's frame and `v` at the fork, so the texture runs on across the
//! joint instead of starting anew in a band around it.

use std::f32::consts::{PI, TAU};

use glam::Vec3;

use super::TubeSpec;

/// One ring's frame: the direction it faces, the unit side its seam lies on (across
/// `dir`), and its texture row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    pub(super) dir: Vec3,
    pub(super) side: Vec3,
    pub(super) v: f32,
}

/// How the texture is wrapped: tiles around every branch and the radius below which `v`
/// grows no faster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Wrap {
    /// Texture tiles around every branch (a whole number, at least 1).
    pub(super) tiles: f32,
    /// Radii below this count as this for `v` (so a tip of radius 0 has a finite `v`).
    floor: f32,
}

impl Wrap {
    /// The wrap of a tree whose thickest ring has radius `thickest`, with tiles of about
    /// `scale` metres around it (at most [`MAX_TILES`]).
    pub(super) fn new(thickest: f32, scale: f32) -> Wrap {
        let tiles = (TAU * thickest / scale).round().clamp(1.0, MAX_TILES);
        let floor = if thickest > 0.0 {
            0.02 * thickest
        } else {
            scale / TAU
        };
        Wrap { tiles, floor }
    }

    /// How far `v` grows between rings at `a` and `b` (centres and radii): the distance over
    /// a tile's height, which is the mean circumference over the tiles.
    fn dv(&self, (a, ra): (Vec3, f32), (b, rb): (Vec3, f32)) -> f32 {
        let r = ra.max(self.floor) + rb.max(self.floor);
        a.distance(b) * self.tiles / (PI * r)
    }
}

/// The most tiles around a branch: beyond it a tile would be a few centimetres on the
/// thickest trunk of a forest, with no detail left in its pixels.
pub(super) const MAX_TILES: f32 = 64.0;

/// The unit direction of every segment between the rings `pts`, each falling back to the
/// one before it (the first to `fallback`) where two rings sit at one place.
pub(super) fn segments(pts: &[(Vec3, f32, f32)], fallback: Vec3, out: &mut Vec<Vec3>) {
    out.clear();
    let first = pts
        .windows(2)
        .find_map(|w| (w[1].0 - w[0].0).try_normalize())
        .unwrap_or(fallback);
    let mut last = first;
    for w in pts.windows(2) {
        last = (w[1].0 - w[0].0).try_normalize().unwrap_or(last);
        out.push(last);
    }
}

/// The direction ring `j` faces, between its two segments `seg` (see [`segments`]).
pub(super) fn ring_dir(seg: &[Vec3], j: usize) -> Vec3 {
    if j == 0 {
        seg[0]
    } else if j == seg.len() {
        seg[j - 1]
    } else {
        (seg[j - 1] + seg[j]).try_normalize().unwrap_or(seg[j])
    }
}

/// Carries `side` from a ring facing `from` to a ring facing `to` (parallel transport),
/// keeping it a unit vector perpendicular to `to`.
pub(super) fn transport(side: Vec3, from: Vec3, to: Vec3) -> Vec3 {
    let rotated = glam::Quat::from_rotation_arc(from, to) * side;
    (rotated - to * rotated.dot(to))
        .try_normalize()
        .unwrap_or_else(|| to.any_orthonormal_vector())
}

/// The frames of every tube's rings, in the order of `points`: tube `k`'s rings are
/// `points[range(k)]`, and `nodes` names the skeleton node of each ring (`None` for a
/// lateral's first ring, inside its parent, and the flare's extra rings). A root tube's
/// seam starts on the side turned `away` from the light; a lateral's frame and `v` start
/// as its parent's at the fork, when the parent's tube came first (it does when every node
/// follows its parent). `skeleton_len` is the number of nodes.
pub(super) fn frames(
    tubes: &[TubeSpec],
    points: &[(Vec3, f32, f32)],
    nodes: &[Option<u32>],
    range: impl Fn(usize) -> std::ops::Range<usize>,
    skeleton_len: usize,
    wrap: Wrap,
    away: Vec3,
) -> Vec<Frame> {
    let mut out = Vec::with_capacity(points.len());
    let mut at_node: Vec<Option<Frame>> = vec![None; skeleton_len];
    let mut seg = Vec::new();
    for (k, tube) in tubes.iter().enumerate() {
        let (pts, ids) = (&points[range(k)], &nodes[range(k)]);
        if pts.len() < 2 {
            out.extend(pts.iter().map(|_| Frame {
                dir: tube.fallback,
                side: tube.fallback.any_orthonormal_vector(),
                v: 0.0,
            }));
            continue;
        }
        segments(pts, tube.fallback, &mut seg);
        let mut dir = ring_dir(&seg, 0);
        let parent = tube.fork.and_then(|f| at_node.get(f).copied().flatten());
        let (mut side, mut v) = match parent {
            Some(p) => (transport(p.side, p.dir, dir), p.v),
            None => (away_side(away, dir), 0.0),
        };
        for (j, (p, id)) in pts.iter().zip(ids).enumerate() {
            if j > 0 {
                let next = ring_dir(&seg, j);
                side = transport(side, dir, next);
                dir = next;
                v += wrap.dv((pts[j - 1].0, pts[j - 1].1), (p.0, p.1));
            }
            let frame = Frame { dir, side, v };
            out.push(frame);
            if let Some(slot) = id.and_then(|i| at_node.get_mut(i as usize)) {
                slot.get_or_insert(frame);
            }
        }
    }
    out
}

/// The unit side of a ring facing `dir` most turned towards `away`; any side across `dir`
/// when the ring's plane is (nearly) across `away`.
fn away_side(away: Vec3, dir: Vec3) -> Vec3 {
    let target = away - dir * away.dot(dir);
    if target.length_squared() > 0.0025 {
        target.normalize()
    } else {
        dir.any_orthonormal_vector()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_whole_and_v_keeps_texels_square() {
        // A 0.5 m trunk with 0.6 m tiles: 5 around (3.14 m / 0.6 m, rounded).
        let wrap = Wrap::new(0.5, 0.6);
        assert_eq!(wrap.tiles, 5.0);
        // Along a 0.5 m radius, a tile is 3.14 m / 5 tall; at 0.1 m, five times shorter.
        let dv = wrap.dv((Vec3::ZERO, 0.5), (Vec3::Y, 0.5));
        assert!((dv - 5.0 / (TAU * 0.5)).abs() < 1e-5, "{dv}");
        let thin = wrap.dv((Vec3::ZERO, 0.1), (Vec3::Y, 0.1));
        assert!((thin / dv - 5.0).abs() < 1e-4);
        // A tip of radius 0 counts as 1 cm (2% of the thickest).
        let tip = wrap.dv((Vec3::ZERO, 0.0), (Vec3::Y, 0.0));
        assert!(tip.is_finite() && (tip / dv - 50.0).abs() < 1e-3);
        assert_eq!(Wrap::new(0.01, 0.6).tiles, 1.0, "at least one tile");
        assert_eq!(Wrap::new(100.0, 0.6).tiles, MAX_TILES);
        assert!(
            Wrap::new(0.0, 0.6)
                .dv((Vec3::ZERO, 0.0), (Vec3::Y, 0.0))
                .is_finite()
        );
    }

    #[test]
    fn transport_keeps_a_unit_side_across_the_new_direction() {
        let side = transport(Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0).normalize());
        assert!((side.length() - 1.0).abs() < 1e-5);
        assert!(side.dot(Vec3::new(1.0, 1.0, 0.0)).abs() < 1e-5);
        // No twist: turning within the plane of the side keeps it in that plane.
        assert!(side.z.abs() < 1e-5);
        assert!(away_side(Vec3::Y, Vec3::Y).dot(Vec3::Y).abs() < 1e-5);
        assert_eq!(away_side(Vec3::X, Vec3::Y), Vec3::X);
    }
}
