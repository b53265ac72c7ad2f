//! Foliage levels of detail in the preview: a leaf mesh with levels of detail ([`MeshLod`])
//! is drawn at a chosen fraction of its leaves through the two ranges of V of each sector,
//! from one index buffer of sequential quads over all of V uploaded once with the mesh.

use std::ops::Range;

use pge_engine::geometry::MeshLod;
use pge_lod::{Row, first_levels};

use crate::VERTEX_FLOATS;

/// One sector's V: its leaves are `offset..` in the mesh (four vertices each) and its table
/// rows `[a, b, c]` are relative to `offset`.
#[derive(Clone, Debug, PartialEq)]
struct Sector {
    offset: u32,
    leaves: u32,
    roots: u32,
    rows: Vec<[u32; 3]>,
}

/// The LOD tables of a leaf mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafLod {
    sectors: Vec<Sector>,
    /// Leaves in V (all sectors): the mesh's vertices over four.
    quads: u32,
}

impl LeafLod {
    /// The levels of a leaf mesh with `vertices` vertices ([`Mesh::lod`]); `None` when it
    /// has none, has a group's, or when they do not fit the mesh.
    ///
    /// [`Mesh::lod`]: pge_engine::geometry::Mesh::lod
    #[must_use]
    pub fn from_lod(lod: Option<&MeshLod>, vertices: usize) -> Option<Self> {
        let sectors: Vec<Sector> = lod?
            .table()?
            .sectors()
            .iter()
            .map(|s| Sector {
                offset: s.offset(),
                leaves: s.leaves(),
                roots: s.roots(),
                rows: s.levels().iter().map(|l| [l.a, l.b, l.c]).collect(),
            })
            .collect();
        let quads = u32::try_from(vertices / 4).ok()?;
        // Every range must lie in the mesh.
        let fits = sectors.iter().all(|s| {
            !s.rows.is_empty()
                && s.rows.iter().all(|&[a, b, c]| {
                    u64::from(s.offset) + u64::from(a) <= u64::from(quads)
                        && u64::from(s.offset) + u64::from(b) + u64::from(c) <= u64::from(quads)
                })
        });
        (fits && vertices.is_multiple_of(4)).then_some(LeafLod { sectors, quads })
    }

    /// Six indices per leaf of V, two triangles `(0 1 2) (0 2 3)` of its four vertices.
    #[must_use]
    pub fn quad_indices(&self) -> Vec<u32> {
        (0..self.quads)
            .flat_map(|k| {
                let b = 4 * k;
                [b, b + 1, b + 2, b, b + 2, b + 3]
            })
            .collect()
    }

    /// The ranges of [`LeafLod::quad_indices`] to draw at `percent` of the leaves (1..=100):
    /// each sector at the level with `max(roots, percent% of its leaves)` leaves.
    #[must_use]
    pub fn index_ranges(&self, percent: u8) -> Vec<Range<u32>> {
        let mut out = Vec::with_capacity(2 * self.sectors.len());
        for s in &self.sectors {
            let want = (u64::from(s.leaves) * u64::from(percent.clamp(1, 100))).div_ceil(100);
            let level = (want.saturating_sub(u64::from(s.roots)) as usize).min(s.rows.len() - 1);
            let [a, b, c] = s.rows[level];
            let o = s.offset;
            for r in [o..o + a, o + b..o + b + c] {
                if !r.is_empty() {
                    out.push(6 * r.start..6 * r.end);
                }
            }
        }
        out
    }

    /// A copy of a leaf mesh's interleaved vertices ([`VERTEX_FLOATS`] floats each, colour
    /// last) with every leaf coloured by the level that created it (the first level drawing
    /// it): blue for the coarsest, through green, to yellow for the original leaves.
    #[must_use]
    pub fn level_colors(&self, vertices: &[f32]) -> Vec<f32> {
        let mut out = vertices.to_vec();
        for s in &self.sectors {
            let len = (2 * s.leaves).saturating_sub(s.roots) as usize;
            let rows: Vec<Row> = s.rows.iter().map(|&[a, b, c]| Row { a, b, c }).collect();
            let last = (rows.len().max(2) - 1) as f32;
            for (k, level) in first_levels(&rows, len).into_iter().enumerate() {
                let t = level as f32 / last;
                let color = [t, 0.35 + 0.5 * t, 1.0 - 0.9 * t, 1.0];
                for v in 0..4 {
                    let at = (4 * (s.offset as usize + k) + v) * VERTEX_FLOATS + 8;
                    if let Some(slot) = out.get_mut(at..at + 4) {
                        slot.copy_from_slice(&color);
                    }
                }
            }
        }
        out
    }

