//! springlab: a teaching tool for mass-spring particle systems.
//!
//! The library holds the physics ([`physics`]), the scenes of the courses ([`scene`]) and the
//! headless simulation driver ([`simulation`]); the binary `springlab` is a thin command line
//! over them. See `ARCHITECTURE.md` for the module map. The core modules, the renderer and the
//! grader are crates of their own (`crates/`, so that they build in parallel), re-exported here
//! under their names: `springlab::physics`, `springlab::render`, `springlab::grade`, ….

// Index loops `for i in 0..n` read like the formulas they implement (x_i, v_i, a_i) and keep the
// lesson code close to the papers; clippy's iterator preference is waived for that reason.
#![allow(clippy::needless_range_loop)]
// Unchecked code (the lint below) only in the fast engine (`physics::fast`: intrinsics, the
// pool) and the grader's process sandbox (fork/exec and limits), both in crates of their own.
#![deny(unsafe_code)]

pub mod cli;
pub mod lesson;
pub mod study;
pub mod tui;

use springlab_core::random;
pub use springlab_core::{
    Energy, Method, MethodParams, Model, RunReport, Scene, SceneError, Simulation, Spring,
    SpringKind, State, Workspace,
};
pub use springlab_core::{bench, budget, format, output, physics, scene, simulation};
pub use springlab_grade::grade;
pub use springlab_render::render;
