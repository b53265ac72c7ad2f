//! Variants shared by the tiles of a world (`pge run --variants-out DIR` writes them once,
//! `pge run --tile I,J --variants DIR` refers to them): the layers of a few variants
//! (`variants = N`) are grown by one run and written once; a tile grows none of them and
//! places its trees by the variants' names. Layers of `"unique"` trees are grown by each tile
//! as before (their trees are its own).

use pge_engine::geometry::{InstanceGroup, Model, VariantCounts};

use crate::Grown;
use crate::assemble::push_variant_meshes;
use crate::layer::Variants;
use crate::layout::Forest;

/// What a forest run does with the variants of its layers of a few variants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VariantSharing {
    /// Grow only those variants (no layout, no terrain): the run's model is
    /// [`variants_model`].
    Write,
    /// Grow none of them: their instance groups have no meshes and name the shared variant
    /// they place (`SPECIES/VARIANT`); `"unique"` layers are grown as usual.
    Refer,
}

/// Whether layer `l` of `forest` is one whose variants are shared (a few variants, not
/// `"unique"`).
#[must_use]
pub fn shared_layer(forest: &Forest, l: usize) -> bool {
    forest
        .layers
        .get(l)
        .is_some_and(|layer| matches!(layer.variants, Variants::Count(_)))
}

/// The shared variants as a model: one instance group per variant of every layer of a few
/// variants, named `SPECIES/VARIANT`, holding its meshes as a standalone tile holds them
/// (parts moved by their own transforms) and no placements. [`Model::variant_counts`] lists,
/// per group, what one instance stands for: its nodes and leaves.
#[must_use]
pub fn variants_model(forest: &Forest, grown: &[Grown]) -> Model {
    let mut model = Model::new();
    for (l, g) in grown.iter().enumerate() {
        if !shared_layer(forest, l) {
            continue;
        }
        let name = forest.layers.get(l).map_or("layer", |x| x.name.as_str());
        for (v, variant) in g.variants.iter().enumerate() {
            // As `assemble` writes a variant.
            let meshes = push_variant_meshes(&mut model, variant);
            model.groups.push(InstanceGroup {
                name: format!("{name}/{v}"),
                meshes,
                transforms: Vec::new(),
                leaves: None,
            });
            model.variant_counts.push(VariantCounts {
                nodes: variant.stats.nodes,
                leaves: variant.stats.leaves,
            });
            model
                .stats
                .warnings
                .extend(variant.stats.warnings.iter().cloned());
        }
    }
    model
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layer::Layer;
    use glam::{Mat4, Vec3};
    use pge_engine::geometry::Mesh;

    #[test]
    fn the_shared_variants_are_the_groups_a_standalone_tile_writes() {
        let mut f = Forest::new([60.0, 60.0], 5, Some(30.0)).expect("forest");
        let mut oak = Layer::new("oak", 5.0);
        oak.variants = Variants::Count(2);
        f.layers.push(oak);
        let mut rare = Layer::new("rare", 20.0);
        rare.variants = Variants::Unique;
        f.layers.push(rare);
        let tri =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let mut moved = Model::new();
        moved.add_mesh(tri.clone(), Mat4::from_translation(Vec3::Y));
        moved.stats.nodes = 7;
        // A variant with foliage levels of detail: its leaf part carries the variant's.
        let mut leaves = tri.clone();
        leaves.name = "leaves".into();
        leaves.lod = Some(std::sync::Arc::new(crate::assemble::tests::one_leaf_lod()));
        let mut leafy = Model::from_mesh(tri.clone());
        leafy.add_mesh(leaves, Mat4::IDENTITY);
        let grown = vec![
            Grown {
                variants: vec![leafy, moved],
            },
            Grown {
                variants: vec![Model::from_mesh(tri)],
            },
        ];
        let shared = variants_model(&f, &grown);
        let names: Vec<&str> = shared.groups.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(names, ["oak/0", "oak/1"]);
        assert!(shared.groups.iter().all(|g| g.transforms.is_empty()));
        assert!(shared_layer(&f, 0) && !shared_layer(&f, 1) && !shared_layer(&f, 2));
        assert_eq!(shared.variant_counts.len(), 2);
        assert_eq!(shared.variant_counts[1].nodes, 7);
        let lod = shared.meshes[shared.groups[0].meshes[1]].lod.as_deref();
        let Some(pge_engine::geometry::MeshLod::Group(group)) = lod else {
            panic!("a group's levels: {lod:?}");
        };
        assert_eq!(group.primitives()[0].primitive, 1);

        // The same meshes as the tile's own groups of those variants.
        let layout = f.layout(Some((0, 0))).expect("layout");
        let tile = crate::assemble(&f, &layout, &grown, Some((0, 0)));
        for group in &shared.groups {
            let own = tile
                .groups
                .iter()
                .find(|g| g.name == group.name)
                .expect("the tile's group");
            let meshes = |m: &Model, g: &InstanceGroup| -> Vec<Mesh> {
                g.meshes.iter().map(|&k| (*m.meshes[k]).clone()).collect()
            };
            assert_eq!(meshes(&shared, group), meshes(&tile, own));
        }
    }
}
