//! Your code in the lesson: a student's integrator steps a copy of a lesson step's body beside
//! springlab's reference, measured step by step (`springlab lesson N --homework DIR`).
//!
//! ```text
//! build   the crate through the grader (`grade::build`: sandbox, limits, cache by content)
//! start   a `Remote` session: the student's program as a process of its own (`grade::remote`)
//! worker  two threads, never the drawing thread:
//!         for n = 1, 2, …   reference ← Reference.method(reference, dt, physics)   (its thread)
//!                           yours     ← Remote.method(yours, dt, physics)     (until it fails)
//!                           both      ← collision response of the scene (lattices)
//!                           compare:  d_x = max_i |x_i - x̂_i|,  d_v = max_i |v_i - v̂_i|,
//!                                     d_E = |E - Ê|
//!         the reference's steps come through a bounded queue from a thread of their own;
//!         frames go back through a bounded queue (the worker waits when it is full)
//! part    the first step n where d_x > τ L, or d_v > τ V, or d_E > τ M (|g| L + V²)
//! ```
//! where `x̂`, `v̂`, `Ê` are the reference's positions (m), velocities (m/s) and energy (J), `L`
//! the diagonal of the body's starting bounding box (m, at least 1 mm), `V` the largest of
//! `√(|g| L)`, 1 mm/s and every reference speed so far (m/s), `M` the body's mass (kg), `g` the
//! gravity (m/s²) and `τ` the relative tolerance ([`DEFAULT_TOLERANCE`]). Ties go to position,
//! then velocity, then energy. A Verlet rope's velocity is `(x_n - x_{n-1})/dt` on both sides.
//! `d_E` is computed (both energies: a pass over every spring each) only when a bound of it from
//! `d_x` and `d_v` does not keep it below half its tolerance (`body::EnergyBound`), and for the
//! frames.
//!
//! Both sides call the homework trait method of the same name with the same `dt` and the same
//! [`Physics`] (the body's model: springs, dampers, gravity, drag), so a correct crate stays
//! within rounding of the reference. What the student's code does wrong is a value, never a
//! crash: a panic, a NaN, a time-out or an exit ends the student's side with a message naming
//! the method and the step, and the reference keeps going.
//!
//! Files: this one holds the set-up and the worker; `live/body.rs` steps one body and measures
//! it; `live/handover.rs` hands the lesson's own steps of the body to the reference, which then
//! does not compute them again; `live/build.rs` builds a crate into a [`Remote`], and asks the
//! grader for the method's hint; `live/watch.rs` rebuilds on every save.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use glam::DVec3;

use super::remote::{CallFailure, Remote, jacobian_too_large, largest_jacobian_body};
use super::{Assignment, ClothHomework, JellyHomework, Reference, RopeHomework};
use crate::physics::{self, Method, Model};
use crate::scene::Scene;

mod body;
mod build;
mod handover;
mod reference;
mod watch;

use body::{Measure, Snapshot, Track};
pub use build::{
    BuildOptions, Built, LazyBuilder, build_homework, builder, first_error, grader_hint,
};
pub use handover::Handover;
use reference::{Steps, reference_steps};
pub use watch::{Reload, Watcher};

/// Relative tolerance `τ` of the parting test (module docs).
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// A homework crate's implementation of one assignment (a [`super::Remote`] in the app).
#[derive(Clone)]
pub enum Homework {
    /// The rope.
    Rope(Arc<dyn RopeHomework>),
    /// The jelly.
    Jelly(Arc<dyn JellyHomework>),
    /// The cloth.
    Cloth(Arc<dyn ClothHomework>),
    /// A student's program (any assignment): one trait call per step, or many steps per
    /// request (`wire`'s STEPS) when the worker may run ahead.
    Program(Remote),
}

impl std::fmt::Debug for Homework {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Homework({})", self.assignment().name())
    }
}

impl Homework {
    /// springlab's own answers to `assignment`.
    #[must_use]
    pub fn reference(assignment: Assignment) -> Homework {
        match assignment {
            Assignment::Rope => Homework::Rope(Arc::new(Reference)),
            Assignment::Jelly => Homework::Jelly(Arc::new(Reference)),
            Assignment::Cloth => Homework::Cloth(Arc::new(Reference)),
        }
    }

