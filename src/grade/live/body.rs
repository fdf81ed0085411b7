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
            let before = speculative.then(|| (state.x.clone(), state.v.clone()));
            let mut s =
                physics::State::new(std::mem::take(&mut state.x), std::mem::take(&mut state.v));
            collide::resolve(&setup.model, &mut s, setup.dt);
            state.x = s.x;
            state.v = s.v;
            if before.is_some_and(|(x, v)| state.x != x || state.v != v) {
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

    fn raw_velocities(&self) -> Cow<'_, [DVec3]> {
        match &self.shape {
            Shape::Rope(r) => Cow::Owned(r.masses.iter().map(|m| m.velocity).collect()),
            Shape::Lattice(s) => Cow::Borrowed(&s.v),
        }
    }

    /// Velocities (m/s); a Verlet rope's are `(x_n - x_{n-1})/dt`.
    pub(super) fn velocities(&self, setup: &Setup) -> Vec<DVec3> {
        match &self.shape {
            Shape::Rope(r) if setup.integrator == Integrator::Verlet => r
                .masses
                .iter()
                .map(|m| (m.position - m.last_position) / setup.dt)
                .collect(),
            _ => self.raw_velocities().into_owned(),
        }
    }

    /// Largest speed (m/s); 0 when any is not finite.
    pub(super) fn speed(&self) -> f64 {
        self.raw_velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max)
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

fn largest_difference(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
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

/// A body's positions (m), velocities (m/s) and energy (J) after a step, measured once.
pub(super) struct Measure {
    x: Vec<DVec3>,
    v: Vec<DVec3>,
    /// Total energy (J).
    pub(super) energy: f64,
}

impl Measure {
    pub(super) fn of(track: &Track, setup: &Setup) -> Measure {
        let mut x = track.positions().into_owned();
        let mut v = track.velocities(setup);
        let energy = energy(setup, &mut x, &mut v);
        Measure { x, v, energy }
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

/// The first quantity whose difference passes its tolerance at this step, if any.
pub(super) fn parting(
    theirs: &Measure,
    yours: &Measure,
    scales: &Scales,
    vmax: f64,
    setup: &Setup,
    step: u64,
) -> Option<Parting> {
    let tau = setup.tolerance;
    let dx = theirs.distance(yours);
    let dv = largest_difference(&theirs.v, &yours.v);
    let de = (theirs.energy - yours.energy).abs();
    let energy_scale = scales.mass * (scales.gravity * scales.length + vmax * vmax);
    [
        (Quantity::Position, dx, tau * scales.length),
        (Quantity::Velocity, dv, tau * vmax),
        (Quantity::Energy, de, tau * energy_scale),
    ]
    .into_iter()
    .find(|&(_, d, t)| d > t || d.is_nan())
    .map(|(quantity, amount, tolerance)| Parting {
        step,
        time: step as f64 * setup.dt,
        quantity,
        amount,
        tolerance,
    })
}
