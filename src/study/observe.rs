//! A scene's answer: the observable that `study resolution` and `advise` compare between
//! models, methods and time steps.
//!
//! # The observables
//!
//! Each body of a scene contributes the components of its shape, recognised from its struct
//! springs ([`crate::render::surface::Lattice`]):
//!
//! ```text
//! body        component         unit  definition
//! jelly/cube  centroid          m     mean position of the body's particles at t = T
//!             max compression   m     max over 0 ≤ t ≤ T of  ∛V_0 - ∛V(t)
//! cloth       sag               m     h_pins - min_i y_i(T)
//!             contact time      s     first t with a particle within r + ε of a sphere's centre
//! other       end point         m     the last particle's position at t_k = k T / 20, k = 1 … 20
//! ```
//! where `V(t)` (m³) is the volume inside the cube's six outer faces (each lattice quad split
//! into two triangles, `V = Σ (x_0 · (x_1 × x_2))/6` with outward normals), so the compression
//! is the shortening of the edge of the cube of equal volume: a length, independent of how the
//! body turns and of how finely it is divided; `h_pins` (m) is the mean initial height of the
//! pinned particles (of all particles when none is pinned); `r` (m) a sphere's radius and `ε`
//! (m) the scene's contact band. A cloth that touches a sphere from the start (the 2024 cloth
//! over its sphere) has no contact time: the component is left out. The rope's end point is
//! sampled at 20 instants, so its component is a trajectory.
//!
//! # The difference of two observations
//!
//! ```text
//! point        |a - b|                          m
//! trajectory   max_k |a_k - b_k|                m
//! length       |a - b|                          m
//! time         |min(a, T) - min(b, T)|          s      "never within T" counts as T
//! ```
//! An observation is within a tolerance `X` of another when every component is: lengths and
//! positions within `X` metres, times within `X` seconds. A run that diverged has no
//! observation and is never within a tolerance.

use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use crate::budget;
use crate::physics::Method;
use crate::render::surface::Lattice;
use crate::scene::Scene;
use crate::simulation::Simulation;

/// Instants at which a trajectory is sampled (and the number of steps of every measured run is
/// a multiple of it, so every run samples the same instants).
pub const SAMPLES: u64 = 20;

/// The unit of a component.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Unit {
    /// Metres: positions and lengths.
    #[serde(rename = "m")]
    Metre,
    /// Seconds: times.
    #[serde(rename = "s")]
    Second,
}

impl Unit {
    /// `m` or `s`.
    #[must_use]
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::Metre => "m",
            Unit::Second => "s",
        }
    }
}

/// The value of one component.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// A position (m).
    Point([f64; 3]),
    /// Positions at the sample instants `k T / SAMPLES` (m).
    Trajectory(Vec<[f64; 3]>),
    /// A length (m).
    Length(f64),
    /// An instant (s), or `null` when the event did not happen within `T`.
    Time(Option<f64>),
}

/// One component of an observation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Component {
    /// For example `centroid`, or `jelly 2 centroid` when the scene has several bodies.
    pub name: String,
    /// Its unit.
    pub unit: Unit,
    /// Its value.
    pub value: Value,
}

impl Component {
    /// The number a table shows for it: a point's height (y), a trajectory's last height, a
    /// length, a time (NaN for "never").
    #[must_use]
    pub fn headline(&self) -> f64 {
        match &self.value {
            Value::Point(p) => p[1],
            Value::Trajectory(t) => t.last().map_or(f64::NAN, |p| p[1]),
            Value::Length(x) => *x,
            Value::Time(t) => t.unwrap_or(f64::NAN),
        }
    }

    /// What [`Component::headline`] shows, for a table's header: `centroid y`, `sag`, ….
    #[must_use]
    pub fn headline_name(&self) -> String {
        match &self.value {
            Value::Point(_) => format!("{} y", self.name),
            Value::Trajectory(_) => format!("{} y(T)", self.name),
            _ => self.name.clone(),
        }
    }
}

