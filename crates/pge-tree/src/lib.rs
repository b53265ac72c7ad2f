//! PGE trees: every tree generator's branch [`Skeleton`] becomes a model here.
//!
//! Space colonization, the turtle and the growth model all produce a skeleton (positions,
//! parents, radii, orders, leaf points); this crate turns it into a [`Model`] with
//! - one bark mesh of generalized cylinders (Bloomenthal) with normals, UVs and a bark texture,
//!   carrying the processed skeleton for the glTF extras;
//! - one leaf mesh of alpha-masked, double-sided quads with a colour per leaf.
//!
//! On the way the skeleton gets pipe-model radii (`r^n = r1^n + r2^n` from a tip radius, or
//! the generator's own radii), optional smoothing and merging of straight chains. Textures
//! are procedural (noise, a leaf silhouette) unless a PNG is given. All of it is plain Rust;
//! the options are read from a script's table by the Lua adapter ([`lua::tree_options`]).
//!
//! ```
//! use glam::Vec3;
//! use pge_engine::geometry::Skeleton;
//! use pge_tree::{LeafOptions, TreeOptions, build_tree};
//!
//! let mut skeleton = Skeleton::new();
//! let root = skeleton.push(Vec3::ZERO, None, 0.0, 0);
//! let fork = skeleton.push(Vec3::Y, Some(root), 0.0, 0);
//! skeleton.push(Vec3::new(-0.5, 2.0, 0.0), Some(fork), 0.0, 1);
//! skeleton.push(Vec3::new(0.5, 2.0, 0.0), Some(fork), 0.0, 1);
//!
//! let options = TreeOptions { leaves: Some(LeafOptions::default()), ..TreeOptions::default() };
//! let model = build_tree(&skeleton, &options, 1).unwrap();
//! assert_eq!(model.meshes.len(), 2); // bark and leaves
//! assert_eq!(model.stats.nodes, 4);
//! model.validate().unwrap();
//! ```

mod cylinders;
mod leaves;
#[cfg(feature = "lua")]
pub mod lua;
mod material;
mod memory;
mod merge;
mod options;
mod radii;
mod smooth;
#[cfg(test)]
mod tangent_tests;
mod textures;
#[cfg(feature = "lua")]
mod tree_lua;

use pge_engine::clock::Instant;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Mat4, Vec3};
use pge_engine::geometry::{GeometryError, Mesh, Model, Skeleton};
use rand_mt::Mt64;

pub use cylinders::{append_bark, bark_mesh};
pub use leaves::{append_leaf_quads, strahler_orders, tip_leaves};
pub use material::{bark_material, leaf_material, leaf_material_with_warning, leaf_transmission};
pub use memory::{MeshMemory, MeshSizes};
pub use merge::merge_straight;
pub use options::{
    Along, Flare, LeafOptions, MAX_PER_CARD, MeshOptions, RadiiMode, TextureSource, TreeOptions,
};
pub use radii::{assign_orders, main_children, pipe_radii};
pub use smooth::smooth;
pub use textures::{
    BarkParams, BarkStyle, LeafParams, LeafShape, Maps, TextureCache, TextureFormat, TextureSet,
    bark_maps, bark_set, bark_textures, card_share, encode_maps, encode_maps_as, leaf_maps,
    leaf_set, leaf_textures, load_png,
};
#[cfg(feature = "lua")]
pub use tree_lua::TreePlugin;

