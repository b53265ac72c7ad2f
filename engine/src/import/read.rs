//! Reading PGE's glTF back: its buffers checked against their data, its instancing nodes,
//! meshes, materials and textures, and the files its buffer URIs name.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use gltf::Gltf;
use serde_json::{Map, Value};

use super::ImportError;
use crate::export::lod_from_json;
use crate::geometry::{
    AlphaMode, DiffuseTransmission, InstanceTransform, Material, Mesh, MeshLod, Primitive, Texture,
};

/// Checks that every accessor lies inside its buffer view, every view inside its buffer and
/// the buffer inside its data (the binary chunk, or the file it names), so that reading them
/// cannot go out of bounds (the gltf crate's validation does not compare them with the bytes
/// actually present). A `byteStride` smaller than its accessor's element is refused too.
pub fn check_bounds(doc: &gltf::Document, data: &[Option<&[u8]>]) -> Result<(), ImportError> {
    let present: Vec<usize> = data.iter().map(|d| d.map_or(0, <[u8]>::len)).collect();
    check_layout(doc, &present)
}

/// [`check_bounds`] against the lengths of the buffers' data (`present[b]` bytes for buffer
/// `b`, none past the list) rather than the data itself: a reader that has the description
/// of a buffer before its bytes (shared variants) checks it the same way.
pub fn check_layout(doc: &gltf::Document, present: &[usize]) -> Result<(), ImportError> {
    for buffer in doc.buffers() {
        let present = present.get(buffer.index()).copied().unwrap_or(0);
        if buffer.length() > present {
            let what = if buffer.index() == 0 {
                "the binary chunk"
            } else {
                "the file it names"
            };
            return Err(ImportError::BufferMissing {
                buffer: buffer.index(),
                what,
            });
        }
    }
    for view in doc.views() {
        if view.offset().saturating_add(view.length()) > view.buffer().length() {
            return Err(ImportError::ViewPastBuffer(view.index()));
        }
    }
    for a in doc.accessors() {
        if a.sparse().is_some() {
            return Err(ImportError::Sparse(a.index()));
        }
        let Some(view) = a.view() else {
            return Err(ImportError::NoView(a.index()));
        };
        let stride = view.stride().unwrap_or(a.size());
        if stride < a.size() {
            return Err(ImportError::StrideTooSmall {
                accessor: a.index(),
                stride,
                size: a.size(),
            });
        }
        let end = match a.count() {
            0 => a.offset(),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(a.offset()))
                .and_then(|x| x.checked_add(a.size()))
                .unwrap_or(usize::MAX),
        };
        if end > view.length() {
            return Err(ImportError::AccessorPastView(a.index()));
        }
    }
    Ok(())
}

/// The types glTF requires of the attributes in `read` (POSITION and NORMAL float VEC3,
/// TEXCOORD_n float or unsigned VEC2, COLOR_n float or unsigned VEC3 or VEC4) and of the
/// indices (an unsigned integer SCALAR): the gltf crate's readers assume them, and reach an
/// `unreachable!` (a panic) or read other bytes than the accessor's when they do not hold.
pub(crate) fn check_primitive_types(
    prim: &gltf::Primitive,
    read: &[gltf::Semantic],
) -> Result<(), ImportError> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let unsigned = |t: DataType| matches!(t, DataType::U8 | DataType::U16);
    for semantic in read {
        let Some(a) = prim.get(semantic) else {
            continue;
        };
        let (t, d) = (a.data_type(), a.dimensions());
        let (ok, expected) = match semantic {
            Semantic::Positions => {
                if t != DataType::F32 || d != Dimensions::Vec3 {
                    return Err(ImportError::PositionType(a.index()));
                }
                continue;
            }
            Semantic::Normals => (t == DataType::F32 && d == Dimensions::Vec3, "FLOAT VEC3"),
            Semantic::TexCoords(_) => (
                (t == DataType::F32 || unsigned(t)) && d == Dimensions::Vec2,
                "a FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT VEC2",
            ),
            Semantic::Colors(_) => (
                (t == DataType::F32 || unsigned(t))
                    && matches!(d, Dimensions::Vec3 | Dimensions::Vec4),
                "a FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT VEC3 or VEC4",
            ),
            _ => (true, ""),
        };
        if !ok {
            return Err(ImportError::AttributeType {
                accessor: a.index(),
                attribute: semantic.to_string(),
                expected,
            });
        }
    }
    if let Some(a) = prim.indices() {
        let integer = unsigned(a.data_type()) || a.data_type() == gltf::accessor::DataType::U32;
        if !integer || a.dimensions() != gltf::accessor::Dimensions::Scalar {
            return Err(ImportError::IndexType(a.index()));
        }
    }
    Ok(())
}

