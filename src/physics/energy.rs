//! Mechanical energy of a mass-spring system.
//!
//! ```text
//! E_kinetic = Σ_i ½ m_i |v_i|²
//! E_gravity = Σ_i -m_i g · x_i          (= Σ m_i 9.8 y_i for g = (0, -9.8, 0))
//! E_elastic = Σ_springs ½ k (L - L0)²
//! ```
//! where `m_i` is in kg, `v_i` in m/s, `x_i` in m, `g` in m/s², `k` in N/m; energies in J.
//! Without damping, drag and collisions the total is conserved by the exact motion, so its drift
//! measures an integrator's error.
//!
//! Dynamic spheres (see [`super::collide::DynamicSphere`]) are bodies of the system too: their
//! `½ m_s |v_s|²` is added to the kinetic and their `-m_s g · c_s` to the gravitational energy
//! (`c_s`: centre, m). A kinematic sphere is driven from outside with infinite mass; it has no
//! energy of its own and is left out.

use serde::Serialize;

use super::forces::Model;
use super::particles::State;

/// Kinetic, gravitational and elastic energy (J).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Energy {
    /// `Σ ½ m |v|²` (J).
    pub kinetic: f64,
    /// `Σ -m g·x` (J).
    pub gravity: f64,
    /// `Σ ½ k (L - L0)²` (J).
    pub elastic: f64,
    /// Sum of the three (J).
    pub total: f64,
}

impl Energy {
    /// Adds two energies (of two bodies).
    #[must_use]
    pub fn plus(self, other: Energy) -> Energy {
        Energy {
            kinetic: self.kinetic + other.kinetic,
            gravity: self.gravity + other.gravity,
            elastic: self.elastic + other.elastic,
            total: self.total + other.total,
        }
    }
}

/// The energy of `state` under `model`.
#[must_use]
pub fn energy(model: &Model, state: &State) -> Energy {
    let mut kinetic = 0.0;
    let mut gravity = 0.0;
    for ((&m, x), v) in model.mass.iter().zip(&state.x).zip(&state.v) {
        kinetic += 0.5 * m * v.length_squared();
        gravity -= m * model.gravity.dot(*x);
    }
    for s in state.spheres.iter().filter(|s| !s.kinematic) {
        kinetic += 0.5 * s.mass * s.velocity.length_squared();
        gravity -= s.mass * model.gravity.dot(s.center);
    }
    let elastic: f64 = model.springs.iter().map(|s| s.energy(&state.x)).sum();
    Energy {
        kinetic,
        gravity,
        elastic,
        total: kinetic + gravity + elastic,
    }
}
