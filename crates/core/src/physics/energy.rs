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

use glam::DVec3;

use super::collide::{Changes, DynamicSphere, calm, contact_power, spheres_energy};
use super::forces::{Model, applied_forces};
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
    // Σ_springs ½ k (L - L0)², `model.springs.iter().map(|s| s.energy(&state.x)).sum()`: the
    // same sum in the same order, its terms a block at a time (`fast/elastic.rs`).
    let elastic = super::fast::elastic::elastic(&model.springs, &state.x);
    energy_with_elastic(model, state, elastic)
}

/// [`energy`] with its elastic term `elastic` (J) computed elsewhere (implicit Euler's energy
/// guard sums it on the lattice).
#[must_use]
pub fn energy_with_elastic(model: &Model, state: &State, elastic: f64) -> Energy {
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
    Energy {
        kinetic,
        gravity,
        elastic,
        total: kinetic + gravity + elastic,
    }
}

/// The change of [`energy`] (J) that a collision response made, from what it recorded
/// ([`Changes`], after [`Changes::finish`]): the kinetic and gravitational terms of the
/// particles it changed, the elastic energy of their springs (each spring once, with both ends
/// as they were), and the dynamic spheres' energy. The same number as the difference of two
/// calls of [`energy`] up to rounding, without a pass over every spring: only the springs at a
/// particle that moved are visited (the others add exactly 0 J; the same bits as summing them,
/// `tests/collide.rs`).
#[must_use]
pub fn energy_change(model: &Model, state: &State, changes: &Changes) -> f64 {
    energy_change_of(model, &state.x, &state.v, &state.spheres, changes)
}

/// [`energy_change`] of the positions `x` (m), velocities `v` (m/s) and dynamic `spheres` after
/// the response.
#[must_use]
pub fn energy_change_of(
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    spheres: &[DynamicSphere],
    changes: &Changes,
) -> f64 {
    energy_change_calm(model, x, v, spheres, changes, false)
}

/// [`energy_change_of`], told by `calm_elsewhere` that every particle the response did not
/// change was calm before it (and so still is; a summary of the parts, `collide::Prepared`):
/// then only the changed particles are checked, not every one. The same result.
#[must_use]
pub fn energy_change_calm(
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    spheres: &[DynamicSphere],
    changes: &Changes,
    calm_elsewhere: bool,
) -> f64 {
    // The position of particle j before the response.
    let before = |j: usize| changes.of(j).map_or(x[j], |c| c.1);
    let records = &changes.particles;
    // A spring whose two ends are where they were adds `E_s - E_s`, exactly 0 J when its
    // energy is finite (ends at calm, equal positions): most of the records are velocities the
    // body's payment scaled, so most springs are left out without changing a bit of the sum
    // (which never holds -0, so adding +0 does nothing). `moved` marks the recorded particles
    // that moved or are not calm; only they and their neighbours have springs to visit (all
    // particles when some position is not calm).
    let mut moved = vec![0u64; x.len().div_ceil(64)];
    let mut records_calm = true;
    for &(i, x_old, _) in records {
        let i = i as usize;
        let here = calm(x[i]);
        records_calm &= here;
        if x[i] != x_old || !here {
            moved[i / 64] |= 1 << (i % 64);
        }
    }
    let moved = |j: usize| moved.get(j / 64).is_none_or(|w| w >> (j % 64) & 1 == 1);
    let mut visit = vec![0u64; x.len().div_ceil(64)];
    let all_calm = if calm_elsewhere {
        records_calm
    } else {
        x.iter().all(|p| calm(*p))
    };
    if all_calm {
        for &(j, ..) in records {
            let j = j as usize;
            if !moved(j) {
                continue;
            }
            visit[j / 64] |= 1 << (j % 64);
            for &s in model.springs_at(j) {
                let s = &model.springs[s as usize];
                let other = if s.a as usize == j { s.b } else { s.a } as usize;
                visit[other / 64] |= 1 << (other % 64);
            }
        }
    } else {
        visit.fill(u64::MAX);
    }
    // Each record's kinetic and gravitational terms first, independent of each other; then
    // the sum in record order, the springs of a visited record after its terms (the same
    // operations in the same order as one loop, so the same bits; the sum alone keeps its
    // register, where one loop spilled it for the springs' work).
    let gravity = model.gravity;
    let terms: Vec<[f64; 2]> = (records.iter())
        .map(|&(i, x_old, v_old)| {
            let i = i as usize;
            let m = model.mass[i];
            [
                0.5 * m * (v[i].length_squared() - v_old.length_squared()),
                m * gravity.dot(x[i] - x_old),
            ]
        })
        .collect();
    let mut delta = 0.0;
    for (&(i, ..), &[kinetic, lift]) in records.iter().zip(&terms) {
        delta += kinetic;
        delta -= lift;
        let i = i as usize;
        if visit[i / 64] >> (i % 64) & 1 == 0 {
            // Every spring at i has both ends where they were: 0 J.
            continue;
        }
        let i_still = !moved(i);
        for &s in model.springs_at(i) {
            let s = &model.springs[s as usize];
            let (a, b) = (s.a as usize, s.b as usize);
            let other = if a == i { b } else { a };
            if i_still && !moved(other) && calm(x[other]) {
                // Both ends where they were: 0 J.
                continue;
            }
            if other < i && changes.of(other).is_some() {
                // Counted with the other end, which comes first.
                continue;
            }
            delta += s.energy(x) - s.energy_between(before(a), before(b));
        }
    }
    delta + spheres_energy(model.gravity, spheres) - changes.spheres_before
}

