//! Colliders and collision response: planes, spheres, bowls, a plane with a hole, dynamic spheres.
//!
//! # Theory
//!
//! **Geometry.** Every static collider describes, for a point `x`, a signed distance `φ(x)` (m) to
//! its surface, positive on the side where particles may be, and the unit normal `N(x)` pointing
//! into that side ([`Collider::contact`]). A particle is *in contact* when it is closer than the
//! contact band `ε` (m) to the surface or already inside (`φ < ε`); the course uses `ε = 0.01` m.
//!
//! **Contact force** (NYCU Computer Animation HW1 2021–2023, `docs/course.md` §2), added in
//! [`super::forces::forces`] after the springs so that every stage of every integrator sees it
//! ([`contact_forces`]). When a particle is in contact, not moving away (`v·N ≤ 0`) and the
//! accumulated force `f` pushes into the surface (`N·f < 0`):
//!
//! ```text
//! λ    = -N·f                          normal load, > 0
//! f_c  = λ N                           cancels the push: N·(f + f_c) = 0
//! f_T  = f - (N·f) N                   tangential part of the applied force
//! v_T  = v - (v·N) N                   tangential velocity
//! f_f  = -k_f λ v_T/|v_T|              Coulomb friction, unit tangent,   if |v_T| ≥ v_rest
//! f_f  = clamp_{k_f λ}(-f_T - (k_f λ / v_rest) v_T)   stick band,        if |v_T| < v_rest
//! ```
//! where
//! - `f`: force on the particle before contact (N), `v`: its velocity (m/s)
//! - `k_f`: friction coefficient (dimensionless; 0.3 in 2021, 0.2 in 2023)
//! - `v_rest`: speed below which a contact counts as resting (m/s), [`ContactParams::rest_speed`]
//! - `clamp_F(g)`: `g` scaled down to length `F` when longer; any part along `+v_T` is removed
//!
//! The course's friction is the first line. Its unit tangent flips sign every step once the
//! particle has almost stopped, because a force does not know the step `dt` and overshoots
//! `v_T = 0`: a block on a slope steeper than its friction angle allows still creeps. Below
//! `v_rest` the friction therefore becomes *static* (Karnopp 1985): it cancels the tangential
//! force, up to the Coulomb limit `k_f λ`, and damps the small sliding speed left. Neither part
//! ever pushes along `v_T`, so friction only removes energy (`f_f·v_T ≤ 0`), and so does `f_c`
//! (`f_c·v = λ (N·v) ≤ 0`, which is why a particle moving away gets no contact force). Pinned
//! particles are skipped. Only the explicit right-hand side sees contact: the implicit method's
//! Jacobian leaves it out, and XPBD, which does not call the force function, gets contact only
//! from [`resolve`].
//!
//! **Velocity response and projection** after every step ([`resolve`]). For each particle in
//! contact, inside the collider (`φ < 0`) it is first moved onto the surface; then, if it moves
//! into the surface, the normal velocity is reflected with restitution `k_r` (0.8 in the course).
//! Moving a particle changes more than its height: the springs attached to it stretch or squeeze
//! while its neighbours stay where they are. So the projection is paid for, like a climb, out of
//! kinetic energy (an *energy budget*, the velocity-level energy clamp of Su, Sheth & Fedkiw
//! 2013): first the particle's own, then, for what that does not cover, the whole body's:
//!
//! ```text
//! Δx   = -φ N                          onto the surface, when φ < 0
//! Δu   = -g·Δx + max(0, E_s,i(x + Δx) - E_s,i(x)) / m
//!                                      potential energy per kg that Δx adds (J/kg)
//! v_N  = v·N,  v_T = v - v_N N
//! s²   = v_N² - 2 Δu                   squared normal speed AT the surface (m²/s²)
//! s² < 0:  ½ |v_T|² pays the rest; what it cannot pay, o = -m (½|v_T|² + ½ s²), is owed
//! v_N' = k_r s   if approaching and s > v_rest      (course: v' = -k_r v_N + v_T)
//! v_N' = 0       if approaching and s ≤ v_rest      resting contact, no bounce
//! v_N' = s       if already moving away
//! v_T' = max(0, 1 - k_f (v_N' - v_N) / |v_T|) v_T   friction of the impact
//! v'   = v_T' + v_N' N
//! after all particles:  v_j ← √(max(0, 1 - O/K)) v_j  for every free particle j,  O = Σ o
//! ```
//! where `g` is gravity (m/s²), `m` the particle's mass (kg), `E_s,i(p)` the elastic energy (J)
//! of the springs at particle `i` with `i` at `p` and every neighbour where it was before the
//! responses (so that the answer does not depend on the order of the particles), `K` the body's
//! kinetic energy (J) and `o`, `O` (J) what a particle and all of them owe ([`take_kinetic`]).
//! Without penetration `Δu = 0` and `s = |v_N|`: this is the course's `v' = -k_r v_N + v_T`.
//! With penetration, the integrator has let the particle fall `|φ|` below the surface and gain
//! the kinetic energy of that fall; moving it back without taking that energy away would make
//! every bounce *add* `m Δu` joules: the height regained and, on a jelly cube, the squeeze of the
//! springs above the particle. A spring that the move relaxes gives nothing back: that energy is
//! lost in the contact. For `k_r ≤ 1`
//!
//! ```text
//! E' - E = Σ_i m (Δu_true,i - Δu_i) - Σ_i (1 - k_r²) ½ m s_i² - friction - resting + C  ≤  C
//! ```
//! where `Δu_true` is `Δu` without the `max(0, ·)` and `C` (J) is the energy of the springs
//! between two particles that both moved (each was measured with the other held) plus what the
//! body could not pay (`O > K`: a body almost at rest whose springs push a particle in). Both are
//! left out of the bound on purpose: the projection is always done in full, so no particle ever
//! ends a step inside a collider. On the course scenes the ledger's `contacts` term stays ≥ 0
//! (`tests/contact_energy.rs`); before the budget it reached −7.6 % of E₀ on `cube-plane`.
//! Implicit Euler's contacts inside its solve keep the bound too: a constraint impulse `J ≥ 0`
//! never sends a particle away from the surface faster than the obstacle moves, so its work
//! `J (v' - V)·N ≤ 0`, and what it leaves inside is this response's paid projection
//! (`integrators/implicit_euler/contacts.rs`). Not yet bounded: a dynamic sphere's reaction in
//! that solve (up to `J²/(2M)` per contact; `cloth-spheres` at dt = 0.04 s still ends with a
//! negative `contacts` term). XPBD holds its contacts in every substep (`integrators/xpbd.rs`).
//! The
//! impact friction is the
//! velocity-level Coulomb rule of Bridson, Fedkiw & Anderson (2002): the tangential velocity loses
//! at most `k_f` times the normal velocity change, and never reverses. The resting threshold is
//! Baraff's (1997): an approach slower than `v_rest` is resting contact, not a collision; without
//! it a resting particle would bounce forever in ever smaller hops.
//!
//! No tunnelling: the plane, the sphere and the floor with a hole are solid regions (a
//! half-space, a ball, the ground around a shaft), and a bowl holds everything inside its rim
//! circle, so a particle that crossed a surface in one step is inside and is projected back to
//! the side it came from, however fast it was. (The one gap: a bowl without a floor around it
//! loses a particle that leaves through its wall just below the rim and ends the step outside
//! the rim circle.)
//!
//! **Dynamic spheres** (cloth scenes, NYCU HW1 2022/2024, `docs/course.md` §3; [`step_spheres`]) move by
//! semi-implicit Euler under gravity, or at a set velocity when kinematic. A sphere and a particle,
//! or two spheres, that overlap exchange an impulse along the line of centres and are pushed apart:
//!
//! ```text
//! d̂    = (x_b - x_a) / |x_b - x_a|                      from body a to body b
//! v_rel = (v_b - v_a)·d̂                                 < 0: approaching
//! p     = r_a + r_b - |x_b - x_a|                       penetration (m), r = 0 for a particle
//! x_a  -= w_a / (w_a + w_b) p d̂,   x_b += w_b / (w_a + w_b) p d̂
//! ΔU    = -g·(m_a Δx_a + m_b Δx_b) + max(0, E_s(x_b') - E_s(x_b))   what the separation adds (J)
//! s²    = v_rel² - 2 (w_a + w_b) ΔU                    relative normal speed² after it
//! v_rel' = e s  if approaching,  s  if separating;  s² < 0: v_rel' = 0, the rest owed
//! J     = (v_rel' - v_rel) / (w_a + w_b)               (N·s)
//! v_a  -= w_a J d̂,   v_b += w_b J d̂
//! ```
//! where `w = 1/m` (1/kg) is zero for a kinematic sphere and a pinned particle, `e` the
//! restitution (sphere–particle 0, sphere–sphere 0.8 in the course), `g` gravity (m/s²) and
//! `E_s` (J) the springs at the particle `b` with its neighbours held. The separation is paid
//! like a collider's projection (Su, Sheth & Fedkiw 2013): from the pair's relative normal
//! kinetic energy `½ μ v_rel²`, `μ = 1/(w_a + w_b)`, and what that cannot pay the system pays
//! from its kinetic energy after all pairs (`budget.rs`; not with a kinematic sphere, which is
//! driven from outside and may do work). Without a climb (`ΔU = 0`) this is the textbook
//! impulse `J = -(1 + e) v_rel μ`: momentum is conserved (`m_a Δv_a + m_b Δv_b = 0`), the
//! kinetic energy falls by `½ μ (1 - e²) v_rel²`, and the separation keeps the centre of mass
//! where it was (`m_a Δx_a + m_b Δx_b = 0`). The course reference pushes the bodies apart by
//! only 0.15 of the penetration; here the whole penetration is removed at once.
//!
//! References: NYCU Computer Animation HW1 (2021–2024), `docs/course.md` §2–3; D. Baraff, "An
//! Introduction to Physically Based Modeling: Rigid Body Simulation II — Nonpenetration
//! Constraints", SIGGRAPH 1997 course notes (colliding contact, the impulse `J`, the resting
//! threshold); R. Bridson, R. Fedkiw, J. Anderson, "Robust Treatment of Collisions, Contact and
//! Friction for Cloth Animation", SIGGRAPH 2002 (friction of impulses, positional projection);
//! D. Karnopp, "Computer Simulation of Stick-Slip Friction in Mechanical Dynamic Systems",
//! J. Dynamic Systems, Measurement, and Control 107 (1985) (the stick band); J. Su, R. Sheth,
//! R. Fedkiw, "Energy Conservation for the Simulation of Deformable Bodies", IEEE Transactions on
//! Visualization and Computer Graphics 19(2), 2013 (a position change paid for by the kinetic
//! energy, so that a correction never raises the total).

