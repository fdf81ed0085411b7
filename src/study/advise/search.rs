//! The search: candidates in order of cost, the reference run, the verifications and the report.

use super::outlook::{Job, Outcome, Outlook, measured, verification_jobs};
use super::*;
use crate::study::ahead;

/// Methods by cost per step, cheapest first (ties in teaching order).
pub(super) fn search_order(methods: &[Method]) -> Vec<Method> {
    let mut m = methods.to_vec();
    let cost =
        |m: &Method| budget::evaluations_per_step(*m, &crate::physics::MethodParams::default());
    m.sort_by(|a, b| cost(a).total_cmp(&cost(b)));
    m
}

/// The margin limit of `method` on `scene`, whose damped-theory limit is `theory`:
/// `(limit dt, kind)`; `None` for no stable dt.
fn margin_limit(
    scene: &Scene,
    method: Method,
    theory: TheoryDt,
) -> Result<Option<(Option<f64>, MarginKind)>, StudyError> {
    Ok(match theory {
        TheoryDt::Conditional { dt } => Some((Some(dt), MarginKind::Theory)),
        TheoryDt::Unconditional => Some((None, MarginKind::Unconditional)),
        TheoryDt::None => None,
        TheoryDt::NotCovered => match stability::max_stable_dt(scene, method)? {
            None => Some((None, MarginKind::Confirmed)),
            Some(dt) if dt > 0.0 => Some((Some(dt), MarginKind::Confirmed)),
            Some(_) => None,
        },
    })
}

/// Accepted when `err + e_ref ≤ X` in each unit.
fn accepted(error: &Difference, reference: &Difference, tolerance: f64) -> bool {
    error.metres + reference.metres <= tolerance && error.seconds + reference.seconds <= tolerance
}

/// The command line that runs a candidate.
fn command(plan: &Plan, c: &Candidate) -> String {
    let model = &plan.models[c.model];
    let mut line = format!(
        "springlab run {} --method {} --dt {:e} --time {}",
        plan.scene,
        c.method,
        c.dt,
        budget::short(plan.time)
    );
    for s in &model.sets {
        line.push_str(&format!(" --set {s}"));
    }
    line
}

/// The confirmation of a verification: the whole scene at 1.5 × `dt` over the run's time.
fn confirm(scene: &Scene, method: Method, dt: f64, time: f64) -> Confirmation {
    let confirm_dt = MARGIN * dt;
    let confirm_count = ((time / confirm_dt).ceil() as u64).max(stability::CONFIRM_MIN_STEPS);
    stability::confirm_steps(
        scene,
        method,
        confirm_dt,
        confirm_count,
        stability::energy_scale(scene),
    )
}

/// What the search compares a run with: the reference's snapshots, its own error, `X` and `T`.
pub(super) struct Against<'r> {
    snapshots: &'r [observe::Observation],
    e_ref: &'r Difference,
    x: f64,
    time: f64,
}

/// The search's verdict on a run of a model by a method (module docs), given the run at the
/// halving before (`previous`) and the cost `bound` (the cheapest accepted, or the reference's):
/// `Diverged` or `TooInaccurate` (halve again), `Meets`, `ModelTooCoarse` (skip the model) or
/// `ProjectedCostlier` (stop the method); with the error over the run when it did not diverge.
pub(super) fn judge(
    run: &Measurement,
    previous: Option<&Measurement>,
    against: &Against<'_>,
    is_reference: bool,
    bound: f64,
) -> (Verdict, Option<Difference>) {
    let Against {
        snapshots,
        e_ref,
        x,
        time,
    } = *against;
    if run.observation.is_none() {
        return (Verdict::Diverged, None);
    }
    // The error over the run: the observable at each of the 20 sample instants.
    let error = observe::history_difference(&run.snapshots, snapshots, time);
    let previous = previous.filter(|p| p.observation.is_some());
    if accepted(&error, e_ref, x) {
        return (Verdict::Meets, Some(error));
    }
    let coarse = !is_reference
        && previous.is_some_and(|p| {
            let step = observe::history_difference(&run.snapshots, &p.snapshots, time);
            error.metres - 2.0 * step.metres > x || error.seconds - 2.0 * step.seconds > x
        });
    if coarse {
        return (Verdict::ModelTooCoarse, Some(error));
    }
    // The error's trend: halvings still needed, and what they would cost.
    if let Some(p) = previous {
        let before = observe::history_difference(&p.snapshots, snapshots, time).worst();
        let now = error.worst();
        if now > 0.0 && before / now >= PROJECTION_RATIO {
            let halvings = ((now / x).ln() / (before / now).ln()).max(0.0);
            if run.cost * 2f64.powf(halvings) >= bound {
                return (Verdict::ProjectedCostlier, Some(error));
            }
        }
    }
    (Verdict::TooInaccurate, Some(error))
}

