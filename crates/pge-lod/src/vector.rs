//! The collapse forest laid out as one vector V and a LOD table (seed 003 §2.5.1,
//! algorithms 1 "V_init", 2 "V_fill" and 3 "V_render"): any level is drawn with two
//! contiguous ranges of V, and every instance of a species shares V.

use std::ops::Range;

use crate::simplify::Chain;

/// One row of the LOD table: level `i` draws `V[0..a)` and `V[b..b+c)`, with
/// `a + c = |R| + i` (seed 003 §2.5.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Row {
    /// Leaves drawn from the start of V (original leaves).
    pub a: u32,
    /// Where the second range starts.
    pub b: u32,
    /// Leaves drawn from `b` (leaves made by collapses).
    pub c: u32,
}

/// V and its LOD table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LodTable {
    /// The vector V: leaf labels of the chain, |M| of them. `V[..|O|]` holds the original
    /// leaves, `V[|O|..]` the new ones.
    pub order: Vec<u32>,
    /// Row `i` draws level `i`: row 0 the roots R (coarsest), the last row the original
    /// leaves O (finest). There are `|M| - |O| + 1` rows.
    pub rows: Vec<Row>,
    /// |O|, the original leaves.
    pub originals: u32,
    /// |R|, the leaves of the coarsest level.
    pub roots: u32,
}

impl LodTable {
    /// Linearises a collapse chain: [`v_init`] then [`v_fill`].
    #[must_use]
    pub fn new(chain: &Chain) -> LodTable {
        let (order, p, q) = v_init(chain);
        let roots = chain.roots().len() as u32;
        let (order, rows) = v_fill(chain, order, p, q);
        LodTable {
            order,
            rows,
            originals: chain.originals as u32,
            roots,
        }
    }

    /// Number of levels (rows).
    #[must_use]
    pub fn levels(&self) -> usize {
        self.rows.len()
    }

    /// The two ranges of V drawn at `level` (algorithm 3, V_render); a level past the last
    /// draws the finest.
    #[must_use]
    pub fn ranges(&self, level: usize) -> [Range<usize>; 2] {
        let Some(row) = self.rows.get(level).or(self.rows.last()) else {
            return [0..0, 0..0];
        };
        let (a, b, c) = (row.a as usize, row.b as usize, row.c as usize);
        [0..a, b..b + c]
    }

    /// The level that draws `leaves` leaves: `leaves - |R|`, clamped to the table.
    #[must_use]
    pub fn level_for(&self, leaves: u32) -> usize {
        (leaves.saturating_sub(self.roots) as usize).min(self.rows.len().saturating_sub(1))
    }

    /// For every position of V, the first level that draws it (the level whose split
    /// created it; 0 for the roots).
    #[must_use]
    pub fn first_levels(&self) -> Vec<u32> {
        first_levels(&self.rows, self.order.len())
    }
}

/// For every position of a V of length `len`, the first level of `rows` that draws it.
/// Original leaves enter the first range one split at a time; new leaves enter the second
/// range as its start moves down. Positions no level draws get the last level.
#[must_use]
pub fn first_levels(rows: &[Row], len: usize) -> Vec<u32> {
    let last = rows.len().saturating_sub(1) as u32;
    let mut out = vec![last; len];
    let mut seen = 0usize;
    let mut low = len;
    for (i, row) in rows.iter().enumerate() {
        let (a, b) = ((row.a as usize).min(len), (row.b as usize).min(len));
        for slot in &mut out[seen.min(a)..a] {
            *slot = i as u32;
        }
        seen = seen.max(a);
        if row.c > 0 && b < low {
            for slot in &mut out[b..low] {
                *slot = i as u32;
            }
            low = b;
        }
    }
    out
}

/// Algorithm 1, V_init: the roots that are original leaves go to the front of V in
/// increasing label order (`p` counts them), the new roots to the back (`q` moves down),
/// the latest made at the very end so V_fill splits it first. Returns `(V, p, q)` with `p`
/// the first free position of the front part and `q` the first free one (from the top) of
/// the back part.
#[must_use]
pub fn v_init(chain: &Chain) -> (Vec<u32>, usize, isize) {
    let m = chain.leaves.len();
    let mut v = vec![u32::MAX; m];
    let roots = chain.roots();
    let mut p = 0usize;
    for &leaf in roots.iter().filter(|&&l| (l as usize) < chain.originals) {
        v[p] = leaf;
        p += 1;
    }
    let mut q = m as isize - 1;
    for &leaf in roots
        .iter()
        .rev()
        .filter(|&&l| (l as usize) >= chain.originals)
    {
        v[q as usize] = leaf;
        q -= 1;
    }
    (v, p, q)
}