/// Why a tree could not be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TreeError {
    /// The skeleton breaks an invariant (a generator bug or bad host data).
    #[error("invalid skeleton: {0}")]
    Skeleton(String),
    /// A texture file could not be read or decoded.
    #[error("texture {}: {message}", path.display())]
    Texture {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A procedural texture could not be made (an encoder failure).
    #[error("texture: {0}")]
    Generated(String),
    /// A mesh or texture broke an invariant.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The leaf mesh could not be given levels of detail.
    #[error("lod: {0}")]
    Lod(#[from] pge_lod::LodError),
}

impl TreeError {
    /// The engine's error for this one, at `at`: a limit of the run (the time ran out while
    /// the leaves were given levels of detail) as the typed limit it is, anything else a
    /// script error whose message is `what: ` and this error.
    #[must_use]
    pub fn into_engine(self, at: pge_engine::Location, what: &str) -> pge_engine::Error {
        match self {
            TreeError::Lod(pge_lod::LodError::Limit(e)) => *e,
            other => pge_engine::Error::script(at, format!("{what}{other}")),
        }
    }
}

/// Checks that a skeleton is usable: equal array lengths, parents before children, finite
/// positions and non-negative finite radii, leaf points on existing nodes.
pub fn check_skeleton(skeleton: &Skeleton) -> Result<(), TreeError> {
    let n = skeleton.positions.len();
    let bad = |m: String| Err(TreeError::Skeleton(m));
    if skeleton.parents.len() != n || skeleton.radii.len() != n || skeleton.orders.len() != n {
        return bad(format!(
            "{n} positions but {} parents, {} radii and {} orders",
            skeleton.parents.len(),
            skeleton.radii.len(),
            skeleton.orders.len()
        ));
    }
    for i in 0..n {
        if let Some(p) = skeleton.parents[i]
            && p as usize >= i
        {
            return bad(format!(
                "node {i} has parent {p}, which does not precede it"
            ));
        }
        if !skeleton.positions[i].is_finite() {
            return bad(format!("node {i} has a non-finite position"));
        }
        let r = skeleton.radii[i];
        if !(r.is_finite() && r >= 0.0) {
            return bad(format!("node {i} has radius {r}"));
        }
    }
    for (k, leaf) in skeleton.leaves.iter().enumerate() {
        if leaf.node as usize >= n {
            return bad(format!("leaf {k} hangs on node {} of {n}", leaf.node));
        }
        if !(leaf.position.is_finite() && leaf.direction.is_finite() && leaf.side.is_finite()) {
            return bad(format!("leaf {k} has a non-finite position or direction"));
        }
    }
    Ok(())
}

/// The skeleton the bark is built on: checked, radii by the options' mode (pipe model from
/// `tip_radius` with `exponent`, or kept), then smoothed, then straight chains merged.
pub fn prepare_skeleton(skeleton: &Skeleton, options: &MeshOptions) -> Result<Skeleton, TreeError> {
    check_skeleton(skeleton)?;
    if options.radii == RadiiMode::Keep
        && let Some(angle) = options.merge_straight
    {
        // The radii are the skeleton's: no copy to change them in.
        return Ok(merge::smooth_and_merge(skeleton, options.smoothing, angle));
    }
    let mut s = skeleton.clone();
    if options.radii == RadiiMode::Pipe {
        pipe_radii(&mut s, options.tip_radius, options.exponent);
    }
    smooth(&mut s, options.smoothing);
    if let Some(angle) = options.merge_straight {
        s = merge_straight(&s, angle);
    }
    Ok(s)
}

/// The bark mesh alone: [`prepare_skeleton`], then generalized cylinders with the bark
/// material (procedural or file texture). The mesh carries the prepared skeleton.
pub fn mesh_skeleton(skeleton: &Skeleton, options: &MeshOptions) -> Result<Mesh, TreeError> {
    let prepared = prepare_skeleton(skeleton, options)?;
    bark_of(Arc::new(prepared), options)
}

fn bark_of(skeleton: Arc<Skeleton>, options: &MeshOptions) -> Result<Mesh, TreeError> {
    let mut mesh = bark_mesh(&skeleton, options);
    mesh.material = bark_material(options)?;
    mesh.skeleton = Some(skeleton);
    Ok(mesh)
}

/// Builds the whole tree: bark (see [`mesh_skeleton`]) and leaves, as a model with the bark
/// mesh first and the leaf mesh (if any leaf) second, both at the origin.
///
/// Leaves are the skeleton's own leaf points plus, when `options.leaves` is set, tip leaves
/// ([`tip_leaves`]) drawn from an MT19937-64 seeded with `seed`: the same skeleton, options
/// and seed give the same model. With `options.lod`, the leaf mesh is simplified and
/// written in the order of the vector V with its LOD table (see [`pge_lod::lod_mesh`]); a
/// tree without leaves then gets a warning instead. The bark mesh's skeleton holds every
/// leaf point. Stats:
/// `nodes` (after merging), `leaves`, and the phases `radii`, `meshing`, `leaves` and
/// `textures` (generating and PNG-encoding the procedural maps, or reading them from the
/// process's [`TextureCache`]).
pub fn build_tree(
    skeleton: &Skeleton,
    options: &TreeOptions,
    seed: u64,
) -> Result<Model, TreeError> {
    build_tree_in(skeleton, options, seed, &MeshMemory::none())
}

/// [`build_tree`] with its meshes written into `memory` (made resident ahead, see
/// [`MeshMemory`]) as far as it is ready: the same model, to the byte.
pub fn build_tree_in(
    skeleton: &Skeleton,
    options: &TreeOptions,
    seed: u64,
    memory: &MeshMemory,
) -> Result<Model, TreeError> {
    let mut model = Model::new();
    let t = Instant::now();
    let mut prepared = prepare_skeleton(skeleton, &options.mesh)?;
    model.stats.add_phase("radii", t.elapsed().as_secs_f64());

    let has_bark = prepared.parents.iter().any(Option::is_some);
    let default_style = LeafOptions::default();
    let style = options.leaves.as_ref().unwrap_or(&default_style);
    // The bark draws nothing from the generator and the leaves read nothing of the bark, so
    // a small tree's are made side by side (a big tree's each use the whole pool already);
    // each phase counts its own time.
    let small = prepared.len() * (options.mesh.sides as usize + 1) < SIDE_BY_SIDE_BELOW;
    // Taken as late as can be: the job making it may still be at work.
    let memory::Buffers {
        bark: bark_memory,
        leaves: leaf_memory,
    } = memory.take();
    // Each mesh comes with whether it has no unusable triangle (the search, or the bark's
    // construction, showed it): the model's clean-up then skips it.
    let ((bark, meshing_time), (leaves, mut leaves_time)) = beside(
        small,
        || {
            // At least one segment, so the bark mesh has triangles.
            has_bark.then(|| cylinders::clean_bark_mesh(&prepared, &options.mesh, bark_memory))
        },
        || {
            let mut rng = Mt64::new(seed);
            let memory::LeafBuffers {
                tips,
                search,
                positions,
                normals,
                uvs,
                colors,
                indices,
            } = leaf_memory;
            let tips = match &options.leaves {
                Some(leaf_options) => {
                    leaves::tip_leaves_into(&prepared, leaf_options, &mut rng, tips)
                }
                None => Vec::new(),
            };
            // The skeleton's own leaves first, then the tip leaves (not copied when alone).
            let points = if prepared.leaves.is_empty() {
                tips
            } else {
                [prepared.leaves.as_slice(), &tips].concat()
            };
            let mesh = (!points.is_empty()).then(|| {
                let mut mesh = Mesh {
                    name: "leaves".into(),
                    positions,
                    normals,
                    uvs,
                    colors,
                    indices,
                    ..Mesh::default()
                };
                append_leaf_quads(&points, style, &mut rng, &mut mesh);
                // A small tree's leaf mesh is searched here, beside the bark; a big tree's
                // by the model's clean-up, after the textures. With levels of detail the
                // mesh is replaced, and never cleaned up.
                let clean =
                    small && options.lod.is_none() && mesh.unusable_triangles_in(search).is_empty();
                (mesh, clean)
            });
            (points, mesh)
        },
    );
    model.stats.add_phase("meshing", meshing_time);
    let (points, leaf_mesh) = leaves;
    prepared.leaves = points;
    let prepared = Arc::new(prepared);

    let t = Instant::now();
    // Side by side: the cache generates each set on texture threads of its own, so a pool
    // thread waiting for a set runs no other job meanwhile.
    let (bark_material, leaf_material) = rayon::join(
        || {
            bark.is_some()
                .then(|| bark_material(&options.mesh))
                .transpose()
        },
        || {
            leaf_mesh
                .is_some()
                .then(|| leaf_material_with_warning(style))
                .transpose()
        },
    );
    let textures_time = t.elapsed().as_secs_f64();
    if let (Some((mut mesh, clean)), Some(material)) = (bark, bark_material?) {
        mesh.material = material;
        mesh.skeleton = Some(prepared.clone());
        add_mesh(&mut model, mesh, clean);
    }

    let t = Instant::now();
    if let (Some((mut mesh, clean)), Some((material, warning))) = (leaf_mesh, leaf_material?) {
        model.stats.warnings.extend(warning);
        mesh.material = material;
        if let Some(lod) = &options.lod {
            mesh = lod_leaves(&mesh, lod, &prepared)?;
        }
        add_mesh(&mut model, mesh, clean);
    } else if let Some(lod) = &options.lod {
        let at = if lod.source.is_empty() {
            String::new()
        } else {
            format!("{}: ", lod.source)
        };
        model.stats.warnings.push(format!(
            "{at}warning: lod: the tree has no leaves, so it has no LOD table (give it leaves = {{...}})"
        ));
    }
    leaves_time += t.elapsed().as_secs_f64();
    model.stats.add_phase("leaves", leaves_time);
    model.stats.add_phase("textures", textures_time);
    model.stats.nodes = prepared.len() as u64;
    model.stats.leaves = prepared.leaves.len() as u64;
    Ok(model)
}

/// Adds `mesh` at the origin, listed as clean (see [`Model::clean`]) when it has no unusable
/// triangle.
fn add_mesh(model: &mut Model, mesh: Mesh, clean: bool) {
    let mesh = Arc::new(mesh);
    if clean {
        model.clean.push(mesh.clone());
    }
    model.add_mesh(mesh, Mat4::IDENTITY);
}

/// Nodes times sides plus one (about half the bark's vertices) below which a tree's bark and
/// leaves are made side by side: above it, the bark's tubes and the leaves each use the pool
/// (from 64 k vertices and 16 k leaves), and making them one after the other costs nothing.
const SIDE_BY_SIDE_BELOW: usize = 1 << 16;

/// `a` on the calling thread beside `b` on the rayon pool when `together` and the pool has
/// more than one thread (one after the other otherwise), each with the seconds it took.
fn beside<A, B: Send>(
    together: bool,
    a: impl FnOnce() -> A,
    b: impl FnOnce() -> B + Send,
) -> ((A, f64), (B, f64)) {
    fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
        let t = Instant::now();
        let out = f();
        (out, t.elapsed().as_secs_f64())
    }
    if !together || rayon::current_num_threads() == 1 {
        return (timed(a), timed(b));
    }
    let mut b_out = None;
    let a_out = rayon::in_place_scope(|scope| {
        scope.spawn(|_| b_out = Some(timed(b)));
        timed(a)
    });
    // The scope returns when every task it spawned has run.
    (a_out, b_out.expect("b ran in the scope"))
}

