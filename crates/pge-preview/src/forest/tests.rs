use super::*;
use serde_json::json;

/// A leaf mesh's levels: `leaves` original leaves and `roots` at the coarsest level, one
/// sector: level i draws the first i leaves of V and the last `roots` (a + c = roots +
/// i, both ranges in V), the finest level the originals.
fn lod(leaves: u32, roots: u32) -> LeafLod {
    let v = 2 * leaves - roots;
    let mut rows: Vec<[u32; 3]> = (0..=leaves - roots)
        .map(|i| [i, v - roots, roots])
        .collect();
    rows[(leaves - roots) as usize] = [leaves, 0, 0];
    let lod = json!({"leaves": leaves, "roots": roots, "table": rows});
    let lod = pge_engine::export::lod_from_json(&lod).expect("a table");
    LeafLod::from_lod(Some(&lod), 4 * v as usize).expect("lod")
}

/// A row of `n` instances along -Z from the origin, one metre apart, scaled by one.
fn row(n: usize) -> Vec<[f32; 16]> {
    (0..n)
        .map(|i| Mat4::from_translation(Vec3::new(0.0, 0.0, -(i as f32) - 5.0)).to_cols_array())
        .collect()
}

fn view() -> View {
    let proj = Mat4::perspective_rh(0.8, 1.0, 0.1, 10_000.0);
    View {
        eye: Vec3::ZERO,
        view_proj: proj * Mat4::look_at_rh(Vec3::ZERO, -Vec3::Z, Vec3::Y),
    }
}

/// Triangles and leaves of a plan counted from its draws alone, and each instance's
/// band checked to be unique.
fn count(plan: &Plan, meshes: &[ForestMesh]) -> u64 {
    let mut triangles = 0;
    for (p, m) in plan.meshes.iter().zip(meshes) {
        let mut seen = vec![0u32; m.instances.len()];
        for i in &p.order {
            seen[*i as usize] += 1;
        }
        assert!(seen.iter().all(|&s| s <= 1), "an instance in two bands");
        for d in &p.draws {
            assert!(d.instances.end as usize <= p.order.len());
            triangles += d.triangles();
        }
    }
    triangles
}

/// The leaves each instance of a leaf mesh draws in `plan`.
fn leaves_per_instance(p: &MeshPlan, n: usize) -> Vec<u32> {
    let mut out = vec![0u32; n];
    for d in &p.draws {
        for &i in &p.order[d.instances.start as usize..d.instances.end as usize] {
            out[i as usize] += d.indices.len() as u32 / 6;
        }
    }
    out
}

#[test]
fn bands_halve_from_the_original_leaves_to_the_coarsest_level() {
    let Detail::Leaves {
        bands,
        leaves,
        least,
    } = Detail::leaves(&lod(64, 16))
    else {
        panic!("leaves");
    };
    assert_eq!((leaves, least), (64, 2));
    let counts: Vec<(u32, bool)> = bands.iter().map(|b| (b.leaves, b.grown)).collect();
    assert_eq!(
        counts,
        vec![
            (64, false),
            (32, false),
            (16, false),
            (8, true),
            (4, true),
            (2, true)
        ]
    );
    for b in &bands {
        let drawn: u32 = b.ranges.iter().map(|r| r.len() as u32 / 6).sum();
        assert_eq!(drawn, b.leaves);
    }
}

#[test]
fn the_budget_holds_and_nearer_instances_get_no_fewer_leaves() {
    let leaves = Detail::leaves(&lod(64, 16));
    let bark = Detail::Rigid {
        full: 300,
        coarse: Some(30),
    };
    let small = Detail::Rigid {
        full: 60,
        coarse: None,
    };
    let instances = row(500);
    let meshes = [
        ForestMesh {
            instances: &instances,
            centre: Vec3::Y,
            radius: 1.5,
            detail: &leaves,
        },
        ForestMesh {
            instances: &instances,
            centre: Vec3::Y,
            radius: 1.5,
            detail: &bark,
        },
        ForestMesh {
            instances: &instances,
            centre: Vec3::ZERO,
            radius: 0.5,
            detail: &small,
        },
    ];
    for budget in [0, 1, 50, 499, 500, 2_000, 10_000, 32_000, 1_000_000] {
        let plan = plan(&meshes, &view(), budget, &mut PlanBuffers::default());
        let triangles = count(&plan, &meshes);
        assert_eq!(triangles, plan.triangles, "budget {budget}");
        assert!(plan.leaves <= budget, "{} leaves > {budget}", plan.leaves);
        let leaf_triangles = 2 * plan.leaves;
        assert!(
            triangles - leaf_triangles <= budget,
            "{} other triangles > {budget}",
            triangles - leaf_triangles
        );
        // Instances are in distance order: nearer never fewer leaves.
        let drawn = leaves_per_instance(&plan.meshes[0], instances.len());
        assert!(
            drawn.windows(2).all(|w| w[0] >= w[1]),
            "{budget}: {drawn:?}"
        );
        assert_eq!(
            drawn.iter().map(|&d| u64::from(d)).sum::<u64>(),
            plan.leaves
        );
        // Bark: whole, then coarse, then none, by distance.
        let mut bark = vec![2u8; instances.len()];
        for d in &plan.meshes[1].draws {
            for &i in &plan.meshes[1].order[d.instances.start as usize..d.instances.end as usize] {
                bark[i as usize] = u8::from(d.source == Source::Coarse);
            }
        }
        assert!(bark.windows(2).all(|w| w[0] <= w[1]), "{budget}: {bark:?}");
    }
    // A generous budget draws everything whole.
    let plan = plan(&meshes, &view(), 1_000_000, &mut PlanBuffers::default());
    assert_eq!(plan.leaves, 500 * 64);
    assert_eq!(plan.triangles, 500 * (128 + 100 + 20));
    // A tight one still draws the nearest trees finer than the farthest.
    let tight = super::plan(&meshes, &view(), 4_000, &mut PlanBuffers::default());
    let drawn = leaves_per_instance(&tight.meshes[0], instances.len());
    assert!(drawn[0] > drawn[400], "{drawn:?}");
    assert!(tight.leaves > 3_000, "the budget is used: {}", tight.leaves);
}