/// Algorithm 2, V_fill: walk the back part of V from its end (`r`), splitting each new leaf
/// into its two children, the later-made child first; an original child goes to the front
/// (`p` up), a new one to the back (`q` down). Before each split the row `{p, q + 1, r - q}`
/// is appended, and once more at the end.
///
/// The thesis loops `while p ≠ q`; with `q` the first free position from the top (as its
/// V_init returns it) the vector is full when `p = q + 1`, which is when no new leaf is left
/// to split (`r = q`). The loop runs while `r > q`, which is the same for every non-empty
/// chain and also ends a chain without collapses.
#[must_use]
pub fn v_fill(chain: &Chain, mut v: Vec<u32>, mut p: usize, mut q: isize) -> (Vec<u32>, Vec<Row>) {
    let mut rows = Vec::with_capacity(chain.children.len() + 1);
    let mut r = v.len() as isize - 1;
    let row = |p: usize, q: isize, r: isize| Row {
        a: p as u32,
        b: (q + 1) as u32,
        c: (r - q) as u32,
    };
    while r > q {
        rows.push(row(p, q, r));
        let leaf = v[r as usize] as usize;
        let [left, right] = chain.children[leaf - chain.originals];
        for l in [left.max(right), left.min(right)] {
            if (l as usize) < chain.originals {
                v[p] = l;
                p += 1;
            } else {
                v[q as usize] = l;
                q -= 1;
            }
        }
        r -= 1;
    }
    rows.push(row(p, q, r));
    (v, rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leaf::Leaf;
    use glam::Vec3;

    /// The chain of the thesis' figure 2.3 shape: 16 original leaves, collapses building
    /// two big trees and leaving leaves 8 and 9 alone.
    fn figure_chain() -> Chain {
        let leaf = Leaf {
            center: Vec3::ZERO,
            normal: Vec3::Z,
            axis: Vec3::Y,
            half_length: 0.5,
            half_width: 0.5,
            count: 1,
            leaf_area: 1.0,
            lo: Vec3::splat(-1.0),
            hi: Vec3::splat(1.0),
        };
        let children: Vec<[u32; 2]> = vec![
            [0, 1],   // 16
            [2, 3],   // 17
            [4, 5],   // 18
            [6, 7],   // 19
            [10, 11], // 20
            [12, 13], // 21
            [14, 15], // 22
            [16, 17], // 23
            [18, 19], // 24
            [20, 21], // 25
            [23, 24], // 26
            [25, 22], // 27
        ];
        Chain {
            leaves: vec![leaf; 16 + children.len()],
            originals: 16,
            children,
        }
    }

    #[test]
    fn the_figure_example_fills_v_and_the_table() {
        let chain = figure_chain();
        assert_eq!(chain.roots(), vec![8, 9, 26, 27]);
        let (v, p, q) = v_init(&chain);
        assert_eq!((p, q), (2, 25));
        assert_eq!(&v[..2], &[8, 9]);
        assert_eq!(&v[26..], &[26, 27]);
        let t = LodTable::new(&chain);
        assert_eq!(t.levels(), 13);
        assert_eq!(t.rows[0], Row { a: 2, b: 26, c: 2 });
        // The first split is of 27 (the last made): its children 25 and 22 go to the back.
        assert_eq!(t.rows[1], Row { a: 2, b: 24, c: 3 });
        assert_eq!(&t.order[24..26], &[22, 25]);
        assert_eq!(*t.rows.last().expect("rows"), Row { a: 16, b: 16, c: 0 });
        for (i, row) in t.rows.iter().enumerate() {
            assert_eq!(row.a + row.c, t.roots + i as u32);
        }
        let mut sorted = t.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..28).collect::<Vec<u32>>());
    }

    #[test]
    fn first_levels_name_the_level_that_draws_each_position_first() {
        let t = LodTable::new(&figure_chain());
        let first = t.first_levels();
        for (pos, &level) in first.iter().enumerate() {
            let drawn = |l: usize| t.ranges(l).iter().any(|r| r.contains(&pos));
            assert!(drawn(level as usize), "position {pos} at level {level}");
            assert!(level == 0 || !drawn(level as usize - 1));
        }
    }

    #[test]
    fn a_chain_without_collapses_has_one_level() {
        let leaf = figure_chain().leaves[0];
        let t = LodTable::new(&Chain::flat(vec![leaf; 3]));
        assert_eq!(t.rows, vec![Row { a: 3, b: 3, c: 0 }]);
        assert_eq!(t.order, vec![0, 1, 2]);
        assert_eq!(t.ranges(5), [0..3, 3..3]);
        assert_eq!(t.level_for(100), 0);
        let empty = LodTable::new(&Chain::flat(Vec::new()));
        assert_eq!(empty.rows, vec![Row { a: 0, b: 0, c: 0 }]);
    }
}
