//! `springlab grade DIR`: builds and runs a student crate's grading test and collects its report.
//!
//! ```text
//! 1. read DIR/Cargo.toml: [package.metadata.springlab] assignment = "rope" | "jelly" | "cloth"
//! 2. cargo test --release --no-run --test grade --message-format=json-render-diagnostics
//!    (in DIR; the JSON on stdout names the test executable, the diagnostics go to stderr)
//!    build fails      → every item 0, the compiler's errors as feedback
//! 3. run the executable with SPRINGLAB_GRADE_REPORT=DIR/target/springlab-grade/report.json
//!    (and the time limit and seed), with a wall-clock limit for the whole run
//!    no report        → every item 0: the process crashed (abort, stack overflow, exit)
//!    over the limit   → the process is killed; every item 0
//! 4. parse the report
//! ```
//! Running the executable directly (rather than through `cargo test`) means a hung run can be
//! killed: it is the only process involved. The student's own `tests/grade.rs` and `Cargo.toml`
//! are used as they are; to grade untrusted submissions, create a fresh crate with
//! `springlab homework new` and copy only the submission's `src/` into it (see the README).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use super::{Assignment, Options, REPORT_ENV, Report, SEED_ENV, TIME_LIMIT_ENV};

/// Settings of an external grading run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExternalOptions {
    /// Time limit and seed passed to the grading test.
    pub grading: Options,
    /// Longest time the build may take.
    pub build_limit: Duration,
    /// Longest time the grading run may take as a whole.
    pub run_limit: Duration,
}

impl Default for ExternalOptions {
    /// The default grading options, 30 minutes for the build (the first build compiles springlab)
    /// and 10 minutes for the run.
    fn default() -> ExternalOptions {
        ExternalOptions {
            grading: Options::default(),
            build_limit: Duration::from_secs(30 * 60),
            run_limit: Duration::from_secs(10 * 60),
        }
    }
}

/// What stops `springlab grade` from producing a report at all (a report with zero points is
/// not an error).
#[derive(Debug, thiserror::Error)]
pub enum GradeError {
    /// DIR is not a directory with a Cargo.toml.
    #[error("{} is not a homework crate: {reason}", .dir.display())]
    NotACrate {
        /// The directory.
        dir: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// cargo could not be started.
    #[error("cannot run cargo: {0}")]
    Cargo(std::io::Error),
    /// A file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
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
    let text = std::fs::read_to_string(&manifest)
        .map_err(|e| not_a_crate(format!("cannot read Cargo.toml ({e})")))?;
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
                 `springlab homework new DIR --assignment rope|jelly|cloth`"
                    .to_string(),
            )
        })?;
    Assignment::from_name(name).ok_or_else(|| {
        not_a_crate(format!(
            "unknown assignment `{name}` in Cargo.toml; expected rope, jelly or cloth"
        ))
    })
}

/// Output of a finished (or killed) child process.
struct Finished {
    success: bool,
    status: String,
    stdout: String,
    stderr: String,
    timed_out: bool,
}

/// Runs `command` with piped output and a wall-clock `limit`; kills it (by its own handle) when
/// the limit passes.
fn run_limited(mut command: Command, limit: Duration) -> std::io::Result<Finished> {
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let mut bytes = Vec::new();
                let _ = p.read_to_end(&mut bytes);
                text = String::from_utf8_lossy(&bytes).into_owned();
            }
            text
        })
    };
    let out = reader(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = reader(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if start.elapsed() > limit {
            timed_out = true;
            let _ = child.kill();
            break child.wait()?;
        }
        thread::sleep(Duration::from_millis(50));
    };
    Ok(Finished {
        success: status.success() && !timed_out,
        status: status.to_string(),
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
        timed_out,
    })
}

