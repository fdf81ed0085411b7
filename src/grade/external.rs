//! `springlab grade DIR…`: builds each submission's `src/` on its own, runs it as a separate
//! program and grades it from this process.
//!
//! ```text
//! 1. the assignment: --assignment, else DIR/Cargo.toml's [package.metadata.springlab]
//! 2. the code: DIR/src/lib.rs, DIR/lib.rs, or the one DIR/*/src/lib.rs     (build::locate)
//! 3. build it against springlab's manifest and student API, in one shared target directory
//!    (build::prepare, build::build); a build that fails → every item 0, the compiler's errors
//! 4. grade with the rubric in this process; every call of a homework method goes to the
//!    program (remote::Session: limits, time-outs, a new program after a crash)
//! 5. stop the program; the report is this process's own
//! ```
//! A submission that cannot be built or run still gets a report in which every item says why;
//! only a directory whose assignment cannot be told is an error.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use super::build::{self, BuildFailure};
use super::remote::{Limits, Remote, Session};
use super::{Assignment, Options, Report, grade_cloth, grade_jelly, grade_rope};

/// Settings of an external grading run.
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalOptions {
    /// Time limit of one check and seed.
    pub grading: Options,
    /// Limits of the student's program.
    pub limits: Limits,
    /// Longest time one build may take.
    pub build_limit: Duration,
    /// The cargo target directory shared by every build.
    pub target_dir: PathBuf,
    /// The assignment of every submission; `None` reads it from each one's Cargo.toml.
    pub assignment: Option<Assignment>,
}

impl Default for ExternalOptions {
    /// Default grading options and limits, 10 minutes per build, [`build::default_target_dir`].
    fn default() -> ExternalOptions {
        ExternalOptions {
            grading: Options::default(),
            limits: Limits::default(),
            build_limit: Duration::from_secs(10 * 60),
            target_dir: build::default_target_dir(),
            assignment: None,
        }
    }
}

/// What stops `springlab grade` from producing a report for a directory (a report with zero
/// points is not an error).
#[derive(Debug, thiserror::Error)]
pub enum GradeError {
    /// DIR is not a homework crate and no assignment was given.
    #[error("{} is not a homework crate: {reason}", .dir.display())]
    NotACrate {
        /// The directory.
        dir: PathBuf,
        /// What is missing.
        reason: String,
    },
}

/// The assignment named in `dir/Cargo.toml` (`[package.metadata.springlab] assignment`).
///
/// # Errors
/// [`GradeError::NotACrate`] when the file is missing, not TOML, or names no known assignment.
pub fn assignment_of(dir: &Path) -> Result<Assignment, GradeError> {
    let not_a_crate = |reason: String| GradeError::NotACrate {
        dir: dir.to_path_buf(),
        reason,
    };
    if !dir.is_dir() {
        return Err(not_a_crate("no such directory".to_string()));
    }
    let manifest = dir.join("Cargo.toml");
    let text = std::fs::read_to_string(&manifest).map_err(|e| {
        not_a_crate(format!(
            "cannot read Cargo.toml ({e}); give the assignment with --assignment"
        ))
    })?;
    let value: toml::Value = toml::from_str(&text)
        .map_err(|e| not_a_crate(format!("Cargo.toml is not valid TOML ({e})")))?;
    let name = value
        .get("package")
        .and_then(|p| p.get("metadata"))
        .and_then(|m| m.get("springlab"))
        .and_then(|s| s.get("assignment"))
        .and_then(toml::Value::as_str)
        .ok_or_else(|| {
            not_a_crate(
                "Cargo.toml has no [package.metadata.springlab] assignment; make the crate with \
                 `springlab homework new DIR --assignment rope|jelly|cloth`, or give --assignment"
                    .to_string(),
            )
        })?;
    Assignment::from_name(name).ok_or_else(|| {
        not_a_crate(format!(
            "unknown assignment `{name}` in Cargo.toml; expected rope, jelly or cloth"
        ))
    })
}

/// True when `dir` looks like one submission: a Cargo.toml, `src/lib.rs` or `lib.rs` in it.
#[must_use]
pub fn is_submission(dir: &Path) -> bool {
    dir.join("Cargo.toml").is_file()
        || dir.join("src/lib.rs").is_file()
        || dir.join("lib.rs").is_file()
}

