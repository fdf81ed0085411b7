//! Running a scene: stepping every body, counting force evaluations, detecting divergence,
//! accounting for the energy that leaves, and the report `springlab run` prints.
//!
//! # Energy accounting
//!
//! ```text
//! E(t) + D(t) = E_0 + residual(t)
//! ```
//! where `E = E_kinetic + E_gravity + E_elastic` (J, [`crate::physics::energy`]) and `D` (J) is
//! the energy taken out: the power of dampers, drag and contact forces integrated with the
//! method's own stages ([`crate::physics::integrators`]), what each collision response removes
//! (measured as the drop of `E` across it), and Verlet's damping and projection. For an exact
//! integrator the residual is 0; otherwise it is the method's own energy error, visible on
//! damped scenes too. Accounting is on by default ([`Simulation::set_accounting`] turns it off
//! for speed); [`Simulation::rebase_energy`] restarts it after an edit from outside (a changed
//! stiffness, a dragged particle).
//!
//! # Implicit Euler's energy guard
//!
//! Backward Euler on springs, gravity and dampers removes energy; one Newton step with a
//! contact response after it can still add some when a step deforms the body far beyond the
//! linearisation (measured: `jelly-bowl` at dt = 0.1 s, the lattice squeezed by more than its
//! spacing in one step). A body stepped by implicit Euler therefore checks each step (the solve
//! and the collision response after it, spheres included):
//!
//! ```text
//! rise = E_1 - E_0                                  (J)
//! rate = rise / dt                                  (W)
//! accept        if  rise ≤ 10⁻¹² (|K_0| + |G_0| + |U_0|)
//! else halve    if  rate < rate_parent / 4  and  depth < MAX_HALVINGS
//! else accept
//! ```
//! where `E_0`, `E_1` (J) are the total energy ([`crate::physics::energy`]) before and after
//! the step, `K_0`, `G_0`, `U_0` (J) its kinetic, gravitational and elastic terms before
//! (the tolerance is rounding of their sum, not a physical allowance), `rate_parent` (W) the
//! rate of the step this one halves (infinite for a whole step) and `depth` the halvings so
//! far. Halving takes the step again as two half steps, each checked the same way, at most
//! [`MAX_HALVINGS`] deep (2⁵ = 32 substeps), and only while halving cuts the rise per second
//! at least fourfold. That is what tells the two kinds of rise apart:
//!
//! - **a linearisation error** (the one Newton step's neglected `½ f''(dt v)²` term) is `O(dt³)`
//!   per step, so its rate falls fourfold per halving or faster: on `jelly-bowl` at dt = 0.1 to
//!   0.3 s a halving cut the rate to 0.7 % – 16 % (or the halves did not rise at all), or left
//!   it at 58 % – 200 % (accepted, under the twofold rule too); none fell between a quarter and
//!   a half, so there the rule takes the decisions the twofold one took;
//! - **a resting contact** (the cloth lands on where a sphere would end the step, and the sphere
//!   gets the reaction a step later) pumps `O(dt²)` per step into the up-and-down of the contact,
//!   which the next steps take out again: halving only halves the rate (measured on
//!   `cloth-spheres` at rest, from t ≈ 6 s: 285, 134, 61, 22 W at dt = 5, 2.5, 1.25 and
//!   0.625 ms), and without the guard the energy falls from second to second (6 to 15 s).
//!   Halving it all the way cost 63 solves a step, slower than real time; now it costs 3 to 5.
//!
//! The report counts the whole steps halved (`solver.halved_steps`). A driven (kinematic)
//! sphere that moves does work on the cloth, so bodies with one are not guarded.
//!
//! The solve keeps contacts inside it (colliders and spheres,
//! [`crate::physics::integrators`]'s implicit Euler), so that a contact does not add the
//! elastic energy a projection after the step would: on `cloth-spheres` at dt = 0.005 s the
//! guard halves none of the 600 steps of 3 s (`examples/implicit_guard.rs`).

use std::sync::{Arc, Mutex, PoisonError};

use glam::DVec3;

