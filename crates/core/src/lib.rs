//! springlab-core: the physics ([`physics`]), the scenes of the courses ([`scene`]), the headless
//! simulation driver ([`simulation`]) and what they share. The `springlab` crate re-exports every
//! module under the same name (`springlab::physics`, …). See `ARCHITECTURE.md` for the module map.

// Index loops `for i in 0..n` read like the formulas they implement (x_i, v_i, a_i) and keep the
// lesson code close to the papers; clippy's iterator preference is waived for that reason.
#![allow(clippy::needless_range_loop)]
// Unchecked code (the lint below) only in the fast engine (`physics::fast`: intrinsics, the
// pool).
#![deny(unsafe_code)]

pub mod bench;
pub mod budget;
pub mod format;
pub mod output;
pub mod physics;
#[doc(hidden)]
pub mod random;
pub mod scene;
pub mod simulation;

pub use physics::{Energy, Method, MethodParams, Model, Spring, SpringKind, State, Workspace};
pub use scene::{Scene, SceneError};
pub use simulation::{RunReport, Simulation};
