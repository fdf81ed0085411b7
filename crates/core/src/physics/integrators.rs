//! Time integrators: one enum, one file per method.
//!
//! Every method advances a [`State`] by one step `dt` under a [`Model`]. The explicit methods learn
//! about the physics only through [`accelerations`](super::accelerations), so their cost is their
//! number of force evaluations, which [`Method::step`] returns.
//!
//! | method | force evaluations / step | global order | oscillator stability (dt·ω) |
//! |---|---|---|---|
//! | explicit Euler | 1 | 1 | none undamped (energy grows at every dt) |
//! | semi-implicit Euler | 1 | 1 | dt·ω < 2 |
//! | midpoint (RK2) | 2 | 2 | none undamped (grows like (dt·ω)⁴/4 per step) |
//! | RK4 | 4 | 4 | dt·ω < 2√2 ≈ 2.828 |
//! | implicit (backward) Euler | 1 + a linear solve | 1 | unconditional |
//! | predictor–corrector | 2 | 1 | dt·ω ≤ 1 (undamped); on pure damping dt·λ ≤ 1, half of explicit Euler's 2 |
//! | position Verlet | 1 | 2 (1 with dampers or drag) | dt·ω < 2 |
//! | XPBD | 1 per substep | 1 | unconditional (dissipative) |
//! | velocity Verlet | 2 | 2 (also with dampers) | dt·ω < 2 |
//!
//! **Energy accounting.** With [`Workspace::account`] set, a step also integrates the power of
//! the dissipative forces (dampers, drag, contact forces and friction,
//! [`dissipated_power`]) as one more equation `D' = P(x, v)`, stepped with the method's own
//! stages and weights (RK4: `dt/6 (P1 + 2 P2 + 2 P3 + P4)`; midpoint: `dt P(mid)`;
//! predictor–corrector: `dt P(predicted)`; the Euler methods and Verlet: `dt P(x_n, v_n)`;
//! implicit Euler: `dt P(x_{n+1}, v_{n+1})`), so that the residual
//! `E + D - E_0` shrinks with the method's order. [`Workspace::dissipated`] holds the result.

pub mod declaration;

use std::fmt;
use std::str::FromStr;

use std::sync::Arc;

use glam::{DMat3, DVec3};
use serde::{Serialize, Serializer};

use super::energy::{Dissipated, Power, dissipated_power};
use super::forces::{Model, accelerations};
use super::particles::State;
use super::stencil::{After, Base, Output, Stencil, Update};

pub use declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction};
pub use implicit_euler::{MAX_CONTACT_PASSES, SolveStats, guard_energy, guard_start_energy};

/// The registry: one line per method, `Variant => file`, in teaching order. The file holds the
/// method (formula, textbook step) and its [`Declaration`]; this line makes it a [`Method`],
/// puts it into [`Method::ALL`] and hands [`Method::declaration`] its row.
macro_rules! methods {
    ($($variant:ident => $file:ident,)*) => {
        $(mod $file;)*

        /// An integration method: one file each in `integrators/`, registered in
        /// `integrators.rs`; [`Method::declaration`] is what everything else reads.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Method {
            $(
                #[doc = concat!("Declared in `crates/core/src/physics/integrators/", stringify!($file), ".rs`.")]
                $variant,
            )*
        }

        impl Method {
            /// Every method, in teaching order.
            pub const ALL: [Method; [$(stringify!($variant)),*].len()] = [$(Method::$variant),*];

            /// The method's row of the registry.
            #[must_use]
            pub fn declaration(self) -> &'static Declaration {
                match self {
                    $(Method::$variant => &$file::DECLARATION,)*
                }
            }
        }
    };
}

methods! {
    ExplicitEuler => explicit_euler,
    SemiImplicitEuler => semi_implicit_euler,
    Midpoint => midpoint,
    Rk4 => rk4,
    ImplicitEuler => implicit_euler,
    PredictorCorrector => predictor_corrector,
    Verlet => verlet,
    Xpbd => xpbd,
    VelocityVerlet => velocity_verlet,
}

impl Method {
    /// The number of methods.
    pub const COUNT: usize = Method::ALL.len();

    /// The position in [`Method::ALL`].
    #[must_use]
    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether the method reads the [`MethodParams`] field `param`.
    #[must_use]
    pub fn reads(self, param: &str) -> bool {
        self.declaration().params.contains(&param)
    }

