//! Assembly: the terrain patch and every variant's meshes, instanced by the layout.

use pge_engine::math;
use std::sync::Arc;

use glam::{Mat3, Mat4, Quat, Vec3};
use pge_engine::geometry::{
    ForestPart, ForestStats, InstanceGroup, InstanceTransform, Mesh, Model, PlacementLeaves,
    SpeciesCount,
};

use crate::layer::Variants;
use crate::layout::{Forest, Layout};

/// The grown variants of one layer (for `"unique"`, one per instance of the layout, in
/// order).
#[derive(Clone, Debug, Default)]
pub struct Grown {
    /// One model per variant.
    pub variants: Vec<Model>,
}

/// The instance transform of a tree: at its trunk, turned by its yaw, scaled.
#[must_use]
pub fn transform(position: [f32; 3], yaw: f32, scale: f32) -> InstanceTransform {
    InstanceTransform {
        translation: position,
        rotation: Quat::from_rotation_y(yaw).to_array(),
        scale,
    }
}
/// Adds a variant's parts to `model` as meshes, each baked by its transform, and returns
/// their indices. The group's mesh takes the first `lod` of its parts: the first leaf part
/// carries the variant's levels of detail (`extras.pge.lod` with `primitives`).
pub(crate) fn push_variant_meshes(model: &mut Model, variant: &Model) -> Vec<usize> {
    let mut meshes = Vec::new();
    let mut lod = crate::variant_mesh_lod(variant).map(Arc::new);
    for inst in &variant.instances {
        let mesh = &variant.meshes[inst.mesh];
        let mut mesh = if inst.transform == Mat4::IDENTITY {
            mesh.clone()
        } else {
            Arc::new(baked(mesh, &inst.transform))
        };
        if mesh.lod.is_some()
            && let Some(lod) = lod.take()
        {
            Arc::make_mut(&mut mesh).lod = Some(lod);
        }
        model.meshes.push(mesh);
        meshes.push(model.meshes.len() - 1);
    }
    meshes
}

/// A copy of `mesh` moved by `m` (for variants whose parts are not at the origin).
pub(crate) fn baked(mesh: &Mesh, m: &Mat4) -> Mesh {
    let normal = Mat3::from_mat4(*m).inverse().transpose();
    let mut out = mesh.clone();
    for p in &mut out.positions {
        *p = m.transform_point3(*p);
    }
    for n in &mut out.normals {
        *n = (normal * *n).normalize_or(Vec3::Y);
    }
    // Tangents turn with the surface; a mirror turns the bitangent's sign.
    let linear = Mat3::from_mat4(*m);
    let mirror = if linear.determinant() < 0.0 {
        -1.0
    } else {
        1.0
    };
    for t in &mut out.tangents {
        let xyz = (linear * t.truncate()).normalize_or(Vec3::X);
        *t = xyz.extend(t.w * mirror);
    }
    out
}

/// The model of a forest (or of tile `tile`): the terrain patch, then one instance group per
/// variant named `SPECIES/VARIANT`, and `extras.pge.forest`. A variant with levels of detail
/// keeps its leaves in the order of V, and its group's mesh carries the
/// [`variant_mesh_lod`](crate::variant_mesh_lod).
#[must_use]
pub fn assemble(
    forest: &Forest,
    layout: &Layout,
    grown: &[Grown],
    tile: Option<(usize, usize)>,
) -> Model {
    assemble_budgeted(forest, layout, grown, tile, None)
}

/// [`assemble`], with how many leaves each instance of `layout` draws (`leaves[k]` for
/// instance k, from [`instance_leaves`](crate::instance_leaves)): each group of a variant
/// with levels gets its placements' counts ([`PlacementLeaves`]), written in the node
/// extras.
#[must_use]
pub fn assemble_budgeted(
    forest: &Forest,
    layout: &Layout,
    grown: &[Grown],
    tile: Option<(usize, usize)>,
    leaves: Option<&[Option<u32>]>,
) -> Model {
    let never = &mut || Ok::<(), std::convert::Infallible>(());
    match assemble_checked(forest, layout, grown, tile, leaves, never) {
        Ok(model) => model,
        Err(never) => match never {},
    }
}

/// Placements assembled between two calls of [`assemble_checked`]'s `check`.
pub const CHECK_EVERY: usize = 1 << 16;

