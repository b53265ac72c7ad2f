//! A leaf mesh with levels of detail: its quads simplified (per sector), laid out in the
//! order of V, with its LOD table ([`MeshLod`], written to the glTF extras).

use pge_engine::math;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use pge_engine::geometry::{
    AlphaMode, GeometryError, LodLevel, LodSector, Material, Mesh, MeshLod, Primitive,
};

use crate::atlas::Atlas;
use crate::leaf::Leaf;
use crate::simplify::{Axis, Chain, Selection, simplify};
use crate::vector::LodTable;

/// The most sectors a tree can be cut into.
pub const MAX_SECTORS: u32 = 64;

/// How a leaf mesh gets its levels of detail (Lua: `lod = { sectors = n, atlas = bool }`).
#[derive(Clone, Debug, PartialEq)]
pub struct LodOptions {
    /// Angular sectors around the tree's axis, each simplified on its own so a renderer can
    /// draw visible sectors finer (the thesis' ERA, seed 003 §2.5.2); 1..=64, default 1.
    pub sectors: u32,
    /// Texture collapsed leaves from a procedural atlas of leaf clusters embedded in the leaf
    /// material (default false: they stretch the single leaf texture, as the FSA did).
    pub atlas: bool,
    /// The collapse distance's weights and bounds, and the tree's axis.
    pub selection: Selection,
    /// Where the option was given (`FILE:LINE`, set by a Lua adapter) so that warnings point
    /// at it; empty when unknown.
    pub source: String,
}

impl Default for LodOptions {
    fn default() -> Self {
        LodOptions {
            sectors: 1,
            atlas: false,
            selection: Selection::default(),
            source: String::new(),
        }
    }
}

/// Why a leaf mesh could not be given levels of detail.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LodError {
    /// The mesh is not made of quads (four vertices per leaf, triangles).
    #[error("a leaf mesh must be triangles with four vertices per leaf, got {vertices} vertices")]
    NotQuads {
        /// Its vertex count.
        vertices: usize,
    },
    /// A leaf is degenerate (no area) or not finite.
    #[error("leaf {index} is degenerate or not finite")]
    Leaf {
        /// The leaf's index (0-based).
        index: usize,
    },
    /// `sectors` is outside 1..=64.
    #[error("sectors must be an integer between 1 and {MAX_SECTORS}, got {0}")]
    Sectors(u32),
    /// The atlas needs the leaf material's texture.
    #[error("atlas: the leaf material has no texture to draw clusters with")]
    NoTexture,
    /// The atlas texture could not be made.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The LOD table breaks an invariant (a bug of the simplification, reported rather than
    /// written).
    #[error(transparent)]
    Table(#[from] pge_engine::geometry::LodError),
    /// The run's time ran out while the leaves were simplified: the engine's
    /// [`pge_engine::Error::TimeLimit`] at the `lod` option's line.
    #[error("{0}")]
    Limit(Box<pge_engine::Error>),
}

impl LodError {
    /// The run's limit this error is, if it is one (a host passes it on typed).
    #[must_use]
    pub fn limit(&self) -> Option<&pge_engine::Error> {
        match self {
            LodError::Limit(e) => Some(e),
            _ => None,
        }
    }
}

/// `FILE:LINE` (an option's `source`) as a location.
fn location_of(source: &str) -> pge_engine::Location {
    match source.rsplit_once(':') {
        Some((file, line)) if line.parse::<u32>().is_ok() => {
            pge_engine::Location::new(file, line.parse().unwrap_or(0))
        }
        _ => pge_engine::Location {
            file: if source.is_empty() { "lod" } else { source }.to_string(),
            line: None,
        },
    }
}

/// One sector's part of V: its leaves are `offset..offset + table.order.len()` of the mesh,
/// and its table's ranges are relative to `offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sector {
    /// First leaf of the sector in the mesh (in leaves; six indices each).
    pub offset: u32,
    /// The sector's V and LOD table (labels are the sector's own).
    pub table: LodTable,
}

/// The leaves of a quad mesh as [`Leaf`]s (four vertices per leaf, in the order of
/// [`Leaf::corners`]), with the first vertex's normal when the mesh has normals.
pub fn leaves_of(mesh: &Mesh) -> Result<Vec<Leaf>, LodError> {
    let n = mesh.positions.len();
    if mesh.primitive != Primitive::Triangles || !n.is_multiple_of(4) {
        return Err(LodError::NotQuads { vertices: n });
    }
    (0..n / 4)
        .map(|k| {
            let p = [0, 1, 2, 3].map(|j| mesh.positions[4 * k + j]);
            Leaf::from_quad(p, mesh.normals.get(4 * k).copied()).ok_or(LodError::Leaf { index: k })
        })
        .collect()
}

