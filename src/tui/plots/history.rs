//! What the plots draw from: the run sampled on a grid of simulated time (per-column min/max
//! bins), and the oscillator with its exact motion.

use std::collections::VecDeque;

use glam::DVec3;

use crate::physics::diverge;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::study::convergence::{self};

/// The harmonic oscillator of the `oscillator` scene and its exact motion along the spring:
/// `x(t) = L0 + u(t - t0)`, `u` the damped harmonic motion from the reference state `(u0, v0)` at
/// `t0` ([`convergence::damped_oscillator`], the study's formula). Undamped and from rest at
/// `t0 = 0` this is `x(t) = L0 + A cos(√(k/m) t)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// Mass of the free particle `m` (kg).
    pub mass: f64,
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Damping `k_d` (N·s/m).
    pub damping: f64,
    /// Unit direction of the spring at the start, from particle 0 to particle 1.
    pub axis: DVec3,
    /// Time of the reference state `t0` (s).
    pub t0: f64,
    /// Stretch `u0 = x - L0` at `t0` (m); at `t0 = 0` this is the amplitude `A`.
    pub u0: f64,
    /// Velocity along the spring at `t0` (m/s).
    pub v0: f64,
}

impl Oscillator {
    /// The oscillator of `scene` read from its first state: one body, two particles, particle 0
    /// pinned, one spring between them, no gravity, drag or colliders. `None` for any other
    /// scene.
    #[must_use]
    pub fn detect(scene: &Scene) -> Option<Oscillator> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let (model, state) = (&body.model, &body.state);
        let [spring] = model.springs() else {
            return None;
        };
        let simple = model.particle_count() == 2
            && model.is_pinned(0)
            && !model.is_pinned(1)
            && model.gravity == DVec3::ZERO
            && model.drag == 0.0
            && model.colliders.is_empty()
            && state.spheres.is_empty()
            && ((spring.a, spring.b) == (0, 1) || (spring.a, spring.b) == (1, 0));
        let d = state.x[1] - state.x[0];
        let axis = d.normalize_or_zero();
        if !simple || axis == DVec3::ZERO {
            return None;
        }
        Some(Oscillator {
            rest_length: spring.rest_length,
            mass: model.mass[1],
            stiffness: spring.stiffness,
            damping: spring.damping,
            axis,
            t0: 0.0,
            u0: d.length() - spring.rest_length,
            v0: (state.v[1] - state.v[0]).dot(axis),
        })
    }

    /// The same oscillator restarted from the simulation's present state and coefficients (after
    /// the student changed the stiffness or damping mid-run).
    #[must_use]
    pub fn restarted(&self, sim: &Simulation) -> Oscillator {
        let Some(body) = sim.scene.bodies.first() else {
            return *self;
        };
        let Some(spring) = body.model.springs().first() else {
            return *self;
        };
        Oscillator {
            stiffness: spring.stiffness,
            damping: spring.damping,
            t0: sim.time(),
            u0: self.position(sim) - self.rest_length,
            v0: (body.state.v[1] - body.state.v[0]).dot(self.axis),
            ..*self
        }
    }

    /// Angular frequency `ω0 = √(k/m)` (rad/s).
    #[must_use]
    pub fn omega(&self) -> f64 {
        (self.stiffness / self.mass).sqrt()
    }

    /// The simulated position along the spring axis, `(x_1 - x_0)·axis` (m).
    #[must_use]
    pub fn position(&self, sim: &Simulation) -> f64 {
        sim.scene
            .bodies
            .first()
            .map_or(f64::NAN, |b| (b.state.x[1] - b.state.x[0]).dot(self.axis))
    }

    /// The exact position `L0 + u(t)` (m) at time `t` (s); see the type's documentation.
    #[must_use]
    pub fn exact(&self, t: f64) -> f64 {
        let u = convergence::damped_oscillator(
            self.stiffness,
            self.damping,
            self.mass,
            self.u0,
            self.v0,
            t - self.t0,
        );
        self.rest_length + u
    }
}

/// One sample of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Simulated time (s).
    pub t: f64,
    /// Kinetic energy (J).
    pub kinetic: f64,
    /// Gravitational energy (J).
    pub gravity: f64,
    /// Elastic energy (J).
    pub elastic: f64,
    /// Total energy (J).
    pub total: f64,
    /// Total plus the energy dissipated since the start (J); NaN without accounting.
    pub total_dissipated: f64,
    /// The method's energy error `E + D - E_0` (J); NaN without accounting.
    pub residual: f64,
    /// Largest particle speed (m/s).
    pub max_speed: f64,
    /// `|x_sim - x_exact|` for the oscillator (m); NaN otherwise.
    pub error: f64,
    /// The oscillator's simulated position along its spring (m); NaN otherwise (the whole run
    /// of the exact-vs-simulated plot's full-history mode).
    pub position: f64,
    /// Per body: total energy (J), kinetic energy (J), largest speed (m/s), largest spring
    /// stretch `max |L/L0 - 1|`.
    pub bodies: Vec<[f64; 4]>,
}

