//! The outcome of grading: [`Report`], its rubric table, its JSON and Gradescope's `results.json`.
//!
//! The Gradescope file follows the autograder specification ("Autograder Specifications",
//! gradescope-autograders.readthedocs.io, section "Output format"): a top-level `score`,
//! `output` and `tests`, each test with `name`, `score`, `max_score`, `status`, `output` and
//! `visibility`. The top level also carries `max_score` (Gradescope ignores it; it keeps the file
//! self-describing) and `execution_time` in seconds.

use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

/// One part of the course's grade the tool cannot judge (a written report, bonus work).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NotGraded {
    /// What it is, for example "report".
    pub name: String,
    /// Its points within the course's maximum (0 for a bonus on top of it).
    pub points: f64,
    /// Who grades it instead.
    pub reason: String,
}

/// Why a check failed: the case, what was expected, what came back, and what to look at.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Feedback {
    /// The input of the failing case.
    pub input: String,
    /// The reference answer.
    pub expected: String,
    /// The student's answer.
    pub got: String,
    /// What is probably wrong.
    pub hint: String,
}

/// What happened to one check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CheckOutcome {
    /// Every case agreed with the reference.
    Passed,
    /// A case disagreed; the check's points are lost.
    Failed,
    /// The item stopped before this check (an earlier check panicked, timed out or returned a
    /// number that is not finite), or the crate did not build.
    NotRun,
}

/// One check of an item.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    /// What the check establishes.
    pub name: String,
    /// Points earned.
    pub score: f64,
    /// Points available.
    pub max_score: f64,
    /// Passed, failed or not run.
    pub outcome: CheckOutcome,
    /// Why it failed (failed checks, and the check that stopped the item).
    pub feedback: Option<Feedback>,
}

/// How an item ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ItemStatus {
    /// Every check passed.
    Full,
    /// Some checks passed.
    Partial,
    /// No check passed.
    Zero,
    /// A check panicked: that check scores zero.
    Panicked,
    /// A check returned NaN or an infinite number: that check scores zero.
    NotFinite,
    /// A check did not finish within the time limit: that check and the item's later checks
    /// score zero.
    TimedOut,
    /// The student's program ended during a check (exit, abort, stack overflow, out of memory):
    /// that check scores zero.
    Crashed,
    /// The student's program answered something the grader cannot read: that check scores zero.
    Malformed,
    /// The crate did not build, or the grading process did not finish: nothing was run.
    NotRun,
}

impl ItemStatus {
    /// A short word for the table.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            ItemStatus::Full => "ok",
            ItemStatus::Partial => "partial",
            ItemStatus::Zero => "failed",
            ItemStatus::Panicked => "panicked",
            ItemStatus::NotFinite => "NaN/inf",
            ItemStatus::TimedOut => "timed out",
            ItemStatus::Crashed => "crashed",
            ItemStatus::Malformed => "bad answer",
            ItemStatus::NotRun => "not run",
        }
    }
}

/// One rubric item: a course task with its points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ItemReport {
    /// Stable identifier, for example `rk4`.
    pub id: String,
    /// The course's rubric category, for example "integrators".
    pub category: String,
    /// The item's name, for example "RK4".
    pub name: String,
    /// Points earned.
    pub score: f64,
    /// Points available.
    pub max_score: f64,
    /// How it ended.
    pub status: ItemStatus,
    /// What happened when a check panicked, timed out, crashed the program, answered something
    /// unreadable or was not finite.
    pub reason: Option<String>,
    /// The checks, in the order they ran.
    pub checks: Vec<CheckReport>,
}

impl ItemReport {
    /// "category: name", or the name alone when the course has no categories.
    #[must_use]
    pub fn label(&self) -> String {
        if self.category.is_empty() {
            self.name.clone()
        } else {
            format!("{}: {}", self.category, self.name)
        }
    }