use crate::physics::collide::{Bodies, Changes, DynamicSphere, PartBounds, Prepared};
use crate::physics::energy::{energy_change, energy_change_calm};
use crate::physics::integrators::{Response, guard_energy, guard_start_energy};
use crate::physics::{
    Dissipated, Divergence, Energy, Method, Model, SolveStats, State, Workspace, collide, diverge,
    energy,
};
use crate::scene::{Body, Scene};

mod report;
pub use report::{BodyReport, RunReport, SolverReport, SphereReport};

/// How many times implicit Euler's energy guard may halve one step (2⁵ = 32 substeps).
pub const MAX_HALVINGS: u32 = 5;

/// Steps per fused call of [`Simulation::advance`]: enough to amortise starting the thread
/// team and a chunk's fixed costs (the states saved, the response's set-up, the speed test at
/// the end; 64 left a few per cent of a 1000-particle jelly's run there), few enough that a
/// chunk taken again step by step costs little.
pub const CHUNK: u64 = 256;

/// A scene of fewer particles and springs than this takes longer fused chunks than [`CHUNK`]
/// (up to [`CHUNK_MAX`]), so that a chunk holds about as much work
/// ([`Simulation::chunk_steps`]).
const CHUNK_WORK: u64 = 1024;

/// Most steps of one fused chunk (a tiny scene's).
pub const CHUNK_MAX: u64 = 512;

/// A scene in motion.
#[derive(Clone, Debug)]
pub struct Simulation {
    /// The scene, whose bodies' states advance.
    pub scene: Scene,
    /// The time step (s).
    dt: f64,
    work: Vec<Workspace>,
    /// Steps taken.
    pub steps: u64,
    /// Force evaluations so far, over all bodies.
    pub force_evals: u64,
    /// Set when a step diverged; no further step is taken.
    pub diverged: Option<Divergence>,
    /// Simulated time when `dt` last changed (s), and the step count then.
    time_base: (f64, u64),
    /// Energy accounting on.
    accounting: bool,
    /// Energy at the start of the accounting (J).
    energy_initial: f64,
    /// Energy taken out since then (J).
    dissipated: Dissipated,
    /// Implicit Euler's linear solves.
    solver: SolverTally,
    /// Implicit Euler's energy guard on (module docs).
    guard: bool,
    /// Chunks [`Simulation::advance`] takes step by step before it tries a fused one again,
    /// and the fused chunks given up in a row.
    fused_wait: u32,
    fused_misses: u32,
    /// Steps taken in fused chunks.
    fused_steps: u64,
}

/// Running totals of implicit Euler's solves.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct SolverTally {
    solves: u64,
    iterations_sum: u64,
    iterations_max: u32,
    residual_sum: f64,
    residual_max: f64,
    passes_max: u32,
    constrained_max: u32,
    halved_steps: u64,
}

impl Simulation {
    /// A simulation of `scene` at its default `dt`.
    #[must_use]
    pub fn new(scene: Scene) -> Simulation {
        let dt = scene.dt;
        let work = scene
            .bodies
            .iter()
            .map(|_| {
                let mut work = Workspace::new();
                work.account = true;
                work.warm_start = true;
                work
            })
            .collect();
        let mut sim = Simulation {
            scene,
            dt,
            work,
            steps: 0,
            force_evals: 0,
            diverged: None,
            time_base: (0.0, 0),
            accounting: true,
            energy_initial: 0.0,
            dissipated: Dissipated::default(),
            solver: SolverTally::default(),
            guard: true,
            fused_wait: 0,
            fused_misses: 0,
            fused_steps: 0,
        };
        // The buffers of the first chunk, before its steps.
        let chunk = sim.chunk_steps() as usize;
        for (body, work) in sim.scene.bodies.iter().zip(&mut sim.work) {
            work.prepare(&body.model, chunk);
        }
        sim.rebase_energy();
        sim
    }

    /// Turns the energy accounting on or off (on by default); either way it restarts from the
    /// present energy. Off, a step costs no more than the method's own work.
    pub fn set_accounting(&mut self, on: bool) {
        self.accounting = on;
        for w in &mut self.work {
            w.account = on;
        }
        self.rebase_energy();
    }