    /// The command-line name, for example `semi-implicit-euler`.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.declaration().name
    }

    /// The next method in [`Method::ALL`], wrapping around.
    #[must_use]
    pub fn next(self) -> Method {
        let i = Method::ALL.iter().position(|&m| m == self).unwrap_or(0);
        Method::ALL[(i + 1) % Method::ALL.len()]
    }

    /// Advances `state` by `dt` seconds; returns the number of force evaluations it took.
    ///
    /// `work` holds the method's scratch buffers; it grows on the first call for a model size and
    /// is reused afterwards, so steps do not allocate.
    pub fn step(
        self,
        model: &Model,
        state: &mut State,
        dt: f64,
        params: &MethodParams,
        work: &mut Workspace,
    ) -> u64 {
        work.resize(model.particle_count(), model.springs.len());
        work.dissipated = Dissipated::default();
        work.projected = false;
        let evals = (self.declaration().step)(model, state, dt, params, work);
        work.dissipated = work.dissipated.summed();
        if let Some(projection) = &work.projection
            && !work.projected
        {
            // The method has no fused last pass (or took the textbook loops): project here.
            (projection.0)(&mut state.x, &mut state.v);
        }
        evals
    }
}

impl Method {
    /// `n` steps of [`Method::step`]; returns the force evaluations they took.
    ///
    /// Semi-implicit Euler and RK4 on a lattice take them in one call, the same numbers bit
    /// for bit: on a large lattice as one team of threads, without handing each pass to the
    /// pool; semi-implicit Euler on a small lattice (a rope, no projection) with the particles
    /// in the stencil's layout in between, without converting the state at every step. With
    /// energy accounting ([`Workspace::account`]) the passes also write the dissipated power,
    /// and [`Workspace::step_dissipated`] holds what each step dissipated, the same bits as
    /// each [`Method::step`]'s [`Workspace::dissipated`].
    pub fn steps(
        self,
        model: &Model,
        state: &mut State,
        dt: f64,
        params: &MethodParams,
        work: &mut Workspace,
        n: u64,
    ) -> u64 {
        work.resize(model.particle_count(), model.springs.len());
        work.step_dissipated.clear();
        let many = match self.declaration().many {
            Some(many) if n >= 2 => many(model, state, dt, work, n),
            _ => None,
        };
        if let Some(evals) = many {
            work.dissipated = Dissipated::default();
            return evals;
        }
        work.step_dissipated.clear();
        // With accounting, a method may leave a share of each step's dissipated energy to
        // the batch's end (Verlet's projection: `fast::energy::Batch`), the same numbers.
        work.energy_batch.on = work.account;
        let evals = (0..n)
            .map(|_| {
                let evals = self.step(model, state, dt, params, work);
                if let Some(response) = &work.response {
                    (response.0)(model, &mut state.x, &mut state.v);
                }
                if work.account {
                    work.step_dissipated.push(work.dissipated);
                }
                evals
            })
            .sum();
        work.energy_batch.on = false;
        work.energy_batch.finish(&mut work.step_dissipated);
        if let Some(&last) = work.step_dissipated.last() {
            work.dissipated = last;
        }
        evals
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for Method {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// A method name that is not one of [`Method::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown method `{0}`; expected one of: {names}", names = method_names())]
pub struct UnknownMethod(pub String);

/// The command-line names of all methods, comma separated.
#[must_use]
pub fn method_names() -> String {
    Method::ALL.map(Method::name).join(", ")
}

impl FromStr for Method {
    type Err = UnknownMethod;

    fn from_str(s: &str) -> Result<Method, UnknownMethod> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownMethod(s.to_string()))
    }
}

/// Settings of the methods that have any; each scene supplies its defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MethodParams {
    /// Verlet's damping factor γ per step in `x + (1 - γ)(x - x_prev)` (dimensionless,
    /// 0 ≤ γ < 1): GAMES101's form, whose decay rate `≈ γ/dt` changes with the step.
    pub verlet_damping: f64,
    /// Verlet's damping rate `r` (1/s), the same at every dt, applied with the centred velocity
    /// so that Verlet stays second order (see `verlet.rs`).
    pub verlet_damping_rate: f64,
    /// Verlet: constraint-projection passes per step (0 = plain position Verlet).
    /// XPBD: solver passes per substep (at least 1).
    pub iterations: u32,
    /// XPBD substeps per step.
    pub substeps: u32,
    /// Implicit Euler: conjugate-gradient stop when `|r| ≤ tolerance · |b|`.
    pub cg_tolerance: f64,
    /// Implicit Euler: conjugate-gradient iteration limit.
    pub cg_max_iterations: u32,
}