    /// The feedback of this item as text: one block per failed check (and the reason the item
    /// stopped, if it did); empty when every check passed.
    #[must_use]
    pub fn feedback_text(&self) -> String {
        let mut out = String::new();
        if let Some(reason) = &self.reason {
            let _ = writeln!(out, "{reason}");
        }
        for check in &self.checks {
            let verdict = match check.outcome {
                CheckOutcome::Passed => continue,
                CheckOutcome::Failed => "failed",
                CheckOutcome::NotRun => "not run",
            };
            let _ = writeln!(
                out,
                "- {} ({} of {} points): {verdict}",
                check.name,
                points(check.score),
                points(check.max_score)
            );
            if let Some(f) = &check.feedback {
                for (label, text) in [
                    ("input", &f.input),
                    ("expected", &f.expected),
                    ("got", &f.got),
                    ("hint", &f.hint),
                ] {
                    if !text.is_empty() {
                        let _ = writeln!(out, "    {label:<9} {text}");
                    }
                }
            }
        }
        if out.is_empty() {
            out.push_str("all checks passed\n");
        }
        out
    }
}

/// The result of grading one homework crate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// `rope`, `jelly` or `cloth`.
    pub assignment: String,
    /// The course and assignment, for example "GAMES101 assignment 8 (2020): rope simulation".
    pub title: String,
    /// Points earned.
    pub score: f64,
    /// Points the tool grades.
    pub max_score: f64,
    /// Points of the whole assignment in the course.
    pub course_max_score: f64,
    /// The parts of the course's grade left out, which make up the difference.
    pub not_graded: Vec<NotGraded>,
    /// The rubric items.
    pub items: Vec<ItemReport>,
    /// The seed of the random cases.
    pub seed: u64,
    /// The time limit of one check (ms).
    pub time_limit_ms: u64,
    /// Wall-clock time of grading (s).
    pub seconds: f64,
    /// The sandbox layers the student's build and program ran under (`springlab grade`), one
    /// line; absent when the code ran in this process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sandbox: Option<String>,
}

/// Points as text: `5`, `2.5`.
#[must_use]
pub fn points(p: f64) -> String {
    if p.fract() == 0.0 {
        format!("{p:.0}")
    } else {
        let s = format!("{p:.2}");
        s.trim_end_matches('0').to_string()
    }
}

impl Report {
    /// "max 80 of the course's 100: the report (20) is graded by hand; ..." or, when nothing is
    /// left out, "max 35 of the course's 35".
    #[must_use]
    pub fn scope(&self) -> String {
        let mut s = format!(
            "max {} of the course's {}",
            points(self.max_score),
            points(self.course_max_score)
        );
        let parts: Vec<String> = self
            .not_graded
            .iter()
            .map(|n| {
                if n.points > 0.0 {
                    format!("{} ({}) {}", n.name, points(n.points), n.reason)
                } else {
                    format!("{} {}", n.name, n.reason)
                }
            })
            .collect();
        if !parts.is_empty() {
            s.push_str(": ");
            s.push_str(&parts.join("; "));
        }
        s
    }

