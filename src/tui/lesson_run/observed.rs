//! The scene's observable watched as the run goes (lesson 8, the `observable` plot): the
//! studies' own definition (`study::observe`: a cloth's sag, a jelly's centroid height and
//! largest compression so far) read every [`SAMPLE_EVERY`] seconds of simulated time, and the
//! value the recorded resolution study gives for this body, when it has one.

use crate::study::observe::{Observable, Value};

use crate::simulation::Simulation;

/// Simulated time between two readings (s): fine enough for an impact's compression, which
/// lasts tens of milliseconds.
pub const SAMPLE_EVERY: f64 = 0.002;

/// Most readings kept: beyond it every other one is dropped (the curve keeps its shape).
const MAX_SAMPLES: usize = 4096;

/// The observable's readings over time.
#[derive(Clone, Debug, Default)]
pub struct Observed {
    observable: Option<Observable>,
    /// Per component: its name with unit, as the legend shows it.
    pub names: Vec<String>,
    /// Per reading: the time (s) and every component's headline value.
    pub samples: Vec<(f64, Vec<f64>)>,
    next: f64,
}

impl Observed {
    /// Watches `sim` from its present state when `on`, nothing otherwise.
    #[must_use]
    pub fn new(sim: &Simulation, on: bool) -> Observed {
        if !on {
            return Observed::default();
        }
        let mut observed = Observed {
            observable: Some(Observable::of(&sim.scene)),
            ..Observed::default()
        };
        observed.record(sim);
        observed
    }

    /// Reads the observable when its next reading is due.
    pub fn record(&mut self, sim: &Simulation) {
        let Some(observable) = &mut self.observable else {
            return;
        };
        let t = sim.time();
        if t + 1e-12 < self.next {
            return;
        }
        self.next = t + SAMPLE_EVERY;
        let observation = observable.watch(sim);
        let shown: Vec<_> = observation
            .components
            .iter()
            .filter(|c| !matches!(c.value, Value::Time(_)))
            .collect();
        if self.names.is_empty() {
            self.names = shown
                .iter()
                .map(|c| format!("{} ({})", c.headline_name(), c.unit.symbol()))
                .collect();
        }
        self.samples
            .push((t, shown.iter().map(|c| c.headline()).collect()));
        if self.samples.len() > MAX_SAMPLES {
            let mut i = 0;
            self.samples.retain(|_| {
                i += 1;
                i % 2 == 1
            });
        }
    }

    /// The latest reading of every component.
    #[must_use]
    pub fn latest(&self) -> Option<&(f64, Vec<f64>)> {
        self.samples.last()
    }
}