/// A node's leaf counts (`extras.pge.lod.leaves`: an array for an instancing node, a number
/// for a node per placement), checked against its `placements`.
pub fn leaf_counts(
    leaves: Option<&Value>,
    placements: usize,
) -> Result<Option<Vec<u32>>, ImportError> {
    let count = |v: &Value| v.as_u64().and_then(|n| u32::try_from(n).ok());
    let counts: Option<Vec<u32>> = match leaves {
        None => return Ok(None),
        Some(Value::Array(list)) => list.iter().map(count).collect(),
        Some(one) => count(one).map(|n| vec![n]),
    };
    match counts {
        Some(c) if c.len() == placements => Ok(Some(c)),
        _ => Err(ImportError::LeafCounts { placements }),
    }
}

/// The placements of an `EXT_mesh_gpu_instancing` node.
pub fn read_instances<'a>(
    gltf: &'a Gltf,
    attributes: &Value,
    buffer: &dyn Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> Result<Vec<InstanceTransform>, ImportError> {
    let accessor = |name: &'static str| {
        attributes
            .get(name)
            .and_then(Value::as_u64)
            .and_then(|i| gltf.document.accessors().nth(i as usize))
            .filter(|a| a.data_type() == gltf::accessor::DataType::F32)
            .ok_or(ImportError::InstancingMissing(name))
    };
    let wrong_type = |attribute, expected| ImportError::InstancingType {
        attribute,
        expected,
    };
    let vec3 = |name: &'static str| -> Result<Vec<[f32; 3]>, ImportError> {
        let a = accessor(name)?;
        if a.dimensions() != gltf::accessor::Dimensions::Vec3 {
            return Err(wrong_type(name, "VEC3"));
        }
        Ok(gltf::accessor::Iter::<[f32; 3]>::new(a, buffer)
            .ok_or(ImportError::InstancingData(name))?
            .collect())
    };
    let translation = vec3("TRANSLATION")?;
    let scale = vec3("SCALE")?;
    let a = accessor("ROTATION")?;
    if a.dimensions() != gltf::accessor::Dimensions::Vec4 {
        return Err(wrong_type("ROTATION", "VEC4"));
    }
    let rotation: Vec<[f32; 4]> = gltf::accessor::Iter::<[f32; 4]>::new(a, buffer)
        .ok_or(ImportError::InstancingData("ROTATION"))?
        .collect();
    if translation.len() != rotation.len() || translation.len() != scale.len() {
        return Err(ImportError::InstancingLengths);
    }
    Ok(translation
        .into_iter()
        .zip(rotation)
        .zip(scale)
        .map(|((t, r), s)| InstanceTransform {
            translation: t,
            rotation: r,
            scale: s[0].max(s[1]).max(s[2]),
        })
        .collect())
}