/// The sector of a point: its angle around the axis, in `n` equal sectors.
fn sector_of(axis: &Axis, basis: (Vec3, Vec3), p: Vec3, n: u32) -> usize {
    let d = p - axis.origin;
    let angle = math::atan2(d.dot(basis.1), d.dot(basis.0)); // -pi..=pi
    let t = (angle + std::f32::consts::PI) / std::f32::consts::TAU;
    ((t * n as f32) as u32).min(n - 1) as usize
}

/// Simplifies `leaves` per sector: the sectors' collapse chains (labels local to each
/// sector) and, for each, the indices of its original leaves in `leaves`.
#[must_use]
pub fn simplify_sectors(leaves: &[Leaf], options: &LodOptions) -> Vec<(Chain, Vec<u32>)> {
    let n = options.sectors.clamp(1, MAX_SECTORS);
    let axis = options
        .selection
        .axis
        .unwrap_or_else(|| Axis::through_crown(leaves));
    let basis = axis.direction.any_orthonormal_pair();
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); n as usize];
    for (i, leaf) in leaves.iter().enumerate() {
        members[sector_of(&axis, basis, leaf.center, n)].push(i as u32);
    }
    let selection = Selection {
        axis: Some(axis),
        ..options.selection
    };
    members
        .into_iter()
        .map(|ids| {
            let own: Vec<Leaf> = ids.iter().map(|&i| leaves[i as usize]).collect();
            (simplify(&own, &selection), ids)
        })
        .collect()
}

