//! `springlab study`: stability limits, convergence orders, work-precision, resolution.

use std::io::Write;
use std::time::Instant;

use anyhow::bail;
use clap::{Args, Subcommand};

use super::interrupt;
use super::progress::Progress;
use crate::budget::{self, Limits};
use crate::format::short;
use crate::output;
use crate::physics::Method;
use crate::scene;
use crate::study::Stability;
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::observe::{Difference, Unit};
use crate::study::resolution::{self, Kinds, LevelRun, ResolutionOptions, ResolutionReport};
use crate::study::stability::{self, DEFAULT_HORIZON, StabilityOptions, StabilityReport};
use crate::study::theory::TheoryLimit;

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
    /// with three coarser and two finer, spacing ratio about √2; ropes: doubling).
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

/// The refinement, options, planned runs and budget estimate of `study resolution` (nothing
/// runs yet; the level scenes are built within `limits`).
///
/// # Errors
/// A scene that cannot be refined, bad levels, method, time or tolerance.
pub fn prepare_resolution(
    args: &ResolutionArgs,
    limits: &Limits,
) -> anyhow::Result<(
    resolution::Refinement,
    ResolutionOptions,
    Vec<resolution::PlannedRun>,
    budget::Estimate,
    f64,
)> {
    let options = ResolutionOptions {
        levels: args.levels.clone(),
        method: args.method.trim().parse::<Method>()?,
        time: args.time,
        tolerance: args.tolerance,
        kinds: !args.no_kinds,
    };
    let (refinement, levels, time) = resolution::plan(&args.scene, &args.sets, &options)?;
    let planned = resolution::runs(&refinement, &levels, &options, time, limits)?;
    let mut list: Vec<(&scene::Scene, Method, f64)> = planned
        .iter()
        .map(|p| (&p.scene, options.method, p.steps as f64))
        .collect();
    // The time-step check: the scene's own level again at dt/2.
    if let Some(p) = planned
        .iter()
        .find(|p| p.n == refinement.base && p.kinds == resolution::Kinds::All)
    {
        list.push((&p.scene, options.method, 2.0 * p.steps as f64));
    }
    let estimate = budget::runs(format!("study resolution {}", args.scene), &list);
    Ok((refinement, options, planned, estimate, time))
}

fn run_resolution(args: &ResolutionArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    interrupt::install(interrupt::Mode::Exit);
    let (refinement, options, planned, estimate, time) = prepare_resolution(args, &limits)?;
    if let Some(path) = &args.png {
        output::check_file(path)?;
    }
    estimate.enforce(&limits)?;
    let total = planned.len() as u64 + 1;
    let mut progress = Progress::new(total, &format!("study resolution {}", args.scene));
    let key = refinement.dimension.key();
    let report = resolution::resolution(&refinement, &options, time, &planned, &mut |i, n, k| {
        progress.set(i as u64);
        let what = if i == planned.len() {
            "time-step check".to_string()
        } else {
            k.name().to_string()
        };
        progress.label(format!("study resolution: {key} = {n}, {what}"));
    });
    progress.finish();
    if let Some(path) = &args.png {
        crate::cli::study_chart::save_resolution(&report, path)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer(&mut out, &report).map_err(std::io::Error::from)?;
        writeln!(out)?;
    } else {
        print_resolution(&mut out, &report)?;
    }
    Ok(())
}

/// A difference for a table: `1.23e-3` (m), with ` / 4.0e-4 s` when the observable has a time.
#[must_use]
pub fn difference_text(d: Option<&Difference>, has_time: bool) -> String {
    match d {
        None => "—".to_string(),
        Some(d) if !d.metres.is_finite() => "diverged".to_string(),
        Some(d) if has_time => format!("{:.2e} / {:.1e} s", d.metres, d.seconds),
        Some(d) => format!("{:.2e}", d.metres),
    }
}

