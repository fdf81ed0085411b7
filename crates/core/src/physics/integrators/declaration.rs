//! What springlab knows about a method, in one place: its [`Declaration`].
//!
//! Every method file ends with one `pub(super) const DECLARATION: Declaration`, and
//! `integrators.rs` registers the file with one line. The lesson app (key, colour, label), the
//! budget (force evaluations, scratch), the damped stability theory and the stability study
//! (stability function, oscillator limit), the scene code (which parameters a method reads) and
//! the simulation (energy guard) read these rows and iterate [`Method::ALL`](super::Method::ALL);
//! none of them names a method to learn a fact about it.

use super::{MethodParams, Workspace};
use crate::physics::forces::Model;
use crate::physics::particles::State;

/// One step of a method: advances the state by `dt` and returns the force evaluations it took
/// (see [`Method::step`](super::Method::step)).
pub type StepFn = fn(&Model, &mut State, f64, &MethodParams, &mut Workspace) -> u64;

/// `n` steps of a method in one call, the same numbers as `n` single steps; `None` when this
/// model or workspace has no such path (see [`Method::steps`](super::Method::steps)).
pub type ManyStepsFn = fn(&Model, &mut State, f64, &mut Workspace, u64) -> Option<u64>;

/// A complex number `(re, im)`, the argument and value of an amplification factor.
pub type Complex = (f64, f64);

/// The product of two complex numbers.
#[must_use]
pub fn mul(a: Complex, b: Complex) -> Complex {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

/// `Σ c_k z^k` for the real coefficients `c` (lowest power first), by Horner's rule.
#[must_use]
pub fn polynomial(c: &[f64], z: Complex) -> Complex {
    c.iter().rev().fold((0.0, 0.0), |acc, &ck| {
        let p = mul(acc, z);
        (p.0 + ck, p.1)
    })
}

/// How a method behaves on one mode of the linearised, damped system
/// `x'' = -ω² x - μ x'` (the damped theory, `study::theory`).
#[derive(Clone, Copy, Debug)]
pub enum StabilityFunction {
    /// A one-step method on `y' = λ y`: the amplification factor `R(z)`, `z = dt λ`; stable on a
    /// mode while `|R(dt λ)| ≤ 1` for both of its eigenvalues `λ`.
    OneStep(fn(Complex) -> Complex),
    /// A method whose step on the mode is the recurrence `r² - t r + d = 0` (a partitioned or
    /// two-step method): `(t, d)` from `(params, dt, ω², μ)` (s, rad²/s², 1/s); stable while
    /// both roots lie in the unit circle.
    TwoStep(fn(&MethodParams, f64, f64, f64) -> (f64, f64)),
    /// The linear theory does not cover the method (with these parameters): why.
    NotCovered(&'static str),
}

/// The stability of a method on the undamped harmonic oscillator `x'' = -ω² x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OscillatorLimit {
    /// The amplitude grows at every step size.
    None,
    /// Stable while `dt·ω` stays below this number.
    Below(f64),
    /// Stable at every step size.
    Unconditional,
}

/// Scratch memory a method keeps beyond the buffers every method shares (bytes per particle and
/// per spring; the budget's memory estimate adds it once per method a run uses).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scratch {
    /// Bytes per particle.
    pub particle: f64,
    /// Bytes per spring.
    pub spring: f64,
}

impl Scratch {
    /// No scratch of its own.
    pub const NONE: Scratch = Scratch {
        particle: 0.0,
        spring: 0.0,
    };
}

/// Everything the rest of springlab knows about a method: its row of the registry.
#[derive(Clone, Copy, Debug)]
pub struct Declaration {
    /// The command-line name, for example `semi-implicit-euler`.
    pub name: &'static str,
    /// A short label for charts and tables, for example `SIE`.
    pub label: &'static str,
    /// The key that picks it in the lesson app's method chooser.
    pub key: char,
    /// The ANSI colour (0–15) of its lines in the lesson app's charts.
    pub colour: u8,
    /// Global order of accuracy on smooth, undamped problems.
    pub order: u32,
    /// Force evaluations (or their equivalent in work) per step, for the budget's estimates.
    pub evaluations: fn(&MethodParams) -> f64,
    /// Its stability on the undamped oscillator.
    pub oscillator: OscillatorLimit,
    /// Its stability function on a damped mode, with these parameters.
    pub stability: fn(&MethodParams) -> StabilityFunction,
    /// The fields of [`MethodParams`] it reads (the scenes' method parameters).
    pub params: &'static [&'static str],
    /// Scratch memory of its own.
    pub scratch: Scratch,
    /// Whether a lattice takes its stages in the stencil's fused passes.
    pub fused: bool,
    /// Whether `Simulation` retakes a step whose energy rose as two halves (the energy guard).
    pub energy_guard: bool,
    /// One step.
    pub step: StepFn,
    /// Many steps in one call, where it has such a path.
    pub many: Option<ManyStepsFn>,
}

/// One evaluation per step.
#[must_use]
pub fn one_evaluation(_: &MethodParams) -> f64 {
    1.0
}

/// Two evaluations per step.
#[must_use]
pub fn two_evaluations(_: &MethodParams) -> f64 {
    2.0
}
