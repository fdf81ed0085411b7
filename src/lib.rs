//! springlab: a teaching tool for mass-spring particle systems.
//!
//! The library holds the physics ([`physics`]), the scenes of the courses ([`scene`]) and the
//! headless simulation driver ([`simulation`]); the binary `springlab` is a thin command line
//! over them. See `ARCHITECTURE.md` for the module map.

// Index loops `for i in 0..n` read like the formulas they implement (x_i, v_i, a_i) and keep the
// lesson code close to the papers; clippy's iterator preference is waived for that reason.
#![allow(clippy::needless_range_loop)]
// Unchecked code (the lint below) only in the fast engine (`physics::fast`: intrinsics, the
// pool) and the grader's process sandbox (fork/exec and limits).
#![deny(unsafe_code)]

pub mod bench;
pub mod budget;
pub mod cli;
pub mod format;
pub mod grade;
pub mod lesson;
pub mod output;
pub mod physics;
mod random;
pub mod render;

pub use physics::{Energy, Method, MethodParams, Model, Spring, SpringKind, State, Workspace};
pub mod scene;
pub mod simulation;
pub mod study;
pub mod tui;

pub use scene::{Scene, SceneError};
pub use simulation::{RunReport, Simulation};