/// What one run gives: a value per component.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Observation {
    /// The components, body by body.
    pub components: Vec<Component>,
}

/// The difference of two observations (module docs), per component and at worst.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Difference {
    /// One per component, in its unit.
    pub components: Vec<f64>,
    /// The largest difference of a position or length (m).
    pub metres: f64,
    /// The largest difference of a time (s); 0 when there is no time component.
    pub seconds: f64,
}

impl Difference {
    /// A difference that fails every tolerance (a diverged run).
    #[must_use]
    pub fn infinite(components: usize) -> Difference {
        Difference {
            components: vec![f64::INFINITY; components],
            metres: f64::INFINITY,
            seconds: f64::INFINITY,
        }
    }

    /// True when every component is within `tolerance` (m for lengths, s for times).
    #[must_use]
    pub fn within(&self, tolerance: f64) -> bool {
        self.metres <= tolerance && self.seconds <= tolerance
    }

    /// The larger of the two, for ordering and display (m or s).
    #[must_use]
    pub fn worst(&self) -> f64 {
        self.metres.max(self.seconds)
    }
}

impl Observation {
    /// The difference from `other` (module docs); `horizon` (s) stands in for a time that never
    /// came.
    #[must_use]
    pub fn difference(&self, other: &Observation, horizon: f64) -> Difference {
        let mut components = Vec::with_capacity(self.components.len());
        let (mut metres, mut seconds) = (0.0f64, 0.0f64);
        for (a, b) in self.components.iter().zip(&other.components) {
            let d = match (&a.value, &b.value) {
                (Value::Point(p), Value::Point(q)) => {
                    DVec3::from_array(*p).distance(DVec3::from_array(*q))
                }
                (Value::Trajectory(p), Value::Trajectory(q)) => p
                    .iter()
                    .zip(q)
                    .map(|(p, q)| DVec3::from_array(*p).distance(DVec3::from_array(*q)))
                    .fold(0.0, f64::max),
                (Value::Length(p), Value::Length(q)) => (p - q).abs(),
                (Value::Time(p), Value::Time(q)) => {
                    (p.unwrap_or(horizon).min(horizon) - q.unwrap_or(horizon).min(horizon)).abs()
                }
                _ => f64::INFINITY,
            };
            // NaN (a non-finite position) never passes.
            let d = if d.is_nan() { f64::INFINITY } else { d };
            match a.unit {
                Unit::Metre => metres = metres.max(d),
                Unit::Second => seconds = seconds.max(d),
            }
            components.push(d);
        }
        if self.components.len() != other.components.len() {
            metres = f64::INFINITY;
        }
        Difference {
            components,
            metres,
            seconds,
        }
    }
}

/// What is tracked of one body during a run.
#[derive(Clone, Debug)]
enum Tracker {
    /// A jelly cube: its outer faces and the largest compression so far (m).
    Block {
        quads: Vec<[u32; 4]>,
        edge0: f64,
        compression: f64,
    },
    /// A cloth: the pins' height (m) and the first contact with a sphere (s).
    Grid {
        pin_height: f64,
        track_contact: bool,
        contact: Option<f64>,
    },
    /// Anything else: its last particle, sampled.
    Last {
        index: usize,
        samples: Vec<[f64; 3]>,
    },
}

/// The observable of a scene: which components each body has (module docs).
#[derive(Clone, Debug)]
pub struct Observable {
    trackers: Vec<(String, Tracker)>,
}

/// The volume (m³) inside a jelly cube's outer faces at positions `x` (module docs), or `None`
/// for a body that is not a lattice block.
#[must_use]
pub fn block_volume(model: &crate::physics::Model, x: &[DVec3]) -> Option<f64> {
    match Lattice::detect(model) {
        Some(lattice @ Lattice::Block { .. }) => Some(volume(&lattice.quads(), x)),
        _ => None,
    }
}

