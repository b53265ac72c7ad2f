//! Foliage levels of detail of a leaf mesh (seed 003, chapter 2): the mesh's leaves are the
//! vector V, four vertices a leaf, and a table of rows `(a, b, c)` draws level `i` as the
//! two ranges `V[0..a)` and `V[b..b+c)`, with `a + c = |R| + i`. A tree cut into sectors has
//! one V and one table per sector, the sectors' V one after the other. A forest variant's
//! mesh (a glTF mesh of several primitives) carries the tables of its leaf primitives.
//!
//! The glTF writer writes these as the mesh's `extras.pge.lod` (docs/glb.md).
//!
//! ```
//! use pge_engine::geometry::{LodLevel, LodSector, LodTable};
//!
//! // Two original leaves collapsed into one: V = [leaf 0, leaf 1, their parent].
//! let levels = vec![LodLevel { a: 0, b: 2, c: 1 }, LodLevel { a: 2, b: 3, c: 0 }];
//! let table = LodTable::new(vec![LodSector::new(0, 2, 1, levels).unwrap()]).unwrap();
//! assert_eq!((table.leaves(), table.roots()), (2, 1));
//! ```

/// Why a LOD table was refused: the numbers do not describe levels of one V.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LodError {
    /// A sector (or a table, or a mesh's primitives) has no entry.
    #[error("a LOD table needs at least one {0}")]
    Empty(&'static str),
    /// A sector's coarsest level has more leaves than its finest.
    #[error("a LOD sector's {roots} roots are more than its {leaves} leaves")]
    Roots {
        /// Leaves of the coarsest level, |R|.
        roots: u32,
        /// Original leaves, |O|.
        leaves: u32,
    },
    /// A sector's rows are not one per level, from |R| leaves to |O|.
    #[error("a LOD sector of {leaves} leaves and {roots} roots has {got} levels, not {want}")]
    Levels {
        /// Original leaves, |O|.
        leaves: u32,
        /// Leaves of the coarsest level, |R|.
        roots: u32,
        /// Rows given.
        got: usize,
        /// Rows wanted: |O| - |R| + 1.
        want: u64,
    },
    /// A row does not draw `|R| + i` leaves, or draws past the sector's V.
    #[error("LOD level {level} ({a}, {b}, {c}) does not draw {want} leaves within V's {len}")]
    Row {
        /// The row's level.
        level: usize,
        /// Leaves drawn from the start of V.
        a: u32,
        /// Where the second range starts.
        b: u32,
        /// Leaves drawn from `b`.
        c: u32,
        /// `|R| + level`.
        want: u64,
        /// The length of the sector's V, `2|O| - |R|`.
        len: u64,
    },
    /// A sector does not start where the previous one's V ends.
    #[error("LOD sector {sector} starts at leaf {offset}, not {want}")]
    Offset {
        /// The sector's place in the table.
        sector: usize,
        /// Where it starts.
        offset: u32,
        /// Where the previous sector's V ends.
        want: u64,
    },
    /// The leaves or roots given for a table are not the sums of its parts.
    #[error("a LOD table's totals are not the sums of its parts")]
    Totals,
    /// Counts summed over sectors or primitives do not fit in 32 bits.
    #[error("a LOD table's leaf counts overflow 32 bits")]
    Overflow,
}

/// One row of a LOD table: its level draws `V[0..a)` and `V[b..b+c)`.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct LodLevel {
    /// Leaves drawn from the start of V (original leaves).
    pub a: u32,
    /// Where the second range starts.
    pub b: u32,
    /// Leaves drawn from `b` (leaves made by collapses).
    pub c: u32,
}

/// The levels of one sector's V: row `i` draws level `i`, from the roots R (row 0) to the
/// original leaves O (the last row).
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "RawSector")]
pub struct LodSector {
    offset: u32,
    leaves: u32,
    roots: u32,
    levels: Vec<LodLevel>,
}

