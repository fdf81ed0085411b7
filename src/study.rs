//! Studies: which method, which time step, how fast, how accurate.
//!
//! A study runs a scene many times under the library's own integrators and measures one property
//! of each method:
//!
//! - [`stability`](mod@stability): the largest stable time step of each method, by the growth
//!   of perturbations ([`linear`]) confirmed by a run, beside the damped theory ([`theory`]);
//! - [`modes`]: the stiffest mode `ω_max` of a scene, which turns a time step into the
//!   dimensionless `dt·ω_max` that the stability limits are stated in.
//!
//! - [`convergence`](mod@convergence): the error of each method at a fixed time for `dt, dt/2, …`,
//!   its fitted order, and the cost (force evaluations, wall time) of each accuracy — the data of
//!   both `study convergence` and `study work-precision`.
//!
//! Every study is deterministic: the same scene and options give the same numbers, run to run.

pub mod advise;
pub mod ahead;
pub mod convergence;
pub mod linear;
pub mod modes;
pub mod observe;
pub mod resolution;
pub mod stability;
pub mod theory;

pub use modes::{OmegaEstimate, omega_max};
pub use stability::{
    Confirmation, MethodLimit, Probe, Stability, StabilityOptions, StabilityReport, max_stable_dt,
    stability,
};

use crate::physics::UnknownMethod;
use crate::scene::SceneError;

/// Anything a user can get wrong when asking for a study.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The scene or one of its parameters.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A method name that does not exist.
    #[error(transparent)]
    Method(#[from] UnknownMethod),
    /// `--methods` named no method.
    #[error("--methods: expected a comma-separated list of methods, for example rk4,verlet")]
    NoMethods,
    /// A time step that is not positive and finite.
    #[error("--dt {0}: expected a time step in seconds > 0")]
    TimeStep(f64),
    /// A measuring time that is not a positive, finite duration.
    #[error("--time {0}: expected a duration in seconds > 0")]
    Time(f64),
    /// Too few time steps to fit an order.
    #[error("--levels {0}: expected at least 2 time steps to fit an order")]
    Levels(u32),
    /// A tolerance that is not positive and finite.
    #[error(
        "--tolerance {0}: expected a positive number (metres for positions and lengths, seconds for times)"
    )]
    Tolerance(f64),
    /// Bad resolutions for a resolution study or advise.
    #[error("--n: {0}")]
    Resolutions(String),
    /// A horizon that is not a positive, finite duration.
    #[error("--horizon {0}: expected a duration in seconds > 0")]
    Horizon(f64),
    /// The scene's springs give no stiffness to any free particle.
    #[error(
        "scene `{0}` has no stiffness on a free particle (ω_max = 0): a stability limit dt·ω_max \
         is undefined; give its springs a stiffness > 0"
    )]
    NoStiffness(String),
    /// A horizon so long that one probe would take more than [`stability::MAX_STEPS`] steps.
    #[error(
        "--horizon {horizon}: at the smallest probed dt ({dt:.3e} s) a run would take {steps:.3e} \
         steps, more than {max:.0e}; choose a shorter horizon"
    )]
    TooManySteps {
        /// The horizon (s).
        horizon: f64,
        /// The smallest time step probed (s).
        dt: f64,
        /// Steps of one run at that time step.
        steps: f64,
        /// The limit.
        max: f64,
    },
}