/// The volume (m³) inside the closed surface `quads` (outward normals) of positions `x`.
fn volume(quads: &[[u32; 4]], x: &[DVec3]) -> f64 {
    let mut six_v = 0.0;
    for q in quads {
        let [a, b, c, d] = q.map(|i| x[i as usize]);
        six_v += a.dot(b.cross(c)) + a.dot(c.cross(d));
    }
    six_v / 6.0
}

/// True when a particle of `x` is within the contact band of a sphere of `spheres`.
fn touches(x: &[DVec3], spheres: &[crate::physics::collide::DynamicSphere], band: f64) -> bool {
    spheres.iter().any(|s| {
        let reach = s.radius + band;
        x.iter()
            .any(|p| p.distance_squared(s.center) <= reach * reach)
    })
}

impl Observable {
    /// The observable of `scene` in its initial state.
    #[must_use]
    pub fn of(scene: &Scene) -> Observable {
        let many = scene.bodies.len() > 1;
        let trackers = scene
            .bodies
            .iter()
            .map(|b| {
                let prefix = if many {
                    format!("{} ", b.label)
                } else {
                    String::new()
                };
                let tracker = match Lattice::detect(&b.model) {
                    Some(lattice @ Lattice::Block { .. }) => {
                        let quads = lattice.quads();
                        let edge0 = volume(&quads, &b.state.x).max(0.0).cbrt();
                        Tracker::Block {
                            quads,
                            edge0,
                            compression: 0.0,
                        }
                    }
                    Some(Lattice::Grid { .. }) => {
                        let pinned: Vec<f64> = (0..b.model.particle_count())
                            .filter(|&i| b.model.is_pinned(i))
                            .map(|i| b.state.x[i].y)
                            .collect();
                        let heights = if pinned.is_empty() {
                            b.state.x.iter().map(|x| x.y).collect()
                        } else {
                            pinned
                        };
                        let pin_height = heights.iter().sum::<f64>() / heights.len().max(1) as f64;
                        let band = b.model.contact.epsilon;
                        let track_contact = !b.state.spheres.is_empty()
                            && !touches(&b.state.x, &b.state.spheres, band);
                        Tracker::Grid {
                            pin_height,
                            track_contact,
                            contact: None,
                        }
                    }
                    None => Tracker::Last {
                        index: b.model.particle_count().saturating_sub(1),
                        samples: Vec::new(),
                    },
                };
                (prefix, tracker)
            })
            .collect();
        Observable { trackers }
    }

    /// The names and units of the components, in order (for headers and the definition).
    #[must_use]
    pub fn names(&self) -> Vec<(String, Unit)> {
        let mut names = Vec::new();
        for (prefix, t) in &self.trackers {
            match t {
                Tracker::Block { .. } => {
                    names.push((format!("{prefix}centroid"), Unit::Metre));
                    names.push((format!("{prefix}max compression"), Unit::Metre));
                }
                Tracker::Grid { track_contact, .. } => {
                    names.push((format!("{prefix}sag"), Unit::Metre));
                    if *track_contact {
                        names.push((format!("{prefix}contact time"), Unit::Second));
                    }
                }
                Tracker::Last { .. } => names.push((format!("{prefix}end point"), Unit::Metre)),
            }
        }
        names
    }

    /// The definition of every component in words, for the output.
    #[must_use]
    pub fn definition(&self, horizon: f64) -> String {
        let mut parts = Vec::new();
        for (prefix, t) in &self.trackers {
            parts.push(match t {
                Tracker::Block { .. } => format!(
                    "{prefix}centroid: mean particle position at t = {horizon} s (m); \
                     {prefix}max compression: max over t ≤ {horizon} s of ∛V0 - ∛V(t), V the \
                     volume inside the outer faces (m)"
                ),
                Tracker::Grid { track_contact, .. } => {
                    let contact = if *track_contact {
                        format!(
                            "; {prefix}contact time: first t with a particle within the contact \
                             band of a sphere (s)"
                        )
                    } else {
                        " (touching a sphere from the start: no contact time)".to_string()
                    };
                    format!(
                        "{prefix}sag: height of the pins minus the lowest particle at t = \
                         {horizon} s (m){contact}"
                    )
                }
                Tracker::Last { .. } => format!(
                    "{prefix}end point: the last particle's position at t = k·{horizon}/{SAMPLES} \
                     s, k = 1…{SAMPLES} (m; compared at every instant)"
                ),
            });
        }
        parts.join("; ")
    }

