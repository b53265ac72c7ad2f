//! Tangents for normal-mapped meshes: MikkTSpace (the `bevy_mikktspace` crate), the tangent
//! space Blender, three.js and game engines bake and read normal maps in, so a glb that
//! carries it is lit alike everywhere instead of each client deriving its own.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::{Mesh, Primitive};

impl Mesh {
    /// Whether the mesh is drawn with a tangent space: its material has a normal map and it
    /// has triangles with normals and texture coordinates (one per vertex) to build it from.
    #[must_use]
    pub fn needs_tangents(&self) -> bool {
        let n = self.positions.len();
        self.material.normal_texture.is_some()
            && self.primitive == Primitive::Triangles
            && n > 0
            && self.normals.len() == n
            && self.uvs.len() == n
            && self.indices.len() >= 3
    }

    /// The tangent of every vertex, glTF's `TANGENT`: a unit `xyz` along the direction `u`
    /// grows in, and in `w` the sign (+1 or -1) of the bitangent (`cross(normal, tangent) *
    /// w` points where `v` grows). `None` when the mesh does not need one
    /// ([`Mesh::needs_tangents`]). The mesh's own [`Mesh::tangents`](Mesh#structfield.tangents)
    /// when it has one per vertex (its generator knows the surface, as the tree mesher's bark
    /// and leaf cards do: no triangle needs to be read), made unit with `w` exactly ±1;
    /// otherwise MikkTSpace's:
    ///
    /// The mesh is cut into its connected pieces (triangles sharing vertices), gathered in
    /// order into batches of at least [`TANGENT_BATCH`] triangles, and each batch is given
    /// to MikkTSpace on its own, the batches in parallel: a tangent depends only on the
    /// triangles around its vertex, which lie in its piece, and the batches depend only on
    /// the mesh, so the tangents are the same for any number of threads. Every tangent is
    /// finite, of unit length and with `w` exactly ±1, as the validator requires: a vertex
    /// MikkTSpace leaves without one (no triangle uses it, or every triangle it is in has
    /// no area in UV space) gets a unit vector across its normal.
    #[must_use]
    pub fn tangents(&self) -> Option<Vec<Vec4>> {
        if !self.needs_tangents() {
            return None;
        }
        let vertices = self.positions.len();
        if self.tangents.len() == vertices {
            return Some(
                self.tangents
                    .iter()
                    .zip(&self.normals)
                    .map(|(t, n)| usable(*t, *n))
                    .collect(),
            );
        }
        // Triangles with an index past the vertices (an invalid mesh, refused at export) are
        // left out, so nothing here reads out of bounds.
        let triangles: Vec<[u32; 3]> = self
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .filter(|t| t.iter().all(|&i| (i as usize) < vertices))
            .collect();
        let batches = batches(&triangles, vertices);
        let found: Vec<Vec<(u32, Vec4)>> = batches
            .par_iter()
            .map(|batch| self.batch_tangents(batch))
            .collect();
        let mut tangents = vec![Vec4::ZERO; vertices];
        for (v, t) in found.into_iter().flatten() {
            tangents[v as usize] = t;
        }
        Some(
            tangents
                .into_iter()
                .zip(&self.normals)
                .map(|(t, n)| usable(t, *n))
                .collect(),
        )
    }

    /// MikkTSpace over the triangles of one batch: each of their vertices and its tangent.
    fn batch_tangents(&self, triangles: &[[u32; 3]]) -> Vec<(u32, Vec4)> {
        // The batch's vertices, numbered from 0 in the order they are met.
        let mut local = std::collections::HashMap::new();
        let mut global = Vec::new();
        let triangles: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    *local.entry(v).or_insert_with(|| {
                        global.push(v);
                        global.len() as u32 - 1
                    })
                })
            })
            .collect();
        let pick = |v: &u32| *v as usize;
        let mut space = Space {
            positions: global.iter().map(|v| self.positions[pick(v)]).collect(),
            normals: global.iter().map(|v| self.normals[pick(v)]).collect(),
            uvs: global.iter().map(|v| self.uvs[pick(v)]).collect(),
            triangles: &triangles,
            tangents: vec![Vec4::ZERO; global.len()],
        };
        // Its error type has no values yet: were one added, every vertex would fall back.
        let _ = bevy_mikktspace::generate_tangents(&mut space);
        global.into_iter().zip(space.tangents).collect()
    }
}

/// Triangles of a batch given to MikkTSpace at once, at least (a batch ends with a piece).
pub const TANGENT_BATCH: usize = 2048;

