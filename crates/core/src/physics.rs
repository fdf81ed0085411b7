//! The physics of mass-spring systems: state, forces, integrators, constraints, energy.
//!
//! # Theory
//!
//! A mass-spring system is a set of point masses (particles) joined by springs. Its motion obeys
//! Newton's second law for every particle,
//!
//! ```text
//! m_i x_i'' = f_i(x, v)
//! ```
//! an ordinary differential equation in the positions `x` (m) and velocities `v = x'` (m/s). An
//! integrator advances `(x, v)` by a time step `dt` (s). Methods differ in how many force
//! evaluations a step costs, how the error shrinks with `dt` (the order), and the largest `dt` at
//! which the simulation stays bounded (the stability limit, `dt·ω` for a spring of angular
//! frequency `ω = √(k/m)` rad/s). See [`integrators`] for the table.
//!
//! This module imports nothing else from the crate: scenes, studies, rendering, grading and the
//! terminal app are built on it, never the other way round.

pub mod bowl;
pub mod collide;
pub mod constraints;
pub mod diverge;
pub mod energy;
pub mod fast;
pub mod forces;
pub mod integrators;
pub mod particles;
pub mod springs;

pub(crate) use fast::lanes;
pub use fast::{pool, stencil};

pub use diverge::Divergence;
pub use energy::{Dissipated, Energy, Power, dissipated_power, energy};
pub use forces::{Model, accelerations, forces};
pub use integrators::{
    Declaration, Method, MethodParams, OscillatorLimit, SolveStats, StabilityFunction,
    UnknownMethod, Workspace,
};
pub use particles::State;
pub use springs::{Spring, SpringKind};
