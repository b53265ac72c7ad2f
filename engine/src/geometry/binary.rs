//! The binary form of a [`Model`]: exact (floats as their bits), compact ([postcard]), and
//! written from the geometry types' serde derives, so a field added to any of them is
//! written by construction. A forest's variant cache keeps grown variants in it.
//!
//! Decoding reads untrusted bytes: it never panics, and refuses with a typed
//! [`BinaryError`] anything that is not a model (truncated or damaged bytes, trailing bytes,
//! LOD tables that break their invariants, instances, groups and skeletons that point past
//! their arrays). What is left out: the timings of the run ([`Stats::phases`]) and the
//! list of meshes known clean ([`Model::clean`]). Meshes, materials, textures and
//! skeletons that were shared (one `Arc`) are shared again.
//!
//! ```
//! use pge_engine::geometry::{Mesh, Model, binary};
//! use glam::Vec3;
//!
//! let mesh = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).unwrap();
//! let model = Model::from_mesh(mesh);
//! let bytes = binary::encode(&model).unwrap();
//! let back = binary::decode(&bytes).unwrap();
//! assert_eq!(back.meshes, model.meshes);
//! assert!(binary::decode(&bytes[..bytes.len() - 1]).is_err());
//! ```

use std::sync::Arc;

use super::{GeometryError, Material, Mesh, Model, Skeleton, Texture};

/// Why bytes are not a model's binary form (or a model could not be written).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BinaryError {
    /// The bytes do not decode (truncated, damaged, or a value out of its range, such as a
    /// LOD table that breaks its invariants); or the model could not be encoded.
    #[error("not a model's binary form: {0}")]
    Format(#[from] postcard::Error),
    /// The model ends before the bytes do.
    #[error("{0} bytes after the model")]
    Trailing(usize),
    /// An instance or a group places a mesh the model does not have, or a group's leaf
    /// counts are not one per placement.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// A skeleton's arrays differ in length, or a node's parent does not precede it, or a
    /// leaf hangs from no node.
    #[error("skeleton: node {node} breaks the skeleton's invariants")]
    Skeleton {
        /// The first node (or leaf point) found wrong.
        node: usize,
    },
}

/// The model's binary form.
pub fn encode(model: &Model) -> Result<Vec<u8>, BinaryError> {
    Ok(postcard::to_stdvec(model)?)
}

/// The model of [`encode`]'s bytes: the same model, bit for bit, with its sharing.
pub fn decode(bytes: &[u8]) -> Result<Model, BinaryError> {
    let (mut model, rest): (Model, &[u8]) = postcard::take_from_bytes(bytes)?;
    if !rest.is_empty() {
        return Err(BinaryError::Trailing(rest.len()));
    }
    for mesh in &model.meshes {
        if let Some(s) = &mesh.skeleton {
            check_skeleton(s)?;
        }
    }
    check_placements(&model)?;
    share(&mut model);
    Ok(model)
}

/// Checks what code reading a model relies on to index it: every instance and group on
/// meshes of the model, a leaf count per placement. (Meshes are not validated: a model is
/// read back as it was written; the exporters validate what they write.)
fn check_placements(model: &Model) -> Result<(), GeometryError> {
    let meshes = model.meshes.len();
    let out_of_range = |at: usize, index: usize| GeometryError::IndexOutOfRange {
        index: u32::try_from(index).unwrap_or(u32::MAX),
        at,
        vertices: meshes,
    };
    if let Some((at, i)) = model
        .instances
        .iter()
        .enumerate()
        .find(|(_, i)| i.mesh >= meshes)
    {
        return Err(out_of_range(at, i.mesh));
    }
    for group in &model.groups {
        if let Some((at, &m)) = group.meshes.iter().enumerate().find(|(_, m)| **m >= meshes) {
            return Err(out_of_range(at, m));
        }
        if let Some(leaves) = &group.leaves
            && leaves.counts.len() != group.transforms.len()
        {
            return Err(GeometryError::AttributeLength {
                attribute: "group leaf counts",
                got: leaves.counts.len(),
                vertices: group.transforms.len(),
            });
        }
    }
    Ok(())
}

/// Checks what code reading a skeleton relies on: one entry per node in every array, each
/// parent before its node, each leaf point on a node.
fn check_skeleton(s: &Skeleton) -> Result<(), BinaryError> {
    let n = s.positions.len();
    if let Some(node) = [s.parents.len(), s.radii.len(), s.orders.len()]
        .into_iter()
        .find(|&len| len != n)
    {
        return Err(BinaryError::Skeleton { node: node.min(n) });
    }
    if let Some(node) = (0..n).find(|&i| s.parents[i].is_some_and(|p| p as usize >= i)) {
        return Err(BinaryError::Skeleton { node });
    }
    if let Some(k) = s.leaves.iter().position(|l| l.node as usize >= n) {
        return Err(BinaryError::Skeleton { node: k });
    }
    Ok(())
}