    /// True when a component looks at every step (a cube's largest compression, a cloth's first
    /// contact); otherwise only the sample instants matter.
    fn per_step(&self) -> bool {
        self.trackers.iter().any(|(_, t)| match t {
            Tracker::Block { .. } => true,
            Tracker::Grid { track_contact, .. } => *track_contact,
            Tracker::Last { .. } => false,
        })
    }

    /// Records what a step did: called after every step with the simulation's time (s) (or,
    /// when [`Observable::per_step`] is false, at least at every sample instant).
    fn after_step(&mut self, sim: &Simulation, step: u64, steps: u64) {
        let sample_every = (steps / SAMPLES).max(1);
        let time = sim.time();
        for ((_, t), body) in self.trackers.iter_mut().zip(&sim.scene.bodies) {
            match t {
                Tracker::Block {
                    quads,
                    edge0,
                    compression,
                } => {
                    let c = *edge0 - volume(quads, &body.state.x).max(0.0).cbrt();
                    if c > *compression || c.is_nan() {
                        *compression = c;
                    }
                }
                Tracker::Grid {
                    track_contact,
                    contact,
                    ..
                } => {
                    if *track_contact
                        && contact.is_none()
                        && touches(
                            &body.state.x,
                            &body.state.spheres,
                            body.model.contact.epsilon,
                        )
                    {
                        *contact = Some(time);
                    }
                }
                Tracker::Last { index, samples } => {
                    if step.is_multiple_of(sample_every) {
                        samples.push(body.state.x[*index].to_array());
                    }
                }
            }
        }
    }

    /// What the observable reads at the simulation's present instant, for a run watched as it
    /// goes (the lesson app samples it every few milliseconds of simulated time): the instant is
    /// recorded as a step would record it (the largest compression and the contact time so far)
    /// and the observation so far is returned. An end point's samples are not kept here.
    pub fn watch(&mut self, sim: &Simulation) -> Observation {
        for ((_, t), body) in self.trackers.iter_mut().zip(&sim.scene.bodies) {
            if let Tracker::Last { samples, index } = t {
                samples.clear();
                samples.push(body.state.x[*index].to_array());
            }
        }
        self.after_step(sim, 1, 1);
        self.finish(sim)
    }

    /// The observation at the end of a run.
    fn finish(&self, sim: &Simulation) -> Observation {
        let mut components = Vec::new();
        for ((prefix, t), body) in self.trackers.iter().zip(&sim.scene.bodies) {
            match t {
                Tracker::Block { compression, .. } => {
                    components.push(Component {
                        name: format!("{prefix}centroid"),
                        unit: Unit::Metre,
                        value: Value::Point(body.state.centroid().to_array()),
                    });
                    components.push(Component {
                        name: format!("{prefix}max compression"),
                        unit: Unit::Metre,
                        value: Value::Length(*compression),
                    });
                }
                Tracker::Grid {
                    pin_height,
                    track_contact,
                    contact,
                } => {
                    let lowest = body
                        .state
                        .x
                        .iter()
                        .map(|x| x.y)
                        .fold(f64::INFINITY, f64::min);
                    components.push(Component {
                        name: format!("{prefix}sag"),
                        unit: Unit::Metre,
                        value: Value::Length(pin_height - lowest),
                    });
                    if *track_contact {
                        components.push(Component {
                            name: format!("{prefix}contact time"),
                            unit: Unit::Second,
                            value: Value::Time(*contact),
                        });
                    }
                }
                Tracker::Last { samples, .. } => components.push(Component {
                    name: format!("{prefix}end point"),
                    unit: Unit::Metre,
                    value: Value::Trajectory(samples.clone()),
                }),
            }
        }
        Observation { components }
    }
}