    /// Which assignment it implements.
    #[must_use]
    pub fn assignment(&self) -> Assignment {
        match self {
            Homework::Rope(_) => Assignment::Rope,
            Homework::Jelly(_) => Assignment::Jelly,
            Homework::Cloth(_) => Assignment::Cloth,
            Homework::Program(remote) => remote.assignment(),
        }
    }
}

/// A homework trait's integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// `explicit_euler` (every assignment).
    ExplicitEuler,
    /// `semi_implicit_euler` (rope).
    SemiImplicitEuler,
    /// `verlet` (rope).
    Verlet,
    /// `implicit_euler` (jelly, cloth).
    ImplicitEuler,
    /// `midpoint` (jelly, cloth).
    Midpoint,
    /// `rk4` (jelly, cloth).
    Rk4,
}

impl Integrator {
    /// The trait method's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Integrator::ExplicitEuler => "explicit_euler",
            Integrator::SemiImplicitEuler => "semi_implicit_euler",
            Integrator::Verlet => "verlet",
            Integrator::ImplicitEuler => "implicit_euler",
            Integrator::Midpoint => "midpoint",
            Integrator::Rk4 => "rk4",
        }
    }

    /// The integrators of `assignment`'s trait.
    #[must_use]
    pub fn of_assignment(assignment: Assignment) -> &'static [Integrator] {
        match assignment {
            Assignment::Rope => &[
                Integrator::ExplicitEuler,
                Integrator::SemiImplicitEuler,
                Integrator::Verlet,
            ],
            Assignment::Jelly | Assignment::Cloth => &[
                Integrator::ExplicitEuler,
                Integrator::ImplicitEuler,
                Integrator::Midpoint,
                Integrator::Rk4,
            ],
        }
    }

    /// The trait method of `assignment` that springlab's `method` is, if it has one.
    #[must_use]
    pub fn of(assignment: Assignment, method: Method) -> Option<Integrator> {
        let m = match method {
            Method::ExplicitEuler => Integrator::ExplicitEuler,
            Method::SemiImplicitEuler => Integrator::SemiImplicitEuler,
            Method::Verlet => Integrator::Verlet,
            Method::ImplicitEuler => Integrator::ImplicitEuler,
            Method::Midpoint => Integrator::Midpoint,
            Method::Rk4 => Integrator::Rk4,
            _ => return None,
        };
        Self::of_assignment(assignment).contains(&m).then_some(m)
    }

    /// The ids of the grader's items that check this integrator.
    #[must_use]
    pub fn items(self) -> &'static [&'static str] {
        match self {
            Integrator::ExplicitEuler => &["explicit"],
            Integrator::SemiImplicitEuler => &["semi_implicit"],
            Integrator::Verlet => &["verlet", "damping"],
            Integrator::ImplicitEuler => &["implicit"],
            Integrator::Midpoint => &["midpoint"],
            Integrator::Rk4 => &["rk4"],
        }
    }
}

/// The lessons whose steps an assignment's integrators can run: rope 1, 3, 4; jelly 5; cloth 6.
#[must_use]
pub fn lessons_of(assignment: Assignment) -> &'static [u32] {
    match assignment {
        Assignment::Rope => &[1, 3, 4],
        Assignment::Jelly => &[5],
        Assignment::Cloth => &[6],
    }
}

