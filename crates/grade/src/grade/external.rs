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
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::build::{self, BuildFailure, BuildLimits, Builder, Staged};
use super::remote::{Limits, Place, Remote, Session};
use super::sandbox::{self, Sandbox};
use super::untrusted::shown_path;
use super::{Assignment, Options, Report, grade_cloth, grade_jelly, grade_rope};

/// Settings of an external grading run.
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalOptions {
    /// Time limit of one check and seed.
    pub grading: Options,
    /// Limits of the student's program.
    pub limits: Limits,
    /// Limits of one build.
    pub build: BuildLimits,
    /// The folder of the grader's build cache (`springlab-grade/` beneath it).
    pub target_dir: PathBuf,
    /// The assignment of every submission; `None` reads it from each one's Cargo.toml.
    pub assignment: Option<Assignment>,
    /// The sandbox's user and the layers left out.
    pub sandbox: sandbox::Config,
    /// Each submission's cases from a seed of its own, made of `grading.seed` and the
    /// submission's code ([`Staged::seed`]): the same code always gets the same cases, changed
    /// code other ones, so answers collected from one submission's feedback do not fit the next.
    pub seed_per_submission: bool,
}

impl Default for ExternalOptions {
    /// Default grading options and limits, [`BuildLimits::default`],
    /// [`build::default_target_dir`], the default sandbox.
    fn default() -> ExternalOptions {
        ExternalOptions {
            grading: Options::default(),
            limits: Limits::default(),
            build: BuildLimits::default(),
            target_dir: build::default_target_dir(),
            assignment: None,
            sandbox: sandbox::Config::default(),
            seed_per_submission: false,
        }
    }
}