/// One `Arc` for equal values, as they were before encoding: the textures of materials and
/// the environment, the materials and skeletons of meshes. (Values equal yet not shared
/// before become shared: no reader of a model tells them apart.)
fn share(model: &mut Model) {
    fn one<T: PartialEq>(seen: &mut Vec<Arc<T>>, item: &mut Arc<T>) {
        match seen.iter().find(|s| **s == *item) {
            Some(s) => *item = s.clone(),
            None => seen.push(item.clone()),
        }
    }
    let (mut textures, mut materials, mut skeletons) = (Vec::new(), Vec::new(), Vec::new());
    for mesh in &mut model.meshes {
        // Freshly decoded: every Arc is the only one, so `make_mut` does not copy.
        let mesh: &mut Mesh = Arc::make_mut(mesh);
        let material: &mut Material = Arc::make_mut(&mut mesh.material);
        for texture in [
            &mut material.texture,
            &mut material.normal_texture,
            &mut material.metallic_roughness_texture,
        ]
        .into_iter()
        .flatten()
        {
            one::<Texture>(&mut textures, texture);
        }
        one(&mut materials, &mut mesh.material);
        if let Some(s) = &mut mesh.skeleton {
            one(&mut skeletons, s);
        }
    }
    if let Some(t) = &mut model.environment {
        one(&mut textures, t);
    }
}

/// A shared value (`Arc<T>`) as the value.
pub(super) mod shared {
    use std::sync::Arc;

    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes the value.
    pub(in crate::geometry) fn serialize<T: Serialize, S: Serializer>(
        value: &Arc<T>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        (**value).serialize(s)
    }

    /// Reads it back, in an `Arc` of its own.
    pub(in crate::geometry) fn deserialize<'de, T: Deserialize<'de>, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Arc<T>, D::Error> {
        T::deserialize(d).map(Arc::new)
    }
}

/// An optional shared value (`Option<Arc<T>>`) as the optional value.
pub(super) mod shared_option {
    use std::sync::Arc;

    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes the value, if any.
    pub(in crate::geometry) fn serialize<T: Serialize, S: Serializer>(
        value: &Option<Arc<T>>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        value.as_deref().serialize(s)
    }

    /// Reads it back, in an `Arc` of its own.
    pub(in crate::geometry) fn deserialize<'de, T: Deserialize<'de>, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Arc<T>>, D::Error> {
        Option::<T>::deserialize(d).map(|v| v.map(Arc::new))
    }
}

/// Shared values (`Vec<Arc<T>>`) as a sequence of the values.
pub(super) mod shared_vec {
    use std::sync::Arc;

    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes the values.
    #[allow(clippy::ptr_arg)] // `with` hands the field as it is.
    pub(in crate::geometry) fn serialize<T: Serialize, S: Serializer>(
        values: &Vec<Arc<T>>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(values.iter().map(|v| &**v))
    }

    /// Reads them back, each in an `Arc` of its own.
    pub(in crate::geometry) fn deserialize<'de, T: Deserialize<'de>, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Vec<Arc<T>>, D::Error> {
        Vec::<T>::deserialize(d).map(|v| v.into_iter().map(Arc::new).collect())
    }
}

/// A JSON map as its text (postcard reads no self-describing values).
pub(super) mod json_text {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    use serde_json::{Map, Value};

    /// Writes the map as compact JSON text.
    pub(in crate::geometry) fn serialize<S: Serializer>(
        map: &Map<String, Value>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let text = serde_json::to_string(map).map_err(serde::ser::Error::custom)?;
        text.serialize(s)
    }

    /// Reads the map back from its text.
    pub(in crate::geometry) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Map<String, Value>, D::Error> {
        let text = String::deserialize(d)?;
        serde_json::from_str(&text).map_err(serde::de::Error::custom)
    }
}

/// Bytes as one run (not a sequence of numbers).
pub(super) mod bytes {
    use serde::de::{Deserializer, Error, Visitor};
    use serde::ser::Serializer;

    /// Writes the bytes.
    pub(in crate::geometry) fn serialize<S: Serializer>(b: &[u8], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(b)
    }