/// The triangles cut into batches of whole connected pieces (triangles joined through
/// shared vertices), pieces in the order of their first triangle, each batch the pieces
/// that follow each other until it holds at least [`TANGENT_BATCH`] triangles.
fn batches(triangles: &[[u32; 3]], vertices: usize) -> Vec<Vec<[u32; 3]>> {
    // Union-find over the vertices, with path halving.
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for t in triangles {
        let mut a = root(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = root(&mut parent, v);
            let (lo, hi) = (a.min(b), a.max(b));
            parent[hi as usize] = lo;
            a = lo;
        }
    }
    // Pieces in the order of their first triangle.
    let mut piece_of_root = std::collections::HashMap::new();
    let mut pieces: Vec<Vec<[u32; 3]>> = Vec::new();
    for t in triangles {
        let r = root(&mut parent, t[0]);
        let k = *piece_of_root.entry(r).or_insert_with(|| {
            pieces.push(Vec::new());
            pieces.len() - 1
        });
        pieces[k].push(*t);
    }
    let mut out: Vec<Vec<[u32; 3]>> = Vec::new();
    for piece in pieces {
        match out.last_mut() {
            Some(batch) if batch.len() < TANGENT_BATCH => batch.extend(piece),
            _ => out.push(piece),
        }
    }
    out
}

/// `t` as glTF accepts a tangent: its `xyz` made unit and `w` ±1; when it has no direction,
/// a unit vector across the normal `n` (or any unit vector, for a zero normal).
fn usable(t: Vec4, n: Vec3) -> Vec4 {
    let w = if t.w < 0.0 { -1.0 } else { 1.0 };
    let xyz = t
        .truncate()
        .try_normalize()
        .or_else(|| n.try_normalize().map(|n| n.any_orthonormal_vector()))
        .unwrap_or(Vec3::X);
    xyz.extend(w)
}

/// A batch of a mesh as MikkTSpace reads it, and the tangents it writes.
struct Space<'a> {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    triangles: &'a [[u32; 3]],
    tangents: Vec<Vec4>,
}

impl Space<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.triangles[face][vert] as usize
    }
}

/// MikkTSpace's two scalar operations over [`crate::math`]: its default (`StdOps`) calls the
/// platform's `acos`, whose last bit differs between C libraries.
struct Ops;

impl bevy_mikktspace::Ops for Ops {
    fn sqrt(x: f32) -> f32 {
        x.sqrt()
    }

    fn acos(x: f32) -> f32 {
        // In f64 like the reference implementation (and `StdOps`).
        crate::math::acos(f64::from(x)) as f32
    }
}

