//! One body of the comparison: stepped by a homework's integrator, measured (positions,
//! velocities, energy), and the parting test of `live.rs`'s module docs.

use std::borrow::Cow;
use std::collections::VecDeque;

use glam::DVec3;
use springlab_homework::wire::{MAX_FRAME, method};

use super::super::assignments::{ClothHomework, JellyHomework, Rope, RopeHomework, State};
use super::super::remote::{CallFailure, Remote};
use super::super::system::Physics;
use super::{Assignment, Homework, Integrator, Parting, Quantity, Setup};
use crate::physics::{self, collide};

/// The body in the homework's own types.
enum Shape {
    Rope(Rope),
    Lattice(State),
}

/// A body and the physics it is stepped with.
///
/// A student's program may step ahead: one request returns the body after each of up to
/// `most` steps ([`super::LiveOptions::ahead`]) (`wire`'s STEPS), kept in `ahead` and taken one per step. The steps are
/// the program's own, each from its last answer, as single calls would give them; only the
/// scene's collision response comes between steps in this process. Where it changes the body
/// (a contact), the steps computed past it are dropped, the next request starts from the
/// changed body, and requests start again at one step, doubling while no contact interrupts
/// them. So the body is bit for bit the one of single calls (`tests/homework_live.rs`).
pub(super) struct Track {
    shape: Shape,
    physics: Physics,
    ahead: VecDeque<Shape>,
    /// Steps of the next request.
    batch: u32,
    /// Most steps of one request.
    most: u32,
    /// False when the program answers one call per step.
    batching: bool,
    /// Why the step after those in `ahead` did not come: raised at that step, as a single call
    /// failing there would be.
    failed: Option<CallFailure>,
    /// What the last collision response changed.
    changes: collide::Changes,
}

