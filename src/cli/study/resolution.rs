//! `springlab study resolution`: the observable per level and spring kinds, where more model
//! stops changing the answer.

use std::io::Write;

use super::super::interrupt;
use super::super::progress::Progress;
use crate::budget::{self, Limits};
use crate::output;
use crate::physics::Method;
use crate::physics::pool::JobEvent;
use crate::scene;
use crate::study::observe::{Difference, Unit};
use crate::study::resolution::{self, Kinds, LevelRun, ResolutionOptions, ResolutionReport};

use super::ResolutionArgs;

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

pub(super) fn run_resolution(args: &ResolutionArgs) -> anyhow::Result<()> {
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
    // The runs go over the cores, the costliest first: the bar counts those ended and names
    // those running.
    let mut on_run = |i: usize, n: i64, k: Kinds, e: JobEvent| {
        let what = if i == planned.len() {
            format!("{key} = {n} at dt/2")
        } else {
            format!("{key} = {n} {}", k.name())
        };
        progress.job(&args.scene, what, e);
    };
    let report = resolution::resolution(&refinement, &options, time, &planned, &mut on_run);
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
    writeln!(out, "limit: {}", r.limit_rule)?;
    writeln!(out, "settling: {}", r.settling_rule)?;
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
        "  {:>14} {:>14} {:>14} {:>14} {:>9}",
        format!("Δ next ({unit})"),
        format!("Δ finest ({unit})"),
        format!("Δ all kinds ({unit})"),
        format!("to limit ({unit})"),
        "settled"
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
        let to_limit = match run.from_limit {
            None => "—".to_string(),
            Some([m, _]) if !has_time => format!("{m:.2e}"),
            Some([m, s]) => format!("{m:.2e} / {s:.1e} s"),
        };
        let settled = match &run.settling {
            None => "—".to_string(),
            Some(s) if s.settled => "yes".to_string(),
            Some(s) => format!("no {:.1e}", s.metres.max(s.seconds)),
        };
        writeln!(
            out,
            "  {:>14} {:>14} {:>14} {:>14} {:>9}",
            difference_text(run.change_next.as_ref(), has_time),
            difference_text(run.change_finest.as_ref(), has_time),
            difference_text(run.change_kinds.as_ref(), has_time),
            to_limit,
            settled
        )?;
    }
    writeln!(out)?;
    print_limit(out, r)?;
    let all: Vec<&LevelRun> = r.runs.iter().filter(|x| x.kinds == Kinds::All).collect();
    let finest = all.last().map_or(0, |x| x.n);
    match r.converged_from {
        Some(n) => writeln!(
            out,
            "successive differences: from {} = {n} every refinement changes the answer by at \
             most {} (Δ next ≤ X up to the finest level, {} = {finest}); this does not bound the \
             distance to the limit",
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

/// The limit, where the answer stops changing against it, and whether it had settled.
fn print_limit(out: &mut impl Write, r: &ResolutionReport) -> std::io::Result<()> {
    for l in r.limits.iter().flatten() {
        let previous = l.previous.map_or(String::new(), |p| {
            format!(
                "; one level coarser: order {:.2}, limit {:.4}",
                p.order, p.limit
            )
        });
        writeln!(
            out,
            "limit of {} ({} = {}, {}, {}): observed order {:.2}, extrapolated {:.4} ± {:.1e} {}{previous}",
            l.name,
            r.key,
            l.levels[0],
            l.levels[1],
            l.levels[2],
            l.order,
            l.limit,
            l.uncertainty,
            l.unit.symbol()
        )?;
    }
    if r.limits.iter().any(Option::is_none) || r.limits.is_empty() {
        writeln!(
            out,
            "no extrapolated limit for every component (fewer than three levels, a diverged \
             level, or differences that change sign)"
        )?;
    }
    match r.within_limit_from {
        Some(n) => writeln!(
            out,
            "stops changing from {} = {n}: every level from there is within X = {} of the \
             extrapolated limit (|O - O_∞| + u ≤ X)",
            r.key, r.tolerance
        )?,
        None => writeln!(
            out,
            "not within X = {} of the extrapolated limit at any level run: refine further (--n) \
             or accept a larger tolerance",
            r.tolerance
        )?,
    }
    let unsettled: Vec<String> = r
        .runs
        .iter()
        .filter(|x| x.kinds == Kinds::All)
        .filter_map(|x| {
            let s = x.settling.as_ref()?;
            (!s.settled)
                .then(|| format!("{} = {} moved {:.1e}", r.key, x.n, s.metres.max(s.seconds)))
        })
        .collect();
    if r.settled {
        writeln!(out, "settled at t = {} s at every level", r.time)?;
    } else if !unsettled.is_empty() {
        writeln!(
            out,
            "not settled at t = {} s ({} over the last fifth, more than X/10): the limit is the \
             answer at T, not at rest; a later --time observes it nearer rest",
            r.time,
            unsettled.join(", ")
        )?;
    }
    Ok(())
}
