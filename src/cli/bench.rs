//! `springlab bench`: the peer-benchmark workloads (`docs/workloads.md`), timed, with checksums.

use std::io::Write;

use anyhow::bail;
use clap::Args;
use serde::Serialize;

use crate::bench::{self, BenchResult, Workload};
use crate::budget;
use crate::physics::Method;
use crate::physics::pool::Pool;
use crate::physics::stencil::{Kernel, ceiling};

/// Options of `springlab bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Workloads to run (default: all): jelly-se, jelly-rk4, cloth64-se, cloth128-se, rope-se,
    /// rope-verlet.
    pub workloads: Vec<String>,
    /// Print the results as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Timed runs of N steps per workload; the median is reported.
    #[arg(long, value_name = "R", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Also time every other method on each workload (wall-time budget per run, in seconds;
    /// 0 times only the workloads' own methods).
    #[arg(long, value_name = "S", default_value_t = 0.2)]
    pub budget: f64,
    /// Run even when the estimated time is over the limit (see README).
    #[arg(long)]
    pub force: bool,
}

/// The estimate of a bench run: every workload `repeats` times, and the other methods for up to
/// `budget` seconds each run (counted at [`budget::RATE`]).
pub fn estimate(workloads: &[Workload], repeats: u32, seconds: f64) -> budget::Estimate {
    let mut e = budget::Estimate::new("bench");
    for &w in workloads {
        let (model, _) = bench::setup(w);
        let size = model.particle_count() as f64 + model.springs().len() as f64 + budget::OVERHEAD;
        let steps = w.steps() as f64;
        e.steps = e.steps.max(steps);
        e.steps_detail = format!("{} steps of the workload {w}", budget::approx(e.steps));
        e.particles = e.particles.max(model.particle_count() as f64);
        e.springs = e.springs.max(model.springs().len() as f64);
        let others = bench::methods_for(w).len().saturating_sub(1) as f64;
        e.work += f64::from(repeats)
            * (steps * budget::evaluations_per_step(w.method(), &w.params()) * size
                + others * seconds * budget::RATE);
        e.runs += f64::from(repeats) * (1.0 + if seconds > 0.0 { others } else { 0.0 });
    }
    e.memory =
        budget::BASE_BYTES + 2.0 * budget::body_bytes(e.particles, e.springs, &Method::ALL, 1.0);
    e
}

/// The JSON document of `springlab bench --json`, fields in declaration order.
#[derive(Serialize)]
struct Report<'a> {
    workloads: &'a [BenchResult],
    ceiling: &'a Ceiling,
}

/// The machine's ceiling for the springs (`physics::stencil::ceiling`): what the fastest spring
/// kernel this CPU has evaluates on data in the first-level cache, on every thread of the pool.
#[derive(Debug, Serialize)]
pub struct Ceiling {
    /// The kernel (`Portable`, `Avx2` or `Avx512`).
    pub kernel: String,
    /// Spring evaluations per second on one thread (1/s).
    pub per_thread: f64,
    /// Threads of the worker pool (`SPRINGLAB_THREADS` sets it).
    pub threads: usize,
    /// `per_thread · threads` (1/s).
    pub springs_per_second: f64,
}

impl Ceiling {
    /// Measures it (about 15 ms).
    #[must_use]
    pub fn measure() -> Ceiling {
        let kernel = Kernel::best();
        let per_thread = ceiling::ceiling(kernel);
        let threads = Pool::global().threads();
        Ceiling {
            kernel: format!("{kernel:?}"),
            per_thread,
            threads,
            springs_per_second: per_thread * threads as f64,
        }
    }

    /// The fraction of the ceiling that `r`'s spring evaluations per second reach.
    #[must_use]
    pub fn fraction(&self, r: &BenchResult) -> f64 {
        r.spring_steps_per_second * r.force_evals_per_step as f64 / self.springs_per_second
    }
}

/// The workloads named on the command line, or all of them.
///
/// # Errors
/// An unknown name (the message lists the known ones).
pub fn selected(names: &[String]) -> anyhow::Result<Vec<Workload>> {
    if names.is_empty() {
        return Ok(Workload::ALL.to_vec());
    }
    Ok(names
        .iter()
        .map(|n| n.parse::<Workload>())
        .collect::<Result<Vec<_>, _>>()?)
}