    /// Turns implicit Euler's energy guard (module docs) on or off (on by default). Off, a
    /// step is one solve however the energy moves: cheaper, for a caller that judges
    /// boundedness rather than every step (tests and `examples/implicit_guard.rs` compare the
    /// two; the stability study's confirmation runs keep it on, as a user's run has it).
    pub fn set_energy_guard(&mut self, on: bool) {
        self.guard = on;
    }

    /// True when the energy accounting is on.
    #[must_use]
    pub fn accounting(&self) -> bool {
        self.accounting
    }

    /// Restarts the energy accounting from the present state: `E_0` = the energy now, nothing
    /// dissipated. Call it after changing the scene from outside the physics.
    pub fn rebase_energy(&mut self) {
        self.energy_initial = self.energy().total;
        self.dissipated = Dissipated::default();
    }

    /// The energy at the start of the accounting (J).
    #[must_use]
    pub fn energy_initial(&self) -> f64 {
        self.energy_initial
    }

    /// The energy taken out since the start of the accounting (J), by where it went.
    #[must_use]
    pub fn dissipated(&self) -> Dissipated {
        self.dissipated
    }

    /// The method's energy error (J): `E + D - E_0`, zero for an exact integrator (module docs);
    /// NaN when accounting is off.
    #[must_use]
    pub fn energy_residual(&self) -> f64 {
        if !self.accounting {
            return f64::NAN;
        }
        self.energy().total + self.dissipated.total - self.energy_initial
    }

    /// The time step (s).
    #[must_use]
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Changes the time step (s). Verlet's history belongs to the old step and is dropped.
    ///
    /// # Panics
    /// If `dt` is not positive and finite (callers validate user input first).
    pub fn set_dt(&mut self, dt: f64) {
        assert!(dt > 0.0 && dt.is_finite(), "dt must be positive");
        self.time_base = (self.time(), self.steps);
        self.dt = dt;
        for b in &mut self.scene.bodies {
            b.state.history_valid = false;
        }
    }

    /// Simulated time (s): `steps · dt`, counted from the last change of `dt` (no drift from
    /// summing `dt`).
    #[must_use]
    pub fn time(&self) -> f64 {
        let (t0, s0) = self.time_base;
        t0 + (self.steps - s0) as f64 * self.dt
    }

    /// Takes one step of every body; returns the divergence if this step produced one.
    /// Does nothing once diverged.
    pub fn step(&mut self) -> Option<&Divergence> {
        if self.diverged.is_some() {
            return None;
        }
        let mut failed_solve = None;
        for (body, work) in self.scene.bodies.iter_mut().zip(&mut self.work) {
            let outcome = if body.method.declaration().energy_guard {
                let depth = if self.guard { 0 } else { MAX_HALVINGS };
                implicit_step(body, work, self.dt, depth, f64::INFINITY, &mut self.solver)
            } else {
                let evals = plain_step(body, work, self.dt);
                StepOutcome {
                    evals,
                    dissipated: work.dissipated,
                    solve: None,
                }
            };
            self.force_evals += outcome.evals;
            if self.accounting {
                self.dissipated = self.dissipated.plus(outcome.dissipated);
            }
            if let Some(stats) = outcome.solve
                && failed_solve.is_none()
            {
                failed_solve = stats.failure(body.params.cg_tolerance);
            }
        }
        self.steps += 1;
        let time = self.time();
        if let Some(reason) = failed_solve {
            let max_speed = self
                .scene
                .bodies
                .iter()
                .map(|b| diverge::max_speed(&b.state))
                .fold(0.0, f64::max);
            self.diverged = Some(Divergence {
                step: self.steps,
                time,
                max_speed,
                reason,
            });
            return self.diverged.as_ref();
        }
        for body in &self.scene.bodies {
            if let Some(d) = diverge::check(&body.state, self.steps, time) {
                self.diverged = Some(d);
                return self.diverged.as_ref();
            }
        }
        None
    }

