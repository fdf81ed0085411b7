//! The report of `springlab run` (printed by `run --json`): what a [`Simulation`] did.

use serde::Serialize;

use super::Simulation;
use crate::physics::{Dissipated, Divergence, Energy, Method};

impl Simulation {
    /// The report of `springlab run` (printed by `run --json`, see README.md "Use").
    #[must_use]
    pub fn report(&self, wall_seconds: f64) -> RunReport {
        RunReport {
            scene: self.scene.name.clone(),
            method: self.scene.method_label(),
            dt: self.dt,
            steps: self.steps,
            time: self.time(),
            particles: self.scene.particle_count(),
            springs: self.scene.spring_count(),
            force_evals: self.force_evals,
            wall_seconds,
            diverged: self.diverged.clone(),
            energy: self.energy(),
            energy_initial: self.energy_initial,
            dissipated: self.accounting.then_some(self.dissipated),
            residual: self.accounting.then(|| self.energy_residual()),
            not_accurate: self
                .accounting
                .then(|| self.energy_residual())
                .filter(|r| r.abs() > self.energy_initial.abs()),
            solver: (self.solver.solves > 0).then(|| self.solver_report()),
            bodies: self
                .scene
                .bodies
                .iter()
                .map(|b| BodyReport {
                    label: b.label.clone(),
                    method: b.method,
                    particles: b.model.particle_count(),
                })
                .collect(),
            positions: self.positions().map(|p| p.to_array()).collect(),
            velocities: self.velocities().map(|v| v.to_array()).collect(),
            spheres: self
                .states()
                .flat_map(|s| &s.spheres)
                .map(|s| SphereReport {
                    center: s.center.to_array(),
                    radius: s.radius,
                    velocity: s.velocity.to_array(),
                })
                .collect(),
        }
    }

    /// Implicit Euler's solves so far, or `None` when no body uses it.
    #[must_use]
    pub fn solver_report(&self) -> SolverReport {
        let t = &self.solver;
        let n = t.solves.max(1) as f64;
        SolverReport {
            solves: t.solves,
            iterations_max: t.iterations_max,
            iterations_mean: t.iterations_sum as f64 / n,
            residual_max: t.residual_max,
            residual_mean: t.residual_sum / n,
            contact_passes_max: t.passes_max,
            constrained_max: t.constrained_max,
            halved_steps: t.halved_steps,
        }
    }
}

/// Implicit Euler's linear solves over a run, in a [`RunReport`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SolverReport {
    /// Linear solves (steps, plus the halves of halved steps).
    pub solves: u64,
    /// Most conjugate-gradient iterations of one solve (all its contact passes).
    pub iterations_max: u32,
    /// Mean iterations per solve.
    pub iterations_mean: f64,
    /// Largest final relative residual `|r|/|b|` (of the solves whose residual was finite).
    pub residual_max: f64,
    /// Mean final relative residual.
    pub residual_mean: f64,
    /// Most solves of one step (1 + contact passes).
    pub contact_passes_max: u32,
    /// Most particles held by contact constraints in one step.
    pub constrained_max: u32,
    /// Steps the energy guard took again as halves (module docs).
    pub halved_steps: u64,
}

/// One body in a [`RunReport`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BodyReport {
    /// The body's name.
    pub label: String,
    /// Its method.
    pub method: Method,
    /// Its particle count (its positions follow the previous bodies' in `positions`).
    pub particles: usize,
}

/// One dynamic sphere in a [`RunReport`] (cloth scenes).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SphereReport {
    /// Centre (m).
    pub center: [f64; 3],
    /// Radius (m).
    pub radius: f64,
    /// Velocity (m/s).
    pub velocity: [f64; 3],
}

/// What `springlab run --json` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// Scene name.
    pub scene: String,
    /// Method name (bodies' methods joined by `,` when they differ).
    pub method: String,
    /// Time step (s).
    pub dt: f64,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Particle count.
    pub particles: usize,
    /// Spring count.
    pub springs: usize,
    /// Force evaluations.
    pub force_evals: u64,
    /// Wall-clock time of the stepping (s).
    pub wall_seconds: f64,
    /// Where and why the run diverged, or null.
    pub diverged: Option<Divergence>,
    /// Energy at the end (J).
    pub energy: Energy,
    /// Total energy at the start of the accounting (J).
    pub energy_initial: f64,
    /// Energy taken out by dampers, drag, contacts and the method (J); null when accounting is
    /// off.
    pub dissipated: Option<Dissipated>,
    /// `energy.total + dissipated.total - energy_initial` (J): the method's own energy error;
    /// null when accounting is off.
    pub residual: Option<f64>,
    /// The residual (J) when it is larger than the starting energy, `|residual| > |E₀|`: the run
    /// stayed bounded but the method created (or removed) more energy than the scene has, so
    /// its motion is not to be trusted (issue 26); null otherwise.
    pub not_accurate: Option<f64>,
    /// Implicit Euler's linear solves; the key is left out when no body uses it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverReport>,
    /// The bodies and their methods.
    pub bodies: Vec<BodyReport>,
    /// Final positions (m).
    pub positions: Vec<[f64; 3]>,
    /// Final velocities (m/s).
    pub velocities: Vec<[f64; 3]>,
    /// The dynamic spheres at the end, every body's in order; the key is left out when there are
    /// none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub spheres: Vec<SphereReport>,
}
