//! Tests of the nutrient-transport growth.

use super::*;
use pge_engine::math;

fn tree(params: TransportParams, seed: u32) -> TransportTree {
    TransportTree::new(params, &[(DVec3::ZERO, DVec3::Y, 1.0)], seed)
}

fn grown(steps: u32, seed: u32) -> TransportTree {
    let mut t = tree(TransportParams::default(), seed);
    for _ in 0..steps {
        t.feed(usize::MAX).expect("under the cap");
    }
    t
}

/// The seed's recursive leaf average, for checking the linear pass.
fn naive_average(t: &TransportTree, b: usize) -> DVec3 {
    let own = t.length[b] * t.dir[b];
    let [a, c] = t.children[b];
    if a == NONE {
        return own;
    }
    let r = t.params.ratio;
    own + r * naive_average(t, a as usize) + (1.0 - r) * naive_average(t, c as usize)
}

#[test]
fn the_fast_cube_root_is_the_standard_librarys_bit_for_bit() {
    let mut rng = Mt::new(11);
    let mut unit = || f64::from(rng.next_u32()) / f64::from(u32::MAX);
    let mut xs: Vec<f64> = vec![1e-200, 1e200, 1.0, 8.0, 27.0, 0.001, 2.0, 3.0, 1e-5];
    for k in 1..2000u32 {
        let c = f64::from(k);
        xs.extend([c * c * c, c.powi(3) / 1e6]);
        let cube = c * c * c;
        xs.extend([
            f64::from_bits(cube.to_bits() - 1),
            f64::from_bits(cube.to_bits() + 1),
        ]);
    }
    for _ in 0..300_000 {
        // Feeds span many decades: exponents from -60 to 60, and the transport
        // model's own range (1e-5 to 1e5) densely.
        xs.push(math::powf(2f64, 120.0 * unit() - 60.0));
        xs.push(math::powf(10f64, 10.0 * unit() - 5.0));
    }
    for x in xs {
        assert_eq!(cbrt(x).to_bits(), math::cbrt(x).to_bits(), "cbrt({x:e})");
    }
    for x in [0.0, -8.0, f64::INFINITY, 1e-300, 1e300] {
        assert_eq!(cbrt(x).to_bits(), math::cbrt(x).to_bits(), "cbrt({x:e})");
    }
}