impl LodSector {
    /// The sector whose V starts at leaf `offset` of the mesh, with `leaves` original leaves
    /// |O|, `roots` leaves at its coarsest level |R|, and one row per level: `|O| - |R| + 1`
    /// rows, row `i` drawing `a + c = |R| + i` leaves within V (`2|O| - |R|` leaves).
    pub fn new(
        offset: u32,
        leaves: u32,
        roots: u32,
        levels: Vec<LodLevel>,
    ) -> Result<LodSector, LodError> {
        if roots > leaves {
            return Err(LodError::Roots { roots, leaves });
        }
        let want = u64::from(leaves - roots) + 1;
        if levels.len() as u64 != want {
            return Err(LodError::Levels {
                leaves,
                roots,
                got: levels.len(),
                want,
            });
        }
        let len = 2 * u64::from(leaves) - u64::from(roots);
        for (level, &LodLevel { a, b, c }) in levels.iter().enumerate() {
            let want = u64::from(roots) + level as u64;
            let (a64, b64, c64) = (u64::from(a), u64::from(b), u64::from(c));
            if a64 + c64 != want || a > leaves || b64 + c64 > len {
                return Err(LodError::Row {
                    level,
                    a,
                    b,
                    c,
                    want,
                    len,
                });
            }
        }
        Ok(LodSector {
            offset,
            leaves,
            roots,
            levels,
        })
    }

    /// Where the sector's V starts among the mesh's leaves.
    #[must_use]
    pub fn offset(&self) -> u32 {
        self.offset
    }

    /// Original leaves, |O|: the finest level draws `V[0..|O|)`.
    #[must_use]
    pub fn leaves(&self) -> u32 {
        self.leaves
    }

    /// Leaves of the coarsest level, |R|.
    #[must_use]
    pub fn roots(&self) -> u32 {
        self.roots
    }

    /// The rows, coarsest first.
    #[must_use]
    pub fn levels(&self) -> &[LodLevel] {
        &self.levels
    }

    /// The length of the sector's V in leaves: `2|O| - |R|` (every collapse made one).
    #[must_use]
    pub fn len(&self) -> u64 {
        2 * u64::from(self.leaves) - u64::from(self.roots)
    }

    /// Whether the sector's V is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.leaves == 0
    }
}

/// The levels of detail of a leaf mesh written in the order of V: one sector, or several
/// whose V follow one another from the mesh's first leaf.
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "RawTable")]
pub struct LodTable {
    sectors: Vec<LodSector>,
    leaves: u32,
    roots: u32,
}

impl LodTable {
    /// The table of `sectors`, each starting where the previous one's V ends (the first at
    /// leaf 0).
    pub fn new(sectors: Vec<LodSector>) -> Result<LodTable, LodError> {
        if sectors.is_empty() {
            return Err(LodError::Empty("sector"));
        }
        let mut at = 0u64;
        let (mut leaves, mut roots) = (0u32, 0u32);
        for (sector, s) in sectors.iter().enumerate() {
            if u64::from(s.offset) != at {
                return Err(LodError::Offset {
                    sector,
                    offset: s.offset,
                    want: at,
                });
            }
            at += s.len();
            leaves = leaves.checked_add(s.leaves).ok_or(LodError::Overflow)?;
            roots = roots.checked_add(s.roots).ok_or(LodError::Overflow)?;
        }
        Ok(LodTable {
            sectors,
            leaves,
            roots,
        })
    }

    /// The sectors, in the order of their V.
    #[must_use]
    pub fn sectors(&self) -> &[LodSector] {
        &self.sectors
    }

    /// Original leaves, |O|, summed over the sectors.
    #[must_use]
    pub fn leaves(&self) -> u32 {
        self.leaves
    }

    /// Leaves of the coarsest level, |R|, summed over the sectors.
    #[must_use]
    pub fn roots(&self) -> u32 {
        self.roots
    }
}