impl Default for MethodParams {
    /// GAMES101's Verlet damping 0.00005 with one projection pass; 10 XPBD substeps; CG to a
    /// relative residual of 1e-3 (why: `implicit_euler.rs`, "How exact the solve is").
    fn default() -> MethodParams {
        MethodParams {
            verlet_damping: 0.00005,
            verlet_damping_rate: 0.0,
            iterations: 1,
            substeps: 10,
            cg_tolerance: 1e-3,
            cg_max_iterations: 1000,
        }
    }
}

/// Scratch buffers shared by the methods, sized once per model.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pub(crate) a: Vec<DVec3>,
    pub(crate) x_stage: Vec<DVec3>,
    pub(crate) v_stage: Vec<DVec3>,
    pub(crate) k: [Vec<DVec3>; 4],
    pub(crate) kx: [Vec<DVec3>; 4],
    pub(crate) blocks: Vec<DMat3>,
    pub(crate) diag_inv: Vec<DMat3>,
    pub(crate) cg: [Vec<DVec3>; 4],
    pub(crate) lambda: Vec<f64>,
    /// XPBD: the springs of a step's passes with their constants ([`crate::physics::fast::xpbd`]).
    pub(crate) xpbd: crate::physics::fast::xpbd::XpbdRows,
    /// Verlet: the springs as rods, in projection order.
    pub(crate) rods: Vec<crate::physics::constraints::Rod>,
    /// Verlet: a chain's rods and particles laid out for the fast projection.
    pub(crate) chain: crate::physics::constraints::ChainScratch,
    /// Verlet's accounting: the kinetic and gravitational term of each particle before the
    /// projection (J, `fast::energy::kinetic_gravity_terms`).
    pub(crate) energy_terms: Vec<f64>,
    /// Verlet's accounting inside [`Method::steps`]: the sums of several steps added up
    /// together (`fast::energy::Batch`).
    pub(crate) energy_batch: crate::physics::fast::energy::Batch,
    /// Statistics of the last implicit solve.
    pub last_solve: SolveStats,
    /// Implicit Euler: the contact constraints of the current step.
    pub(crate) constraints: Vec<implicit_euler::Constraint>,
    /// Implicit Euler: the particles that a solve's `Δv` carries inside a sphere (the contact
    /// search's candidates).
    pub(crate) inside: Vec<usize>,
    /// Implicit Euler: the rows of the dynamic spheres that the step's contacts tie into the
    /// solve.
    pub(crate) sphere_rows: crate::physics::fast::implicit_constraint::SphereRows,
    /// When true, every step also integrates the dissipated power with the method's own stages
    /// (energy accounting, [`crate::physics::energy::dissipated_power`]); costs about one more
    /// pass over the springs per stage, and one more force evaluation with colliders.
    pub account: bool,
    /// The energy the last step dissipated (J), when `account` is set; contact responses after
    /// the step are not in it (the simulation adds them).
    pub dissipated: Dissipated,
    /// Scratch space of the dissipated power.
    pub(crate) power_f: PowerScratch,
    /// With `account`: what each step of the last [`Method::steps`] dissipated, in order.
    pub(crate) step_dissipated: Vec<Dissipated>,
    /// Scratch of the many-step paths: each step's (or pass's) power `(dampers and drag,
    /// contact)` (W), and the power ring of a team ([`Stencil::team_with_power`]).
    pub(crate) step_powers: Vec<(f64, f64)>,
    pub(crate) power_slots: Vec<f64>,
    /// When true, every method runs its textbook loops even on a lattice, where it otherwise
    /// fuses its stages into the stencil's passes (same numbers, bit for bit: the tests
    /// compare the two).
    pub textbook: bool,
    /// Applied to every particle's position and velocity at the end of each step, inside the
    /// method's last pass where it has a fused one (the benchmark workloads' contact rules).
    pub projection: Option<Projection>,
    /// Set by a fused last pass that applied `projection` itself.
    pub(crate) projected: bool,
    /// Applied to the whole state after each step of [`Method::steps`] (never by
    /// [`Method::step`]): between two steps of a thread team, on one of its threads while the
    /// others wait (`Simulation::advance`'s collision response).
    pub response: Option<Response>,
    /// What the last collision response changed (energy accounting; see `Simulation`).
    pub(crate) changes: super::collide::Changes,
    /// Implicit Euler: start each solve from the last step's `Δv` (scaled by the ratio of the
    /// steps) instead of zero. A step then depends on the steps before it (within the solve's
    /// tolerance), so it is off by default: `Simulation` turns it on; finite differences of
    /// single steps (the stability study) keep it off.
    pub warm_start: bool,
    /// Implicit Euler: the last step's `Δv` (m/s) and its `dt` (s), for the warm start.
    pub(crate) last_dv: Vec<DVec3>,
    pub(crate) last_dt: f64,
    /// The `Δv` and `dt` of the step before that (the warm start's extrapolation).
    pub(crate) before_dv: Vec<DVec3>,
    pub(crate) before_dt: f64,
    /// Implicit Euler on a lattice: the elastic energy (J) at the step's start, summed by its
    /// assembly (for `Simulation`'s energy guard); `None` when the step summed none.
    pub start_elastic: Option<f64>,
    /// Implicit Euler's system on a lattice (`implicit_lattice`).
    pub(crate) lattice: crate::physics::fast::implicit_lattice::Lattice,
}