#[test]
fn the_first_feedings_follow_the_seed_by_hand() {
    let mut t = tree(TransportParams::default(), 1);
    t.feed(usize::MAX).expect("ok");
    // length 1, area 0.1 + (1 - 1 * 0.1) / 1 = 1.0.
    assert!((t.length[0] - 1.0).abs() < 1e-12);
    assert!((t.area[0] - 1.0).abs() < 1e-12);
    t.feed(usize::MAX).expect("ok");
    assert!((t.length[0] - 2.0).abs() < 1e-12);
    assert!((t.area[0] - (1.0 + (1.0 - 1.0) / 2.0)).abs() < 1e-12);
    assert_eq!(t.len(), 1, "2 < splitsize 2.5: no split yet");
    t.feed(usize::MAX).expect("ok");
    assert_eq!(t.len(), 3, "3 > 2.5: the trunk split");
    assert_eq!(t.children[0], [1, 2]);
    assert_eq!(t.depth[1], 1);
    assert_eq!(t.length[1], 0.0);
    // The heavier child A (ratio 0.6) leans less from the trunk than B.
    assert!(t.dir[1].dot(DVec3::Y) > t.dir[2].dot(DVec3::Y));
    for d in &t.dir {
        assert!((d.length() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn every_feeding_is_accounted_for() {
    let mut t = tree(TransportParams::default(), 3);
    let mut splits = 0;
    for _ in 0..80 {
        let v0 = t.volume();
        let f = t.feed(usize::MAX).expect("ok");
        assert!((f.fed - 1.0).abs() < 1e-15);
        let grown = t.volume() - v0;
        assert!(
            (f.fed - grown - f.dropped).abs() < 1e-9 * f.fed.max(t.volume()),
            "fed {} grown {grown} dropped {}",
            f.fed,
            f.dropped
        );
        assert!((f.grown - grown).abs() < 1e-9 * t.volume());
        splits += f.splits;
    }
    assert!(splits > 20, "{splits}");
    assert_eq!(t.len() as u32, 1 + 2 * splits);
}

#[test]
fn cross_sections_at_forks_follow_the_feedback_rule() {
    // The parent keeps (A + B) / (A + B + P) of the feed: the more its children's area
    // exceeds its own, the more it keeps, so its area tracks the sum of theirs. As the
    // seed notes, it does not settle at exactly 1 because area grows by feed / length
    // and the parent is longer: it settles near 1.6. Bound: at every fork that carries
    // 15 branches or more, parent area / (A + B) lies within [0.5, 2], and the median
    // within [1.2, 1.8]; the same holds at every size from 80 to 250 feedings.
    for steps in [80, 150, 250] {
        let t = grown(steps, 7);
        let mut size = vec![1u32; t.len()];
        for i in (0..t.len()).rev() {
            let [a, b] = t.children[i];
            if a != NONE {
                size[i] = 1 + size[a as usize] + size[b as usize];
            }
        }
        let mut q = Vec::new();
        for (i, &n) in size.iter().enumerate() {
            let [a, b] = t.children[i];
            if a != NONE && n >= 15 {
                q.push(t.area[i] / (t.area[a as usize] + t.area[b as usize]));
            }
        }
        q.sort_by(f64::total_cmp);
        assert!(q.len() >= 5, "{} forks after {steps} feedings", q.len());
        let (lo, hi, median) = (q[0], q[q.len() - 1], q[q.len() / 2]);
        assert!(lo >= 0.5 && hi <= 2.0, "after {steps}: {lo} .. {hi}");
        assert!(
            (1.2..=1.8).contains(&median),
            "after {steps}: median {median}"
        );
    }
}

#[test]
fn the_linear_pass_equals_the_seeds_recursion() {
    let mut t = grown(60, 2);
    t.leaf_averages();
    for i in 0..t.len() {
        let want = naive_average(&t, i);
        assert!(
            (t.average[i] - want).length() < 1e-9 * (1.0 + want.length()),
            "branch {i}"
        );
    }
}

#[test]
fn same_seed_same_tree_and_another_seed_another() {
    let a = grown(60, 5);
    let b = grown(60, 5);
    let c = grown(60, 6);
    assert_eq!(a.dir, b.dir);
    assert_eq!(a.area, b.area);
    assert_ne!(a.dir, c.dir);
}

#[test]
fn the_cap_refuses_before_growing_past_it() {
    let params = TransportParams {
        feed: 1e4,
        splitsize: 0.1,
        ..TransportParams::default()
    };
    let mut t = tree(params, 1);
    let mut result = Ok(Feeding::default());
    for _ in 0..100 {
        result = t.feed(1000);
        if result.is_err() {
            break;
        }
    }
    let e = result.expect_err("explodes");
    assert_eq!(e.cap, 1000);
    assert!(e.would_have > 1000);
    assert!(t.len() <= 1000);
}

#[test]
fn bad_parameters_name_themselves() {
    let bad = |f: fn(&mut TransportParams)| {
        let mut p = TransportParams::default();
        f(&mut p);
        p.validate().expect_err("invalid").to_string()
    };
    assert_eq!(
        bad(|p| p.ratio = 1.0),
        "ratio must be a number between 0 and 1 (exclusive), got 1"
    );
    assert_eq!(
        bad(|p| p.splitsize = 0.0),
        "splitsize must be a number > 0, got 0"
    );
    assert_eq!(bad(|p| p.feed = -1.0), "feed must be a number > 0, got -1");
    assert_eq!(
        bad(|p| p.spread = f64::NAN),
        "spread must be a finite number, got NaN"
    );
    assert!(TransportParams::default().validate().is_ok());
}