    /// Takes up to `n` steps, stopping at divergence: the same states, counts, divergence and
    /// energy accounting as `n` calls of [`Simulation::step`], bit for bit.
    ///
    /// Where nothing happens between two steps but the method itself and the colliders'
    /// response (no sphere, no energy guard), the steps go to [`Method::steps`] in chunks of
    /// [`Simulation::chunk_steps`]: the fused multi-step passes `springlab bench` times (the rope's pass in
    /// structure-of-arrays form, the lattices' thread team). Colliders act inside the passes
    /// (their contact force), and their response after each step ([`collide::resolve`], as
    /// [`Simulation::step`] applies it) runs between two steps inside the chunk
    /// ([`Workspace::response`]: on one thread of the team while the others wait, so the team
    /// stays up), recording the energy it removes step by step. With energy accounting the
    /// passes also write the dissipated power of every stage, and each step's share, less the
    /// energy its response removed, is added in step order, as [`Simulation::step`] adds it.
    /// A chunk is kept when every body's fastest particle ends it
    /// below a tenth of the divergence speed (at 100 m/s against 1000 m/s, so no step inside it
    /// can have diverged: unstable growth does not turn back); otherwise the states go back to
    /// the chunk's start and its steps are taken one by one, each checked.
    pub fn advance(&mut self, n: u64) {
        let mut left = n;
        while left > 0 && self.diverged.is_none() {
            let chunk = left.min(self.chunk_steps());
            if self.fused_wait > 0 {
                self.fused_wait -= 1;
            } else if chunk >= 2 && self.fusable() {
                if self.fused_chunk(chunk) {
                    self.fused_misses = 0;
                    left -= chunk;
                    continue;
                }
                // Taken again step by step: wait 2, 4, … 64 chunks before the next try, so
                // that a body that keeps touching costs at most a few per cent more.
                self.fused_misses = (self.fused_misses + 1).min(6);
                self.fused_wait = 1 << self.fused_misses;
            }
            for _ in 0..chunk {
                if self.step().is_some() {
                    return;
                }
            }
            left -= chunk;
        }
    }

    /// Steps per fused chunk of [`Simulation::advance`]: [`CHUNK`], or for a scene of fewer
    /// than [`CHUNK_WORK`] particles and springs as many more as keep the chunk's work about
    /// the same, at most [`CHUNK_MAX`] (a 64-node rope: 512). A chunk has fixed costs (the
    /// states saved, the passes' start, the layout copied in and out, the speed test at its
    /// end), a large share of a tiny scene's short chunk; one taken again step by step costs
    /// no more than the steps it holds. The length changes no result: a fused chunk is the
    /// same as its single steps.
    #[must_use]
    pub fn chunk_steps(&self) -> u64 {
        let size: u64 = (self.scene.bodies.iter())
            .map(|b| (b.model.particle_count() + b.model.springs().len()) as u64)
            .sum();
        (CHUNK * CHUNK_WORK / size.max(1)).clamp(CHUNK, CHUNK_MAX)
    }

    /// True when a step may be the method's step and the collision response (see
    /// [`Simulation::advance`]): no energy guard, no projection of the caller's, and a body
    /// with colliders or spheres stepped by a method with a many-step path (the response
    /// between two of its steps sees positions and velocities only; a method without that path
    /// gains nothing from a chunk, and Verlet's and XPBD's history `x_prev` must follow the
    /// response, as [`plain_step`] keeps it).
    fn fusable(&self) -> bool {
        (self.scene.bodies.iter().zip(&self.work)).all(|(b, work)| {
            let declaration = b.method.declaration();
            let contacts = !b.model.colliders.is_empty() || !b.state.spheres.is_empty();
            !declaration.energy_guard
                && work.projection.is_none()
                && (!contacts || declaration.many.is_some())
        })
    }

