//! `springlab study`: stability limits (convergence and work-precision to come).

use std::io::Write;
use std::time::Instant;

use anyhow::bail;
use clap::{Args, Subcommand};

use crate::budget::{self, Limits, Progress, interrupt, short};
use crate::output;
use crate::physics::Method;
use crate::scene;
use crate::study::Stability;
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::stability::{self, DEFAULT_HORIZON, StabilityOptions, StabilityReport};

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
    /// Horizon T in seconds: each probe runs max(T/dt, N_min) steps.
    #[arg(long, value_name = "T", default_value_t = DEFAULT_HORIZON, allow_negative_numbers = true)]
    pub horizon: f64,
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
    }
}

/// The scene, options and `--set` list of `study stability`, and its budget estimate (not yet
/// checked).
///
/// # Errors
/// Bad methods, horizon or scene.
pub fn prepare_stability(
    args: &StabilityArgs,
    limits: &Limits,
) -> anyhow::Result<(
    scene::Scene,
    StabilityOptions,
    Vec<String>,
    budget::Estimate,
)> {
    let options = StabilityOptions {
        methods: match &args.methods {
            Some(text) => stability::parse_methods(text)?,
            None => Method::ALL.to_vec(),
        },
        horizon: args.horizon,
        criterion: None,
    };
    if !(options.horizon > 0.0 && options.horizon.is_finite()) {
        bail!(
            "--horizon {}: expected a duration in seconds > 0",
            short(options.horizon)
        );
    }
    let sets = stability::scene_sets(&args.scene, &args.sets);
    let scene = scene::load_with(&args.scene, &sets, limits)?;
    let estimate = budget::stability(
        format!("study stability {}", args.scene),
        &scene,
        &options.methods,
        options.horizon,
        budget::STABILITY_MIN_STEPS,
    );
    Ok((scene, options, sets, estimate))
}

fn run_stability(args: &StabilityArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    interrupt::install(interrupt::Mode::Exit);
    let (scene, options, sets, estimate) = prepare_stability(args, &limits)?;
    estimate.enforce(&limits)?;
    let mut progress = Progress::new(
        options.methods.len() as u64,
        &format!("study stability {}", args.scene),
    );
    let mut current = None;
    let start = Instant::now();
    let result = stability::stability(&scene, &options, &mut |m, p| {
        if current.is_some_and(|c| c != m) {
            progress.inc(1);
        }
        current = Some(m);
        let verdict = if p.stable { "stable" } else { "unstable" };
        progress.label(format!(
            "study stability: {m} dt = {:.4e} s (dt·ω = {:.4}) {verdict}",
            p.dt, p.dt_omega
        ));
    });
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

/// The scene, options and `--set` list of `study convergence` (or `work-precision`), and its
/// budget estimate (not yet checked).
///
/// # Errors
/// Bad methods, time, time step or scene.
pub fn prepare_convergence(
    args: &ConvergenceArgs,
    work_precision: bool,
    limits: &Limits,
) -> anyhow::Result<(
    scene::Scene,
    ConvergenceOptions,
    Vec<String>,
    budget::Estimate,
)> {
    let options = ConvergenceOptions {
        methods: match &args.methods {
            Some(text) => stability::parse_methods(text)?,
            None => Method::ALL.to_vec(),
        },
        time: args.time,
        dt: args.dt,
        levels: args.levels.unwrap_or(if work_precision { 6 } else { 4 }),
        repeats: args.repeats.unwrap_or(if work_precision { 3 } else { 1 }),
    };
    let name = if work_precision {
        "work-precision"
    } else {
        "convergence"
    };
    let mut sets: Vec<String> = convergence::SAME_EQUATIONS
        .iter()
        .map(|s| (*s).to_string())
        .collect();
    sets.extend(args.sets.iter().cloned());
    let scene = scene::load_with(&args.scene, &sets, limits)?;
    let time = options.time.unwrap_or(1.0);
    if !(time > 0.0 && time.is_finite()) {
        bail!("--time {}: expected a duration in seconds > 0", short(time));
    }
    // The study's largest dt: --dt, else 0.005 s for the oscillator, else the scene's.
    let dt = options.dt.unwrap_or(if scene.name == "oscillator" {
        0.005
    } else {
        scene.dt
    });
    if !(dt > 0.0 && dt.is_finite()) {
        bail!("--dt {}: expected a time step in seconds > 0", short(dt));
    }
    if dt > time {
        bail!(
            "--dt {} s is longer than the time the error is measured at (--time {} s): expected \
             a time step at most the simulated time",
            short(dt),
            short(time)
        );
    }
    let estimate = budget::convergence(
        format!("study {name} {}", args.scene),
        &scene,
        &options.methods,
        time,
        dt,
        options.levels,
        options.repeats,
    );
    Ok((scene, options, sets, estimate))
}

fn run_convergence(args: &ConvergenceArgs, work_precision: bool) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    interrupt::install(interrupt::Mode::Exit);
    let (scene, options, sets, estimate) = prepare_convergence(args, work_precision, &limits)?;
    let name = if work_precision {
        "work-precision"
    } else {
        "convergence"
    };
    if let Some(path) = &args.png {
        output::check_file(path)?;
    }
    estimate.enforce(&limits)?;
    let mut progress = Progress::new(
        options.methods.len() as u64 * u64::from(options.levels),
        &format!("study {name} {}", args.scene),
    );
    let result = convergence::convergence(&scene, &options, &mut |m, level| {
        progress.label(format!(
            "study {name}: {m} dt level {} of {}",
            level + 1,
            options.levels
        ));
        progress.inc(1);
    });
    progress.finish();
    let mut report = result?;
    report.sets = sets;
    if let Some(path) = &args.png {
        crate::cli::study_chart::save(&report, work_precision, path)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer(&mut out, &report).map_err(std::io::Error::from)?;
        writeln!(out)?;
    } else {
        print_convergence(&mut out, &report, work_precision)?;
    }
    Ok(())
}

/// The text table of a convergence or work-precision study.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print_convergence(
    out: &mut impl Write,
    r: &ConvergenceReport,
    work_precision: bool,
) -> std::io::Result<()> {
    let name = if work_precision {
        "work-precision"
    } else {
        "convergence"
    };
    writeln!(
        out,
        "study {name} · scene {} · error = max |x - x_ref| at t = {} s",
        r.scene, r.time
    )?;
    writeln!(out, "set: {}", r.sets.join(" "))?;
    let estimate = if r.reference_error > 0.0 {
        format!(" (its own error ≈ {:.2e} m)", r.reference_error)
    } else {
        String::new()
    };
    writeln!(out, "reference: {}{estimate}\n", r.reference)?;
    for m in &r.methods {
        let order = m
            .order
            .map_or_else(|| "—".to_string(), |p| format!("{p:.3}"));
        writeln!(out, "{:<21} order {order}", m.method.name())?;
        writeln!(
            out,
            "    {:>12} {:>12} {:>12} {:>12}",
            "dt (s)", "error (m)", "force evals", "wall (s)"
        )?;
        for p in &m.points {
            let error = p
                .error
                .map_or_else(|| "diverged".to_string(), |e| format!("{e:.4e}"));
            let mark = if p.fitted { "" } else { "  (not fitted)" };
            writeln!(
                out,
                "    {:>12.4e} {error:>12} {:>12} {:>12.3e}{mark}",
                p.dt, p.force_evals, p.wall_seconds
            )?;
        }
    }
    if work_precision {
        writeln!(
            out,
            "\nCheapest method for an accuracy: the one with the fewest force evaluations at or below that error."
        )?;
    }
    Ok(())
}
