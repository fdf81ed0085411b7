//! `springlab study convergence` and `study work-precision`: error against dt and against cost,
//! the fitted order of each method.

use std::io::Write;

use anyhow::bail;

use super::super::interrupt;
use super::super::progress::Progress;
use crate::budget::{self, Limits};
use crate::format::short;
use crate::output;
use crate::physics::Method;
use crate::scene;
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::stability;

use super::ConvergenceArgs;

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

pub(super) fn run_convergence(args: &ConvergenceArgs, work_precision: bool) -> anyhow::Result<()> {
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
