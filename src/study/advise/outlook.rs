//! What advise's search will likely ask for next: the keys of its runs ([`Job`]) and the
//! runs it hints ahead ([`Outlook`]), computed by helpers on the other cores
//! ([`crate::study::ahead`]). Hints only decide what is computed early, never what the search
//! decides or reports.

use super::search::{Against, judge, search_order};
use super::*;
use crate::study::ahead;

/// A computation of the search, a deterministic function of its key: a run of a model by a
/// method for `steps` steps of `T / steps` (with the energy accounting on or off: the same
/// motion), or a verification's confirmation of the candidate of `steps` steps.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) enum Job {
    Run {
        model: usize,
        method: Method,
        steps: u64,
        accounted: bool,
    },
    Confirm {
        model: usize,
        method: Method,
        steps: u64,
    },
}

/// What a [`Job`] gives.
#[derive(Clone, Debug)]
pub(super) enum Outcome {
    Run(Measurement),
    Confirm(Confirmation),
}

/// The two computations that verify the candidate of `steps` steps: its run at `dt/2` (energy
/// accounting on) and the confirmation at 1.5 × dt.
pub(super) fn verification_jobs(model: usize, method: Method, steps: u64) -> [Job; 2] {
    [
        Job::Run {
            model,
            method,
            steps: 2 * steps,
            accounted: true,
        },
        Job::Confirm {
            model,
            method,
            steps,
        },
    ]
}

/// The measurement a [`Job::Run`] gives.
pub(super) fn measured(runs: &ahead::Ahead<'_, Job, Outcome>, job: &Job) -> Measurement {
    match runs.get(job) {
        Outcome::Run(m) => m,
        Outcome::Confirm(_) => unreachable!("a run's job gives a measurement"),
    }
}

/// What the search expects to run next, for its hints: each model's damped-theory limits
/// (one spectrum per model, computed on first use) and the first runs of every method.
pub(super) struct Outlook<'p> {
    plan: &'p Plan,
    /// The methods in search order.
    pub(super) order: Vec<Method>,
    /// Each model's [`TheoryDt`] per method of `order`.
    theory: Vec<std::cell::OnceCell<Vec<TheoryDt>>>,
    /// Whether helpers compute runs ahead.
    ahead: bool,
}

/// Halvings hinted ahead of a method the search has not reached while the reference chain runs
/// (before its end nothing can be judged): a model's first method (which judges whether the
/// model is too coarse for the rest), the other methods of the model being searched, and those
/// of the reference model (the finest, never judged too coarse, whose runs are the longest: the
/// ones worth starting early).
const AHEAD_FIRST: u32 = 2;
const AHEAD_OTHERS: u32 = 3;
const AHEAD_REFERENCE: u32 = 3;

