//! [`MatrixManipulator`]: a transform with a stack, as the thesis' extruder uses for its path
//! and its shape.

use glam::{Mat4, Quat, Vec3};

/// The deepest a matrix stack may grow; a script pushing in a runaway loop gets an error
/// instead of exhausting memory.
pub const MAX_STACK_DEPTH: usize = 1 << 16;

/// Why a matrix operation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MatrixError {
    /// `pop` was called more often than `push`.
    #[error("pop without a matching push: the matrix stack is empty")]
    PopWithoutPush,
    /// `push` was called more than [`MAX_STACK_DEPTH`] times without `pop`.
    #[error("the matrix stack is deeper than {MAX_STACK_DEPTH} (a push without pop in a loop?)")]
    StackOverflow,
    /// An argument was NaN or infinite.
    #[error("{0} is not a finite number")]
    NotFinite(&'static str),
    /// `rotate` got a zero axis.
    #[error("the rotation axis has zero length")]
    ZeroAxis,
}

/// A 4x4 transform with a push/pop stack.
///
/// Every operation multiplies on the right (`M = M * T`): transforms are expressed in the
/// current local frame, as a turtle's are. `advance(d)` moves along the local +Y axis, the
/// direction the extruder extrudes in. Angles are in degrees.
///
/// ```
/// use pge_extruder::MatrixManipulator;
/// use glam::Vec3;
///
/// let mut m = MatrixManipulator::new();
/// m.rotate_z(90.0).unwrap();          // local +Y now points to world -X
/// m.advance(2.0).unwrap();
/// assert!(m.transform_point(Vec3::ZERO).abs_diff_eq(Vec3::new(-2.0, 0.0, 0.0), 1e-6));
/// m.push().unwrap();
/// m.reset();
/// m.pop().unwrap();                    // back to the saved matrix
/// assert!(m.pop().is_err());           // nothing left to pop
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixManipulator {
    matrix: Mat4,
    stack: Vec<Mat4>,
}

impl Default for MatrixManipulator {
    fn default() -> Self {
        MatrixManipulator::new()
    }
}

fn finite(v: f32, what: &'static str) -> Result<f32, MatrixError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(MatrixError::NotFinite(what))
    }
}

fn finite3(v: Vec3, what: &'static str) -> Result<Vec3, MatrixError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(MatrixError::NotFinite(what))
    }
}

impl MatrixManipulator {
    /// The identity with an empty stack.
    #[must_use]
    pub fn new() -> MatrixManipulator {
        MatrixManipulator {
            matrix: Mat4::IDENTITY,
            stack: Vec::new(),
        }
    }

    /// The current matrix.
    #[must_use]
    pub fn matrix(&self) -> Mat4 {
        self.matrix
    }

    /// Replaces the current matrix (the stack is kept).
    pub fn set_matrix(&mut self, matrix: Mat4) -> Result<(), MatrixError> {
        if !matrix.is_finite() {
            return Err(MatrixError::NotFinite("matrix"));
        }
        self.matrix = matrix;
        Ok(())
    }

    /// Number of matrices saved by `push` and not yet popped.
    #[must_use]
    pub fn depth(&self) -> usize {
        self.stack.len()
    }

    /// Saves the current matrix on the stack.
    pub fn push(&mut self) -> Result<(), MatrixError> {
        if self.stack.len() >= MAX_STACK_DEPTH {
            return Err(MatrixError::StackOverflow);
        }
        self.stack.push(self.matrix);
        Ok(())
    }

    /// Restores the matrix saved by the last `push`.
    pub fn pop(&mut self) -> Result<(), MatrixError> {
        self.matrix = self.stack.pop().ok_or(MatrixError::PopWithoutPush)?;
        Ok(())
    }

    /// Sets the current matrix to the identity; the stack is kept.
    pub fn reset(&mut self) {
        self.matrix = Mat4::IDENTITY;
    }

    /// Multiplies by a rotation of `degrees` about `axis` (local frame).
    pub fn rotate(&mut self, axis: Vec3, degrees: f32) -> Result<(), MatrixError> {
        let axis = finite3(axis, "rotation axis")?;
        let degrees = finite(degrees, "rotation angle")?;
        let axis = axis.try_normalize().ok_or(MatrixError::ZeroAxis)?;
        self.matrix *= Mat4::from_quat(Quat::from_axis_angle(axis, degrees.to_radians()));
        Ok(())
    }

    /// Rotates about the local X axis.
    pub fn rotate_x(&mut self, degrees: f32) -> Result<(), MatrixError> {
        self.rotate(Vec3::X, degrees)
    }