impl bevy_mikktspace::Geometry<Ops> for Space<'_> {
    fn num_faces(&self) -> usize {
        self.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.vertex(face, vert)].to_array()
    }

    fn set_tangent(
        &mut self,
        tangent: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        let v = self.vertex(face, vert);
        // None (a degenerate face with no neighbour to borrow from) leaves the zero that
        // `usable` replaces.
        if let Some(t) = tangent {
            self.tangents[v] = Vec4::from_array(t.tangent_encoded());
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::geometry::{Material, Texture};

    /// A quad in the XY plane facing +Z, `u` along `u_axis`, `v` along +Y (or -Y when
    /// `flip`), with a normal-mapped material.
    fn quad(u_axis: Vec3, flip: bool) -> Mesh {
        let v = if flip { -1.0 } else { 1.0 };
        let normal = Texture::from_rgba("n", 1, 1, &[128, 128, 255, 255]).expect("png");
        Mesh {
            positions: vec![Vec3::ZERO, u_axis, u_axis + Vec3::Y, Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, v),
                Vec2::new(0.0, v),
            ],
            indices: if u_axis.x > 0.0 {
                vec![0, 1, 2, 0, 2, 3]
            } else {
                vec![0, 2, 1, 0, 3, 2]
            },
            material: Arc::new(Material {
                normal_texture: Some(Arc::new(normal)),
                ..Material::default()
            }),
            ..Mesh::default()
        }
    }

    fn approx(a: Vec4, b: Vec4) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    #[test]
    fn tangents_follow_u_and_carry_the_bitangent_sign() {
        let t = quad(Vec3::X, false).tangents().expect("normal-mapped");
        assert!(
            t.iter().all(|&t| approx(t, Vec4::new(1.0, 0.0, 0.0, 1.0))),
            "{t:?}"
        );
        // v running down instead: the bitangent's sign flips.
        let t = quad(Vec3::X, true).tangents().expect("normal-mapped");
        assert!(
            t.iter().all(|&t| approx(t, Vec4::new(1.0, 0.0, 0.0, -1.0))),
            "{t:?}"
        );
        // u running along -X: the tangent turns with it.
        let t = quad(-Vec3::X, false).tangents().expect("normal-mapped");
        assert!(
            t.iter()
                .all(|&t| approx(t, Vec4::new(-1.0, 0.0, 0.0, -1.0))),
            "{t:?}"
        );
    }

    /// `m` with `other`'s vertices and triangles after its own.
    fn joined(mut m: Mesh, other: &Mesh) -> Mesh {
        let base = m.positions.len() as u32;
        m.positions.extend(&other.positions);
        m.normals.extend(&other.normals);
        m.uvs.extend(&other.uvs);
        m.indices.extend(other.indices.iter().map(|i| i + base));
        m
    }

    #[test]
    fn each_piece_gets_the_tangents_it_has_alone_on_any_number_of_threads() {
        // Many separate quads, turned every way, and one ring of quads sharing vertices:
        // more triangles than a batch, so the pieces are spread over several.
        let pieces: Vec<Mesh> = (0..2500)
            .map(|k| {
                let mut q = quad(if k % 2 == 0 { Vec3::X } else { -Vec3::X }, k % 3 == 0);
                let turn = glam::Quat::from_rotation_y(k as f32 * 0.1);
                q.positions = q
                    .positions
                    .iter()
                    .map(|p| turn * *p + Vec3::Y * k as f32)
                    .collect();
                q.normals = q.normals.iter().map(|n| turn * *n).collect();
                q
            })
            .collect();
        let mut all = pieces[0].clone();
        for p in &pieces[1..] {
            all = joined(all, p);
        }
        assert!(all.indices.len() / 3 > 2 * TANGENT_BATCH);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool")
                .install(|| all.tangents().expect("normal-mapped"))
        };
        let one = on(1);
        assert_eq!(on(3), one);
        for (k, piece) in pieces.iter().enumerate() {
            let alone = piece.tangents().expect("normal-mapped");
            assert_eq!(one[4 * k..4 * k + 4], alone[..], "piece {k}");
        }
    }

    #[test]
    fn a_mesh_s_own_tangents_are_used_when_it_has_one_per_vertex() {
        let mut m = quad(Vec3::X, false);
        let own = Vec4::new(0.0, 2.0, 0.0, -3.0);
        m.tangents = vec![own; 4];
        m.validate().expect("valid");
        let t = m.tangents().expect("normal-mapped");
        assert_eq!(t, vec![Vec4::new(0.0, 1.0, 0.0, -1.0); 4], "unit, w = -1");
        // One short: MikkTSpace's.
        m.tangents.pop();
        m.validate().expect("left out, still valid");
        assert_eq!(m.tangents(), quad(Vec3::X, false).tangents());
        // Appended: kept when both sides have theirs, dropped otherwise.
        let mut a = quad(Vec3::X, false);
        a.tangents = vec![own; 4];
        let b = a.clone();
        a.append(&b);
        assert_eq!(a.tangents, vec![own; 8]);
        a.append(&quad(Vec3::X, false));
        assert!(a.tangents.is_empty());
        let mut nan = quad(Vec3::X, false);
        nan.tangents = vec![Vec4::NAN; 4];
        assert!(nan.validate().is_err());
    }

    #[test]
    fn only_normal_mapped_triangles_with_normals_and_uvs_get_tangents() {
        let plain = Mesh {
            material: Arc::new(Material::default()),
            ..quad(Vec3::X, false)
        };
        assert_eq!(plain.tangents(), None, "no normal map");
        let mut no_uvs = quad(Vec3::X, false);
        no_uvs.uvs.clear();
        assert_eq!(no_uvs.tangents(), None);
        let mut lines = quad(Vec3::X, false);
        lines.primitive = Primitive::Lines;
        lines.indices = vec![0, 1];
        assert_eq!(lines.tangents(), None);
    }

    #[test]
    fn degenerate_and_unused_vertices_get_a_unit_tangent_across_their_normal() {
        let mut m = quad(Vec3::X, false);
        // A fifth vertex no triangle uses, and a triangle with no area in UV space.
        m.positions
            .extend([Vec3::Z, Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)]);
        m.normals.extend([Vec3::Y, Vec3::Z, Vec3::Z]);
        m.uvs.extend([Vec2::ZERO, Vec2::ONE, Vec2::ONE]);
        m.indices.extend([1, 5, 6]);
        let t = m.tangents().expect("normal-mapped");
        assert_eq!(t.len(), 7);
        for (t, n) in t.iter().zip(&m.normals) {
            assert!((t.truncate().length() - 1.0).abs() < 1e-5, "{t}");
            assert!(t.w == 1.0 || t.w == -1.0, "{t}");
            assert!(t.is_finite());
            if *n == Vec3::Y {
                assert!(t.truncate().dot(*n).abs() < 1e-5, "across the normal: {t}");
            }
        }
        assert_eq!(m.tangents(), Some(t), "deterministic");
    }
}