/// Gives a leaf mesh levels of detail: its quads ([`leaves_of`]) are simplified per sector
/// ([`simplify_sectors`]), each sector laid out as V with its table ([`LodTable`]), and the
/// mesh rebuilt with four vertices per leaf of V in V's order (sectors one after another):
/// leaf `k` of the mesh is vertices `4k..4k + 4`, two triangles `(0 1 2) (0 2 3)`. The index
/// buffer holds those six indices for the finest level only (`V[0..|O|)` of each sector), so
/// a viewer that knows nothing of LOD draws exactly the original leaves; a LOD renderer
/// draws the leaves of a level's two ranges from the vertices. Original leaves
/// keep their vertices; a collapsed leaf gets its rectangle, its normal, the mean colour of
/// the leaves it stands for, and texture coordinates covering the whole leaf texture or,
/// with `options.atlas`, the atlas cell chosen by its count and density (the material then
/// carries the atlas, and the atlases of its normal and metallic-roughness maps where it had
/// them, and original leaves map into its single-leaf cell).
///
/// The mesh's [`Mesh::lod`] holds every sector's table ([`mesh_lod`]), each relative to its
/// offset (in leaves); the glTF writer writes it as `extras.pge.lod = {leaves = |O|, roots =
/// |R|, table = [[a, b, c], ...]}` (one sector) or `{leaves, roots, sectors = [{offset,
/// leaves, roots, table}, ...]}`.
pub fn lod_mesh(mesh: &Mesh, options: &LodOptions) -> Result<(Mesh, Vec<Sector>), LodError> {
    if !(1..=MAX_SECTORS).contains(&options.sectors) {
        return Err(LodError::Sectors(options.sectors));
    }
    let leaves = leaves_of(mesh)?;
    let atlas = if options.atlas {
        let m = &mesh.material;
        let texture = m.texture.as_ref().ok_or(LodError::NoTexture)?;
        Some(Atlas::with_maps(
            texture,
            m.normal_texture.as_deref(),
            m.metallic_roughness_texture.as_deref(),
        )?)
    } else {
        None
    };
    let sectors = simplify_sectors(&leaves, options);
    if let Some(d) = options.selection.deadline
        && pge_engine::clock::Instant::now() >= d
    {
        return Err(LodError::Limit(Box::new(pge_engine::Error::TimeLimit {
            location: location_of(&options.source),
        })));
    }
    let total: usize = sectors.iter().map(|(c, _)| c.leaves.len()).sum();
    let mut out = Mesh {
        name: mesh.name.clone(),
        material: match &atlas {
            // The atlases of the leaf's maps line up with the colour atlas' cells.
            Some(a) => Arc::new(Material {
                texture: Some(a.texture.clone()),
                normal_texture: a.normal.clone(),
                metallic_roughness_texture: a.roughness.clone(),
                // A masked leaf is masked with the cutoff chosen for the atlas.
                alpha: match mesh.material.alpha {
                    AlphaMode::Mask(_) => AlphaMode::Mask(a.alpha_cutoff),
                    other => other,
                },
                ..(*mesh.material).clone()
            }),
            None => mesh.material.clone(),
        },
        skeleton: mesh.skeleton.clone(),
        extras: mesh.extras.clone(),
        ..Mesh::default()
    };
    let (has_n, has_uv, has_c) = (
        !mesh.normals.is_empty(),
        !mesh.uvs.is_empty(),
        !mesh.colors.is_empty(),
    );
    // The cards' own tangents, kept per quad (the atlas maps `u` and `v` each onto a cell
    // without turning them), and a merged card's side where `u` grows, w = +1 (`cross(normal,
    // side)` is its axis, where `v` grows).
    let has_t = !mesh.positions.is_empty() && mesh.tangents.len() == mesh.positions.len();
    out.positions.reserve(total * 4);
    out.indices.reserve(total * 6);
    let mut result = Vec::with_capacity(sectors.len());
    let mut offset = 0u32;
    for (chain, ids) in &sectors {
        let table = LodTable::new(chain);
        let colors = has_c.then(|| chain_colors(chain, ids, &mesh.colors));
        for (position, &label) in table.order.iter().enumerate() {
            let base = out.positions.len() as u32;
            let l = label as usize;
            // The index buffer draws the finest level only: V[0..|O|) of each sector.
            if position < chain.originals {
                out.indices.extend_from_slice(&[
                    base,
                    base + 1,
                    base + 2,
                    base,
                    base + 2,
                    base + 3,
                ]);
            }
            if l < chain.originals {
                let v = 4 * ids[l] as usize;
                out.positions.extend_from_slice(&mesh.positions[v..v + 4]);
                if has_n {
                    out.normals.extend_from_slice(&mesh.normals[v..v + 4]);
                }
                if has_t {
                    out.tangents.extend_from_slice(&mesh.tangents[v..v + 4]);
                }
                if has_uv {
                    let uvs = &mesh.uvs[v..v + 4];
                    match &atlas {
                        Some(a) => out.uvs.extend(uvs.iter().map(|&uv| a.cells[0].map(uv))),
                        None => out.uvs.extend_from_slice(uvs),
                    }
                }
                if has_c {
                    out.colors.extend_from_slice(&mesh.colors[v..v + 4]);
                }
            } else {
                let leaf = &chain.leaves[l];
                out.positions.extend_from_slice(&leaf.corners());
                if has_n {
                    out.normals.extend_from_slice(&[leaf.normal; 4]);
                }
                if has_t {
                    let side = leaf.side().try_normalize().unwrap_or(leaf.axis);
                    out.tangents.extend_from_slice(&[side.extend(1.0); 4]);
                }
                if has_uv {
                    let (min, max) = match &atlas {
                        Some(a) => {
                            let cell = a.cell_for(leaf.count, leaf.leaf_area / leaf.area());
                            (cell.min, cell.max)
                        }
                        None => (Vec2::ZERO, Vec2::ONE),
                    };
                    out.uvs.extend_from_slice(&[
                        min,
                        Vec2::new(max.x, min.y),
                        max,
                        Vec2::new(min.x, max.y),
                    ]);
                }
                if let Some(c) = &colors {
                    out.colors.extend_from_slice(&[c[l]; 4]);
                }
            }
        }
        let len = table.order.len() as u32;
        result.push(Sector { offset, table });
        offset += len;
    }
    out.lod = Some(Arc::new(mesh_lod(&result)?));
    Ok((out, result))
}

/// Every leaf's colour: an original leaf's mean vertex colour, a new leaf's the mean of its
/// children's weighted by the leaves they stand for.
fn chain_colors(chain: &Chain, ids: &[u32], colors: &[Vec4]) -> Vec<Vec4> {
    let mut out = Vec::with_capacity(chain.leaves.len());
    for &i in ids {
        let v = 4 * i as usize;
        out.push(colors[v..v + 4].iter().copied().sum::<Vec4>() * 0.25);
    }
    for [a, b] in &chain.children {
        let (wa, wb) = (
            chain.leaves[*a as usize].count as f32,
            chain.leaves[*b as usize].count as f32,
        );
        out.push((out[*a as usize] * wa + out[*b as usize] * wb) / (wa + wb));
    }
    out
}

