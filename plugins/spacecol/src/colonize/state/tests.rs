//! The colonization state's tests: the parts, the pulls and the dead points against plain
//! loops.

use super::*;
use crate::shape::Shape;
use pge_engine::random::uniform24;
use rand_mt::Mt64;

/// A point of the cube `[0, scale)³`, drawn from `rng`.
fn random_point(rng: &mut Mt64, scale: f32) -> Vec3 {
    Vec3::new(uniform24(rng), uniform24(rng), uniform24(rng)) * scale
}

/// The tests' crown: a sphere of radius 3 in that cube, with a short step.
fn sphere_params() -> Params {
    let mut p = Params::new(Shape::Sphere {
        center: Vec3::splat(3.0),
        radius: 3.0,
    });
    (p.influence, p.kill, p.step) = (1.2, 0.3, 0.15);
    p
}

/// Two parts, updated side by side, leave every point as one part does: the same
/// nearest nodes and distances, the same dead, the same pulls to the bit.
#[test]
fn two_parts_update_as_one() {
    let mut rng = Mt64::new(11);
    let mut random = |scale: f32| random_point(&mut rng, scale);
    let pts: Vec<Vec3> = (0..4000).map(|_| random(6.0)).collect();
    let p = sphere_params();
    let mut one = State::with_parts(pts.clone(), p.influence, 1);
    let mut two = State::with_parts(pts, p.influence, 2);
    assert_eq!((one.parts.len(), two.parts.len()), (1, 2));
    for iteration in 1..40 {
        for _ in 0..iteration % 7 * 9 {
            let q = random(6.0);
            one.add_node(q, None, &p);
            two.add_node(q, None, &p);
        }
        one.flush(&p);
        two.flush(&p);
        let dying = (iteration * 97) as usize % one.points.len();
        one.kill(dying);
        two.kill(dying);
        one.pull(iteration, None);
        two.pull(iteration, None);
        assert_eq!(one.alive, two.alive);
        assert_eq!(one.alive_count, two.alive_count);
        let bits = |v: &[Nearest]| {
            v.iter()
                .map(|n| (n.node, n.d2.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&one.nearest), bits(&two.nearest));
        assert_eq!(one.touched, two.touched);
        assert_eq!(one.pulls, two.pulls);
        one.touched.clear();
        two.touched.clear();
    }
    let pulling = one.nearest.iter().filter(|n| n.node != NONE).count();
    assert!(
        one.alive_count < one.points.len() * 9 / 10 && pulling > 2000,
        "{} of 4000 points left, {pulling} with a nearest node",
        one.alive_count
    );
}

/// A pull sums every live point with a nearest node in increasing index order,
/// whatever order the points got their nodes in, drops the points of a node refused at
/// the last iteration, and says whether any point still pulls: as a loop over all the
/// points does.
/// Every point with a pulling bit is alive and has a nearest node.
fn assert_only_live_points_pull(st: &State) {
    for i in 0..st.points.len() {
        if st.pulling[i / 64] >> (i % 64) & 1 == 1 {
            assert!(st.alive[i] && st.nearest[i].node != NONE, "point {i}");
        }
    }
}

#[test]
fn a_start_skeleton_clears_the_bits_of_the_points_it_kills() {
    let pts: Vec<Vec3> = (0..400)
        .map(|i| Vec3::new((i % 20) as f32, (i / 20) as f32, 0.0) * 0.1)
        .collect();
    let mut p = Params::new(Shape::Sphere {
        center: Vec3::ONE,
        radius: 1.0,
    });
    (p.influence, p.kill, p.step) = (0.5, 0.15, 0.1);
    let mut st = State::with_parts(pts, p.influence, 1);
    // A root, a short tip (it gives points their nearest node), then a branch of inner
    // nodes that kill some of those points, parents before children.
    let mut positions = vec![Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.05, 1.0, 0.0)];
    let mut parents = vec![None, Some(0)];
    for k in 2..12 {
        positions.push(Vec3::new(1.0 - (k - 1) as f32 * 0.08, 1.0, 0.0));
        parents.push(Some(if k == 2 { 0 } else { k as u32 - 1 }));
    }
    let n = positions.len();
    let start = Skeleton {
        positions,
        parents,
        radii: vec![0.01; n],
        orders: vec![0; n],
        leaves: Vec::new(),
    };
    st.seed_from(&start, &p);
    assert!(st.alive_count < 400, "no point killed");
    assert_only_live_points_pull(&st);
}

