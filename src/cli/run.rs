//! `springlab run`: a headless run with a summary, JSON or CSV.

use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;

use super::interrupt;
use super::progress::Progress;
use crate::budget::{self, Estimate, Limits, short};
use crate::output::{self, AtomicFile};
use crate::physics::Method;
use crate::scene::{self, Scene};
use crate::simulation::{RunReport, Simulation};

/// Most steps between two checks of Ctrl-C and two progress updates, in fused chunks
/// ([`Simulation::chunk_steps`]): four.
const PIECE_CHUNKS: u64 = 4;

/// Options of `springlab run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml).
    pub scene: String,
    /// Integration method, or one per body separated by commas (for `ropes`).
    #[arg(long, short)]
    pub method: Option<String>,
    /// Time step in seconds (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    pub dt: Option<f64>,
    /// Number of steps.
    #[arg(long, conflicts_with = "time", allow_negative_numbers = true,
          value_parser = parse_steps)]
    pub steps: Option<u64>,
    /// Simulated time in seconds (rounded to whole steps).
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write a time series of energies and positions to this CSV file (`-`: standard output,
    /// the summary then goes to standard error).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write a CSV row every this many steps.
    #[arg(long, value_name = "K", default_value_t = 1)]
    pub csv_every: u64,
    /// Run even when the estimated steps, memory or time are over the limits (see README).
    #[arg(long)]
    pub force: bool,
    /// Leave out the energy accounting (what dampers, drag and contacts take out, and the
    /// method's energy error `E + D - E0`): faster steps, the same motion bit for bit. The
    /// summary and the CSV then show the energy without it.
    #[arg(long)]
    pub no_accounting: bool,
}

/// Parses `--steps`: a whole number >= 0, with a message that says so (`--steps -5` included).
///
/// # Errors
/// Anything else, as text for clap.
pub fn parse_steps(text: &str) -> Result<u64, String> {
    text.trim()
        .parse::<u64>()
        .map_err(|_| "expected a whole number of steps >= 0, for example 1000".to_string())
}

/// Applies `--method` to the scene: one name for all bodies, or one per body.
///
/// # Errors
/// An unknown name, or a list whose length is not the number of bodies.
pub fn apply_methods(scene: &mut Scene, text: &str) -> anyhow::Result<()> {
    let names: Vec<&str> = text.split(',').map(str::trim).collect();
    let methods = names
        .iter()
        .map(|n| n.parse::<Method>())
        .collect::<Result<Vec<_>, _>>()?;
    match methods.as_slice() {
        [one] => scene.set_method(*one),
        many if many.len() == scene.bodies.len() => {
            for (body, m) in scene.bodies.iter_mut().zip(many) {
                body.method = *m;
            }
        }
        many => bail!(
            "--method lists {} methods but scene `{}` has {} bodies; give one method or one per body",
            many.len(),
            scene.name,
            scene.bodies.len()
        ),
    }
    Ok(())
}

/// Number of steps for `--steps` or `--time` (default: the scene's duration), as a real number
/// so that `--time 1 --dt 1e-300` can be refused by the budget rather than saturate.
///
/// # Errors
/// A duration that is not positive and finite, or shorter than one time step.
pub fn step_count(
    steps: Option<u64>,
    time: Option<f64>,
    default_time: f64,
    dt: f64,
) -> anyhow::Result<f64> {
    if let Some(n) = steps {
        return Ok(n as f64);
    }
    let t = time.unwrap_or(default_time);
    if !(t.is_finite() && t >= 0.0) {
        bail!("--time {}: expected a duration in seconds >= 0", short(t));
    }
    check_dt_within(
        dt,
        t,
        if time.is_some() {
            "--time"
        } else {
            "the scene's duration"
        },
    )?;
    Ok((t / dt).round())
}

/// Refuses a time step longer than a run of `time` seconds (which would take no step, or one
/// step past the end): `dt` must be at most `time` when `time > 0`.
///
/// # Errors
/// `dt > time > 0`.
pub fn check_dt_within(dt: f64, time: f64, what: &str) -> anyhow::Result<()> {
    if time > 0.0 && dt > time {
        bail!(
            "--dt {} s is longer than the run ({what} {} s): expected a time step at most the \
             simulated time",
            short(dt),
            short(time)
        );
    }
    Ok(())
}