/// [`assemble_budgeted`], calling `check` (a run's deadline) before each variant's meshes
/// and every [`CHECK_EVERY`] placements: its error stops the assembly.
pub fn assemble_checked<E>(
    forest: &Forest,
    layout: &Layout,
    grown: &[Grown],
    tile: Option<(usize, usize)>,
    leaves: Option<&[Option<u32>]>,
    check: &mut dyn FnMut() -> Result<(), E>,
) -> Result<Model, E> {
    let unique: Vec<bool> = forest
        .layers
        .iter()
        .map(|l| l.variants == Variants::Unique)
        .collect();
    let mut model = build(forest, layout, grown, tile, &unique, check)?;
    if let Some(leaves) = leaves {
        check()?;
        place_leaves(&mut model, layout, grown, leaves, &unique);
    }
    Ok(model)
}

/// Gives every group of a variant with levels the leaf counts of its placements, in the
/// order [`build`] placed them.
fn place_leaves(
    model: &mut Model,
    layout: &Layout,
    grown: &[Grown],
    leaves: &[Option<u32>],
    unique: &[bool],
) {
    let mut first_group = Vec::with_capacity(grown.len());
    let mut next = 0;
    for g in grown {
        first_group.push(next);
        next += g.variants.len();
    }
    let mut rank = vec![0usize; grown.len()];
    for (inst, count) in layout.instances.iter().zip(leaves) {
        let l = inst.layer as usize;
        let Some(&first) = first_group.get(l) else {
            continue;
        };
        let v = if unique.get(l).copied().unwrap_or(false) {
            rank[l] += 1;
            rank[l] - 1
        } else {
            inst.variant as usize
        };
        let (Some(count), Some(lod)) =
            (count, grown[l].variants.get(v).and_then(crate::variant_lod))
        else {
            continue;
        };
        if let Some(group) = model.groups.get_mut(first + v) {
            group
                .leaves
                .get_or_insert_with(|| PlacementLeaves {
                    roots: lod.roots,
                    counts: Vec::new(),
                })
                .counts
                .push(*count);
        }
    }
}

/// [`assemble`], with the layers whose trees are grown one per instance (`unique[l]`): their
/// k-th instance is placed by their k-th grown tree, and the group is named after the
/// instance's variant (its identity, the same in every tile).
fn build<E>(
    forest: &Forest,
    layout: &Layout,
    grown: &[Grown],
    tile: Option<(usize, usize)>,
    unique: &[bool],
    check: &mut dyn FnMut() -> Result<(), E>,
) -> Result<Model, E> {
    let by_rank = |l: usize| unique.get(l).copied().unwrap_or(false);
    let mut model = Model::new();
    let grid = forest.terrain.grid(forest.tile);
    let (kx, kz) = forest.terrain.patch(&grid, tile);
    model.add_mesh(
        forest.terrain.mesh_checked(&grid, kx, kz, check)?,
        Mat4::IDENTITY,
    );
    let mut first_group = Vec::with_capacity(grown.len());
    for (l, g) in grown.iter().enumerate() {
        first_group.push(model.groups.len());
        let name = forest.layers.get(l).map_or("layer", |x| x.name.as_str());
        let ids: Vec<u32> = if by_rank(l) {
            layout
                .instances
                .iter()
                .filter(|i| i.layer as usize == l)
                .map(|i| i.variant)
                .collect()
        } else {
            Vec::new()
        };
        for (v, variant) in g.variants.iter().enumerate() {
            check()?;
            let meshes = push_variant_meshes(&mut model, variant);
            model.groups.push(InstanceGroup {
                name: format!("{name}/{}", ids.get(v).copied().unwrap_or(v as u32)),
                meshes,
                transforms: Vec::new(),
                leaves: None,
            });
            model
                .stats
                .warnings
                .extend(variant.stats.warnings.iter().cloned());
        }
    }
    let mut rank = vec![0usize; grown.len()];
    for (k, inst) in layout.instances.iter().enumerate() {
        if k % CHECK_EVERY == 0 {
            check()?;
        }
        let l = inst.layer as usize;
        let Some(&first) = first_group.get(l) else {
            continue;
        };
        let v = if by_rank(l) {
            rank[l] += 1;
            rank[l] - 1
        } else {
            inst.variant as usize
        };
        if let Some(group) = model.groups.get_mut(first + v) {
            group
                .transforms
                .push(transform(inst.position, inst.yaw, inst.scale));
        }
    }
    // Trees grown by instances, for the stats.
    for (l, g) in grown.iter().enumerate() {
        for (v, variant) in g.variants.iter().enumerate() {
            let n = model.groups[first_group[l] + v].transforms.len() as u64;
            model.stats.nodes += variant.stats.nodes * n;
            model.stats.leaves += variant.stats.leaves * n;
        }
    }
    model.stats.warnings.extend(layout.warnings.iter().cloned());
    let species = forest
        .layers
        .iter()
        .enumerate()
        .map(|(l, layer)| {
            let count = layout.counts.get(l).copied().unwrap_or(0) as u64;
            let variants = match layer.variants {
                Variants::Count(n) => u64::from(n),
                Variants::Unique => count,
            };
            SpeciesCount {
                name: layer.name.clone(),
                variants,
                count,
            }
        })
        .collect();
    model.forest = Some(ForestStats {
        size: forest.size,
        seed: forest.seed,
        tile: forest.tile,
        part: ForestPart::Tile(tile.map(|(i, j)| [i as u64, j as u64])),
        instances: layout.instances.len() as u64,
        species,
    });
    Ok(model)
}