/// The levels of detail of a leaf mesh whose V is `sectors`, one after the other (see
/// [`lod_mesh`]): written by the glTF writer as the mesh's `extras.pge.lod`.
pub fn mesh_lod(sectors: &[Sector]) -> Result<MeshLod, LodError> {
    let sectors = sectors
        .iter()
        .map(|s| {
            let levels = s
                .table
                .rows
                .iter()
                .map(|r| LodLevel {
                    a: r.a,
                    b: r.b,
                    c: r.c,
                })
                .collect();
            LodSector::new(s.offset, s.table.originals, s.table.roots, levels)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(MeshLod::Leaves(pge_engine::geometry::LodTable::new(
        sectors,
    )?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::geometry::Texture;

    /// A ring of `n` small square leaves around the Y axis, facing outwards, coloured by
    /// index.
    fn ring(n: usize) -> Mesh {
        let mut mesh = Mesh::default();
        for i in 0..n {
            let t = i as f32 / n as f32 * std::f32::consts::TAU;
            let normal = Vec3::new(math::cos(t), 0.0, math::sin(t));
            let leaf = Leaf {
                center: normal * 3.0 + Vec3::Y * (2.0 + (i % 3) as f32 * 0.1),
                normal,
                axis: Vec3::Y,
                half_length: 0.2,
                half_width: 0.2,
                count: 1,
                leaf_area: 0.16,
                lo: Vec3::splat(-1.0),
                hi: Vec3::splat(1.0),
            };
            mesh.positions.extend_from_slice(&leaf.corners());
            mesh.normals.extend_from_slice(&[normal; 4]);
            mesh.uvs
                .extend_from_slice(&[Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
            mesh.colors
                .extend_from_slice(&[Vec4::new(i as f32 / n as f32, 0.5, 0.0, 1.0); 4]);
            let b = 4 * i as u32;
            mesh.indices
                .extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
        }
        mesh
    }

    #[test]
    fn cards_keep_their_tangents_and_merged_cards_run_along_their_side() {
        let mut mesh = ring(120);
        // Each card's side, where `u` grows (the ring's leaves: axis +Y, corners 0 to 1).
        mesh.tangents = (0..mesh.positions.len())
            .map(|v| {
                let q = 4 * (v / 4);
                (mesh.positions[q + 1] - mesh.positions[q])
                    .normalize()
                    .extend(1.0)
            })
            .collect();
        let (out, _) = lod_mesh(&mesh, &LodOptions::default()).expect("lod");
        out.validate().expect("valid");
        assert_eq!(out.tangents.len(), out.positions.len());
        for (v, t) in out.tangents.iter().enumerate() {
            let q = 4 * (v / 4);
            let side = (out.positions[q + 1] - out.positions[q]).normalize();
            assert!(
                (t.truncate() - side).length() < 1e-4,
                "vertex {v}: {t} vs {side}"
            );
            assert_eq!(t.w, 1.0);
            assert!(t.truncate().dot(out.normals[v]).abs() < 1e-4);
        }
        // Without tangents of its own, the mesh's are left to the export.
        let (out, _) = lod_mesh(&ring(120), &LodOptions::default()).expect("lod");
        assert!(out.tangents.is_empty());
    }

    #[test]
    fn the_mesh_is_written_in_the_order_of_v() {
        let mesh = ring(120);
        let (out, sectors) = lod_mesh(&mesh, &LodOptions::default()).expect("lod");
        out.validate().expect("valid");
        let table = &sectors[0].table;
        assert_eq!(out.positions.len(), 4 * table.order.len());
        assert!(table.roots < 60, "{} roots", table.roots);
        // The finest level draws the original quads, unchanged.
        let [first, second] = table.ranges(table.levels() - 1);
        assert_eq!((first.clone(), second.len()), (0..120, 0));
        let mut originals: Vec<[u32; 3]> = first
            .map(|k| {
                let p = out.positions[4 * k];
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
            })
            .collect();
        let mut expected: Vec<[u32; 3]> = (0..120)
            .map(|k| {
                let p = mesh.positions[4 * k];
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
            })
            .collect();
        originals.sort_unstable();
        expected.sort_unstable();
        assert_eq!(originals, expected);
        let lod = out.lod.as_deref().and_then(MeshLod::table).expect("table");
        assert_eq!(lod.leaves(), 120);
        assert_eq!(lod.roots(), table.roots);
        let first = lod.sectors()[0].levels()[0];
        assert_eq!(
            [first.a, first.b, first.c],
            [table.rows[0].a, table.rows[0].b, table.rows[0].c]
        );
        // The index buffer is the finest level: the first 120 leaves of V, in order.
        assert_eq!(out.indices.len(), 6 * 120);
        assert_eq!(&out.indices[6..12], &[4, 5, 6, 4, 6, 7]);
        assert_eq!(out.indices.iter().max(), Some(&(4 * 120 - 1)));
    }

    #[test]
    fn sectors_keep_their_leaves_apart() {
        let mesh = ring(96);
        let options = LodOptions {
            sectors: 4,
            ..LodOptions::default()
        };
        let (out, sectors) = lod_mesh(&mesh, &options).expect("lod");
        assert_eq!(sectors.len(), 4);
        let mut offset = 0;
        for s in &sectors {
            assert_eq!(s.offset, offset);
            offset += s.table.order.len() as u32;
            // Every leaf of a sector lies in its quarter of the ring.
            let dirs: Vec<Vec3> = (s.offset as usize..offset as usize)
                .map(|k| {
                    let c = (0..4).map(|j| out.positions[4 * k + j]).sum::<Vec3>();
                    Vec3::new(c.x, 0.0, c.z).normalize()
                })
                .collect();
            let mean = dirs.iter().sum::<Vec3>().normalize();
            for d in &dirs {
                assert!(d.dot(mean) > math::cos(std::f32::consts::FRAC_PI_4 + 0.1));
            }
        }
        assert_eq!(
            offset,
            2 * 96 - sectors.iter().map(|s| s.table.roots).sum::<u32>()
        );
        let lod = out.lod.as_deref().and_then(MeshLod::table).expect("table");
        assert_eq!(lod.sectors().len(), 4);
        assert_eq!(lod.leaves(), 96);
        // The index buffer draws each sector's original leaves, sector after sector.
        let finest: Vec<u32> = sectors
            .iter()
            .flat_map(|s| s.offset..s.offset + s.table.originals)
            .collect();
        let drawn: Vec<u32> = out.indices.chunks(6).map(|q| q[0] / 4).collect();
        assert_eq!(drawn, finest);
    }

    #[test]
    fn the_atlas_material_keeps_the_maps_the_leaf_had() {
        let square = |name: &str, px: [u8; 4]| {
            Arc::new(Texture::from_rgba(name, 8, 8, &px.repeat(64)).expect("png"))
        };
        let leaf = Material {
            texture: Some(square("color", [40, 120, 30, 255])),
            normal_texture: Some(square("normal", [150, 110, 240, 255])),
            metallic_roughness_texture: Some(square("roughness", [0, 140, 0, 255])),
            ..Material::default()
        };
        let options = LodOptions {
            atlas: true,
            ..LodOptions::default()
        };
        let mut mesh = ring(40);
        mesh.material = Arc::new(leaf.clone());
        let (out, _) = lod_mesh(&mesh, &options).expect("lod");
        let m = &out.material;
        let size = |t: &Option<Arc<Texture>>| t.as_ref().map(|t| (t.width, t.height));
        let atlas = Some((crate::ATLAS_SIZE, crate::ATLAS_SIZE));
        assert_eq!(size(&m.texture), atlas);
        assert_eq!(size(&m.normal_texture), atlas);
        assert_eq!(size(&m.metallic_roughness_texture), atlas);
        // A leaf without the maps gets none.
        mesh.material = Arc::new(Material {
            normal_texture: None,
            metallic_roughness_texture: None,
            ..leaf
        });
        let (out, _) = lod_mesh(&mesh, &options).expect("lod");
        assert_eq!(size(&out.material.texture), atlas);
        assert_eq!(out.material.normal_texture, None);
        assert_eq!(out.material.metallic_roughness_texture, None);
    }

    #[test]
    fn bad_meshes_and_options_are_errors() {
        let mut mesh = ring(3);
        let e = lod_mesh(
            &mesh,
            &LodOptions {
                sectors: 65,
                ..LodOptions::default()
            },
        )
        .expect_err("sectors");
        assert_eq!(
            e.to_string(),
            "sectors must be an integer between 1 and 64, got 65"
        );
        let atlas = LodOptions {
            atlas: true,
            ..LodOptions::default()
        };
        assert!(matches!(lod_mesh(&mesh, &atlas), Err(LodError::NoTexture)));
        mesh.positions.pop();
        assert!(matches!(
            leaves_of(&mesh),
            Err(LodError::NotQuads { vertices: 11 })
        ));
        let mut flat = ring(2);
        for p in &mut flat.positions[4..8] {
            *p = Vec3::ONE;
        }
        assert!(matches!(leaves_of(&flat), Err(LodError::Leaf { index: 1 })));
    }
}