/// The submissions named by `paths`: each path that is a submission, and for each other
/// directory its subdirectories that are (a class folder), sorted by name; each once.
#[must_use]
pub fn expand(paths: &[PathBuf]) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = Vec::new();
    for path in paths {
        if is_submission(path) || !path.is_dir() {
            out.push(path.clone());
            continue;
        }
        let mut members: Vec<PathBuf> = std::fs::read_dir(path)
            .map(|entries| {
                entries
                    .filter_map(Result::ok)
                    .map(|e| e.path())
                    .filter(|p| p.is_dir() && is_submission(p))
                    .collect()
            })
            .unwrap_or_default();
        members.sort();
        if members.is_empty() {
            out.push(path.clone());
        } else {
            out.extend(members);
        }
    }
    // The same submission twice would be built twice into one directory at once.
    let mut seen = std::collections::BTreeSet::new();
    out.retain(|p| seen.insert(std::path::absolute(p).unwrap_or_else(|_| p.clone())));
    out
}

/// Builds and grades the submission in `dir` (module docs). `progress` receives one line per
/// stage.
///
/// # Errors
/// [`GradeError`] only when the assignment is neither given nor in `dir/Cargo.toml`; a
/// submission that does not build, crashes or hangs gets a report that says so.
pub fn grade_crate(
    dir: &Path,
    options: &ExternalOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Report, GradeError> {
    let assignment = match options.assignment {
        Some(a) => a,
        None => assignment_of(dir)?,
    };
    Ok(grade_as(dir, assignment, options, progress))
}

fn grade_as(
    dir: &Path,
    assignment: Assignment,
    options: &ExternalOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Report {
    let not_run = |reason: &str| assignment.not_run(reason, &options.grading);
    let target =
        std::path::absolute(&options.target_dir).unwrap_or_else(|_| options.target_dir.clone());
    let submission = match build::locate(dir) {
        Ok(s) => s,
        Err(why) => return not_run(&format!("nothing to build: {why}")),
    };
    progress(&format!("building {}", dir.display()));
    let prepared = match build::prepare(&submission, assignment, &target) {
        Ok(p) => p,
        Err(why) => return not_run(&format!("the submission could not be prepared: {why}")),
    };
    let exe = match build::build(&prepared, &target, options.build_limit) {
        Ok(exe) => exe,
        Err(BuildFailure::Compile(errors)) => {
            return not_run(&format!("the crate did not build:\n{errors}"));
        }
        Err(BuildFailure::TimedOut(limit)) => {
            return not_run(&format!(
                "the build did not finish within {} s",
                limit.as_secs()
            ));
        }
        Err(BuildFailure::Cargo(why)) => {
            return not_run(&format!("the grader could not build the crate: {why}"));
        }
    };
    progress(&format!("grading {}", dir.display()));
    let remote = Remote::new(
        Session::new(exe, assignment, options.limits),
        options.grading.time_limit,
    );
    let report = match assignment {
        Assignment::Rope => grade_rope(remote.clone(), &options.grading),
        Assignment::Jelly => grade_jelly(remote.clone(), &options.grading),
        Assignment::Cloth => grade_cloth(remote.clone(), &options.grading),
    };
    remote.shut_down();
    report
}

/// Grades every directory of `dirs` with `jobs` submissions at a time (at least one); results
/// in the order of `dirs`.
pub fn grade_all(
    dirs: &[PathBuf],
    options: &ExternalOptions,
    jobs: usize,
    progress: &(dyn Fn(&str) + Sync),
) -> Vec<Result<Report, GradeError>> {
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<Result<Report, GradeError>>>> =
        dirs.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, dirs.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(dir) = dirs.get(i) else { break };
                    let result = grade_crate(dir, options, progress);
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(result);
                    }
                }
            });
        }
    });
    results
        .into_iter()
        .zip(dirs)
        .map(|(slot, dir)| {
            slot.into_inner().ok().flatten().unwrap_or_else(|| {
                Err(GradeError::NotACrate {
                    dir: dir.clone(),
                    reason: "grading stopped".to_string(),
                })
            })
        })
        .collect()
}