/// The text table of `study resolution`.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print_resolution(out: &mut impl Write, r: &ResolutionReport) -> std::io::Result<()> {
    writeln!(
        out,
        "study resolution · scene {} · {} · observable at t = {} s · tolerance X = {} ({})",
        r.scene,
        r.method,
        r.time,
        r.tolerance,
        crate::study::advise::TOLERANCE_UNIT
    )?;
    if !r.sets.is_empty() {
        writeln!(out, "set: {}", r.sets.join(" "))?;
    }
    writeln!(out, "refinement: {}", r.refinement)?;
    writeln!(out, "observable: {}", r.observable)?;
    writeln!(out, "time step: {}", r.time_step)?;
    writeln!(out, "stops changing: {}", r.definition)?;
    let has_time = r.components.iter().any(|c| c.1 == Unit::Second);
    let unit = if has_time { "m / s" } else { "m" };
    let heads: Vec<String> = r
        .runs
        .first()
        .and_then(|run| run.run.observation.as_ref())
        .map(|o| {
            o.components
                .iter()
                .map(|c| format!("{} ({})", c.headline_name(), c.unit.symbol()))
                .collect()
        })
        .unwrap_or_default();
    write!(
        out,
        "\n{:>5}  {:<8} {:>9} {:>8} {:>11} {:>7} {:>13} {:>8}",
        r.key, "kinds", "particles", "springs", "dt (s)", "steps", "springs·steps", "wall (s)"
    )?;
    for h in &heads {
        write!(out, " {h:>20}")?;
    }
    writeln!(
        out,
        "  {:>14} {:>14} {:>14}",
        format!("Δ next ({unit})"),
        format!("Δ finest ({unit})"),
        format!("Δ all kinds ({unit})")
    )?;
    for run in &r.runs {
        write!(
            out,
            "{:>5}  {:<8} {:>9} {:>8} {:>11.4e} {:>7} {:>13.3e} {:>8.2}",
            run.n,
            run.kinds.name(),
            run.particles,
            run.springs,
            run.run.dt,
            run.run.steps,
            run.springs_steps,
            run.run.wall_seconds
        )?;
        match &run.run.observation {
            Some(o) => {
                for c in &o.components {
                    write!(out, " {:>20.6}", c.headline())?;
                }
            }
            None => {
                for _ in &heads {
                    write!(out, " {:>20}", "diverged")?;
                }
            }
        }
        writeln!(
            out,
            "  {:>14} {:>14} {:>14}",
            difference_text(run.change_next.as_ref(), has_time),
            difference_text(run.change_finest.as_ref(), has_time),
            difference_text(run.change_kinds.as_ref(), has_time)
        )?;
    }
    writeln!(out)?;
    let all: Vec<&LevelRun> = r.runs.iter().filter(|x| x.kinds == Kinds::All).collect();
    let finest = all.last().map_or(0, |x| x.n);
    match r.converged_from {
        Some(n) => writeln!(
            out,
            "stops changing from {} = {n}: every refinement from there changes the answer by at \
             most {} (Δ next ≤ X up to the finest level, {} = {finest})",
            r.key, r.tolerance, r.key
        )?,
        None => {
            let last = all.iter().rev().find_map(|x| {
                x.change_next
                    .as_ref()
                    .map(|d| (x.n, difference_text(Some(d), has_time)))
            });
            match last {
                Some((n, d)) => writeln!(
                    out,
                    "still changing: {} = {n} → {finest} changes the answer by {d} {unit} > X = {}; \
                     refine further (--n) or accept a larger tolerance",
                    r.key, r.tolerance
                )?,
                None => writeln!(out, "one level only: nothing to compare")?,
            }
        }
    }
    if let Some(own) = all.iter().find(|x| x.n == r.base)
        && own.n != finest
        && let Some(d) = &own.change_finest
    {
        let verdict = if d.within(r.tolerance) {
            "within X"
        } else {
            "more than X"
        };
        writeln!(
            out,
            "the scene's own {} = {} is {} {unit} from the finest level ({verdict})",
            r.key,
            r.base,
            difference_text(Some(d), has_time)
        )?;
    }
    for kinds in [Kinds::NoBend, Kinds::NoShear] {
        let rows: Vec<&LevelRun> = r.runs.iter().filter(|x| x.kinds == kinds).collect();
        if rows.is_empty() {
            continue;
        }
        let needed: Vec<String> = rows
            .iter()
            .filter(|x| {
                x.change_kinds
                    .as_ref()
                    .is_none_or(|d| !d.within(r.tolerance))
            })
            .map(|x| x.n.to_string())
            .collect();
        let spring = if kinds == Kinds::NoBend {
            "bend"
        } else {
            "shear"
        };
        if needed.is_empty() {
            writeln!(
                out,
                "{spring} springs: leaving them out changes the answer by at most X at every \
                 level: not needed at this tolerance"
            )?;
        } else {
            writeln!(
                out,
                "{spring} springs: leaving them out changes the answer by more than X at {} = {}: \
                 needed",
                r.key,
                needed.join(", ")
            )?;
        }
    }
    if let Some(d) = &r.time_step_check {
        writeln!(
            out,
            "time step: halving dt at {} = {} changes the answer by {} {unit} (the time step's \
             own share of the differences above)",
            r.key,
            r.base,
            difference_text(Some(d), has_time)
        )?;
    }
    Ok(())
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
        confirm: !args.no_confirm,
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
        omega_bound(&scene),
        stability::STIFFEST_SAMPLE_INTERVAL,
    );
    Ok((scene, options, sets, estimate))
}