/// The leaf mesh with levels of detail ([`pge_lod::lod_mesh`]): simplified around the
/// vertical through the skeleton's first root unless the options name another axis, written
/// in the order of the vector V, with `extras.pge.lod`.
fn lod_leaves(
    mesh: &Mesh,
    options: &pge_lod::LodOptions,
    skeleton: &Skeleton,
) -> Result<Mesh, TreeError> {
    let mut options = options.clone();
    if options.selection.axis.is_none() {
        options.selection.axis = skeleton.positions.first().map(|&origin| pge_lod::Axis {
            origin,
            direction: Vec3::Y,
        });
    }
    Ok(pge_lod::lod_mesh(mesh, &options)?.0)
}

/// The centre of a skeleton's bounding box, or the origin when empty (handy for envelopes
/// and cameras).
#[must_use]
pub fn skeleton_centre(skeleton: &Skeleton) -> Vec3 {
    let Some(first) = skeleton.positions.first() else {
        return Vec3::ZERO;
    };
    let (lo, hi) = skeleton
        .positions
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    (lo + hi) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::geometry::{AlphaMode, Material};

    fn hex_rgb(s: &str) -> [f32; 3] {
        let [r, g, b, _] = Material::from_hex("", s).expect("colour").base_color;
        [r, g, b]
    }

    fn y_tree() -> Skeleton {
        let mut s = Skeleton::new();
        let r = s.push(Vec3::ZERO, None, 0.0, 0);
        let a = s.push(Vec3::Y, Some(r), 0.0, 0);
        let b = s.push(Vec3::new(0.0, 2.0, 0.0), Some(a), 0.0, 0);
        s.push(Vec3::new(-0.5, 2.5, 0.0), Some(b), 0.0, 1);
        s.push(Vec3::new(0.5, 2.5, 0.2), Some(b), 0.0, 1);
        s
    }

    #[test]
    fn a_tree_has_bark_and_leaves_and_is_deterministic() {
        let options = TreeOptions {
            leaves: Some(LeafOptions::default()),
            ..TreeOptions::default()
        };
        let a = build_tree(&y_tree(), &options, 7).expect("builds");
        let b = build_tree(&y_tree(), &options, 7).expect("builds");
        let c = build_tree(&y_tree(), &options, 8).expect("builds");
        a.validate().expect("valid");
        assert_eq!(a.meshes.len(), 2);
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(a.meshes[1].positions, b.meshes[1].positions);
        assert_eq!(a.meshes[1].colors, b.meshes[1].colors);
        assert_ne!(a.meshes[1].positions, c.meshes[1].positions);
        let bark = &a.meshes[0];
        let skeleton = bark.skeleton.as_ref().expect("skeleton attached");
        assert_eq!(skeleton.len(), 5);
        assert_eq!(skeleton.leaves.len() as u64, a.stats.leaves);
        assert!(a.stats.leaves >= 6);
        assert!(bark.material.texture.is_some());
        let leaves = &a.meshes[1];
        // The default card's cutoff is chosen with its texture: its mean alpha above it.
        let AlphaMode::Mask(cutoff) = leaves.material.alpha else {
            panic!("masked leaves")
        };
        let texture = leaves.material.texture.as_ref().expect("leaf texture");
        let rgba = image::load_from_memory(&texture.encoded)
            .expect("png")
            .to_rgba8();
        let mean = pge_lod::mask::mean_alpha(&pge_lod::mask::alpha_of(rgba.as_raw()));
        assert!(mean >= cutoff + pge_lod::mask::MARGIN, "{mean} vs {cutoff}");
        assert!(leaves.material.double_sided);
        let through = leaves.material.transmission.expect("translucent leaves");
        assert_eq!(through.factor, 0.3);
        assert_eq!(through.color, hex_rgb("#c8dc64"));
        assert!(bark.material.transmission.is_none(), "bark is opaque");
        let opaque = LeafOptions {
            translucency: 0.0,
            ..LeafOptions::default()
        };
        assert_eq!(leaf_transmission(&opaque), None);
        assert_eq!(leaves.positions.len() as u64, 4 * a.stats.leaves);
        let phases: Vec<&str> = a.stats.phases.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(phases, ["radii", "meshing", "leaves", "textures"]);
    }

    #[test]
    fn a_tree_built_in_memory_made_ahead_is_the_same() {
        let mut s = y_tree();
        // A longer trunk, so the bark has several tubes and rings.
        for k in 0..40 {
            let parent = s.len() as u32 - 1;
            let y = 2.5 + 0.3 * k as f32;
            s.push(
                Vec3::new(0.1 * (k % 3) as f32, y, 0.0),
                Some(parent),
                0.0,
                1,
            );
        }
        let options = TreeOptions {
            leaves: Some(LeafOptions::default()),
            ..TreeOptions::default()
        };
        let fresh = build_tree(&s, &options, 5).expect("builds");
        // Room for all of it, for part of it (the arrays grow), for none.
        for nodes in [400, 10, 0] {
            let memory = MeshMemory::made_now(MeshSizes::of_nodes(nodes, &options));
            let ahead = build_tree_in(&s, &options, 5, &memory).expect("builds");
            for (a, b) in ahead.meshes.iter().zip(&fresh.meshes) {
                assert_eq!(a.positions, b.positions, "{nodes}");
                assert_eq!(a.normals, b.normals, "{nodes}");
                assert_eq!(a.uvs, b.uvs, "{nodes}");
                assert_eq!(a.colors, b.colors, "{nodes}");
                assert_eq!(a.indices, b.indices, "{nodes}");
            }
            assert_eq!(ahead.meshes.len(), fresh.meshes.len());
            assert_eq!(ahead.clean.len(), fresh.clean.len());
            let leaves = |m: &Model| m.meshes[0].skeleton.as_ref().map(|k| k.leaves.clone());
            assert_eq!(leaves(&ahead), leaves(&fresh));
        }
        let memory = MeshMemory::made_now(MeshSizes::of_nodes(400, &options));
        let bark = &build_tree_in(&s, &options, 5, &memory)
            .expect("builds")
            .meshes[0];
        assert!(bark.positions.capacity() >= MeshSizes::of_nodes(400, &options).bark_vertices);
    }

    #[test]
    fn kept_radii_are_not_replaced() {
        let mut s = y_tree();
        s.radii = vec![0.3, 0.3, 0.2, 0.1, 0.05];
        let keep = MeshOptions {
            radii: RadiiMode::Keep,
            ..MeshOptions::default()
        };
        assert_eq!(prepare_skeleton(&s, &keep).expect("ok").radii, s.radii);
        let pipe = prepare_skeleton(&s, &MeshOptions::default()).expect("ok");
        assert_eq!(pipe.radii[3], 0.02);
    }

    #[test]
    fn bad_skeletons_and_textures_are_errors() {
        let mut s = y_tree();
        s.positions[2].x = f32::NAN;
        assert!(matches!(
            build_tree(&s, &TreeOptions::default(), 1),
            Err(TreeError::Skeleton(_))
        ));
        let mut s = y_tree();
        s.parents[1] = Some(3);
        let e = build_tree(&s, &TreeOptions::default(), 1).expect_err("bad parent");
        assert_eq!(
            e.to_string(),
            "invalid skeleton: node 1 has parent 3, which does not precede it"
        );
        let options = TreeOptions {
            mesh: MeshOptions {
                texture: TextureSource::File("/no/such/bark.png".into()),
                ..MeshOptions::default()
            },
            leaves: None,
            lod: None,
        };
        let e = build_tree(&y_tree(), &options, 1).expect_err("missing file");
        assert!(
            e.to_string().starts_with("texture /no/such/bark.png:"),
            "{e}"
        );
    }

    #[test]
    fn lod_writes_the_leaves_in_the_order_of_v_with_the_table() {
        let options = TreeOptions {
            leaves: Some(LeafOptions {
                per_tip: (40, 40),
                ..LeafOptions::default()
            }),
            lod: Some(pge_lod::LodOptions::default()),
            ..TreeOptions::default()
        };
        let plain = TreeOptions {
            lod: None,
            ..options.clone()
        };
        let m = build_tree(&y_tree(), &options, 3).expect("builds");
        m.validate().expect("valid");
        let without = build_tree(&y_tree(), &plain, 3).expect("builds");
        assert_eq!(m.stats.leaves, without.stats.leaves);
        let leaves = &m.meshes[1];
        let lod = leaves
            .lod
            .as_deref()
            .and_then(pge_engine::geometry::MeshLod::table)
            .expect("a table");
        let (originals, roots) = (u64::from(lod.leaves()), u64::from(lod.roots()));
        assert_eq!(originals, m.stats.leaves);
        assert!(roots < originals, "{roots} roots of {originals}");
        // |M| = |O| + collapses = 2|O| - |R| quads; the indices draw the finest level only,
        // with the plain tree's triangle count.
        assert_eq!(leaves.positions.len() as u64, 4 * (2 * originals - roots));
        assert_eq!(leaves.indices.len() as u64, 6 * originals);
        assert_eq!(leaves.indices.len(), without.meshes[1].indices.len());
        let rows = lod.sectors()[0].levels();
        assert_eq!(rows.len() as u64, originals - roots + 1);
        assert_eq!(u64::from(rows.last().expect("finest").a), originals);
        // Deterministic, bytes included.
        let again = build_tree(&y_tree(), &options, 3).expect("builds");
        assert_eq!(again.meshes[1].positions, leaves.positions);
    }

    #[test]
    fn lod_on_a_tree_without_leaves_is_a_warning() {
        let options = TreeOptions {
            lod: Some(pge_lod::LodOptions {
                source: "oak.lua:3".into(),
                ..pge_lod::LodOptions::default()
            }),
            ..TreeOptions::default()
        };
        let m = build_tree(&y_tree(), &options, 1).expect("builds");
        assert_eq!(m.meshes.len(), 1);
        assert_eq!(m.stats.warnings.len(), 1);
        assert!(
            m.stats.warnings[0].starts_with("oak.lua:3: warning: lod: the tree has no leaves"),
            "{:?}",
            m.stats.warnings
        );
    }

    #[test]
    fn empty_and_single_node_skeletons_give_empty_models() {
        let m = build_tree(&Skeleton::new(), &TreeOptions::default(), 1).expect("ok");
        assert_eq!(m.meshes.len(), 0);
        let mut s = Skeleton::new();
        s.push(Vec3::ZERO, None, 0.1, 0);
        let m = build_tree(&s, &TreeOptions::default(), 1).expect("ok");
        assert_eq!(m.meshes.len(), 0);
        // Two roots and no segment: still nothing to mesh.
        s.push(Vec3::X, None, 0.1, 0);
        let m = build_tree(&s, &TreeOptions::default(), 1).expect("ok");
        assert_eq!(m.meshes.len(), 0);
        assert_eq!(skeleton_centre(&y_tree()), Vec3::new(0.0, 1.25, 0.1));
    }
}