#[test]
fn buffers_kept_from_earlier_plans_make_the_same_plans_as_new_ones() {
    let small = Detail::leaves(&lod(64, 16));
    let big = Detail::leaves(&lod(200, 25));
    let bark = Detail::Rigid {
        full: 300,
        coarse: Some(30),
    };
    let (many, few) = (row(800), row(120));
    let forest = |instances| {
        [&small, &big, &bark].map(|detail| ForestMesh {
            instances,
            centre: Vec3::Y,
            radius: 1.5,
            detail,
        })
    };
    let (large, smaller) = (forest(&many), forest(&few));
    let turned = |x: f32| {
        let eye = Vec3::new(x, 2.0, 3.0);
        View {
            eye,
            view_proj: Mat4::perspective_rh(0.8, 1.0, 0.1, 10_000.0)
                * Mat4::look_at_rh(eye, Vec3::new(0.0, 0.0, -60.0), Vec3::Y),
        }
    };
    // One set of buffers through plans of more instances, then fewer, other cameras and
    // budgets: each plan is the one new buffers (what `pge_lod::assign` allocates) make.
    let mut kept = PlanBuffers::default();
    let mut drawn = 0;
    for (meshes, x, budget) in [
        (&large, 0.0, 50_000),
        (&smaller, 0.0, 50_000),
        (&smaller, 4.0, 3_000),
        (&large, -3.0, 900),
        (&large, -3.0, 1_000_000),
        (&smaller, 1.0, 20_000),
    ] {
        let again = plan(meshes, &turned(x), budget, &mut kept);
        let fresh = plan(meshes, &turned(x), budget, &mut PlanBuffers::default());
        assert_eq!(
            again,
            fresh,
            "{} instances at x = {x}, T = {budget}",
            meshes[0].instances.len()
        );
        drawn += again.leaves;
    }
    assert!(drawn > 0);
    assert_eq!(kept.meshes.len(), 3);
    assert!(kept.meshes[1].counts.capacity() >= 120);
}

#[test]
fn meshes_get_their_needs_first_then_shares_of_the_rest() {
    // Needs 100 + 50 fit in 450: the remaining 300 go 4:1 as asked beyond the needs.
    assert_eq!(share(450, &[500, 150], &[100, 50]), vec![340, 110]);
    // They do not fit in 30: 2:1 of the needs.
    assert_eq!(share(30, &[500, 150], &[100, 50]), vec![20, 10]);
    // Never more than the total, even with rounding.
    for total in [0, 1, 7, 149, 150, 151, 1000] {
        let s = share(total, &[333, 333, 334], &[10, 20, 30]);
        assert!(s.iter().sum::<u64>() <= total, "{total}: {s:?}");
    }
    assert_eq!(share(10, &[0, 0], &[0, 0]), vec![0, 0]);
}

#[test]
fn instances_out_of_view_are_not_drawn() {
    let bark = Detail::Rigid {
        full: 3,
        coarse: None,
    };
    // Two in front of the eye, one behind it, one far to the side.
    let instances: Vec<[f32; 16]> = [
        Vec3::new(0.0, 0.0, -10.0),
        Vec3::new(1.0, 0.0, -20.0),
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(100.0, 0.0, -10.0),
    ]
    .iter()
    .map(|p| Mat4::from_translation(*p).to_cols_array())
    .collect();
    let meshes = [ForestMesh {
        instances: &instances,
        centre: Vec3::ZERO,
        radius: 1.0,
        detail: &bark,
    }];
    let plan = plan(&meshes, &view(), 100, &mut PlanBuffers::default());
    let mut order = plan.meshes[0].order.clone();
    order.sort_unstable();
    assert_eq!(order, vec![0, 1]);
    assert_eq!(plan.triangles, 2);
    // Nothing in view: nothing drawn.
    let away = View {
        eye: Vec3::ZERO,
        view_proj: Mat4::perspective_rh(0.8, 1.0, 0.1, 10_000.0)
            * Mat4::look_at_rh(Vec3::ZERO, Vec3::Y, Vec3::Z),
    };
    assert_eq!(
        super::plan(&meshes, &away, 100, &mut PlanBuffers::default()),
        Plan {
            meshes: vec![MeshPlan::default()],
            ..Plan::default()
        }
    );
}