/// The lesson that shows integrator item `item` (a grader item id) live, as a command run in
/// the crate's folder: the rope's Euler methods in lesson 3 (explicit Euler on the rope is its
/// step 3, semi-implicit Euler on the oscillator its step 2), Verlet and its damping in lesson 4
/// (step 1 on), the jelly's in lesson 5 and the cloth's in lesson 6, whose steps run methods the
/// traits lack: `m` picks the method there.
#[must_use]
pub fn see_it(assignment: Assignment, item: &str) -> Option<String> {
    let (lesson, method) = match (assignment, item) {
        (Assignment::Rope, "explicit") => (3, None),
        (Assignment::Rope, "semi_implicit") => (3, None),
        (Assignment::Rope, "verlet" | "damping") => (4, None),
        (Assignment::Jelly, m @ ("explicit" | "implicit" | "midpoint" | "rk4")) => (5, Some(m)),
        (Assignment::Cloth, m @ ("explicit" | "implicit" | "midpoint" | "rk4")) => (6, Some(m)),
        _ => return None,
    };
    let pick = method.map_or(String::new(), |m| {
        let name = match m {
            "explicit" => "explicit Euler",
            "implicit" => "implicit Euler",
            "midpoint" => "midpoint",
            _ => "RK4",
        };
        format!(" (m: choose {name})")
    });
    Some(format!("springlab lesson {lesson} --homework .{pick}"))
}

/// What one comparison runs: a body of a lesson step's scene, its method and time step.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The assignment whose trait steps it.
    pub assignment: Assignment,
    /// The trait method both sides call.
    pub integrator: Integrator,
    /// Index of the body in the scene.
    pub body: usize,
    /// The body's label in the scene.
    pub label: String,
    /// Masses, springs, gravity, drag and colliders of the body.
    pub model: Model,
    /// The body's state at the step's start.
    pub start: physics::State,
    /// Verlet's damping factor γ per step (the scene's `verlet_damping`).
    pub damping: f64,
    /// Time step (s).
    pub dt: f64,
    /// Steps to compare (0: until stopped).
    pub horizon: u64,
    /// Relative tolerance `τ` (module docs).
    pub tolerance: f64,
}

impl Setup {
    /// The comparison of lesson `lesson`'s step whose scene (its method and dt applied) is
    /// `scene`, over `seconds` of simulated time (0: until stopped): the last body whose method
    /// is one of the assignment's integrators.
    ///
    /// # Errors
    /// A sentence for the status line: the lesson is not one of the assignment's, or no body of
    /// this step runs one of its integrators.
    pub fn from_scene(
        assignment: Assignment,
        lesson: u32,
        scene: &Scene,
        seconds: f64,
    ) -> Result<Setup, String> {
        let lessons = lessons_of(assignment);
        if !lessons.contains(&lesson) {
            return Err(format!(
                "lesson {lesson} has no step for the {} homework (its integrators run in lesson{} {})",
                assignment.name(),
                if lessons.len() > 1 { "s" } else { "" },
                lessons
                    .iter()
                    .map(u32::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        let found = scene
            .bodies
            .iter()
            .enumerate()
            .rev()
            .find_map(|(i, b)| Integrator::of(assignment, b.method).map(|m| (i, b, m)));
        let Some((index, body, integrator)) = found else {
            let methods: Vec<&str> = scene
                .bodies
                .iter()
                .map(|b| b.method.declaration().name)
                .collect();
            let names: Vec<&str> = Integrator::of_assignment(assignment)
                .iter()
                .map(|m| m.name())
                .collect();
            return Err(format!(
                "this step runs {}; the {} homework has {}: nothing of yours to run here",
                methods.join(" and "),
                assignment.name(),
                names.join(", ")
            ));
        };
        let horizon = if seconds > 0.0 && scene.dt > 0.0 {
            (seconds / scene.dt).ceil() as u64
        } else {
            0
        };
        Ok(Setup {
            assignment,
            integrator,
            body: index,
            label: body.label.clone(),
            model: body.model.clone(),
            start: body.state.clone(),
            damping: body.params.verlet_damping,
            dt: scene.dt,
            horizon,
            tolerance: DEFAULT_TOLERANCE,
        })
    }
}

/// Which quantity parted first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The largest particle distance.
    Position,
    /// The largest velocity difference.
    Velocity,
    /// The total energy.
    Energy,
}

impl Quantity {
    /// Its name in messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Energy => "energy",
        }
    }
}

/// Where the two bodies first parted by more than the tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parting {
    /// The step (1 = after the first step).
    pub step: u64,
    /// Its simulated time (s).
    pub time: f64,
    /// What parted first.
    pub quantity: Quantity,
    /// The difference (m, m/s or J).
    pub amount: f64,
    /// The tolerance it passed (same unit).
    pub tolerance: f64,
}