/// Runs the plan (module docs). `progress` is called before every run.
///
/// The search is sequential (each run decides the next), but its runs are deterministic
/// functions of their keys and mostly predictable: with more than one thread, helpers compute
/// the runs it hints ([`super::super::ahead`]) — the next halving unless its cost would skip it,
/// the verification of the cheapest accepted candidate, then the first runs of the methods and
/// models still ahead — at most one computation per core; the search takes the same decisions
/// and reports the same numbers.
///
/// # Errors
/// A confirmed stability study that fails (for methods the theory does not cover).
pub fn advise(plan: &Plan, progress: &mut dyn FnMut(&Stage)) -> Result<AdviseReport, StudyError> {
    let compute = |job: &Job, cancel: &ahead::Cancel| match *job {
        Job::Run {
            model,
            method,
            steps,
            accounted,
        } => {
            let scene = &plan.models[model].scene;
            let dt = plan.time / steps as f64;
            observe::measure_with_unless(scene, method, dt, steps, accounted, cancel)
                .map(Outcome::Run)
        }
        Job::Confirm {
            model,
            method,
            steps,
        } => {
            let scene = &plan.models[model].scene;
            let dt = plan.time / steps as f64;
            Some(Outcome::Confirm(confirm(scene, method, dt, plan.time)))
        }
    };
    let threads = crate::physics::pool::Pool::global().threads();
    ahead::with_cores(threads, &compute, |runs| {
        search(plan, progress, runs, threads >= 2)
    })
}