use glam::DVec3;

use super::springs::Spring;

mod budget;
mod force;
mod geometry;
mod prepared;
mod response;
mod spheres;

pub use budget::take_kinetic_with_spheres;
use budget::{above_rounding, energy_rise};
pub(crate) use force::ROUNDING_SPEED;
#[cfg(test)]
pub(crate) use force::contact_force;
pub use force::{ContactParams, contact_forces, contact_power};
use geometry::distance_and_direction;
pub(crate) use geometry::{Broad, RIM_MARGIN};
pub use geometry::{Collider, Contact};
pub use prepared::{PartBounds, Prepared, Taken};
pub use response::{Changes, after_step, resolve, resolve_logged, resolve_prepared, take_kinetic};
use response::{pay, respond};
pub use spheres::{
    DynamicSphere, advance_spheres, collide_spheres, collide_spheres_logged,
    collide_spheres_prepared, step_spheres,
};

/// What the colliders read of the system: a view of the model, so that this module imports
/// neither the model (`forces`) nor the state (`particles`), which both build on it. `&Model`
/// converts into a `World` and `&mut State` into [`Bodies`], so every function here is called
/// with `&model` and `&mut state` as they are.
#[derive(Clone, Copy, Debug)]
pub struct World<'a> {
    /// Static obstacles, normals of unit length.
    pub colliders: &'a [Collider],
    /// Restitution, friction and contact band.
    pub contact: &'a ContactParams,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Inverse mass of each particle (1/kg); zero for a pinned particle. Its length is the
    /// particle count.
    pub inv_mass: &'a [f64],
    /// The springs, whose elastic energy a projection changes (module docs, "energy budget").
    pub springs: &'a [Spring],
    /// The indices of the springs at particle `i` are
    /// `incident[incident_start[i]..incident_start[i + 1]]` (empty slices: no springs).
    pub incident: &'a [u32],
    /// Where each particle's list starts in `incident` (particle count + 1 entries, or empty).
    pub incident_start: &'a [u32],
}

