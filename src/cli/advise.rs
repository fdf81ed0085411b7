//! `springlab advise`: the cheapest resolution, method and time step for an accuracy.

use std::io::Write;

use clap::Args;

use super::interrupt;
use super::progress::Progress;
use crate::budget::{self, Limits};
use crate::study::advise::{self, AdviseOptions, AdviseReport, MarginKind, Plan, Stage, Verdict};
use crate::study::observe::Unit;
use crate::study::stability;

/// Options of `springlab advise`.
#[derive(Debug, Args)]
pub struct AdviseArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml); resolutions are tried
    /// only for built-in scenes with `n` or `nodes`.
    pub scene: String,
    /// The tolerance X on the scene's observable: metres for positions and lengths (centroid,
    /// compression, sag, end point), seconds for times (contact time).
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub tolerance: f64,
    /// When the observable is taken, in seconds (default: 2.5 for the cubes and the jelly,
    /// 3 for cloth-sphere, 1 otherwise).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Methods to consider, comma separated (default: all but xpbd).
    #[arg(long, value_name = "A,B")]
    pub methods: Option<String>,
    /// Resolutions to consider, comma separated; the finest is the reference's (default: the
    /// scene's own and three coarser, spacing ratio about √2).
    #[arg(long = "n", value_name = "N,N,…", value_delimiter = ',')]
    pub levels: Option<Vec<i64>>,
    /// Keep every spring kind (do not try leaving out bend or shear springs).
    #[arg(long)]
    pub no_kinds: bool,
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

/// The plan and its budget estimate (an upper bound; nothing runs yet; every model is built
/// within `limits`).
///
/// # Errors
/// Bad tolerance, time, methods, resolutions or scene.
pub fn prepare(args: &AdviseArgs, limits: &Limits) -> anyhow::Result<(Plan, budget::Estimate)> {
    let options = AdviseOptions {
        tolerance: args.tolerance,
        time: args.time,
        methods: match &args.methods {
            Some(text) => stability::parse_methods(text)?,
            None => advise::DEFAULT_METHODS.to_vec(),
        },
        levels: args.levels.clone(),
        kinds: !args.no_kinds,
    };
    let plan = advise::plan(&args.scene, &args.sets, &options, limits)?;
    let estimate = advise::estimate(format!("advise {}", args.scene), &plan);
    Ok((plan, estimate))
}

/// `springlab advise`.
///
/// # Errors
/// As [`prepare`], the budget, and the stability study of a method the theory does not cover.
pub fn run(args: &AdviseArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    interrupt::install(interrupt::Mode::Exit);
    let (plan, estimate) = prepare(args, &limits)?;
    estimate.enforce(&limits)?;
    // Units: the reference's halvings, the models × methods, the verifications.
    let total = u64::from(advise::REFERENCE_HALVINGS + 1)
        + (plan.models.len() * plan.options.methods.len()) as u64
        + advise::MAX_VERIFICATIONS as u64;
    let mut progress = Progress::new(total, &format!("advise {}", args.scene));
    let mut done = 0u64;
    let mut last: Option<(Option<i64>, &'static str, crate::physics::Method)> = None;
    let key = plan.key.unwrap_or("n");
    let result = advise::advise(&plan, &mut |stage| {
        let label = match stage {
            Stage::Reference(dt) => {
                done += 1;
                format!("advise: reference rk4 at dt = {dt:.3e} s")
            }
            Stage::Candidate {
                n,
                kinds,
                method,
                dt,
            } => {
                let here = (*n, kinds.name(), *method);
                if last != Some(here) {
                    done += 1;
                    last = Some(here);
                }
                let at = n.map_or_else(String::new, |n| format!("{key} = {n}, "));
                format!("advise: {at}{}, {method} at dt = {dt:.3e} s", kinds.name())
            }
            Stage::Verify(method, dt) => {
                done += 1;
                format!("advise: verifying {method} at dt = {dt:.3e} s")
            }
        };
        progress.set(done.min(total));
        progress.label(label);
    });
    progress.finish();
    let report = result?;
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer(&mut out, &report).map_err(std::io::Error::from)?;
        writeln!(out)?;
    } else {
        print(&mut out, &report)?;
    }
    Ok(())
}

fn error_text(d: Option<&crate::study::observe::Difference>, has_time: bool) -> String {
    crate::cli::study::difference_text(d, has_time)
}

