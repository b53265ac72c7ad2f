//! A model prepared for drawing: interleaved vertex arrays, instance matrices grouped per
//! mesh, decoded textures with their mip chains, the branch skeleton as world-space lines.
//!
//! Built on the worker thread right after generation, so the window only uploads buffers.

use pge_engine::math;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::{Mat4, Vec3};
use pge_engine::geometry::{AlphaMode, DiffuseTransmission, Mesh, Model, Primitive, Texture};

use crate::VERTEX_FLOATS;

/// An RGBA8 (sRGB) texture with its mip chain, largest first.
#[derive(Debug)]
pub struct TextureData {
    /// Width of level 0.
    pub width: u32,
    /// Height of level 0.
    pub height: u32,
    /// Pixels of each level.
    pub levels: Vec<Vec<u8>>,
}

/// One mesh with every instance that places it.
#[derive(Debug)]
pub struct SceneMesh {
    /// Interleaved vertices, [`VERTEX_FLOATS`] floats each.
    pub vertices: Vec<f32>,
    /// Triangle (or line) indices.
    pub indices: Vec<u32>,
    /// Whether `indices` are line pairs.
    pub lines: bool,
    /// Column-major local-to-world matrices, one per instance.
    pub instances: Vec<[f32; 16]>,
    /// Linear base colour factor.
    pub base_color: [f32; 4],
    /// Base colour texture.
    pub texture: Option<Arc<TextureData>>,
    /// Normal map (tangent space, linear data), read with the vertices' tangents.
    pub normal_texture: Option<Arc<TextureData>>,
    /// Alpha cutoff for masked materials (leaves).
    pub alpha_cutoff: Option<f32>,
    /// Back faces drawn (lit from the side they face).
    pub double_sided: bool,
    /// Light through the surface (leaves): back faces tinted by its colour.
    pub transmission: Option<DiffuseTransmission>,
    /// Foliage, hidden by the "leaves" toggle: a masked material or a name saying so.
    pub is_leaf: bool,
    /// For foliage: an eighth of the leaves (triangle pairs); for a big bark mesh: its
    /// largest eighth of triangles. A compact mesh of its own (interleaved vertices,
    /// indices), drawn while the camera moves. Compact, because a
    /// software renderer shades every vertex in the index range, used or not.
    pub coarse: Option<(Vec<f32>, Vec<u32>)>,
    /// A leaf mesh's levels of detail (its own, or computed for a forest's leaves).
    pub lod: Option<super::lod::LeafLod>,
    /// Placed by a forest (an instance group) only: drawn within the forest's budget
    /// ([`super::forest`]).
    pub forest: bool,
    /// A sphere around the mesh in its own frame: centre and radius.
    pub sphere: (Vec3, f32),
}

/// The model's environment: an equirectangular sky drawn behind everything, whose average
/// colour tints the ambient light.
#[derive(Debug)]
pub struct Environment {
    /// The decoded sky image.
    pub texture: Arc<TextureData>,
    /// Average colour of the image, linear RGB.
    pub average: [f32; 3],
}

/// Counts shown in the statistics panel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneStats {
    /// Vertices drawn, over all instances.
    pub vertices: usize,
    /// Triangles drawn, over all instances.
    pub triangles: usize,
    /// Skeleton nodes.
    pub nodes: u64,
    /// Leaves.
    pub leaves: u64,
    /// L-system modules.
    pub modules: u64,
    /// Seconds per phase.
    pub phases: Vec<(String, f64)>,
}

/// A model ready to upload.
#[derive(Debug)]
pub struct Scene {
    /// Meshes with their instances.
    pub meshes: Vec<SceneMesh>,
    /// The skeletons of every instance as world-space segments (pairs of points).
    pub skeleton: Vec<[f32; 3]>,
    /// World-space bounds, `None` when empty.
    pub bounds: Option<(Vec3, Vec3)>,
    /// Counts.
    pub stats: SceneStats,
    /// The sky, when the model has one (and it decodes).
    pub environment: Option<Environment>,
}