/// The trait object of a homework (its program's, for a [`Homework::Program`]).
enum Methods<'h> {
    Rope(&'h dyn RopeHomework),
    Jelly(&'h dyn JellyHomework),
    Cloth(&'h dyn ClothHomework),
}

impl<'h> Methods<'h> {
    fn of(homework: &'h Homework) -> Methods<'h> {
        match homework {
            Homework::Rope(h) => Methods::Rope(h.as_ref()),
            Homework::Jelly(h) => Methods::Jelly(h.as_ref()),
            Homework::Cloth(h) => Methods::Cloth(h.as_ref()),
            Homework::Program(remote) => match remote.assignment() {
                Assignment::Rope => Methods::Rope(remote),
                Assignment::Jelly => Methods::Jelly(remote),
                Assignment::Cloth => Methods::Cloth(remote),
            },
        }
    }
}

impl Track {
    /// The body at the step's start, in the types of `setup`'s assignment; a student's program
    /// may compute up to `most` steps per request (1: single calls).
    pub(super) fn new(setup: &Setup, most: u32) -> Track {
        let model = &setup.model;
        let x = &setup.start.x;
        let v = &setup.start.v;
        // The springs in the order springlab projects them (colour by colour: red-black on a
        // chain), so that a Verlet pass over the list in order is the reference's pass.
        let springs: Vec<physics::Spring> = model
            .spring_colours()
            .flatten()
            .map(|&i| model.springs()[i as usize])
            .collect();
        let shape = match setup.assignment {
            super::Assignment::Rope => Shape::Rope(Rope::from_physics(
                x,
                v,
                |i| model.mass.get(i).copied().unwrap_or(1.0),
                |i| model.inv_mass.get(i).is_some_and(|&w| w == 0.0),
                &springs,
            )),
            _ => Shape::Lattice(State {
                x: x.clone(),
                v: v.clone(),
            }),
        };
        Track {
            shape,
            physics: Physics::from_model(model.clone()),
            ahead: VecDeque::new(),
            batch: most.clamp(1, 8),
            most: most.max(1),
            batching: most > 1,
            failed: None,
            changes: collide::Changes::default(),
        }
    }

    /// One step of `setup.integrator` by `homework`, then the scene's collision response;
    /// a student's program may compute up to `budget` steps (this one included) in advance.
    pub(super) fn step(&mut self, homework: &Homework, setup: &Setup, budget: u64) {
        let ahead = match homework {
            Homework::Program(remote) => self.next_ahead(remote, setup, budget),
            _ => None,
        };
        match ahead {
            Some(shape) => self.shape = shape,
            None => self.call(homework, setup),
        }
        if let Shape::Lattice(state) = &mut self.shape
            && !setup.model.colliders.is_empty()
            && state.x.len() == setup.model.particle_count()
            && state.v.len() == state.x.len()
        {
            let speculative = !self.ahead.is_empty() || self.failed.is_some();
            let mut s =
                physics::State::new(std::mem::take(&mut state.x), std::mem::take(&mut state.v));
            // The response records every particle it changes: an empty record is an unchanged
            // body, told without a copy of it.
            self.changes.clear();
            collide::resolve_logged(&setup.model, &mut s, setup.dt, Some(&mut self.changes));
            state.x = s.x;
            state.v = s.v;
            if speculative && !self.changes.particles.is_empty() {
                // A contact: the steps computed from the body without it are not this body's
                // (nor is a failure after them).
                self.ahead.clear();
                self.failed = None;
                self.batch = 1;
            }
        }
    }

    /// One step as one call of the trait method.
    fn call(&mut self, homework: &Homework, setup: &Setup) {
        let (dt, p) = (setup.dt, &self.physics);
        match (&mut self.shape, Methods::of(homework)) {
            (Shape::Rope(rope), Methods::Rope(h)) => match setup.integrator {
                Integrator::ExplicitEuler => h.explicit_euler(rope, dt, p),
                Integrator::SemiImplicitEuler => h.semi_implicit_euler(rope, dt, p),
                _ => h.verlet(rope, dt, setup.damping, p),
            },
            (Shape::Lattice(state), Methods::Jelly(h)) => match setup.integrator {
                Integrator::ImplicitEuler => h.implicit_euler(state, dt, p),
                Integrator::Midpoint => h.midpoint(state, dt, p),
                Integrator::Rk4 => h.rk4(state, dt, p),
                _ => h.explicit_euler(state, dt, p),
            },
            (Shape::Lattice(state), Methods::Cloth(h)) => match setup.integrator {
                Integrator::ImplicitEuler => h.implicit_euler(state, dt, p),
                Integrator::Midpoint => h.midpoint(state, dt, p),
                Integrator::Rk4 => h.rk4(state, dt, p),
                _ => h.explicit_euler(state, dt, p),
            },
            _ => std::panic::panic_any(format!(
                "the crate implements the {} homework, this step needs the {} homework",
                homework.assignment().name(),
                setup.assignment.name()
            )),
        }
    }

    /// Steps of one request that fit a frame: half the frame limit over the body's size.
    fn most_steps(&self) -> u64 {
        let bytes = match &self.shape {
            Shape::Rope(r) => 16 + 64 * r.masses.len() + 40 * r.springs.len(),
            Shape::Lattice(s) => 16 + 24 * (s.x.len() + s.v.len()),
        };
        ((MAX_FRAME / 2 / bytes.max(1)) as u64).clamp(1, u64::from(self.most))
    }

    /// The next step from the program's requests ([`Track`]'s docs), or `None` when this step
    /// is a single call: the program may not run ahead (`budget` steps left to the target,
    /// counting this one). A step that failed in a request fails here, at its own step.
    fn next_ahead(&mut self, remote: &Remote, setup: &Setup, budget: u64) -> Option<Shape> {
        if self.ahead.is_empty()
            && let Some(failure) = self.failed.take()
        {
            std::panic::resume_unwind(Box::new(failure));
        }
        if !self.batching || (budget <= 1 && self.ahead.is_empty()) {
            return None;
        }
        if self.ahead.is_empty() {
            let count = budget.min(u64::from(self.batch)).min(self.most_steps());
            // At most `most`.
            let count = u32::try_from(count).unwrap_or(1);
            let (shapes, failed) = self.fetch(remote, setup, count);
            self.ahead.extend(shapes);
            self.failed = failed;
            self.batch = (self.batch * 2).min(self.most);
            if self.ahead.is_empty()
                && let Some(failure) = self.failed.take()
            {
                std::panic::resume_unwind(Box::new(failure));
            }
        }
        self.ahead.pop_front()
    }

    /// `count` steps of `setup.integrator` by the program, from the current body.
    fn fetch(
        &self,
        remote: &Remote,
        setup: &Setup,
        count: u32,
    ) -> (Vec<Shape>, Option<CallFailure>) {
        let (dt, p) = (setup.dt, &self.physics);
        match &self.shape {
            Shape::Rope(rope) => {
                let (m, damping) = match setup.integrator {
                    Integrator::ExplicitEuler => (method::ROPE_EXPLICIT_EULER, None),
                    Integrator::SemiImplicitEuler => (method::ROPE_SEMI_IMPLICIT_EULER, None),
                    _ => (method::ROPE_VERLET, Some(setup.damping)),
                };
                let (ropes, failed) = remote.rope_steps(m, rope, dt, damping, p, count);
                (ropes.into_iter().map(Shape::Rope).collect(), failed)
            }
            Shape::Lattice(state) => {
                let jelly = setup.assignment == Assignment::Jelly;
                let m = match (setup.integrator, jelly) {
                    (Integrator::ImplicitEuler, true) => method::JELLY_IMPLICIT_EULER,
                    (Integrator::Midpoint, true) => method::JELLY_MIDPOINT,
                    (Integrator::Rk4, true) => method::JELLY_RK4,
                    (_, true) => method::JELLY_EXPLICIT_EULER,
                    (Integrator::ImplicitEuler, false) => method::CLOTH_IMPLICIT_EULER,
                    (Integrator::Midpoint, false) => method::CLOTH_MIDPOINT,
                    (Integrator::Rk4, false) => method::CLOTH_RK4,
                    (_, false) => method::CLOTH_EXPLICIT_EULER,
                };
                let (states, failed) = remote.state_steps(m, state, dt, p, count);
                (states.into_iter().map(Shape::Lattice).collect(), failed)
            }
        }
    }

    /// What is wrong with the state a student's step returned, if anything.
    pub(super) fn problem(&self, method: &str, step: u64) -> Option<String> {
        let n = self.physics.particle_count();
        let (count, what) = match &self.shape {
            Shape::Rope(r) => (r.masses.len(), "masses"),
            Shape::Lattice(s) => (s.x.len().min(s.v.len()), "particles"),
        };
        if count != n {
            return Some(format!(
                "your {method}() returned {count} {what} at step {step}; the body has {n}"
            ));
        }
        let x = self.positions();
        let v = self.raw_velocities();
        let bad = (0..n).find(|&i| !x[i].is_finite() || !v[i].is_finite())?;
        let which = if x[bad].is_finite() {
            "velocity"
        } else {
            "position"
        };
        Some(format!(
            "your {method}() returned a {which} that is not a number (NaN or infinite) at step \
             {step}, particle {bad}"
        ))
    }

    /// Positions (m): a lattice's own list, a rope's gathered.
    pub(super) fn positions(&self) -> Cow<'_, [DVec3]> {
        match &self.shape {
            Shape::Rope(r) => Cow::Owned(r.masses.iter().map(|m| m.position).collect()),
            Shape::Lattice(s) => Cow::Borrowed(&s.x),
        }
    }

    /// Velocities (m/s) as the integrator left them.
    pub(super) fn raw_velocities(&self) -> Cow<'_, [DVec3]> {
        match &self.shape {
            Shape::Rope(r) => Cow::Owned(r.masses.iter().map(|m| m.velocity).collect()),
            Shape::Lattice(s) => Cow::Borrowed(&s.v),
        }
    }

    /// Velocities (m/s); a Verlet rope's are `(x_n - x_{n-1})/dt`.
    pub(super) fn velocities(&self, setup: &Setup) -> Cow<'_, [DVec3]> {
        match &self.shape {
            Shape::Rope(r) if setup.integrator == Integrator::Verlet => Cow::Owned(
                r.masses
                    .iter()
                    .map(|m| (m.position - m.last_position) / setup.dt)
                    .collect(),
            ),
            _ => self.raw_velocities(),
        }
    }

    /// A lattice's state replaced by positions `x` (m) and velocities `v` (m/s): the lesson's
    /// own step (`handover.rs`); false for a rope, which keeps its state.
    pub(super) fn set_lattice(&mut self, x: &[DVec3], v: &[DVec3]) -> bool {
        match &mut self.shape {
            Shape::Lattice(s) => {
                s.x.clear();
                s.x.extend_from_slice(x);
                s.v.clear();
                s.v.extend_from_slice(v);
                true
            }
            Shape::Rope(_) => false,
        }
    }

    /// Largest speed (m/s); 0 when any is not finite.
    pub(super) fn speed(&self) -> f64 {
        // √ of the largest |v|² is the largest √|v|² (√ rounds correctly and never decreases):
        // one square root instead of one per particle.
        self.raw_velocities()
            .iter()
            .map(|v| v.length_squared())
            .fold(0.0, f64::max)
            .sqrt()
    }
}

