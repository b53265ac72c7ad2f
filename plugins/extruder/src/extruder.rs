//! [`Extruder`]: a 2D shape in the XZ plane swept along the path matrix's +Y axis. This file
//! is the modeller's state (shape, matrices, open pieces, the push/pop stack); `tube.rs`
//! meshes the rings it placed.

use pge_engine::math;
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{Material, Mesh};

use crate::matrix::{MatrixError, MatrixManipulator};
use crate::tube::{Piece, Ring, TubeStyle, build_mesh, centroid};

/// The most points a shape may have.
pub const MAX_SHAPE_POINTS: usize = 1 << 16;

/// The deepest `push` nesting of an extruder.
pub const MAX_STATE_DEPTH: usize = 1 << 16;

/// Why an extruder operation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExtruderError {
    /// `extrude` was called with fewer than 3 shape points.
    #[error("the shape has {got} point(s); extruding needs at least 3 (addPoint2/addPoint3)")]
    TooFewPoints {
        /// Points in the shape.
        got: usize,
    },
    /// The shape grew past [`MAX_SHAPE_POINTS`].
    #[error("the shape has more than {MAX_SHAPE_POINTS} points")]
    TooManyPoints,
    /// `extrude` got a negative distance.
    #[error("extrusion distance {0} is negative")]
    NegativeDistance(f32),
    /// A point or distance was NaN or infinite.
    #[error("{0} is not a finite number")]
    NotFinite(&'static str),
    /// `pop` without a matching `push`.
    #[error("pop without a matching push: the extruder's state stack is empty")]
    PopWithoutPush,
    /// `push` nested deeper than [`MAX_STATE_DEPTH`].
    #[error(
        "the extruder's state stack is deeper than {MAX_STATE_DEPTH} (a push without pop in a loop?)"
    )]
    StackOverflow,
    /// The geometry would grow past [`ExtruderOptions::max_points`].
    #[error("the extrusion has more than {0} ring points, past the memory limit; extrude less")]
    TooLarge(usize),
    /// An operation of the path or shape matrix failed.
    #[error(transparent)]
    Matrix(#[from] MatrixError),
}

/// How an [`Extruder`] builds its mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtruderOptions {
    /// Smooth normals (averaged around the tube) instead of one normal per quad. Default
    /// `false`: buildings and crystals are faceted.
    pub smooth: bool,
    /// Close both ends of every piece with a polygon. Default `true`.
    pub caps: bool,
    /// The mesh's material.
    pub material: Arc<Material>,
    /// The most ring points the extruder stores (a memory budget); `extrude` past it is
    /// an error. Default: unlimited.
    pub max_points: usize,
}

impl Default for ExtruderOptions {
    fn default() -> Self {
        ExtruderOptions {
            smooth: false,
            caps: true,
            material: Arc::new(Material::default()),
            max_points: usize::MAX,
        }
    }
}

/// What `push` saves and `pop` restores.
#[derive(Clone, Debug)]
struct Saved {
    path: Mat4,
    shape_matrix: Mat4,
    shape: Vec<Vec3>,
    color: Vec4,
}

