use super::*;
use crate::params::Crown;
use pge_engine::math;

fn grown(params: &ConiferParams, seed: u64, years: u32) -> Built {
    let whorls: Vec<Whorl> = (1..=years).map(|y| Whorl::draw(params, seed, y)).collect();
    build(params, &whorls, seed).expect("under the cap")
}

/// First-order branches per trunk node, in trunk order.
fn per_joint(b: &Built) -> Vec<usize> {
    b.trunk
        .iter()
        .map(|t| b.branches.iter().filter(|(_, j)| j == t).count())
        .collect()
}

#[test]
fn every_year_lays_down_a_whorl_of_branches_at_its_node() {
    let p = ConiferParams::default();
    let b = grown(&p, 1, 20);
    // The root and one node per year, nothing between whorls by default.
    assert_eq!(b.trunk.len(), 21);
    let counts = per_joint(&b);
    // Shed below the crown base (10% of 12 m: the first year's whorl at 0.6 m is gone),
    // none at the apex yet.
    assert_eq!(counts[0], 0);
    assert_eq!(counts[1], 0);
    assert_eq!(counts[20], 0);
    for (k, &n) in counts.iter().enumerate().take(20).skip(3) {
        assert!((4..=6).contains(&n), "whorl {k}: {n} branches");
    }
    // Turned from one whorl to the next: the first azimuths differ.
    let w: Vec<Whorl> = (1..=3).map(|y| Whorl::draw(&p, 1, y)).collect();
    assert!((w[0].buds[0].azimuth - w[1].buds[0].azimuth).abs() > 20.0);
}

#[test]
fn angles_grow_toward_the_base_and_branches_droop() {
    let p = ConiferParams {
        jitter: 0.0,
        ..ConiferParams::default()
    };
    let b = grown(&p, 1, 20);
    let s = &b.skeleton;
    // The angle of each branch's first segment from the vertical, by joint height.
    let mut angles: Vec<(f32, f32)> = b
        .branches
        .iter()
        .map(|(r, j)| {
            let a = s.positions[*j as usize];
            let d = (s.positions[r.start as usize] - a).normalize();
            (a.y, math::acos(d.y).to_degrees())
        })
        .collect();
    angles.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (low, high) = (angles[0].1, angles[angles.len() - 1].1);
    assert!(low > 85.0 && low < 96.0, "lowest branch at {low} degrees");
    assert!(
        high > 59.0 && high < 66.0,
        "highest branch at {high} degrees"
    );
    for w in angles.windows(2) {
        assert!(w[0].1 >= w[1].1 - 1e-3, "{w:?}");
    }
    // The lowest branch's tip heads further down than its base.
    let (r, _) = &b.branches[0];
    let axis_end = (r.start..r.end)
        .take_while(|&i| i == r.start || s.parents[i as usize] == Some(i - 1))
        .last()
        .expect("an axis");
    let n = axis_end as usize;
    let tip_dir = (s.positions[n] - s.positions[n - 1]).normalize();
    let base_dir =
        (s.positions[r.start as usize] - s.positions[b.branches[0].1 as usize]).normalize();
    assert!(tip_dir.y < base_dir.y - 0.1, "{tip_dir} vs {base_dir}");
}

#[test]
fn lengths_fall_toward_the_apex_along_the_crown() {
    let p = ConiferParams {
        jitter: 0.0,
        orders: 1,
        ..ConiferParams::default()
    };
    let b = grown(&p, 1, 20);
    let s = &b.skeleton;
    let reach: Vec<(f32, f32)> = b
        .branches
        .iter()
        .map(|(r, j)| {
            let base = s.positions[*j as usize];
            let tip = s.positions[r.end as usize - 1];
            (base.y, (tip - base).length())
        })
        .collect();
    for w in reach.windows(2) {
        assert!(w[1].1 <= w[0].1 + 1e-4, "{w:?}");
    }
    // The longest is near the crown radius (the chord of a drooping branch is shorter).
    let longest = reach[0].1;
    assert!(longest > 2.3 && longest <= 3.0, "{longest}");
    // A columnar crown keeps long branches higher up.
    let col = grown(
        &ConiferParams {
            crown: Crown::Columnar,
            ..p.clone()
        },
        1,
        20,
    );
    assert!(col.skeleton.len() > b.skeleton.len());
}