/// A glTF mesh as its name and one [`Mesh`] per primitive; the mesh's `extras.pge` goes to
/// the first (where the exporter, which lets the first member's keys win, puts it back).
pub fn read_mesh<'s>(
    mesh: &gltf::Mesh,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> Result<(String, Vec<Mesh>), ImportError> {
    let name = mesh.name().unwrap_or_default().to_string();
    let (extras, lod) = split_lod(match mesh.extras() {
        Some(raw) => match serde_json::from_str::<Value>(raw.get())?.get("pge") {
            Some(Value::Object(m)) => m.clone(),
            _ => Map::new(),
        },
        None => Map::new(),
    });
    let mut parts = Vec::new();
    for prim in mesh.primitives() {
        check_primitive_types(
            &prim,
            &[
                gltf::Semantic::Positions,
                gltf::Semantic::Normals,
                gltf::Semantic::TexCoords(0),
                gltf::Semantic::Colors(0),
            ],
        )?;
        let reader = prim.reader(buffer);
        let primitive = match prim.mode() {
            gltf::mesh::Mode::Triangles => Primitive::Triangles,
            gltf::mesh::Mode::Lines => Primitive::Lines,
            other => {
                return Err(ImportError::Primitive {
                    mesh: name,
                    mode: format!("{other:?}"),
                });
            }
        };
        let mut m = Mesh {
            name: name.clone(),
            primitive,
            positions: reader
                .read_positions()
                .ok_or_else(|| ImportError::missing(&name, "positions"))?
                .map(Vec3::from_array)
                .collect(),
            normals: reader
                .read_normals()
                .map(|n| n.map(Vec3::from_array).collect())
                .unwrap_or_default(),
            uvs: reader
                .read_tex_coords(0)
                .map(|t| t.into_f32().map(Vec2::from_array).collect())
                .unwrap_or_default(),
            colors: reader
                .read_colors(0)
                .map(|c| c.into_rgba_f32().map(Vec4::from_array).collect())
                .unwrap_or_default(),
            indices: reader
                .read_indices()
                .ok_or_else(|| ImportError::missing(&name, "indices"))?
                .into_u32()
                .collect(),
            material: Arc::new(read_material(&prim.material(), buffer, json)?),
            ..Mesh::default()
        };
        if parts.is_empty() {
            m.extras = extras.clone();
            m.lod = lod.clone();
        }
        parts.push(m);
    }
    Ok((name, parts))
}

/// A mesh's `extras.pge` without its `lod`, and the levels of detail read from it
/// ([`lod_from_json`]). An `lod` that is not PGE's, or not last (where the writer puts it),
/// stays among the extras and is written back as it was.
pub fn split_lod(mut extras: Map<String, Value>) -> (Map<String, Value>, Option<Arc<MeshLod>>) {
    let last = extras.keys().next_back().is_some_and(|k| k == "lod");
    let lod = last
        .then(|| extras.get("lod").and_then(lod_from_json))
        .flatten();
    if lod.is_some() {
        extras.remove("lod");
    }
    (extras, lod.map(Arc::new))
}

/// A glTF material as PGE's, its textures (base colour, normal, metallic-roughness) read
/// back from their buffers, its `KHR_materials_diffuse_transmission` from the file's JSON
/// (`json`: the gltf crate reads no such extension).
fn read_material<'s>(
    m: &gltf::Material,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> Result<Material, ImportError> {
    let pbr = m.pbr_metallic_roughness();
    let read = |texture: Option<gltf::Texture>| -> Result<Option<Arc<Texture>>, ImportError> {
        texture.map(|t| read_texture(&t, buffer)).transpose()
    };
    Ok(Material {
        name: m.name().unwrap_or_default().to_string(),
        base_color: pbr.base_color_factor(),
        texture: read(pbr.base_color_texture().map(|i| i.texture()))?,
        normal_texture: read(m.normal_texture().map(|i| i.texture()))?,
        metallic_roughness_texture: read(pbr.metallic_roughness_texture().map(|i| i.texture()))?,
        alpha: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        transmission: m.index().and_then(|i| read_transmission(json, i)),
    })
}

/// The `KHR_materials_diffuse_transmission` of material `index` in a glTF JSON, with the
/// extension's defaults (factor 0, white) for what it leaves out.
fn read_transmission(json: &Value, index: usize) -> Option<DiffuseTransmission> {
    let ext = json.pointer(&format!(
        "/materials/{index}/extensions/KHR_materials_diffuse_transmission"
    ))?;
    let number =
        |v: Option<&Value>, default: f32| v.and_then(Value::as_f64).map_or(default, |x| x as f32);
    let color = ext.get("diffuseTransmissionColorFactor");
    Some(DiffuseTransmission {
        factor: number(ext.get("diffuseTransmissionFactor"), 0.0),
        color: [0, 1, 2].map(|i| number(color.and_then(|c| c.get(i)), 1.0)),
    })
}

/// A texture's image (PNG or JPEG), read back from its buffer as it is.
fn read_texture<'s>(
    texture: &gltf::Texture,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
) -> Result<Arc<Texture>, ImportError> {
    let image = texture.source();
    let gltf::image::Source::View { view, .. } = image.source() else {
        return Err(ImportError::ImageOutsideGlb);
    };
    let bytes = buffer(view.buffer())
        .and_then(|b| b.get(view.offset()..view.offset().saturating_add(view.length())))
        .ok_or(ImportError::ImageOutsideBuffer)?;
    let name = image.name().unwrap_or_default().to_string();
    let texture = Texture::from_encoded(name, bytes.to_vec()).map_err(|_| ImportError::NotPng)?;
    Ok(Arc::new(texture))
}