/// The last `n` lines of `text`.
fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// The compiler's error messages in cargo's stderr: everything from the first line starting with
/// `error`, without cargo's progress lines, at most 80 lines; or the tail when there is none.
fn compiler_errors(stderr: &str) -> String {
    let Some(start) = stderr.lines().position(|l| l.starts_with("error")) else {
        return tail(stderr, 30);
    };
    let progress = [
        "Compiling ",
        "Checking ",
        "Building ",
        "Finished ",
        "Downloaded ",
        "Locking ",
    ];
    stderr
        .lines()
        .skip(start)
        .filter(|l| !progress.iter().any(|p| l.trim_start().starts_with(p)))
        .take(80)
        .collect::<Vec<_>>()
        .join("\n")
}

/// The test executable named in cargo's JSON messages.
fn executable(stdout: &str) -> Option<PathBuf> {
    stdout
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v.get("reason").and_then(|r| r.as_str()) == Some("compiler-artifact"))
        .filter(|v| {
            v.get("target")
                .and_then(|t| t.get("name"))
                .and_then(|n| n.as_str())
                == Some("grade")
        })
        .find_map(|v| {
            v.get("executable")
                .and_then(|e| e.as_str())
                .map(PathBuf::from)
        })
}

/// Builds and runs the grading test of the crate in `dir` (module docs) and returns its report.
/// `progress` receives one line per stage.
///
/// # Errors
/// [`GradeError`] when `dir` is not a homework crate, cargo cannot be started, or the report
/// directory cannot be created. A crate that fails to build, crashes or hangs is not an error:
/// its report scores zero and says why.
pub fn grade_crate(
    dir: &Path,
    options: &ExternalOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Report, GradeError> {
    let assignment = assignment_of(dir)?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    progress(&format!(
        "building {} (cargo test --release --no-run; the first build compiles springlab)",
        dir.display()
    ));
    let mut build = Command::new(&cargo);
    build
        .current_dir(dir)
        .args(["test", "--release", "--no-run", "--test", "grade"])
        .arg("--message-format=json-render-diagnostics");
    let built = run_limited(build, options.build_limit).map_err(GradeError::Cargo)?;
    if built.timed_out {
        return Ok(assignment.not_run(
            &format!(
                "the build did not finish within {} s",
                options.build_limit.as_secs()
            ),
            &options.grading,
        ));
    }
    let exe = match (built.success, executable(&built.stdout)) {
        (true, Some(exe)) => exe,
        _ => {
            return Ok(assignment.not_run(
                &format!(
                    "the crate did not build ({}):\n{}",
                    built.status,
                    compiler_errors(&built.stderr)
                ),
                &options.grading,
            ));
        }
    };
    let report_dir = dir.join("target").join("springlab-grade");
    std::fs::create_dir_all(&report_dir).map_err(|source| GradeError::Io {
        path: report_dir.clone(),
        source,
    })?;
    let report_path = report_dir.join("report.json");
    if report_path.exists() {
        std::fs::remove_file(&report_path).map_err(|source| GradeError::Io {
            path: report_path.clone(),
            source,
        })?;
    }
    progress("grading");
    let mut run = Command::new(&exe);
    run.current_dir(dir)
        .env(REPORT_ENV, &report_path)
        .env(
            TIME_LIMIT_ENV,
            options.grading.time_limit.as_millis().max(1).to_string(),
        )
        .env(SEED_ENV, options.grading.seed.to_string());
    let ran = run_limited(run, options.run_limit).map_err(|source| GradeError::Io {
        path: exe.clone(),
        source,
    })?;
    if ran.timed_out {
        return Ok(assignment.not_run(
            &format!(
                "grading did not finish within {} s and was stopped",
                options.run_limit.as_secs()
            ),
            &options.grading,
        ));
    }
    let text = match std::fs::read_to_string(&report_path) {
        Ok(text) => text,
        Err(_) => {
            return Ok(assignment.not_run(
                &format!(
                    "the grading process ended ({}) without a report: it crashed (an abort, a \
                     stack overflow, or a call to process::exit in the homework).\n{}",
                    ran.status,
                    tail(&ran.stderr, 20)
                ),
                &options.grading,
            ));
        }
    };
    serde_json::from_str(&text).map_err(|e| GradeError::Io {
        path: report_path,
        source: std::io::Error::other(e),
    })
}
