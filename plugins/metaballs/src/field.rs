//! [`Metaballs`]: a scalar field made of charged particles.

use glam::Vec3;

/// The most particles one field may hold.
pub const MAX_PARTICLES: usize = 1 << 22;

/// Why a metaball operation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FieldError {
    /// A position, charge or radius was NaN or infinite.
    #[error("{0} is not a finite number")]
    NotFinite(&'static str),
    /// A particle's radius of influence was zero or negative.
    #[error("particle radius must be positive, got {0}")]
    BadRadius(f32),
    /// More than [`MAX_PARTICLES`] particles.
    #[error("more than {MAX_PARTICLES} particles")]
    TooManyParticles,
}

/// One charged particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Centre.
    pub position: Vec3,
    /// Charge: positive particles attract the surface, negative ones carve it.
    pub charge: f32,
    /// Radius of influence: the particle adds nothing at this distance or beyond.
    pub radius: f32,
}

impl Particle {
    /// This particle's contribution at squared distance `d2` (exactly 0 outside its radius).
    #[inline]
    #[must_use]
    pub fn falloff(&self, d2: f32) -> f32 {
        let r2 = self.radius * self.radius;
        if d2 >= r2 {
            return 0.0;
        }
        let t = 1.0 - d2 / r2;
        self.charge * t * t * t
    }

    /// This particle's contribution at `p`.
    #[inline]
    #[must_use]
    pub fn value(&self, p: Vec3) -> f32 {
        self.falloff(p.distance_squared(self.position))
    }

    /// The gradient of this particle's contribution at `p`.
    #[inline]
    #[must_use]
    pub fn gradient(&self, p: Vec3) -> Vec3 {
        let d = p - self.position;
        let r2 = self.radius * self.radius;
        let d2 = d.length_squared();
        if d2 >= r2 {
            return Vec3::ZERO;
        }
        let t = 1.0 - d2 / r2;
        d * (-6.0 * self.charge * t * t / r2)
    }
}

/// A metaball field: `f(p) = Σ qᵢ (1 - |p - cᵢ|² / Rᵢ²)³` over the particles within their
/// radius `Rᵢ` (the Wyvill "soft object" kernel: smooth, and exactly zero beyond `Rᵢ`, so
/// marching cubes only visits the cells near particles).
///
/// A lone particle of charge `q` and radius `R` has the isosurface `f = iso` on the sphere of
/// radius `R * sqrt(1 - (iso / q)^(1/3))`; two particles closer than their radii blend.
///
/// ```
/// use pge_metaballs::Metaballs;
/// use glam::Vec3;
///
/// let mut m = Metaballs::new(1.0);
/// m.add_particle(Vec3::ZERO, 1.0, None).unwrap();
/// assert_eq!(m.value(Vec3::ZERO), 1.0);
/// assert_eq!(m.value(Vec3::new(1.0, 0.0, 0.0)), 0.0);
/// assert!(m.gradient(Vec3::new(0.5, 0.0, 0.0)).x < 0.0);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metaballs {
    particles: Vec<Particle>,
    default_radius: f32,
    bounds: Option<(Vec3, Vec3)>,
    version: u64,
}

impl Metaballs {
    /// An empty field whose particles have radius `default_radius` unless told otherwise.
    ///
    /// # Panics
    /// If `default_radius` is not a positive finite number (check user input first).
    #[must_use]
    pub fn new(default_radius: f32) -> Metaballs {
        assert!(
            default_radius.is_finite() && default_radius > 0.0,
            "default radius must be positive"
        );
        Metaballs {
            particles: Vec::new(),
            default_radius,
            bounds: None,
            version: 0,
        }
    }

    /// The radius used when `add_particle` is given none.
    #[must_use]
    pub fn default_radius(&self) -> f32 {
        self.default_radius
    }

    /// Adds a particle; returns its index.
    pub fn add_particle(
        &mut self,
        position: Vec3,
        charge: f32,
        radius: Option<f32>,
    ) -> Result<usize, FieldError> {
        if !position.is_finite() {
            return Err(FieldError::NotFinite("particle position"));
        }
        if !charge.is_finite() {
            return Err(FieldError::NotFinite("particle charge"));
        }
        let radius = radius.unwrap_or(self.default_radius);
        if !radius.is_finite() {
            return Err(FieldError::NotFinite("particle radius"));
        }
        if radius <= 0.0 {
            return Err(FieldError::BadRadius(radius));
        }
        if self.particles.len() >= MAX_PARTICLES {
            return Err(FieldError::TooManyParticles);
        }
        self.particles.push(Particle {
            position,
            charge,
            radius,
        });
        self.bounds = None;
        self.version += 1;
        Ok(self.particles.len() - 1)
    }