/// The file a buffer's URI names, relative to the tile: percent-decoded first, then
/// refused when the decoded name is absolute, has a scheme (`data:`, `http:`) or a `\\`, or
/// is empty (`%2F` must not reach an absolute path). A `..` stays: the caller resolves the
/// path and requires it inside its folder.
pub fn relative_file(uri: &str) -> Result<PathBuf, ImportError> {
    let refuse = || ImportError::BufferUri(uri.to_string());
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = uri.get(k + 1..k + 3).ok_or_else(refuse)?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| refuse())?);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    let text = String::from_utf8(out).map_err(|_| refuse())?;
    let absolute = text.starts_with('/') || std::path::Path::new(&text).is_absolute();
    if absolute
        || text.contains(':')
        || text.contains('\\')
        || text.is_empty()
        || text.contains('\0')
    {
        return Err(refuse());
    }
    Ok(PathBuf::from(text))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Model;

    /// A glb of one triangle with its JSON changed by `edit`.
    fn tampered_triangle(edit: impl FnOnce(&mut Value)) -> Vec<u8> {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let bytes =
            crate::export::glb_bytes(&Model::from_mesh(mesh), &Default::default()).expect("glb");
        let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
        let mut json: Value = serde_json::from_slice(&glb.json).expect("json");
        edit(&mut json);
        let text = serde_json::to_vec(&json).expect("json");
        gltf::binary::Glb {
            header: glb.header,
            json: text.into(),
            bin: glb.bin.clone(),
        }
        .to_vec()
        .expect("glb")
    }

    #[test]
    fn attributes_of_types_gltf_forbids_are_errors_not_panics() {
        // Found by tampering the tile_gltf fuzz target's seeds: the gltf crate's readers
        // reach `unreachable!` on float indices and on texture coordinates or colours of
        // other types, which `pge merge` read from a tampered tile (a panic).
        type Tamper = fn(&mut Value);
        let tampers: [(&str, Tamper); 4] = [
            ("(indices) must be an unsigned integer SCALAR", |j| {
                let a = j["meshes"][0]["primitives"][0]["indices"]
                    .as_u64()
                    .expect("indices");
                let t = &mut j["accessors"][a as usize]["componentType"];
                // Signed or float of the same size: inside its view, of a forbidden type.
                *t = Value::from(if *t == 5125 { 5126 } else { 5122 });
            }),
            ("(TEXCOORD_0) must be", |j| {
                let i = j["meshes"][0]["primitives"][0]["indices"].clone();
                j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = i;
            }),
            ("(COLOR_0) must be", |j| {
                let i = j["meshes"][0]["primitives"][0]["indices"].clone();
                j["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = i;
            }),
            ("(NORMAL) must be FLOAT VEC3", |j| {
                let i = j["meshes"][0]["primitives"][0]["indices"].clone();
                j["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = i;
            }),
        ];
        for (needle, tamper) in tampers {
            let bytes = tampered_triangle(tamper);
            let gltf = super::super::open(&bytes).expect("opens");
            let data = vec![gltf.blob.as_deref()];
            check_bounds(&gltf.document, &data).expect("inside its buffers");
            let buffer = |b: gltf::Buffer| data.get(b.index()).copied().flatten();
            let mesh = gltf.document.meshes().next().expect("a mesh");
            let json: Value =
                serde_json::from_slice(&gltf::binary::Glb::from_slice(&bytes).expect("glb").json)
                    .expect("json");
            let e = read_mesh(&mesh, &buffer, &json).expect_err(needle);
            assert!(e.to_string().contains(needle), "{e}");
        }
    }

    #[test]
    fn a_buffer_uri_is_checked_after_it_is_decoded() {
        assert_eq!(
            relative_file("../variants%20a.bin").expect("relative"),
            PathBuf::from("../variants a.bin")
        );
        for uri in [
            "%2Fetc%2Fpasswd",
            "/etc/passwd",
            "data%3Abase64",
            "a%5Cb",
            "",
            "%00",
            "%2",
        ] {
            assert!(relative_file(uri).is_err(), "{uri}");
        }
    }
}
