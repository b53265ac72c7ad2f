//! Reading a tile's glTF back: its buffers checked against their data, its instancing
//! nodes, meshes, materials and textures, and the files its buffer URIs name.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use glam::{Vec2, Vec3, Vec4};
use gltf::Gltf;
use pge_engine::geometry::{
    AlphaMode, DiffuseTransmission, InstanceTransform, Material, Mesh, Primitive, Texture,
};
use serde_json::{Map, Value};

/// Checks that every accessor lies inside its buffer view, every view inside its buffer and
/// the buffer inside its data (the binary chunk, or the file it names), so that reading them
/// cannot go out of bounds (the gltf crate's validation does not compare them with the bytes
/// actually present).
pub(super) fn check_bounds(doc: &gltf::Document, data: &[Option<&[u8]>]) -> anyhow::Result<()> {
    for buffer in doc.buffers() {
        let present = data
            .get(buffer.index())
            .copied()
            .flatten()
            .map_or(0, <[u8]>::len);
        if buffer.length() > present {
            let what = if buffer.index() == 0 {
                "the binary chunk"
            } else {
                "the file it names"
            };
            bail!("buffer {} is not in {what}", buffer.index());
        }
    }
    for view in doc.views() {
        if view.offset().saturating_add(view.length()) > view.buffer().length() {
            bail!("buffer view {} goes past its buffer", view.index());
        }
    }
    for a in doc.accessors() {
        if a.sparse().is_some() {
            bail!("accessor {} is sparse, which PGE never writes", a.index());
        }
        let Some(view) = a.view() else {
            bail!("accessor {} has no buffer view", a.index());
        };
        let stride = view.stride().unwrap_or(a.size());
        let end = match a.count() {
            0 => a.offset(),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(a.offset()))
                .and_then(|x| x.checked_add(a.size()))
                .unwrap_or(usize::MAX),
        };
        if end > view.length() {
            bail!("accessor {} goes past its buffer view", a.index());
        }
    }
    Ok(())
}

/// A node's leaf counts (`extras.pge.lod.leaves`: an array for an instancing node, a number
/// for a node per placement), checked against its `placements`.
pub(super) fn leaf_counts(
    leaves: Option<&Value>,
    placements: usize,
) -> anyhow::Result<Option<Vec<u32>>> {
    let count = |v: &Value| v.as_u64().and_then(|n| u32::try_from(n).ok());
    let counts: Option<Vec<u32>> = match leaves {
        None => return Ok(None),
        Some(Value::Array(list)) => list.iter().map(count).collect(),
        Some(one) => count(one).map(|n| vec![n]),
    };
    match counts {
        Some(c) if c.len() == placements => Ok(Some(c)),
        _ => bail!("a node's extras.pge.lod.leaves do not match its {placements} placements"),
    }
}

/// The placements of an `EXT_mesh_gpu_instancing` node.
pub(super) fn read_instances<'a>(
    gltf: &'a Gltf,
    attributes: &Value,
    buffer: &dyn Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> anyhow::Result<Vec<InstanceTransform>> {
    let accessor = |name: &str| {
        attributes
            .get(name)
            .and_then(Value::as_u64)
            .and_then(|i| gltf.document.accessors().nth(i as usize))
            .filter(|a| a.data_type() == gltf::accessor::DataType::F32)
            .with_context(|| format!("an instancing node without a float {name} accessor"))
    };
    let vec3 = |name: &str| -> anyhow::Result<Vec<[f32; 3]>> {
        let a = accessor(name)?;
        if a.dimensions() != gltf::accessor::Dimensions::Vec3 {
            bail!("the instancing {name} accessor is not VEC3");
        }
        Ok(gltf::accessor::Iter::<[f32; 3]>::new(a, buffer)
            .with_context(|| format!("the instancing {name} data is missing"))?
            .collect())
    };
    let translation = vec3("TRANSLATION")?;
    let scale = vec3("SCALE")?;
    let a = accessor("ROTATION")?;
    if a.dimensions() != gltf::accessor::Dimensions::Vec4 {
        bail!("the instancing ROTATION accessor is not VEC4");
    }
    let rotation: Vec<[f32; 4]> = gltf::accessor::Iter::<[f32; 4]>::new(a, buffer)
        .context("the instancing ROTATION data is missing")?
        .collect();
    if translation.len() != rotation.len() || translation.len() != scale.len() {
        bail!("the instancing accessors differ in length");
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
pub(super) fn read_mesh<'s>(
    mesh: &gltf::Mesh,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> anyhow::Result<(String, Vec<Mesh>)> {
    let name = mesh.name().unwrap_or_default().to_string();
    let extras: Map<String, Value> = match mesh.extras() {
        Some(raw) => match serde_json::from_str::<Value>(raw.get())?.get("pge") {
            Some(Value::Object(m)) => m.clone(),
            _ => Map::new(),
        },
        None => Map::new(),
    };
    let mut parts = Vec::new();
    for prim in mesh.primitives() {
        let reader = prim.reader(buffer);
        let primitive = match prim.mode() {
            gltf::mesh::Mode::Triangles => Primitive::Triangles,
            gltf::mesh::Mode::Lines => Primitive::Lines,
            other => bail!("mesh {name}: {other:?} primitives are not PGE's"),
        };
        let mut m = Mesh {
            name: name.clone(),
            primitive,
            positions: reader
                .read_positions()
                .with_context(|| format!("mesh {name}: no positions"))?
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
                .with_context(|| format!("mesh {name}: no indices"))?
                .into_u32()
                .collect(),
            material: Arc::new(read_material(&prim.material(), buffer, json)?),
            ..Mesh::default()
        };
        if parts.is_empty() {
            m.extras = extras.clone();
        }
        parts.push(m);
    }
    Ok((name, parts))
}

/// A glTF material as PGE's, its textures (base colour, normal, metallic-roughness) read
/// back from their buffers, its `KHR_materials_diffuse_transmission` from the file's JSON
/// (`json`: the gltf crate reads no such extension).
fn read_material<'s>(
    m: &gltf::Material,
    buffer: &dyn for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    json: &Value,
) -> anyhow::Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let read = |texture: Option<gltf::Texture>| -> anyhow::Result<Option<Arc<Texture>>> {
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
) -> anyhow::Result<Arc<Texture>> {
    let image = texture.source();
    let gltf::image::Source::View { view, .. } = image.source() else {
        bail!("an image outside the .glb");
    };
    let bytes = buffer(view.buffer())
        .and_then(|b| b.get(view.offset()..view.offset() + view.length()))
        .context("an image outside its buffer")?;
    let name = image.name().unwrap_or_default().to_string();
    let texture = Texture::from_encoded(name, bytes.to_vec())
        .context("an image that is neither a PNG nor a JPEG")?;
    Ok(Arc::new(texture))
}

/// The file a buffer's URI names, relative to the tile: percent-decoded; absolute paths,
/// schemes (`data:`, `http:`) and `..` past nothing are refused.
pub(super) fn relative_file(uri: &str) -> anyhow::Result<PathBuf> {
    let refuse = || anyhow::anyhow!("buffer URI '{uri}' is not a relative file");
    if uri.starts_with('/') || uri.contains(':') || uri.contains('\\') || uri.is_empty() {
        return Err(refuse());
    }
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
    Ok(PathBuf::from(text))
}

/// `path` made absolute, `.` and `..` folded (lexically), so one file has one key.
pub(super) fn normal_path(path: &Path) -> anyhow::Result<PathBuf> {
    let absolute =
        std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))?;
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    Ok(out)
}