impl Parting {
    /// One line for the status area.
    #[must_use]
    pub fn describe(&self) -> String {
        let unit = match self.quantity {
            Quantity::Position => "m",
            Quantity::Velocity => "m/s",
            Quantity::Energy => "J",
        };
        format!(
            "parted at step {} (t = {:.3} s): {} differs by {:.3e} {unit} (tolerance {:.1e})",
            self.step,
            self.time,
            self.quantity.name(),
            self.amount,
            self.tolerance
        )
    }
}

/// One frame of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Steps taken.
    pub step: u64,
    /// Simulated time (s).
    pub time: f64,
    /// The reference body's positions (m).
    pub reference: Vec<DVec3>,
    /// The student's body's positions (m), until the student's code failed.
    pub yours: Option<Vec<DVec3>>,
    /// Largest particle distance between the two (m).
    pub distance: f64,
    /// The reference's total energy (J).
    pub energy_reference: f64,
    /// The student's body's total energy (J).
    pub energy_yours: Option<f64>,
    /// The first parting so far.
    pub parting: Option<Parting>,
    /// Why the student's side stopped.
    pub failure: Option<String>,
    /// The horizon was reached.
    pub finished: bool,
}

/// Settings of the worker.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveOptions {
    /// A frame every this many steps (and at a parting, a failure and the end).
    pub frame_every: u64,
    /// Frames the queue holds before the worker waits.
    pub queue: usize,
    /// Most steps a student's program computes in one request (`wire`'s STEPS), never past the
    /// app's clock; 1: one call per step. The body is the same bit for bit either way.
    pub ahead: u32,
}

impl Default for LiveOptions {
    /// A frame every 16 steps, 8 frames queued, up to 64 steps per request.
    fn default() -> LiveOptions {
        LiveOptions {
            frame_every: 16,
            queue: 8,
            ahead: 64,
        }
    }
}

struct Shared {
    stop: AtomicBool,
    /// Steps the worker may take (the app's clock); `u64::MAX` runs free.
    target: AtomicU64,
    /// The worker and the reference's thread, woken when the target moves or at a stop.
    threads: Mutex<Vec<thread::Thread>>,
}

impl Shared {
    /// Wakes the worker and the reference's thread (the target moved, or stop).
    fn wake(&self) {
        if let Ok(threads) = self.threads.lock() {
            for t in threads.iter() {
                t.unpark();
            }
        }
    }
}

/// Steps the reference's thread may be ahead of the worker: two of the student's longest
/// requests ([`LiveOptions::ahead`]'s default), so that the reference keeps stepping while the
/// worker is inside one request (it takes that request's steps only when it has ended) and the
/// two sides run side by side, not in turn.
const REFERENCE_AHEAD: usize = 128;

/// A running comparison (module docs); dropping it stops the worker.
pub struct Live {
    shared: Arc<Shared>,
    frames: Receiver<Frame>,
    setup: Setup,
    handover: Option<Handover>,
}

impl std::fmt::Debug for Live {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Live")
            .field("setup", &self.setup.integrator)
            .finish_non_exhaustive()
    }
}