/// The text report of `springlab advise`.
///
/// # Errors
/// Only when `out` cannot be written.
pub fn print(out: &mut impl Write, r: &AdviseReport) -> std::io::Result<()> {
    writeln!(
        out,
        "advise · scene {} · observable at t = {} s · tolerance X = {} ({})",
        r.scene, r.time, r.tolerance, r.tolerance_unit
    )?;
    if !r.sets.is_empty() {
        writeln!(out, "set: {}", r.sets.join(" "))?;
    }
    writeln!(out, "observable: {}", r.observable)?;
    if let Some(rule) = &r.refinement {
        writeln!(out, "resolutions: {rule}")?;
    }
    let has_time = r
        .reference
        .observation
        .as_ref()
        .is_some_and(|o| o.components.iter().any(|c| c.unit == Unit::Second));
    let unit = if has_time { "m / s" } else { "m" };
    let key = r.key.unwrap_or("n");
    let at = |n: Option<i64>| {
        n.map_or_else(
            || "the scene's model".to_string(),
            |n| format!("{key} = {n}"),
        )
    };
    let e_ref = error_text(Some(&r.reference.error), has_time);
    writeln!(
        out,
        "reference: {}, every spring kind, rk4 at dt = {:.4e} s ({} steps); its own error ≈ {e_ref} {unit} \
         (the largest difference from the run at 2·dt over 20 instants{})",
        at(r.reference.n),
        r.reference.dt,
        r.reference.steps,
        if r.reference.converged {
            String::new()
        } else {
            format!(
                "; above X/10 after {} halvings: the advice is limited by the reference",
                advise::REFERENCE_HALVINGS
            )
        }
    )?;
    writeln!(out, "margin: {}", r.margin_rule)?;
    writeln!(
        out,
        "accepted when: error + the reference's own error ≤ X (in m, and in s for times); error: \
         the largest difference from the reference at the 20 instants k·T/20, T included"
    )?;
    writeln!(out, "cost: {}", r.cost_unit)?;
    for (m, why) in &r.left_out {
        writeln!(out, "left out: {m}: {why}")?;
    }
    writeln!(
        out,
        "\n{:>14}  {:<8} {:<20} {:>11} {:>8} {:>10} {:>10} {:>8} {:>16}  verdict",
        key,
        "kinds",
        "method",
        "dt (s)",
        "steps",
        "margin",
        "cost",
        "wall (s)",
        format!("error ({unit})")
    )?;
    for (i, c) in r.candidates.iter().enumerate() {
        let margin = match (c.margin, c.margin_kind) {
            _ if c.verdict == Verdict::NoStableDt => "none".to_string(),
            (_, MarginKind::Unconditional) => "∞ theory".to_string(),
            (Some(m), MarginKind::Theory) => format!("{m:.1} th."),
            (Some(m), MarginKind::Confirmed) => format!("{m:.1} conf."),
            (None, _) => "∞ conf.".to_string(),
        };
        let (dt, steps) = if c.verdict == Verdict::NoStableDt {
            ("—".to_string(), "—".to_string())
        } else {
            (format!("{:.4e}", c.dt), c.steps.to_string())
        };
        let wall = c
            .wall_seconds
            .map_or_else(|| "—".to_string(), |w| format!("{w:.2}"));
        let mark = if r.recommended == Some(i) {
            "  ◀ recommended"
        } else {
            ""
        };
        writeln!(
            out,
            "{:>14}  {:<8} {:<20} {:>11} {:>8} {:>10} {:>10.3e} {:>8} {:>16}  {}{mark}",
            c.n.map_or_else(|| "—".to_string(), |n| n.to_string()),
            c.kinds.name(),
            c.method.name(),
            dt,
            steps,
            margin,
            c.cost,
            wall,
            error_text(c.error.as_ref(), has_time),
            c.verdict.name()
        )?;
    }
    writeln!(
        out,
        "\nsearch: {:.3e} updates of a cap of {:.3e} ({} × the reference run), {:.1} s in all",
        r.search_work,
        r.search_cap,
        advise::SEARCH_CAP,
        r.wall_seconds
    )?;
    for v in &r.verifications {
        let c = &r.candidates[v.candidate];
        writeln!(
            out,
            "verification of {}, {} kinds, {} at dt = {:.4e} s:",
            at(c.n),
            c.kinds.name(),
            c.method,
            c.dt
        )?;
        writeln!(
            out,
            "    time step: the same model and method at dt/2 = {:.4e} s: error at T {} {unit}, \
             largest over the 20 instants {} {unit}, + reference {e_ref} ≤ X: {}; change from \
             dt to dt/2 {} {unit}",
            v.dt,
            error_text(Some(&v.error_at_t), has_time),
            error_text(Some(&v.error), has_time),
            if v.accurate { "holds" } else { "fails" },
            error_text(Some(&v.time_step_change), has_time)
        )?;
        writeln!(
            out,
            "    stability: the whole scene at 1.5 × dt = {:.4e} s for {} steps: {}",
            v.stability.dt,
            v.stability.steps,
            if v.stability.passed {
                "no divergence, energy bounded: holds".to_string()
            } else {
                format!("fails ({})", v.stability.reason.as_deref().unwrap_or(""))
            }
        )?;
        writeln!(
            out,
            "    energy residual E + dissipated - E0 at T (the dt/2 run): {:.4e} J",
            v.energy_residual
        )?;
    }
    match r.recommended {
        Some(i) => {
            let c = &r.candidates[i];
            let v = r.verifications.iter().find(|v| v.candidate == i);
            let ratio = r.reference.cost / c.cost;
            writeln!(
                out,
                "\nrecommended: {}, {} spring kinds, {} at dt = {:.4e} s (margin {}): error {} {unit} ≤ X = {}, \
                 cost {:.3e} updates ({ratio:.1}× cheaper than the reference)",
                at(c.n),
                c.kinds.name(),
                c.method,
                c.dt,
                match (c.margin, c.margin_kind) {
                    (Some(m), MarginKind::Theory) => format!("{m:.1} by the damped theory"),
                    (Some(m), _) => format!("{m:.1} by the confirmed limit"),
                    (None, _) => "unconditional".to_string(),
                },
                error_text(c.error.as_ref(), has_time),
                r.tolerance,
                c.cost
            )?;
            if let Some(v) = v {
                writeln!(out, "    {}", v.command)?;
            }
        }
        None => writeln!(
            out,
            "\nno configuration verified within X = {}: a smaller tolerance than the reference \
             can show, or every candidate failed its verification",
            r.tolerance
        )?,
    }
    Ok(())
}
