//! [`Lines`]: coloured 3D segments, exported as a glTF line mesh or as thin tubes.

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
    width: f32,
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
            width: 0.0,
        }
    }

    /// Draws every segment as a thin four-sided tube `width` across (triangles, which every
    /// client renders) instead of a line (which Blender imports as edges that do not
    /// render); `0` (the default) keeps lines. `width` must be finite and not negative.
    #[must_use]
    pub fn with_width(mut self, width: f32) -> Lines {
        self.width = width.max(0.0);
        self
    }

    /// The tube width, `0` for lines.
    #[must_use]
    pub fn width(&self) -> f32 {
        self.width
    }

    /// Bytes of mesh per segment drawn as a line (two vertices of position and colour, two
    /// indices).
    pub const BYTES_PER_SEGMENT: usize = 2 * (12 + 16) + 2 * 4;

    /// Bytes of mesh per segment drawn as a tube (eight vertices of position, normal and
    /// colour, eight triangles).
    pub const BYTES_PER_TUBE: usize = 8 * (12 + 12 + 16) + 24 * 4;

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

    /// The mesh: with a width, `Lines::tubes`; else a [`Primitive::Lines`] mesh with one
    /// vertex per segment end and vertex colours.
    #[must_use]
    pub fn mesh(&self) -> Mesh {
        if self.width > 0.0 {
            return self.tubes();
        }
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

impl Lines {
    /// Every segment as an open four-sided tube `width` across around it, in the segment's
    /// colour, with outward normals (the four corners of each end share a radial normal, so
    /// tubes look round). Segments shorter than a millionth of the width are left out: they
    /// would only make zero-area triangles.
    fn tubes(&self) -> Mesh {
        let r = self.width / 2.0;
        let n = self.positions.len() / 2;
        let mut positions = Vec::with_capacity(8 * n);
        let mut normals = Vec::with_capacity(8 * n);
        let mut colors = Vec::with_capacity(8 * n);
        let mut indices = Vec::with_capacity(24 * n);
        for (ends, color) in self
            .positions
            .chunks_exact(2)
            .zip(self.colors.chunks_exact(2))
        {
            let (a, b) = (ends[0], ends[1]);
            let Some(d) = (b - a).try_normalize() else {
                continue;
            };
            if (b - a).length() < self.width * 1e-6 {
                continue;
            }
            // (u, v, d) is a right-handed frame: corner k sits at angle k * 90 degrees.
            let u = d.any_orthonormal_vector();
            let v = d.cross(u);
            let base = positions.len() as u32;
            for end in [a, b] {
                for radial in [u, v, -u, -v] {
                    positions.push(end + radial * r);
                    normals.push(radial);
                    colors.push(color[0]);
                }
            }
            for k in 0..4u32 {
                let (a0, a1) = (base + k, base + (k + 1) % 4);
                let (b0, b1) = (a0 + 4, a1 + 4);
                indices.extend([a0, a1, b0, a1, b1, b0]);
            }
        }
        Mesh {
            name: "lines".into(),
            positions,
            normals,
            colors,
            indices,
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

    #[test]
    fn with_a_width_segments_become_outward_facing_tubes() {
        let red = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let mut l = Lines::new(Vec4::ONE).with_width(0.2);
        l.add(Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0), Some(red))
            .expect("ok");
        l.add(Vec3::ONE, Vec3::new(3.0, 1.0, 2.0), None)
            .expect("ok");
        // A segment of no length makes nothing.
        l.add(Vec3::X, Vec3::X, None).expect("ok");
        let m = l.mesh();
        m.validate().expect("valid");
        assert_eq!(m.primitive, Primitive::Triangles);
        assert_eq!(m.vertex_count(), 16);
        assert_eq!(m.triangle_count(), 16);
        assert!(m.colors[..8].iter().all(|c| *c == red));
        assert!(m.colors[8..].iter().all(|c| *c == Vec4::ONE));
        // Every corner is half the width from its segment's axis.
        for p in &m.positions[..8] {
            assert!((Vec3::new(p.x, 0.0, p.z).length() - 0.1).abs() < 1e-6);
        }
        // Every triangle faces away from the axis of its segment, and has an area.
        for (seg, tris) in m.indices.chunks_exact(24).enumerate() {
            let (a, b) = if seg == 0 {
                (Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0))
            } else {
                (Vec3::ONE, Vec3::new(3.0, 1.0, 2.0))
            };
            for t in tris.chunks_exact(3) {
                let [p, q, r] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                let face = (q - p).cross(r - p);
                assert!(face.length() > 1e-4, "zero-area triangle");
                let centre = (p + q + r) / 3.0;
                let d = (b - a).normalize();
                let radial = (centre - a) - d * (centre - a).dot(d);
                assert!(face.dot(radial) > 0.0, "triangle {t:?} faces inward");
            }
        }
    }
}