    /// Rotates about the local Y axis.
    pub fn rotate_y(&mut self, degrees: f32) -> Result<(), MatrixError> {
        self.rotate(Vec3::Y, degrees)
    }

    /// Rotates about the local Z axis.
    pub fn rotate_z(&mut self, degrees: f32) -> Result<(), MatrixError> {
        self.rotate(Vec3::Z, degrees)
    }

    /// Multiplies by a scaling (zero factors are allowed: a shape scaled to a point).
    pub fn scale(&mut self, factors: Vec3) -> Result<(), MatrixError> {
        let factors = finite3(factors, "scale factor")?;
        self.matrix *= Mat4::from_scale(factors);
        Ok(())
    }

    /// Scales along the local X axis.
    pub fn scale_x(&mut self, factor: f32) -> Result<(), MatrixError> {
        self.scale(Vec3::new(factor, 1.0, 1.0))
    }

    /// Scales along the local Y axis.
    pub fn scale_y(&mut self, factor: f32) -> Result<(), MatrixError> {
        self.scale(Vec3::new(1.0, factor, 1.0))
    }

    /// Scales along the local Z axis.
    pub fn scale_z(&mut self, factor: f32) -> Result<(), MatrixError> {
        self.scale(Vec3::new(1.0, 1.0, factor))
    }

    /// Multiplies by a translation (local frame).
    pub fn translate(&mut self, offset: Vec3) -> Result<(), MatrixError> {
        let offset = finite3(offset, "translation")?;
        self.matrix *= Mat4::from_translation(offset);
        Ok(())
    }

    /// `translate(0, distance, 0)`: moves along the local extrusion axis.
    pub fn advance(&mut self, distance: f32) -> Result<(), MatrixError> {
        self.translate(Vec3::new(0.0, finite(distance, "distance")?, 0.0))
    }

    /// The current matrix applied to a point.
    #[must_use]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.matrix.transform_point3(p)
    }

    /// The current matrix applied to a direction (no translation).
    #[must_use]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.matrix.transform_vector3(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(a: Vec3, b: Vec3) {
        assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
    }

    #[test]
    fn operations_compose_in_the_local_frame() {
        let mut m = MatrixManipulator::new();
        m.translate(Vec3::new(1.0, 0.0, 0.0)).expect("ok");
        m.rotate_x(90.0).expect("ok"); // local +Y becomes world +Z
        m.advance(2.0).expect("ok");
        assert_close(m.transform_point(Vec3::ZERO), Vec3::new(1.0, 0.0, 2.0));
        m.scale(Vec3::splat(2.0)).expect("ok");
        assert_close(m.transform_point(Vec3::Y), Vec3::new(1.0, 0.0, 4.0));
        m.scale_x(0.5).expect("ok");
        assert_close(m.transform_vector(Vec3::X), Vec3::X);
        m.rotate_y(180.0).expect("ok");
        assert_close(m.transform_vector(Vec3::X), -Vec3::X);
        m.reset();
        assert_eq!(m.matrix(), Mat4::IDENTITY);
    }

    #[test]
    fn stack_restores_and_refuses_pop_without_push() {
        let mut m = MatrixManipulator::new();
        assert_eq!(m.pop(), Err(MatrixError::PopWithoutPush));
        m.advance(1.0).expect("ok");
        m.push().expect("ok");
        m.push().expect("ok");
        assert_eq!(m.depth(), 2);
        m.rotate_z(45.0).expect("ok");
        m.advance(3.0).expect("ok");
        m.pop().expect("ok");
        assert_close(m.transform_point(Vec3::ZERO), Vec3::Y);
        m.reset();
        m.pop().expect("ok"); // reset keeps the stack
        assert_close(m.transform_point(Vec3::ZERO), Vec3::Y);
        assert_eq!(m.depth(), 0);
        assert_eq!(m.pop(), Err(MatrixError::PopWithoutPush));
        // A failed pop changes nothing.
        assert_close(m.transform_point(Vec3::ZERO), Vec3::Y);
    }

    #[test]
    fn bad_arguments_are_errors() {
        let mut m = MatrixManipulator::new();
        assert_eq!(m.rotate(Vec3::ZERO, 10.0), Err(MatrixError::ZeroAxis));
        assert_eq!(m.advance(f32::NAN), Err(MatrixError::NotFinite("distance")));
        assert_eq!(
            m.scale(Vec3::new(1.0, f32::INFINITY, 1.0)),
            Err(MatrixError::NotFinite("scale factor"))
        );
        assert_eq!(m.matrix(), Mat4::IDENTITY);
        for _ in 0..MAX_STACK_DEPTH {
            m.push().expect("within the limit");
        }
        assert_eq!(m.push(), Err(MatrixError::StackOverflow));
    }
}