/// The power that the dissipative forces take out of the particles at positions `x` (m) and
/// velocities `v` (m/s), split by source (W, each ≥ 0):
///
/// ```text
/// P_dampers = Σ_springs k_d ((v_b - v_a)·n)²          the damper force times the stretch rate
/// P_drag    = Σ_free c |v_i|²
/// P_contact = -Σ_i f_contact,i · v_i                  normal force and friction, see collide
/// ```
/// where `k_d` is a damper coefficient (N·s/m), `n` its spring's unit direction, `c` the viscous
/// drag (N·s/m). `scratch` (one entry per particle) receives the forces before contact; it is
/// used only when the model has colliders.
///
/// Integrated over a step with the method's own stages (see [`crate::physics::integrators`]),
/// these powers give the energy dissipated, so that
/// `E_kinetic + E_gravity + E_elastic + dissipated = E_0` for an exact integrator.
#[must_use]
pub fn dissipated_power(model: &Model, x: &[DVec3], v: &[DVec3], scratch: &mut [DVec3]) -> Power {
    let mut dampers = 0.0;
    for s in model.springs.iter().filter(|s| s.damping != 0.0) {
        let (a, b) = (s.a as usize, s.b as usize);
        let d = x[b] - x[a];
        let length = d.length();
        if length == 0.0 {
            continue;
        }
        let rate = (v[b] - v[a]).dot(d) / length;
        dampers += s.damping * rate * rate;
    }
    let mut drag = 0.0;
    if model.drag != 0.0 {
        for (v, &w) in v.iter().zip(&model.inv_mass) {
            if w != 0.0 {
                drag += model.drag * v.length_squared();
            }
        }
    }
    let contact = if model.colliders.is_empty() {
        0.0
    } else {
        applied_forces(model, x, v, scratch);
        contact_power(model, x, v, scratch)
    };
    Power {
        dampers_and_drag: dampers + drag,
        contact,
    }
}

/// Dissipated power by source (W); see [`dissipated_power`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Power {
    /// Spring dampers and viscous drag (W).
    pub dampers_and_drag: f64,
    /// Contact forces and friction of the colliders (W).
    pub contact: f64,
}

impl Power {
    /// `self + w p`: one term of a quadrature.
    #[must_use]
    pub fn plus(self, w: f64, p: Power) -> Power {
        Power {
            dampers_and_drag: self.dampers_and_drag + w * p.dampers_and_drag,
            contact: self.contact + w * p.contact,
        }
    }
}

/// Energy taken out of a system (J), by where it went. Positive: removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Dissipated {
    /// By spring dampers and viscous drag: their power integrated with the method's stages (J).
    pub dampers_and_drag: f64,
    /// By the colliders' contact forces and friction during the steps (J).
    pub contact_forces: f64,
    /// By what happens between steps: collision responses (bounces, projection), sphere
    /// impulses, and implicit Euler's contact constraints (J). Work done on the system by a
    /// driven (kinematic) sphere counts negative.
    pub contacts: f64,
    /// By the method itself on purpose: Verlet's damping factor and its constraint projection
    /// (J).
    pub method: f64,
    /// The sum (J).
    pub total: f64,
}

impl Dissipated {
    /// The sum of two (of two steps, or of two bodies), with `total` recomputed.
    #[must_use]
    pub fn plus(self, o: Dissipated) -> Dissipated {
        Dissipated {
            dampers_and_drag: self.dampers_and_drag + o.dampers_and_drag,
            contact_forces: self.contact_forces + o.contact_forces,
            contacts: self.contacts + o.contacts,
            method: self.method + o.method,
            total: 0.0,
        }
        .summed()
    }

    /// The same with `total` set to the sum of the parts.
    #[must_use]
    pub fn summed(mut self) -> Dissipated {
        self.total = self.dampers_and_drag + self.contact_forces + self.contacts + self.method;
        self
    }

    /// Adds `dt · p` (one step's quadrature of the powers `p`, W) to the force parts.
    pub fn add_power(&mut self, dt: f64, p: Power) {
        self.dampers_and_drag += dt * p.dampers_and_drag;
        self.contact_forces += dt * p.contact;
    }
}