/// The LOD table of one leaf primitive of a group's mesh.
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct PrimitiveLod {
    /// The primitive's place among the mesh's primitives (from 0).
    pub primitive: u32,
    /// Its levels.
    pub table: LodTable,
}

/// The levels of detail of a group's mesh (a forest variant drawn as one glTF mesh): the
/// tables of its leaf primitives, with their leaves and roots summed.
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "RawGroup")]
pub struct GroupLod {
    primitives: Vec<PrimitiveLod>,
    leaves: u32,
    roots: u32,
}

impl GroupLod {
    /// The levels of `primitives` (at least one).
    pub fn new(primitives: Vec<PrimitiveLod>) -> Result<GroupLod, LodError> {
        if primitives.is_empty() {
            return Err(LodError::Empty("primitive"));
        }
        let (mut leaves, mut roots) = (0u32, 0u32);
        for p in &primitives {
            leaves = leaves
                .checked_add(p.table.leaves)
                .ok_or(LodError::Overflow)?;
            roots = roots.checked_add(p.table.roots).ok_or(LodError::Overflow)?;
        }
        Ok(GroupLod {
            primitives,
            leaves,
            roots,
        })
    }

    /// The leaf primitives' tables, in the order of the primitives.
    #[must_use]
    pub fn primitives(&self) -> &[PrimitiveLod] {
        &self.primitives
    }
}

/// What a mesh carries of foliage levels of detail ([`Mesh::lod`](super::Mesh::lod)).
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum MeshLod {
    /// A leaf mesh written in the order of V.
    Leaves(LodTable),
    /// The mesh of a group (a forest variant): the tables of its leaf primitives.
    Group(GroupLod),
}

impl MeshLod {
    /// Original leaves |O|, summed over sectors and primitives.
    #[must_use]
    pub fn leaves(&self) -> u32 {
        match self {
            MeshLod::Leaves(t) => t.leaves,
            MeshLod::Group(g) => g.leaves,
        }
    }

    /// Leaves of the coarsest level |R|, summed over sectors and primitives.
    #[must_use]
    pub fn roots(&self) -> u32 {
        match self {
            MeshLod::Leaves(t) => t.roots,
            MeshLod::Group(g) => g.roots,
        }
    }

    /// The table of a leaf mesh, `None` for a group's.
    #[must_use]
    pub fn table(&self) -> Option<&LodTable> {
        match self {
            MeshLod::Leaves(t) => Some(t),
            MeshLod::Group(_) => None,
        }
    }
}

/// The fields of a [`LodSector`] as read, checked by [`LodSector::new`].
#[derive(serde::Deserialize)]
struct RawSector {
    offset: u32,
    leaves: u32,
    roots: u32,
    levels: Vec<LodLevel>,
}

impl TryFrom<RawSector> for LodSector {
    type Error = LodError;
    fn try_from(r: RawSector) -> Result<LodSector, LodError> {
        LodSector::new(r.offset, r.leaves, r.roots, r.levels)
    }
}

/// The fields of a [`LodTable`] as read, checked by [`LodTable::new`] (the sums too).
#[derive(serde::Deserialize)]
struct RawTable {
    sectors: Vec<LodSector>,
    leaves: u32,
    roots: u32,
}

impl TryFrom<RawTable> for LodTable {
    type Error = LodError;
    fn try_from(r: RawTable) -> Result<LodTable, LodError> {
        let table = LodTable::new(r.sectors)?;
        if (table.leaves, table.roots) != (r.leaves, r.roots) {
            return Err(LodError::Totals);
        }
        Ok(table)
    }
}

/// The fields of a [`GroupLod`] as read, checked by [`GroupLod::new`] (the sums too).
#[derive(serde::Deserialize)]
struct RawGroup {
    primitives: Vec<PrimitiveLod>,
    leaves: u32,
    roots: u32,
}