    /// The particles, in the order they were added.
    #[must_use]
    pub fn particles(&self) -> &[Particle] {
        &self.particles
    }

    /// The `i`-th particle (0-based).
    #[must_use]
    pub fn particle(&self, i: usize) -> Option<&Particle> {
        self.particles.get(i)
    }

    /// Number of particles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether there are no particles.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// A counter that changes whenever a particle is added (for caches of meshes).
    #[must_use]
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Recomputes the bounding box of the field (done lazily by [`Metaballs::bounds`] too).
    pub fn update(&mut self) {
        self.bounds = self.compute_bounds();
    }

    fn compute_bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = self.particles.first()?;
        let r = Vec3::splat(first.radius);
        let init = (first.position - r, first.position + r);
        Some(self.particles.iter().fold(init, |(lo, hi), p| {
            let r = Vec3::splat(p.radius);
            (lo.min(p.position - r), hi.max(p.position + r))
        }))
    }

    /// The box outside which the field is zero, `None` without particles.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.bounds.or_else(|| self.compute_bounds())
    }

    /// The field's value at `p`.
    #[must_use]
    pub fn value(&self, p: Vec3) -> f32 {
        self.particles.iter().map(|q| q.value(p)).sum()
    }

    /// The field's gradient at `p` (the direction of steepest increase).
    #[must_use]
    pub fn gradient(&self, p: Vec3) -> Vec3 {
        self.particles.iter().map(|q| q.gradient(p)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::math;

    #[test]
    fn value_and_gradient_agree_with_finite_differences() {
        let mut m = Metaballs::new(1.5);
        m.add_particle(Vec3::ZERO, 1.0, None).expect("ok");
        m.add_particle(Vec3::new(0.8, 0.2, 0.0), -0.5, Some(0.7))
            .expect("ok");
        m.add_particle(Vec3::new(-0.3, 0.5, 0.4), 2.0, Some(1.0))
            .expect("ok");
        let h = 1e-3;
        for p in [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.6, 0.1, -0.2),
            Vec3::new(-0.5, 0.9, 0.1),
        ] {
            let g = m.gradient(p);
            let fd = Vec3::new(
                m.value(p + Vec3::X * h) - m.value(p - Vec3::X * h),
                m.value(p + Vec3::Y * h) - m.value(p - Vec3::Y * h),
                m.value(p + Vec3::Z * h) - m.value(p - Vec3::Z * h),
            ) / (2.0 * h);
            assert!(g.abs_diff_eq(fd, 2e-2), "{g} vs {fd}");
        }
        // Exactly zero beyond every radius.
        assert_eq!(m.value(Vec3::new(5.0, 0.0, 0.0)), 0.0);
        assert_eq!(m.gradient(Vec3::new(5.0, 0.0, 0.0)), Vec3::ZERO);
    }

    #[test]
    fn lone_particle_surface_radius() {
        let mut m = Metaballs::new(2.0);
        m.add_particle(Vec3::ONE, 1.0, None).expect("ok");
        let s = 2.0 * (1.0f32 - math::cbrt(0.5f32)).sqrt();
        assert!((m.value(Vec3::ONE + Vec3::X * s) - 0.5).abs() < 1e-6);
        let (lo, hi) = m.bounds().expect("one particle");
        assert_eq!(lo, Vec3::splat(-1.0));
        assert_eq!(hi, Vec3::splat(3.0));
    }

    #[test]
    fn bad_particles_are_refused() {
        let mut m = Metaballs::new(1.0);
        assert_eq!(
            m.add_particle(Vec3::NAN, 1.0, None),
            Err(FieldError::NotFinite("particle position"))
        );
        assert_eq!(
            m.add_particle(Vec3::ZERO, f32::INFINITY, None),
            Err(FieldError::NotFinite("particle charge"))
        );
        assert_eq!(
            m.add_particle(Vec3::ZERO, 1.0, Some(0.0)),
            Err(FieldError::BadRadius(0.0))
        );
        assert!(m.is_empty());
        assert_eq!(m.bounds(), None);
        let v = m.version();
        assert_eq!(m.add_particle(Vec3::ZERO, 1.0, None), Ok(0));
        assert!(m.version() > v);
        assert_eq!(m.particle(0).map(|p| p.radius), Some(1.0));
        assert!(m.particle(1).is_none());
    }
}