/// Total energy (J) of positions `x` and velocities `v`: kinetic, gravity and elastic, under
/// the body's model (the lists are lent to a state and given back).
fn energy(setup: &Setup, x: &mut Vec<DVec3>, v: &mut Vec<DVec3>) -> f64 {
    if x.len() != setup.model.particle_count() || v.len() != x.len() {
        return f64::NAN;
    }
    // No history: the energy reads positions and velocities only.
    let state = physics::State {
        x: std::mem::take(x),
        v: std::mem::take(v),
        x_prev: Vec::new(),
        history_valid: false,
        spheres: Vec::new(),
    };
    let e = physics::energy::energy(&setup.model, &state).total;
    *x = state.x;
    *v = state.v;
    e
}

/// `max_i |a_i - b_i|`; NaN entries are passed over (0 when there is nothing else).
fn largest_difference(a: &[DVec3], b: &[DVec3]) -> f64 {
    // The square root of the largest square, as [`Track::speed`].
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length_squared())
        .fold(0.0, f64::max)
        .sqrt()
}

/// The body's length, speed and mass scales `L`, `V`, `M` and gravity `|g|` (module docs).
pub(super) struct Scales {
    length: f64,
    pub(super) velocity: f64,
    mass: f64,
    gravity: f64,
}

impl Scales {
    pub(super) fn of(setup: &Setup) -> Scales {
        let x = &setup.start.x;
        let (lo, hi) = x.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let diagonal = if x.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        };
        let length = diagonal.max(1e-3);
        let gravity = setup.model.gravity.length();
        let speed = setup.start.v.iter().map(|v| v.length()).fold(0.0, f64::max);
        let mass = setup
            .model
            .mass
            .iter()
            .filter(|m| m.is_finite())
            .sum::<f64>();
        Scales {
            length,
            velocity: (gravity * length).sqrt().max(speed).max(1e-3),
            mass,
            gravity,
        }
    }
}