/// An upper bound on the fastest angular frequency of `scene` (rad/s), by Gershgorin's theorem:
/// `ω² ≤` the largest [`spring_gershgorin`](crate::study::modes::spring_gershgorin) of its bodies.
fn omega_bound(scene: &scene::Scene) -> f64 {
    scene
        .bodies
        .iter()
        .map(|b| crate::study::modes::spring_gershgorin(&b.model))
        .fold(0.0, f64::max)
        .sqrt()
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
        "study stability · scene {} · horizon {} s · criterion: {}",
        r.scene, r.horizon, r.criterion
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
    writeln!(out, "damped theory: {}", r.theory_spectrum)?;
    writeln!(
        out,
        "search: dt·ω_max from {} to {}, bisection in log dt to {:e} relative\n",
        r.dt_omega_range[0],
        r.dt_omega_range[1],
        stability::BISECTION_TOLERANCE
    )?;
    let st = &r.stiffest_state;
    writeln!(
        out,
        "stiffest state: ω_max = {:.6} rad/s ({:+.2} % against the start) at t = {:.4} s of a run \
         of the scene ({}, dt = {:e} s, {} samples{}); damped theory there: {}\n",
        st.omega_max,
        100.0 * (st.ratio - 1.0),
        st.time,
        st.method.name(),
        st.dt,
        st.samples,
        st.stopped
            .as_deref()
            .map_or_else(String::new, |why| format!(", stopped early: {why}")),
        st.theory_spectrum
    )?;
    writeln!(
        out,
        "{:<21} {:<14} {:>13} {:>11} {:>13} {:>11} {:>9} │ {:>13} {:>9} {:>9} {:>15}  \
         binding mode (theory)",
        "method",
        "stability",
        "linear dt",
        "linear dt·ω",
        "theory dt",
        "theory dt·ω",
        "vs theory",
        "scene dt",
        "dt·ω",
        "vs theory",
        "theory stiffest"
    )?;
    let limit = |class: Stability, z: Option<f64>| match (class, z) {
        (_, Some(z)) => format!("{z:.4}"),
        (Stability::Unconditional, None) => format!("> {}", r.dt_omega_range[1]),
        (_, None) => "none".to_string(),
    };
    let seconds = |class: Stability, dt: Option<f64>| match (class, dt) {
        (_, Some(dt)) => format!("{dt:.4e} s"),
        (Stability::Unconditional, None) => "any".to_string(),
        (_, None) => "none".to_string(),
    };
    let versus = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => format!("{:+.2} %", 100.0 * (a / b - 1.0)),
        _ => "—".to_string(),
    };
    let theory_seconds = |t: &TheoryLimit| match t.dt {
        Some(dt) => format!("{dt:.4e} s"),
        None => t.stability.to_string(),
    };
    for m in &r.methods {
        let t = &m.damped_theory;
        let theory_z = t
            .dt_omega
            .map_or_else(|| "—".to_string(), |z| format!("{z:.4}"));
        let binding = t.binding.map_or_else(String::new, |b| {
            let which = if b.stiffest { "ω_max" } else { "ω" };
            let kind = if b.lambda_im == 0.0 {
                format!("decay λ = {:.4e} 1/s", b.lambda_re)
            } else {
                format!("λ = {:.3e} ± {:.3e} i 1/s", b.lambda_re, b.lambda_im)
            };
            format!(
                "{which} = {:.4} rad/s, μ = {:.4e} 1/s, {kind}",
                b.omega, b.mu
            )
        });
        writeln!(
            out,
            "{:<21} {:<14} {:>13} {:>11} {:>13} {:>11} {:>9} │ {:>13} {:>9} {:>9} {:>15}  {binding}",
            m.method.name(),
            m.stability.name(),
            seconds(m.linear_stability, m.linear_max_dt),
            limit(m.linear_stability, m.linear_dt_omega),
            theory_seconds(t),
            theory_z,
            versus(m.linear_max_dt, t.dt),
            seconds(m.stability, m.max_stable_dt),
            limit(m.stability, m.limit_dt_omega),
            versus(m.max_stable_dt, t.dt),
            theory_seconds(&m.stiffest_theory),
        )?;
        for c in m.confirmations.iter().filter(|c| !c.passed) {
            writeln!(
                out,
                "    confirmation at dt·ω = {:.4} failed after {} steps: {}",
                c.dt_omega,
                c.steps,
                c.reason.as_deref().unwrap_or("")
            )?;
        }
    }
    writeln!(
        out,
        "\nlinear dt: the largest dt at which a perturbation of the scene at rest does not grow \
         (measured; the damped theory predicts it, vs theory compares the two). scene dt: the \
         largest dt at which the whole scene, contacts and impacts included, runs without \
         breaking (the linear limit confirmed by runs, lowered and bisected when one fails): \
         the dt to use; stability is its class. theory stiffest: the damped theory linearised \
         at the stiffest state above: an impact squeezes a body and stiffens its stiffest \
         mode, so on scenes with impacts the scene dt lies between the two theories; below \
         both, motion pumps a stiff mode (a nonlinear resonance) ({:.2} s wall)",
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
    if options.repeats == 0 {
        bail!("--repeats 0: expected at least 1 timed repeat per point");
    }
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
    // The scene as budgeted above; the study loads it again with the Verlet companion's sets.
    let _ = (scene, sets);
    let result = convergence::convergence_with_companion(
        &args.scene,
        &args.sets,
        &options,
        &limits,
        &mut |m, level| {
            progress.label(format!(
                "study {name}: {m} dt level {} of {}",
                level + 1,
                options.levels
            ));
            progress.inc(1);
        },
    );
    progress.finish();
    let report = result?;
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
        if let Some(own) = &m.reference {
            writeln!(out, "    reference: {own}")?;
        }
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
    if let Some(c) = &r.verlet_companion {
        let order = |m: &crate::study::convergence::MethodConvergence| {
            m.order
                .map_or_else(|| "—".to_string(), |p| format!("{p:.3}"))
        };
        let plain = r.methods.iter().find(|m| m.method == Method::Verlet);
        let (with, without) = if c.damped {
            (
                order(&c.verlet),
                plain.map_or_else(|| "—".to_string(), order),
            )
        } else {
            (
                plain.map_or_else(|| "—".to_string(), order),
                order(&c.verlet),
            )
        };
        writeln!(
            out,
            "\nverlet with dampers: order {with}; without: order {without} (the row with {}, \
             reference {})",
            c.sets.join(" "),
            c.reference
        )?;
        writeln!(
            out,
            "    dampers and drag see Verlet's velocity (x_n - x_(n-1))/dt, half a step late: an \
             O(dt) error in the force, so first order; verlet_damping_rate is applied centred \
             and keeps it second order"
        )?;
    }
    if work_precision {
        writeln!(
            out,
            "\nCheapest method for an accuracy: the one with the fewest force evaluations at or below that error."
        )?;
    }
    Ok(())
}