/// A per-particle rule on positions and velocities (m, m/s) applied at the end of every step
/// (see [`Workspace::projection`]). It must treat every particle on its own: it may be applied
/// to any split of the particles, in any order.
#[derive(Clone)]
pub struct Projection(pub Arc<ProjectionFn>);

/// The function of a [`Projection`].
pub type ProjectionFn = dyn Fn(&mut [DVec3], &mut [DVec3]) + Send + Sync;

impl std::fmt::Debug for Projection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Projection")
    }
}

/// A rule on the whole state, positions and velocities (m, m/s), with the model, applied after
/// each step of [`Method::steps`] (see [`Workspace::response`]). Unlike a [`Projection`] it may
/// read any particle (a collision response that measures the springs, or pays from the body's
/// kinetic energy); it runs on one thread at a time, in step order.
///
/// The second function, if given, prepares it part by part: where a team of threads runs the
/// steps ([`crate::physics::stencil::Crew::pass_then`]), each thread calls it on the particles of its own
/// part right after the step's last pass wrote them, `(model, part, first particle, x, v)`, so
/// that the response can read a summary of each part (its broad phase) instead of scanning
/// every particle on one thread. The response must give the same result with or without it.
#[derive(Clone)]
pub struct Response(pub Arc<ResponseFn>, pub Option<Arc<PrepareFn>>);

/// The function of a [`Response`].
pub type ResponseFn = dyn Fn(&Model, &mut [DVec3], &mut [DVec3]) + Send + Sync;

/// The preparing function of a [`Response`]: model, part, its first particle, its new positions
/// (m) and velocities (m/s).
pub type PrepareFn = dyn Fn(&Model, usize, usize, &mut [DVec3], &mut [DVec3]) + Send + Sync;

impl Response {
    /// The preparing function bound to `model`, as a team's threads call it on each part they
    /// wrote (part, its first particle, its new positions (m) and velocities (m/s)); `None`
    /// when the response prepares nothing.
    // The returned closure's type is `PartFn`'s (`stencil/team.rs`) without the reference.
    #[allow(clippy::type_complexity)]
    pub(crate) fn part_summary<'a>(
        &'a self,
        model: &'a Model,
    ) -> Option<impl Fn(usize, usize, &mut [DVec3], &mut [DVec3]) + Sync + 'a> {
        let prepare = self.1.as_deref()?;
        Some(
            move |k: usize, q0: usize, x: &mut [DVec3], v: &mut [DVec3]| {
                prepare(model, k, q0, x, v);
            },
        )
    }
}

impl std::fmt::Debug for Response {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Response")
    }
}

/// Scratch space of the dissipated power: forces before contact (spring-list models) and the
/// stencil's per-chunk sums (lattices).
#[derive(Clone, Debug, Default)]
pub(crate) struct PowerScratch {
    forces: Vec<DVec3>,
    chunks: Vec<f64>,
}

impl PowerScratch {
    /// The stencil's power buffer, sized for `stencil`.
    fn chunks(&mut self, stencil: &Stencil) -> &mut [f64] {
        self.chunks.resize(stencil.power_len(), 0.0);
        &mut self.chunks
    }
}

