//! Rebuilt on every save: the crate's `src/` and `Cargo.toml` are watched (the `notify` crate,
//! inotify on Linux); a change rebuilds it on a thread of its own and reports
//! [`Reload::Building`], then [`Reload::Reloaded`] or [`Reload::Failed`] with the compiler's
//! first error. Changes that come within 150 ms of each other are one rebuild (an editor's save
//! writes several files).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread;
use std::time::Duration;

use notify::{RecursiveMode, Watcher as _};

use super::super::build::Builder;
use super::build::{BuildOptions, Built, LazyBuilder, build_homework};

/// What the watcher reports.
#[derive(Debug)]
pub enum Reload {
    /// A change was seen; the crate is being built.
    Building,
    /// The new build, ready to run.
    Reloaded(Box<Built>),
    /// The build failed: why (the compiler's first error, bounded).
    Failed(String),
}

impl Reload {
    /// The status line's word for it.
    #[must_use]
    pub fn status(&self) -> String {
        match self {
            Reload::Building => "building…".to_string(),
            Reload::Reloaded(_) => "reloaded".to_string(),
            Reload::Failed(why) => why.clone(),
        }
    }
}

/// A crate being watched; dropping it stops watching and building.
pub struct Watcher {
    _watcher: notify::RecommendedWatcher,
    reloads: Receiver<Reload>,
}

impl std::fmt::Debug for Watcher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Watcher").finish_non_exhaustive()
    }
}

impl Watcher {
    /// Builds the crate in `dir` at once (the first [`Reload`]) and again after every change.
    ///
    /// # Errors
    /// A sentence when the folder cannot be watched.
    pub fn start(
        dir: &Path,
        builder: Arc<Builder>,
        options: BuildOptions,
    ) -> Result<Watcher, String> {
        Watcher::start_lazy(dir, LazyBuilder::made(builder), options)
    }

    /// As [`Watcher::start`], the builder made (or taken from an earlier attach) on the build
    /// thread: nothing here starts a process. A builder that cannot be made is the first
    /// [`Reload::Failed`].
    ///
    /// # Errors
    /// A sentence when the folder cannot be watched.
    pub fn start_lazy(
        dir: &Path,
        builder: LazyBuilder,
        options: BuildOptions,
    ) -> Result<Watcher, String> {
        let (changes_tx, changes) = mpsc::channel::<()>();
        let mut watcher =
            notify::recommended_watcher(move |event: notify::Result<notify::Event>| {
                if let Ok(e) = event
                    && !matches!(e.kind, notify::EventKind::Access(_))
                {
                    let _ = changes_tx.send(());
                }
            })
            .map_err(|e| format!("cannot watch {}: {e}", dir.display()))?;
        let src = dir.join("src");
        let watched: [(PathBuf, RecursiveMode); 2] = [
            (src, RecursiveMode::Recursive),
            (dir.join("Cargo.toml"), RecursiveMode::NonRecursive),
        ];
        for (path, mode) in &watched {
            if path.exists() {
                watcher
                    .watch(path, *mode)
                    .map_err(|e| format!("cannot watch {}: {e}", path.display()))?;
            }
        }
        let (tx, reloads) = mpsc::channel();
        let dir = dir.to_path_buf();
        thread::Builder::new()
            .name("homework-build".to_string())
            .spawn(move || {
                // Below the app's drawing thread (nice 10, as the app's other workers): a
                // build must not slow the answer to a key.
                #[cfg(target_os = "linux")]
                let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), 10);
                if tx.send(Reload::Building).is_err() {
                    return;
                }
                match builder.get(&options) {
                    Ok(builder) => rebuild_loop(&dir, &builder, &options, &changes, &tx),
                    Err(why) => {
                        let _ = tx.send(Reload::Failed(why));
                    }
                }
            })
            .map_err(|e| format!("cannot start the build thread: {e}"))?;
        Ok(Watcher {
            _watcher: watcher,
            reloads,
        })
    }

    /// The next report, if one came.
    #[must_use]
    pub fn try_next(&self) -> Option<Reload> {
        self.reloads.try_recv().ok()
    }

    /// The next report, waiting up to `wait`.
    #[must_use]
    pub fn next(&self, wait: Duration) -> Option<Reload> {
        self.reloads.recv_timeout(wait).ok()
    }
}

fn rebuild_loop(
    dir: &Path,
    builder: &Arc<Builder>,
    options: &BuildOptions,
    changes: &Receiver<()>,
    tx: &Sender<Reload>,
) {
    loop {
        let report = match build_homework(dir, builder, options) {
            Ok(built) => Reload::Reloaded(Box::new(built)),
            Err(why) => Reload::Failed(why),
        };
        if tx.send(report).is_err() {
            return;
        }
        // Wait for a change, then for 150 ms of quiet.
        if changes.recv().is_err() {
            return;
        }
        loop {
            match changes.recv_timeout(Duration::from_millis(150)) {
                Ok(()) => {}
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => return,
            }
        }
        if tx.send(Reload::Building).is_err() {
            return;
        }
    }
}