impl Sample {
    /// The quantities of a sample as one vector (for the min / max of a bin): the nine scalars,
    /// then four per body.
    fn values(&self) -> Vec<f64> {
        let mut v = vec![
            self.kinetic,
            self.gravity,
            self.elastic,
            self.total,
            self.total_dissipated,
            self.residual,
            self.max_speed,
            self.error,
            self.position,
        ];
        for b in &self.bodies {
            v.extend_from_slice(b);
        }
        v
    }
}

/// Index of a per-body quantity in [`Sample::values`]: body `b`, quantity `q` (0 total, 1
/// kinetic, 2 max speed, 3 stretch).
pub(super) fn body_index(b: usize, q: usize) -> usize {
    SCALARS + 4 * b + q
}

/// Index of the oscillator's position in [`Sample::values`].
pub(super) const POSITION: usize = 8;

/// The quantities of a sample before the per-body ones.
const SCALARS: usize = 9;

/// A stretch of the run: the smallest and largest value of every quantity in it, and its last
/// sample. Long runs merge neighbouring bins, so the plots draw a min / max envelope, never a
/// thinned-out line that misses the peaks.
#[derive(Clone, Debug, PartialEq)]
pub struct Bin {
    /// Simulated time of the first sample (s).
    pub t0: f64,
    /// Simulated time of the last sample (s).
    pub t1: f64,
    /// Per quantity ([`Sample::values`] order): smallest finite value (NaN if none).
    pub lo: Vec<f64>,
    /// Per quantity: largest finite value (NaN if none).
    pub hi: Vec<f64>,
    /// Samples merged into it.
    pub count: u32,
}

impl Bin {
    fn new(s: &Sample) -> Bin {
        let v = s.values();
        Bin {
            t0: s.t,
            t1: s.t,
            lo: v.clone(),
            hi: v,
            count: 1,
        }
    }

    fn merge(&mut self, other: &Bin) {
        self.t1 = other.t1;
        self.count += other.count;
        let pick = |a: f64, b: f64, min: bool| match (a.is_finite(), b.is_finite()) {
            (true, true) => {
                if min {
                    a.min(b)
                } else {
                    a.max(b)
                }
            }
            (true, false) => a,
            _ => b,
        };
        for (i, v) in self.lo.iter_mut().enumerate() {
            *v = pick(*v, other.lo.get(i).copied().unwrap_or(f64::NAN), true);
        }
        for (i, v) in self.hi.iter_mut().enumerate() {
            *v = pick(*v, other.hi.get(i).copied().unwrap_or(f64::NAN), false);
        }
    }
}

/// Most bins kept of the whole run; beyond, neighbours merge in pairs, so the plots always span
/// the whole run with every peak kept.
pub(super) const CAPACITY: usize = 1024;

/// Simulated time between samples (s) when the step is shorter.
pub(super) const SAMPLE_INTERVAL: f64 = 0.01;

/// The sampled history of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct History {
    /// Bins of the whole run, in time order.
    pub bins: Vec<Bin>,
    /// Labels of the bodies (for per-body curves).
    pub labels: Vec<String>,
    /// Simulated time between samples (s).
    pub interval: f64,
    /// Samples per bin: doubles whenever the bins merge.
    pub(super) per_bin: u32,
    pub(super) next: f64,
    /// Recent `(t, x_sim)` of the oscillator, finely sampled, for the exact-solution plot.
    pub recent: VecDeque<(f64, f64)>,
    pub(super) recent_interval: f64,
    pub(super) recent_span: f64,
    pub(super) recent_next: f64,
    /// The exact-vs-simulated plot shows the whole run instead of the last three periods.
    pub full_exact: bool,
}