impl<'a> From<&World<'a>> for World<'a> {
    fn from(world: &World<'a>) -> World<'a> {
        *world
    }
}

impl World<'_> {
    /// Number of particles.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.inv_mass.len()
    }

    /// Elastic energy (J) of the springs at particle `i` with `i` at `at` (m) and every other
    /// end where `x` has it: the part of `E_elastic` that moving `i` alone changes.
    #[must_use]
    pub fn elastic_at(&self, x: &[DVec3], i: usize, at: DVec3) -> f64 {
        self.elastic_at_with(|j| x[j], i, at)
    }

    /// [`World::elastic_at_with`] at `to` and at `from` (m), `(E_to, E_from)` (J), in one pass
    /// over the springs at `i` (each other end looked up once): the same two sums, each in
    /// the springs' order from `.sum()`'s start.
    #[must_use]
    pub fn elastic_at_both(
        &self,
        x: impl Fn(usize) -> DVec3,
        i: usize,
        to: DVec3,
        from: DVec3,
    ) -> (f64, f64) {
        let (Some(&first), Some(&end)) =
            (self.incident_start.get(i), self.incident_start.get(i + 1))
        else {
            return (0.0, 0.0);
        };
        let start: f64 = std::iter::empty::<f64>().sum();
        let (mut e_to, mut e_from) = (start, start);
        for &k in &self.incident[first as usize..end as usize] {
            let s = &self.springs[k as usize];
            let other = x(if s.a as usize == i { s.b } else { s.a } as usize);
            e_to += s.energy_between(to, other);
            e_from += s.energy_between(from, other);
        }
        (e_to, e_from)
    }

    /// [`World::elastic_at`] with every other end `j` at `x(j)` (m).
    #[must_use]
    pub fn elastic_at_with(&self, x: impl Fn(usize) -> DVec3, i: usize, at: DVec3) -> f64 {
        let (Some(&start), Some(&end)) =
            (self.incident_start.get(i), self.incident_start.get(i + 1))
        else {
            return 0.0;
        };
        self.incident[start as usize..end as usize]
            .iter()
            .map(|&k| {
                let s = &self.springs[k as usize];
                let other = if s.a as usize == i { s.b } else { s.a } as usize;
                s.energy_between(at, x(other))
            })
            .sum()
    }
}