/// The steps of a run of `time` seconds at a step of at most `dt_max` seconds: a multiple of
/// [`SAMPLES`], so that the run ends exactly at `time` and samples the same instants as any
/// other.
#[must_use]
pub fn steps_for(time: f64, dt_max: f64) -> u64 {
    let per_sample = (time / (dt_max * SAMPLES as f64)).ceil().max(1.0);
    // Saturates for absurd inputs; the budget refuses them before anything runs.
    (per_sample as u64).saturating_mul(SAMPLES)
}

/// One measured run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// The method.
    pub method: Method,
    /// Time step (s).
    pub dt: f64,
    /// Steps taken.
    pub steps: u64,
    /// Force evaluations.
    pub force_evals: u64,
    /// Implicit Euler's conjugate-gradient iterations (0 for the other methods).
    pub cg_iterations: u64,
    /// Cost in particle and spring updates (see [`cost`]).
    pub cost: f64,
    /// Wall time of the run (s), this machine.
    pub wall_seconds: f64,
    /// The observation, or `null` when the run diverged.
    pub observation: Option<Observation>,
    /// The observation as it stood at each sample instant `k T / SAMPLES`, `k = 1 …` (the
    /// last one is `observation`): what a verification compares over the whole run.
    #[serde(skip)]
    pub snapshots: Vec<Observation>,
    /// Why the run stopped early, when it diverged.
    pub diverged: Option<String>,
    /// The energy error `E + dissipated - E0` (J) at the end, when measured with the energy
    /// accounting on ([`measure_accounted`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_residual: Option<f64>,
}

/// The cost of a run in particle and spring updates, the unit of the budget
/// ([`crate::budget`]):
///
/// ```text
/// cost = Σ_bodies (E + I) · (N + S + C)
/// ```
/// where `E` is the force evaluations a body's steps took (steps × evaluations per step;
/// Verlet's projection passes and XPBD's substeps counted as evaluations, as the budget does),
/// `I` implicit Euler's conjugate-gradient iterations (each a pass over the springs, like an
/// evaluation), `N` and `S` the body's particles and springs and `C` = [`budget::OVERHEAD`].
/// Repeatable on any machine, unlike wall time.
#[must_use]
pub fn cost(scene: &Scene, steps: u64, force_evals: u64, cg_iterations: u64) -> f64 {
    scene
        .bodies
        .iter()
        .map(|b| {
            let size =
                b.model.particle_count() as f64 + b.model.springs().len() as f64 + budget::OVERHEAD;
            let evals = if b.method == Method::ImplicitEuler {
                // Measured: the energy guard's halved steps cost more than one evaluation.
                (force_evals as f64 / scene.bodies.len() as f64) + cg_iterations as f64
            } else {
                steps as f64 * budget::evaluations_per_step(b.method, &b.params)
            };
            evals * size
        })
        .sum()
}

/// Runs `scene` with `method` for `steps` steps of `dt` seconds, recording the observable's
/// components (energy accounting off: it does not change the motion).
#[must_use]
pub fn measure(scene: &Scene, method: Method, dt: f64, steps: u64) -> Measurement {
    run(scene, method, dt, steps, false, None).unwrap_or_else(|| unreachable!("not cancelled"))
}

/// [`measure`], given up (`None`) at the first sample instant after `cancel` becomes true: a
/// run computed ahead that the search no longer wants ([`super::ahead`]).
#[must_use]
pub fn measure_unless(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    cancel: &std::sync::atomic::AtomicBool,
) -> Option<Measurement> {
    run(scene, method, dt, steps, false, Some(cancel))
}

/// [`measure_unless`] with the energy accounting on or off: the same motion either way (the
/// accounting only adds up what leaves), so one run serves a search that compares the motion
/// and a check that also reads the energy residual.
#[must_use]
pub fn measure_with_unless(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    accounting: bool,
    cancel: &std::sync::atomic::AtomicBool,
) -> Option<Measurement> {
    run(scene, method, dt, steps, accounting, Some(cancel))
}

