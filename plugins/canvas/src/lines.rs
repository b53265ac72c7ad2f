//! [`Lines`]: coloured 3D segments, exported as a glTF line mesh.

use std::sync::Arc;

use glam::{Vec3, Vec4};
use pge_engine::geometry::{Material, Mesh, Primitive};

/// The most segments one [`Lines`] may hold.
pub const MAX_SEGMENTS: usize = 1 << 24;

/// Why a segment was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinesError {
    /// An end point or colour was NaN or infinite.
    #[error("{0} is not a finite number")]
    NotFinite(&'static str),
    /// More segments than the limit ([`MAX_SEGMENTS`] or the memory budget).
    #[error("more than {0} segments, past the memory limit")]
    TooManySegments(usize),
}

/// The thesis' 3D line generator: segments between two points, each with a colour.
///
/// ```
/// use pge_canvas::Lines;
/// use glam::{Vec3, Vec4};
///
/// let mut lines = Lines::new(Vec4::ONE);
/// lines.add(Vec3::ZERO, Vec3::Y, None).unwrap();
/// lines.add(Vec3::Y, Vec3::ONE, Some(Vec4::new(1.0, 0.0, 0.0, 1.0))).unwrap();
/// let mesh = lines.mesh();
/// assert_eq!(mesh.indices, vec![0, 1, 2, 3]);
/// assert_eq!(mesh.colors[3], Vec4::new(1.0, 0.0, 0.0, 1.0));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Lines {
    positions: Vec<Vec3>,
    colors: Vec<Vec4>,
    color: Vec4,
    max_segments: usize,
}

impl Lines {
    /// An empty set of lines whose segments default to `color` (linear RGBA).
    #[must_use]
    pub fn new(color: Vec4) -> Lines {
        Lines::with_max_segments(color, MAX_SEGMENTS)
    }

    /// An empty set of lines that refuses more than `max` segments (a memory budget; at most
    /// [`MAX_SEGMENTS`]).
    #[must_use]
    pub fn with_max_segments(color: Vec4, max: usize) -> Lines {
        Lines {
            positions: Vec::new(),
            colors: Vec::new(),
            color,
            max_segments: max.min(MAX_SEGMENTS),
        }
    }

    /// Bytes of mesh per segment (two vertices of position and colour, two indices).
    pub const BYTES_PER_SEGMENT: usize = 2 * (12 + 16) + 2 * 4;

    /// Adds the segment `a`-`b` in `color` (the default colour when `None`).
    pub fn add(&mut self, a: Vec3, b: Vec3, color: Option<Vec4>) -> Result<(), LinesError> {
        if !a.is_finite() || !b.is_finite() {
            return Err(LinesError::NotFinite("segment end"));
        }
        let color = color.unwrap_or(self.color);
        if !color.is_finite() {
            return Err(LinesError::NotFinite("colour"));
        }
        if self.positions.len() / 2 >= self.max_segments {
            return Err(LinesError::TooManySegments(self.max_segments));
        }
        self.positions.extend([a, b]);
        self.colors.extend([color, color]);
        Ok(())
    }

    /// Number of segments.
    #[must_use]
    pub fn len(&self) -> usize {
        self.positions.len() / 2
    }

    /// Whether there are no segments.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Removes every segment.
    pub fn clear(&mut self) {
        self.positions.clear();
        self.colors.clear();
    }

    /// A [`Primitive::Lines`] mesh with one vertex per segment end and vertex colours.
    #[must_use]
    pub fn mesh(&self) -> Mesh {
        Mesh {
            name: "lines".into(),
            primitive: Primitive::Lines,
            positions: self.positions.clone(),
            colors: self.colors.clone(),
            indices: (0..self.positions.len() as u32).collect(),
            material: Arc::new(Material {
                name: "lines".into(),
                base_color: [1.0; 4],
                ..Material::default()
            }),
            ..Mesh::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_become_a_valid_line_mesh() {
        let mut l = Lines::new(Vec4::new(0.0, 1.0, 0.0, 1.0));
        assert!(l.is_empty());
        for i in 0..5 {
            l.add(Vec3::splat(i as f32), Vec3::splat(i as f32 + 1.0), None)
                .expect("ok");
        }
        assert_eq!(l.len(), 5);
        let m = l.mesh();
        m.validate().expect("valid");
        assert_eq!(m.primitive, Primitive::Lines);
        assert_eq!(m.triangle_count(), 0);
        assert_eq!(m.indices.len(), 10);
        assert!(m.colors.iter().all(|c| *c == Vec4::new(0.0, 1.0, 0.0, 1.0)));
        l.clear();
        assert_eq!(l.mesh().vertex_count(), 0);
    }

    #[test]
    fn non_finite_input_is_refused() {
        let mut l = Lines::new(Vec4::ONE);
        assert_eq!(
            l.add(Vec3::NAN, Vec3::ZERO, None),
            Err(LinesError::NotFinite("segment end"))
        );
        assert_eq!(
            l.add(Vec3::ZERO, Vec3::ONE, Some(Vec4::splat(f32::INFINITY))),
            Err(LinesError::NotFinite("colour"))
        );
        assert!(l.is_empty());
        let mut l = Lines::with_max_segments(Vec4::ONE, 2);
        l.add(Vec3::ZERO, Vec3::X, None).expect("1");
        l.add(Vec3::ZERO, Vec3::Y, None).expect("2");
        assert_eq!(
            l.add(Vec3::ZERO, Vec3::Z, None),
            Err(LinesError::TooManySegments(2))
        );
    }
}