impl TryFrom<RawGroup> for GroupLod {
    type Error = LodError;
    fn try_from(r: RawGroup) -> Result<GroupLod, LodError> {
        let group = GroupLod::new(r.primitives)?;
        if (group.leaves, group.roots) != (r.leaves, r.roots) {
            return Err(LodError::Totals);
        }
        Ok(group)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(a: u32, b: u32, c: u32) -> LodLevel {
        LodLevel { a, b, c }
    }

    /// Three leaves collapsed to one: V = [0, 1, 2, (0 1), ((0 1) 2)].
    fn three(offset: u32) -> LodSector {
        let rows = vec![level(0, 4, 1), level(1, 3, 1), level(3, 5, 0)];
        LodSector::new(offset, 3, 1, rows).expect("valid")
    }

    #[test]
    fn sectors_follow_one_another_and_sum() {
        let t = LodTable::new(vec![three(0), three(5)]).expect("valid");
        assert_eq!((t.leaves(), t.roots()), (6, 2));
        assert_eq!(t.sectors()[1].len(), 5);
        assert_eq!(
            LodTable::new(vec![three(0), three(4)]),
            Err(LodError::Offset {
                sector: 1,
                offset: 4,
                want: 5
            })
        );
        assert_eq!(
            LodTable::new(vec![three(1)]).map(|t| t.leaves()),
            Err(LodError::Offset {
                sector: 0,
                offset: 1,
                want: 0
            })
        );
        assert_eq!(LodTable::new(Vec::new()), Err(LodError::Empty("sector")));
        let lod = MeshLod::Leaves(t.clone());
        assert_eq!((lod.leaves(), lod.roots()), (6, 2));
        assert_eq!(lod.table(), Some(&t));
    }

    #[test]
    fn rows_must_draw_their_level_within_v() {
        // Too few rows, a row drawing the wrong count, a range past V, roots past leaves.
        assert!(matches!(
            LodSector::new(0, 3, 1, vec![level(0, 4, 1)]),
            Err(LodError::Levels {
                got: 1,
                want: 3,
                ..
            })
        ));
        assert!(matches!(
            LodSector::new(
                0,
                3,
                1,
                vec![level(0, 4, 1), level(1, 3, 2), level(3, 5, 0)]
            ),
            Err(LodError::Row { level: 1, .. })
        ));
        assert!(matches!(
            LodSector::new(
                0,
                3,
                1,
                vec![level(0, 5, 1), level(1, 3, 1), level(3, 5, 0)]
            ),
            Err(LodError::Row { level: 0, .. })
        ));
        assert!(matches!(
            LodSector::new(0, 3, 4, Vec::new()),
            Err(LodError::Roots { .. })
        ));
        // A sector with no leaf: one empty row.
        let empty = LodSector::new(0, 0, 0, vec![level(0, 0, 0)]).expect("valid");
        assert!(empty.is_empty());
    }

    #[test]
    fn a_group_sums_its_primitives_and_overflow_is_an_error() {
        let table = LodTable::new(vec![three(0)]).expect("valid");
        let g = GroupLod::new(vec![
            PrimitiveLod {
                primitive: 1,
                table: table.clone(),
            },
            PrimitiveLod {
                primitive: 3,
                table,
            },
        ])
        .expect("valid");
        let lod = MeshLod::Group(g);
        assert_eq!((lod.leaves(), lod.roots()), (6, 2));
        assert_eq!(lod.table(), None);
        assert_eq!(GroupLod::new(Vec::new()), Err(LodError::Empty("primitive")));
        let big = |offset| {
            let rows = vec![level(u32::MAX, 0, 0)];
            LodSector::new(offset, u32::MAX, u32::MAX, rows).expect("valid")
        };
        assert_eq!(
            LodTable::new(vec![big(0), big(u32::MAX)]),
            Err(LodError::Overflow)
        );
    }
}
