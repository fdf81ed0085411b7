//! Contact force and friction during a step (module docs of `collide`, "Contact force").

use glam::DVec3;

use super::{Collider, Contact, World};

/// `v·N` (m/s) up to which a particle counts as not moving away, so that the contact force still
/// holds it: the velocity response sets `v·N = 0`, which rounding may turn into `+1e-17`.
pub(crate) const ROUNDING_SPEED: f64 = 1e-9;

/// Coefficients of contact and collision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Restitution `k_r` of particle–collider collisions (dimensionless, 0..=1; course 0.8).
    pub restitution: f64,
    /// Coulomb friction coefficient `k_f` (dimensionless; course 0.3 in 2021, 0.2 in 2023).
    pub friction: f64,
    /// Contact band `ε` (m): closer than this to a surface counts as touching (course 0.01).
    pub epsilon: f64,
    /// Speed `v_rest` (m/s) below which a contact is resting: no bounce, static friction.
    pub rest_speed: f64,
    /// Restitution `e` of sphere–particle impulses (course 0: the cloth does not bounce).
    pub sphere_particle_restitution: f64,
    /// Restitution `e` of sphere–sphere impulses (course 0.8).
    pub sphere_sphere_restitution: f64,
}

impl ContactParams {
    /// NYCU HW1 2021: restitution 0.8, friction 0.3, ε = 0.01 m; with this crate's resting
    /// speed 0.05 m/s and the 2022 sphere restitutions (sphere–particle 0, sphere–sphere 0.8).
    #[must_use]
    pub fn course_2021() -> ContactParams {
        ContactParams {
            restitution: 0.8,
            friction: 0.3,
            epsilon: 0.01,
            rest_speed: 0.05,
            sphere_particle_restitution: 0.0,
            sphere_sphere_restitution: 0.8,
        }
    }

    /// NYCU HW1 2023: as 2021 with friction 0.2.
    #[must_use]
    pub fn course_2023() -> ContactParams {
        ContactParams {
            friction: 0.2,
            ..ContactParams::course_2021()
        }
    }
}

impl Default for ContactParams {
    /// [`ContactParams::course_2021`]. Its `v_rest = 0.05` m/s is about five steps of gravity at
    /// the course's `dt = 0.001` s: slower approaches are resting contact.
    fn default() -> ContactParams {
        ContactParams::course_2021()
    }
}

/// Adds the contact force and friction of the model's colliders to `f` (N); see the module
/// documentation for the formulas. Called by [`crate::physics::forces()`] after the springs, only when
/// the model has colliders. Pure and allocation-free.
pub fn contact_forces<'a>(model: impl Into<World<'a>>, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
    let model = model.into();
    for i in 0..model.particle_count() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        if let Some(total) = with_contact(&model, x[i], v[i], f[i]) {
            f[i] = total;
        }
    }
}

/// The power the contact forces and friction take out of the particles (W, ≥ 0):
///
/// ```text
/// P_contact = -Σ_i f_contact,i · v_i = -Σ_i (λ N + f_f) · v_i
/// ```
/// where `f_applied` are the forces on the particles before contact (N): weight, drag and
/// springs, as [`crate::physics::forces::applied_forces`] computes them. Each term is ≥ 0 by
/// construction (`f_c·v = λ N·v ≤ 0`, `f_f·v_T ≤ 0`, module docs).
#[must_use]
pub fn contact_power<'a>(
    model: impl Into<World<'a>>,
    x: &[DVec3],
    v: &[DVec3],
    f_applied: &[DVec3],
) -> f64 {
    let model = model.into();
    let mut power = 0.0;
    for i in 0..model.particle_count() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        if let Some(total) = with_contact(&model, x[i], v[i], f_applied[i]) {
            power -= (total - f_applied[i]).dot(v[i]);
        }
    }
    power
}

/// The force on particle `i` at `x` moving at `v` after the colliders added their contact force
/// and friction to the applied force `f` (N), each collider in order seeing what the previous
/// ones left (module docs); `None` when no collider pushes it.
fn with_contact(model: &World<'_>, x: DVec3, v: DVec3, f: DVec3) -> Option<DVec3> {
    contact_force(model.colliders, model.contact, x, v, f)
}

/// [`contact_forces`] for one particle at `x` (m) moving at `v` (m/s) with applied force `f`
/// (N): the force after `colliders` added their contact force and friction, or `None` when no
/// collider pushes it. The stencil's fused pass calls this for the particles that may touch.
pub(crate) fn contact_force(
    colliders: &[Collider],
    params: &ContactParams,
    x: DVec3,
    v: DVec3,
    f: DVec3,
) -> Option<DVec3> {
    let mut f = f;
    let mut touched = false;
    for collider in colliders {
        if !collider.may_touch(x, params.epsilon) {
            continue;
        }
        let Some(Contact { phi, normal }) = collider.contact(x) else {
            continue;
        };
        let push = normal.dot(f);
        let v_n = normal.dot(v);
        if phi >= params.epsilon || push >= 0.0 || v_n > ROUNDING_SPEED {
            continue;
        }
        // λ = -N·f > 0; f_T = f - (N·f) N; v_T = v - (v·N) N.
        let load = -push;
        let f_t = f - push * normal;
        let v_t = v - v_n * normal;
        // f_c = λ N cancels the push; f_f resists sliding.
        f += load * normal + friction_force(params.friction * load, f_t, v_t, params.rest_speed);
        touched = true;
    }
    touched.then_some(f)
}

/// Coulomb friction (N) with limit `limit = k_f λ` (N), for tangential force `f_t` (N) and
/// tangential velocity `v_t` (m/s): kinetic above `rest_speed`, static below (module docs).
fn friction_force(limit: f64, f_t: DVec3, v_t: DVec3, rest_speed: f64) -> DVec3 {
    let speed = v_t.length();
    if speed > 0.0 && speed >= rest_speed {
        // Kinetic: -k_f λ t̂ with the unit tangent t̂ = v_T/|v_T|.
        return (-limit / speed) * v_t;
    }
    // Static: cancel f_T and damp v_T at the rate that reaches the limit at |v_T| = v_rest.
    let damping = if rest_speed > 0.0 {
        limit / rest_speed
    } else {
        0.0
    };
    let mut f_f = -f_t - damping * v_t;
    // Coulomb limit: |f_f| ≤ k_f λ.
    let magnitude = f_f.length();
    if magnitude > limit {
        f_f *= limit / magnitude;
    }
    // Never push along the sliding direction (f_f·v_T ≤ 0): friction only dissipates.
    let along = f_f.dot(v_t);
    if along > 0.0 {
        f_f -= (along / (speed * speed)) * v_t;
    }
    f_f
}