/// [`measure`] with the energy accounting on, as `springlab run` runs: the same motion, and
/// the energy residual at the end.
#[must_use]
pub fn measure_accounted(scene: &Scene, method: Method, dt: f64, steps: u64) -> Measurement {
    run(scene, method, dt, steps, true, None).unwrap_or_else(|| unreachable!("not cancelled"))
}

fn run(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    accounting: bool,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Option<Measurement> {
    let cancelled = || cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed));
    let mut scene = scene.clone();
    scene.set_method(method);
    let mut observable = Observable::of(&scene);
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    sim.set_accounting(accounting);
    let start = Instant::now();
    let sample_every = (steps / SAMPLES).max(1);
    let mut snapshots = Vec::with_capacity(SAMPLES as usize);
    if observable.per_step() {
        for k in 1..=steps {
            if sim.step().is_some() {
                break;
            }
            observable.after_step(&sim, k, steps);
            if k.is_multiple_of(sample_every) {
                snapshots.push(observable.finish(&sim));
                if cancelled() {
                    return None;
                }
            }
        }
    } else {
        // Only the sample instants are looked at: the steps between them go through
        // `Simulation::advance` (the fused multi-step path where the scene allows it, the same
        // bits as one step at a time).
        let mut k = 0;
        while k < steps && sim.diverged.is_none() {
            let chunk = (sample_every - k % sample_every).min(steps - k);
            sim.advance(chunk);
            if sim.diverged.is_some() {
                break;
            }
            k += chunk;
            observable.after_step(&sim, k, steps);
            if k.is_multiple_of(sample_every) {
                snapshots.push(observable.finish(&sim));
            }
            if cancelled() {
                return None;
            }
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    let solver = sim.solver_report();
    let cg_iterations = (solver.iterations_mean * solver.solves as f64).round() as u64;
    let diverged = sim.diverged.as_ref().map(|d| {
        format!(
            "diverged at t = {:.4e} s (step {}): {}",
            d.time, d.step, d.reason
        )
    });
    Some(Measurement {
        method,
        dt,
        steps: sim.steps,
        force_evals: sim.force_evals,
        cg_iterations,
        cost: cost(&sim.scene, sim.steps, sim.force_evals, cg_iterations),
        wall_seconds,
        observation: diverged.is_none().then(|| observable.finish(&sim)),
        snapshots: if diverged.is_none() {
            snapshots
        } else {
            Vec::new()
        },
        diverged,
        energy_residual: accounting.then(|| sim.energy_residual()),
    })
}

/// The largest difference of two runs over their sample instants: snapshot `k` of each
/// (`k = 1 …`, at `t_k = k T / K`) compared as in [`Observation::difference`] with `t_k` for
/// the horizon, the worst instant per unit. Infinite when either run diverged or they sampled
/// different instants.
#[must_use]
pub fn history_difference(a: &[Observation], b: &[Observation], horizon: f64) -> Difference {
    let count = a.first().or(b.first()).map_or(0, |o| o.components.len());
    if a.is_empty() || a.len() != b.len() {
        return Difference::infinite(count);
    }
    let mut worst = Difference {
        components: vec![0.0; count],
        metres: 0.0,
        seconds: 0.0,
    };
    let len = a.len() as f64;
    for (k, (p, q)) in a.iter().zip(b).enumerate() {
        let d = p.difference(q, horizon * (k + 1) as f64 / len);
        for (w, c) in worst.components.iter_mut().zip(&d.components) {
            *w = w.max(*c);
        }
        worst.metres = worst.metres.max(d.metres);
        worst.seconds = worst.seconds.max(d.seconds);
    }
    worst
}

impl Measurement {
    /// The difference from a reference observation (infinite when this run diverged).
    #[must_use]
    pub fn difference(&self, reference: &Observation, horizon: f64) -> Difference {
        match &self.observation {
            Some(o) => o.difference(reference, horizon),
            None => Difference::infinite(reference.components.len()),
        }
    }
}