impl Workspace {
    /// An empty workspace; buffers grow on first use.
    #[must_use]
    pub fn new() -> Workspace {
        Workspace::default()
    }

    /// Sizes the buffers for `model` and for `steps` steps of [`Method::steps`] (each step's
    /// dissipated energy and power) before the first step needs them: a caller that times its
    /// steps does not time their allocation (the same numbers either way).
    pub fn prepare(&mut self, model: &Model, steps: usize) {
        self.resize(model.particle_count(), model.springs.len());
        self.step_dissipated.reserve(steps);
        self.step_powers.reserve(steps);
    }

    fn resize(&mut self, particles: usize, springs: usize) {
        if self.a.len() == particles && self.lambda.len() == springs {
            return;
        }
        let zeros = vec![DVec3::ZERO; particles];
        self.a.clone_from(&zeros);
        self.x_stage.clone_from(&zeros);
        self.v_stage.clone_from(&zeros);
        for buf in self
            .k
            .iter_mut()
            .chain(self.kx.iter_mut())
            .chain(self.cg.iter_mut())
        {
            buf.clone_from(&zeros);
        }
        self.power_f.forces.clone_from(&zeros);
        self.diag_inv = vec![DMat3::ZERO; particles];
        self.blocks = vec![DMat3::ZERO; springs];
        self.lambda = vec![0.0; springs];
    }
}

/// The dissipated power at `(x, v)` when `account` is set, else zero (see
/// [`dissipated_power`]); on a lattice from one pass of the stencil (the same sums up to
/// rounding).
fn power_if(
    account: bool,
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    scratch: &mut PowerScratch,
) -> Power {
    if !account {
        return Power::default();
    }
    if let Some(stencil) = model.stencil() {
        let parts = stencil.parallel_parts(crate::physics::pool::Pool::global().threads());
        return stencil_power(stencil, model, x, v, scratch, parts);
    }
    dissipated_power(model, x, v, &mut scratch.forces)
}

/// The dissipated power at `(x, v)` from one pass of `stencil` split into `parts` ranges (the
/// sums do not depend on the split, see [`Stencil::write_in_parts`]).
fn stencil_power(
    stencil: &Stencil,
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    scratch: &mut PowerScratch,
    parts: usize,
) -> Power {
    let output = Output::Power(model.dynamics(true));
    stencil.write_in_parts(
        x,
        v,
        [&mut [], &mut [], &mut []],
        scratch.chunks(stencil),
        output,
        parts,
    );
    let contact = !model.colliders.is_empty();
    let (dampers_and_drag, contact) = Stencil::sum_power(&scratch.chunks, contact);
    Power {
        dampers_and_drag,
        contact,
    }
}

// ---------------------------------------------------------------------------------------------
// The seam between the textbook loops and the fused passes
// ---------------------------------------------------------------------------------------------

/// An explicit method's textbook step (its file's `textbook`): the loops of its formulas.
type TextbookStep = fn(&Model, &mut State, f64, &mut Workspace) -> u64;

/// The same step in the stencil's fused passes (its file's `step_fused`): the same numbers,
/// tested per method.
type FusedStep = fn(&Stencil, &Model, &mut State, f64, &mut Workspace) -> u64;

/// The seam of every explicit method: `fast` on a lattice when the fused passes are wanted
/// ([`fused`]), else `textbook`. Returns the force evaluations.
fn explicit_step(
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
    textbook: TextbookStep,
    fast: FusedStep,
) -> u64 {
    match fused(model, work.textbook) {
        Some(stencil) => fast(stencil, model, state, dt, work),
        None => textbook(model, state, dt, work),
    }
}

/// The stencil, when the method should fuse its stages into the stencil's passes: a lattice,
/// and `textbook` (the workspace's flag) not set.
fn fused(model: &Model, textbook: bool) -> Option<&Stencil> {
    if textbook { None } else { model.stencil() }
}

/// The stencil and its number of parts when a method's many steps can run as one team of
/// threads ([`Stencil::team`]): a lattice with the fused passes wanted ([`fused`]) and work for
/// at least two threads.
fn team<'m>(model: &'m Model, work: &Workspace) -> Option<(&'m Stencil, usize)> {
    let stencil = fused(model, work.textbook)?;
    let parts = stencil.parallel_parts(crate::physics::pool::Pool::global().threads());
    (parts >= 2).then_some((stencil, parts))
}