impl Scene {
    /// Prepares `model`. Textures that fail to decode are left out (the exporter would
    /// have refused them earlier; the preview still shows the geometry).
    #[must_use]
    pub fn new(model: &Model) -> Scene {
        let mut textures: HashMap<*const Texture, Option<Arc<TextureData>>> = HashMap::new();
        let mut normal_maps: HashMap<*const Texture, Option<Arc<TextureData>>> = HashMap::new();
        let mut per_mesh: Vec<Vec<[f32; 16]>> = vec![Vec::new(); model.meshes.len()];
        for inst in &model.instances {
            if let Some(list) = per_mesh.get_mut(inst.mesh) {
                list.push(inst.transform.to_cols_array());
            }
        }
        // Instance groups (a forest's variants) are drawn instanced too; their skeletons
        // are not drawn (a forest has millions of branches).
        let plain: Vec<usize> = per_mesh.iter().map(Vec::len).collect();
        for group in &model.groups {
            let matrices: Vec<[f32; 16]> = group
                .transforms
                .iter()
                .map(|t| t.matrix().to_cols_array())
                .collect();
            for &m in &group.meshes {
                if let Some(list) = per_mesh.get_mut(m) {
                    list.extend_from_slice(&matrices);
                }
            }
        }
        let in_groups: HashSet<usize> = model
            .groups
            .iter()
            .flat_map(|g| g.meshes.iter().copied())
            .collect();
        let forest: Vec<bool> = (0..model.meshes.len())
            .map(|m| plain[m] == 0 && in_groups.contains(&m))
            .collect();
        let lods = forest_lods(model, &forest);
        let mut meshes = Vec::new();
        let mut skeleton = Vec::new();
        for (index, ((mesh, instances), plain)) in
            model.meshes.iter().zip(per_mesh).zip(plain).enumerate()
        {
            if instances.is_empty() || mesh.positions.is_empty() {
                continue;
            }
            let forest = forest[index];
            // A forest's leaves without levels get them here (the draw reads them in V's
            // order; the model itself is not changed).
            let mesh: &Mesh = lods.get(&index).unwrap_or(&**mesh);
            if let Some(sk) = &mesh.skeleton {
                for m in &instances[..plain] {
                    let m = Mat4::from_cols_array(m);
                    for (i, parent) in sk.parents.iter().enumerate() {
                        if let (Some(p), Some(c)) = (parent, sk.positions.get(i))
                            && let Some(pp) = sk.positions.get(*p as usize)
                        {
                            skeleton.push(m.transform_point3(*pp).to_array());
                            skeleton.push(m.transform_point3(*c).to_array());
                        }
                    }
                }
            }
            let texture = mesh.material.texture.as_ref().and_then(|t| {
                textures
                    .entry(Arc::as_ptr(t))
                    .or_insert_with(|| decode(t).map(Arc::new))
                    .clone()
            });
            let normal_texture = mesh.material.normal_texture.as_ref().and_then(|t| {
                normal_maps
                    .entry(Arc::as_ptr(t))
                    .or_insert_with(|| decode_linear(t).map(Arc::new))
                    .clone()
            });
            let vertices = interleave(mesh);
            let lod = super::lod::LeafLod::from_lod(mesh.lod.as_deref(), mesh.positions.len());
            let coarse = if mesh.primitive != Primitive::Triangles || (forest && lod.is_some()) {
                None
            } else if is_leaf(mesh) {
                Some(coarse_leaves(&vertices, &mesh.indices))
            } else {
                coarse_grid(&vertices, &mesh.indices, instances.len())
                    .or_else(|| coarse_bark(&vertices, &mesh.indices, instances.len()))
            };
            meshes.push(SceneMesh {
                vertices,
                indices: mesh.indices.clone(),
                lines: mesh.primitive == Primitive::Lines,
                instances,
                base_color: mesh.material.base_color,
                texture,
                normal_texture,
                alpha_cutoff: match mesh.material.alpha {
                    AlphaMode::Mask(c) => Some(c),
                    _ => None,
                },
                double_sided: mesh.material.double_sided,
                transmission: mesh.material.transmission,
                is_leaf: is_leaf(mesh),
                coarse,
                lod,
                forest,
                sphere: sphere(mesh),
            });
        }
        let stats = SceneStats {
            vertices: model.vertex_count(),
            triangles: model.triangle_count(),
            nodes: model.stats.nodes,
            leaves: model.stats.leaves,
            modules: model.stats.modules,
            phases: model.stats.phases.clone(),
        };
        let environment = model.environment.as_ref().and_then(|t| {
            let texture = decode(t)?;
            let average = average_linear(texture.levels.first()?);
            Some(Environment {
                texture: Arc::new(texture),
                average,
            })
        });
        Scene {
            meshes,
            skeleton,
            bounds: model.bounds(),
            stats,
            environment,
        }
    }
}