    /// All original leaves (|O| over every sector).
    #[must_use]
    pub fn leaves(&self) -> u32 {
        self.sectors.iter().map(|s| s.leaves).sum()
    }

    /// The leaves of the coarsest level (|R| over every sector).
    #[must_use]
    pub fn roots(&self) -> u32 {
        self.sectors.iter().map(|s| s.roots).sum()
    }

    /// The ranges of [`LeafLod::quad_indices`] that draw about `leaves` leaves in all, and
    /// how many they draw (never more than `leaves`, unless `leaves` is 0). From
    /// [`LeafLod::roots`] up, each sector draws its share of `leaves` (rounded down), at
    /// least its coarsest level and at most its original leaves; asked for exactly the
    /// roots it draws the coarsest level. Below the roots, the coarsest level's leaves are
    /// dropped: each sector draws its share of `leaves` as the first leaves of each of its
    /// two ranges, in proportion to their lengths (a far tree's impostor-like minimum).
    #[must_use]
    pub fn leaf_ranges(&self, leaves: u32) -> (Vec<Range<u32>>, u32) {
        let (all, roots) = (u64::from(self.leaves().max(1)), self.roots());
        let mut out = Vec::with_capacity(2 * self.sectors.len());
        let mut drawn = 0;
        for s in &self.sectors {
            let o = s.offset;
            let [a, b, c] = if leaves >= roots {
                let share = if leaves == roots {
                    u64::from(s.roots)
                } else {
                    u64::from(leaves) * u64::from(s.leaves) / all
                };
                let want = share.clamp(u64::from(s.roots), u64::from(s.leaves.max(s.roots)));
                let level = (want - u64::from(s.roots)) as usize;
                s.rows[level.min(s.rows.len() - 1)]
            } else {
                // Fewer than the roots: a share of the coarsest level's two ranges.
                let [a, b, c] = s.rows[0];
                let share = (u64::from(leaves) * u64::from(s.roots) / u64::from(roots.max(1)))
                    .min(u64::from(a + c)) as u32;
                let from_a = if a + c == 0 {
                    0
                } else {
                    (u64::from(share) * u64::from(a) / u64::from(a + c)) as u32
                };
                [from_a, b, (share - from_a).min(c)]
            };
            drawn += a + c;
            for r in [o..o + a, o + b..o + b + c] {
                if !r.is_empty() {
                    out.push(6 * r.start..6 * r.end);
                }
            }
        }
        (out, drawn)
    }

    /// A copy of a leaf mesh's interleaved vertices ([`VERTEX_FLOATS`] floats each) with
    /// every leaf of V grown by `factor` about its centre: drawn for far instances that show
    /// only part of the coarsest level, so their crowns keep their size and cover.
    #[must_use]
    pub fn grown(&self, vertices: &[f32], factor: f32) -> Vec<f32> {
        let mut out = vertices.to_vec();
        for quad in out.chunks_exact_mut(4 * VERTEX_FLOATS) {
            let mut centre = [0.0f32; 3];
            for v in quad.chunks_exact(VERTEX_FLOATS) {
                for k in 0..3 {
                    centre[k] += v[k] / 4.0;
                }
            }
            for v in quad.chunks_exact_mut(VERTEX_FLOATS) {
                for k in 0..3 {
                    v[k] = centre[k] + (v[k] - centre[k]) * factor;
                }
            }
        }
        out
    }

