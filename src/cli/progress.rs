//! The progress bar of long work (terminal only, after a second).

use std::fmt;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar on standard error that appears only on a terminal and only once the work has
/// taken a second; piped or redirected output stays free of it. Off a terminal there is no bar
/// at all (`bar` is `None`), so a short run's timing holds no bar's set-up (indicatif parses its
/// templates when a bar is made).
pub struct Progress {
    bar: Option<ProgressBar>,
    start: Instant,
    shown: bool,
}

impl Progress {
    /// A bar of `len` units labelled `label`. On a terminal it appears after a second even
    /// when no unit is done by then (a study's first run can be long), and then redraws twice
    /// a second.
    #[must_use]
    pub fn new(len: u64, label: &str) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::hidden();
            bar.set_length(len);
            if let Ok(style) = ProgressStyle::with_template(
                "{msg} {bar:30} {pos}/{len} elapsed {elapsed} eta {eta}",
            ) {
                bar.set_style(style);
            }
            bar.set_message(label.to_string());
            let later = bar.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_secs(1));
                if !later.is_finished() {
                    later.set_draw_target(ProgressDrawTarget::stderr());
                    later.enable_steady_tick(Duration::from_millis(500));
                }
            });
            bar
        });
        Progress {
            bar,
            start: Instant::now(),
            shown: false,
        }
    }

    fn reveal(&mut self) {
        if let Some(bar) = &self.bar
            && !self.shown
            && self.start.elapsed() >= Duration::from_secs(1)
        {
            bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
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

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
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