/// What collisions change after a step: a view of the state's positions (m), velocities (m/s),
/// Verlet history and dynamic spheres.
#[derive(Debug)]
pub struct Bodies<'a> {
    /// Positions (m).
    pub x: &'a mut [DVec3],
    /// Velocities (m/s).
    pub v: &'a mut [DVec3],
    /// Positions one step ago (m), kept consistent for position Verlet.
    pub x_prev: &'a mut [DVec3],
    /// True when `x_prev` holds a Verlet history.
    pub history_valid: bool,
    /// The moving spheres.
    pub spheres: &'a mut [DynamicSphere],
}

impl Bodies<'_> {
    /// The same view for a shorter borrow (to pass it on and use it again).
    pub fn reborrow(&mut self) -> Bodies<'_> {
        Bodies {
            x: self.x,
            v: self.v,
            x_prev: self.x_prev,
            history_valid: self.history_valid,
            spheres: self.spheres,
        }
    }
}

/// True when every coordinate of `p` is below 1e50 m in size (false for NaN and ±∞): a spring
/// between two calm points has a finite elastic energy for any stiffness below 1e200 N/m.
#[must_use]
pub(crate) fn calm(p: DVec3) -> bool {
    p.abs().cmplt(DVec3::splat(CALM)).all()
}

