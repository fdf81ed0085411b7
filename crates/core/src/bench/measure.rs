//! Measuring: timed runs of a workload with each method and their checksums, as `springlab bench` reports them.

use super::*;

/// What `springlab bench` reports for one workload.
#[derive(Clone, Debug, Serialize)]
pub struct BenchResult {
    /// The workload.
    pub workload: Workload,
    /// The integration method.
    pub method: Method,
    /// Number of particles.
    pub particles: usize,
    /// Number of springs (for `rope-verlet`: distance constraints).
    pub springs: usize,
    /// Steps per run (N).
    pub steps: u64,
    /// Time step (s).
    pub dt: f64,
    /// Runs of N steps timed; the median is reported.
    pub repeats: u32,
    /// Median wall time of one run of N steps (s).
    pub wall_seconds: f64,
    /// `steps / wall_seconds` (1/s).
    pub steps_per_second: f64,
    /// `springs · steps / wall_seconds` (1/s).
    pub spring_steps_per_second: f64,
    /// Force evaluations per step (4 for RK4).
    pub force_evals_per_step: u64,
    /// Centroid after N steps (m).
    pub centroid: [f64; 3],
    /// Energy after N steps (J).
    pub energy: f64,
    /// True when the checksum agrees with the reference to [`REL_TOL`].
    pub checksum_ok: bool,
    /// Largest relative deviation of the checksum from the reference.
    pub max_relative_deviation: f64,
    /// True when every repeat ended in bit-identical checksums.
    pub deterministic: bool,
    /// The reference checksum (`null` for a method other than the workload's own).
    pub reference: Option<Checksum>,
    /// True for the workload's own method (run for N steps and checked against the reference);
    /// false for the other methods, which run for a time budget on the same set-up.
    pub reference_method: bool,
    /// The step at which the run diverged (NaN or |v| > 1000 m/s), if it did.
    pub diverged_at: Option<u64>,
}

/// Times `workload`: `repeats` runs of N steps, each from a fresh copy of the set-up (set-up
/// and copying are not timed), and reports the median. `progress(i)` is called before run `i`
/// (0-based).
///
/// # Panics
/// If `repeats` is zero.
pub fn measure(workload: Workload, repeats: u32, mut progress: impl FnMut(u32)) -> BenchResult {
    assert!(repeats > 0, "at least one run");
    let (model, state) = setup(workload);
    let steps = workload.steps();
    let mut run = Run::from_setup(workload, model.clone(), state.clone());
    let mut walls = Vec::with_capacity(repeats as usize);
    let mut checksums = Vec::with_capacity(repeats as usize);
    for i in 0..repeats {
        progress(i);
        // A fresh state; the workspace is scratch only and is kept (already sized).
        run.state.clone_from(&state);
        run.steps = 0;
        run.force_evals = 0;
        let start = Instant::now();
        run.advance(steps);
        walls.push(start.elapsed().as_secs_f64());
        checksums.push(run.checksum());
    }
    walls.sort_by(f64::total_cmp);
    let wall = if walls.len() % 2 == 1 {
        walls[walls.len() / 2]
    } else {
        0.5 * (walls[walls.len() / 2 - 1] + walls[walls.len() / 2])
    };
    let first = checksums[0];
    let bits = |c: &Checksum| (c.centroid.map(f64::to_bits), c.energy.to_bits());
    let deterministic = checksums.iter().all(|c| bits(c) == bits(&first));
    let reference = workload.reference();
    let springs = model.springs().len();
    BenchResult {
        workload,
        method: workload.method(),
        particles: model.particle_count(),
        springs,
        steps,
        dt: workload.dt(),
        repeats,
        wall_seconds: wall,
        steps_per_second: steps as f64 / wall,
        spring_steps_per_second: springs as f64 * steps as f64 / wall,
        force_evals_per_step: run.force_evals / steps.max(1),
        centroid: first.centroid,
        energy: first.energy,
        checksum_ok: deterministic && first.agrees(&reference, REL_TOL),
        max_relative_deviation: first.max_relative_deviation(&reference),
        deterministic,
        reference: Some(reference),
        reference_method: true,
        diverged_at: None,
    }
}

/// The methods worth timing on `workload`: every method on the spring workloads; only Verlet on
/// `rope-verlet`, whose springs have no stiffness (they are pure distance constraints, which only
/// Verlet's projection enforces).
#[must_use]
pub fn methods_for(workload: Workload) -> Vec<Method> {
    if workload == Workload::RopeVerlet {
        vec![Method::Verlet]
    } else {
        Method::ALL.to_vec()
    }
}

/// Times `method` on `workload`'s set-up with the workload's contact rule: `repeats` runs, each
/// from a fresh state, of up to N steps or `budget` seconds of wall time, whichever comes first;
/// reports the median rate. Verlet runs without projection or damping here (`iterations = 0`,
/// `verlet_damping = 0`) so that every method integrates the same spring forces; XPBD uses
/// the library's default substeps. Only the workload's own method has a reference checksum:
/// for the others `checksum_ok` is false and `reference` is `null`.
///
/// # Panics
/// If `repeats` is zero.
pub fn measure_method(
    workload: Workload,
    method: Method,
    repeats: u32,
    budget: f64,
) -> BenchResult {
    assert!(repeats > 0, "at least one run");
    let (model, state) = setup(workload);
    let mut run = Run::with_method(workload, method);
    if method == workload.method() {
        // The workload's own method, timed like the others (Verlet without projection).
        run.params = MethodParams {
            iterations: 0,
            verlet_damping: 0.0,
            ..MethodParams::default()
        };
    }
    let mut rates = Vec::with_capacity(repeats as usize);
    let mut diverged_at = None;
    let mut last = (
        0,
        Checksum {
            centroid: [0.0; 3],
            energy: 0.0,
        },
        0,
    );
    for _ in 0..repeats {
        run.state.clone_from(&state);
        run.steps = 0;
        run.force_evals = 0;
        let start = Instant::now();
        // Batches of 16 steps between clock reads and divergence checks.
        while run.steps < workload.steps() && start.elapsed().as_secs_f64() < budget {
            run.advance(16.min(workload.steps() - run.steps));
            if crate::physics::diverge::check(&run.state, run.steps, run.steps as f64 * run.dt)
                .is_some()
            {
                diverged_at = Some(run.steps);
                break;
            }
        }
        let wall = start.elapsed().as_secs_f64();
        rates.push(run.steps as f64 / wall);
        last = (run.steps, run.checksum(), run.force_evals);
    }
    rates.sort_by(f64::total_cmp);
    let rate = rates[rates.len() / 2];
    let (steps, checksum, evals) = last;
    let springs = model.springs().len();
    BenchResult {
        workload,
        method,
        particles: model.particle_count(),
        springs,
        steps,
        dt: workload.dt(),
        repeats,
        wall_seconds: steps as f64 / rate,
        steps_per_second: rate,
        spring_steps_per_second: springs as f64 * rate,
        force_evals_per_step: evals / steps.max(1),
        centroid: checksum.centroid,
        energy: checksum.energy,
        checksum_ok: false,
        max_relative_deviation: f64::NAN,
        deterministic: true,
        reference: None,
        reference_method: false,
        diverged_at,
    }
}
