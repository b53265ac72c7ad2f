use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::{Material, MeshLod, SearchMemory, Skeleton, triangles};

/// Elements a thread checks at a time when a mesh is validated.
const CHECK_CHUNK: usize = 1 << 15;

/// Fewest elements checked on the rayon pool: fewer take less time than handing them to
/// another thread (tens of microseconds, more on a loaded machine), and are checked on the
/// calling thread.
const CHECK_IN_PARALLEL: usize = 8 * CHECK_CHUNK;

/// Why a mesh, a texture or a colour was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeometryError {
    /// An attribute array does not have one entry per vertex.
    #[error("{attribute} has {got} entries but there are {vertices} vertices")]
    AttributeLength {
        /// Which attribute (`normals`, `uvs`, `colors`).
        attribute: &'static str,
        /// Entries found.
        got: usize,
        /// Vertices in the mesh.
        vertices: usize,
    },
    /// The index count is not a multiple of the primitive size.
    #[error("{count} indices is not a multiple of {per} ({primitive})")]
    IndexCount {
        /// Number of indices.
        count: usize,
        /// Indices per primitive.
        per: usize,
        /// Primitive name.
        primitive: &'static str,
    },
    /// An index points past the last vertex.
    #[error("index {index} at position {at} is out of range (the mesh has {vertices} vertices)")]
    IndexOutOfRange {
        /// The offending index value.
        index: u32,
        /// Its position in the index array.
        at: usize,
        /// Vertex count.
        vertices: usize,
    },
    /// A position, normal, uv or colour is NaN or infinite.
    #[error("{attribute}[{at}] is not a finite number")]
    NotFinite {
        /// Which attribute.
        attribute: &'static str,
        /// Vertex index.
        at: usize,
    },
    /// A colour string could not be parsed.
    #[error("'{0}' is not a colour: expected \"#rrggbb\" or \"#rrggbbaa\"")]
    Color(String),
    /// A texture could not be encoded or decoded.
    #[error("texture: {0}")]
    Texture(String),
}

/// How the indices of a mesh are grouped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Primitive {
    /// Three indices per triangle, counter-clockwise front faces.
    #[default]
    Triangles,
    /// Two indices per line segment.
    Lines,
}

impl Primitive {
    /// Indices per primitive.
    #[must_use]
    pub fn arity(self) -> usize {
        match self {
            Primitive::Triangles => 3,
            Primitive::Lines => 2,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Primitive::Triangles => "triangles",
            Primitive::Lines => "lines",
        }
    }
}

/// An indexed mesh with per-vertex attributes.
///
/// `normals`, `uvs` and `colors` are either empty (absent) or have one entry per position;
/// `tangents` too, or any other length, which leaves them out.
/// Builders fill the fields directly; [`Mesh::validate`] checks the invariants and the
/// exporters refuse a mesh that fails it.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mesh {
    /// Name written to the glTF mesh.
    pub name: String,
    /// Triangles or lines.
    pub primitive: Primitive,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit normals (empty for none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates (empty for none).
    pub uvs: Vec<Vec2>,
    /// Linear RGBA vertex colours (empty for none).
    pub colors: Vec<Vec4>,
    /// The tangent space its generator knows, glTF's `TANGENT`: per vertex a unit `xyz`
    /// along the direction `u` grows in (across the normal) and in `w` the bitangent's sign
    /// (±1), as [`Mesh::tangents()`] describes. Empty for none; only one per vertex is used
    /// (otherwise [`Mesh::tangents()`] derives them with MikkTSpace), so code that adds
    /// vertices without tangents may leave it short.
    pub tangents: Vec<Vec4>,
    /// u32 indices into the vertex arrays.
    pub indices: Vec<u32>,
    /// The material, shared between meshes that use the same one.
    #[serde(with = "super::binary::shared")]
    pub material: Arc<Material>,
    /// The branch graph this mesh was grown from, if any (written to its glTF extras).
    #[serde(with = "super::binary::shared_option")]
    pub skeleton: Option<Arc<Skeleton>>,
    /// The foliage levels of detail of a leaf mesh written in the order of V, or of a
    /// group's leaf primitives (written to its glTF extras as `lod`).
    #[serde(with = "super::binary::shared_option")]
    pub lod: Option<Arc<MeshLod>>,
    /// Application data written under the mesh's `extras.pge`.
    #[serde(with = "super::binary::json_text")]
    pub extras: serde_json::Map<String, serde_json::Value>,
}