/// `springlab bench`.
///
/// # Errors
/// An unknown workload; unwritable standard output; a checksum that disagrees with the
/// reference (after the results are printed).
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let workloads = selected(&args.workloads)?;
    if !(args.budget >= 0.0 && args.budget.is_finite()) {
        bail!(
            "--budget {}: expected a wall time in seconds >= 0",
            budget::short(args.budget)
        );
    }
    estimate(&workloads, args.repeats, args.budget).enforce(&budget::Limits::forced(args.force))?;
    super::interrupt::install(super::interrupt::Mode::Exit);
    let runs: usize = workloads
        .iter()
        .map(|&w| {
            1 + if args.budget > 0.0 {
                bench::methods_for(w).len().saturating_sub(1)
            } else {
                0
            }
        })
        .sum();
    let mut progress = super::progress::Progress::new(runs as u64, "bench");
    let mut results = Vec::with_capacity(workloads.len());
    for w in workloads {
        progress.label(format!(
            "bench {w}: {} runs of {} steps of {} s",
            args.repeats,
            w.steps(),
            w.dt()
        ));
        let result = bench::measure(w, args.repeats, |_| {});
        results.push(result);
        progress.inc(1);
        if args.budget > 0.0 {
            for m in bench::methods_for(w)
                .into_iter()
                .filter(|&m| m != w.method())
            {
                progress.label(format!(
                    "bench {w}: {m} for up to {} s per run",
                    args.budget
                ));
                results.push(bench::measure_method(w, m, args.repeats, args.budget));
                progress.inc(1);
            }
        }
    }
    progress.finish();
    let ceiling = Ceiling::measure();
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer(
            &mut out,
            &Report {
                workloads: &results,
                ceiling: &ceiling,
            },
        )?;
        writeln!(out)?;
    } else {
        print_table(&mut out, &results, &ceiling)?;
    }
    out.flush()?;
    let bad: Vec<&str> = results
        .iter()
        .filter(|r| r.reference_method && !r.checksum_ok)
        .map(|r| r.workload.name())
        .collect();
    if !bad.is_empty() {
        bail!(
            "checksum disagrees with the reference (relative tolerance {:e}) for: {}",
            bench::REL_TOL,
            bad.join(", ")
        );
    }
    Ok(())
}

/// The human-readable table.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print_table(
    out: &mut impl Write,
    results: &[BenchResult],
    ceiling: &Ceiling,
) -> std::io::Result<()> {
    writeln!(
        out,
        "{:<12} {:<20} {:>9} {:>9} {:>7} {:>11} {:>15} {:>7}  {:<44} {:>17}  checksum",
        "workload",
        "method",
        "particles",
        "springs",
        "steps",
        "steps/s",
        "springs·steps/s",
        "ceiling",
        "centroid (m)",
        "energy (J)"
    )?;
    for r in results {
        let [cx, cy, cz] = r.centroid;
        let centroid = format!("({cx:.12}, {cy:.12}, {cz:.12})");
        let ok = if !r.reference_method {
            match r.diverged_at {
                Some(step) => format!("— (other method; diverged at step {step})"),
                None => "— (other method: no reference)".to_string(),
            }
        } else if r.checksum_ok {
            format!("ok ({:.1e})", r.max_relative_deviation)
        } else if !r.deterministic {
            "MISMATCH (not deterministic)".to_string()
        } else {
            format!("MISMATCH ({:.1e})", r.max_relative_deviation)
        };
        writeln!(
            out,
            "{:<12} {:<20} {:>9} {:>9} {:>7} {:>11.0} {:>15.3e} {:>6.0}%  {:<44} {:>17.10}  {}",
            r.workload.name(),
            r.method.name(),
            r.particles,
            r.springs,
            r.steps,
            r.steps_per_second,
            r.spring_steps_per_second,
            100.0 * ceiling.fraction(r),
            centroid,
            r.energy,
            ok
        )?;
    }
    let repeats = results.first().map_or(0, |r| r.repeats);
    writeln!(
        out,
        "median of {repeats} run(s) of N steps each; checksum: centroid and energy after N steps \
         vs the C++ f64 reference (relative tolerance {:e}; in brackets the largest deviation)",
        bench::REL_TOL
    )?;
    writeln!(
        out,
        "ceiling: springs·steps/s times the force evaluations per step, against the {} spring \
         kernel on data in the first-level cache: {:.3e} springs/s per thread × {} thread(s) = \
         {:.3e} springs/s",
        ceiling.kernel, ceiling.per_thread, ceiling.threads, ceiling.springs_per_second
    )
}