/// [`advise`] with its runs from `runs` (`helped`: computed ahead by helpers).
fn search(
    plan: &Plan,
    progress: &mut dyn FnMut(&Stage),
    runs: &ahead::Ahead<'_, Job, Outcome>,
    helped: bool,
) -> Result<AdviseReport, StudyError> {
    let outlook = Outlook::new(plan, helped);
    let chain_job = |steps: u64| Job::Run {
        model: plan.reference,
        method: Method::Rk4,
        steps,
        accounted: false,
    };
    let start = Instant::now();
    let time = plan.time;
    let x = plan.options.tolerance;
    let reference_model = &plan.models[plan.reference];

    // 1. The reference chain.
    let mut chain_runs: Vec<Measurement> = Vec::new();
    let mut chain: Vec<(f64, Option<Difference>)> = Vec::new();
    let mut converged = false;
    for k in 0..=REFERENCE_HALVINGS {
        let steps = plan.reference_steps << k;
        let dt = time / steps as f64;
        progress(&Stage::Reference(dt));
        // Hints: this run, the chain's last, then the next (at the start also the third), then
        // the search's first runs. The last run is as long as all the others together and, on a
        // scene with impacts, the one the chain most often ends with (the changes between
        // halvings do not shrink as the method's order would have them until the steps resolve
        // the impacts): started at once, it runs beside the shorter ones instead of after them.
        // Where the chain ends earlier it is stopped then, having taken a core from guesses only.
        let ahead = if k == 0 { 2 } else { 1 };
        let last = chain_job(plan.reference_steps << REFERENCE_HALVINGS);
        let mut hints: Vec<Job> = std::iter::once(chain_job(steps))
            .chain((k < REFERENCE_HALVINGS).then(|| last.clone()))
            .chain((1..=ahead.min(REFERENCE_HALVINGS - k)).map(|i| chain_job(steps << i)))
            .collect();
        hints.dedup();
        if k == 0 {
            runs.hint(hints.clone());
        }
        let chain_bound = outlook.cost(
            plan.reference,
            Method::Rk4,
            plan.reference_steps << REFERENCE_HALVINGS,
        );
        hints.extend(outlook.after(None, chain_bound, None));
        runs.hint(hints);
        let run = measured(runs, &chain_job(steps));
        debug_assert_eq!(run.dt, dt);
        let change = chain_runs
            .last()
            .map(|prev| observe::history_difference(&run.snapshots, &prev.snapshots, time));
        let done = change
            .as_ref()
            .is_some_and(|d| d.within(REFERENCE_FRACTION * x));
        chain.push((dt, change));
        chain_runs.push(run);
        if done {
            converged = true;
            break;
        }
    }
    let reference_run = chain_runs.last().cloned().unwrap_or_else(|| {
        observe::measure(&reference_model.scene, Method::Rk4, time, observe::SAMPLES)
    });
    let count = Observable::of(&reference_model.scene).names().len();
    let e_ref = chain
        .last()
        .and_then(|c| c.1.clone())
        .unwrap_or_else(|| Difference::infinite(count));
    let reference_obs = reference_run.observation.clone();
    let reference = Reference {
        n: reference_model.n,
        method: Method::Rk4,
        dt: reference_run.dt,
        steps: reference_run.steps,
        cost: reference_run.cost,
        chain,
        error: e_ref.clone(),
        converged,
        observation: reference_obs.clone(),
    };
    let cap = SEARCH_CAP * reference_run.cost;

    // 2. The search.
    let mut candidates: Vec<Candidate> = Vec::new();
    let mut best = f64::INFINITY;
    let mut work = 0.0;
    let mut left_out = Vec::new();
    // The accepted runs' snapshots, by candidate index, for the verification's comparison.
    let mut accepted_runs: Vec<(usize, Vec<observe::Observation>)> = Vec::new();
    // The verification of the cheapest accepted candidate so far: `(cost, particles, jobs)`.
    let mut to_verify: Option<(f64, usize, [Job; 2])> = None;
    if !plan.options.methods.contains(&Method::Xpbd) {
        left_out.push((
            Method::Xpbd,
            "not considered unless asked (--methods): no stability theory, and its confirmed \
             limit needs the whole stability study"
                .to_string(),
        ));
    }
    let Some(reference_obs) = reference_obs else {
        return Ok(report(
            plan,
            reference,
            candidates,
            None,
            Vec::new(),
            work,
            cap,
            left_out,
            start,
        ));
    };
    let against = Against {
        snapshots: &reference_run.snapshots,
        e_ref: &e_ref,
        x,
        time,
    };
    for (index, model) in plan.models.iter().enumerate() {
        let is_reference = index == plan.reference;
        let mut too_coarse = false;
        for (j, &method) in outlook.order.iter().enumerate() {
            let base = Candidate {
                model: index,
                n: model.n,
                kinds: model.kinds,
                particles: model.scene.particle_count(),
                springs: model.scene.spring_count(),
                method,
                dt: 0.0,
                steps: 0,
                margin: None,
                margin_kind: MarginKind::Theory,
                cost: 0.0,
                wall_seconds: None,
                error: None,
                error_at_t: None,
                verdict: Verdict::NoStableDt,
                diverged: None,
            };
            if too_coarse {
                // The model was judged with a cheaper method: nothing to run.
                continue;
            }
            let Some((limit, margin_kind)) =
                margin_limit(&model.scene, method, outlook.theory(index, j))?
            else {
                candidates.push(base);
                continue;
            };
            let dt_max = match limit {
                Some(limit) => (limit / MARGIN).min(time),
                None => time / observe::SAMPLES as f64,
            };
            let first_steps = observe::steps_for(time, dt_max);
            let mut previous: Option<Measurement> = None;
            for k in 0..=MAX_HALVINGS {
                let steps = first_steps << k;
                let dt = time / steps as f64;
                let mut c = Candidate {
                    dt,
                    steps,
                    margin: limit.map(|l| l / dt),
                    margin_kind,
                    ..base.clone()
                };
                // RK4 at the reference model: the reference chain's runs.
                let reused = (is_reference && method == Method::Rk4)
                    .then(|| chain_runs.iter().find(|r| r.steps == steps).cloned())
                    .flatten();
                let predicted = match (&reused, &previous) {
                    (Some(r), _) => r.cost,
                    (None, Some(p)) => 2.0 * p.cost,
                    (None, None) => {
                        steps as f64 * budget::updates_per_step(&model.scene, Some(method))
                    }
                };
                if predicted >= best.min(reference_run.cost) && reused.is_none() {
                    c.cost = predicted;
                    c.verdict = Verdict::Costlier;
                    candidates.push(c);
                    break;
                }
                if reused.is_none() && work + predicted > cap {
                    c.cost = predicted;
                    c.verdict = Verdict::OverCap;
                    candidates.push(c);
                    break;
                }
                let run = match reused {
                    Some(r) => r,
                    None => {
                        progress(&Stage::Candidate {
                            n: model.n,
                            kinds: model.kinds,
                            method,
                            dt,
                        });
                        // Hints: this run, the next halving unless its predicted cost would
                        // skip it, the cheapest accepted candidate's verification, then the
                        // first runs of the methods and models ahead.
                        let bound = best.min(reference_run.cost);
                        let this = outlook.run_job(index, method, steps, k);
                        let mut hints = vec![this.clone()];
                        let nominal = outlook.cost(index, method, steps);
                        if k < MAX_HALVINGS && 2.0 * nominal < bound && work + 3.0 * nominal <= cap
                        {
                            hints.push(outlook.run_job(index, method, steps << 1, k + 1));
                        }
                        if let Some((_, _, jobs)) = &to_verify {
                            hints.extend(jobs.iter().cloned());
                        }
                        hints.extend(outlook.after(
                            Some((index, j)),
                            bound,
                            Some((runs, &against)),
                        ));
                        runs.hint(hints);
                        let r = measured(runs, &this);
                        work += r.cost;
                        r
                    }
                };
                c.cost = run.cost;
                c.wall_seconds = Some(run.wall_seconds);
                let Some(obs) = &run.observation else {
                    c.verdict = Verdict::Diverged;
                    c.diverged = run.diverged.clone();
                    candidates.push(c);
                    previous = Some(run);
                    continue;
                };
                let bound = best.min(reference_run.cost);
                let (verdict, error) =
                    judge(&run, previous.as_ref(), &against, is_reference, bound);
                c.error_at_t = Some(obs.difference(&reference_obs, time));
                c.error = error;
                c.verdict = verdict;
                candidates.push(c);
                match verdict {
                    Verdict::Meets => {
                        best = best.min(run.cost);
                        let particles = model.scene.particle_count();
                        if to_verify
                            .as_ref()
                            .is_none_or(|(cost, p, _)| (run.cost, particles) < (*cost, *p))
                        {
                            to_verify = Some((
                                run.cost,
                                particles,
                                verification_jobs(index, method, steps),
                            ));
                        }
                        accepted_runs.push((candidates.len() - 1, run.snapshots));
                        break;
                    }
                    Verdict::ModelTooCoarse => {
                        too_coarse = true;
                        break;
                    }
                    Verdict::ProjectedCostlier => break,
                    _ => {}
                }
                previous = Some(run);
            }
        }
    }

    // 3. Verification, cheapest accepted first.
    let mut accepted_order: Vec<usize> = (0..candidates.len())
        .filter(|&i| candidates[i].verdict == Verdict::Meets)
        .collect();
    accepted_order.sort_by(|&a, &b| {
        candidates[a]
            .cost
            .total_cmp(&candidates[b].cost)
            .then(candidates[a].particles.cmp(&candidates[b].particles))
    });
    let mut verifications = Vec::new();
    let mut recommended = None;
    for &i in accepted_order.iter().take(MAX_VERIFICATIONS) {
        let c = &candidates[i];
        progress(&Stage::Verify(c.method, c.dt));
        // Its two runs side by side where there are two cores (the run at dt/2 usually
        // computed already, ahead of the search's end).
        let jobs = verification_jobs(c.model, c.method, c.steps);
        runs.hint(jobs.to_vec());
        let [half, check] = jobs;
        let run = measured(runs, &half);
        let Outcome::Confirm(confirmation) = runs.get(&check) else {
            unreachable!("a confirmation's job gives a confirmation")
        };
        let energy_residual = run.energy_residual.unwrap_or(f64::NAN);
        let error = observe::history_difference(&run.snapshots, &reference_run.snapshots, time);
        let error_at_t = run.difference(&reference_obs, time);
        let own = accepted_runs
            .iter()
            .find(|(j, _)| *j == i)
            .map_or(&[][..], |(_, s)| s.as_slice());
        let time_step_change = observe::history_difference(&run.snapshots, own, time);
        let accurate = accepted(&error, &e_ref, x);
        let holds = accurate && confirmation.passed;
        verifications.push(Verification {
            candidate: i,
            dt: c.dt / 2.0,
            error,
            error_at_t,
            time_step_change,
            accurate,
            stability: confirmation,
            holds,
            energy_residual,
            command: command(plan, c),
        });
        if holds {
            recommended = Some(i);
            break;
        }
    }
    Ok(report(
        plan,
        reference,
        candidates,
        recommended,
        verifications,
        work,
        cap,
        left_out,
        start,
    ))
}

