//! What the event loop leaves to other threads so that no key waits for a computation: a step's
//! text numbers and study charts (the newest step wins, [`StepWorker`]) and the `e` exports (in
//! order, [`Exports`]). Outside the event loop (tests, tools) the run computes them at once.

use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, Sender};

use super::background::Latest;
use super::memo::{self, Memo};
use crate::lesson::Plot;
use crate::render::Camera;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::tui::pane::SpringFilter;
use crate::tui::plots::Studies;

/// What a newly opened step computes from its front matter and its scene.
pub struct StepInputs {
    /// The step's text with its placeholders.
    pub text: String,
    /// The step's scene name or path and its parameters.
    pub name: String,
    pub params: Vec<String>,
    /// The step's plots (the study charts among them are computed).
    pub plots: Vec<Plot>,
    /// The step's scene at `t = 0`.
    pub scene: Scene,
}

/// The step's text with its numbers and its study charts.
#[derive(Clone)]
pub struct StepWork {
    pub text: String,
    pub studies: Studies,
}

/// The last steps' work ([`super::memo`]).
static STEP_WORK: Memo<StepWork> = Memo::new(memo::KEPT);

/// Computes what a step shows beside its scene (kept: a step opened again finds it at once).
#[must_use]
pub fn step_work(i: StepInputs) -> StepWork {
    let key = memo::key(&(&i.text, &i.name, &i.params, &i.plots, &i.scene));
    STEP_WORK.get_or(key, || {
        let studies = Studies::compute(&i.plots, &i.name, &i.params);
        let text = crate::lesson::numbers::fill(&i.text, &i.name, &i.params, Some(i.scene));
        StepWork { text, studies }
    })
}

/// The worker of [`step_work`].
pub type StepWorker = Latest<StepInputs, StepWork>;

impl Default for StepWorker {
    fn default() -> Self {
        Latest::new("springlab-step", step_work)
    }
}

/// `text` with every `{{…}}` placeholder shown as `…` while its number is computed.
#[must_use]
pub fn placeholders_pending(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find("{{") {
        let Some(close) = rest[open..].find("}}") else {
            break;
        };
        out.push_str(&rest[..open]);
        out.push('…');
        rest = &rest[open + close + 2..];
    }
    out.push_str(rest);
    out
}

/// One `e`: the pane's view written as a PNG file.
pub struct Export {
    pub sim: Simulation,
    pub generation: u64,
    pub camera: Camera,
    pub filter: SpringFilter,
    pub aspect: f64,
    pub path: PathBuf,
}

impl Export {
    /// Writes the file; the status line's message.
    #[must_use]
    pub fn write(&self) -> String {
        match crate::tui::export::export_png(
            &self.sim,
            self.generation,
            &self.camera,
            self.filter,
            self.aspect,
            &self.path,
        ) {
            Ok(p) => format!("wrote {}", p.display()),
            Err(e) => e,
        }
    }
}

/// The exports' worker: every export written, in order, on a thread of its own; the messages
/// come back through [`Exports::poll`]. Exports still waiting when the app quits are not
/// written (a file is written whole or not at all).
#[derive(Default)]
pub struct Exports {
    jobs: Option<Sender<Export>>,
    done: Option<Receiver<String>>,
    waiting: usize,
}

impl Exports {
    /// Queues `export`; gives it back when no thread could be started (the caller writes it).
    pub fn send(&mut self, export: Export) -> Result<(), Box<Export>> {
        if self.jobs.is_none() {
            let (jobs, inbox) = mpsc::channel::<Export>();
            let (outbox, done) = mpsc::channel();
            let spawned = std::thread::Builder::new()
                .name("springlab-export".into())
                .spawn(move || {
                    super::background::lower_priority();
                    for job in inbox {
                        if outbox.send(job.write()).is_err() {
                            return;
                        }
                    }
                });
            if spawned.is_err() {
                return Err(Box::new(export));
            }
            self.jobs = Some(jobs);
            self.done = Some(done);
        }
        let Some(jobs) = &self.jobs else {
            return Err(Box::new(export));
        };
        jobs.send(export).map_err(|e| Box::new(e.0))?;
        self.waiting += 1;
        Ok(())
    }

    /// The message of the newest export written since the last call.
    pub fn poll(&mut self) -> Option<String> {
        let mut newest = None;
        if let Some(done) = &self.done {
            while let Ok(m) = done.try_recv() {
                self.waiting = self.waiting.saturating_sub(1);
                newest = Some(m);
            }
        }
        newest
    }

    /// True while an export is being written.
    #[must_use]
    pub fn busy(&self) -> bool {
        self.waiting > 0
    }
}

impl Clone for Exports {
    /// A clone starts without a worker.
    fn clone(&self) -> Self {
        Exports::default()
    }
}

impl std::fmt::Debug for Exports {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Exports")
            .field("waiting", &self.waiting)
            .finish_non_exhaustive()
    }
}
