//! The progress bar of long work (terminal only, after a second).

use std::fmt;
use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{HumanDuration, ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};

use crate::physics::pool::JobEvent;

/// A progress bar on standard error that appears only on a terminal and only once the work has
/// taken a second; piped or redirected output stays free of it. Off a terminal there is no bar
/// at all (`bar` is `None`), so a short run's timing holds no bar's set-up (indicatif parses its
/// templates when a bar is made).
///
/// The bar is one line, its label cut to the terminal's width (a line that wrapped would be
/// redrawn on the line below at every tick). It is shown once, by whichever comes first after a
/// second: a timer thread, or an update (a second `set_draw_target` would start a new bar below
/// the first and leave the first on the screen). Its time left says `…` until a unit is done.
pub struct Progress {
    bar: Option<ProgressBar>,
    start: Instant,
    shown: Arc<AtomicBool>,
    /// [`Progress::job`]: the names of the jobs running, and how many have ended.
    running: Vec<String>,
    ended: u64,
}

impl Progress {
    /// A bar of `len` units labelled `label`. On a terminal it appears after a second even
    /// when no unit is done by then (a study's first run can be long), and then redraws twice
    /// a second.
    #[must_use]
    pub fn new(len: u64, label: &str) -> Progress {
        let shown = Arc::new(AtomicBool::new(false));
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::hidden();
            bar.set_length(len);
            if let Ok(style) = ProgressStyle::with_template(
                "{wide_msg} {bar:20} {pos}/{len} {elapsed} · {left} left",
            ) {
                bar.set_style(style.with_key("left", time_left));
            }
            bar.set_message(label.to_string());
            let later = bar.clone();
            let once = Arc::clone(&shown);
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_secs(1));
                if !later.is_finished() {
                    show(&later, &once);
                }
            });
            bar
        });
        Progress {
            bar,
            start: Instant::now(),
            shown,
            running: Vec::new(),
            ended: 0,
        }
    }

    fn reveal(&mut self) {
        if let Some(bar) = &self.bar
            && self.start.elapsed() >= Duration::from_secs(1)
        {
            show(bar, &self.shown);
        }
    }

    /// Sets the position.
    pub fn set(&mut self, position: u64) {
        if let Some(bar) = &self.bar {
            bar.set_position(position);
        }
        self.reveal();
    }

    /// Advances by `n`.
    pub fn inc(&mut self, n: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(n);
        }
        self.reveal();
    }

    /// Changes the label.
    pub fn label(&mut self, label: String) {
        if let Some(bar) = &self.bar {
            bar.set_message(label);
        }
        self.reveal();
    }

    /// Job `name`, one of several running side by side (a study's runs over the cores),
    /// started or ended (`event`): the bar counts the jobs ended, and its label is `scene`
    /// followed by the names of those running (or "finishing" once none is).
    pub fn job(&mut self, scene: &str, name: String, event: JobEvent) {
        match event {
            JobEvent::Started => self.running.push(name),
            JobEvent::Finished => {
                self.running.retain(|r| *r != name);
                self.ended += 1;
            }
        }
        let label = if self.running.is_empty() {
            format!("{scene}: finishing")
        } else {
            format!("{scene}: {}", self.running.join(", "))
        };
        self.label(label);
        self.set(self.ended);
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Shows `bar` on standard error unless `shown` says it already is.
fn show(bar: &ProgressBar, shown: &AtomicBool) {
    if !shown.swap(true, Ordering::SeqCst) {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        bar.enable_steady_tick(Duration::from_millis(500));
    }
}

/// The time left at the rate so far (`…` before the first unit is done, when there is no rate).
fn time_left(state: &ProgressState, w: &mut dyn fmt::Write) {
    let _ = if state.pos() == 0 {
        write!(w, "…")
    } else {
        write!(w, "{:#}", HumanDuration(state.eta()))
    };
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(bar) = &self.bar
            && !bar.is_finished()
        {
            bar.finish_and_clear();
        }
    }
}

impl fmt::Debug for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Progress")
            .field("enabled", &self.bar.is_some())
            .field("shown", &self.shown)
            .finish_non_exhaustive()
    }
}