impl<'p> Outlook<'p> {
    /// `ahead`: whether helpers compute the hinted runs.
    pub(super) fn new(plan: &'p Plan, ahead: bool) -> Outlook<'p> {
        Outlook {
            plan,
            ahead,
            order: search_order(&plan.options.methods),
            theory: plan
                .models
                .iter()
                .map(|_| std::cell::OnceCell::new())
                .collect(),
        }
    }

    /// The search's run at halving `k` of its method. With helpers, from the first halving on
    /// with the energy accounting on (the same motion), so that the run after an accepted one,
    /// computed ahead while the accepted one runs, is also the verification's run at `dt/2`
    /// ([`Verification`]); without, every candidate's run without it (the verification makes
    /// its own: nothing is computed ahead to reuse).
    pub(super) fn run_job(&self, model: usize, method: Method, steps: u64, k: u32) -> Job {
        Job::Run {
            model,
            method,
            steps,
            accounted: self.ahead && k >= 1,
        }
    }

    pub(super) fn theory(&self, model: usize, j: usize) -> TheoryDt {
        self.theory[model].get_or_init(|| {
            let plan = self.plan;
            if model == plan.reference {
                // Computed once for the plan.
                let of = |m: Method| plan.reference_theory.iter().find(|(n, _)| *n == m);
                if let Some(known) = (self.order.iter().map(|&m| of(m).map(|&(_, t)| t))).collect()
                {
                    return known;
                }
            }
            super::super::resolution::theory_dts(&plan.models[model].scene, &self.order)
        })[j]
    }

    /// The predicted cost of a run (what the search predicts before running).
    pub(super) fn cost(&self, model: usize, method: Method, steps: u64) -> f64 {
        steps as f64 * budget::updates_per_step(&self.plan.models[model].scene, Some(method))
    }

    /// The steps of the first run of the `j`-th method on `model`, when the theory gives its
    /// limit (a method it does not cover needs the confirmed study: not guessed ahead).
    fn first_steps(&self, model: usize, j: usize) -> Option<u64> {
        let time = self.plan.time;
        let dt_max = match self.theory(model, j) {
            TheoryDt::Conditional { dt } => (dt / MARGIN).min(time),
            TheoryDt::Unconditional => time / observe::SAMPLES as f64,
            TheoryDt::None | TheoryDt::NotCovered => return None,
        };
        Some(observe::steps_for(time, dt_max))
    }

    /// The runs ahead of the search's position (the `j`-th method on a model; everything
    /// when `from` is `None`), likeliest first, each below `bound` in cost.
    ///
    /// Once the reference is known (`judged`), a method's runs already computed ahead are
    /// judged as the search will judge them ([`judge`]), so that what is hinted is the run the
    /// search will ask for next (or, after an accepted one, its verification's run at `dt/2`),
    /// and the halving after it on the reference model; a model found too coarse is left. Before
    /// that, fixed depths ([`AHEAD_FIRST`], [`AHEAD_OTHERS`], [`AHEAD_REFERENCE`]). Either way a
    /// model not yet reached gets only its first method's runs until that method is judged,
    /// unless it is the reference model. The order is breadth first: every method's next run,
    /// then every second one, ...
    pub(super) fn after(
        &self,
        from: Option<(usize, usize)>,
        bound: f64,
        judged: Option<(&ahead::Ahead<'_, Job, Outcome>, &Against<'_>)>,
    ) -> Vec<Job> {
        // (rank, job): rank 0 is a method's next run, 1 the one after, ...
        let mut ranked: Vec<(u32, Job)> = Vec::new();
        let (m0, j0) = from.map_or((0, 0), |(m, j)| (m, j + 1));
        for model in m0..self.plan.models.len() {
            let is_reference = model == self.plan.reference;
            let reached = from.is_some() && model == m0;
            let j_start = if model == m0 { j0 } else { 0 };
            for j in j_start..self.order.len() {
                let method = self.order[j];
                if is_reference && method == Method::Rk4 {
                    continue; // the reference chain's runs
                }
                let Some(first) = self.first_steps(model, j) else {
                    continue;
                };
                let cost_ok =
                    |k: u32| (0..=k).all(|i| self.cost(model, method, first << i) < bound);
                let Some((runs, against)) = judged else {
                    let depth = if is_reference {
                        AHEAD_REFERENCE
                    } else if j == 0 {
                        AHEAD_FIRST
                    } else if reached {
                        AHEAD_OTHERS
                    } else {
                        break;
                    };
                    for k in (0..depth).take_while(|&k| cost_ok(k)) {
                        ranked.push((k, self.run_job(model, method, first << k, k)));
                    }
                    continue;
                };
                // The search's walk over this method's halvings, on the runs already made.
                let mut previous: Option<Measurement> = None;
                let mut concluded = false;
                let mut coarse = false;
                for k in 0..=MAX_HALVINGS {
                    if !cost_ok(k) {
                        concluded = true;
                        break;
                    }
                    let job = self.run_job(model, method, first << k, k);
                    let Some(Outcome::Run(run)) = runs.peek(&job) else {
                        ranked.push((0, job));
                        if is_reference && k < MAX_HALVINGS && cost_ok(k + 1) {
                            ranked.push((1, self.run_job(model, method, first << (k + 1), k + 1)));
                        }
                        break;
                    };
                    match judge(&run, previous.as_ref(), against, is_reference, bound).0 {
                        Verdict::Meets => {
                            let [half, _] = verification_jobs(model, method, first << k);
                            ranked.push((0, half));
                            concluded = true;
                            break;
                        }
                        Verdict::ModelTooCoarse => {
                            coarse = true;
                            break;
                        }
                        Verdict::ProjectedCostlier => {
                            concluded = true;
                            break;
                        }
                        _ => previous = Some(run),
                    }
                }
                // A model not reached: its other methods once its first is judged, not coarse.
                if coarse || (j == 0 && !concluded && !reached && !is_reference) {
                    break;
                }
            }
        }
        ranked.sort_by_key(|&(rank, _)| rank);
        let jobs: Vec<Job> = ranked.into_iter().map(|(_, job)| job).collect();
        jobs
    }
}
