//! A homework crate built into a [`Homework`] through the grader's own path (copy, sandboxed
//! build, cache by content, a [`Remote`] session), and the grader's hint for one integrator.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use super::super::build::{self, BuildFailure, Builder};
use super::super::external::{self, ExternalOptions};
use super::super::remote::{Limits, Place, Remote, Session};
use super::super::{Assignment, ItemStatus, Options, grade_cloth, grade_jelly, grade_rope};
use super::{Homework, Integrator};

/// Where and how a crate is built and run.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// The grader's build cache (`springlab-grade/` beneath it); builds are cached by content.
    pub target_dir: PathBuf,
    /// Deadline of one call of the student's code.
    pub call_limit: Duration,
}

impl Default for BuildOptions {
    /// The grader's default cache, 2 s per call.
    fn default() -> BuildOptions {
        BuildOptions {
            target_dir: build::default_target_dir(),
            call_limit: Duration::from_secs(2),
        }
    }
}

/// A built crate.
#[derive(Clone)]
pub struct Built {
    /// Its assignment (from its Cargo.toml).
    pub assignment: Assignment,
    /// The program behind the homework trait.
    pub homework: Homework,
    /// The same program as a [`Remote`].
    pub remote: Remote,
    /// The program came from the cache (the sources did not change).
    pub cached: bool,
    exe: PathBuf,
    place: Place,
}

impl std::fmt::Debug for Built {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Built")
            .field("assignment", &self.assignment)
            .field("exe", &self.exe)
            .field("cached", &self.cached)
            .finish_non_exhaustive()
    }
}

/// The sandbox and build folders for a session of live comparisons (one per app run).
///
/// # Errors
/// A sentence: the build cache cannot be made or written.
pub fn builder(options: &BuildOptions) -> Result<Arc<Builder>, String> {
    let external = ExternalOptions {
        target_dir: options.target_dir.clone(),
        ..ExternalOptions::default()
    };
    external::builder(&external).map_err(|e| e.to_string())
}

/// The session's [`Builder`], made by [`builder`] the first time a build thread asks for it and
/// shared from then on (clones share it). Making one probes the sandbox (it starts processes)
/// and the cache folder: tens of milliseconds on a loaded machine, so the app's `H` asks for it
/// on the build thread, never on the drawing thread, and only once however often it is pressed.
#[derive(Clone, Debug, Default)]
pub struct LazyBuilder(Arc<OnceLock<Result<Arc<Builder>, String>>>);

impl LazyBuilder {
    /// A builder already made.
    #[must_use]
    pub fn made(builder: Arc<Builder>) -> LazyBuilder {
        LazyBuilder(Arc::new(OnceLock::from(Ok(builder))))
    }

    /// The builder, made now with `options` when no clone made it before (waiting while
    /// another thread makes it).
    ///
    /// # Errors
    /// As [`builder`] (the first attempt's sentence, kept).
    pub fn get(&self, options: &BuildOptions) -> Result<Arc<Builder>, String> {
        self.0.get_or_init(|| builder(options)).clone()
    }
}

/// The first compiler error of `output`: from the first line starting with `error` up to
/// the next blank line, at most 12 lines and 1200 characters.
#[must_use]
pub fn first_error(output: &str) -> String {
    let lines: Vec<&str> = output.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.starts_with("error"))
        .unwrap_or(0);
    let mut kept: Vec<&str> = Vec::new();
    for line in &lines[start..] {
        if !kept.is_empty() && line.trim().is_empty() {
            break;
        }
        kept.push(line);
        if kept.len() == 12 {
            break;
        }
    }
    let mut text = kept.join("\n");
    if text.len() > 1200 {
        let mut cut = 1200;
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        text.truncate(cut);
        text.push('…');
    }
    text
}

/// Builds the crate in `dir` with `builder` (job slot 0) and starts nothing yet: the program
/// starts at the first call.
///
/// # Errors
/// A sentence for the status line: not a homework crate, the compiler's first error, a build
/// limit, or the grader's own failure.
pub fn build_homework(
    dir: &Path,
    builder: &Arc<Builder>,
    options: &BuildOptions,
) -> Result<Built, String> {
    let assignment = external::assignment_of(dir).map_err(|e| e.to_string())?;
    let submission = build::locate(dir).map_err(|why| format!("nothing to build: {why}"))?;
    let failure = |e: BuildFailure| match e {
        BuildFailure::Compile(errors) => {
            format!("your crate did not build: {}", first_error(&errors))
        }
        BuildFailure::TimedOut(limit) => {
            format!("the build did not finish within {} s", limit.as_secs_f64())
        }
        BuildFailure::Limit(why) => format!("the build was stopped: {why}"),
        BuildFailure::Grader(why) => format!("grader error (not your code's fault): {why}"),
    };
    let staged = builder.stage(&submission, assignment).map_err(failure)?;
    let built = builder.build(&staged, 0).map_err(failure)?;
    let place = Place {
        builder: Arc::clone(builder),
        slot: 0,
        dir: built.dir.clone(),
    };
    let remote = Remote::new(
        Session::new(
            built.exe.clone(),
            assignment,
            Limits::default(),
            place.clone(),
        ),
        options.call_limit,
    );
    let homework = Homework::Program(remote.clone());
    Ok(Built {
        assignment,
        homework,
        remote,
        cached: built.cached,
        exe: built.exe,
        place,
    })
}

/// The grader's verdict on `integrator` of the built crate: the hint of its first failed check,
/// or that it found no fault. Grades the whole assignment with a program of its own (job slot
/// 1), so it takes as long as `springlab grade`; run it off the drawing thread.
#[must_use]
pub fn grader_hint(built: &Built, integrator: Integrator) -> String {
    let place = Place {
        slot: 1,
        ..built.place.clone()
    };
    let remote = Remote::new(
        Session::new(
            built.exe.clone(),
            built.assignment,
            Limits::default(),
            place,
        ),
        Duration::from_secs(10),
    );
    let options = Options::default();
    let report = match built.assignment {
        Assignment::Rope => grade_rope(remote.clone(), &options),
        Assignment::Jelly => grade_jelly(remote.clone(), &options),
        Assignment::Cloth => grade_cloth(remote.clone(), &options),
    };
    remote.shut_down();
    built.place.builder.sandbox.sweep(1);
    let name = integrator.name();
    for item in report
        .items
        .iter()
        .filter(|i| integrator.items().contains(&i.id.as_str()))
    {
        if item.status == ItemStatus::Full {
            continue;
        }
        if let Some(f) = item.checks.iter().find_map(|c| c.feedback.as_ref()) {
            let text = format!(
                "grader on {name}(): expected {}, got {}; hint: {}",
                f.expected, f.got, f.hint
            );
            return first_error(&text);
        }
        if let Some(reason) = &item.reason {
            return format!("grader on {name}(): {reason}");
        }
    }
    format!("the grader finds no fault in your {name}()")
}