/// A marker for the layout step: a slim cone 1 m wide and 6 m tall, one group per layer, so
/// the preview shows where trees will stand before they grow.
#[must_use]
pub fn layout_model(forest: &Forest, layout: &Layout, tile: Option<(usize, usize)>) -> Model {
    let sides = 6u32;
    let mut positions = vec![Vec3::new(0.0, 6.0, 0.0)];
    for k in 0..sides {
        let a = k as f32 * std::f32::consts::TAU / sides as f32;
        positions.push(Vec3::new(0.5 * math::cos(a), 0.0, 0.5 * math::sin(a)));
    }
    let mut indices = Vec::new();
    for k in 0..sides {
        indices.extend_from_slice(&[0, 1 + (k + 1) % sides, 1 + k]);
    }
    let mut grown = Vec::new();
    for layer in &forest.layers {
        let cone = match Mesh::from_triangles(positions.clone(), indices.clone()) {
            Ok(mut m) => {
                m.name = format!("{}/layout", layer.name);
                m
            }
            Err(_) => Mesh::default(),
        };
        let n = match layer.variants {
            Variants::Count(n) => n as usize,
            Variants::Unique => 1,
        };
        let marker = Model::from_mesh(cone);
        grown.push(Grown {
            variants: vec![marker; n],
        });
    }
    let mut unique = layout.clone();
    for i in &mut unique.instances {
        if forest.layers[i.layer as usize].variants == Variants::Unique {
            i.variant = 0;
        }
    }
    let never = &mut || Ok::<(), std::convert::Infallible>(());
    match build(forest, &unique, &grown, tile, &[], never) {
        Ok(model) => model,
        Err(never) => match never {},
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::layer::Layer;
    use pge_engine::geometry::{LodLevel, LodSector, LodTable, MeshLod};

    #[test]
    fn baked_tangents_turn_with_the_mesh_and_a_mirror_flips_their_sign() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO; 2],
            normals: vec![Vec3::Y; 2],
            tangents: vec![glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 2],
            ..Mesh::default()
        };
        let turn = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            Vec3::X,
        );
        let t = baked(&mesh, &turn).tangents[0];
        assert!(
            (t - glam::Vec4::new(0.0, 0.0, -1.0, 1.0))
                .abs()
                .max_element()
                < 1e-6,
            "{t}"
        );
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let t = baked(&mesh, &mirror).tangents[1];
        assert_eq!(t, glam::Vec4::new(-1.0, 0.0, 0.0, -1.0));
    }

    /// The levels of one leaf: one level, drawing it.
    pub(crate) fn one_leaf_lod() -> MeshLod {
        let level = LodLevel { a: 1, b: 1, c: 0 };
        let sector = LodSector::new(0, 1, 1, vec![level]).expect("sector");
        MeshLod::Leaves(LodTable::new(vec![sector]).expect("table"))
    }

    #[test]
    fn variants_with_levels_carry_their_table_and_their_instances_counts() {
        let mut f = Forest::new([60.0, 60.0], 5, None).expect("forest");
        let mut l = Layer::new("oak", 5.0);
        l.variants = Variants::Count(2);
        f.layers.push(l);
        let layout = f.layout(None).expect("layout");
        let tri =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let mut leaves = tri.clone();
        leaves.lod = Some(Arc::new(one_leaf_lod()));
        let mut with_lod = Model::from_mesh(tri.clone());
        with_lod.add_mesh(leaves, Mat4::IDENTITY);
        let grown = vec![Grown {
            variants: vec![with_lod, Model::from_mesh(tri)],
        }];
        // Instance k of variant 0 draws k leaves; variant 1 has no levels.
        let counts: Vec<Option<u32>> = layout
            .instances
            .iter()
            .enumerate()
            .map(|(k, i)| (i.variant == 0).then_some(k as u32))
            .collect();
        let model = assemble_budgeted(&f, &layout, &grown, None, Some(&counts));
        model.validate().expect("valid");
        let placed = model.groups[0].leaves.as_ref().expect("counts");
        assert_eq!(placed.roots, 1);
        let want: Vec<u32> = counts.iter().flatten().copied().collect();
        assert_eq!(placed.counts, want);
        assert!(model.groups[1].leaves.is_none());
        let lod = model.meshes[model.groups[0].meshes[1]].lod.as_deref();
        let Some(MeshLod::Group(group)) = lod else {
            panic!("a group's levels: {lod:?}");
        };
        assert_eq!(group.primitives()[0].primitive, 1);
        assert_eq!(Some(&group.primitives()[0].table), one_leaf_lod().table());
        // Without counts the table is there, the placements have none.
        let plain = assemble(&f, &layout, &grown, None);
        assert!(plain.groups.iter().all(|g| g.leaves.is_none()));
        assert_eq!(plain.meshes[plain.groups[0].meshes[1]].lod.as_deref(), lod);
    }

    #[test]
    fn the_assembly_checks_between_variants_and_placements_and_stops_on_an_error() {
        let mut f = Forest::new([60.0, 60.0], 5, None).expect("forest");
        let mut l = Layer::new("oak", 5.0);
        l.variants = Variants::Count(2);
        f.layers.push(l);
        let layout = f.layout(None).expect("layout");
        assert!(layout.instances.len() < CHECK_EVERY);
        let tri =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let grown = vec![Grown {
            variants: vec![Model::from_mesh(tri.clone()), Model::from_mesh(tri)],
        }];
        let mut calls = 0;
        let model = assemble_checked(&f, &layout, &grown, None, None, &mut || {
            calls += 1;
            Ok::<(), &str>(())
        })
        .expect("assembled");
        // The terrain's rows of vertices and of triangles, two variants, then the placements.
        let rows = f.terrain.grid(f.tile).last[1] + 1;
        let terrain = rows + rows - 1;
        assert_eq!(calls, terrain + 3);
        assert_eq!(model.groups.len(), 2);
        // The deadline passing at the placements stops the assembly with its error.
        let mut calls = 0;
        let stopped = assemble_checked(&f, &layout, &grown, None, None, &mut || {
            calls += 1;
            if calls == terrain + 3 {
                Err("time limit")
            } else {
                Ok(())
            }
        });
        assert_eq!(stopped.err(), Some("time limit"));
    }

    #[test]
    fn each_variant_is_a_group_placed_by_the_layout() {
        let mut f = Forest::new([60.0, 60.0], 5, None).expect("forest");
        let mut l = Layer::new("oak", 5.0);
        l.variants = Variants::Count(2);
        f.layers.push(l);
        let layout = f.layout(None).expect("layout");
        let tri =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let mut v1 = Model::new();
        v1.add_mesh(tri.clone(), Mat4::from_translation(Vec3::Y));
        let grown = vec![Grown {
            variants: vec![Model::from_mesh(tri), v1],
        }];
        let model = assemble(&f, &layout, &grown, None);
        assert_eq!(model.groups.len(), 2);
        assert_eq!(model.groups[0].name, "oak/0");
        assert_eq!(model.instance_count(), 1 + layout.instances.len());
        // The second variant's part was moved up by its own transform.
        let baked = &model.meshes[model.groups[1].meshes[0]];
        assert_eq!(baked.positions[0], Vec3::Y);
        let first = layout
            .instances
            .iter()
            .find(|i| i.variant == 0)
            .expect("one");
        let t = model.groups[0].transforms[0];
        assert_eq!(t.translation, first.position);
        let stats = model.forest.as_ref().expect("the forest");
        assert_eq!(stats.instances, layout.instances.len() as u64);
        assert_eq!(stats.species[0].name, "oak");
        assert_eq!(stats.species[0].count, layout.instances.len() as u64);
        assert_eq!(stats.part, ForestPart::Tile(None));
        model.validate().expect("valid");
        assert!(
            std::mem::size_of::<InstanceTransform>() + std::mem::size_of::<crate::Instance>() <= 64
        );
    }
}