impl Mesh {
    /// A triangle mesh from positions and indices, with smooth normals computed.
    pub fn from_triangles(positions: Vec<Vec3>, indices: Vec<u32>) -> Result<Mesh, GeometryError> {
        let mut mesh = Mesh {
            positions,
            indices,
            ..Mesh::default()
        };
        mesh.validate()?;
        mesh.compute_normals();
        Ok(mesh)
    }

    /// The bytes its vertex arrays and indices hold (what a script that keeps it is charged,
    /// [`crate::Budget`]); its material's textures and its skeleton are counted apart.
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.positions.as_slice())
            + size_of_val(self.normals.as_slice())
            + size_of_val(self.uvs.as_slice())
            + size_of_val(self.colors.as_slice())
            + size_of_val(self.tangents.as_slice())
            + size_of_val(self.indices.as_slice())
    }

    /// Number of vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles (0 for a line mesh).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        match self.primitive {
            Primitive::Triangles => self.indices.len() / 3,
            Primitive::Lines => 0,
        }
    }

    /// Checks attribute lengths, index ranges and that every number is finite.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let n = self.positions.len();
        for (attribute, got) in [
            ("normals", self.normals.len()),
            ("uvs", self.uvs.len()),
            ("colors", self.colors.len()),
        ] {
            if got != 0 && got != n {
                return Err(GeometryError::AttributeLength {
                    attribute,
                    got,
                    vertices: n,
                });
            }
        }
        let per = self.primitive.arity();
        if !self.indices.len().is_multiple_of(per) {
            return Err(GeometryError::IndexCount {
                count: self.indices.len(),
                per,
                primitive: self.primitive.name(),
            });
        }
        // The largest index first (a loop without early exit, vectorized), the culprit only
        // when there is one.
        let most = |c: &[u32]| c.iter().copied().max().unwrap_or(0);
        let largest = if self.indices.len() < CHECK_IN_PARALLEL {
            most(&self.indices)
        } else {
            self.indices
                .par_chunks(CHECK_CHUNK)
                .map(most)
                .max()
                .unwrap_or(0)
        };
        if let Some((at, &index)) = (largest as usize >= n)
            .then(|| {
                self.indices
                    .iter()
                    .enumerate()
                    .find(|(_, i)| **i as usize >= n)
            })
            .flatten()
        {
            return Err(GeometryError::IndexOutOfRange {
                index,
                at,
                vertices: n,
            });
        }
        // All finite first (without early exit, vectorized, in parallel pieces), the culprit
        // only when not.
        // The vectors as one run of floats, checked without a branch per float.
        fn check<T: bytemuck::Pod>(attribute: &'static str, v: &[T]) -> Result<(), GeometryError> {
            let floats: &[f32] = bytemuck::cast_slice(v);
            let finite = |c: &[f32]| c.iter().fold(true, |all, x| all & x.is_finite());
            let all = if floats.len() < CHECK_IN_PARALLEL {
                finite(floats)
            } else {
                floats.par_chunks(CHECK_CHUNK).all(finite)
            };
            if all {
                return Ok(());
            }
            let per = floats.len() / v.len().max(1);
            let at = floats
                .iter()
                .position(|x| !x.is_finite())
                .unwrap_or_default()
                / per.max(1);
            Err(GeometryError::NotFinite { attribute, at })
        }
        check("positions", &self.positions)?;
        check("normals", &self.normals)?;
        check("uvs", &self.uvs)?;
        check("colors", &self.colors)?;
        if self.tangents.len() == n {
            check("tangents", &self.tangents)?;
        }
        Ok(())
    }

    /// Replaces the normals by area-weighted vertex normals of the triangles.
    ///
    /// A vertex used by no triangle (or only degenerate ones) gets `+Y`.
    pub fn compute_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        if self.primitive == Primitive::Triangles {
            for tri in self.indices.chunks_exact(3) {
                let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                let n = (self.positions[b] - self.positions[a])
                    .cross(self.positions[c] - self.positions[a]);
                normals[a] += n;
                normals[b] += n;
                normals[c] += n;
            }
        }
        for n in &mut normals {
            *n = n.try_normalize().unwrap_or(Vec3::Y);
        }
        self.normals = normals;
    }

    /// Appends another mesh's geometry (its material and skeleton are ignored).
    ///
    /// Attributes present in only one of the two are filled with defaults for the other
    /// (normal `+Y`, uv `0`, colour white) so the result stays valid. Tangents are kept
    /// when both have one per vertex, and dropped otherwise (then [`Mesh::tangents()`] derives
    /// them).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        let (n_self, n_other) = (self.positions.len(), other.positions.len());
        if self.tangents.len() == n_self && other.tangents.len() == n_other {
            self.tangents.extend_from_slice(&other.tangents);
        } else {
            self.tangents.clear();
        }
        fill_attribute(&mut self.normals, &other.normals, n_self, n_other, Vec3::Y);
        fill_attribute(&mut self.uvs, &other.uvs, n_self, n_other, Vec2::ZERO);
        fill_attribute(&mut self.colors, &other.colors, n_self, n_other, Vec4::ONE);
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Removes the triangles no client can use: degenerate ones (two corners at the same
    /// place, or all three on a line: zero area, such as those closing a pointed tip) and
    /// repeats of an earlier triangle (the same three corner positions in the same turning
    /// order; a back face, the same corners turned the other way, is kept). Returns how many
    /// were removed. Vertices are left as they are, and so are line meshes, meshes with
    /// levels of detail (their tables count indices) and meshes with `extras` (which may
    /// describe their index buffer).
    pub fn remove_unusable_triangles(&mut self) -> usize {
        let dropped = self.unusable_triangles();
        self.remove_triangles(&dropped);
        dropped.len()
    }

    /// Whether [`Mesh::remove_unusable_triangles`] would remove anything.
    #[must_use]
    pub fn has_unusable_triangles(&self) -> bool {
        !self.unusable_triangles().is_empty()
    }

    /// The triangles (numbered from 0) that [`Mesh::remove_unusable_triangles`] removes, in
    /// increasing order; found in parallel on the current rayon pool, the same for any
    /// number of threads.
    #[must_use]
    pub fn unusable_triangles(&self) -> Vec<usize> {
        self.unusable_triangles_in(SearchMemory::default())
    }

    /// [`Mesh::unusable_triangles`], searched in `memory` (made resident ahead) when the
    /// mesh is small enough to be searched in one pass and it has room.
    #[must_use]
    pub fn unusable_triangles_in(&self, memory: SearchMemory) -> Vec<usize> {
        if !self.may_drop_triangles() {
            return Vec::new();
        }
        triangles::unusable(&self.positions, &self.indices, memory)
    }

    /// Whether the mesh has no unusable triangle (none that
    /// [`Mesh::remove_unusable_triangles`] would remove), shown without searching for
    /// repeats, for a generator whose triangles are distinct by construction: no two have
    /// the same three corners (as vertex numbers, whatever the turning order) once each
    /// vertex of a pair in `twins` is taken as the other. It checks that no triangle is
    /// degenerate and that no two vertices share a position except the pairs of `twins`
    /// (`(vertex, other)` in increasing order of `vertex`, e.g. a tube's seam vertex and the
    /// first of its ring). `false` when that does not hold: then search.
    #[must_use]
    pub fn usable_by_construction(&self, twins: &[(u32, u32)]) -> bool {
        !self.may_drop_triangles()
            || triangles::usable_by_construction(&self.positions, &self.indices, twins)
    }

    /// The half of [`Mesh::usable_by_construction`] left to a generator that ran each
    /// triangle it wrote through a [`DegenerateTest`](super::DegenerateTest) as it wrote it and found none
    /// degenerate: whether no two vertices share a position except the pairs of `twins` (as
    /// there). Then the mesh has no unusable triangle.
    #[must_use]
    pub fn distinct_positions(&self, twins: &[(u32, u32)]) -> bool {
        triangles::distinct_positions(&self.positions, twins)
    }

    /// Removes the triangles listed in `dropped` (numbers from 0, in increasing order, as
    /// [`Mesh::unusable_triangles`] gives them; a number out of order or past the last
    /// triangle is ignored).
    pub fn remove_triangles(&mut self, dropped: &[usize]) {
        if !dropped.is_empty() {
            self.indices = triangles::without(&self.indices, dropped);
        }
    }

    fn may_drop_triangles(&self) -> bool {
        self.primitive == Primitive::Triangles && self.lod.is_none() && self.extras.is_empty()
    }

    /// The axis-aligned bounds `(min, max)`, or `None` for an empty mesh.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}

/// A triangle's corner positions as bits, rotated to start at the smallest (the same for
/// the same triangle whichever corner its indices start at), or `None` when it is degenerate:
/// its area is below a millionth of its longest edge squared (coincident or collinear
/// corners). Indices must be in range (validated meshes).
fn fill_attribute<T: Copy>(
    mine: &mut Vec<T>,
    theirs: &[T],
    n_mine: usize,
    n_theirs: usize,
    default: T,
) {
    if mine.is_empty() && theirs.is_empty() {
        return;
    }
    if mine.is_empty() {
        mine.resize(n_mine, default);
    }
    if theirs.is_empty() {
        mine.extend(std::iter::repeat_n(default, n_theirs));
    } else {
        mine.extend_from_slice(theirs);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh::from_triangles(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(0.0, 0.0, -1.0),
            ],
            vec![0, 1, 2, 0, 2, 3],
        )
        .expect("valid quad")
    }

    #[test]
    fn normals_of_a_flat_quad_point_up() {
        let q = quad();
        assert!(q.normals.iter().all(|n| (*n - Vec3::Y).length() < 1e-6));
        assert_eq!(q.triangle_count(), 2);
    }

    #[test]
    fn validation_names_the_problem() {
        let mut q = quad();
        q.indices[4] = 9;
        assert_eq!(
            q.validate(),
            Err(GeometryError::IndexOutOfRange {
                index: 9,
                at: 4,
                vertices: 4
            })
        );
        let mut q = quad();
        q.uvs = vec![Vec2::ZERO; 3];
        assert!(matches!(
            q.validate(),
            Err(GeometryError::AttributeLength {
                attribute: "uvs",
                ..
            })
        ));
        let mut q = quad();
        q.indices.pop();
        assert!(matches!(
            q.validate(),
            Err(GeometryError::IndexCount { .. })
        ));
        let mut q = quad();
        q.positions[1].x = f32::NAN;
        assert!(matches!(
            q.validate(),
            Err(GeometryError::NotFinite {
                attribute: "positions",
                at: 1
            })
        ));
        // The culprit's vertex, not its float, in a run long enough to be checked in
        // parallel pieces.
        let mut big = quad();
        big.colors = vec![Vec4::ONE; CHECK_IN_PARALLEL];
        big.positions = vec![Vec3::ZERO; CHECK_IN_PARALLEL];
        big.normals.clear();
        big.uvs.clear();
        big.colors[CHECK_IN_PARALLEL - 3].w = f32::INFINITY;
        assert!(matches!(
            big.validate(),
            Err(GeometryError::NotFinite {
                attribute: "colors",
                at
            }) if at == CHECK_IN_PARALLEL - 3
        ));
    }

    #[test]
    fn degenerate_and_repeated_triangles_are_removed_back_faces_kept() {
        let mut m = quad();
        let n = m.positions.len() as u32;
        // A tip: two corners at the same place (a copy of vertex 1).
        m.positions.push(Vec3::X);
        // A sliver with all three corners on a line.
        m.positions.push(Vec3::new(2.0, 0.0, 0.0));
        m.normals.extend([Vec3::Y; 2]);
        m.indices.extend([0, 1, n]); // coincident corners
        m.indices.extend([0, 1, n + 1]); // collinear
        m.indices.extend([1, 1, 2]); // a repeated index
        m.indices.extend([2, 0, 1]); // the first triangle, rotated
        m.indices.extend([2, 3, 0]); // the second, rotated, through another start
        m.indices.extend([0, 2, 1]); // the first one's back face: kept
        m.validate().expect("valid");
        assert!(m.has_unusable_triangles());
        assert_eq!(m.remove_unusable_triangles(), 5);
        assert_eq!(m.indices, [0, 1, 2, 0, 2, 3, 0, 2, 1]);
        assert!(!m.has_unusable_triangles());
        assert_eq!(m.remove_unusable_triangles(), 0);
        // A mesh whose levels of detail or extras count indices is left alone.
        let mut lod = quad();
        lod.indices.extend([0, 1, 2]);
        let level = |a, b, c| crate::geometry::LodLevel { a, b, c };
        let sector = crate::geometry::LodSector::new(0, 1, 1, vec![level(1, 1, 0)]);
        let table = crate::geometry::LodTable::new(vec![sector.expect("sector")]);
        lod.lod = Some(Arc::new(MeshLod::Leaves(table.expect("table"))));
        assert!(!lod.has_unusable_triangles());
        assert_eq!(lod.remove_unusable_triangles(), 0);
        assert_eq!(lod.indices.len(), 9);
        let mut extras = quad();
        extras.indices.extend([0, 1, 2]);
        extras.extras.insert("mine".into(), serde_json::json!({}));
        assert_eq!(extras.remove_unusable_triangles(), 0);
    }

    #[test]
    fn append_offsets_indices_and_fills_missing_attributes() {
        let mut a = quad();
        let mut b = quad();
        b.uvs = vec![Vec2::ONE; 4];
        a.append(&b);
        assert_eq!(a.positions.len(), 8);
        assert_eq!(&a.indices[6..], &[4, 5, 6, 4, 6, 7]);
        assert_eq!(a.uvs.len(), 8);
        assert_eq!(a.uvs[0], Vec2::ZERO);
        a.validate().expect("still valid");
    }
}