/// One fused pass: `output` at `(x, v)` into `outs` (see [`Stencil::write`]), and the
/// dissipated power at `(x, v)` from the same pass when `account` (zero otherwise).
fn fused_pass(
    stencil: &Stencil,
    x: &[DVec3],
    v: &[DVec3],
    outs: [&mut [DVec3]; 3],
    output: Output,
    account: bool,
    scratch: &mut PowerScratch,
) -> Power {
    if !account {
        stencil.write(x, v, outs, &mut [], output);
        return Power::default();
    }
    let (dampers_and_drag, contact) =
        stencil.write_with_power(x, v, outs, scratch.chunks(stencil), output);
    Power {
        dampers_and_drag,
        contact,
    }
}

/// `a = a(x, v)` ([`accelerations`]) and, when `account`, the dissipated power at `(x, v)`
/// ([`power_if`], zero otherwise), for a method whose update is its own loop (position and
/// velocity Verlet): on a lattice with the fused passes wanted (`textbook` not set) both come
/// from one stencil pass ([`fused_pass`]) instead of two, the same numbers bit for bit (the
/// accelerations are that pass's output, and its power sums do not depend on what it writes or
/// on the split); else the two calls.
fn accelerations_and_power(
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    a: &mut [DVec3],
    account: bool,
    textbook: bool,
    scratch: &mut PowerScratch,
) -> Power {
    match fused(model, textbook) {
        Some(stencil) => {
            let output = Output::Accelerations(model.dynamics(true));
            fused_pass(
                stencil,
                x,
                v,
                [a, &mut [], &mut []],
                output,
                account,
                scratch,
            )
        }
        None => {
            accelerations(model, x, v, a);
            power_if(account, model, x, v, scratch)
        }
    }
}

/// A one-pass step on a lattice: every thread computes its particles' accelerations and applies
/// `update` to them in the same pass (with the dissipated power and the projection), into fresh
/// buffers, because the other threads still read the old positions and velocities; then the
/// buffers become the state. Returns the force evaluations (1).
fn one_pass_step(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
    update: Update,
) -> u64 {
    let output = Output::Step {
        dynamics: model.dynamics(true),
        update,
        after: after(&work.projection),
    };
    let (x_new, v_new) = (&mut work.x_stage, &mut work.v_stage);
    let outs = [&mut x_new[..], &mut v_new[..], &mut []];
    let p = fused_pass(
        stencil,
        &state.x,
        &state.v,
        outs,
        output,
        work.account,
        &mut work.power_f,
    );
    work.dissipated.add_power(dt, p);
    std::mem::swap(&mut state.x, x_new);
    std::mem::swap(&mut state.v, v_new);
    work.projected = true;
    state.history_valid = false;
    1
}

/// A two-pass step on a lattice, the shape midpoint and the predictor–corrector share: the
/// first pass writes the stage `(x + h v, v + h a)` from the state into the stage buffers, the
/// second advances the state in place from the stage, `x += dt v_stage`, `v += dt a(stage)`
/// (with the projection), and the dissipated power at the stage. Returns the force
/// evaluations (2).
fn stage_then_step(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    h: f64,
    work: &mut Workspace,
) -> u64 {
    let Workspace {
        x_stage,
        v_stage,
        account,
        dissipated,
        power_f,
        projection,
        projected,
        ..
    } = work;
    let dynamics = model.dynamics(true);
    let stage = Output::Step {
        dynamics,
        update: Update::Euler {
            h,
            base: Base::Input,
        },
        after: None,
    };
    let outs = [&mut x_stage[..], &mut v_stage[..], &mut []];
    fused_pass(stencil, &state.x, &state.v, outs, stage, false, power_f);
    let last = Output::Step {
        dynamics,
        update: Update::Euler {
            h: dt,
            base: Base::InPlace,
        },
        after: after(projection),
    };
    let outs = [&mut state.x[..], &mut state.v[..], &mut []];
    // D_{n+1} = D_n + dt P(stage), when accounting: from the pass at the stage.
    let p = fused_pass(stencil, x_stage, v_stage, outs, last, *account, power_f);
    dissipated.add_power(dt, p);
    *projected = true;
    state.history_valid = false;
    2
}

/// The projection as the stencil's per-tile hook.
pub(super) fn after(projection: &Option<Projection>) -> Option<After<'_>> {
    projection.as_ref().map(|p| &*p.0 as After)
}