/// The reference body after a step, as the reference's thread hands it to the worker: what the
/// parting test and the frames read of it.
pub(super) struct Snapshot {
    /// Positions (m).
    pub(super) x: Vec<DVec3>,
    /// Velocities as measured (m/s, [`Track::velocities`]).
    pub(super) v: Vec<DVec3>,
    /// Largest speed (m/s, [`Track::speed`]).
    pub(super) speed: f64,
}

impl Snapshot {
    pub(super) fn of(track: &Track, setup: &Setup) -> Snapshot {
        Snapshot {
            x: track.positions().into_owned(),
            v: track.velocities(setup).into_owned(),
            speed: track.speed(),
        }
    }
}

/// A body's positions (m) and energy (J) after a step, measured once.
pub(super) struct Measure {
    x: Vec<DVec3>,
    /// Total energy (J).
    pub(super) energy: f64,
}

impl Measure {
    pub(super) fn of(track: &Track, setup: &Setup) -> Measure {
        Measure::new(
            track.positions().into_owned(),
            track.velocities(setup).into_owned(),
            setup,
        )
    }

    /// The reference's measure from its snapshot.
    pub(super) fn of_snapshot(snapshot: &Snapshot, setup: &Setup) -> Measure {
        Measure::new(snapshot.x.clone(), snapshot.v.clone(), setup)
    }

    fn new(mut x: Vec<DVec3>, mut v: Vec<DVec3>, setup: &Setup) -> Measure {
        let energy = energy(setup, &mut x, &mut v);
        Measure { x, energy }
    }

    /// Positions (m).
    pub(super) fn positions(&self) -> &[DVec3] {
        &self.x
    }

    /// Largest distance to `other`'s particles (m).
    pub(super) fn distance(&self, other: &Measure) -> f64 {
        largest_difference(&self.x, &other.x)
    }
}