    /// Reads them back.
    pub(in crate::geometry) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Vec<u8>, D::Error> {
        struct Bytes;
        impl Visitor<'_> for Bytes {
            type Value = Vec<u8>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("bytes")
            }
            fn visit_bytes<E: Error>(self, v: &[u8]) -> Result<Vec<u8>, E> {
                Ok(v.to_vec())
            }
            fn visit_byte_buf<E: Error>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
                Ok(v)
            }
        }
        d.deserialize_byte_buf(Bytes)
    }
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec2, Vec3, Vec4};

    use super::*;
    use crate::geometry::{
        AlphaMode, DiffuseTransmission, ForestPart, ForestStats, GroupLod, InstanceGroup,
        InstanceTransform, LeafPoint, LodLevel, LodSector, LodTable, MeshLod, PlacementLeaves,
        Primitive, PrimitiveLod, SpeciesCount, VariantCounts,
    };

    /// A model with every kind of field set, odd floats included, and sharing.
    fn sample() -> Model {
        let texture = Arc::new(Texture::from_rgba("bark", 1, 1, &[10, 20, 30, 255]).expect("png"));
        let material = Arc::new(Material {
            texture: Some(texture.clone()),
            normal_texture: Some(texture.clone()),
            alpha: AlphaMode::Mask(0.25),
            transmission: Some(DiffuseTransmission {
                factor: 0.3,
                color: [0.1, f32::MIN_POSITIVE, 1.0],
            }),
            ..Material::default()
        });
        let mut skeleton = Skeleton::new();
        let root = skeleton.push(Vec3::ZERO, None, 0.5, 0);
        skeleton.push(Vec3::Y, Some(root), 0.25, 1);
        skeleton.leaves.push(LeafPoint {
            node: 1,
            position: Vec3::Y,
            direction: Vec3::X,
            side: Vec3::Z,
            size: 0.1,
        });
        let mut mesh = Mesh::from_triangles(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::MIN_POSITIVE, -0.0)],
            vec![0, 1, 2],
        )
        .expect("mesh");
        mesh.name = "trunk".into();
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        mesh.colors = vec![Vec4::ONE; 3];
        mesh.material = material.clone();
        mesh.skeleton = Some(Arc::new(skeleton));
        mesh.extras.insert(
            "mine".into(),
            serde_json::json!([1, -2, 0.1, "x", null, {"a": true}, u64::MAX, 1e-300]),
        );
        let level = |a, b, c| LodLevel { a, b, c };
        let sector = |offset| {
            let rows = vec![level(0, 4, 1), level(1, 3, 1), level(3, 5, 0)];
            LodSector::new(offset, 3, 1, rows).expect("sector")
        };
        let table = LodTable::new(vec![sector(0), sector(5)]).expect("table");
        mesh.lod = Some(Arc::new(MeshLod::Leaves(table.clone())));
        let mesh = Arc::new(mesh);
        let mut lines = (*mesh).clone();
        // Lines of three indices: read back as written (the exporters refuse them).
        lines.primitive = Primitive::Lines;
        let group = GroupLod::new(vec![PrimitiveLod {
            primitive: 1,
            table,
        }]);
        lines.lod = Some(Arc::new(MeshLod::Group(group.expect("group"))));
        let mut model = Model::from_mesh(mesh.clone());
        model.add_mesh(lines, Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)));
        model.groups.push(InstanceGroup {
            name: "g".into(),
            meshes: vec![0, 1],
            transforms: vec![InstanceTransform {
                translation: [1.0, 2.0, 3.0],
                rotation: [0.0, 0.0, 0.0, 1.0],
                scale: 2.0,
            }],
            leaves: Some(PlacementLeaves {
                roots: 3,
                counts: vec![7],
            }),
        });
        model.forest = Some(ForestStats {
            size: [60.0, 0.1],
            seed: u64::MAX,
            tile: Some(f64::MIN_POSITIVE),
            part: ForestPart::Merged(vec![[0, 1], [2, 3]]),
            instances: 4,
            species: vec![SpeciesCount {
                name: "oak".into(),
                variants: 2,
                count: 4,
            }],
        });
        model.variant_counts = vec![VariantCounts {
            nodes: 2,
            leaves: 1,
        }];
        model
            .extras
            .insert("seed".into(), serde_json::json!(u64::MAX));
        model.stats.nodes = 2;
        model.stats.leaves = 1;
        model.stats.modules = 5;
        model.stats.add_phase("meshing", 0.5);
        model.stats.warnings.push("oak.lua:3: warning: thin".into());
        model.environment = Some(texture);
        model
    }

    #[test]
    fn a_model_comes_back_bit_for_bit_with_its_sharing() {
        let model = sample();
        let bytes = encode(&model).expect("encodes");
        let back = decode(&bytes).expect("decodes");
        assert_eq!(back.meshes, model.meshes);
        assert_eq!(back.instances, model.instances);
        assert_eq!(back.groups, model.groups);
        assert_eq!(back.forest, model.forest);
        assert_eq!(back.variant_counts, model.variant_counts);
        assert_eq!(back.extras, model.extras);
        assert_eq!(back.environment, model.environment);
        assert_eq!(back.stats.warnings, model.stats.warnings);
        assert_eq!(back.stats.nodes, 2);
        // The timings of the run are not part of the model's form.
        assert!(back.stats.phases.is_empty());
        let bits = |m: &Model| -> Vec<u32> {
            m.meshes[0]
                .positions
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect()
        };
        assert_eq!(bits(&back), bits(&model));
        let (a, b) = (&back.meshes[0], &back.meshes[1]);
        assert!(Arc::ptr_eq(&a.material, &b.material));
        let texture = a.material.texture.as_ref().expect("texture");
        assert!(Arc::ptr_eq(
            texture,
            back.environment.as_ref().expect("sky")
        ));
        assert!(Arc::ptr_eq(
            texture,
            a.material.normal_texture.as_ref().expect("normal")
        ));
        assert!(Arc::ptr_eq(
            a.skeleton.as_ref().expect("skeleton"),
            b.skeleton.as_ref().expect("skeleton")
        ));
        assert_eq!(encode(&back).expect("again"), bytes);
    }

    #[test]
    fn the_empty_models_bytes_are_pinned() {
        // Meshes, instances, groups, no forest, variant counts, extras "{}", stats (nodes,
        // leaves, modules, warnings), no environment (fuzz/corpus/model_binary/empty).
        let bytes = encode(&Model::new()).expect("encodes");
        assert_eq!(bytes, b"\x00\x00\x00\x00\x00\x02{}\x00\x00\x00\x00\x00");
        assert!(decode(&bytes).expect("decodes").meshes.is_empty());
    }

    #[test]
    fn truncated_damaged_and_trailing_bytes_are_errors_never_panics() {
        let bytes = encode(&sample()).expect("encodes");
        for n in 0..bytes.len() {
            assert!(decode(&bytes[..n]).is_err(), "{n} bytes decoded");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(decode(&longer), Err(BinaryError::Trailing(1))));
        // Every byte changed in turn, by several patterns: an error or a model, never a
        // panic (a change in a float is a model).
        let mut decoded = 0;
        for at in 0..bytes.len() {
            for flip in [0x01, 0x80, 0xff] {
                let mut bad = bytes.clone();
                bad[at] ^= flip;
                decoded += usize::from(decode(&bad).is_ok());
            }
        }
        assert!(decoded < 3 * bytes.len());
        // A huge length is refused without allocating it.
        let mut huge = vec![0xff; 9];
        huge.push(0x01);
        assert!(decode(&huge).is_err());
    }

    #[test]
    fn models_that_break_invariants_are_refused() {
        // A mesh index past the meshes.
        let mut m = sample();
        m.instances[0].mesh = 9;
        let bytes = encode(&m).expect("encodes");
        assert!(matches!(
            decode(&bytes),
            Err(BinaryError::Geometry(GeometryError::IndexOutOfRange { .. }))
        ));
        // Leaf counts that are not one per placement.
        let mut m = sample();
        m.groups[0].leaves = Some(PlacementLeaves {
            roots: 1,
            counts: vec![1, 2],
        });
        let bytes = encode(&m).expect("encodes");
        assert!(matches!(
            decode(&bytes),
            Err(BinaryError::Geometry(GeometryError::AttributeLength { .. }))
        ));
        // A skeleton whose node's parent follows it.
        let mut m = sample();
        let mesh = Arc::make_mut(&mut m.meshes[0]);
        let mut s = (**mesh.skeleton.as_ref().expect("skeleton")).clone();
        s.parents[0] = Some(1);
        mesh.skeleton = Some(Arc::new(s));
        let bytes = encode(&m).expect("encodes");
        assert!(matches!(
            decode(&bytes),
            Err(BinaryError::Skeleton { node: 0 })
        ));
        // A LOD table whose row draws the wrong count: written (the writer trusts the
        // type), refused when read.
        let bytes = encode(&sample()).expect("encodes");
        let rows: &[u8] = &[0, 4, 1, 1, 3, 1, 3, 5, 0];
        let at = bytes
            .windows(rows.len())
            .position(|w| w == rows)
            .expect("the rows are in the bytes");
        let mut bad = bytes.clone();
        bad[at + 5] = 2; // level 1's c: 1 -> 2
        assert!(matches!(decode(&bad), Err(BinaryError::Format(_))));
    }
}