#[allow(clippy::too_many_arguments)]
fn report(
    plan: &Plan,
    reference: Reference,
    candidates: Vec<Candidate>,
    recommended: Option<usize>,
    verifications: Vec<Verification>,
    search_work: f64,
    search_cap: f64,
    left_out: Vec<(Method, String)>,
    start: Instant,
) -> AdviseReport {
    AdviseReport {
        scene: plan.scene.clone(),
        sets: plan.sets.clone(),
        time: plan.time,
        tolerance: plan.options.tolerance,
        tolerance_unit: TOLERANCE_UNIT,
        observable: Observable::of(&plan.models[plan.reference].scene).definition(plan.time),
        refinement: plan.refinement.clone(),
        key: plan.key,
        margin_rule: format!(
            "dt ≤ limit / {MARGIN}: limit = the damped theory's (linearised at the initial state, \
             study::theory) on that resolution and kinds; the confirmed stability study's for a \
             method the theory does not cover; implicit Euler is unconditional (first dt = T/{})",
            observe::SAMPLES
        ),
        cost_unit: "particle and spring updates: (force evaluations + CG iterations) × \
                    (particles + springs + 8), as the budget counts them",
        reference,
        candidates,
        recommended,
        verifications,
        search_work,
        search_cap,
        left_out,
        wall_seconds: start.elapsed().as_secs_f64(),
    }
}