/// Validates a time step given on the command line.
///
/// # Errors
/// `dt <= 0`, NaN or infinite.
pub fn check_dt(dt: f64) -> anyhow::Result<f64> {
    if dt > 0.0 && dt.is_finite() {
        Ok(dt)
    } else {
        bail!("--dt {}: expected a time step in seconds > 0", short(dt))
    }
}

/// The scene, time step (s) and step count of `springlab run`, and its budget estimate (not yet
/// checked): everything decided from the inputs before anything runs.
///
/// # Errors
/// Bad scene, parameters or options (the scene file's size and memory within `limits`).
pub fn prepare(args: &RunArgs, limits: &Limits) -> anyhow::Result<(Scene, f64, f64, Estimate)> {
    let mut scene = scene::load_with(&args.scene, &args.sets, limits)?;
    if let Some(m) = &args.method {
        apply_methods(&mut scene, m)?;
    }
    let dt = check_dt(args.dt.unwrap_or(scene.dt))?;
    let steps = step_count(args.steps, args.time, scene.duration, dt)?;
    if args.csv_every == 0 {
        bail!("--csv-every 0: expected a number of steps >= 1");
    }
    let estimate = budget::run(format!("run {}", args.scene), &scene, dt, steps);
    Ok((scene, dt, steps, estimate))
}

/// `springlab run`.
///
/// # Errors
/// Bad scene, parameters or options; an unwritable CSV file.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    let (scene, dt, steps, estimate) = prepare(args, &limits)?;
    // `--csv -` (or `/dev/stdout`) puts the CSV on standard output; the summary then goes to
    // standard error, and `--json` has no place left.
    let csv_on_stdout = args.csv.as_deref().is_some_and(output::is_stdout);
    if let Some(path) = &args.csv {
        output::check_file(path)?;
        if csv_on_stdout && args.json {
            bail!(
                "--csv {} and --json both write to standard output; write the CSV to a file",
                path.display()
            );
        }
    }
    estimate.enforce(&limits)?;
    // Within the budget, the step count fits in u64.
    let steps = steps as u64;
    interrupt::install(interrupt::Mode::Flag);
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    if args.no_accounting {
        sim.set_accounting(false);
    }

    let mut csv = match &args.csv {
        Some(path) => {
            let file = AtomicFile::create(path)
                .with_context(|| format!("cannot write CSV file {}", path.display()))?;
            let mut w = BufWriter::new(file);
            write_csv_header(&mut w, &sim)?;
            write_csv_row(&mut w, &sim)?;
            Some((w, path))
        }
        None => None,
    };
    let start = Instant::now();
    let mut progress = Progress::new(steps, &format!("run {}", args.scene));
    let mut csv_error = None;
    // The steps go to `Simulation::advance` (the fused multi-step passes where the scene
    // allows them, the same numbers as single steps) in pieces of at most `PIECE_CHUNKS` chunks,
    // ending at every CSV row.
    let mut done = 0;
    while done < steps && sim.diverged.is_none() {
        // Ctrl-C: stop between pieces; the CSV's temporary file is removed when dropped.
        interrupt::check()?;
        progress.set(done);
        let mut piece = (steps - done).min(PIECE_CHUNKS * sim.chunk_steps());
        if csv.is_some() {
            piece = piece.min(args.csv_every - sim.steps % args.csv_every);
        }
        let before = sim.steps;
        sim.advance(piece);
        done += piece;
        if let Some((w, _)) = csv.as_mut()
            && csv_error.is_none()
            && sim.steps > before
            && (sim.steps.is_multiple_of(args.csv_every) || sim.diverged.is_some())
            && let Err(e) = write_csv_row(w, &sim)
        {
            csv_error = Some(e);
        }
    }
    progress.finish();
    let wall = start.elapsed().as_secs_f64();
    if let Some((w, path)) = csv {
        if let Some(e) = csv_error {
            return Err(e).with_context(|| format!("cannot write CSV file {}", path.display()));
        }
        w.into_inner()
            .map_err(std::io::IntoInnerError::into_error)
            .and_then(AtomicFile::commit)
            .with_context(|| format!("cannot write CSV file {}", path.display()))?;
    }
    let report = sim.report(wall);
    if args.json {
        let mut out = std::io::stdout().lock();
        serde_json::to_writer(&mut out, &report).map_err(std::io::Error::from)?;
        writeln!(out)?;
    } else if csv_on_stdout {
        print_summary(&mut std::io::stderr().lock(), &report)?;
    } else {
        print_summary(&mut std::io::stdout().lock(), &report)?;
    }
    Ok(())
}

