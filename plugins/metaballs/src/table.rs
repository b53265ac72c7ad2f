//! The marching cubes case table, generated so that neighbouring cells always agree.
//!
//! Corner `c` of a cell sits at offset `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`. The table is
//! built from the faces rather than typed in: on every face the crossing points are joined
//! by segments, and on an ambiguous face (two diagonal corners inside, two outside) the
//! segments always cut off the *inside* corners. A face's segments therefore depend on that
//! face alone, so the two cells sharing it draw the same segments and the surface has no
//! cracks; each case's segments are chained into loops and each loop is fanned into
//! triangles. Triangles are wound counter-clockwise seen from outside (from lower values).

use std::sync::OnceLock;

use glam::Vec3;

/// The 12 edges of a cell: `(lower corner, upper corner, axis)`.
pub const EDGES: [(usize, usize, usize); 12] = [
    (0, 1, 0),
    (2, 3, 0),
    (4, 5, 0),
    (6, 7, 0),
    (0, 2, 1),
    (1, 3, 1),
    (4, 6, 1),
    (5, 7, 1),
    (0, 4, 2),
    (1, 5, 2),
    (2, 6, 2),
    (3, 7, 2),
];

/// The offset of a corner inside its cell.
#[must_use]
pub fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

fn corner_pos(c: usize) -> Vec3 {
    let [x, y, z] = corner_offset(c);
    Vec3::new(x as f32, y as f32, z as f32)
}

fn edge_between(a: usize, b: usize) -> usize {
    let (lo, hi) = (a.min(b), a.max(b));
    EDGES
        .iter()
        .position(|&(p, q, _)| p == lo && q == hi)
        .unwrap_or(usize::MAX)
}

fn edge_mid(e: usize) -> Vec3 {
    (corner_pos(EDGES[e].0) + corner_pos(EDGES[e].1)) * 0.5
}

/// The triangles (as edge indices) of every one of the 256 corner configurations; bit `c` of
/// the case index is set when corner `c` is inside.
pub fn table() -> &'static [Vec<[u8; 3]>; 256] {
    static TABLE: OnceLock<[Vec<[u8; 3]>; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(triangles_of_case))
}

fn triangles_of_case(case: usize) -> Vec<[u8; 3]> {
    let inside = |c: usize| case & (1 << c) != 0;
    // Directed segments on the faces: next[start edge] = end edge.
    let mut next = [usize::MAX; 12];
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2 {
            let normal = {
                let mut n = [0.0f32; 3];
                n[axis] = if side == 0 { -1.0 } else { 1.0 };
                Vec3::from(n)
            };
            // The face's corners in cyclic order.
            let corner = |du: usize, dv: usize| (side << axis) | (du << u) | (dv << v);
            let ring = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            let crossed: Vec<usize> = (0..4)
                .filter(|&i| inside(ring[i]) != inside(ring[(i + 1) % 4]))
                .collect();
            // (edge a, edge b, an inside corner on the side the segment cuts off)
            let mut segments = Vec::new();
            match crossed.len() {
                2 => {
                    let rep = ring.iter().copied().find(|&c| inside(c)).unwrap_or(ring[0]);
                    let e = |i: usize| edge_between(ring[i], ring[(i + 1) % 4]);
                    segments.push((e(crossed[0]), e(crossed[1]), rep));
                }
                4 => {
                    for i in 0..4 {
                        if inside(ring[i]) {
                            let before = edge_between(ring[(i + 3) % 4], ring[i]);
                            let after = edge_between(ring[i], ring[(i + 1) % 4]);
                            segments.push((before, after, ring[i]));
                        }
                    }
                }
                _ => {}
            }
            for (a, b, rep) in segments {
                let (pa, pb) = (edge_mid(a), edge_mid(b));
                let toward_inside = corner_pos(rep) - (pa + pb) * 0.5;
                let (start, end) = if (pb - pa).cross(normal).dot(toward_inside) > 0.0 {
                    (a, b)
                } else {
                    (b, a)
                };
                next[start] = end;
            }
        }
    }
    let mut triangles = Vec::new();
    let mut used = [false; 12];
    for first in 0..12 {
        if next[first] == usize::MAX || used[first] {
            continue;
        }
        let mut lp = vec![first];
        used[first] = true;
        let mut e = next[first];
        while e != first && e != usize::MAX && !used[e] {
            used[e] = true;
            lp.push(e);
            e = next[e];
        }
        for k in 1..lp.len().saturating_sub(1) {
            triangles.push([lp[0] as u8, lp[k] as u8, lp[k + 1] as u8]);
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_segment_chains_into_a_loop() {
        for case in 0..256usize {
            let tris = &table()[case];
            // Count directed edges between edge-vertices over the case's triangles: every
            // boundary (face) segment appears once, inner fan diagonals twice (both ways).
            let crossed = EDGES
                .iter()
                .filter(|(a, b, _)| (case >> a & 1) != (case >> b & 1))
                .count();
            let used: std::collections::BTreeSet<u8> = tris.iter().flatten().copied().collect();
            assert_eq!(
                used.len(),
                crossed,
                "case {case}: every crossed edge gets a vertex"
            );
            if case == 0 || case == 255 {
                assert!(tris.is_empty());
            }
        }
        // One corner inside: one triangle, facing away from that corner.
        let t = table()[1][0];
        let [a, b, c] = t.map(|e| edge_mid(e as usize));
        assert!((b - a).cross(c - a).dot(Vec3::ONE) > 0.0);
        assert_eq!(table()[1].len(), 1);
        // Complementary cases have the same number of crossed edges but not mirrored
        // connectivity on ambiguous faces: case 0b0000_0110 (two diagonal corners of the
        // bottom face) gives two separate triangles.
        assert_eq!(table()[0b0000_0110].len(), 2);
    }
}