/// The thesis' extrusion modeller.
///
/// A *shape* (a closed polygon given by points in the local XZ plane) is placed by the
/// *shape matrix* (in the section's own frame) and then by the *path matrix* (in the world):
/// a shape point `s` lands at `path * shape_matrix * s`. [`Extruder::extrude`] places a ring
/// there, moves the path `distance` along its local +Y axis and places another ring; rings of
/// consecutive extrusions are joined into one tube (a *piece*), so rotating the path between
/// extrusions bends the tube and scaling the shape matrix tapers it.
///
/// A piece ends (and gets its caps) at [`Extruder::finish`], [`Extruder::start`], a `pop`, or
/// when the shape's point count changes. [`Extruder::push`] saves the path, the shape, its
/// matrix and the colour and opens a new piece (a branch); [`Extruder::pop`] closes the branch
/// and resumes the piece that was open at the `push`.
///
/// # Mesh size
/// A piece of `r` rings of an `n`-point shape gives `2n(r-1)` side triangles plus `n - 2` per
/// cap. Vertices: smooth normals share them, `(n+1) r` (one duplicated for the texture seam);
/// flat normals give each quad its own four, `4n(r-1)`; each cap adds `n`. A cap whose ring
/// has collapsed to a point (shape scaled to zero: a spire) is left out.
///
/// # Texture coordinates
/// `u` runs from 0 to 1 around the shape's perimeter, `v` is the distance along the path
/// divided by the perimeter of the piece's first ring (so a square texture is not stretched);
/// caps map the shape's local bounding box to the unit square.
///
/// ```
/// use pge_extruder::{Extruder, ExtruderOptions};
/// use glam::Vec2;
///
/// let mut e = Extruder::new(ExtruderOptions::default());
/// for p in [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)] {
///     e.add_point2(Vec2::new(p.0, p.1)).unwrap();
/// }
/// e.extrude(2.0).unwrap();
/// e.extrude(1.0).unwrap();
/// let mesh = e.mesh();
/// assert_eq!(mesh.triangle_count(), 2 * 4 * 2 + 2 * 2);
/// ```
#[derive(Clone, Debug)]
pub struct Extruder {
    options: ExtruderOptions,
    shape: Vec<Vec3>,
    path: MatrixManipulator,
    shape_matrix: MatrixManipulator,
    color: Vec4,
    colored: bool,
    /// Open pieces: the last is the one extrusions extend; `push` adds one.
    open: Vec<Piece>,
    saved: Vec<Saved>,
    done: Vec<Piece>,
    /// Ring points stored so far (for memory budgets).
    stored: usize,
}

impl Extruder {
    /// An extruder with an empty shape, identity matrices and nothing built.
    #[must_use]
    pub fn new(options: ExtruderOptions) -> Extruder {
        Extruder {
            options,
            shape: Vec::new(),
            path: MatrixManipulator::new(),
            shape_matrix: MatrixManipulator::new(),
            color: Vec4::ONE,
            colored: false,
            open: vec![Piece::default()],
            saved: Vec::new(),
            done: Vec::new(),
            stored: 0,
        }
    }

    /// The options it builds with.
    #[must_use]
    pub fn options(&self) -> &ExtruderOptions {
        &self.options
    }

    /// Empties the current shape.
    pub fn clear_shape(&mut self) {
        self.shape.clear();
    }

    /// Adds a point in the local XZ plane (`(x, z)`).
    pub fn add_point2(&mut self, p: Vec2) -> Result<(), ExtruderError> {
        self.add_point3(Vec3::new(p.x, 0.0, p.y))
    }

    /// Adds a point in 3D (the shape need not be planar).
    pub fn add_point3(&mut self, p: Vec3) -> Result<(), ExtruderError> {
        if !p.is_finite() {
            return Err(ExtruderError::NotFinite("shape point"));
        }
        if self.shape.len() >= MAX_SHAPE_POINTS {
            return Err(ExtruderError::TooManyPoints);
        }
        self.shape.push(p);
        Ok(())
    }

