//! The homework a student implements: one trait per assignment and the plain data they use.
//!
//! Each trait mirrors the TODO list of a course (`docs/course.md`): [`RopeHomework`] is GAMES101
//! assignment 8 (2020), [`JellyHomework`] is NYCU Computer Animation HW1 (2023, the jelly in a
//! bowl), [`ClothHomework`] is NYCU Computer Animation HW1 (2022, the cloth and the spheres). A
//! student crate (`springlab homework new`) implements one trait for its `Student` struct;
//! [`super::Reference`] implements all three with springlab's own physics.
//!
//! # Conventions (every assignment)
//!
//! - Vectors are [`DVec3`] (`glam`, re-exported as `springlab::grade::DVec3`): `a + b`, `k * a`,
//!   `a.dot(b)`, `a.length()`, `a / a.length()`. Units are SI: positions in m, velocities in m/s,
//!   accelerations in m/s², forces in N, masses in kg, time steps in s (the GAMES101 rope in the
//!   course used pixels; the formulas do not care).
//! - Particle `i` is entry `i` of every slice. A pinned particle has inverse mass 0 (or
//!   `pinned: true`); it never moves.
//! - The integrators do not compute forces themselves: they receive a [`Physics`], whose
//!   [`Physics::accelerations`] is the reference physics of the system being stepped (springs,
//!   dampers, gravity, pinning). A mistake in a force function therefore costs points only in the
//!   force items, never in the integrator items, and the other way round.
//! - Every method must return (no panic, no endless loop) and produce finite numbers; the grader
//!   runs each check on its own thread with a time limit and scores the item zero otherwise.
//!
//! References: GAMES101 assignment 8, "Mass-spring system" (Lingqi Yan, 2020), §1.1–1.4; NYCU
//! Computer Animation HW1 "Mass-spring system" (2022 cloth, 2023 jelly), TODO #1–#4; D. Baraff,
//! A. Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998, §3 (backward Euler).

pub use glam::DVec3;

pub use crate::physics::SpringKind;

use super::system::Physics;

pub use super::data::{
    Body, Bowl, ContactCoefficients, Mass, Particle, Plane, Rope, Spring, SpringSetup, State,
};

/// GAMES101 assignment 8 (2020): the rope.
///
/// ```text
/// TODO 1  rope construction     node i at start + (end - start) i / (nodes - 1), i = 0 .. nodes-1;
///                               a spring (i, i+1) with rest length = initial spacing; pinned nodes
/// TODO 2  Hooke's law           f_a = k_s (b - a)/|b - a| · (|b - a| - l)   on a, -f_a on b
///                               (the sheet's f_{b→a} = -k_s (b - a)/|b - a| (|b - a| - l) is -f_a)
/// TODO 3  explicit Euler        x(t+dt) = x(t) + v(t) dt,        v(t+dt) = v(t) + a(t) dt
///         semi-implicit Euler   v(t+dt) = v(t) + a(t) dt,        x(t+dt) = x(t) + v(t+dt) dt
/// TODO 4  Verlet                x(t+dt) = x(t) + [x(t) - x(t-dt)] + a(t) dt²,
///                               then every spring back to its rest length (a rigid rod)
/// TODO 5  damping               x(t+dt) = x(t) + (1 - γ) [x(t) - x(t-dt)] + a(t) dt²
/// ```
/// where `a`, `b` are the two ends' positions (m), `k_s` the stiffness (N/m), `l` the rest
/// length (m), `a(t)` the acceleration from [`Physics::accelerations_of`] (m/s², zero for a
/// pinned mass), `dt` the time step (s) and `γ` the dimensionless damping factor (0.00005 in the
/// course). Units: the course's rope lives in pixels with gravity (0, -1); SI works the same.
pub trait RopeHomework: Send + Sync + 'static {
    /// TODO 1: `nodes` masses of `node_mass` kg evenly spaced from `start` to `end` (m), at rest
    /// (`last_position = position`), the masses listed in `pinned` pinned, and a spring of
    /// stiffness `stiffness` (N/m, damping 0) between each pair of neighbours whose rest length is
    /// their initial distance. The grader calls it with `nodes ≥ 2` and valid `pinned` indices.
    fn rope(
        &self,
        start: DVec3,
        end: DVec3,
        nodes: usize,
        node_mass: f64,
        stiffness: f64,
        pinned: &[usize],
    ) -> Rope;

    /// TODO 2: the force (N) the spring exerts on the end at `a` (m), by Hooke's law; the end at
    /// `b` gets the negative. `stiffness` in N/m, `rest_length` in m.
    fn spring_force(&self, a: DVec3, b: DVec3, stiffness: f64, rest_length: f64) -> DVec3;

    /// TODO 2: the net spring force (N) on every mass of `rope`: for every spring, its Hooke force
    /// on end `a` and the opposite force on end `b`, summed (no gravity; pinned masses included).
    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3>;

    /// TODO 3: one explicit Euler step of `dt` seconds: position with the OLD velocity.
    /// `physics.accelerations_of(rope)` gives `a(t)` for every mass.
    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics);

    /// TODO 3: one semi-implicit Euler step of `dt` seconds: position with the NEW velocity.
    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics);

    /// TODO 4 and 5: one Verlet step of `dt` seconds with damping factor `damping` (γ), then one
    /// pass over the springs moving both ends so each spring has its rest length again (each end
    /// half the correction; a pinned end does not move and the other end takes all of it).
    /// Update `last_position` to the position before the step. `velocity` may be left as is.
    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics);
}

