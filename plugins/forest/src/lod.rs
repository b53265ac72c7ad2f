//! Foliage levels of detail in a forest (seed 003, chapter 2): every variant keeps the vector
//! V and the LOD table its tree generator wrote (or gets them from the forest's own `lod`
//! option), and for a camera each instance is given how many leaves it draws, by the
//! thesis' Scaling ([`pge_lod::assign`]) over the instances of its variant.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use pge_engine::geometry::{GroupLod, LodTable, Mesh, MeshLod, Model, PrimitiveLod};
use pge_engine::{Location, RunContext};
use pge_lod::{self, Axis, Budget, LodError, LodOptions};

use crate::ForestError;
use crate::layer::Variants;
use crate::layout::{Forest, Layout};

/// A forest's `lod` option: levels for the variants and a leaf budget for one camera.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ForestLod {
    /// Levels of detail for every variant whose species did not give its leaves any (its
    /// own `lod` wins); `None` leaves the variants as grown.
    pub variants: Option<LodOptions>,
    /// The camera whose leaf budget is written per instance; `None` for no budget.
    pub camera: Option<Camera>,
}

/// A leaf budget seen from one point: each instance's distance is from `position` to its
/// trunk base (the instance's translation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the camera stands, in the forest's frame (metres).
    pub position: [f32; 3],
    /// `near`, `far` and the total `T` of leaves drawn by the whole forest.
    pub budget: Budget,
}

/// The levels of detail of one variant: its leaf primitives' original leaves |O| and
/// coarsest level |R|, summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VariantLod {
    /// Original leaves, |O|.
    pub leaves: u32,
    /// Leaves of the coarsest level, |R|.
    pub roots: u32,
}

/// The leaf meshes of a variant with a LOD table, as `(primitive, table)`: the primitive is
/// the mesh's place among the variant's parts (its instances, in order, as
/// [`assemble()`](crate::assemble()) writes them).
fn lod_parts(model: &Model) -> Vec<(usize, &LodTable)> {
    model
        .instances
        .iter()
        .enumerate()
        .filter_map(|(k, inst)| Some((k, model.meshes.get(inst.mesh)?.lod.as_deref()?.table()?)))
        .filter(|(_, table)| table.leaves() > 0)
        .collect()
}

/// The levels of a grown variant, `None` when none of its meshes has a LOD table.
#[must_use]
pub fn variant_lod(model: &Model) -> Option<VariantLod> {
    let parts = lod_parts(model);
    if parts.is_empty() {
        return None;
    }
    let sum = |count: fn(&LodTable) -> u32| {
        parts
            .iter()
            .map(|(_, table)| count(table))
            .fold(0u32, u32::saturating_add)
    };
    Some(VariantLod {
        leaves: sum(LodTable::leaves),
        roots: sum(LodTable::roots),
    })
}

/// The levels of detail of a variant's mesh in a forest: the table of each leaf primitive
/// `p` (0-based, among the mesh's primitives), written as `extras.pge.lod = {leaves = |O|,
/// roots = |R|, primitives = [{primitive = p, leaves, roots, table | sectors}, ...]}`.
/// `None` for a variant without levels.
#[must_use]
pub fn variant_mesh_lod(model: &Model) -> Option<MeshLod> {
    let primitives: Vec<PrimitiveLod> = lod_parts(model)
        .into_iter()
        .map(|(k, table)| PrimitiveLod {
            primitive: u32::try_from(k).unwrap_or(u32::MAX),
            table: table.clone(),
        })
        .collect();
    // Empty, or leaves past 32 bits in all: no levels.
    GroupLod::new(primitives).ok().map(MeshLod::Group)
}