impl History {
    /// An empty history for a run with time step `dt` (s); `oscillator` sets the fine sampling
    /// of the exact plot (40 samples per period, three periods kept).
    #[must_use]
    pub fn new(dt: f64, oscillator: Option<&Oscillator>) -> History {
        let period = oscillator
            .map(|o| std::f64::consts::TAU / o.omega())
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or(1.0);
        History {
            bins: Vec::new(),
            labels: Vec::new(),
            interval: dt.max(SAMPLE_INTERVAL),
            per_bin: 1,
            next: 0.0,
            recent: VecDeque::new(),
            recent_interval: period / 40.0,
            recent_span: 3.0 * period,
            recent_next: 0.0,
            full_exact: false,
        }
    }

    /// Switches the exact-vs-simulated plot between the whole run and the last three periods;
    /// returns what it shows now (the status message of the `x` key).
    pub fn toggle_full_exact(&mut self) -> String {
        self.full_exact = !self.full_exact;
        if self.full_exact {
            "x(t) vs exact: the whole run (x: the last three periods)".into()
        } else {
            "x(t) vs exact: the last three periods (x: the whole run)".into()
        }
    }

    /// The last sample time (s).
    #[must_use]
    pub fn last_time(&self) -> Option<f64> {
        self.bins.last().map(|b| b.t1)
    }

    /// Records the simulation's state when its time has reached the next sample time.
    pub fn record(&mut self, sim: &Simulation, oscillator: Option<&Oscillator>) {
        let t = sim.time();
        if let Some(o) = oscillator
            && t >= self.recent_next - 1e-12
        {
            self.recent.push_back((t, o.position(sim)));
            while self
                .recent
                .front()
                .is_some_and(|&(t0, _)| t - t0 > self.recent_span)
            {
                self.recent.pop_front();
            }
            self.recent_next = t + self.recent_interval;
        }
        if t < self.next - 1e-12 {
            return;
        }
        self.set_labels(sim);
        let sample = sample(sim, oscillator, t);
        self.push(&sample);
        while self.next <= t + 1e-12 {
            self.next += self.interval;
        }
    }

    /// Records the state a diverged step produced: its time and the speed the divergence check
    /// measured (the last point of the speed plot), and whatever energies are still finite.
    pub fn record_divergence(&mut self, sim: &Simulation, oscillator: Option<&Oscillator>) {
        let Some(d) = &sim.diverged else { return };
        self.set_labels(sim);
        let mut s = sample(sim, oscillator, d.time);
        s.max_speed = d.max_speed;
        self.push(&s);
    }

    fn set_labels(&mut self, sim: &Simulation) {
        if self.labels.len() != sim.scene.bodies.len() {
            self.labels = sim.scene.bodies.iter().map(|b| b.label.clone()).collect();
        }
    }

    fn push(&mut self, sample: &Sample) {
        let bin = Bin::new(sample);
        match self.bins.last_mut() {
            Some(last) if last.count < self.per_bin => last.merge(&bin),
            _ => self.bins.push(bin),
        }
        if self.bins.len() >= CAPACITY {
            let old = std::mem::take(&mut self.bins);
            for pair in old.chunks(2) {
                let mut b = pair[0].clone();
                if let Some(second) = pair.get(1) {
                    b.merge(second);
                }
                self.bins.push(b);
            }
            self.per_bin *= 2;
        }
    }
}

/// The sample of `sim` at time `t`.
pub(super) fn sample(sim: &Simulation, oscillator: Option<&Oscillator>, t: f64) -> Sample {
    let e = sim.energy();
    let mut bodies = Vec::new();
    let mut max_speed = 0.0f64;
    for body in &sim.scene.bodies {
        let be = crate::physics::energy::energy(&body.model, &body.state);
        let speed = diverge::max_speed(&body.state);
        max_speed = if speed.is_nan() || max_speed.is_nan() {
            f64::NAN
        } else {
            max_speed.max(speed)
        };
        let stretch = body
            .model
            .springs()
            .iter()
            .filter(|s| s.rest_length > 0.0)
            .map(|s| {
                let l = (body.state.x[s.a as usize] - body.state.x[s.b as usize]).length();
                (l / s.rest_length - 1.0).abs()
            })
            .fold(0.0f64, f64::max);
        bodies.push([be.total, be.kinetic, speed, stretch]);
    }
    let error = oscillator.map_or(f64::NAN, |o| (o.position(sim) - o.exact(t)).abs());
    let position = oscillator.map_or(f64::NAN, |o| o.position(sim));
    Sample {
        t,
        kinetic: e.kinetic,
        gravity: e.gravity,
        elastic: e.elastic,
        total: e.total,
        total_dissipated: if sim.accounting() {
            e.total + sim.dissipated().total
        } else {
            f64::NAN
        },
        residual: sim.energy_residual(),
        max_speed,
        error,
        position,
        bodies,
    }
}
