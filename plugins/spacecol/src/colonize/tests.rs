//! Unit tests of the colonization.

use super::*;
use crate::shape::Shape;
use pge_engine::algorithm::run;
use pge_engine::math;

fn crown(points: u32) -> Params {
    let mut p = Params::new(Shape::Ellipsoid {
        center: Vec3::new(0.0, 6.0, 0.0),
        radii: Vec3::new(4.0, 3.0, 4.0),
    });
    p.points = Some(points);
    p.step = 0.25;
    p.influence = 2.0;
    p.kill = 0.5;
    p
}

fn grow(params: Params, seed: u64) -> (SpaceColonization, Model) {
    let mut sc = SpaceColonization::new(params, Location::new("t.lua", 1)).expect("valid");
    let ctx = RunContext {
        seed,
        ..RunContext::default()
    };
    let model = run(&mut sc, &ctx, &mut |_| {}).expect("grows");
    (sc, model)
}

#[test]
fn a_snapshot_goes_on_as_the_original() {
    let ctx = RunContext::default();
    let mut a = SpaceColonization::new(crown(300), Location::new("t.lua", 1)).expect("valid");
    a.init(&ctx).expect("init");
    for _ in 0..5 {
        a.step(&ctx).expect("step");
    }
    let mut b = a.snapshot().expect("copyable");
    while a.step(&ctx).expect("step") == Step::Continue {}
    while b.step(&ctx).expect("step") == Step::Continue {}
    let (sa, sb) = (
        Algorithm::skeleton(&a).expect("grown"),
        b.skeleton().expect("grown"),
    );
    assert!(sa.positions.len() > 10);
    assert_eq!(sa.positions, sb.positions);
    assert_eq!(sa.parents, sb.parents);
}

#[test]
fn every_point_is_reached_or_out_of_reach() {
    let (sc, model) = grow(crown(2000), 1);
    assert!(sc.warnings().is_empty(), "{:?}", sc.warnings());
    let (pts, alive) = sc.attraction_points().expect("state");
    let skeleton = sc.skeleton().expect("skeleton");
    let influence = sc.params().influence;
    for (p, a) in pts.iter().zip(alive) {
        if *a {
            let nearest = skeleton
                .positions
                .iter()
                .map(|n| n.distance(*p))
                .fold(f32::INFINITY, f32::min);
            assert!(
                nearest >= influence,
                "a live point is within reach of a node ({nearest})"
            );
        }
    }
    let removed = alive.iter().filter(|a| !**a).count();
    assert!(removed > 1900, "only {removed} of 2000 points were reached");
    // The skeleton's arrays are the state's: every parent before its children, as
    // `Skeleton::push` requires, one root, radii and orders unset.
    let mut pushed = pge_engine::geometry::Skeleton::new();
    for (p, parent) in skeleton.positions.iter().zip(&skeleton.parents) {
        pushed.push(*p, *parent, 0.0, 0);
    }
    assert_eq!(skeleton, pushed);
    assert_eq!(skeleton.parents.iter().filter(|p| p.is_none()).count(), 1);
    assert!(model.stats.nodes > 100);
    model.validate().expect("valid model");
}

#[test]
fn the_skeleton_is_one_tree_rooted_at_the_root() {
    let (sc, _) = grow(crown(1500), 3);
    let s = sc.skeleton().expect("skeleton");
    assert_eq!(s.positions[0], Vec3::ZERO);
    assert_eq!(s.parents[0], None);
    for i in 1..s.len() {
        let parent = s.parents[i].expect("only node 0 is a root");
        assert!((parent as usize) < i);
        let len = s.positions[i].distance(s.positions[parent as usize]);
        assert!((len - 0.25).abs() < 1e-4, "segment {i} has length {len}");
    }
    // The trunk reaches the crown: some node lies inside the ellipsoid.
    assert!(s.positions.iter().any(|p| p.y > 4.0));
}