#[test]
fn the_leader_is_straight_and_branches_are_thin_at_their_joint() {
    let p = ConiferParams::default();
    let b = grown(&p, 7, 20);
    let s = &b.skeleton;
    let root = s.positions[0];
    let top = s.positions[*b.trunk.last().expect("apex") as usize];
    let height = top.y - root.y;
    assert!((height - 12.0).abs() < 1e-3, "{height}");
    for &t in &b.trunk {
        let d = s.positions[t as usize] - root;
        assert!(math::hypot(d.x, d.z) <= 0.02 * 0.6 * 1.5, "{d}");
    }
    let mut next = std::collections::BTreeMap::new();
    for w in b.trunk.windows(2) {
        next.insert(w[0], w[1]);
    }
    for (r, j) in &b.branches {
        let ratio = s.radii[r.start as usize] / s.radii[*j as usize];
        assert!(ratio <= 0.45 + 1e-6, "{ratio}");
        // The trunk goes on through the thickest child.
        let above = next[j];
        assert!(s.radii[above as usize] > s.radii[r.start as usize]);
    }
    // Tips carry the tip radius where nothing was thinned; the trunk's base is the thickest.
    let max = s.radii.iter().copied().fold(0.0, f32::max);
    assert_eq!(s.radii[0], max);
}

#[test]
fn sprays_lie_flat_beside_their_branch_and_orders_add_shoots() {
    let p = ConiferParams {
        jitter: 0.0,
        spray_droop: 0.0,
        droop: 0.0,
        ..ConiferParams::default()
    };
    let b = grown(&p, 2, 20);
    let s = &b.skeleton;
    let mut seen = 0;
    for i in 0..s.len() {
        if s.orders[i] != 2 {
            continue;
        }
        let q = s.parents[i].expect("a parent") as usize;
        if s.orders[q] != 1 {
            continue;
        }
        // A shoot's first segment lies in the plane of its branch's segment and the
        // horizontal across it.
        let shoot = (s.positions[i] - s.positions[q]).normalize();
        let branch = (s.positions[q] - s.positions[s.parents[q].expect("p") as usize]).normalize();
        let across = Vec3::new(branch.z, 0.0, -branch.x).normalize();
        let normal = branch.cross(across).normalize();
        assert!(shoot.dot(normal).abs() < 1e-3, "{shoot} {branch}");
        seen += 1;
    }
    assert!(seen > 100, "{seen}");
    let one = grown(
        &ConiferParams {
            orders: 1,
            ..p.clone()
        },
        2,
        20,
    );
    let three = grown(
        &ConiferParams {
            orders: 3,
            ..p.clone()
        },
        2,
        20,
    );
    assert!(one.skeleton.orders.iter().all(|&o| o <= 1));
    assert!(s.orders.iter().all(|&o| o <= 2));
    assert!(three.skeleton.orders.contains(&3));
    assert!(one.skeleton.len() < s.len() && s.len() < three.skeleton.len());
}

#[test]
fn draws_depend_on_the_seed_and_year_only() {
    let p = ConiferParams {
        interwhorl: (1, 2),
        ..ConiferParams::default()
    };
    let a = grown(&p, 5, 15);
    let b = grown(&p, 5, 15);
    let c = grown(&p, 6, 15);
    assert_eq!(a.skeleton, b.skeleton);
    assert_ne!(a.skeleton, c.skeleton);
    // Year 4's whorl is the same whenever it is drawn; interwhorl buds sit below it.
    let w = Whorl::draw(&p, 5, 4);
    assert_eq!(w, Whorl::draw(&p, 5, 4));
    let small: Vec<_> = w.buds.iter().filter(|b| b.along < 1.0).collect();
    assert!((1..=2).contains(&small.len()));
    assert!(small.iter().all(|b| b.along > 0.19 && b.along < 0.81));
    // Interwhorl branches add trunk nodes between the whorls.
    assert!(a.trunk.len() > 16);
}

