//! Running a scene: stepping every body, counting force evaluations, detecting divergence, and
//! the report `springlab run` prints.

use glam::DVec3;
use serde::Serialize;

use crate::physics::{Divergence, Energy, Method, State, Workspace, collide, diverge, energy};
use crate::scene::Scene;

/// A scene in motion.
#[derive(Clone, Debug)]
pub struct Simulation {
    /// The scene, whose bodies' states advance.
    pub scene: Scene,
    /// The time step (s).
    dt: f64,
    work: Vec<Workspace>,
    /// Steps taken.
    pub steps: u64,
    /// Force evaluations so far, over all bodies.
    pub force_evals: u64,
    /// Set when a step diverged; no further step is taken.
    pub diverged: Option<Divergence>,
    /// Simulated time when `dt` last changed (s), and the step count then.
    time_base: (f64, u64),
}

impl Simulation {
    /// A simulation of `scene` at its default `dt`.
    #[must_use]
    pub fn new(scene: Scene) -> Simulation {
        let dt = scene.dt;
        let work = scene.bodies.iter().map(|_| Workspace::new()).collect();
        Simulation {
            scene,
            dt,
            work,
            steps: 0,
            force_evals: 0,
            diverged: None,
            time_base: (0.0, 0),
        }
    }

    /// The time step (s).
    #[must_use]
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Changes the time step (s). Verlet's history belongs to the old step and is dropped.
    ///
    /// # Panics
    /// If `dt` is not positive and finite (callers validate user input first).
    pub fn set_dt(&mut self, dt: f64) {
        assert!(dt > 0.0 && dt.is_finite(), "dt must be positive");
        self.time_base = (self.time(), self.steps);
        self.dt = dt;
        for b in &mut self.scene.bodies {
            b.state.history_valid = false;
        }
    }

    /// Simulated time (s): `steps · dt`, counted from the last change of `dt` (no drift from
    /// summing `dt`).
    #[must_use]
    pub fn time(&self) -> f64 {
        let (t0, s0) = self.time_base;
        t0 + (self.steps - s0) as f64 * self.dt
    }

    /// Takes one step of every body; returns the divergence if this step produced one.
    /// Does nothing once diverged.
    pub fn step(&mut self) -> Option<&Divergence> {
        if self.diverged.is_some() {
            return None;
        }
        for (body, work) in self.scene.bodies.iter_mut().zip(&mut self.work) {
            self.force_evals +=
                body.method
                    .step(&body.model, &mut body.state, self.dt, &body.params, work);
            // Colliders and dynamic spheres (returns at once when the body has neither).
            collide::after_step(&body.model, &mut body.state, self.dt);
        }
        self.steps += 1;
        let time = self.time();
        for body in &self.scene.bodies {
            if let Some(d) = diverge::check(&body.state, self.steps, time) {
                self.diverged = Some(d);
                return self.diverged.as_ref();
            }
        }
        None
    }

    /// Takes up to `n` steps, stopping at divergence; calls `after_step` after each one.
    pub fn run(&mut self, n: u64, mut after_step: impl FnMut(&Simulation)) {
        for _ in 0..n {
            if self.diverged.is_some() {
                break;
            }
            self.step();
            after_step(self);
        }
    }

    /// Total energy over all bodies.
    #[must_use]
    pub fn energy(&self) -> Energy {
        self.scene
            .bodies
            .iter()
            .map(|b| energy(&b.model, &b.state))
            .fold(Energy::default(), Energy::plus)
    }

    /// Every body's positions, concatenated.
    pub fn positions(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.scene
            .bodies
            .iter()
            .flat_map(|b| b.state.x.iter().copied())
    }

    /// Every body's velocities, concatenated.
    pub fn velocities(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.scene
            .bodies
            .iter()
            .flat_map(|b| b.state.v.iter().copied())
    }

    /// Sets every body's method.
    pub fn set_method(&mut self, method: Method) {
        self.scene.set_method(method);
    }

    /// The body states (for example to compare with an exact solution).
    pub fn states(&self) -> impl Iterator<Item = &State> {
        self.scene.bodies.iter().map(|b| &b.state)
    }

    /// The report of `springlab run` (see DESIGN.md's JSON contract).
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