    /// The leaves drawn by [`LeafLod::index_ranges`].
    #[must_use]
    pub fn drawn(&self, percent: u8) -> u32 {
        self.index_ranges(percent)
            .iter()
            .map(|r| (r.end - r.start) / 6)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The levels of `{"lod": ...}` as the glTF importer reads them.
    fn read(extras: &serde_json::Value) -> MeshLod {
        pge_engine::export::lod_from_json(&extras["lod"]).expect("a table")
    }

    #[test]
    fn levels_are_read_and_drawn_as_two_ranges_per_sector() {
        // Four original leaves and two collapses (six leaves in V), as pge-lod writes them.
        let extras = json!({"lod": {"leaves": 4, "roots": 2,
                              "table": [[0, 4, 2], [2, 5, 1], [4, 4, 0]]}});
        let lod = LeafLod::from_lod(Some(&read(&extras)), 24).expect("lod");
        assert_eq!(lod.quad_indices().len(), 36);
        assert_eq!(lod.index_ranges(100), vec![0..24]);
        assert_eq!(lod.drawn(100), 4);
        assert_eq!(lod.index_ranges(1), vec![24..36]);
        assert_eq!(lod.drawn(75), 3);
        assert_eq!(lod.index_ranges(75), vec![0..12, 30..36]);
        // By leaf count: the coarsest level at the roots, part of it below them.
        assert_eq!((lod.leaves(), lod.roots()), (4, 2));
        assert_eq!(lod.leaf_ranges(4).0, vec![0..24]);
        assert_eq!(lod.leaf_ranges(4).1, 4);
        assert_eq!(lod.leaf_ranges(3), (vec![0..12, 30..36], 3));
        assert_eq!(lod.leaf_ranges(2).0, vec![24..36]);
        assert_eq!(lod.leaf_ranges(2).1, 2);
        assert_eq!(lod.leaf_ranges(1).0, vec![24..30]);
        assert_eq!(lod.leaf_ranges(1).1, 1);
        assert_eq!(lod.leaf_ranges(0), (vec![], 0));
        // Two sectors, one after the other.
        let extras = json!({"lod": {"leaves": 4, "roots": 2, "sectors": [
            {"offset": 0, "leaves": 2, "roots": 1, "table": [[0, 2, 1], [2, 2, 0]]},
            {"offset": 3, "leaves": 2, "roots": 1, "table": [[0, 2, 1], [2, 2, 0]]}]}});
        let lod = LeafLod::from_lod(Some(&read(&extras)), 24).expect("lod");
        assert_eq!(lod.index_ranges(1), vec![12..18, 30..36]);
        assert_eq!(lod.index_ranges(100), vec![0..12, 18..30]);
        // Out of the mesh: ignored.
        assert!(LeafLod::from_lod(Some(&read(&extras)), 20).is_none());
        assert!(LeafLod::from_lod(None, 24).is_none());
        // Colour by level: the roots (level 0) blue, the original leaves yellow.
        let extras = json!({"lod": {"leaves": 2, "roots": 1, "table": [[0, 2, 1], [2, 2, 0]]}});
        let lod = LeafLod::from_lod(Some(&read(&extras)), 12).expect("lod");
        let colored = lod.level_colors(&vec![0.5; 12 * VERTEX_FLOATS]);
        let near = |leaf: usize, want: [f32; 4]| {
            let got = &colored[4 * leaf * VERTEX_FLOATS + 8..][..4];
            got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6)
        };
        assert!(near(0, [1.0, 0.85, 0.1, 1.0]) && near(1, [1.0, 0.85, 0.1, 1.0]));
        assert!(near(2, [0.0, 0.35, 1.0, 1.0]));
        // Positions are untouched.
        assert_eq!(&colored[..8], &[0.5; 8]);
        // Grown leaves: each quad twice as wide about its centre.
        let quad: Vec<f32> = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ]
        .iter()
        .flat_map(|p| {
            let mut v = vec![0.25; VERTEX_FLOATS];
            v[..3].copy_from_slice(p);
            v
        })
        .collect();
        let grown = lod.grown(&quad, 2.0);
        let corners: Vec<&[f32]> = grown.chunks(VERTEX_FLOATS).map(|v| &v[..3]).collect();
        assert_eq!(corners[0], &[-0.5, -0.5, 0.0]);
        assert_eq!(corners[2], &[1.5, 1.5, 0.0]);
        assert_eq!(
            &grown[3..VERTEX_FLOATS],
            &quad[3..VERTEX_FLOATS],
            "only positions"
        );
    }
}