/// The bound of [`calm`] (m).
pub(crate) const CALM: f64 = 1e50;

/// Kinetic and gravitational energy of the non-kinematic dynamic `spheres` under `gravity`
/// (m/s²), in J, as [`crate::physics::energy::energy`] counts them.
#[must_use]
pub fn spheres_energy(gravity: DVec3, spheres: &[DynamicSphere]) -> f64 {
    spheres
        .iter()
        .filter(|s| !s.kinematic)
        .map(|s| 0.5 * s.mass * s.velocity.length_squared() - s.mass * gravity.dot(s.center))
        .sum()
}

/// After a particle's `x` or `v` changed outside the integrator: Verlet's implied velocity
/// `(x - x_prev)/dt` becomes the new `v` again (`x_prev = x - dt v`), if Verlet has a history.
fn keep_verlet_history(history_valid: bool, x_prev: &mut DVec3, x: DVec3, v: DVec3, dt: f64) {
    if history_valid {
        *x_prev = x - dt * v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::springs::SpringKind;

    /// Both sums of one pass are the two sums of [`World::elastic_at_with`], bit for bit: a
    /// particle with springs (one to itself, one twice), one without, one out of range, other
    /// ends moved, at ±0, infinite and NaN.
    #[test]
    fn elastic_at_both_is_two_sums() {
        let spring = |a: u32, b: u32, rest_length: f64| Spring {
            a,
            b,
            rest_length,
            stiffness: 300.0 + 50.0 * f64::from(a + b),
            damping: 0.0,
            kind: SpringKind::Struct,
        };
        let springs = [
            spring(0, 1, 0.1),
            spring(1, 2, 0.2),
            spring(2, 0, 0.15),
            spring(2, 2, 0.0),
            spring(1, 2, 0.3),
            spring(3, 1, 0.05),
        ];
        // Incidence lists as `Model::new` makes them: each particle's springs in order.
        let n = 5u32;
        let mut incident_start = vec![0u32];
        let mut incident = Vec::new();
        for p in 0..n {
            for (k, s) in springs.iter().enumerate() {
                for end in [s.a, s.b] {
                    if end == p {
                        incident.push(k as u32);
                    }
                }
            }
            incident_start.push(incident.len() as u32);
        }
        let params = ContactParams::default();
        let world = World {
            colliders: &[],
            contact: &params,
            gravity: DVec3::new(0.0, -9.8, 0.0),
            inv_mass: &[1.0; 5],
            springs: &springs,
            incident: &incident,
            incident_start: &incident_start,
        };
        let x = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.1, -0.0, 0.02),
            DVec3::new(0.05, 0.2, -0.1),
            DVec3::new(-0.3, 0.1, 0.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        let points = [
            DVec3::ZERO,
            DVec3::new(-0.0, 0.0, -0.0),
            DVec3::new(0.3, -0.1, 0.2),
            DVec3::new(1e200, 0.0, 0.0),
            DVec3::new(f64::INFINITY, 0.0, 0.0),
            DVec3::new(0.0, f64::NAN, 0.0),
        ];
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for i in 0..=n as usize {
            for shift in [DVec3::ZERO, DVec3::new(0.01, -0.02, 0.0)] {
                let at = |j: usize| x[j] + shift * j as f64;
                for to in points {
                    for from in points {
                        let (e_to, e_from) = world.elastic_at_both(at, i, to, from);
                        let want = (
                            world.elastic_at_with(at, i, to),
                            world.elastic_at_with(at, i, from),
                        );
                        assert!(
                            same(e_to, want.0) && same(e_from, want.1),
                            "particle {i}, {to} {from}: {e_to} {e_from} vs {want:?}"
                        );
                    }
                }
            }
        }
    }
}