/// Σ_s k_s |L_s - L0_s| (N) of the model's springs at positions `x` (m): the stiffness-weighted
/// stretch that bounds how much the elastic energy can change ([`EnergyBound`]).
fn weighted_stretch(setup: &Setup, x: &[DVec3]) -> f64 {
    setup
        .model
        .springs()
        .iter()
        .map(|s| s.stiffness.abs() * (s.length(x) - s.rest_length).abs())
        .sum()
}

/// An upper bound of the energy difference `d_E = |E - Ê|` from `d_x` and `d_v` alone, so that
/// the parting test computes both bodies' energies (a pass over every spring each) only when
/// the bound does not keep `d_E` below its tolerance:
///
/// ```text
/// |ΔK|   = |Σ ½ m_i (v_i - v̂_i)·(v_i + v̂_i)|        ≤ d_v Σ m_i |v̂_i| + ½ M d_v²
/// |ΔU_g| = |Σ m_i g·(x_i - x̂_i)|                     ≤ M |g| d_x
/// |ΔU_s| = |Σ ½ k_s (2 e_s + δ_s) δ_s|,  |δ_s| ≤ 2 d_x ≤ 2 d_x S + 2 K d_x²
/// S      = Σ k_s |e_s|  ≤  S(x̂ᵃ) + 2 K max_i |x̂_i - x̂ᵃ_i|
/// ```
/// where `m_i` (kg) are the masses, `M = Σ m_i`, `g` gravity (m/s²), `k_s` (N/m) the
/// stiffnesses, `K = Σ k_s`, `e_s` (m) the reference's stretch `L_s - L0_s` of spring `s`,
/// `δ_s` (m) how much longer the student's spring is than the reference's, and `x̂ᵃ` the
/// reference's positions at an anchor step where `S` was summed (a spring moves its length by
/// at most the sum of its ends' displacements). The test trusts the bound only with a factor 2
/// to spare (the bound's own rounding); anything closer is decided by the exact energies.
pub(super) struct EnergyBound {
    /// `M` (kg).
    mass: f64,
    /// `K` (N/m).
    stiffness: f64,
    /// `x̂ᵃ` (m); empty before the first anchor.
    anchor: Vec<DVec3>,
    /// `S(x̂ᵃ)` (N).
    stretch: f64,
}

impl EnergyBound {
    pub(super) fn of(setup: &Setup) -> EnergyBound {
        EnergyBound {
            mass: setup.model.mass.iter().sum(),
            stiffness: setup
                .model
                .springs()
                .iter()
                .map(|s| s.stiffness.abs())
                .sum(),
            anchor: Vec::new(),
            stretch: 0.0,
        }
    }

    /// True when `d_E` cannot pass half of `tolerance` (J) at the reference's positions `x`
    /// (m) and velocities `v` (m/s), `d_x` (m) and `d_v` (m/s) (the type's docs); false means
    /// "not known": the exact energies decide.
    pub(super) fn holds(
        &mut self,
        setup: &Setup,
        x: &[DVec3],
        v: &[DVec3],
        dx: f64,
        dv: f64,
        tolerance: f64,
    ) -> bool {
        let momentum: f64 = setup
            .model
            .mass
            .iter()
            .zip(v)
            .map(|(m, v)| m * v.length())
            .sum();
        let (mass, stiffness) = (self.mass, self.stiffness);
        let rest = dv * momentum
            + 0.5 * mass * dv * dv
            + mass * setup.model.gravity.length() * dx
            + 2.0 * stiffness * dx * dx;
        let fits = |stretch: f64| {
            let bound = rest + 2.0 * dx * stretch;
            bound.is_finite() && 2.0 * bound <= tolerance
        };
        if self.anchor.len() == x.len() {
            let moved = largest_difference(x, &self.anchor);
            if fits(self.stretch + 2.0 * stiffness * moved) {
                return true;
            }
            if !fits(self.stretch) {
                // Not the anchor's distance: a new anchor would not help.
                return false;
            }
        }
        self.anchor.clear();
        self.anchor.extend_from_slice(x);
        self.stretch = weighted_stretch(setup, x);
        fits(self.stretch)
    }
}