#[test]
fn pulls_sum_the_live_points_in_index_order() {
    let mut rng = Mt64::new(7);
    let mut random = |scale: f32| random_point(&mut rng, scale);
    let pts: Vec<Vec3> = (0..3000).map(|_| random(6.0)).collect();
    let p = sphere_params();
    let mut st = State::with_parts(pts, p.influence, 1);
    let (mut summed, mut dropped) = (0, 0);
    for iteration in 1..60u32 {
        for _ in 0..6 {
            let q = random(6.0);
            st.add_node(q, None, &p);
        }
        st.flush(&p);
        assert_only_live_points_pull(&st);
        if iteration % 4 == 0 {
            let n = (iteration as usize * 37) % st.nodes.len();
            st.refused[n] = iteration - 1;
        }
        let mut want = vec![Pull::NONE; st.nodes.len()];
        let (mut touched, mut unreachable) = (Vec::new(), Vec::new());
        for i in 0..st.points.len() {
            let Nearest { node, d2 } = st.nearest[i];
            if !st.alive[i] || node == NONE {
                continue;
            }
            let n = node as usize;
            if st.refused[n] == iteration - 1 {
                unreachable.push(i);
                continue;
            }
            let pull = &mut want[n];
            if pull.closest == NONE {
                touched.push(node);
            }
            pull.sum += (st.points[i] - st.nodes[n]) / d2.sqrt();
            if d2 < pull.closest_d2 {
                (pull.closest_d2, pull.closest) = (d2, i as u32);
            }
        }
        st.pull(iteration, None);
        assert_eq!(st.touched, touched, "iteration {iteration}");
        assert_eq!(st.pulls, want, "iteration {iteration}");
        assert!(unreachable.iter().all(|i| !st.alive[*i]));
        assert_eq!(st.none_active(), touched.is_empty());
        summed += touched.len();
        dropped += unreachable.len();
        for n in st.touched.drain(..) {
            st.pulls[n as usize] = Pull::NONE;
        }
    }
    assert!(
        summed > 100 && dropped > 10 && st.alive_count < 2500,
        "{summed} pulls, {dropped} points dropped, {} points left",
        st.alive_count
    );
}

/// The duplicate-growth guard finds a node within `eps` exactly when there is one, on
/// either side of a cell's border, below zero, and where cells 2^21 apart share a key.
#[test]
fn the_guard_finds_exactly_the_nodes_within_eps() {
    let mut rng = Mt64::new(13);
    let mut random = |scale: f32| {
        (Vec3::new(
            uniform24(&mut rng),
            uniform24(&mut rng),
            uniform24(&mut rng),
        ) - 0.5)
            * scale
    };
    let mut p = Params::new(Shape::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    });
    p.step = 0.25;
    let mut st = State::with_parts(vec![Vec3::ZERO], 2.0, 1);
    // Cells 2^21 steps apart along x share their keys with the cells around the origin.
    let far = Vec3::X * (p.step * (1 << 21) as f32);
    for _ in 0..400 {
        let q = random(4.0);
        st.push_node(q, None, &p);
        st.push_node(q + far, None, &p);
    }
    let eps = 0.2 * p.step;
    let (mut near, mut clear) = (0, 0);
    for k in 0..4000 {
        let base = random(4.0);
        // Every other query close to a node, so that both answers are common.
        let q = if k % 2 == 0 {
            st.nodes[k % st.nodes.len()] + random(0.08)
        } else {
            base
        };
        let want = st.nodes.iter().any(|n| n.distance_squared(q) < eps * eps);
        assert_eq!(st.occupied(q, eps, p.step), want, "query at {q}");
        if want {
            near += 1;
        } else {
            clear += 1;
        }
    }
    assert!(near > 500 && clear > 500, "{near} near, {clear} clear");
}

#[test]
fn floor_i32_is_floor_cast() {
    let mut xs = vec![
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        -1.5,
        2.999_999_8,
        -2.000_000_2,
        16_777_217.0,
        -16_777_215.5,
        2.5e9,
        -2.5e9,
        -2_147_483_648.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
    ];
    xs.extend((-2000..2000).map(|k| k as f32 * 0.173));
    for x in xs {
        assert_eq!(floor_i32(x), x.floor() as i32, "{x}");
    }
}
