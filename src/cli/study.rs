//! `springlab study`: stability limits, convergence orders, work-precision, resolution.

use clap::{Args, Subcommand};

use crate::budget::{self, Limits};
use crate::study::stability::DEFAULT_HORIZON;

mod convergence;
mod resolution;
mod stability;

pub use convergence::prepare_convergence;
use convergence::run_convergence;
use resolution::run_resolution;
pub use resolution::{difference_text, prepare_resolution};
pub use stability::prepare_stability;
use stability::run_stability;

/// The studies.
#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Largest stable time step of each method, by bisection on dt·ω_max.
    Stability(StabilityArgs),
    /// Error at a fixed time for dt, dt/2, ... and the fitted order of each method.
    Convergence(ConvergenceArgs),
    /// Error against cost (force evaluations and wall time) for each method, log-log.
    #[command(name = "work-precision")]
    WorkPrecision(ConvergenceArgs),
    /// The scene's observable against particle count and spring kinds, with the cost of each:
    /// where more model stops changing the answer.
    Resolution(ResolutionArgs),
}

/// Options of `springlab study resolution`.
#[derive(Debug, Args)]
pub struct ResolutionArgs {
    /// A built-in scene with a resolution parameter: `n` (cubes, jelly, cloths) or `nodes`
    /// (ropes).
    pub scene: String,
    /// Resolutions to run, comma separated, for example `4,6,8,10` (default: the scene's own
    /// with three coarser and one finer, spacing ratio about √2).
    #[arg(long = "n", value_name = "N,N,…", value_delimiter = ',')]
    pub levels: Option<Vec<i64>>,
    /// The method of every run (default rk4).
    #[arg(long, default_value = "rk4")]
    pub method: String,
    /// When the observable is taken, in seconds (default: 2.5 for the cubes and the jelly,
    /// 3 for cloth-sphere, 1 otherwise).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// The tolerance X: metres for positions and lengths, seconds for times (default 0.01).
    #[arg(long, value_name = "X", allow_negative_numbers = true,
          default_value_t = crate::study::resolution::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    /// Run only the scene's spring kinds (skip the runs without bend and without shear).
    #[arg(long)]
    pub no_kinds: bool,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Also draw the differences against particle count (log-log) into this PNG file.
    #[arg(long, value_name = "FILE")]
    pub png: Option<std::path::PathBuf>,
    /// Run even when the estimated steps, memory or time are over the limits (see README).
    #[arg(long)]
    pub force: bool,
}

/// Options of `springlab study convergence` and `springlab study work-precision`.
#[derive(Debug, Args)]
pub struct ConvergenceArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml).
    pub scene: String,
    /// Methods to study, comma separated (default: all), for example `rk4,verlet`.
    #[arg(long, value_name = "A,B")]
    pub methods: Option<String>,
    /// The time at which the error is measured, in seconds (default 1).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// The largest time step in seconds (default: the scene's; 0.005 s for the oscillator).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub dt: Option<f64>,
    /// Number of time steps dt, dt/2, ... (default 4 for convergence, 6 for work-precision).
    #[arg(long, value_name = "N")]
    pub levels: Option<u32>,
    /// Timed repeats per point; wall time is their median (default 1, 3 for work-precision).
    #[arg(long, value_name = "R")]
    pub repeats: Option<u32>,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Also draw the log-log chart into this PNG file.
    #[arg(long, value_name = "FILE")]
    pub png: Option<std::path::PathBuf>,
    /// Run even when the estimated steps, memory or time are over the limits (see README).
    #[arg(long)]
    pub force: bool,
}

/// Options of `springlab study stability`.
#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml).
    pub scene: String,
    /// Methods to study, comma separated (default: all), for example `rk4,verlet`.
    #[arg(long, value_name = "A,B")]
    pub methods: Option<String>,
    /// Horizon T in seconds: each linear probe takes max(T/dt, 4 000) steps, each
    /// confirmation run min(50 T/dt, 10 000).
    #[arg(long, value_name = "T", default_value_t = DEFAULT_HORIZON, allow_negative_numbers = true)]
    pub horizon: f64,
    /// Report the linear limit without the confirmation runs (faster).
    #[arg(long)]
    pub no_confirm: bool,
    /// Skip the usable dt (the largest dt whose energy error stays within 1 % of E0 over the
    /// scene's duration; several runs of the whole scene per method).
    #[arg(long)]
    pub no_usable: bool,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Run even when the estimated steps, memory or time are over the limits (see README).
    #[arg(long)]
    pub force: bool,
}

/// The budget estimate of a study (see [`crate::budget`]), without running it.
///
/// # Errors
/// As the study's checks of its inputs.
pub fn estimate(command: &StudyCommand, limits: &Limits) -> anyhow::Result<budget::Estimate> {
    Ok(match command {
        StudyCommand::Stability(args) => prepare_stability(args, limits)?.3,
        StudyCommand::Convergence(args) => prepare_convergence(args, false, limits)?.3,
        StudyCommand::WorkPrecision(args) => prepare_convergence(args, true, limits)?.3,
        StudyCommand::Resolution(args) => prepare_resolution(args, limits)?.3,
    })
}

/// `springlab study ...`.
///
/// # Errors
/// As the study's `run`.
pub fn run(command: &StudyCommand) -> anyhow::Result<()> {
    match command {
        StudyCommand::Stability(args) => run_stability(args),
        StudyCommand::Convergence(args) => run_convergence(args, false),
        StudyCommand::WorkPrecision(args) => run_convergence(args, true),
        StudyCommand::Resolution(args) => run_resolution(args),
    }
}
