//! Tests of the unusable-triangle search: degenerate and repeated triangles, and meshes usable by construction.

use super::*;
use crate::math;

/// Numbers in [0, 1) from a xorshift generator seeded with `state`: many triangles
/// without a dependency.
fn xorshift(mut state: u64) -> impl FnMut() -> f32 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// The definition, one triangle at a time with a set of the keys seen.
fn unusable_by_definition(positions: &[Vec3], indices: &[u32]) -> Vec<usize> {
    let mut seen = std::collections::HashSet::new();
    let (triangles, _) = indices.as_chunks::<3>();
    (0..triangles.len())
        .filter(|&t| match corners(positions, &triangles[t]) {
            None => false,
            Some(c) => degenerate(c) || !seen.insert(key(c)),
        })
        .collect()
}

#[test]
fn repeats_and_degenerate_triangles_of_a_large_mesh_are_found_in_every_shard() {
    // A grid of 200 x 200 quads (80 k triangles: sharded), with every 7th triangle
    // repeated later (some rotated), every 11th made degenerate, a back face of every
    // 13th, and -0.0 spelling a corner at 0.0.
    let n = 201;
    let mut positions: Vec<Vec3> = (0..n * n)
        .map(|k| Vec3::new((k % n) as f32, 0.0, (k / n) as f32))
        .collect();
    positions.push(Vec3::new(-0.0, 0.0, 1.0));
    let mut indices = Vec::new();
    for z in 0..n - 1 {
        for x in 0..n - 1 {
            let v = (z * n + x) as u32;
            let n = n as u32;
            indices.extend([v, v + n, v + 1, v + 1, v + n, v + n + 1]);
        }
    }
    let triangles = indices.len() / 3;
    for t in (0..triangles).step_by(7) {
        let [a, b, c] = [0, 1, 2].map(|k| indices[3 * t + k]);
        indices.extend(if t % 2 == 0 { [a, b, c] } else { [b, c, a] });
    }
    for t in (0..triangles).step_by(11) {
        indices[3 * t + 2] = indices[3 * t];
    }
    for t in (0..triangles).step_by(13) {
        let [a, b, c] = [0, 1, 2].map(|k| indices[3 * t + k]);
        indices.extend([a, c, b]);
    }
    // The second triangle, through the corner spelled -0.0.
    indices.extend([1, (n * n) as u32, n as u32 + 1]);
    indices.extend([2, 9, (n * n + 1) as u32]); // past the vertices: kept
    assert!(indices.len() / 3 >= SHARDED_FROM);
    let found = unusable(&positions, &indices, SearchMemory::default());
    assert_eq!(found, unusable_by_definition(&positions, &indices));
    // The repeats of the 7th triangles (not made degenerate), the degenerate ones, and
    // the one at -0.0.
    let degenerate = triangles.div_ceil(11);
    assert!(found.len() > triangles / 7 + degenerate - triangles / 77 - 2);
    assert!(found.contains(&(indices.len() / 3 - 2)));
    let kept = without(&indices, &found);
    assert_eq!(kept.len(), indices.len() - 3 * found.len());
    assert!(unusable(&positions, &kept, SearchMemory::default()).is_empty());
}

#[test]
fn a_small_mesh_searched_in_one_pass_finds_what_the_definition_finds() {
    // Corners on a coarse lattice, so many triangles repeat (in every rotation), many
    // are back faces of others and many are degenerate; -0.0 spells some corners.
    let mut positions: Vec<Vec3> = (0..60)
        .map(|k| Vec3::new((k % 4) as f32, (k % 3) as f32, (k % 5) as f32))
        .collect();
    positions.push(Vec3::new(-0.0, 0.0, -0.0));
    let indices: Vec<u32> = (0..3 * 5000u32).map(|i| (i * 7919 + i / 7) % 61).collect();
    assert!(indices.len() / 3 < SHARDED_FROM);
    let found = unusable(&positions, &indices, SearchMemory::default());
    assert_eq!(found, unusable_by_definition(&positions, &indices));
    assert!(found.len() > 100 && found.len() < 5000, "{}", found.len());
    // In resident memory with room, without enough room, and memory used before (its
    // table left full of another mesh's slots): the same triangles.
    let room = SearchMemory::resident(positions.len(), indices.len() / 3);
    assert_eq!(unusable(&positions, &indices, room), found);
    let short = SearchMemory::resident(10, 10);
    assert_eq!(unusable(&positions, &indices, short), found);
    let used = SearchMemory {
        hashes: vec![7; 3 * positions.len()],
        slots: vec![u32::MAX; 4 * super::small_table_len(indices.len() / 3)],
    };
    assert_eq!(unusable(&positions, &indices, used), found);
}