#[test]
fn same_seed_same_tree() {
    let (_, a) = grow(crown(800), 5);
    let (_, b) = grow(crown(800), 5);
    let (_, c) = grow(crown(800), 6);
    assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
    assert_eq!(a.meshes[0].indices, b.meshes[0].indices);
    assert_ne!(a.meshes[0].positions, c.meshes[0].positions);
}

#[test]
fn an_unreachable_crown_stops_at_the_cap_with_a_warning() {
    let mut p = crown(300);
    p.roots = vec![Vec3::new(0.0, -1000.0, 0.0)];
    p.max_iterations = 50;
    let (sc, model) = grow(p, 1);
    assert_eq!(sc.iterations(), 50);
    assert_eq!(sc.warnings().len(), 1);
    assert!(
        sc.warnings()[0].contains("maxIterations = 50"),
        "{}",
        sc.warnings()[0]
    );
    assert_eq!(model.stats.nodes, 51);
}

#[test]
fn a_straight_trunk_grows_first() {
    let mut p = crown(1500);
    p.trunk = 7.0;
    let (sc, model) = grow(p, 2);
    let s = sc.skeleton().expect("skeleton");
    // 28 nodes of 0.25 stand straight above the root, each the parent of the next.
    let mut below = 0u32;
    for k in 1..=28 {
        let above = (0..s.len())
            .find(|&i| {
                s.parents[i] == Some(below)
                    && s.positions[i].x.abs() < 1e-5
                    && s.positions[i].z.abs() < 1e-5
            })
            .unwrap_or_else(|| panic!("no trunk node {k}"));
        assert!((s.positions[above].y - 0.25 * k as f32).abs() < 1e-4);
        below = above as u32;
    }
    model.validate().expect("valid");
}

#[test]
fn opposite_points_do_not_trap_a_node() {
    // Two points exactly on either side of the root: their pulls cancel.
    let pts = Shape::Union(
        vec![
            Shape::Sphere {
                center: Vec3::new(-1.0, 0.0, 0.0),
                radius: 0.01,
            },
            Shape::Sphere {
                center: Vec3::new(1.0, 0.0, 0.0),
                radius: 0.01,
            },
        ]
        .into(),
    );
    let mut p = Params::new(pts);
    assert_eq!(p.trunk, 0.0);
    p.points = Some(2);
    p.step = 0.3;
    p.influence = 1.5;
    p.kill = 0.2;
    p.max_iterations = 100;
    let (sc, _) = grow(p, 1);
    assert!(sc.warnings().is_empty(), "it finished on its own");
    assert!(sc.iterations() < 30);
}

#[test]
fn a_start_skeleton_keeps_its_nodes_and_grows_from_its_tips() {
    let mut start = Skeleton::new();
    let r = start.push(Vec3::ZERO, None, 0.3, 0);
    let a = start.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.25, 0);
    start.push(Vec3::new(-1.0, 4.0, 0.0), Some(a), 0.1, 1);
    start.push(Vec3::new(1.0, 4.0, 0.0), Some(a), 0.1, 1);
    let mut p = crown(1500);
    p.start = Some(std::sync::Arc::new(start.clone()));
    let (sc, model) = grow(p, 1);
    model.validate().expect("valid");
    let s = sc.skeleton().expect("skeleton");
    assert_eq!(&s.positions[..4], &start.positions[..]);
    assert_eq!(&s.parents[..4], &start.parents[..]);
    assert_eq!(&s.radii[..4], &start.radii[..]);
    assert!(s.len() > 100, "{}", s.len());
    // Growth hangs on the two tips (or on what grew from them), never on the trunk.
    for i in 4..s.len() {
        let parent = s.parents[i].expect("no new root");
        assert!(parent >= 2, "node {i} grew from the trunk node {parent}");
    }
}

/// The growth parameters of `scripts/species/conifer.lua` at its default parameters,
/// without the options that hold a branch's course: a cone crown, a leader grown first
/// through it, drooping side branches.
fn conifer() -> Params {
    let mut p = Params::new(Shape::Cone {
        base: Vec3::new(0.0, 1.5, 0.0),
        apex: Vec3::new(0.0, 12.0, 0.0),
        radius: 3.2,
    });
    p.points = Some(3500);
    p.step = 0.22;
    p.influence = 1.3;
    p.kill = 0.35;
    p.trunk = 12.0 - 1.5 - 0.5;
    p.tropism = Vec3::new(0.0, -0.3, 0.0);
    p
}