/// The leaf meshes of a forest (`forest[m]`) that have no levels of detail, given them by
/// the same simplification as `lod = {}` ([`pge_lod::lod_mesh`]), on every core. Meshes
/// that are not quads (or have degenerate leaves) are left out: they are drawn whole or by
/// their coarse eighth.
fn forest_lods(model: &Model, forest: &[bool]) -> HashMap<usize, Mesh> {
    use rayon::prelude::*;
    let wanted: Vec<usize> = (0..model.meshes.len())
        .filter(|&m| {
            let mesh = &model.meshes[m];
            forest[m]
                && is_leaf(mesh)
                && mesh.primitive == Primitive::Triangles
                && mesh.lod.is_none()
        })
        .collect();
    wanted
        .into_par_iter()
        .filter_map(|m| {
            let options = pge_lod::LodOptions::default();
            let (mesh, _) = pge_lod::lod_mesh(&model.meshes[m], &options).ok()?;
            Some((m, mesh))
        })
        .collect()
}

/// The sphere around the bounding box of `mesh`'s positions.
fn sphere(mesh: &Mesh) -> (Vec3, f32) {
    mesh.bounds().map_or((Vec3::ZERO, 0.0), |(lo, hi)| {
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    })
}

/// Whether a mesh is foliage: an alpha-masked material, or "leaf"/"foliage" in the mesh's or
/// the material's name.
fn is_leaf(mesh: &Mesh) -> bool {
    let named = |s: &str| {
        let s = s.to_ascii_lowercase();
        s.contains("leaf") || s.contains("leaves") || s.contains("foliage")
    };
    matches!(mesh.material.alpha, AlphaMode::Mask(_))
        || named(&mesh.name)
        || named(&mesh.material.name)
}

/// One leaf (a pair of triangles) in [`COARSE_KEEP`], each grown about its centre so the
/// crown keeps most of its density: a compact mesh of its own.
fn coarse_leaves(vertices: &[f32], indices: &[u32]) -> (Vec<f32>, Vec<u32>) {
    let (mut out, kept) = compact(vertices, &coarse(indices));
    // Half the leaf area of the full crown: enough to keep its look, and software renderers
    // are bound by the area of alpha-tested leaves.
    let grow = (COARSE_KEEP as f32 / 2.0).sqrt();
    let mut i = 0;
    for pair in kept.chunks(6) {
        // Vertices of a pair are numbered consecutively by `compact` (first use order).
        let (lo, hi) = match (pair.iter().min(), pair.iter().max()) {
            (Some(a), Some(b)) => (*a as usize, *b as usize + 1),
            _ => continue,
        };
        if lo < i {
            continue; // shares vertices with an earlier pair: leave it as it is
        }
        i = hi;
        let n = (hi - lo) as f32;
        let mut centre = Vec3::ZERO;
        for v in lo..hi {
            centre += Vec3::from_slice(&out[v * VERTEX_FLOATS..v * VERTEX_FLOATS + 3]);
        }
        centre /= n;
        for v in lo..hi {
            let p = &mut out[v * VERTEX_FLOATS..v * VERTEX_FLOATS + 3];
            let q = centre + (Vec3::from_slice(p) - centre) * grow;
            p.copy_from_slice(&q.to_array());
        }
    }
    (out, kept)
}

/// One leaf of how many is kept while the camera moves.
const COARSE_KEEP: usize = 8;

/// Bark meshes that draw at least this many triangles (over all their instances: a forest's
/// small bushes count by the thousand) get a coarse version for moving frames.
const COARSE_BARK_MIN: usize = 20_000;

/// The largest eighth of the triangles of a bark mesh drawn `instances` times (by area:
/// trunk and limbs stay, twigs go), compacted, for frames drawn while the camera moves;
/// `None` for meshes that draw few triangles.
fn coarse_bark(
    vertices: &[f32],
    indices: &[u32],
    instances: usize,
) -> Option<(Vec<f32>, Vec<u32>)> {
    let triangles = indices.len() / 3;
    if triangles < 8 || triangles.saturating_mul(instances.max(1)) < COARSE_BARK_MIN {
        return None;
    }
    let position = |i: u32| {
        let at = i as usize * VERTEX_FLOATS;
        vertices
            .get(at..at + 3)
            .map_or(Vec3::ZERO, Vec3::from_slice)
    };
    let areas: Vec<f32> = indices
        .chunks_exact(3)
        .map(|t| {
            let (a, b, c) = (position(t[0]), position(t[1]), position(t[2]));
            (b - a).cross(c - a).length_squared()
        })
        .collect();
    let mut sorted = areas.clone();
    let nth = triangles - triangles / 8;
    sorted.select_nth_unstable_by(nth, f32::total_cmp);
    let threshold = sorted[nth];
    let kept: Vec<u32> = indices
        .chunks_exact(3)
        .zip(&areas)
        .filter(|(_, a)| **a >= threshold)
        .flat_map(|(t, _)| t.iter().copied())
        .collect();
    Some(compact(vertices, &kept))
}

