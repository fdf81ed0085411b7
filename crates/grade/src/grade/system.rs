//! What an integrator sees of the physics: [`Physics`] (accelerations and their Jacobians) and a
//! small dense [`Matrix`] with a linear solver, for the backward Euler task.
//!
//! # Theory
//!
//! Newton's second law as a first-order system: `x' = v`, `v' = a(x, v)`, with
//!
//! ```text
//! a_i(x, v) = w_i f_i(x, v)          f_i = m_i g + Σ_springs (spring + damper force on i)
//! J_x = ∂a/∂x,   J_v = ∂a/∂v          3n × 3n matrices, row 3i + c is component c of a_i
//! ```
//! where `w_i = 1/m_i` (1/kg, zero for a pinned particle), `g` is gravity (m/s²), `x` positions
//! (m) and `v` velocities (m/s). The Jacobians are computed by central differences of `a`:
//!
//! ```text
//! column j of J_x ≈ (a(x + h e_j, v) - a(x - h e_j, v)) / 2h,     h = 1e-6 · max(1, |x_j|)
//! ```
//! whose error is `O(h²)` times the third derivative plus round-off `O(ε |a| / h)`: about 1e-10
//! relative for springs. `J_v` is exact up to round-off (the dampers are linear in `v`).

use glam::DVec3;

use super::data::Rope;
use crate::physics::{Model, accelerations};
/// The student API's dense matrix and solver: the grader's Jacobians are the same type the
/// students' integrators receive.
pub use springlab_homework::Matrix;

/// The physics of the system being stepped: the grader builds it from the same masses, springs
/// and gravity as the state it hands to an integrator.
///
/// Cloning is cheap enough for tests; the grader makes one per check.
#[derive(Clone, Debug)]
pub struct Physics {
    model: Model,
}

impl Physics {
    /// The physics of a springlab [`Model`] (for experiments outside the grader: any built-in
    /// scene's `bodies[0].model`).
    #[must_use]
    pub fn from_model(model: Model) -> Physics {
        Physics { model }
    }

    /// The springlab model (the reference implementation steps it directly).
    #[must_use]
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Number of particles.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.model.particle_count()
    }

    /// Inverse mass `w_i = 1/m_i` of every particle (1/kg); zero for a pinned particle.
    #[must_use]
    pub fn inverse_mass(&self) -> &[f64] {
        &self.model.inv_mass
    }

    /// The acceleration `a_i(x, v)` of every particle (m/s²): springs, dampers and gravity
    /// divided by the mass, zero for a pinned particle.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one entry per particle (the message says which).
    #[must_use]
    pub fn accelerations(&self, x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        let n = self.particle_count();
        assert!(
            x.len() == n && v.len() == n,
            "Physics::accelerations: the system has {n} particles, but x has {} entries and v has {}",
            x.len(),
            v.len()
        );
        let mut a = vec![DVec3::ZERO; n];
        accelerations(&self.model, x, v, &mut a);
        a
    }

    /// [`Physics::accelerations`] at the rope's current positions and velocities.
    ///
    /// # Panics
    /// If the rope does not have one mass per particle of the system.
    #[must_use]
    pub fn accelerations_of(&self, rope: &Rope) -> Vec<DVec3> {
        let x: Vec<DVec3> = rope.masses.iter().map(|m| m.position).collect();
        let v: Vec<DVec3> = rope.masses.iter().map(|m| m.velocity).collect();
        self.accelerations(&x, &v)
    }

    /// `J_x = ∂a/∂x` at `(x, v)`: a `3n × 3n` matrix, entry `(3i + c, 3j + d)` is
    /// `∂a_{i,c}/∂x_{j,d}` (1/s²), by central differences (module docs).
    ///
    /// # Panics
    /// As [`Physics::accelerations`].
    #[must_use]
    pub fn jacobian_x(&self, x: &[DVec3], v: &[DVec3]) -> Matrix {
        let mut xs = x.to_vec();
        self.jacobian(x.len(), |j, delta| {
            let (i, c) = (j / 3, j % 3);
            let old = xs[i][c];
            let h = 1e-6 * old.abs().max(1.0);
            xs[i][c] = old + delta * h;
            let a = self.accelerations(&xs, v);
            xs[i][c] = old;
            (a, h)
        })
    }

    /// `J_v = ∂a/∂v` at `(x, v)`: a `3n × 3n` matrix, entry `(3i + c, 3j + d)` is
    /// `∂a_{i,c}/∂v_{j,d}` (1/s), by central differences (module docs).
    ///
    /// # Panics
    /// As [`Physics::accelerations`].
    #[must_use]
    pub fn jacobian_v(&self, x: &[DVec3], v: &[DVec3]) -> Matrix {
        let mut vs = v.to_vec();
        self.jacobian(v.len(), |j, delta| {
            let (i, c) = (j / 3, j % 3);
            let old = vs[i][c];
            let h = 1e-6 * old.abs().max(1.0);
            vs[i][c] = old + delta * h;
            let a = self.accelerations(x, &vs);
            vs[i][c] = old;
            (a, h)
        })
    }

    /// Central differences: `eval(j, ±1)` returns `a` at the state moved by `±h` in coordinate
    /// `j`, and `h`.
    fn jacobian(
        &self,
        particles: usize,
        mut eval: impl FnMut(usize, f64) -> (Vec<DVec3>, f64),
    ) -> Matrix {
        let size = 3 * particles;
        let mut jac = Matrix::zeros(size);
        for j in 0..size {
            let (plus, h) = eval(j, 1.0);
            let (minus, _) = eval(j, -1.0);
            for i in 0..particles {
                // (a(+h) - a(-h)) / 2h, component by component.
                let column = (plus[i] - minus[i]) / (2.0 * h);
                for c in 0..3 {
                    jac[(3 * i + c, j)] = column[c];
                }
            }
        }
        jac
    }
}

/// `[x0, y0, z0, x1, y1, z1, ...]`: vectors as one column, the layout of [`Matrix`] rows.
#[must_use]
pub fn flatten(vectors: &[DVec3]) -> Vec<f64> {
    vectors.iter().flat_map(|v| v.to_array()).collect()
}

/// The inverse of [`flatten`]; a trailing incomplete triple is dropped.
#[must_use]
pub fn unflatten(values: &[f64]) -> Vec<DVec3> {
    values
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}