/// What stops `springlab grade` from producing a report for a directory (a report with zero
/// points is not an error).
#[derive(Clone, Debug, thiserror::Error)]
pub enum GradeError {
    /// DIR is not a homework crate and no assignment was given.
    #[error("{} is not a homework crate: {reason}", shown_path(.dir))]
    NotACrate {
        /// The directory.
        dir: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// The crate names another assignment than the class's.
    #[error("{} names the {named} assignment in its Cargo.toml, but the class is graded as {class}; give --assignment to grade every crate as one assignment", shown_path(.dir))]
    OtherAssignment {
        /// The directory.
        dir: PathBuf,
        /// What its Cargo.toml names.
        named: &'static str,
        /// The class's assignment.
        class: &'static str,
    },
    /// The grader itself failed (its folders, its toolchain): not the student's doing.
    #[error("grader error (not the submission's fault): {0}")]
    Grader(String),
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
    if std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_file()) {
        return Err(not_a_crate(
            "a lone file names no assignment; give it with --assignment".to_string(),
        ));
    }
    if !dir.is_dir() {
        return Err(not_a_crate("no such directory".to_string()));
    }
    let mut manifest = dir.join("Cargo.toml");
    let present = |p: &Path| std::fs::symlink_metadata(p).is_ok();
    if !present(&manifest)
        && let Ok(found) = build::locate(dir)
        && let Some(krate) = found.src.parent()
        && present(&krate.join("Cargo.toml"))
    {
        // A crate uploaded a folder or more down.
        manifest = krate.join("Cargo.toml");
    }
    // Read as the submission's own file: no link followed, no FIFO waited on, bounded.
    let text = build::read_regular(&manifest, MAX_MANIFEST_BYTES)
        .and_then(|b| String::from_utf8(b).map_err(|_| "not UTF-8".to_string()))
        .map_err(|e| {
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

/// A Cargo.toml larger than this is not read.
const MAX_MANIFEST_BYTES: u64 = 1 << 20;

/// True when `dir` looks like one submission: a Cargo.toml, `src/lib.rs` or `lib.rs` in it.
#[must_use]
pub fn is_submission(dir: &Path) -> bool {
    dir.join("Cargo.toml").is_file()
        || dir.join("src/lib.rs").is_file()
        || dir.join("lib.rs").is_file()
}

/// The submissions named by `paths`: each path that is a submission; for each other directory
/// (a class folder), every folder in it, sorted by name (hidden folders, `target` and symbolic
/// links left out: a class folder's content may come from students), each one submission
/// wherever its crate sits inside ([`build::locate`]); each once.
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
                    .filter(|e| {
                        let name = e.file_name();
                        let name = name.to_string_lossy();
                        !name.starts_with('.') && name != "target"
                    })
                    .map(|e| e.path())
                    .filter(|p| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir()))
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

/// The sandbox and build folders of one run.
///
/// # Errors
/// [`GradeError::Grader`]: the build cache cannot be made or written.
pub fn builder(options: &ExternalOptions) -> Result<Arc<Builder>, GradeError> {
    let target =
        std::path::absolute(&options.target_dir).unwrap_or_else(|_| options.target_dir.clone());
    let sandbox = Arc::new(Sandbox::detect(&options.sandbox));
    Builder::new(&target, sandbox, options.build)
        .map(Arc::new)
        .map_err(GradeError::Grader)
}

/// Copies the submission in `dir` into the run's scratch space (before any student code runs).
fn stage(dir: &Path, assignment: Assignment, builder: &Builder) -> Result<Staged, String> {
    let submission = build::locate(dir).map_err(|why| format!("nothing to build: {why}"))?;
    builder.stage(&submission, assignment).map_err(|e| match e {
        BuildFailure::Grader(why) => format!("grader: {why}"),
        BuildFailure::Compile(why) | BuildFailure::Limit(why) => {
            format!("the submission could not be copied: {why}")
        }
        BuildFailure::TimedOut(_) => "the submission could not be copied".to_string(),
    })
}

/// Builds and grades the submission staged from `dir` as `assignment` in job `slot` (module
/// docs).
///
/// # Errors
/// [`GradeError::Grader`] when the grader fails (its toolchain, its folders); a submission that
/// does not build, crashes or hangs gets a report that says so.
pub fn grade_as(
    dir: &Path,
    staged: Result<Staged, String>,
    assignment: Assignment,
    options: &ExternalOptions,
    builder: &Arc<Builder>,
    slot: u32,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Report, GradeError> {
    let summary = builder.sandbox.summary();
    let not_run = |reason: &str| {
        let mut r = assignment.not_run(reason, &options.grading);
        r.sandbox = Some(summary.clone());
        Ok(r)
    };
    let staged = match staged {
        Ok(s) => s,
        Err(why) => match why.strip_prefix("grader: ") {
            Some(why) => return Err(GradeError::Grader(why.to_string())),
            None => return not_run(&why),
        },
    };
    progress(&format!("building {}", shown_path(dir)));
    let built = match builder.build(&staged, slot) {
        Ok(built) => built,
        Err(BuildFailure::Compile(errors)) => {
            return not_run(&format!("the crate did not build:\n{errors}"));
        }
        Err(BuildFailure::TimedOut(limit)) => {
            return not_run(&format!(
                "the build did not finish within {} s (the build's time limit)",
                limit.as_secs_f64()
            ));
        }
        Err(BuildFailure::Limit(why)) => {
            return not_run(&format!("the build was stopped: {why}"));
        }
        Err(BuildFailure::Grader(why)) => return Err(GradeError::Grader(why)),
    };
    progress(&format!("grading {}", shown_path(dir)));
    let grading = Options {
        seed: if options.seed_per_submission {
            staged.seed(options.grading.seed)
        } else {
            options.grading.seed
        },
        ..options.grading
    };
    let place = Place {
        builder: Arc::clone(builder),
        slot,
        dir: built.dir.clone(),
    };
    let remote = Remote::new(
        Session::new(built.exe, assignment, options.limits, place),
        grading.time_limit,
    );
    let mut report = match assignment {
        Assignment::Rope => grade_rope(remote.clone(), &grading),
        Assignment::Jelly => grade_jelly(remote.clone(), &grading),
        Assignment::Cloth => grade_cloth(remote.clone(), &grading),
    };
    remote.shut_down();
    builder.sandbox.sweep(slot);
    let _ = std::fs::remove_dir_all(&built.dir);
    report.sandbox = Some(summary);
    Ok(report)
}

/// The assignment of each of `dirs`: `--assignment`, else each crate's Cargo.toml; in a class
/// (several submissions) without `--assignment`, the one most crates name, and a crate naming
/// another is an error (it is not graded as what it claims).
fn assignments(dirs: &[PathBuf], given: Option<Assignment>) -> Vec<Result<Assignment, GradeError>> {
    if let Some(a) = given {
        return dirs.iter().map(|_| Ok(a)).collect();
    }
    let named: Vec<Result<Assignment, GradeError>> =
        dirs.iter().map(|d| assignment_of(d)).collect();
    let class = Assignment::ALL.into_iter().max_by_key(|a| {
        (
            named.iter().filter(|n| n.as_ref().ok() == Some(a)).count(),
            // Ties: the first in ALL.
            std::cmp::Reverse(Assignment::ALL.iter().position(|b| b == a)),
        )
    });
    named
        .into_iter()
        .zip(dirs)
        .map(|(n, dir)| match (n, class) {
            (Ok(a), Some(c)) if dirs.len() > 1 && a != c => Err(GradeError::OtherAssignment {
                dir: dir.clone(),
                named: a.name(),
                class: c.name(),
            }),
            (n, _) => n,
        })
        .collect()
}

/// Grades every directory of `dirs` with `jobs` submissions at a time (at least one); results
/// in the order of `dirs`. When the run cannot start (the build cache), every result is that
/// grader error. Returns after every process of the sandbox is gone.
pub fn grade_all(
    dirs: &[PathBuf],
    options: &ExternalOptions,
    jobs: usize,
    progress: &(dyn Fn(&str) + Sync),
) -> Vec<Result<Report, GradeError>> {
    let builder = match builder(options) {
        Ok(b) => b,
        Err(e) => {
            let why = e.to_string();
            return dirs
                .iter()
                .map(|_| Err(GradeError::Grader(why.clone())))
                .collect();
        }
    };
    let assignments = assignments(dirs, options.assignment);
    // Every submission is copied before any student code runs.
    let staged: Vec<Mutex<Option<Result<Staged, String>>>> = dirs
        .iter()
        .zip(&assignments)
        .map(|(dir, a)| Mutex::new(a.as_ref().ok().map(|a| stage(dir, *a, &builder))))
        .collect();
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<Result<Report, GradeError>>>> =
        dirs.iter().map(|_| Mutex::new(None)).collect();
    let workers = jobs.clamp(1, dirs.len().max(1));
    std::thread::scope(|scope| {
        for slot in 0..workers {
            let (next, results, builder, assignments, staged) =
                (&next, &results, &builder, &assignments, &staged);
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(dir) = dirs.get(i) else { break };
                    let result = match &assignments[i] {
                        Ok(a) => {
                            let copy = staged[i]
                                .lock()
                                .ok()
                                .and_then(|mut s| s.take())
                                .unwrap_or_else(|| Err("grader: not staged".to_string()));
                            grade_as(dir, copy, *a, options, builder, slot as u32, progress)
                        }
                        Err(e) => Err(e.clone()),
                    };
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(result);
                    }
                }
            });
        }
    });
    // Nothing of the sandbox may be left when the results are written.
    for slot in 0..workers {
        builder.sandbox.sweep(slot as u32);
    }
    builder.finish();
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