#[test]
fn the_largest_mesh_searched_in_one_pass_finds_what_the_definition_finds() {
    // Every triangle number a one-pass table holds, with repeats of the first triangles
    // at the end.
    let positions: Vec<Vec3> = (0..900)
        .map(|k| Vec3::new((k % 30) as f32, (k / 30) as f32, (k % 7) as f32))
        .collect();
    let mut indices: Vec<u32> = (0..3 * (SHARDED_FROM as u32 - 11))
        .map(|i| (i * 7919 + i / 3) % 900)
        .collect();
    indices.extend_from_within(..30);
    assert_eq!(indices.len() / 3, SHARDED_FROM - 1);
    let found = unusable(&positions, &indices, SearchMemory::default());
    assert_eq!(found, unusable_by_definition(&positions, &indices));
    assert!(found.ends_with(&[SHARDED_FROM - 2]), "{:?}", found.last());
}

#[test]
fn triangles_distinct_by_construction_are_usable_unless_two_vertices_meet() {
    // A strip of 40 quads around a cylinder: its last column of vertices repeats the
    // first (the seam), named as twins.
    let (columns, rows) = (41u32, 3u32);
    let mut positions: Vec<Vec3> = (0..rows * columns)
        .map(|v| {
            let (row, k) = (v / columns, (v % columns) % (columns - 1));
            let a = std::f32::consts::TAU * k as f32 / (columns - 1) as f32;
            Vec3::new(math::cos(a), row as f32, math::sin(a))
        })
        .collect();
    let mut indices = Vec::new();
    for row in 0..rows - 1 {
        for k in 0..columns - 1 {
            let (a, b) = (row * columns + k, (row + 1) * columns + k);
            indices.extend([a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    let twins: Vec<(u32, u32)> = (0..rows)
        .map(|row| (row * columns + columns - 1, row * columns))
        .collect();
    let by_construction = |p: &[Vec3], i: &[u32], t: &[(u32, u32)]| {
        let usable = usable_by_construction(p, i, t);
        assert!(
            !usable || unusable(p, i, SearchMemory::default()).is_empty(),
            "usable, yet some are not"
        );
        usable
    };
    assert!(by_construction(&positions, &indices, &twins));
    // Unnamed, the seam is two vertices at one place: no longer shown.
    assert!(!by_construction(&positions, &indices, &twins[1..]));
    // A twin elsewhere than its other is an ordinary vertex.
    positions[columns as usize - 1].y = 0.5;
    assert!(by_construction(&positions, &indices, &twins));
    // -0.0 and 0.0 are one place.
    positions[columns as usize - 1] = positions[0] * Vec3::new(1.0, -1.0, 1.0);
    assert!(by_construction(&positions, &indices, &twins));
    // Another vertex moved onto one of a row above: a repeat is possible.
    positions[5] = positions[columns as usize + 5];
    assert!(!by_construction(&positions, &indices, &twins));
    positions[5] = positions[6] * 1.5;
    assert!(by_construction(&positions, &indices, &twins));
    // A degenerate triangle, an index past the vertices.
    let mut flat = positions.clone();
    flat[columns as usize + 1] = (flat[0] + flat[1]) * 0.5;
    assert!(!by_construction(&flat, &indices, &twins));
    let mut past = indices.clone();
    past[4] = positions.len() as u32;
    assert!(!usable_by_construction(&positions, &past, &twins));
    // Many vertices, most sharing a bit of the table with another.
    let mut many: Vec<Vec3> = (0..100_000)
        .map(|k| Vec3::new(k as f32, (k % 7) as f32, 0.0))
        .collect();
    assert!(usable_by_construction(&many, &[], &[]));
    many[99_999] = many[3];
    assert!(!usable_by_construction(&many, &[], &[]));
    assert!(usable_by_construction(&many, &[], &[(99_999, 3)]));
}

#[test]
fn triangles_tested_eight_at_a_time_are_degenerate_as_one_at_a_time() {
    // Triangles around the threshold: a base of length 1..4 and a height near a
    // millionth of it, at places far from the origin; -0.0 and NaN too.
    let mut next = xorshift(0x2545_f491_4f6c_dd1du64);
    let mut positions = Vec::new();
    for _ in 0..3000 {
        let origin = Vec3::new(next(), next(), next()) * 100.0 - 50.0;
        let base = Vec3::new(next(), next(), next()).normalize() * (1.0 + 3.0 * next());
        let up = base.any_orthonormal_vector() * base.length() * 2e-6 * next();
        positions.extend([origin, origin + base, origin + base * next() + up]);
    }
    positions.extend([Vec3::new(-0.0, 0.0, 1.0), Vec3::Z, Vec3::NAN]);
    let n = positions.len() as u32;
    let mut triangles: Vec<[u32; 3]> = (0..n / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    triangles.extend([[n - 3, n - 2, 0], [n - 1, 0, 1], [0, 1, n]]);
    let mut both = 0;
    for tri in &triangles {
        let one = corners(&positions, tri).is_none_or(degenerate);
        both += usize::from(one);
        assert_eq!(any_degenerate(&positions, &[*tri; 8]), one, "{tri:?}");
        // In a full batch and among the last, untested until the end.
        for at in [5, 9] {
            let mut mixed = [[1, 2, 3]; 11];
            mixed[at] = *tri;
            assert_eq!(any_degenerate(&positions, &mixed), one, "{tri:?}");
        }
    }
    assert!(both > 100 && both < triangles.len() - 100, "{both}");
}

#[test]
fn strips_are_degenerate_as_their_triangles_one_at_a_time() {
    // Rows of 5 vertices around a ring, one row a little above the other: some quads
    // nearly flat (a height near a millionth of their size), one row at a time moved far
    // from the origin; -0.0 and NaN too.
    let mut next = xorshift(0x9e37_79b9_7f4a_7c15u64);
    let mut both = 0;
    for round in 0..4000 {
        let origin = Vec3::new(next(), next(), next()) * 100.0 - 50.0;
        let height = if round % 2 == 0 {
            2e-6 * next()
        } else {
            next()
        };
        let row = |lift: f32, next: &mut dyn FnMut() -> f32| -> Vec<Vec3> {
            (0..5)
                .map(|k| {
                    let a = k as f32 * 1.3 + next() * 0.01;
                    origin + Vec3::new(math::cos(a), lift, math::sin(a)) * (1.0 + next())
                })
                .collect()
        };
        let below = row(0.0, &mut next);
        let mut above = if round % 3 == 0 {
            below.iter().map(|p| *p + Vec3::Y * height).collect()
        } else {
            row(height, &mut next)
        };
        if round % 97 == 0 {
            above[2] = below[2];
        }
        if round % 89 == 0 {
            above[3] = Vec3::new(-0.0, f32::NAN, 0.0);
        }
        let one: bool = (0..4).any(|k| {
            degenerate([below[k], below[k + 1], above[k + 1]])
                || degenerate([below[k], above[k + 1], above[k]])
        });
        both += usize::from(one);
        let by_axis = |row: &[Vec3]| -> [Vec<f32>; 3] {
            [0, 1, 2].map(|axis| row.iter().map(|p| p[axis]).collect())
        };
        let (b, a) = (by_axis(&below), by_axis(&above));
        let mut test = DegenerateTest::default();
        test.strip([&b[0], &b[1], &b[2]], [&a[0], &a[1], &a[2]]);
        assert_eq!(test.found(), one, "round {round}");
    }
    assert!(both > 100 && both < 3900, "{both}");
}

#[test]
fn the_same_triangles_are_found_on_one_thread_and_on_four() {
    let positions: Vec<Vec3> = (0..500)
        .map(|k| Vec3::new((k % 7) as f32, (k % 5) as f32, (k % 3) as f32))
        .collect();
    let indices: Vec<u32> = (0..3 * 60_000u32).map(|i| (i * 7919) % 500).collect();
    let on = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| unusable(&positions, &indices, SearchMemory::default()))
    };
    let one = on(1);
    assert_eq!(one, on(4));
    assert_eq!(one, unusable_by_definition(&positions, &indices));
    assert!(!one.is_empty());
}