/// The first quantity whose difference passes its tolerance at this step, if any: the
/// reference `theirs` against the student's `yours`; the energies are computed only when
/// `bound` cannot keep their difference below its tolerance.
pub(super) fn parting(
    theirs: &Snapshot,
    yours: &Track,
    bound: &mut EnergyBound,
    scales: &Scales,
    vmax: f64,
    setup: &Setup,
    step: u64,
) -> Option<Parting> {
    let tau = setup.tolerance;
    let parted = |quantity, amount: f64, tolerance: f64| {
        (amount > tolerance || amount.is_nan()).then_some(Parting {
            step,
            time: step as f64 * setup.dt,
            quantity,
            amount,
            tolerance,
        })
    };
    let (x, x_yours) = (theirs.x.as_slice(), yours.positions());
    let dx = largest_difference(x, &x_yours);
    if let Some(p) = parted(Quantity::Position, dx, tau * scales.length) {
        return Some(p);
    }
    let (v, v_yours) = (theirs.v.as_slice(), yours.velocities(setup));
    let dv = largest_difference(v, &v_yours);
    if let Some(p) = parted(Quantity::Velocity, dv, tau * vmax) {
        return Some(p);
    }
    let energy_scale = scales.mass * (scales.gravity * scales.length + vmax * vmax);
    let tolerance = tau * energy_scale;
    if bound.holds(setup, x, v, dx, dv, tolerance) {
        return None;
    }
    let e = energy(setup, &mut x.to_vec(), &mut v.to_vec());
    let e_yours = energy(setup, &mut x_yours.into_owned(), &mut v_yours.into_owned());
    parted(Quantity::Energy, (e - e_yours).abs(), tolerance)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::{EnergyBound, Scales, energy, largest_difference};
    use crate::grade::Assignment;
    use crate::grade::live::Setup;
    use crate::physics::Method;

    /// A displacement of length at most `size` for particle `i` (a fixed pattern, every
    /// direction and length up to `size`).
    fn nudge(i: usize, size: f64) -> DVec3 {
        let f = |k: usize| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5;
        DVec3::new(f(1), f(2), f(3)) * (size / 0.75_f64.sqrt())
    }

    #[test]
    fn the_energy_bound_never_hides_an_energy_difference_past_half_the_tolerance() {
        let mut scene = crate::scene::load("jelly-bowl", &[]).expect("scene");
        scene.set_method(Method::ExplicitEuler);
        let setup = Setup::from_scene(Assignment::Jelly, 5, &scene, 0.0).expect("setup");
        let scales = Scales::of(&setup);
        let length = scales.length;
        // The reference: squeezed and moving, so that springs are stretched and energy moves.
        let x: Vec<DVec3> = (setup.start.x.iter().enumerate())
            .map(|(i, p)| *p + nudge(i, 1e-3 * length))
            .collect();
        let v: Vec<DVec3> = (0..x.len())
            .map(|i| nudge(i + 5, scales.velocity))
            .collect();
        let vmax = scales.velocity * 2.0;
        let tolerance =
            setup.tolerance * scales.mass * (scales.gravity * scales.length + vmax * vmax);
        let exact = |xs: &[DVec3], vs: &[DVec3]| energy(&setup, &mut xs.to_vec(), &mut vs.to_vec());
        let e = exact(&x, &v);
        let mut bound = EnergyBound::of(&setup);
        let (mut held, mut not) = (0, 0);
        for k in 0..24 {
            // Differences from 1e-16 L to 1e-4 L (and the same fraction of V).
            let size = 10f64.powf(-16.0 + 0.5 * f64::from(k));
            let y: Vec<DVec3> = (x.iter().enumerate())
                .map(|(i, p)| *p + nudge(i + 11, size * length))
                .collect();
            let w: Vec<DVec3> = (v.iter().enumerate())
                .map(|(i, u)| *u + nudge(i + 17, size * scales.velocity))
                .collect();
            let (dx, dv) = (largest_difference(&x, &y), largest_difference(&v, &w));
            let de = (exact(&y, &w) - e).abs();
            if bound.holds(&setup, &x, &v, dx, dv, tolerance) {
                held += 1;
                assert!(
                    de <= tolerance / 2.0,
                    "d_x = {dx:e} m, d_v = {dv:e} m/s: d_E = {de:e} J past {:e} J",
                    tolerance / 2.0
                );
            } else {
                not += 1;
            }
        }
        // Both ways taken: small differences are told without the energies, large ones not.
        assert!(held > 0 && not > 0, "held {held}, not {not}");
    }
}
