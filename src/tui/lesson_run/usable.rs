//! The usable dt beside the stability limit (issue 26): stable is not the same as right. The
//! usable dt is the largest dt whose energy residual `|E + D − E₀|` stays within 1 % of `|E₀|`
//! over the scene's duration, searched as `springlab study stability` searches it
//! ([`crate::study::stability::usable`]), here from the damped theory's limit of the present
//! methods down. Where it is lower than the stable limit, the status line shows it as the limit.
//!
//! The search runs the whole scene several times per method, so the app searches only small
//! scenes: at most [`SEARCH_BUDGET`] spring updates in all (the oscillator and the ropes). In the event loop it runs on a worker thread (the newest
//! request winning, [`super::background::Latest`]); results are kept per scene, coefficients and
//! methods, so a key pressed back and forth does not search again. Larger scenes (the jelly, the
//! cloth) show the stable limit only; `springlab study stability SCENE` prints their usable dt.

use std::collections::HashMap;

use super::background::Latest;
use super::memo::{self, Memo};
use crate::physics::Method;
use crate::scene::Scene;
use crate::study::stability::{energy_scale, usable};

/// A search in the app may take at most this many spring updates (springs × steps, summed over
/// its runs and methods): a few tenths of a second on a loaded 2-core machine.
pub const SEARCH_BUDGET: f64 = 2.0e7;

/// What the status line knows about the usable dt of the present methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UsableDt {
    /// The energy stays within 1 % of `|E₀|` below this dt (s): the smallest over the bodies'
    /// methods.
    Below(f64),
    /// A method keeps it nowhere from its stable limit down to 1/1024 of it.
    NoneFound,
    /// The scene is too large to search in the app.
    TooLarge,
}

/// One search: the scene at `t = 0` with its present coefficients and methods, from `start`.
pub struct Inputs {
    pub key: String,
    pub scene: Scene,
    pub start: f64,
}

/// The worker's type.
pub type Worker = Latest<Inputs, (String, UsableDt)>;

impl Default for Worker {
    fn default() -> Self {
        Latest::new("springlab-usable", |i: Inputs| {
            let found = search(&i.scene, i.start);
            (i.key, found)
        })
    }
}

/// The usable dt of `scene` (every body's method in turn, on the whole scene) from `start` (s)
/// down, the smallest deciding; [`UsableDt::TooLarge`] as soon as the runs would pass
/// [`SEARCH_BUDGET`] (a search cut short is never shown).
///
/// Kept for the process by the scene's whole contents ([`super::memo`]): another run of the same
/// step (a step opened again) finds it at once.
#[must_use]
pub fn search(scene: &Scene, start: f64) -> UsableDt {
    SEARCHES.get_or(memo::key(&(scene, start.to_bits())), || {
        search_anew(scene, start)
    })
}

/// The last searches.
static SEARCHES: Memo<UsableDt> = Memo::new(memo::KEPT);

fn search_anew(scene: &Scene, start: f64) -> UsableDt {
    if too_large(scene, start) {
        return UsableDt::TooLarge;
    }
    let allowed = usable::allowed_residual(scene, energy_scale(scene));
    let mut methods: Vec<Method> = Vec::new();
    for b in &scene.bodies {
        if !methods.contains(&b.method) {
            methods.push(b.method);
        }
    }
    let mut spent = 0.0;
    let mut over = false;
    let mut smallest: Option<f64> = None;
    for method in methods {
        let found = usable::search(start, &mut |dt, _next| {
            let cost = run_cost(scene, dt);
            if over || spent + cost > SEARCH_BUDGET {
                over = true;
                return false;
            }
            spent += cost;
            usable::usable_run(scene, method, dt, scene.duration, allowed).passed
        });
        if over {
            return UsableDt::TooLarge;
        }
        match found {
            Some(dt) => smallest = Some(smallest.map_or(dt, |s: f64| s.min(dt))),
            None => return UsableDt::NoneFound,
        }
    }
    smallest.map_or(UsableDt::NoneFound, UsableDt::Below)
}