impl Live {
    /// Starts the worker: `homework` beside the reference on `setup`; it takes no step until
    /// [`Live::advance_to`] or [`Live::run_free`].
    #[must_use]
    pub fn start(homework: Homework, setup: Setup, options: LiveOptions) -> Live {
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            target: AtomicU64::new(0),
            threads: Mutex::new(Vec::new()),
        });
        let (tx, frames) = mpsc::sync_channel(options.queue.max(1));
        let worker_shared = Arc::clone(&shared);
        let worker_setup = setup.clone();
        let handover = Handover::for_setup(&setup);
        let worker_handover = handover.clone();
        let handle = thread::Builder::new()
            .name("homework-live".to_string())
            .spawn(move || {
                // Both sides' physics on this thread alone: the pool's workers stay with the
                // lesson's own simulation (pool::alone).
                physics::pool::alone(|| {
                    let handover = worker_handover.as_ref();
                    work(
                        &homework,
                        &worker_setup,
                        options,
                        &worker_shared,
                        &tx,
                        handover,
                    );
                });
            })
            .ok();
        if let (Ok(mut threads), Some(h)) = (shared.threads.lock(), handle) {
            threads.push(h.thread().clone());
        }
        Live {
            shared,
            frames,
            setup,
            handover,
        }
    }

    /// Where the lesson's simulation hands its steps of the body to the reference
    /// (`live/handover.rs`), when they can be the reference's: the lesson run calls
    /// [`Handover::offer`] after each step.
    #[must_use]
    pub fn handover(&self) -> Option<Handover> {
        self.handover.clone()
    }

    /// What it compares.
    #[must_use]
    pub fn setup(&self) -> &Setup {
        &self.setup
    }

    /// Lets the worker step up to `step` (the app's clock).
    pub fn advance_to(&self, step: u64) {
        self.shared.target.fetch_max(step, Ordering::Relaxed);
        self.wake();
    }

    /// Lets the worker step to the horizon as fast as it can.
    pub fn run_free(&self) {
        self.advance_to(u64::MAX);
    }

    fn wake(&self) {
        self.shared.wake();
    }

    /// Every frame queued so far.
    #[must_use]
    pub fn drain(&self) -> Vec<Frame> {
        self.frames.try_iter().collect()
    }

    /// The next frame, waiting up to `wait`; `None` when none came or the worker ended.
    #[must_use]
    pub fn next_frame(&self, wait: Duration) -> Option<Frame> {
        self.frames.recv_timeout(wait).ok()
    }

    /// Asks the worker to stop; returns at once (a call in progress ends by its deadline and
    /// the student's program is then killed).
    pub fn stop(&self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(h) = &self.handover {
            h.end();
        }
        self.wake();
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The failure of a student call as a sentence naming `method` and the step.
fn describe_failure(payload: &(dyn std::any::Any + Send), method: &str, step: u64) -> String {
    if let Some(f) = payload.downcast_ref::<CallFailure>() {
        return match f {
            CallFailure::Panicked(why) => {
                format!("your {method}() panicked at step {step}: {why}")
            }
            CallFailure::Crashed(why) => {
                format!("your program ended during {method}() at step {step}: {why}")
            }
            CallFailure::TimedOut => {
                format!("your {method}() did not return in time at step {step}")
            }
            CallFailure::Malformed(why) => {
                format!("your {method}()'s answer at step {step} is unusable: {why}")
            }
            CallFailure::NotStarted(why) => format!("your program did not start: {why}"),
        };
    }
    let why = payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_string()))
        .unwrap_or_else(|| "a panic".to_string());
    format!("your {method}() panicked at step {step}: {why}")
}

/// The worker (module docs): the student's side and the comparison on this thread, the
/// reference's steps on a thread of their own ([`reference_steps`]), so that the two sides'
/// physics run on both cores at once; the bodies and every measurement are those of one thread
/// doing both in turn.
fn work(
    homework: &Homework,
    setup: &Setup,
    options: LiveOptions,
    shared: &Shared,
    tx: &SyncSender<Frame>,
    handover: Option<&Handover>,
) {
    let horizon = if setup.horizon == 0 {
        u64::MAX
    } else {
        setup.horizon
    };
    let (steps_tx, steps) = mpsc::sync_channel(REFERENCE_AHEAD);
    thread::scope(|scope| {
        let spawned = thread::Builder::new()
            .name("homework-reference".to_string())
            .spawn_scoped(scope, move || {
                physics::pool::alone(|| {
                    reference_steps(setup, shared, horizon, &steps_tx, handover);
                });
            });
        let mut steps = match spawned {
            Ok(handle) => {
                if let Ok(mut threads) = shared.threads.lock() {
                    threads.push(handle.thread().clone());
                }
                Steps::Thread(steps)
            }
            Err(_) => Steps::Here(Box::new(Track::new(setup, 1))),
        };
        compare(homework, setup, options, shared, tx, &mut steps, horizon);
        // The reference's thread ends at the closed channel (or `stop`); the scope waits.
        drop(steps);
        shared.wake();
    });
    // Dropping the last handle to a `Remote` (when the thread ends) stops its program.
}