    /// `chunk` steps of every body in one [`Method::steps`] call each; false, with every state
    /// back where it was, when a body ends the chunk too fast to tell that no step diverged.
    fn fused_chunk(&mut self, chunk: u64) -> bool {
        let saved: Vec<State> = self.scene.bodies.iter().map(|b| b.state.clone()).collect();
        let mut evals = 0;
        // Each body's response log (bodies with colliders or spheres, as `plain_step`).
        let mut logs: Vec<Option<Arc<Mutex<ResponseLog>>>> = Vec::new();
        for (body, work) in self.scene.bodies.iter_mut().zip(&mut self.work) {
            let contacts = !body.model.colliders.is_empty() || !body.state.spheres.is_empty();
            let log = contacts.then(|| {
                let log = Arc::new(Mutex::new(ResponseLog {
                    spheres: body.state.spheres.clone(),
                    ..ResponseLog::default()
                }));
                work.response = Some(response(self.dt, work.account, Arc::clone(&log)));
                log
            });
            evals += body.method.steps(
                &body.model,
                &mut body.state,
                self.dt,
                &body.params,
                work,
                chunk,
            );
            work.response = None;
            logs.push(log);
        }
        let calm = self.scene.bodies.iter().all(|b| {
            let speed = diverge::max_speed(&b.state);
            speed * speed < 0.01 * diverge::MAX_SPEED_SQUARED
        });
        if !calm {
            for (body, state) in self.scene.bodies.iter_mut().zip(saved) {
                body.state = state;
            }
            return false;
        }
        let logs: Vec<Option<ResponseLog>> = (logs.into_iter())
            .map(|log| log.map(|log| take_log(&log)))
            .collect();
        // The spheres moved with the responses.
        for (body, log) in self.scene.bodies.iter_mut().zip(&logs) {
            if let Some(log) = log {
                body.state.spheres.clone_from(&log.spheres);
            }
        }
        self.force_evals += evals;
        self.steps += chunk;
        self.fused_steps += chunk;
        if self.accounting {
            // Step by step, body by body: the order of the sums of `Simulation::step`, each
            // step's share less what its response removed, as `plain_step` takes it; summed in
            // a local (the field would be stored and read back at every step).
            let mut total = self.dissipated;
            if let ([work], [None]) = (&self.work[..], &logs[..]) {
                // One body without responses: its steps' shares in step order.
                for d in &work.step_dissipated[..chunk as usize] {
                    total = total.plus(*d);
                }
            } else {
                for s in 0..chunk as usize {
                    for (work, log) in self.work.iter().zip(&logs) {
                        let mut d = work.step_dissipated[s];
                        if let Some(log) = log {
                            d.contacts -= log.contacts[s];
                            d = d.summed();
                        }
                        total = total.plus(d);
                    }
                }
            }
            self.dissipated = total;
        }
        true
    }

    /// The steps [`Simulation::advance`] took in fused chunks (the rest were single steps).
    #[must_use]
    pub fn fused_steps(&self) -> u64 {
        self.fused_steps
    }

    /// Takes up to `n` steps, stopping at divergence; calls `after_step` after each one.
    pub fn run(&mut self, n: u64, mut after_step: impl FnMut(&Simulation)) {
        for _ in 0..n {
            if self.diverged.is_some() {
                break;
            }
            self.step();
            after_step(self);
        }
    }

    /// Total energy over all bodies.
    #[must_use]
    pub fn energy(&self) -> Energy {
        self.scene
            .bodies
            .iter()
            .map(|b| energy(&b.model, &b.state))
            .fold(Energy::default(), Energy::plus)
    }

    /// Every body's positions, concatenated.
    pub fn positions(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.scene
            .bodies
            .iter()
            .flat_map(|b| b.state.x.iter().copied())
    }

    /// Every body's velocities, concatenated.
    pub fn velocities(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.scene
            .bodies
            .iter()
            .flat_map(|b| b.state.v.iter().copied())
    }

    /// Sets every body's method.
    pub fn set_method(&mut self, method: Method) {
        self.scene.set_method(method);
    }

    /// The body states (for example to compare with an exact solution).
    pub fn states(&self) -> impl Iterator<Item = &State> {
        self.scene.bodies.iter().map(|b| &b.state)
    }
}

/// What the collision responses of a fused chunk recorded, and their scratch.
#[derive(Default)]
struct ResponseLog {
    /// With accounting: the change of energy each step's response made (J), in step order.
    contacts: Vec<f64>,
    changes: Changes,
    /// Verlet's history, unused (the fused methods keep none), for the [`Bodies`] view.
    x_prev: Vec<DVec3>,
    /// The body's dynamic spheres, moved by the responses (the methods' steps do not read
    /// them), back into the state after the chunk.
    spheres: Vec<DynamicSphere>,
    /// The whole body's summary for the response's broad phase, when the parts made none.
    whole: PartBounds,
}