/// Spring updates of one run of `scene` at `dt` over its duration.
fn run_cost(scene: &Scene, dt: f64) -> f64 {
    scene.spring_count().max(1) as f64 * (scene.duration / dt).ceil()
}

/// True when the search's first run, at `start` (s), would pass [`SEARCH_BUDGET`] alone.
#[must_use]
pub fn too_large(scene: &Scene, start: f64) -> bool {
    let cost = run_cost(scene, start);
    cost.is_nan() || cost > SEARCH_BUDGET
}

/// What a search depends on: every body's method, method settings, masses, springs, drag and
/// pins, the start and the duration.
#[must_use]
pub fn key(scene: &Scene, start: f64) -> String {
    let mut key = format!("{:x} {:x}", start.to_bits(), scene.duration.to_bits());
    for b in &scene.bodies {
        let springs: f64 = b
            .model
            .springs()
            .iter()
            .map(|s| s.stiffness + 1e3 * s.damping)
            .sum();
        let masses: f64 = b.model.inv_mass.iter().sum();
        key.push_str(&format!(
            " {} {:?} {:x} {:x} {:x}",
            b.method,
            b.params,
            springs.to_bits(),
            masses.to_bits(),
            b.model.drag.to_bits()
        ));
    }
    key
}

/// The run's usable dt: the value shown, the search asked for, and the results so far.
#[derive(Clone, Debug, Default)]
pub struct State {
    /// The value for the present limit (`None`: none or still searching).
    pub shown: Option<UsableDt>,
    /// The key of the value shown or being searched.
    wanted: Option<String>,
    cache: HashMap<String, UsableDt>,
    worker: Worker,
}

impl State {
    /// The present stable limit is `start` (s) on `scene` (`None`: no conditional limit):
    /// shows the cached value or searches, on the worker when `deferred`, else at once.
    pub fn refresh(&mut self, scene: Option<Scene>, start: Option<f64>, deferred: bool) {
        let (Some(scene), Some(start)) = (scene, start) else {
            self.shown = None;
            self.wanted = None;
            return;
        };
        let key = key(&scene, start);
        self.wanted = Some(key.clone());
        if let Some(found) = self.cache.get(&key) {
            self.shown = Some(*found);
            return;
        }
        if too_large(&scene, start) {
            self.keep(key, UsableDt::TooLarge);
            return;
        }
        self.shown = None;
        if deferred {
            self.worker.request(Inputs { key, scene, start });
        } else {
            let found = search(&scene, start);
            self.keep(key, found);
        }
    }

    fn keep(&mut self, key: String, found: UsableDt) {
        if self.wanted.as_ref() == Some(&key) {
            self.shown = Some(found);
        }
        self.cache.insert(key, found);
    }

    /// Takes the worker's newest result; true when the value shown changed.
    pub fn poll(&mut self) -> bool {
        let Some((key, found)) = self.worker.poll() else {
            return false;
        };
        let before = self.shown;
        self.keep(key, found);
        self.shown != before
    }

    /// Waits for the newest search (the public key API and tests).
    pub fn settle(&mut self) {
        if let Some((key, found)) = self.worker.settle() {
            self.keep(key, found);
        }
    }

    /// True while the search for the present limit runs.
    #[must_use]
    pub fn pending(&self) -> bool {
        self.shown.is_none() && self.wanted.is_some()
    }
}

impl super::LessonRun {
    /// After the stable limit changed: the usable dt below it (cached, searched, or none).
    pub(super) fn limit_changed(&mut self) {
        let start = match &self.limit {
            Some((super::Limit::Below(dt), _)) => Some(*dt),
            _ => None,
        };
        let scene = start.map(|_| self.scene_at_start());
        self.usable.refresh(scene, start, self.deferred);
    }

    /// The usable dt of the present methods on this scene, when known (see the module docs).
    #[must_use]
    pub fn usable_dt(&self) -> Option<UsableDt> {
        self.usable.shown
    }
}