    /// The rubric table followed by the feedback of every item that lost points.
    #[must_use]
    pub fn table(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "springlab grade: {}", self.title);
        let _ = writeln!(
            out,
            "score {} / {}  ({})",
            points(self.score),
            points(self.max_score),
            self.scope()
        );
        if let Some(sandbox) = &self.sandbox {
            let _ = writeln!(out, "{sandbox}");
        }
        let _ = writeln!(out);
        let name_width = self
            .items
            .iter()
            .map(|i| i.label().chars().count())
            .max()
            .unwrap_or(10)
            .max(10);
        let _ = writeln!(out, "  {:<name_width$}  {:>11}  result", "item", "points");
        for item in &self.items {
            let name = item.label();
            let pts = format!("{} / {}", points(item.score), points(item.max_score));
            let _ = writeln!(
                out,
                "  {name:<name_width$}  {pts:>11}  {}",
                item.status.label()
            );
        }
        // Nothing ran (the build failed, the run crashed): one reason for every item.
        let first_reason = self.items.first().and_then(|i| i.reason.as_ref());
        if self
            .items
            .iter()
            .all(|i| i.status == ItemStatus::NotRun && i.reason.as_ref() == first_reason)
        {
            if let Some(reason) = first_reason {
                let _ = writeln!(out);
                let _ = writeln!(out, "nothing was graded: {reason}");
            }
            return out;
        }
        let lost: Vec<&ItemReport> = self
            .items
            .iter()
            .filter(|i| i.status != ItemStatus::Full)
            .collect();
        if !lost.is_empty() {
            let _ = writeln!(out);
            let _ = writeln!(out, "feedback");
            for item in lost {
                let _ = writeln!(
                    out,
                    "{} ({} / {})",
                    item.label(),
                    points(item.score),
                    points(item.max_score)
                );
                for line in item.feedback_text().lines() {
                    let _ = writeln!(out, "  {line}");
                }
            }
        }
        out
    }

    /// The report as pretty JSON (the shape of this struct).
    ///
    /// # Errors
    /// Never in practice (serialising plain data); the error is serde_json's.
    pub fn to_json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(self)
    }

    /// Gradescope's `results.json` (module docs).
    #[must_use]
    pub fn gradescope(&self) -> serde_json::Value {
        let tests: Vec<serde_json::Value> = self
            .items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                serde_json::json!({
                    "name": item.label(),
                    "number": (i + 1).to_string(),
                    "score": item.score,
                    "max_score": item.max_score,
                    "status": if item.score == item.max_score { "passed" } else { "failed" },
                    "output": item.feedback_text(),
                    "visibility": "visible",
                })
            })
            .collect();
        serde_json::json!({
            "score": self.score,
            "max_score": self.max_score,
            "execution_time": self.seconds,
            "output": format!(
                "{}\nscore {} / {} ({}){}",
                self.title,
                points(self.score),
                points(self.max_score),
                self.scope(),
                self.sandbox.as_ref().map(|s| format!("\n{s}")).unwrap_or_default()
            ),
            "visibility": "visible",
            "stdout_visibility": "hidden",
            "tests": tests,
        })
    }
}

/// Writes `bytes` to `path` as the grader's result: into a temporary file created beside it
/// with `O_CREAT | O_EXCL | O_NOFOLLOW` (never through a link, never over another file), then
/// renamed onto `path`. Whatever is at `path` and is not a regular file (a FIFO, a symbolic
/// link, a device, a folder) is refused, neither followed nor opened.
///
/// # Errors
/// A sentence naming the path and what was found or what failed.
pub fn write_result(path: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write as _;
    use std::os::unix::fs::OpenOptionsExt;
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        let ft = meta.file_type();
        if !ft.is_file() {
            use std::os::unix::fs::FileTypeExt;
            let what = if ft.is_symlink() {
                "a symbolic link"
            } else if ft.is_fifo() {
                "a FIFO"
            } else if ft.is_dir() {
                "a folder"
            } else if ft.is_char_device() || ft.is_block_device() {
                "a device"
            } else if ft.is_socket() {
                "a socket"
            } else {
                "not a regular file"
            };
            return Err(format!(
                "{}: refusing to write a result over {what} (remove it, or choose another path)",
                path.display()
            ));
        }
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "result".to_string());
    let tmp = dir.join(format!(".{name}.{}.tmp", super::token::random_tag()));
    let io = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o644)
        .custom_flags(nix::libc::O_NOFOLLOW)
        .open(&tmp)
        .map_err(io)?;
    let written = file.write_all(bytes).and_then(|()| file.sync_all());
    drop(file);
    if let Err(e) = written.and_then(|()| std::fs::rename(&tmp, path)) {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}