    /// Replaces the shape by a regular polygon of `sides` points and circumradius `radius`
    /// in the XZ plane, counter-clockwise seen from +Y.
    pub fn set_polygon(&mut self, sides: usize, radius: f32) -> Result<(), ExtruderError> {
        if sides < 3 {
            return Err(ExtruderError::TooFewPoints { got: sides });
        }
        if sides > MAX_SHAPE_POINTS {
            return Err(ExtruderError::TooManyPoints);
        }
        if !radius.is_finite() {
            return Err(ExtruderError::NotFinite("radius"));
        }
        self.shape = (0..sides)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / sides as f32;
                Vec3::new(radius * math::cos(a), 0.0, -radius * math::sin(a))
            })
            .collect();
        Ok(())
    }

    /// The current shape's points.
    #[must_use]
    pub fn shape(&self) -> &[Vec3] {
        &self.shape
    }

    /// The path matrix (places the section in the world).
    #[must_use]
    pub fn path(&self) -> &MatrixManipulator {
        &self.path
    }

    /// The path matrix, to change.
    pub fn path_mut(&mut self) -> &mut MatrixManipulator {
        &mut self.path
    }

    /// The shape matrix (transforms the shape in the section's frame).
    #[must_use]
    pub fn shape_matrix(&self) -> &MatrixManipulator {
        &self.shape_matrix
    }

    /// The shape matrix, to change.
    pub fn shape_matrix_mut(&mut self) -> &mut MatrixManipulator {
        &mut self.shape_matrix
    }

    /// Sets the vertex colour (linear RGBA) of the rings placed from now on. Once a colour
    /// is set the mesh carries vertex colours (white where none was set).
    pub fn set_color(&mut self, color: Vec4) -> Result<(), ExtruderError> {
        if !color.is_finite() {
            return Err(ExtruderError::NotFinite("colour"));
        }
        self.color = color;
        self.colored = true;
        Ok(())
    }

    /// Ends the current piece (capping it) so the next extrusion starts a new one.
    pub fn start(&mut self) {
        self.close_top();
    }

    /// Ends the current piece, computing its caps; the same as [`Extruder::start`] but named
    /// for the end of an object.
    pub fn finish(&mut self) {
        self.close_top();
    }

    fn close_top(&mut self) {
        if let Some(top) = self.open.last_mut() {
            let piece = std::mem::take(top);
            if piece.rings.len() >= 2 {
                self.done.push(piece);
            }
        }
    }

    /// Saves the state (path and shape matrices, shape, colour) and opens a new piece.
    pub fn push(&mut self) -> Result<(), ExtruderError> {
        if self.saved.len() >= MAX_STATE_DEPTH {
            return Err(ExtruderError::StackOverflow);
        }
        self.saved.push(Saved {
            path: self.path.matrix(),
            shape_matrix: self.shape_matrix.matrix(),
            shape: self.shape.clone(),
            color: self.color,
        });
        self.open.push(Piece::default());
        Ok(())
    }

    /// Closes the piece opened by the last `push` and restores the state saved there.
    pub fn pop(&mut self) -> Result<(), ExtruderError> {
        let saved = self.saved.pop().ok_or(ExtruderError::PopWithoutPush)?;
        self.close_top();
        self.open.pop();
        self.path.set_matrix(saved.path)?;
        self.shape_matrix.set_matrix(saved.shape_matrix)?;
        self.shape = saved.shape;
        self.color = saved.color;
        Ok(())
    }

    /// Number of `push`es not yet popped.
    #[must_use]
    pub fn depth(&self) -> usize {
        self.saved.len()
    }

    /// Extrudes the shape `distance` along the path's local +Y axis.
    ///
    /// Places a ring at the current frame when the piece has none, advances the path and
    /// places a ring at the new frame. A distance of 0 is allowed (a step in the section,
    /// e.g. a ledge made by scaling the shape between two extrusions).
    pub fn extrude(&mut self, distance: f32) -> Result<(), ExtruderError> {
        if !distance.is_finite() {
            return Err(ExtruderError::NotFinite("extrusion distance"));
        }
        if distance < 0.0 {
            return Err(ExtruderError::NegativeDistance(distance));
        }
        if self.shape.len() < 3 {
            return Err(ExtruderError::TooFewPoints {
                got: self.shape.len(),
            });
        }
        let n = self.shape.len();
        if self.stored.saturating_add(2 * n) > self.options.max_points {
            return Err(ExtruderError::TooLarge(self.options.max_points));
        }
        let needs_new = self
            .open
            .last()
            .and_then(|p| p.rings.last())
            .is_some_and(|r| r.points.len() != n);
        if needs_new {
            self.close_top();
        }
        if self.open.last().is_none_or(|p| p.rings.is_empty()) {
            let ring = self.ring(0.0);
            let flip = self.winding_flip();
            if let Some(top) = self.open.last_mut() {
                top.flip = flip;
                self.stored += ring.points.len();
                top.rings.push(ring);
            }
        }
        self.path.advance(distance)?;
        let previous = self
            .open
            .last()
            .and_then(|p| p.rings.last())
            .map(|r| (centroid(&r.points), r.length));
        let mut ring = self.ring(0.0);
        if let Some((c, len)) = previous {
            ring.length = len + c.distance(centroid(&ring.points));
        }
        if let Some(top) = self.open.last_mut() {
            self.stored += ring.points.len();
            top.rings.push(ring);
        }
        Ok(())
    }

    /// Whether the side quads must be wound the other way for outward normals.
    fn winding_flip(&self) -> bool {
        let area: f32 = (0..self.shape.len())
            .map(|i| {
                let a = self.shape[i];
                let b = self.shape[(i + 1) % self.shape.len()];
                a.x * b.z - b.x * a.z
            })
            .sum();
        let det = (self.path.matrix() * self.shape_matrix.matrix()).determinant();
        (area > 0.0) != (det < 0.0)
    }

    fn ring(&self, length: f32) -> Ring {
        let m = self.path.matrix() * self.shape_matrix.matrix();
        let points = self.shape.iter().map(|p| m.transform_point3(*p)).collect();
        let local = self
            .shape
            .iter()
            .map(|p| {
                let q = self.shape_matrix.transform_point(*p);
                Vec2::new(q.x, q.z)
            })
            .collect();
        let axis = self
            .path
            .transform_vector(Vec3::Y)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        Ring {
            points,
            local,
            axis,
            color: self.color,
            length,
        }
    }

    /// Ring points placed so far: the mesh has at most [`Extruder::MESH_BYTES_PER_POINT`]
    /// bytes per point (flat normals, caps), which bounds its memory.
    #[must_use]
    pub fn stored_points(&self) -> usize {
        self.stored
    }

    /// An upper bound on the mesh's bytes per stored ring point (4 vertices of position,
    /// normal, uv and colour, 6 indices, and the ring itself).
    pub const MESH_BYTES_PER_POINT: usize = 4 * (12 + 12 + 8 + 16) + 6 * 4 + 20;

    /// Number of finished and open pieces with geometry.
    #[must_use]
    pub fn piece_count(&self) -> usize {
        self.done.len() + self.open.iter().filter(|p| p.rings.len() >= 2).count()
    }

    /// Builds the mesh of everything extruded so far; open pieces are included as if
    /// finished (the extruder's state is not changed).
    #[must_use]
    pub fn mesh(&self) -> Mesh {
        let pieces = self
            .done
            .iter()
            .chain(self.open.iter().filter(|p| p.rings.len() >= 2));
        let style = TubeStyle {
            smooth: self.options.smooth,
            caps: self.options.caps,
            material: self.options.material.clone(),
            colored: self.colored,
        };
        build_mesh(pieces, &style)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    fn square(e: &mut Extruder) {
        for (x, z) in [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)] {
            e.add_point2(Vec2::new(x, z)).expect("finite");
        }
    }

    /// Every undirected edge of the triangles, with its use count, keyed by welded position.
    fn edge_uses(mesh: &Mesh) -> HashMap<([i64; 3], [i64; 3]), usize> {
        let key = |p: Vec3| {
            [
                (p.x * 1e4).round() as i64,
                (p.y * 1e4).round() as i64,
                (p.z * 1e4).round() as i64,
            ]
        };
        let mut uses = HashMap::new();
        for t in mesh.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (ka, kb) = (
                    key(mesh.positions[a as usize]),
                    key(mesh.positions[b as usize]),
                );
                let k = if ka < kb { (ka, kb) } else { (kb, ka) };
                *uses.entry(k).or_insert(0) += 1;
            }
        }
        uses
    }

    /// Signed volume by the divergence theorem (positive when normals point out).
    fn volume(mesh: &Mesh) -> f32 {
        mesh.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn counts_match_the_formulas() {
        for smooth in [false, true] {
            for n in [3usize, 4, 7] {
                for rings in [2usize, 3, 6] {
                    let mut e = Extruder::new(ExtruderOptions {
                        smooth,
                        ..ExtruderOptions::default()
                    });
                    e.set_polygon(n, 1.0).expect("polygon");
                    for _ in 0..rings - 1 {
                        e.extrude(0.5).expect("extrudes");
                    }
                    let m = e.mesh();
                    m.validate().expect("valid");
                    let side_vertices = if smooth {
                        (n + 1) * rings
                    } else {
                        4 * n * (rings - 1)
                    };
                    assert_eq!(
                        m.vertex_count(),
                        side_vertices + 2 * n,
                        "smooth={smooth} n={n} r={rings}"
                    );
                    assert_eq!(m.triangle_count(), 2 * n * (rings - 1) + 2 * (n - 2));
                    assert_eq!(m.uvs.len(), m.vertex_count());
                    assert!(m.colors.is_empty(), "no colour was set");
                }
            }
        }
    }

    #[test]
    fn a_capped_prism_is_closed_and_outward() {
        for smooth in [false, true] {
            for clockwise in [false, true] {
                let mut e = Extruder::new(ExtruderOptions {
                    smooth,
                    ..ExtruderOptions::default()
                });
                let mut pts = vec![(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)];
                if clockwise {
                    pts.reverse();
                }
                for (x, z) in pts {
                    e.add_point2(Vec2::new(x, z)).expect("finite");
                }
                e.extrude(3.0).expect("extrudes");
                let m = e.mesh();
                assert!(edge_uses(&m).values().all(|&u| u == 2), "closed");
                assert!((volume(&m) - 12.0).abs() < 1e-4, "volume {}", volume(&m));
                // Side normals point away from the axis, caps along it.
                for (p, nrm) in m.positions.iter().zip(&m.normals) {
                    if smooth && p.y > 0.01 && p.y < 2.99 {
                        continue;
                    }
                    assert!(nrm.length() > 0.99);
                }
                let top = m.positions.len() - 1;
                assert!(m.normals[top].abs_diff_eq(Vec3::Y, 1e-5));
                assert!(m.normals[top - 4].abs_diff_eq(-Vec3::Y, 1e-5));
                if !smooth {
                    // The first edge runs along x = 1 (or x = -1 when reversed).
                    let expected = if clockwise { -Vec3::X } else { Vec3::X };
                    assert!(
                        m.normals[0].abs_diff_eq(expected, 1e-5),
                        "first quad faces out"
                    );
                }
            }
        }
    }

    #[test]
    fn mirrored_path_keeps_normals_outward() {
        let mut e = Extruder::new(ExtruderOptions::default());
        square(&mut e);
        e.path_mut().scale(Vec3::new(-1.0, 1.0, 1.0)).expect("ok");
        e.extrude(1.0).expect("ok");
        assert!((volume(&e.mesh()) - 4.0).abs() < 1e-4);
    }

    #[test]
    fn bends_tapers_and_exact_positions() {
        let mut e = Extruder::new(ExtruderOptions::default());
        square(&mut e);
        e.extrude(1.0).expect("ok");
        e.path_mut().rotate_z(90.0).expect("ok");
        e.shape_matrix_mut().scale(Vec3::splat(0.5)).expect("ok");
        e.extrude(2.0).expect("ok");
        let m = e.mesh();
        // The third ring: centre at (-2, 1, 0), half-size 0.5 in the rotated frame.
        let ring3 = &e.open[0].rings[2];
        assert!(centroid(&ring3.points).abs_diff_eq(Vec3::new(-2.0, 1.0, 0.0), 1e-5));
        assert!(
            ring3.points[0].abs_diff_eq(Vec3::new(-2.0, 1.5, 0.5), 1e-5),
            "{}",
            ring3.points[0]
        );
        assert_eq!(m.triangle_count(), 2 * 4 * 2 + 4);
        assert!(
            (ring3.length - 3.0).abs() < 1e-5,
            "length accumulates along the path"
        );
    }

    #[test]
    fn push_pop_branches_and_restores() {
        let mut e = Extruder::new(ExtruderOptions::default());
        square(&mut e);
        e.extrude(1.0).expect("ok");
        e.push().expect("ok");
        e.path_mut().rotate_x(45.0).expect("ok");
        e.clear_shape();
        e.set_polygon(3, 0.3).expect("ok");
        e.extrude(1.0).expect("ok");
        e.pop().expect("ok");
        assert_eq!(e.shape().len(), 4, "the shape is restored");
        e.extrude(1.0).expect("ok");
        assert_eq!(e.piece_count(), 2);
        // The trunk continued: 3 rings of 4 points; the branch 2 rings of 3.
        let m = e.mesh();
        assert_eq!(m.triangle_count(), (2 * 4 * 2 + 4) + (2 * 3 + 2));
        assert!(
            e.path()
                .transform_point(Vec3::ZERO)
                .abs_diff_eq(Vec3::new(0.0, 2.0, 0.0), 1e-5)
        );
        assert_eq!(e.pop(), Err(ExtruderError::PopWithoutPush));
    }

    #[test]
    fn shape_changes_split_pieces_and_spires_have_no_top_cap() {
        let mut e = Extruder::new(ExtruderOptions::default());
        e.set_polygon(6, 1.0).expect("ok");
        e.extrude(2.0).expect("ok");
        e.shape_matrix_mut().scale(Vec3::ZERO).expect("ok");
        e.extrude(1.0).expect("ok");
        let m = e.mesh();
        assert_eq!(m.triangle_count(), 2 * 6 * 2 + 4, "one cap only");
        assert_eq!(e.piece_count(), 1);
        e.shape_matrix_mut().reset();
        e.set_polygon(4, 1.0).expect("ok");
        e.extrude(1.0).expect("ok");
        assert_eq!(e.piece_count(), 2);
        e.finish();
        e.extrude(1.0).expect("ok");
        assert_eq!(e.piece_count(), 3);
    }

    #[test]
    fn the_point_budget_is_enforced() {
        let mut e = Extruder::new(ExtruderOptions {
            max_points: 20,
            ..ExtruderOptions::default()
        });
        e.set_polygon(4, 1.0).expect("ok");
        e.extrude(1.0).expect("8 points");
        e.extrude(1.0).expect("12 points");
        e.extrude(1.0).expect("16 points");
        assert_eq!(e.extrude(1.0), Err(ExtruderError::TooLarge(20)));
        assert_eq!(e.stored_points(), 16);
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut e = Extruder::new(ExtruderOptions::default());
        e.add_point2(Vec2::ONE).expect("ok");
        e.add_point2(Vec2::ZERO).expect("ok");
        assert_eq!(e.extrude(1.0), Err(ExtruderError::TooFewPoints { got: 2 }));
        assert_eq!(
            e.add_point3(Vec3::NAN),
            Err(ExtruderError::NotFinite("shape point"))
        );
        e.add_point2(Vec2::X).expect("ok");
        assert_eq!(e.extrude(-1.0), Err(ExtruderError::NegativeDistance(-1.0)));
        assert_eq!(
            e.extrude(f32::INFINITY),
            Err(ExtruderError::NotFinite("extrusion distance"))
        );
        assert_eq!(e.pop(), Err(ExtruderError::PopWithoutPush));
        assert_eq!(e.mesh().vertex_count(), 0);
    }

    #[test]
    fn colours_and_non_convex_caps() {
        let mut e = Extruder::new(ExtruderOptions::default());
        // An L shape (non-convex), clockwise.
        for (x, z) in [
            (0.0, 0.0),
            (0.0, -2.0),
            (1.0, -2.0),
            (1.0, -1.0),
            (2.0, -1.0),
            (2.0, 0.0),
        ] {
            e.add_point2(Vec2::new(x, z)).expect("ok");
        }
        e.set_color(Vec4::new(1.0, 0.0, 0.0, 1.0)).expect("ok");
        e.extrude(1.0).expect("ok");
        let m = e.mesh();
        assert_eq!(m.colors.len(), m.vertex_count());
        assert!(edge_uses(&m).values().all(|&u| u == 2));
        assert!(
            (volume(&m) - 3.0).abs() < 1e-4,
            "L area 3 x height 1, got {}",
            volume(&m)
        );
    }
}
