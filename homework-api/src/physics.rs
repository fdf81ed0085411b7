//! [`Physics`]: what an integrator sees of the system it steps.
//!
//! ```text
//! a_i(x, v) = w_i f_i(x, v)          f_i = m_i g + Σ_springs (spring + damper force on i)
//! J_x = ∂a/∂x,   J_v = ∂a/∂v          3n × 3n matrices, row 3i + c is component c of a_i
//! ```
//! where `w_i = 1/m_i` (1/kg, zero for a pinned particle), `g` is gravity (m/s²), `x` positions
//! (m) and `v` velocities (m/s).
//!
//! Under the grader, every call goes to the grader, which answers with its own physics of the
//! system being stepped (the Jacobians by central differences, about 1e-10 relative). For your
//! own experiments, [`Physics::new`] wraps any acceleration function; its Jacobians are the same
//! central differences:
//!
//! ```text
//! column j of J_x ≈ (a(x + h e_j, v) - a(x - h e_j, v)) / 2h,     h = 1e-6 · max(1, |x_j|)
//! ```

use std::fmt;

use crate::matrix::Matrix;
use crate::wire::physics_request;
use crate::{DVec3, Rope};

/// An acceleration function `a(x, v)`.
type AccelerationFn = dyn Fn(&[DVec3], &[DVec3]) -> Vec<DVec3>;

enum Source {
    /// Calls go to the grader over the program's standard input and output.
    Grader,
    /// A function in this program.
    Local(Box<AccelerationFn>),
}

/// The physics of the system being stepped: accelerations and their Jacobians.
pub struct Physics {
    inverse_mass: Vec<f64>,
    source: Source,
}

impl fmt::Debug for Physics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Physics")
            .field("particles", &self.inverse_mass.len())
            .field(
                "source",
                &match self.source {
                    Source::Grader => "grader",
                    Source::Local(_) => "local",
                },
            )
            .finish()
    }
}

impl Physics {
    /// Physics from an acceleration function, for tests of your own: `inverse_mass[i]` is
    /// `1/m_i` (0 pins particle `i`), `accelerations(x, v)` returns one vector per particle.
    #[must_use]
    pub fn new(
        inverse_mass: Vec<f64>,
        accelerations: impl Fn(&[DVec3], &[DVec3]) -> Vec<DVec3> + 'static,
    ) -> Physics {
        Physics {
            inverse_mass,
            source: Source::Local(Box::new(accelerations)),
        }
    }

    /// The grader's physics of a system of `inverse_mass.len()` particles.
    pub(crate) fn grader(inverse_mass: Vec<f64>) -> Physics {
        Physics {
            inverse_mass,
            source: Source::Grader,
        }
    }

    /// Number of particles.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.inverse_mass.len()
    }

    /// Inverse mass `w_i = 1/m_i` of every particle (1/kg); zero for a pinned particle.
    #[must_use]
    pub fn inverse_mass(&self) -> &[f64] {
        &self.inverse_mass
    }

    /// The acceleration `a_i(x, v)` of every particle (m/s²): springs, dampers and gravity
    /// divided by the mass, zero for a pinned particle.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one entry per particle (the message says which).
    #[must_use]
    pub fn accelerations(&self, x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        self.check_sizes("accelerations", x, v);
        match &self.source {
            Source::Grader => crate::channel::ask_accelerations(x, v),
            Source::Local(f) => f(x, v),
        }
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
    /// `∂a_{i,c}/∂x_{j,d}` (1/s²).
    ///
    /// # Panics
    /// As [`Physics::accelerations`].
    #[must_use]
    pub fn jacobian_x(&self, x: &[DVec3], v: &[DVec3]) -> Matrix {
        self.jacobian(physics_request::JACOBIAN_X, x, v)
    }

    /// `J_v = ∂a/∂v` at `(x, v)`: a `3n × 3n` matrix, entry `(3i + c, 3j + d)` is
    /// `∂a_{i,c}/∂v_{j,d}` (1/s).
    ///
    /// # Panics
    /// As [`Physics::accelerations`].
    #[must_use]
    pub fn jacobian_v(&self, x: &[DVec3], v: &[DVec3]) -> Matrix {
        self.jacobian(physics_request::JACOBIAN_V, x, v)
    }

    fn check_sizes(&self, what: &str, x: &[DVec3], v: &[DVec3]) {
        let n = self.particle_count();
        assert!(
            x.len() == n && v.len() == n,
            "Physics::{what}: the system has {n} particles, but x has {} entries and v has {}",
            x.len(),
            v.len()
        );
    }

    fn jacobian(&self, what: u8, x: &[DVec3], v: &[DVec3]) -> Matrix {
        let name = if what == physics_request::JACOBIAN_X {
            "jacobian_x"
        } else {
            "jacobian_v"
        };
        self.check_sizes(name, x, v);
        let size = 3 * x.len();
        match &self.source {
            Source::Grader => {
                let values = crate::channel::ask_grader(what, x, v, size * size);
                Matrix::from_row_major(size, values).unwrap_or_else(|| Matrix::zeros(size))
            }
            Source::Local(f) => central_differences(f.as_ref(), what, x, v),
        }
    }
}

/// The Jacobian of `f` by central differences (module docs).
fn central_differences(f: &AccelerationFn, what: u8, x: &[DVec3], v: &[DVec3]) -> Matrix {
    let n = x.len();
    let size = 3 * n;
    let mut jac = Matrix::zeros(size);
    let mut xs = x.to_vec();
    let mut vs = v.to_vec();
    for j in 0..size {
        let (i, c) = (j / 3, j % 3);
        let moved = if what == physics_request::JACOBIAN_X {
            &mut xs
        } else {
            &mut vs
        };
        let old = moved[i][c];
        let h = 1e-6 * old.abs().max(1.0);
        moved[i][c] = old + h;
        let plus = f(&xs, &vs);
        let moved = if what == physics_request::JACOBIAN_X {
            &mut xs
        } else {
            &mut vs
        };
        moved[i][c] = old - h;
        let minus = f(&xs, &vs);
        let moved = if what == physics_request::JACOBIAN_X {
            &mut xs
        } else {
            &mut vs
        };
        moved[i][c] = old;
        for k in 0..n.min(plus.len()).min(minus.len()) {
            let column = (plus[k] - minus[k]) / (2.0 * h);
            for d in 0..3 {
                jac[(3 * k + d, j)] = column[d];
            }
        }
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::Physics;
    use crate::DVec3;

    #[test]
    fn local_jacobians_of_a_linear_spring_are_exact_to_round_off() {
        // Particle 0 fixed at the origin by a spring of 100 N/m (rest length 0) and a damper of
        // 2 N·s/m, mass 1: a = -100 x - 2 v, so J_x = -100 I and J_v = -2 I.
        let physics = Physics::new(vec![1.0], |x, v| vec![-100.0 * x[0] - 2.0 * v[0]]);
        let x = [DVec3::new(0.3, -0.2, 0.1)];
        let v = [DVec3::new(1.0, 0.0, -1.0)];
        let jx = physics.jacobian_x(&x, &v);
        let jv = physics.jacobian_v(&x, &v);
        for r in 0..3 {
            for c in 0..3 {
                let (wx, wv) = if r == c { (-100.0, -2.0) } else { (0.0, 0.0) };
                assert!((jx[(r, c)] - wx).abs() < 1e-6, "{}", jx[(r, c)]);
                assert!((jv[(r, c)] - wv).abs() < 1e-6, "{}", jv[(r, c)]);
            }
        }
    }
}
