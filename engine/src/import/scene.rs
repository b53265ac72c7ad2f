//! Opening a glTF file with its accessor indices checked, and the triangles of its default
//! scene.

use glam::{Mat4, Vec3};
use gltf::Gltf;

use super::read::check_primitive_types;
use super::{ImportError, check_bounds};

/// Parses a `.glb` (or a `.gltf` text) after checking that every primitive attribute names
/// an accessor that exists: the `gltf` crate's own validation indexes the POSITION accessor
/// before checking it (a panic, found by fuzzing).
pub fn open(bytes: &[u8]) -> Result<Gltf, ImportError> {
    let unchecked = Gltf::from_slice_without_validation(bytes)?;
    let root = unchecked.document.as_json();
    let count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let named = primitive.attributes.values().chain(&primitive.indices);
            for index in named {
                if index.value() >= count {
                    return Err(ImportError::AccessorIndex {
                        mesh: m,
                        primitive: p,
                        accessor: index.value(),
                        count,
                    });
                }
            }
        }
    }
    Ok(Gltf::from_slice(bytes)?)
}

/// The triangles of every mesh node of a `.glb` (or a `.gltf` with its data embedded) in
/// its default scene (else its first), placed by the node transforms: positions, and
/// triangles indexing them. Primitives other than triangles are skipped, and so are
/// triangles with an index past their primitive's vertices.
pub fn scene_triangles(bytes: &[u8]) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), ImportError> {
    // Buffers only: a shape needs no images (and the gltf crate's image import panics on an
    // image view without a MIME type, found by the mesh_gltf fuzz target).
    let Gltf {
        document: doc,
        blob,
    } = open(bytes)?;
    let buffers = gltf::import_buffers(&doc, None, blob)?;
    let data: Vec<Option<&[u8]>> = buffers.iter().map(|d| Some(&d.0[..])).collect();
    check_bounds(&doc, &data)?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let mut stack: Vec<(gltf::Node, Mat4, usize)> = match &scene {
        Some(s) => s.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect(),
        None => Vec::new(),
    };
    // A valid node graph is a forest: no path is longer than the node count, and no node is
    // visited twice. Invalid files (cycles, shared children) must not loop or explode.
    let nodes = doc.nodes().len();
    let mut visits = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        visits += 1;
        if depth > nodes || visits > nodes {
            return Err(ImportError::NotATree);
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                check_primitive_types(&prim, &[gltf::Semantic::Positions])?;
                let reader = prim.reader(|b| data.get(b.index()).copied().flatten());
                let Some(ps) = reader.read_positions() else {
                    continue;
                };
                let base = positions.len() as u32;
                positions.extend(ps.map(|p| world.transform_point3(Vec3::from_array(p))));
                let count = positions.len() as u32 - base;
                let idx: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..count).collect(),
                };
                for t in idx.chunks_exact(3) {
                    if t.iter().all(|i| *i < count) {
                        triangles.push([base + t[0], base + t[1], base + t[2]]);
                    }
                }
            }
        }
        stack.extend(node.children().map(|c| (c, world, depth + 1)));
    }
    Ok((positions, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gltf_naming_a_missing_accessor_is_an_error_not_a_panic() {
        // Found by the mesh_gltf fuzz target: the gltf crate's validation indexed it.
        let text = br#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}"#;
        let e = scene_triangles(text).expect_err("no accessor 0");
        assert!(e.to_string().contains("names accessor 0 of 0"), "{e}");
    }

    /// A .gltf with one triangle whose data is embedded; `indices` and `position` are the
    /// componentType and type of the two accessors, `children` the first node's children.
    fn triangle_gltf(indices: (u32, &str), position: (u32, &str), children: &str) -> String {
        // Three float VEC3 positions (36 bytes) then three u32 indices (12 bytes), base64.
        let mut bytes = Vec::new();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            bytes.extend(v.to_le_bytes());
        }
        for i in [0u32, 1, 2] {
            bytes.extend(i.to_le_bytes());
        }
        const B64: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let data: String = bytes
            .chunks(3)
            .flat_map(|c| {
                let n = (u32::from(c[0]) << 16)
                    | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                    | u32::from(*c.get(2).unwrap_or(&0));
                let k = c.len() + 1;
                (0..4).map(move |j| {
                    if j < k {
                        B64[(n >> (18 - 6 * j)) as usize & 63] as char
                    } else {
                        '='
                    }
                })
            })
            .collect();
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}],
            "nodes": [{{"mesh": 0, "children": {children}}}, {{"children": [0]}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
            "buffers": [{{"byteLength": 48, "uri": "data:application/octet-stream;base64,{data}"}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 36}},
                            {{"buffer": 0, "byteOffset": 36, "byteLength": 12}}],
            "accessors": [{{"bufferView": 0, "componentType": {}, "count": 3, "type": "{}",
                            "min": [0, 0, 0], "max": [1, 1, 0]}},
                          {{"bufferView": 1, "componentType": {}, "count": 3, "type": "{}"}}]}}"#,
            position.0, position.1, indices.0, indices.1
        )
    }

    #[test]
    fn a_well_typed_embedded_gltf_reads_back_its_triangle() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]");
        let (positions, triangles) = scene_triangles(text.as_bytes()).expect("valid");
        assert_eq!((positions.len(), triangles), (3, vec![[0, 1, 2]]));
    }

    #[test]
    fn float_indices_are_an_error_not_a_panic() {
        // Found by the mesh_gltf fuzz target: the gltf crate's index reader reached
        // `unreachable!()` for an indices accessor of floats.
        let text = triangle_gltf((5126, "SCALAR"), (5126, "VEC3"), "[]");
        let e = scene_triangles(text.as_bytes()).expect_err("float indices");
        assert!(
            e.to_string()
                .contains("(indices) must be an unsigned integer"),
            "{e}"
        );
        let text = triangle_gltf((5125, "VEC2"), (5126, "VEC3"), "[]");
        assert!(scene_triangles(text.as_bytes()).is_err());
    }

    #[test]
    fn integer_positions_are_an_error_not_a_panic() {
        let text = triangle_gltf((5125, "SCALAR"), (5125, "VEC3"), "[]");
        let e = scene_triangles(text.as_bytes()).expect_err("integer positions");
        assert!(
            e.to_string().contains("(POSITION) must be FLOAT VEC3"),
            "{e}"
        );
    }

    #[test]
    fn an_image_view_without_a_mime_type_is_ignored_not_a_panic() {
        // Found by the mesh_gltf fuzz target: the gltf crate's image import unwrapped the
        // missing MIME type. The mesh reader reads no image.
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]");
        let text = text.replacen(
            r#""accessors""#,
            r#""images": [{"bufferView": 0}], "accessors""#,
            1,
        );
        let (positions, _) = scene_triangles(text.as_bytes()).expect("the mesh reads");
        assert_eq!(positions.len(), 3);
    }

    #[test]
    fn a_node_cycle_is_an_error_not_a_hang() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[1]");
        let e = scene_triangles(text.as_bytes()).expect_err("a cycle");
        assert!(e.to_string().contains("not a tree"), "{e}");
    }

    #[test]
    fn an_index_accessor_out_of_range_is_an_error_not_a_panic() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]")
            .replace(r#""indices": 1"#, r#""indices": 7"#);
        let e = scene_triangles(text.as_bytes()).expect_err("no accessor 7");
        assert!(
            matches!(
                e,
                ImportError::AccessorIndex {
                    accessor: 7,
                    count: 2,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn a_stride_smaller_than_the_element_is_an_error_not_a_panic() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]").replace(
            r#"{"buffer": 0, "byteLength": 36}"#,
            r#"{"buffer": 0, "byteLength": 36, "byteStride": 4}"#,
        );
        let e = scene_triangles(text.as_bytes()).expect_err("stride 4 < 12");
        assert!(
            matches!(
                e,
                ImportError::StrideTooSmall {
                    accessor: 0,
                    stride: 4,
                    size: 12
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn an_accessor_past_its_data_is_an_error_not_a_panic() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]").replacen(
            r#""count": 3"#,
            r#""count": 30"#,
            1,
        );
        let e = scene_triangles(text.as_bytes()).expect_err("30 positions in 36 bytes");
        assert!(matches!(e, ImportError::AccessorPastView(0)), "{e}");
    }

    #[test]
    fn node_transforms_place_the_triangles() {
        let text = triangle_gltf((5125, "SCALAR"), (5126, "VEC3"), "[]").replace(
            r#"{"mesh": 0, "children": []}"#,
            r#"{"mesh": 0, "children": [], "translation": [0, 0, 5]}"#,
        );
        let (positions, _) = scene_triangles(text.as_bytes()).expect("valid");
        assert_eq!(positions[1], Vec3::new(1.0, 0.0, 5.0));
    }
}
