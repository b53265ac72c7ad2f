//! [`Extruder`]: a 2D shape in the XZ plane swept along the path matrix's +Y axis.

use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{Material, Mesh};

use crate::matrix::{MatrixError, MatrixManipulator};
use crate::triangulate::triangulate;

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

/// One cross-section placed along the path.
#[derive(Clone, Debug)]
struct Ring {
    /// World positions, one per shape point.
    points: Vec<Vec3>,
    /// The shape points after the shape matrix, projected on the local XZ plane.
    local: Vec<Vec2>,
    /// The path's +Y axis (world) at this ring: the direction caps face.
    axis: Vec3,
    /// Vertex colour.
    color: Vec4,
    /// Distance travelled along the path from the piece's first ring (world units).
    length: f32,
}

/// A run of rings joined by quads: one tube.
#[derive(Clone, Debug, Default)]
struct Piece {
    rings: Vec<Ring>,
    /// Reverse the side winding (a clockwise shape or a mirroring matrix).
    flip: bool,
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
                Vec3::new(radius * a.cos(), 0.0, -radius * a.sin())
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
        let mut mesh = Mesh {
            name: "extrusion".into(),
            material: self.options.material.clone(),
            ..Mesh::default()
        };
        let pieces = || {
            self.done
                .iter()
                .chain(self.open.iter().filter(|p| p.rings.len() >= 2))
        };
        // Reserve the exact sizes of the formulas (caps at most).
        let (mut vertices, mut indices) = (0usize, 0usize);
        for piece in pieces() {
            let (n, r) = (piece.rings[0].points.len(), piece.rings.len());
            vertices += if self.options.smooth {
                (n + 1) * r
            } else {
                4 * n * (r - 1)
            };
            indices += 6 * n * (r - 1);
            if self.options.caps {
                vertices += 2 * n;
                indices += 6 * (n - 2);
            }
        }
        mesh.positions.reserve_exact(vertices);
        mesh.normals.reserve_exact(vertices);
        mesh.uvs.reserve_exact(vertices);
        mesh.colors.reserve_exact(vertices);
        mesh.indices.reserve_exact(indices);
        for piece in pieces() {
            self.build_piece(piece, &mut mesh);
        }
        if !self.colored {
            mesh.colors.clear();
        }
        mesh
    }

    fn build_piece(&self, piece: &Piece, mesh: &mut Mesh) {
        let n = piece.rings[0].points.len();
        let perimeter0 = perimeter(&piece.rings[0].points).max(1e-6);
        if self.options.smooth {
            build_smooth(piece, n, perimeter0, mesh);
        } else {
            build_flat(piece, n, perimeter0, mesh);
        }
        if self.options.caps {
            let first = &piece.rings[0];
            let last = &piece.rings[piece.rings.len() - 1];
            build_cap(first, -first.axis, mesh);
            build_cap(last, last.axis, mesh);
        }
    }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().copied().sum::<Vec3>() / points.len().max(1) as f32
}

fn perimeter(points: &[Vec3]) -> f32 {
    (0..points.len())
        .map(|i| points[i].distance(points[(i + 1) % points.len()]))
        .sum()
}

/// `u` of each shape point around the perimeter, with the seam point (`u = 1`) appended.
fn perimeter_us(local: &[Vec2]) -> Vec<f32> {
    let n = local.len();
    let mut us = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    us.push(0.0);
    for i in 0..n {
        acc += local[i].distance(local[(i + 1) % n]);
        us.push(acc);
    }
    let total = acc;
    if total > 0.0 {
        for u in &mut us {
            *u /= total;
        }
    } else {
        for (i, u) in us.iter_mut().enumerate() {
            *u = i as f32 / n as f32;
        }
    }
    us
}

/// The two triangles of quad `(a0, a1)` on one ring and `(b0, b1)` on the next.
fn quad(a0: u32, a1: u32, b0: u32, b1: u32, flip: bool) -> [u32; 6] {
    if flip {
        [a0, b1, a1, a0, b0, b1]
    } else {
        [a0, a1, b1, a0, b1, b0]
    }
}