/// A grid mesh keeps every this many rows and columns of vertices (and its last) while the
/// camera moves: a sixteenth of its triangles (measured on a 1 km terrain of 127,000
/// triangles orbited on lavapipe: every third row, a ninth, made moving frames about 9 %
/// slower than the scattered eighth a bark mesh keeps; every fourth, as fast).
const COARSE_GRID_STEP: usize = 4;

/// The triangles of the cells between the vertex columns `columns` and rows `rows` (both
/// increasing) of a grid `width` vertices wide, numbered row by row: each cell (a, c, b),
/// (b, c, d) with b right of a and c below it, cells in row order, as a forest's terrain
/// is built.
fn grid_triangles(width: usize, columns: &[usize], rows: &[usize]) -> Vec<u32> {
    let cells = columns.len().saturating_sub(1) * rows.len().saturating_sub(1);
    let mut out = Vec::with_capacity(cells * 6);
    for l in rows.windows(2) {
        for k in columns.windows(2) {
            let at = |row: usize, column: usize| (row * width + column) as u32;
            let (a, b) = (at(l[0], k[0]), at(l[0], k[1]));
            let (c, d) = (at(l[1], k[0]), at(l[1], k[1]));
            out.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    out
}

/// A grid mesh drawn `instances` times (a terrain), for frames drawn while the camera
/// moves: its every [`COARSE_GRID_STEP`]th row and column of vertices and its last ones,
/// joined as a grid of their own, compacted. It covers every cell of the full grid and its
/// cells share their edges: no holes (the largest triangles of a terrain, as a bark mesh
/// keeps them, are its steepest ones, scattered). `None` for a mesh that is no grid laid out
/// as [`grid_triangles`] makes them, or draws few triangles.
fn coarse_grid(
    vertices: &[f32],
    indices: &[u32],
    instances: usize,
) -> Option<(Vec<f32>, Vec<u32>)> {
    let triangles = indices.len() / 3;
    if triangles.saturating_mul(instances.max(1)) < COARSE_BARK_MIN {
        return None;
    }
    // The first cell's (a, c, b): c is the vertex below the first, one row further.
    let width = *indices.get(1)? as usize;
    let count = vertices.len() / VERTEX_FLOATS;
    if width < 2 || !count.is_multiple_of(width) || count / width < 2 {
        return None;
    }
    let height = count / width;
    let all = |n: usize| (0..n).collect::<Vec<usize>>();
    if indices.len() != (width - 1) * (height - 1) * 6
        || grid_triangles(width, &all(width), &all(height)) != indices
    {
        return None;
    }
    let kept = |n: usize| {
        let mut kept: Vec<usize> = (0..n).step_by(COARSE_GRID_STEP).collect();
        if kept.last() != Some(&(n - 1)) {
            kept.push(n - 1);
        }
        kept
    };
    let coarse = grid_triangles(width, &kept(width), &kept(height));
    Some(compact(vertices, &coarse))
}

/// Every [`COARSE_KEEP`]th pair of triangles (a leaf quad is one pair).
fn coarse(indices: &[u32]) -> Vec<u32> {
    indices
        .chunks(6 * COARSE_KEEP)
        .flat_map(|c| c.iter().take(6))
        .copied()
        .collect()
}

/// The vertices `indices` use, in order of first use, and the indices renumbered to them.
fn compact(vertices: &[f32], indices: &[u32]) -> (Vec<f32>, Vec<u32>) {
    let mut map: HashMap<u32, u32> = HashMap::new();
    let mut out_vertices = Vec::new();
    let mut out_indices = Vec::with_capacity(indices.len());
    for &i in indices {
        let next = map.len() as u32;
        let j = *map.entry(i).or_insert_with(|| {
            let at = i as usize * VERTEX_FLOATS;
            out_vertices.extend_from_slice(&vertices[at..at + VERTEX_FLOATS]);
            next
        });
        out_indices.push(j);
    }
    (out_vertices, out_indices)
}

fn interleave(mesh: &Mesh) -> Vec<f32> {
    let n = mesh.positions.len();
    // The tangents the glb carries (the same function writes them), where a normal map
    // reads them.
    let tangents = mesh.tangents().unwrap_or_default();
    let mut out = Vec::with_capacity(n * VERTEX_FLOATS);
    for i in 0..n {
        let p = mesh.positions[i];
        let nr = mesh.normals.get(i).copied().unwrap_or(Vec3::Y);
        let uv = mesh.uvs.get(i).copied().unwrap_or_default();
        let c = mesh.colors.get(i).copied().unwrap_or(glam::Vec4::ONE);
        let t = tangents.get(i).copied().unwrap_or(glam::Vec4::ZERO);
        out.extend_from_slice(&[
            p.x, p.y, p.z, nr.x, nr.y, nr.z, uv.x, uv.y, c.x, c.y, c.z, c.w, t.x, t.y, t.z, t.w,
        ]);
    }
    out
}

/// Decodes a colour texture (PNG or JPEG) and builds its mip chain (2x2 box filter,
/// sRGB-aware).
fn decode(texture: &Texture) -> Option<TextureData> {
    decode_with(texture, downsample)
}

/// Decodes a texture holding data, not colour (a normal map), and builds its mip chain by a
/// plain 2x2 box filter of the stored values.
fn decode_linear(texture: &Texture) -> Option<TextureData> {
    decode_with(texture, downsample_data)
}

fn decode_with(
    texture: &Texture,
    down: fn(&[u8], u32, u32, u32, u32) -> Vec<u8>,
) -> Option<TextureData> {
    let img = image::load_from_memory(&texture.encoded).ok()?.to_rgba8();
    let (width, height) = img.dimensions();
    let mut levels = vec![img.into_raw()];
    let (mut w, mut h) = (width, height);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let prev = levels.last().map(Vec::as_slice).unwrap_or_default();
        levels.push(down(prev, w, h, nw, nh));
        (w, h) = (nw, nh);
    }
    Some(TextureData {
        width,
        height,
        levels,
    })
}

/// One mip level of data from the level above: the rounded mean of each 2x2 block.
fn downsample_data(src: &[u8], w: u32, h: u32, nw: u32, nh: u32) -> Vec<u8> {
    let mut next = vec![0u8; (nw * nh * 4) as usize];
    for y in 0..nh {
        for x in 0..nw {
            for k in 0..4 {
                let mut sum = 0u32;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                    sum += u32::from(src[((sy * w + sx) * 4 + k) as usize]);
                }
                next[((y * nw + x) * 4 + k) as usize] = ((sum + 2) / 4) as u8;
            }
        }
    }
    next
}