/// The comparison (module docs): the student's steps, the parting test and the frames.
fn compare(
    homework: &Homework,
    setup: &Setup,
    options: LiveOptions,
    shared: &Shared,
    tx: &SyncSender<Frame>,
    steps: &mut Steps,
    horizon: u64,
) {
    let mut failure: Option<String> = None;
    let mut theirs = Snapshot::of(&Track::new(setup, 1), setup);
    let mut yours = Some(Track::new(setup, options.ahead));
    let n = setup.model.particle_count();
    if setup.integrator == Integrator::ImplicitEuler && n > largest_jacobian_body() {
        // Physics hands implicit Euler dense Jacobians: stated, shown, and not run.
        yours = None;
        failure = Some(format!(
            "your implicit_euler() is not run on this body: {}",
            jacobian_too_large(n)
        ));
    }
    let scales = body::Scales::of(setup);
    let mut bound = body::EnergyBound::of(setup);
    let mut vmax = scales.velocity;
    let mut parting: Option<Parting> = None;
    let mut step = 0u64;
    let mut finished_sent = false;
    loop {
        if shared.stop.load(Ordering::Relaxed) {
            break;
        }
        let target = shared.target.load(Ordering::Relaxed).min(horizon);
        if step >= target {
            if step >= horizon && !finished_sent {
                finished_sent = true;
                let r = Measure::of_snapshot(&theirs, setup);
                let y = yours.as_ref().map(|t| Measure::of(t, setup));
                let frame = frame_of(step, setup, &r, y.as_ref(), parting, &failure);
                if tx
                    .send(Frame {
                        finished: true,
                        ..frame
                    })
                    .is_err()
                {
                    break;
                }
            }
            thread::park_timeout(Duration::from_millis(20));
            continue;
        }
        let Some(next) = steps.next(setup) else {
            break;
        };
        theirs = next;
        // The student's program may run ahead up to the target (many steps per request).
        let budget = target - step;
        step += 1;
        let mut event = false;
        if let Some(track) = yours.as_mut() {
            let outcome = catch_unwind(AssertUnwindSafe(|| track.step(homework, setup, budget)));
            let problem = match outcome {
                Err(payload) => Some(describe_failure(
                    payload.as_ref(),
                    setup.integrator.name(),
                    step,
                )),
                Ok(()) => track.problem(setup.integrator.name(), step),
            };
            if let Some(why) = problem {
                failure = Some(why);
                yours = None;
                event = true;
            }
        }
        vmax = vmax.max(theirs.speed);
        let framed = step.is_multiple_of(options.frame_every.max(1)) || step == target;
        // The parting test reads the bodies where they are; both are measured (copied, their
        // energies summed) only for a frame.
        if parting.is_none()
            && let Some(track) = yours.as_ref()
        {
            parting = body::parting(&theirs, track, &mut bound, &scales, vmax, setup, step);
            event |= parting.is_some();
        }
        if event || framed {
            let r = Measure::of_snapshot(&theirs, setup);
            let y = yours.as_ref().map(|t| Measure::of(t, setup));
            let frame = frame_of(step, setup, &r, y.as_ref(), parting, &failure);
            if tx.send(frame).is_err() {
                break;
            }
        }
    }
    // Dropping the last handle to a `Remote` (when the thread ends) stops its program.
}

fn frame_of(
    step: u64,
    setup: &Setup,
    theirs: &Measure,
    yours: Option<&Measure>,
    parting: Option<Parting>,
    failure: &Option<String>,
) -> Frame {
    Frame {
        step,
        time: step as f64 * setup.dt,
        reference: theirs.positions().to_vec(),
        yours: yours.map(|y| y.positions().to_vec()),
        distance: yours.map_or(0.0, |y| theirs.distance(y)),
        energy_reference: theirs.energy,
        energy_yours: yours.map(|y| y.energy),
        parting,
        failure: failure.clone(),
        finished: false,
    }
}