/// Gives a grown variant the levels of detail of `options`, as its tree generator's `lod`
/// option would have: every mesh named `leaves` without a LOD table is simplified
/// ([`pge_lod::lod_mesh`]) around the vertical through the first skeleton root of the model
/// (unless `options` names an axis) and written in the order of V with its table.
/// Meshes that already have a table (the species asked for its own) are kept.
pub fn with_lod(model: &Model, options: &LodOptions) -> Result<Model, LodError> {
    let root = model
        .meshes
        .iter()
        .find_map(|m| m.skeleton.as_ref()?.positions.first().copied());
    let mut options = options.clone();
    if options.selection.axis.is_none() {
        options.selection.axis = root.map(|origin| Axis {
            origin,
            direction: Vec3::Y,
        });
    }
    let mut out = model.clone();
    for mesh in &mut out.meshes {
        if is_bare_leaves(mesh) {
            *mesh = Arc::new(pge_lod::lod_mesh(mesh, &options)?.0);
        }
    }
    Ok(out)
}

fn is_bare_leaves(mesh: &Mesh) -> bool {
    mesh.name == "leaves" && mesh.lod.is_none() && !mesh.positions.is_empty()
}

/// How many leaves every instance of `layout` draws for `camera` (`None` for an instance
/// of a variant without levels), the same in a tile as in the whole forest.
///
/// The instances of each variant (layer `l`, variant `v`, whose levels are `lods[l][v]`) are
/// budgeted together by [`pge_lod::assign`] from their distances to the camera, in the
/// order of the whole forest's layout. The total T is shared among variants in proportion
/// to their tentative leaves ([`Budget::tentative`], summed over their instances): variant
/// g gets `floor(T * D_g / D)`, so the forest never draws more than T. `tile` is the tile
/// `layout` was laid out for: the budget is then computed on the whole forest's layout and
/// each instance of the tile takes its count there. Layers of `"unique"` trees cannot be
/// budgeted (their trees are grown where they stand, so a tile does not know the others').
pub fn instance_leaves(
    forest: &Forest,
    layout: &Layout,
    tile: Option<(usize, usize)>,
    lods: &[Vec<Option<VariantLod>>],
    camera: &Camera,
) -> Result<Vec<Option<u32>>, ForestError> {
    let unlimited = RunContext::unlimited();
    instance_leaves_within(forest, layout, tile, lods, camera, &unlimited, &|_| {
        Location::new("forest", 0)
    })
}

/// [`instance_leaves`] within a run's limits: for a tile, the whole forest's layout is laid
/// out within `ctx`'s deadline and memory budget, its limits placed by `at`, as
/// [`Forest::layout_located`] places them.
pub fn instance_leaves_within(
    forest: &Forest,
    layout: &Layout,
    tile: Option<(usize, usize)>,
    lods: &[Vec<Option<VariantLod>>],
    camera: &Camera,
    ctx: &RunContext,
    at: &dyn Fn(Option<usize>) -> Location,
) -> Result<Vec<Option<u32>>, ForestError> {
    check_budget(forest, camera)?;
    if tile.is_none() {
        return Ok(budget(layout, lods, camera));
    }
    let whole = forest.layout_located(None, ctx, at)?;
    let leaves = budget(&whole, lods, camera);
    let key = |i: &crate::Instance| (i.layer, i.position[0].to_bits(), i.position[2].to_bits());
    let at: HashMap<_, usize> = whole
        .instances
        .iter()
        .enumerate()
        .map(|(k, i)| (key(i), k))
        .collect();
    Ok(layout
        .instances
        .iter()
        .map(|i| at.get(&key(i)).and_then(|&k| leaves[k]))
        .collect())
}

/// Checks that `camera`'s budget can be computed for `forest`: `near` and `far` finite,
/// non-negative and ordered, and no layer of `"unique"` trees (see [`instance_leaves`]).
pub fn check_budget(forest: &Forest, camera: &Camera) -> Result<(), ForestError> {
    camera.budget.check().map_err(|e| ForestError::Option {
        option: "lod",
        message: e.to_string(),
    })?;
    if let Some((l, layer)) = forest
        .layers
        .iter()
        .enumerate()
        .find(|(_, layer)| layer.variants == Variants::Unique)
    {
        return Err(ForestError::Option {
            option: "lod.camera",
            message: format!(
                "cannot budget layer {} ({}): its trees are \"unique\", grown where they stand, \
                 so a tile cannot know the others' leaves (give it variants = N)",
                l + 1,
                layer.name
            ),
        });
    }
    Ok(())
}