/// The average linear RGB of sRGB-encoded RGBA8 pixels (alpha ignored).
fn average_linear(rgba: &[u8]) -> [f32; 3] {
    let to_linear = |c: u8| math::powf(c as f32 / 255.0, 2.2);
    let mut acc = [0.0f64; 3];
    let mut n = 0usize;
    for p in rgba.chunks_exact(4) {
        for k in 0..3 {
            acc[k] += f64::from(to_linear(p[k]));
        }
        n += 1;
    }
    let n = n.max(1) as f64;
    acc.map(|a| (a / n) as f32)
}

fn downsample(src: &[u8], w: u32, h: u32, nw: u32, nh: u32) -> Vec<u8> {
    let to_linear = |c: u8| math::powf(c as f32 / 255.0, 2.2);
    let to_srgb = |c: f32| {
        (math::powf(c.max(0.0), 1.0 / 2.2) * 255.0)
            .round()
            .min(255.0) as u8
    };
    let mut out = Vec::with_capacity((nw * nh * 4) as usize);
    for y in 0..nh {
        for x in 0..nw {
            let mut acc = [0.0f32; 4];
            let mut n = 0.0;
            for (sx, sy) in [
                (2 * x, 2 * y),
                (2 * x + 1, 2 * y),
                (2 * x, 2 * y + 1),
                (2 * x + 1, 2 * y + 1),
            ] {
                if sx < w && sy < h {
                    let i = ((sy * w + sx) * 4) as usize;
                    for k in 0..3 {
                        acc[k] += to_linear(src[i + k]);
                    }
                    acc[3] += src[i + 3] as f32 / 255.0;
                    n += 1.0;
                }
            }
            for (k, a) in acc.iter().enumerate() {
                out.push(if k < 3 {
                    to_srgb(a / n)
                } else {
                    (a / n * 255.0).round() as u8
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