/// The largest angle in degrees between a segment and the first segment of its
/// branch: a branch goes on through each node's first-grown child (the apical bud, the
/// lowest index); later children start side branches.
fn largest_turn(s: &Skeleton) -> f32 {
    let mut start = vec![Vec3::ZERO; s.len()];
    let mut continued = vec![false; s.len()];
    let mut worst = 0.0f32;
    for i in 0..s.len() {
        let Some(q) = s.parents[i] else { continue };
        let q = q as usize;
        let d = (s.positions[i] - s.positions[q]).normalize();
        start[i] = if continued[q] || start[q] == Vec3::ZERO {
            d
        } else {
            start[q]
        };
        continued[q] = true;
        worst = worst.max(math::acos(d.dot(start[i]).clamp(-1.0, 1.0)).to_degrees());
    }
    worst
}

#[test]
fn conifer_branches_never_turn_back() {
    for seed in [1, 2, 3] {
        // Each tip follows the mean of its pulls alone: the lower branches follow the
        // cone up and back toward the leader, pulled by the points above them.
        let (sc, _) = grow(conifer(), seed);
        let free = largest_turn(&sc.skeleton().expect("skeleton"));
        assert!(free > 140.0, "seed {seed}: the free growth turns {free}");
        let mut p = conifer();
        p.persistence = 0.5;
        p.perception = 90.0;
        p.max_turn = 100.0;
        let (sc, model) = grow(p, seed);
        let turn = largest_turn(&sc.skeleton().expect("skeleton"));
        assert!(turn <= 100.01, "seed {seed}: a branch turns {turn} degrees");
        assert!(sc.warnings().is_empty(), "{:?}", sc.warnings());
        assert!(model.stats.nodes > 1500, "{}", model.stats.nodes);
        model.validate().expect("valid model");
    }
}

#[test]
fn persistence_and_perception_alone_straighten_branches() {
    let (sc, _) = grow(conifer(), 1);
    let free = largest_turn(&sc.skeleton().expect("skeleton"));
    let mut p = conifer();
    p.persistence = 1.0;
    p.perception = 60.0;
    let (sc, _) = grow(p, 1);
    let held = largest_turn(&sc.skeleton().expect("skeleton"));
    assert!(held < free - 20.0, "{free} -> {held}");
}

#[test]
fn bad_parameters_name_themselves() {
    let mut p = crown(10);
    p.kill = 3.0;
    let e = SpaceColonization::new(p, Location::new("t.lua", 4))
        .err()
        .expect("kill > influence");
    assert!(
        e.to_string()
            .starts_with("t.lua:4: kill (3) must be smaller than influence (2)"),
        "{e}"
    );
    let mut p = crown(10);
    p.step = -1.0;
    let e = SpaceColonization::new(p, Location::new("t.lua", 4))
        .err()
        .expect("negative step");
    assert_eq!(e.to_string(), "t.lua:4: step must be a number > 0, got -1");
    for (name, set) in [
        (
            "perception",
            (|p, v| p.perception = v) as fn(&mut Params, f32),
        ),
        ("maxTurn", |p, v| p.max_turn = v),
    ] {
        for bad in [0.0, 181.0, f32::NAN] {
            let mut p = crown(10);
            set(&mut p, bad);
            let e = SpaceColonization::new(p, Location::new("t.lua", 2))
                .err()
                .expect("a bad angle");
            assert!(
                e.to_string()
                    .starts_with(&format!("t.lua:2: {name} must be")),
                "{e}"
            );
        }
    }
    let mut p = crown(10);
    p.persistence = -1.0;
    assert!(SpaceColonization::new(p, Location::new("t.lua", 4)).is_err());
    let mut p = crown(10);
    p.influence = f32::NAN;
    assert!(SpaceColonization::new(p, Location::new("t.lua", 4)).is_err());
}