/// NYCU Computer Animation HW1 (2023): the jelly cube falling into a bowl.
///
/// ```text
/// #1  springs        struct: axis neighbours; shear: the other 20 of the 26 neighbours in the
///                    3×3×3 block; bend: axis neighbours two apart
/// #2  spring force   f_a = -k_s (|x_a - x_b| - L0) l̂,            l̂ = (x_a - x_b)/|x_a - x_b|
///     damper force   f_a = -k_d ((v_a - v_b)·l̂) l̂
///     internal force Σ over springs: f_a on a, -f_a on b
/// #3  collision      v' = -k_r v_N + v_T, contact force, friction (plane, bowl)
/// #4  integrators    explicit Euler, implicit (backward) Euler, midpoint, RK4
/// ```
/// where `x` are positions (m), `v` velocities (m/s), `k_s` the stiffness (N/m), `k_d` the
/// damper coefficient (N·s/m) and `L0` the rest length (m). See the student README for every
/// formula in full.
pub trait JellyHomework: Send + Sync + 'static {
    /// #1: every spring of a lattice of `counts = [nx, ny, nz]` particles, where particle
    /// `(ix, iy, iz)` has index `ix + nx (iy + ny iz)` ([`super::cube_index`]).
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup>;

    /// #2: Hooke's force (N) on the particle at `xa` from the spring to `xb` (m).
    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3;

    /// #2: the damper's force (N) on the particle at `xa` moving at `va` (m/s), joined to the one
    /// at `xb` moving at `vb`; only the relative velocity along the spring counts.
    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3;

    /// #2: the internal force (N) on every particle: spring plus damper force of every spring,
    /// `f_a` on `a` and `-f_a` on `b` (no gravity).
    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3>;

    /// #3: collision of one particle with a plane (bounce, projection, contact force, friction).
    fn plane_collision(&self, plane: &Plane, particle: &mut Particle, c: &ContactCoefficients);

    /// #3: collision of one particle with the inside of a bowl (same rules, the bowl's normal).
    fn bowl_collision(&self, bowl: &Bowl, particle: &mut Particle, c: &ContactCoefficients);

    /// #4: one explicit Euler step of `dt` seconds.
    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one implicit (backward) Euler step of `dt` seconds: solve, do not predict.
    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one midpoint (RK2) step of `dt` seconds.
    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one classic fourth-order Runge–Kutta step of `dt` seconds.
    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics);
}

/// NYCU Computer Animation HW1 (2022): the cloth and the four spheres.
///
/// ```text
/// #1  springs        struct: grid neighbours; shear: both diagonals; bend: two apart
/// #2  forces         spring + damper force of every spring, as accelerations a = f w
/// #3  collision      sphere–particle impulse J = -(1 + e)(v_rel·d̂) / (w_s + w_p)
/// #4  integrators    explicit Euler, implicit (backward) Euler, midpoint, RK4
/// ```
/// where `w = 1/m` is an inverse mass (1/kg), `e` the restitution and `d̂` the unit vector from
/// the sphere's centre to the particle. See the student README for every formula in full.
pub trait ClothHomework: Send + Sync + 'static {
    /// #1: every spring of an `n × n` cloth, where particle (row `r`, column `c`) has index
    /// `r n + c` ([`super::cloth_index`]).
    fn springs(&self, n: usize) -> Vec<SpringSetup>;

    /// #2: Hooke's force (N) on the particle at `xa` from the spring to `xb` (m).
    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3;

    /// #2: the damper's force (N) on the particle at `xa` moving at `va` (m/s), joined to the one
    /// at `xb` moving at `vb`; only the relative velocity along the spring counts.
    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3;

    /// #2: the acceleration (m/s²) every particle gets from the springs and dampers:
    /// `a_i = w_i Σ f_i` with `w_i = inverse_mass[i]` (0 for a pinned corner). No gravity.
    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        inverse_mass: &[f64],
        springs: &[Spring],
    ) -> Vec<DVec3>;

    /// #3: collision of a sphere of `radius` (m) with one cloth particle: impulse with
    /// restitution `restitution`, then push both apart so they just touch.
    fn sphere_collision(
        &self,
        sphere: &mut Body,
        radius: f64,
        particle: &mut Body,
        restitution: f64,
    );

    /// #4: one explicit Euler step of `dt` seconds.
    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one implicit (backward) Euler step of `dt` seconds: solve, do not predict.
    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one midpoint (RK2) step of `dt` seconds.
    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics);

    /// #4: one classic fourth-order Runge–Kutta step of `dt` seconds.
    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics);
}

/// Index of particle `(ix, iy, iz)` in a cube lattice of `counts = [nx, ny, nz]` particles:
/// `ix + nx (iy + ny iz)` (x fastest, as springlab's cube builder).
#[must_use]
pub fn cube_index(counts: [usize; 3], ix: usize, iy: usize, iz: usize) -> usize {
    ix + counts[0] * (iy + counts[1] * iz)
}

/// Index of particle (row `r`, column `c`) of an `n × n` cloth: `r n + c`.
#[must_use]
pub fn cloth_index(n: usize, r: usize, c: usize) -> usize {
    r * n + c
}