#[test]
fn huge_counts_stop_at_the_node_cap_not_in_memory() {
    let p = ConiferParams {
        orders: 3,
        per_whorl: (12, 12),
        segment: 0.01,
        max_nodes: 10_000,
        ..ConiferParams::default()
    };
    let whorls: Vec<Whorl> = (1..=1000).map(|y| Whorl::draw(&p, 1, y)).collect();
    let e = build(&p, &whorls, 1).expect_err("capped");
    assert_eq!(e, TooManyNodes { cap: 10_000 });
    // Segments per axis are bounded: a 3 m branch of 1 cm segments has 64 of them.
    let p = ConiferParams {
        orders: 1,
        segment: 0.001,
        jitter: 0.0,
        ..ConiferParams::default()
    };
    let b = grown(&p, 1, 20);
    assert!(
        b.branches
            .iter()
            .all(|(r, _)| r.len() <= MAX_SEGMENTS as usize)
    );
}

#[test]
fn the_draws_are_uniform_enough() {
    let mut d = Draws::new(1, 2);
    let xs: Vec<f32> = (0..4000).map(|_| d.unit()).collect();
    assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
    let mean = xs.iter().sum::<f32>() / xs.len() as f32;
    assert!((mean - 0.5).abs() < 0.02, "{mean}");
    let ints: Vec<u32> = (0..600).map(|_| d.int(3, 5)).collect();
    for k in 3..=5 {
        let n = ints.iter().filter(|&&i| i == k).count();
        assert!(n > 150, "{k}: {n}");
    }
}

/// Any valid parameters, extremes included, build a skeleton or stop at the cap: no panic,
/// no non-finite position, every radius finite and positive.
#[test]
fn any_valid_parameters_build_or_stop_at_the_cap() {
    let mut d = Draws::new(9, 9);
    let mut pick = |values: &[f32]| values[d.int(0, values.len() as u32 - 1) as usize];
    for case in 0..150 {
        let lo = pick(&[1.0, 3.0, 12.0]) as u32;
        let p = ConiferParams {
            years: pick(&[1.0, 2.0, 7.0, 30.0]) as u32,
            height: pick(&[1e-4, 1.0, 12.0, 1e4]),
            crown_radius: pick(&[1e-4, 3.0, 1e4]),
            crown: match case % 4 {
                0 => Crown::Conic,
                1 => Crown::Ogive,
                2 => Crown::Columnar,
                _ => Crown::Profile(vec![0.0, pick(&[0.0, 1.0, 1e6]), 0.0]),
            },
            crown_base: pick(&[0.0, 0.5, 0.95]),
            per_whorl: (lo, lo.max(pick(&[1.0, 6.0, 12.0]) as u32)),
            twist: pick(&[-360.0, 0.0, 137.5]),
            angle: (pick(&[0.0, 60.0, 180.0]), pick(&[0.0, 95.0, 180.0])),
            droop: pick(&[0.0, 20.0, 90.0]),
            jitter: pick(&[0.0, 0.15, 1.0]),
            waviness: pick(&[0.0, 0.5]),
            segment: pick(&[1e-6, 0.25, 1e3]),
            orders: pick(&[1.0, 2.0, 3.0]) as u32,
            spray_angle: pick(&[0.0, 55.0, 90.0]),
            spray_length: pick(&[0.0, 0.5, 2.0]),
            spray_droop: pick(&[0.0, 90.0]),
            spray_pattern: if case % 3 == 0 {
                SprayPattern::Paired
            } else {
                SprayPattern::Alternate
            },
            bare: pick(&[0.0, 0.5, 1.0]),
            interwhorl: (0, pick(&[0.0, 8.0]) as u32),
            joint_ratio: pick(&[1e-3, 0.45, 1.0]),
            max_nodes: 20_000,
            ..ConiferParams::default()
        };
        p.validate().expect("valid");
        let whorls: Vec<Whorl> = (1..=p.years).map(|y| Whorl::draw(&p, 3, y)).collect();
        match build(&p, &whorls, 3) {
            Ok(b) => {
                let s = &b.skeleton;
                assert!(s.positions.iter().all(|v| v.is_finite()), "{p:?}");
                assert!(s.radii.iter().all(|r| r.is_finite() && *r >= 0.0), "{p:?}");
                pge_tree::check_skeleton(s).expect("a usable skeleton");
            }
            Err(e) => assert_eq!(e.cap, 20_000),
        }
    }
}