/// The contact part of `plain_step` (the spheres move, then every response happens) as a rule
/// between the steps of [`Method::steps`], the same calls on the same numbers, on the spheres
/// of `log`: with `account` it records each step's change of energy in `log`. Where a team of
/// threads takes the steps, each thread sums up its part for the response's broad phase
/// ([`collide::Prepared`]: boxes, calm positions, particles near a collider) right after
/// writing it, and the response reads those summaries instead of every particle.
fn response(dt: f64, account: bool, log: Arc<Mutex<ResponseLog>>) -> Response {
    let prepared = Arc::new(Prepared::default());
    let parts = Arc::clone(&prepared);
    // The spheres' broad phase needs boxes; a body without spheres only the colliders' test.
    let with_boxes = !log
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .spheres
        .is_empty();
    // The spheres as the last response left them, for the parts' pushes (kinematic spheres).
    let spheres_now = Arc::clone(&log);
    let prepare = move |model: &Model, k: usize, q0: usize, x: &mut [DVec3], v: &mut [DVec3]| {
        SPHERES.with(|copy| {
            let copy = &mut *copy.borrow_mut();
            copy.clear();
            if with_boxes {
                let log = spheres_now.lock().unwrap_or_else(PoisonError::into_inner);
                copy.extend_from_slice(&log.spheres);
            }
            let spheres = with_boxes.then_some((&copy[..], dt));
            parts.prepare(model, k, q0, x, v, spheres);
        });
    };
    let respond = move |model: &Model, x: &mut [DVec3], v: &mut [DVec3]| {
        let mut log = log.lock().unwrap_or_else(PoisonError::into_inner);
        let ResponseLog {
            contacts,
            changes,
            x_prev,
            spheres,
            whole,
        } = &mut *log;
        x_prev.resize(x.len(), DVec3::ZERO);
        // The parts' summaries of this step, else one of the whole body made here.
        let n = x.len().min(model.particle_count());
        let mut taken = prepared.take(n);
        let (parts, calm) = match taken.as_mut() {
            Some(taken) => {
                let calm = taken.calm();
                (taken.parts(), calm)
            }
            None => {
                prepared.undo_pushes(x, v);
                whole.sum_up(model, 0, &x[..n], Some(&v[..n]), with_boxes);
                let calm = whole.calm();
                (std::slice::from_mut(whole), calm)
            }
        };
        let mut bodies = Bodies {
            x: &mut *x,
            v: &mut *v,
            x_prev,
            history_valid: false,
            spheres,
        };
        collide::advance_spheres(model, bodies.reborrow(), dt);
        // The colliders' candidates of the summaries hold while no sphere has moved a particle.
        let no_spheres = bodies.spheres.is_empty();
        if !account {
            collide::collide_spheres_prepared(
                model,
                bodies.reborrow(),
                dt,
                None,
                Some(&mut *parts),
            );
            collide::resolve_prepared(model, bodies, dt, None, no_spheres.then_some(parts));
            return;
        }
        changes.clear();
        collide::collide_spheres_prepared(
            model,
            bodies.reborrow(),
            dt,
            Some(changes),
            Some(&mut *parts),
        );
        collide::resolve_prepared(
            model,
            bodies,
            dt,
            Some(changes),
            no_spheres.then_some(parts),
        );
        changes.finish(model.particle_count());
        contacts.push(energy_change_calm(model, x, v, spheres, changes, calm));
    };
    Response(Arc::new(respond), Some(Arc::new(prepare)))
}

thread_local! {
    /// A thread's copy of a body's spheres for its parts' pushes (reused).
    static SPHERES: std::cell::RefCell<Vec<DynamicSphere>> = const {
        std::cell::RefCell::new(Vec::new())
    };
}

/// The log of a finished chunk, taken out of its lock.
fn take_log(log: &Mutex<ResponseLog>) -> ResponseLog {
    std::mem::take(&mut *log.lock().unwrap_or_else(PoisonError::into_inner))
}

/// What one body's step did.
struct StepOutcome {
    evals: u64,
    dissipated: Dissipated,
    /// Implicit Euler: the worst solve of the step.
    solve: Option<SolveStats>,
}

