//! `springlab study stability`: the largest stable time step of each method, linear and
//! confirmed, beside the damped theory.

use std::io::Write;
use std::time::Instant;

use anyhow::bail;

use super::super::interrupt;
use super::super::progress::Progress;
use crate::budget::{self, Limits};
use crate::format::short;
use crate::physics::Method;
use crate::scene;
use crate::study::Stability;
use crate::study::stability::usable::Usable;
use crate::study::stability::{self, StabilityOptions, StabilityReport};
use crate::study::theory::TheoryLimit;

use super::StabilityArgs;

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
        usable: !args.no_usable,
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

pub(super) fn run_stability(args: &StabilityArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    interrupt::install(interrupt::Mode::Exit);
    let (scene, options, sets, estimate) = prepare_stability(args, &limits)?;
    estimate.enforce(&limits)?;
    let mut progress = Progress::new(
        options.methods.len() as u64,
        &format!("study stability {}", args.scene),
    );
    let start = Instant::now();
    // Each method's search runs on a core of its own; the bar counts the searches ended and
    // names those running (the probes are reported only when all have ended).
    let result = stability::stability_with(&scene, &options, &mut |_, _| {}, &mut |m, e| {
        progress.job(&args.scene, m.name().to_string(), e);
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
    writeln!(out, "hanging equilibrium: {}\n", r.equilibrium_spectrum)?;
    writeln!(
        out,
        "{:<21} {:<14} {:>13} {:>11} {:>13} {:>11} {:>9} │ {:>13} {:>9} {:>9} {:>15} │ {:>11}  \
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
        "theory stiffest",
        "usable dt"
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
    let usable_seconds = |u: Option<&Usable>| match u {
        Some(Usable { dt: Some(dt), .. }) => format!("{dt:.4e} s"),
        Some(_) => "none".to_string(),
        None => "—".to_string(),
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
            "{:<21} {:<14} {:>13} {:>11} {:>13} {:>11} {:>9} │ {:>13} {:>9} {:>9} {:>15} │ {:>11}  \
             {binding}",
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
            usable_seconds(m.usable.as_ref()),
        )?;
        if let Some(e) = &m.equilibrium_theory {
            let note = if m.classed_by_equilibrium {
                ": unstable at every dt where the scene hangs, so classed none (its pendulum \
                 modes are not damped by along-spring dampers)"
            } else {
                ""
            };
            writeln!(
                out,
                "    damped theory at the hanging equilibrium: {}{note}",
                theory_seconds(e)
            )?;
        }
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
         both, motion pumps a stiff mode (a nonlinear resonance).",
    )?;
    if let Some(u) = r.methods.iter().find_map(|m| m.usable.as_ref()) {
        writeln!(
            out,
            "usable dt: stable is not the same as right. The dt at which the energy error \
             |E + D - E0| (D: what dampers, drag and contacts took out), fitted as C·dt^q to runs \
             at the scene dt and half of it (q: the fitted order, at most the method's own), \
             reaches {} % of the allowed {} % of |E0| ({:.4e} J) over the scene's duration {} s; \
             checked: a run at 95 % of it stayed within {} % (lowered by √2 until one did). Use \
             it where it is below the scene dt.",
            100.0 * u.aim,
            100.0 * u.fraction,
            u.allowed,
            u.horizon,
            100.0 * u.fraction,
        )?;
    }
    writeln!(out, "({wall_seconds:.2} s wall)")
}