fn build_smooth(piece: &Piece, n: usize, perimeter0: f32, mesh: &mut Mesh) {
    let r = piece.rings.len();
    // Area-weighted normals of the side quads, accumulated on the n x r grid.
    let mut acc = vec![Vec3::ZERO; n * r];
    for k in 0..r - 1 {
        let (a, b) = (&piece.rings[k].points, &piece.rings[k + 1].points);
        for j in 0..n {
            let j1 = (j + 1) % n;
            let mut normal = (a[j1] - a[j]).cross(b[j1] - a[j]) + (b[j1] - a[j]).cross(b[j] - a[j]);
            if piece.flip {
                normal = -normal;
            }
            for idx in [k * n + j, k * n + j1, (k + 1) * n + j, (k + 1) * n + j1] {
                acc[idx] += normal;
            }
        }
    }
    let base = mesh.positions.len() as u32;
    for (k, ring) in piece.rings.iter().enumerate() {
        let us = perimeter_us(&ring.local);
        let fallback = ring.axis;
        for (j, u) in us.iter().enumerate() {
            let jj = j % n;
            mesh.positions.push(ring.points[jj]);
            mesh.normals
                .push(acc[k * n + jj].try_normalize().unwrap_or(fallback));
            mesh.uvs.push(Vec2::new(*u, ring.length / perimeter0));
            mesh.colors.push(ring.color);
        }
    }
    let stride = (n + 1) as u32;
    for k in 0..(r - 1) as u32 {
        for j in 0..n as u32 {
            let a0 = base + k * stride + j;
            let b0 = a0 + stride;
            mesh.indices
                .extend(quad(a0, a0 + 1, b0, b0 + 1, piece.flip));
        }
    }
}

fn build_flat(piece: &Piece, n: usize, perimeter0: f32, mesh: &mut Mesh) {
    for k in 0..piece.rings.len() - 1 {
        let (ra, rb) = (&piece.rings[k], &piece.rings[k + 1]);
        let (ua, ub) = (perimeter_us(&ra.local), perimeter_us(&rb.local));
        for j in 0..n {
            let j1 = (j + 1) % n;
            let corners = [
                (
                    ra.points[j],
                    Vec2::new(ua[j], ra.length / perimeter0),
                    ra.color,
                ),
                (
                    ra.points[j1],
                    Vec2::new(ua[j + 1], ra.length / perimeter0),
                    ra.color,
                ),
                (
                    rb.points[j],
                    Vec2::new(ub[j], rb.length / perimeter0),
                    rb.color,
                ),
                (
                    rb.points[j1],
                    Vec2::new(ub[j + 1], rb.length / perimeter0),
                    rb.color,
                ),
            ];
            let [a0, a1, b0, b1] = [corners[0].0, corners[1].0, corners[2].0, corners[3].0];
            let mut normal = (a1 - a0).cross(b1 - a0) + (b1 - a0).cross(b0 - a0);
            if piece.flip {
                normal = -normal;
            }
            let normal = normal.try_normalize().unwrap_or_else(|| {
                // A degenerate quad (zero-length step): point away from the axis.
                let mid = (a0 + a1) * 0.5 - centroid(&ra.points);
                mid.try_normalize().unwrap_or(ra.axis)
            });
            let base = mesh.positions.len() as u32;
            for (p, uv, c) in corners {
                mesh.positions.push(p);
                mesh.normals.push(normal);
                mesh.uvs.push(uv);
                mesh.colors.push(c);
            }
            mesh.indices
                .extend(quad(base, base + 1, base + 2, base + 3, piece.flip));
        }
    }
}

/// A cap over `ring` facing `facing`; nothing when the ring has collapsed to a point.
fn build_cap(ring: &Ring, facing: Vec3, mesh: &mut Mesh) {
    let (lo, hi) = ring.local.iter().fold(
        (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = (hi - lo).max_element();
    if extent <= 1e-9 || perimeter(&ring.points) <= 1e-9 {
        return;
    }
    let mut tris = triangulate(&ring.local);
    let total: Vec3 = tris
        .iter()
        .map(|t| {
            (ring.points[t[1]] - ring.points[t[0]]).cross(ring.points[t[2]] - ring.points[t[0]])
        })
        .sum();
    if total.dot(facing) < 0.0 {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    let normal = if total.dot(facing) < 0.0 {
        -total
    } else {
        total
    };
    let normal = normal.try_normalize().unwrap_or(facing);
    let base = mesh.positions.len() as u32;
    for (p, l) in ring.points.iter().zip(&ring.local) {
        mesh.positions.push(*p);
        mesh.normals.push(normal);
        mesh.uvs.push((*l - lo) / extent);
        mesh.colors.push(ring.color);
    }
    for t in tris {
        mesh.indices.extend(t.map(|i| base + i as u32));
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