/// A step of a body's method and the collision response after it; the energy the response
/// removes goes into `work.dissipated.contacts` when accounting.
fn plain_step(body: &mut Body, work: &mut Workspace, dt: f64) -> u64 {
    let evals = body
        .method
        .step(&body.model, &mut body.state, dt, &body.params, work);
    let has_contacts = !body.model.colliders.is_empty() || !body.state.spheres.is_empty();
    if !has_contacts {
        return evals;
    }
    // Colliders and dynamic spheres: the spheres move, then every response happens.
    collide::advance_spheres(&body.model, &mut body.state, dt);
    if !work.account {
        collide::collide_spheres(&body.model, &mut body.state, dt);
        collide::resolve(&body.model, &mut body.state, dt);
        return evals;
    }
    // The energy the responses remove: the change of E over the particles they touched.
    let changes = &mut work.changes;
    changes.clear();
    collide::collide_spheres_logged(&body.model, &mut body.state, dt, Some(changes));
    collide::resolve_logged(&body.model, &mut body.state, dt, Some(changes));
    changes.finish(body.model.particle_count());
    work.dissipated.contacts -= energy_change(&body.model, &body.state, changes);
    work.dissipated = work.dissipated.summed();
    evals
}

/// An implicit Euler step with the energy guard of the module docs, `depth` halvings deep.
fn implicit_step(
    body: &mut Body,
    work: &mut Workspace,
    dt: f64,
    depth: u32,
    parent_rate: f64,
    tally: &mut SolverTally,
) -> StepOutcome {
    let driven = body
        .state
        .spheres
        .iter()
        .any(|s| s.kinematic && s.velocity != DVec3::ZERO);
    let guard = !driven && depth < MAX_HALVINGS;
    let saved = guard.then(|| body.state.clone());
    work.start_elastic = None;
    let evals = plain_step(body, work, dt);
    // The energy before the step, of the saved state (its elastic term from the step's own
    // assembly where it summed one).
    let e0 = saved
        .as_ref()
        .map(|s| guard_start_energy(&body.model, s, work));
    let stats = work.last_solve;
    tally.solves += 1;
    tally.iterations_sum += u64::from(stats.iterations);
    tally.iterations_max = tally.iterations_max.max(stats.iterations);
    if stats.relative_residual.is_finite() {
        tally.residual_sum += stats.relative_residual;
        tally.residual_max = tally.residual_max.max(stats.relative_residual);
    }
    tally.passes_max = tally.passes_max.max(stats.passes);
    tally.constrained_max = tally.constrained_max.max(stats.constrained);
    if !stats.converged {
        return StepOutcome {
            evals,
            dissipated: work.dissipated,
            solve: Some(stats),
        };
    }
    if let (Some(saved), Some(e0)) = (saved, e0) {
        let e1 = guard_energy(&body.model, &body.state, work).total;
        let scale = e0.kinetic.abs() + e0.gravity.abs() + e0.elastic.abs();
        // The rise per second of this attempt; halving is worth it only while it cuts the rate
        // fourfold (a linearisation error is O(dt³) per step; a resting contact's lag, O(dt²)
        // per step, only halves it, and an oscillation of a resting contact not at all).
        let rate = (e1 - e0.total) / dt;
        if e1 > e0.total + 1e-12 * scale && rate < parent_rate / 4.0 {
            if depth == 0 {
                tally.halved_steps += 1;
            }
            body.state = saved;
            let a = implicit_step(body, work, 0.5 * dt, depth + 1, rate, tally);
            let b = implicit_step(body, work, 0.5 * dt, depth + 1, rate, tally);
            return StepOutcome {
                evals: evals + a.evals + b.evals,
                dissipated: a.dissipated.plus(b.dissipated),
                solve: worse(a.solve, b.solve),
            };
        }
    }
    StepOutcome {
        evals,
        dissipated: work.dissipated,
        solve: Some(stats),
    }
}

/// The failed one of two solves, else the second.
fn worse(a: Option<SolveStats>, b: Option<SolveStats>) -> Option<SolveStats> {
    match (a, b) {
        (Some(a), _) if !a.converged => Some(a),
        (_, b) => b,
    }
}
