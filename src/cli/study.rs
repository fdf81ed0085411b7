//! `springlab study`: stability limits (convergence and work-precision to come).

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

use clap::{Args, Subcommand};

use crate::physics::Method;
use crate::study::stability::{self, DEFAULT_HORIZON, StabilityOptions, StabilityReport};
use crate::study::{Probe, Stability};

/// The studies.
#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Largest stable time step of each method, by bisection on dt·ω_max.
    Stability(StabilityArgs),
}

/// Options of `springlab study stability`.
#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml).
    pub scene: String,
    /// Methods to study, comma separated (default: all), for example `rk4,verlet`.
    #[arg(long, value_name = "A,B")]
    pub methods: Option<String>,
    /// Horizon T in seconds: each probe runs max(T/dt, N_min) steps.
    #[arg(long, value_name = "T", default_value_t = DEFAULT_HORIZON, allow_negative_numbers = true)]
    pub horizon: f64,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// `springlab study ...`.
///
/// # Errors
/// As the study's `run`.
pub fn run(command: &StudyCommand) -> anyhow::Result<()> {
    match command {
        StudyCommand::Stability(args) => run_stability(args),
    }
}

/// Progress on standard error, only on a terminal and only once the study has taken a second.
struct Progress {
    enabled: bool,
    start: Instant,
    shown: bool,
}

impl Progress {
    fn new() -> Progress {
        Progress {
            enabled: std::io::stderr().is_terminal(),
            start: Instant::now(),
            shown: false,
        }
    }

    fn update(&mut self, method: Method, probe: &Probe) {
        if !self.enabled || self.start.elapsed() < Duration::from_secs(1) {
            return;
        }
        let verdict = if probe.stable { "stable" } else { "unstable" };
        // \r and "erase line": one line, rewritten.
        eprint!(
            "\r\x1b[2Kstudy stability: {method} dt = {:.4e} s (dt·ω = {:.4}) {verdict}",
            probe.dt, probe.dt_omega
        );
        self.shown = true;
    }

    fn finish(&self) {
        if self.shown {
            eprint!("\r\x1b[2K");
        }
    }
}

fn run_stability(args: &StabilityArgs) -> anyhow::Result<()> {
    let options = StabilityOptions {
        methods: match &args.methods {
            Some(text) => stability::parse_methods(text)?,
            None => Method::ALL.to_vec(),
        },
        horizon: args.horizon,
        criterion: None,
    };
    if !(options.horizon > 0.0 && options.horizon.is_finite()) {
        return Err(crate::study::StudyError::Horizon(options.horizon).into());
    }
    let (scene, sets) = stability::load_scene(&args.scene, &args.sets)?;
    let mut progress = Progress::new();
    let start = Instant::now();
    let result = stability::stability(&scene, &options, &mut |m, p| progress.update(m, p));
    progress.finish();
    let mut report = result?;
    report.sets = sets;
    let wall = start.elapsed().as_secs_f64();
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer(&mut out, &report).map_err(std::io::Error::from)?;
        writeln!(out)?;
    } else {
        print_table(&mut out, &report, wall)?;
    }
    Ok(())
}

/// The human-readable table.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print_table(
    out: &mut impl Write,
    r: &StabilityReport,
    wall_seconds: f64,
) -> std::io::Result<()> {
    writeln!(
        out,
        "study stability · scene {} · horizon {} s · criterion {}",
        r.scene,
        r.horizon,
        match r.criterion {
            stability::Criterion::Growth => "growth",
            stability::Criterion::Divergence => "divergence",
        }
    )?;
    if !r.sets.is_empty() {
        writeln!(out, "set: {}", r.sets.join(" "))?;
    }
    writeln!(
        out,
        "ω_max = {:.6} rad/s ({}, {} iterations; Gershgorin bound {:.6} rad/s)",
        r.omega_max, r.omega_method, r.omega_iterations, r.omega_gershgorin
    )?;
    writeln!(out, "stable means: {}", r.definition)?;
    writeln!(
        out,
        "search: dt·ω_max from {} to {}, bisection in log dt to {:e} relative\n",
        r.dt_omega_range[0],
        r.dt_omega_range[1],
        stability::BISECTION_TOLERANCE
    )?;
    writeln!(
        out,
        "{:<21} {:<14} {:>14} {:>11} {:>13} {:>7}",
        "method", "stability", "max stable dt", "dt·ω limit", "theory dt·ω", "probes"
    )?;
    for m in &r.methods {
        let dt = m
            .max_stable_dt
            .map_or_else(|| "—".to_string(), |dt| format!("{dt:.4e} s"));
        let limit = match (m.stability, m.limit_dt_omega) {
            (_, Some(z)) => format!("{z:.4}"),
            (Stability::Unconditional, None) => format!("> {}", r.dt_omega_range[1]),
            (_, None) => format!("< {}", r.dt_omega_range[0]),
        };
        let theory = match (m.theory, m.theory_dt_omega) {
            (_, Some(z)) => format!("{z:.4}"),
            (t, None) => t.name().to_string(),
        };
        writeln!(
            out,
            "{:<21} {:<14} {:>14} {:>11} {:>13} {:>7}",
            m.method.name(),
            m.stability.name(),
            dt,
            limit,
            theory,
            m.probes.len()
        )?;
    }
    writeln!(
        out,
        "\ntheory: the undamped harmonic oscillator (Verlet without damping or projection); \
         damping, gravity, contact, projection and large motions move the measured limit \
         ({:.2} s wall)",
        wall_seconds
    )
}
