//! The search: candidates in order of cost, the reference run, the verifications and the report.

use super::*;
use crate::study::ahead;

/// Methods by cost per step, cheapest first (ties in teaching order).
fn search_order(methods: &[Method]) -> Vec<Method> {
    let mut m = methods.to_vec();
    let cost =
        |m: &Method| budget::evaluations_per_step(*m, &crate::physics::MethodParams::default());
    m.sort_by(|a, b| cost(a).total_cmp(&cost(b)));
    m
}

/// The margin limit of `method` on `scene`: `(limit dt, kind)`; `None` for no stable dt.
fn margin_limit(
    scene: &Scene,
    method: Method,
) -> Result<Option<(Option<f64>, MarginKind)>, StudyError> {
    Ok(match theory_dt(scene, method) {
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

/// A verification's two runs, side by side on two cores where there are two (each the same
/// whichever thread runs it): the candidate at `dt/2` with the energy accounting on, and the
/// confirmation of the whole scene at 1.5 × dt over the run's time.
fn verify(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    time: f64,
) -> (Measurement, Confirmation) {
    let confirm_dt = MARGIN * dt;
    let confirm_count = ((time / confirm_dt).ceil() as u64).max(stability::CONFIRM_MIN_STEPS);
    let confirm = || {
        stability::confirm_steps(
            scene,
            method,
            confirm_dt,
            confirm_count,
            stability::energy_scale(scene),
        )
    };
    let half = || observe::measure_accounted(scene, method, dt / 2.0, 2 * steps);
    if crate::physics::pool::Pool::global().threads() < 2 {
        return (half(), confirm());
    }
    // Two runs beside each other, each on its own thread alone (the same bits): a pool worker
    // woken for one run's passes would take time from the other.
    use crate::physics::pool::alone;
    std::thread::scope(|scope| {
        let confirmation = scope.spawn(|| alone(confirm));
        let run = alone(half);
        let confirmation = confirmation
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (run, confirmation)
    })
}

/// A run of the search: (model index, method, steps); its `dt` is `T / steps`.
type RunKey = (usize, Method, u64);

/// Runs the plan (module docs). `progress` is called before every run.
///
/// The search is sequential (each run decides the next), but its next run is usually the next
/// halving of `dt`: with more than one thread, helpers compute the hinted runs ahead
/// ([`super::super::ahead`]); the search takes the same decisions and reports the same numbers.
///
/// # Errors
/// A confirmed stability study that fails (for methods the theory does not cover).
pub fn advise(plan: &Plan, progress: &mut dyn FnMut(&Stage)) -> Result<AdviseReport, StudyError> {
    let compute = |&(model, method, steps): &RunKey, cancel: &ahead::Cancel| {
        let scene = &plan.models[model].scene;
        observe::measure_unless(scene, method, plan.time / steps as f64, steps, cancel)
    };
    let threads = crate::physics::pool::Pool::global().threads();
    let helpers = if threads < 2 { 0 } else { threads };
    ahead::with_helpers(helpers, &compute, |runs| search(plan, progress, runs))
}

/// [`advise`] with its runs from `runs`.
fn search(
    plan: &Plan,
    progress: &mut dyn FnMut(&Stage),
    runs: &ahead::Ahead<'_, RunKey, Measurement>,
) -> Result<AdviseReport, StudyError> {
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
        runs.hint(if k < REFERENCE_HALVINGS {
            vec![(plan.reference, Method::Rk4, steps << 1)]
        } else {
            Vec::new()
        });
        let run = runs.get(&(plan.reference, Method::Rk4, steps));
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
    for (index, model) in plan.models.iter().enumerate() {
        let is_reference = index == plan.reference;
        let mut too_coarse = false;
        for method in search_order(&plan.options.methods) {
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
            let Some((limit, margin_kind)) = margin_limit(&model.scene, method)? else {
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
                        let next = (k < MAX_HALVINGS).then_some((index, method, steps << 1));
                        runs.hint(next.into_iter().collect());
                        let r = runs.get(&(index, method, steps));
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
                // The error over the run: the observable at each of the 20 sample instants.
                let error =
                    observe::history_difference(&run.snapshots, &reference_run.snapshots, time);
                let meets = accepted(&error, &e_ref, x);
                let coarse = !is_reference
                    && previous
                        .as_ref()
                        .filter(|p| p.observation.is_some())
                        .is_some_and(|p| {
                            let step =
                                observe::history_difference(&run.snapshots, &p.snapshots, time);
                            error.metres - 2.0 * step.metres > x
                                || error.seconds - 2.0 * step.seconds > x
                        });
                c.error_at_t = Some(obs.difference(&reference_obs, time));
                c.error = Some(error);
                c.verdict = if meets {
                    Verdict::Meets
                } else if coarse {
                    Verdict::ModelTooCoarse
                } else {
                    Verdict::TooInaccurate
                };
                candidates.push(c);
                if meets {
                    best = best.min(run.cost);
                    accepted_runs.push((candidates.len() - 1, run.snapshots));
                    break;
                }
                if coarse {
                    too_coarse = true;
                    break;
                }
                // The error's trend: halvings still needed, and what they would cost.
                let bound = best.min(reference_run.cost);
                let trend = previous
                    .as_ref()
                    .filter(|p| p.observation.is_some())
                    .map(|p| {
                        observe::history_difference(&p.snapshots, &reference_run.snapshots, time)
                            .worst()
                    })
                    .zip(
                        candidates
                            .last()
                            .and_then(|c| c.error.as_ref())
                            .map(Difference::worst),
                    );
                if let Some((before, now)) = trend
                    && now > 0.0
                    && before / now >= PROJECTION_RATIO
                {
                    let halvings = ((now / x).ln() / (before / now).ln()).max(0.0);
                    if run.cost * 2f64.powf(halvings) >= bound
                        && let Some(last) = candidates.last_mut()
                    {
                        last.verdict = Verdict::ProjectedCostlier;
                        break;
                    }
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
        let model = &plan.models[c.model];
        progress(&Stage::Verify(c.method, c.dt));
        let (run, confirmation) = verify(&model.scene, c.method, c.dt, c.steps, time);
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