fn write_csv_header(w: &mut impl Write, sim: &Simulation) -> std::io::Result<()> {
    write!(
        w,
        "step,time,kinetic,gravity,elastic,total,dissipated,residual"
    )?;
    for i in 0..sim.scene.particle_count() {
        write!(w, ",x{i},y{i},z{i}")?;
    }
    writeln!(w)
}

fn write_csv_row(w: &mut impl Write, sim: &Simulation) -> std::io::Result<()> {
    let e = sim.energy();
    write!(
        w,
        "{},{},{},{},{},{},",
        sim.steps,
        sim.time(),
        e.kinetic,
        e.gravity,
        e.elastic,
        e.total,
    )?;
    // Without the accounting (`--no-accounting`) nothing is known of either: empty fields.
    if sim.accounting() {
        write!(w, "{},{}", sim.dissipated().total, sim.energy_residual())?;
    } else {
        write!(w, ",")?;
    }
    for p in sim.positions() {
        write!(w, ",{},{},{}", p.x, p.y, p.z)?;
    }
    writeln!(w)
}

/// The human-readable summary.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print_summary(out: &mut impl Write, r: &RunReport) -> std::io::Result<()> {
    writeln!(
        out,
        "scene {} · method {} · dt {} s · {} steps · t = {} s",
        r.scene, r.method, r.dt, r.steps, r.time
    )?;
    let rate = if r.wall_seconds > 0.0 {
        r.steps as f64 / r.wall_seconds
    } else {
        f64::INFINITY
    };
    writeln!(
        out,
        "{} particles · {} springs · {} force evaluations · {:.3} ms wall ({:.3e} steps/s)",
        r.particles,
        r.springs,
        r.force_evals,
        r.wall_seconds * 1e3,
        rate
    )?;
    let e = &r.energy;
    writeln!(
        out,
        "energy: kinetic {:.6e} J · gravity {:.6e} J · elastic {:.6e} J · total {:.6e} J",
        e.kinetic, e.gravity, e.elastic, e.total
    )?;
    if r.dissipated.is_none() {
        writeln!(out, "energy accounting: off (--no-accounting)")?;
    }
    if let (Some(d), Some(residual)) = (&r.dissipated, r.residual) {
        writeln!(
            out,
            "energy accounting: start {:.6e} J · dissipated {:.6e} J (dampers and drag {:.3e}, \
             contact forces {:.3e}, contacts {:.3e}, method {:.3e}) · residual {:.3e} J",
            r.energy_initial,
            d.total,
            d.dampers_and_drag,
            d.contact_forces,
            d.contacts,
            d.method,
            residual
        )?;
    }
    if let Some(s) = &r.solver {
        writeln!(
            out,
            "implicit solves: {} · CG iterations max {} mean {:.1} · relative residual max {:.2e} \
             mean {:.2e} · contact passes max {} · steps halved by the energy guard {}",
            s.solves,
            s.iterations_max,
            s.iterations_mean,
            s.residual_max,
            s.residual_mean,
            s.contact_passes_max,
            s.halved_steps
        )?;
    }
    match &r.diverged {
        None if r.not_accurate.is_some() => {
            let x = r.not_accurate.unwrap_or(0.0);
            let verb = if x > 0.0 { "created" } else { "removed" };
            writeln!(
                out,
                "bounded but not accurate: the method {verb} {:.3e} J (more than the {:.3e} J \
                 the scene started with)",
                x.abs(),
                r.energy_initial
            )
        }
        None => writeln!(out, "stable: no divergence"),
        Some(d) => writeln!(
            out,
            "DIVERGED at step {} (t = {} s): {}; max speed {:.4e} m/s",
            d.step, d.time, d.reason, d.max_speed
        ),
    }
}