/// The budget over the instances of a whole forest's `layout` (see [`instance_leaves`]).
fn budget(layout: &Layout, lods: &[Vec<Option<VariantLod>>], camera: &Camera) -> Vec<Option<u32>> {
    let lod_of = |l: u32, v: u32| -> Option<VariantLod> { *lods.get(l as usize)?.get(v as usize)? };
    // Instances of each variant with levels, in layout order; variants in (layer, variant)
    // order.
    let mut groups: Vec<((u32, u32), Vec<usize>)> = Vec::new();
    let mut index: HashMap<(u32, u32), usize> = HashMap::new();
    for (k, i) in layout.instances.iter().enumerate() {
        if lod_of(i.layer, i.variant).is_none() {
            continue;
        }
        let g = *index.entry((i.layer, i.variant)).or_insert_with(|| {
            groups.push(((i.layer, i.variant), Vec::new()));
            groups.len() - 1
        });
        groups[g].1.push(k);
    }
    groups.sort_by_key(|(id, _)| *id);
    let eye = Vec3::from_array(camera.position);
    let b = camera.budget;
    let distances: Vec<Vec<f32>> = groups
        .iter()
        .map(|(_, members)| {
            members
                .iter()
                .map(|&k| eye.distance(Vec3::from_array(layout.instances[k].position)))
                .collect()
        })
        .collect();
    let tentative: Vec<u64> = groups
        .iter()
        .zip(&distances)
        .map(|(((l, v), _), d)| {
            let lod = lod_of(*l, *v).unwrap_or(VariantLod {
                leaves: 0,
                roots: 0,
            });
            d.iter()
                .map(|&d| u64::from(b.tentative(d, lod.leaves, lod.roots)))
                .sum()
        })
        .collect();
    let all: u128 = tentative.iter().map(|&t| u128::from(t)).sum();
    let mut out = vec![None; layout.instances.len()];
    for (((l, v), members), (d, t)) in groups.iter().zip(distances.iter().zip(&tentative)) {
        let Some(lod) = lod_of(*l, *v) else { continue };
        let share = (u128::from(b.total) * u128::from(*t))
            .checked_div(all)
            .map_or(0, |s| s as u64);
        let own = Budget { total: share, ..b };
        // The budget was checked and the distances are finite and >= 0.
        let counts = pge_lod::assign(d, lod.leaves, lod.roots, &own)
            .unwrap_or_else(|_| vec![0; members.len()]);
        for (&k, c) in members.iter().zip(counts) {
            out[k] = Some(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layer::Layer;
    use pge_engine::math;

    fn camera(total: u64) -> Camera {
        Camera {
            position: [0.0, 2.0, 0.0],
            budget: Budget {
                near: 5.0,
                far: 60.0,
                total,
            },
        }
    }

    fn forest(tile: Option<f64>) -> Forest {
        let mut f = Forest::new([120.0, 80.0], 3, tile).expect("forest");
        let mut oak = Layer::new("oak", 6.0);
        oak.variants = Variants::Count(3);
        let mut pine = Layer::new("pine", 4.0);
        pine.variants = Variants::Count(2);
        f.layers = vec![oak, pine];
        f
    }

    /// Levels of every variant but the last pine, which has no leaves.
    fn lods() -> Vec<Vec<Option<VariantLod>>> {
        let lod = |leaves, roots| Some(VariantLod { leaves, roots });
        vec![
            vec![lod(400, 30), lod(350, 20), lod(500, 41)],
            vec![lod(120, 9), None],
        ]
    }

    #[test]
    fn each_variant_is_budgeted_by_assign_within_the_total() {
        let f = forest(None);
        let layout = f.layout(None).expect("layout");
        let lods = lods();
        let total = 9000;
        let leaves = instance_leaves(&f, &layout, None, &lods, &camera(total)).expect("budget");
        let sum: u64 = leaves.iter().flatten().map(|&c| u64::from(c)).sum();
        assert!(sum <= total && sum > total / 2, "{sum}");
        let eye = Vec3::from_array(camera(total).position);
        for (inst, c) in layout.instances.iter().zip(&leaves) {
            let lod = lods[inst.layer as usize][inst.variant as usize];
            assert_eq!(c.is_some(), lod.is_some());
            if let (Some(c), Some(lod)) = (c, lod) {
                assert!(*c == 0 || (lod.roots..=lod.leaves).contains(c));
            }
        }
        // Within a variant, a nearer instance never draws fewer leaves.
        for (a, ca) in layout.instances.iter().zip(&leaves) {
            for (b, cb) in layout.instances.iter().zip(&leaves) {
                let (Some(ca), Some(cb)) = (ca, cb) else {
                    continue;
                };
                if (a.layer, a.variant) == (b.layer, b.variant)
                    && eye.distance(Vec3::from_array(a.position))
                        < eye.distance(Vec3::from_array(b.position))
                {
                    assert!(ca >= cb, "{ca} < {cb}");
                }
            }
        }
        // The counts of one variant are assign's on its distances, with its share of T.
        let members: Vec<usize> = (0..layout.instances.len())
            .filter(|&k| (layout.instances[k].layer, layout.instances[k].variant) == (0, 1))
            .collect();
        let d: Vec<f32> = members
            .iter()
            .map(|&k| eye.distance(Vec3::from_array(layout.instances[k].position)))
            .collect();
        let got: Vec<u32> = members.iter().filter_map(|&k| leaves[k]).collect();
        let b = camera(total).budget;
        let share = {
            let mut all = 0u128;
            let mut own = 0u128;
            for (k, inst) in layout.instances.iter().enumerate() {
                if let Some(lod) = lods[inst.layer as usize][inst.variant as usize] {
                    let t = u128::from(b.tentative(
                        eye.distance(Vec3::from_array(layout.instances[k].position)),
                        lod.leaves,
                        lod.roots,
                    ));
                    all += t;
                    if (inst.layer, inst.variant) == (0, 1) {
                        own += t;
                    }
                }
            }
            (u128::from(total) * own / all) as u64
        };
        let want = pge_lod::assign(&d, 350, 20, &Budget { total: share, ..b }).expect("assign");
        assert_eq!(got, want);
    }

    #[test]
    fn a_tile_gives_each_instance_its_count_in_the_whole_forest() {
        let f = forest(Some(40.0));
        let whole = f.layout(None).expect("layout");
        let lods = lods();
        let cam = camera(4000);
        let all = instance_leaves(&f, &whole, None, &lods, &cam).expect("budget");
        let mut seen = 0;
        for t in f.tiles().expect("tiles") {
            let part = f.layout(Some((t.i, t.j))).expect("tile");
            let leaves = instance_leaves(&f, &part, Some((t.i, t.j)), &lods, &cam).expect("budget");
            for (inst, c) in part.instances.iter().zip(leaves) {
                let k = whole
                    .instances
                    .iter()
                    .position(|w| w == inst)
                    .expect("in the whole forest");
                assert_eq!(c, all[k]);
                seen += 1;
            }
        }
        assert_eq!(seen, whole.instances.len());
    }

    #[test]
    fn unique_layers_and_bad_budgets_are_errors() {
        let mut f = forest(None);
        f.layers[1].variants = Variants::Unique;
        let layout = f.layout(None).expect("layout");
        let e = instance_leaves(&f, &layout, None, &lods(), &camera(10)).expect_err("unique");
        assert!(
            e.to_string().contains("cannot budget layer 2 (pine)"),
            "{e}"
        );
        let f = forest(None);
        let mut cam = camera(10);
        cam.budget.near = 100.0;
        let e = instance_leaves(&f, &layout, None, &lods(), &cam).expect_err("order");
        assert!(e.to_string().contains("near must be at most far"), "{e}");
    }

    /// A small tree with leaves, with or without its own levels of detail.
    fn tree(lod: Option<LodOptions>) -> Model {
        use pge_engine::geometry::Skeleton;
        let mut skeleton = Skeleton::new();
        let mut parent = skeleton.push(Vec3::ZERO, None, 0.0, 0);
        for k in 1..12 {
            let t = k as f32;
            let p = Vec3::new(
                math::sin(t * 1.3) * 0.1 * t,
                t * 0.4,
                math::cos(t * 0.7) * 0.1 * t,
            );
            parent = skeleton.push(p, Some(parent), 0.0, 0);
            let side = Vec3::new(math::cos(t * 2.1), 0.3, math::sin(t * 2.1));
            skeleton.push(p + side, Some(parent), 0.0, 1);
        }
        let options = pge_tree::TreeOptions {
            leaves: Some(pge_tree::LeafOptions {
                per_tip: (6, 9),
                ..pge_tree::LeafOptions::default()
            }),
            lod,
            ..pge_tree::TreeOptions::default()
        };
        pge_tree::build_tree(&skeleton, &options, 7).expect("tree")
    }

    #[test]
    fn the_forests_lod_gives_a_variant_the_levels_its_species_would_have() {
        let options = LodOptions {
            sectors: 2,
            ..LodOptions::default()
        };
        let own = tree(Some(options.clone()));
        let given = with_lod(&tree(None), &options).expect("lod");
        assert_eq!(given.meshes, own.meshes);
        let lod = variant_lod(&given).expect("levels");
        assert!(lod.roots >= 1 && lod.roots < lod.leaves, "{lod:?}");
        // A variant that has its own levels keeps them.
        let kept = with_lod(
            &own,
            &LodOptions {
                sectors: 5,
                ..LodOptions::default()
            },
        )
        .expect("kept");
        assert_eq!(kept.meshes, own.meshes);
        // The table of each primitive keeps the invariant a + c = |R| + i, inside V.
        let Some(MeshLod::Group(group)) = variant_mesh_lod(&given) else {
            panic!("a group's levels");
        };
        for p in group.primitives() {
            assert_eq!(p.table.sectors().len(), 2);
            for s in p.table.sectors() {
                let (roots, leaves) = (s.roots(), s.leaves());
                for (i, row) in s.levels().iter().enumerate() {
                    assert_eq!(row.a + row.c, roots + i as u32);
                    assert!(row.a <= row.b && u64::from(row.b + row.c) <= s.len());
                    assert!(row.a <= leaves);
                }
            }
        }
    }

    #[test]
    fn a_variants_levels_list_its_leaf_primitives() {
        use pge_engine::geometry::{LodLevel, LodSector};
        let tri =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let mut leaves = tri.clone();
        // Ten leaves, three roots: a table of eight levels.
        let levels = (0..8)
            .map(|i| LodLevel {
                a: 3 + i,
                b: 17,
                c: 0,
            })
            .collect();
        let sector = LodSector::new(0, 10, 3, levels).expect("sector");
        let table = LodTable::new(vec![sector]).expect("table");
        leaves.lod = Some(Arc::new(MeshLod::Leaves(table.clone())));
        let mut model = Model::from_mesh(tri);
        assert_eq!(variant_lod(&model), None);
        assert_eq!(variant_mesh_lod(&model), None);
        model.add_mesh(leaves, glam::Mat4::IDENTITY);
        assert_eq!(
            variant_lod(&model),
            Some(VariantLod {
                leaves: 10,
                roots: 3
            })
        );
        let group = GroupLod::new(vec![PrimitiveLod {
            primitive: 1,
            table,
        }])
        .expect("group");
        assert_eq!(variant_mesh_lod(&model), Some(MeshLod::Group(group)));
    }
}
