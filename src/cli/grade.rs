//! `springlab homework new|autograder` and `springlab grade`: student crates, the Gradescope
//! autograder, and grading one submission or a whole class.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use crate::grade::build::{BuildLimits, default_target_dir};
use crate::grade::external::{ExternalOptions, GradeError, expand, grade_all};
use crate::grade::homework::{new_homework, this_springlab};
use crate::grade::remote::Limits;
use crate::grade::sandbox::{self, Sandbox};
use crate::grade::untrusted::shown_path;
use crate::grade::{Assignment, Options, Report, autograder, points, write_result};

/// Options of `springlab homework`.
#[derive(Debug, Args)]
pub struct HomeworkArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: HomeworkCommand,
}

/// The `homework` subcommands.
#[derive(Debug, Subcommand)]
pub enum HomeworkCommand {
    /// Write a student crate whose `cargo test` grades it.
    New {
        /// A new or empty directory.
        dir: PathBuf,
        /// The assignment: rope (GAMES101 2020), jelly (NYCU 2023) or cloth (NYCU 2022).
        #[arg(long, value_enum)]
        assignment: Assignment,
    },
    /// Write the zip a Gradescope course uploads as the assignment's autograder.
    Autograder {
        /// The assignment: rope, jelly or cloth.
        #[arg(long, value_enum)]
        assignment: Assignment,
        /// The zip file to write.
        #[arg(long, value_name = "FILE", default_value = "autograder.zip")]
        out: PathBuf,
        /// The secret seed of the graded cases [default: a fresh random one]. Each submission's
        /// cases come from it and the submission's code (`grade --seed-per-submission`), never
        /// from the public default seed a student's own `cargo test` uses.
        #[arg(long)]
        seed: Option<u64>,
    },
}

/// Options of `springlab grade`.
#[derive(Debug, Args)]
pub struct GradeArgs {
    /// Homework crates (made by `springlab homework new`), or folders of them (a class: each
    /// folder in it is one submission, wherever its crate sits inside).
    #[arg(required_unless_present = "sandbox_report", value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Print which sandbox layers are active on this machine (and why any is missing), then
    /// stop.
    #[arg(long)]
    pub sandbox_report: bool,
    /// The user id builds and programs run as when springlab runs as root (job k of --jobs:
    /// this + k) [default: $SPRINGLAB_SANDBOX_UID, else 65534, nobody]; 0 keeps root.
    #[arg(long, value_name = "UID")]
    pub sandbox_uid: Option<u32>,
    /// Their group id [default: $SPRINGLAB_SANDBOX_GID, else 65534].
    #[arg(long, value_name = "GID")]
    pub sandbox_gid: Option<u32>,
    /// Wall-clock and CPU limit of one submission's build, in seconds.
    #[arg(long, value_name = "S", default_value_t = 60,
          value_parser = clap::value_parser!(u64).range(1..=3600))]
    pub build_limit_s: u64,
    /// Address space of the compiler, in MiB.
    #[arg(long, value_name = "MB", default_value_t = 3072,
          value_parser = clap::value_parser!(u64).range(512..=1 << 20))]
    pub build_memory_mb: u64,
    /// The assignment, for submissions without springlab's Cargo.toml (just src/ or lib.rs).
    #[arg(long, value_enum)]
    pub assignment: Option<Assignment>,
    /// Write the report as JSON to this file (a list of reports for several submissions).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write Gradescope's results.json to this file (one submission only).
    #[arg(long, value_name = "FILE")]
    pub gradescope: Option<PathBuf>,
    /// Write one line per submission (score and points per item) to this CSV file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Submissions graded at the same time.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub jobs: u32,
    /// Cargo's target directory for the builds, shared by every submission
    /// [default: $CARGO_TARGET_DIR, else ~/.cache/springlab/grade].
    #[arg(long, value_name = "DIR")]
    pub target_dir: Option<PathBuf>,
    /// Time limit of one check, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 10_000,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub time_limit_ms: u64,
    /// Address space of the student's program, in MiB.
    #[arg(long, value_name = "MB", default_value_t = 1024,
          value_parser = clap::value_parser!(u64).range(64..=1 << 20))]
    pub memory_mb: u64,
    /// Seed of the random cases.
    #[arg(long, default_value_t = crate::grade::DEFAULT_SEED)]
    pub seed: u64,
    /// Give each submission cases of its own, from --seed and its code: the same code gets the
    /// same cases, changed code other ones (the autograder's run_autograder sets it).
    #[arg(long)]
    pub seed_per_submission: bool,
}

/// `springlab homework new DIR --assignment A` and `springlab homework autograder`.
///
/// # Errors
/// When DIR is not empty or a file cannot be written.
pub fn homework(args: &HomeworkArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match &args.command {
        HomeworkCommand::New { dir, assignment } => {
            new_homework(dir, *assignment)?;
            writeln!(
                out,
                "wrote the {} homework crate to {}: src/lib.rs (your code), README.md (the \
                 tasks), tests/grade.rs (cargo test grades it)",
                assignment.name(),
                dir.display()
            )?;
            writeln!(
                out,
                "next: cd {} && cargo test   (or: springlab grade {})",
                dir.display(),
                dir.display()
            )?;
        }
        HomeworkCommand::Autograder {
            assignment,
            out: zip,
            seed,
        } => {
            let exe = this_springlab();
            let seed = seed.unwrap_or_else(autograder::secret_seed);
            let bytes = autograder::write(*assignment, &exe, zip, seed)
                .with_context(|| format!("cannot write {}", zip.display()))?;
            writeln!(
                out,
                "wrote {} ({} MiB): setup.sh, run_autograder, springlab, README.txt; upload it \
                 as the autograder of a Gradescope programming assignment",
                zip.display(),
                bytes >> 20
            )?;
            writeln!(
                out,
                "the graded cases come from the secret seed {seed} and each submission's code; \
                 keep the zip from students (`--seed {seed}` makes the same zip again)"
            )?;
        }
    }
    Ok(())
}

/// `springlab grade DIR…`: prints the rubric (one submission) or one line per submission
/// (several); writes the files asked for; exit code 0 whatever the scores.
///
/// # Errors
/// When an output option does not fit the submissions, a submission's assignment cannot be
/// told, or an output file cannot be written.
pub fn grade(args: &GradeArgs) -> anyhow::Result<()> {
    let env_id = |key: &str| {
        std::env::var(key)
            .ok()
            .and_then(|v| v.trim().parse::<u32>().ok())
    };
    let sandbox_config = sandbox::Config {
        uid: args
            .sandbox_uid
            .or_else(|| env_id("SPRINGLAB_SANDBOX_UID"))
            .unwrap_or(sandbox::DEFAULT_UID),
        gid: args
            .sandbox_gid
            .or_else(|| env_id("SPRINGLAB_SANDBOX_GID"))
            .unwrap_or(sandbox::DEFAULT_GID),
        ..sandbox::Config::default()
    };
    if args.sandbox_report {
        let sandbox = Sandbox::detect(&sandbox_config);
        let mut out = std::io::stdout().lock();
        writeln!(out, "{}", sandbox.summary())?;
        out.write_all(sandbox.report().as_bytes())?;
        return Ok(());
    }
    // A path that is not there is the caller's mistake, never a student's 0.
    if let Some(missing) = args.dirs.iter().find(|d| std::fs::metadata(d).is_err()) {
        bail!("{}: no such file or directory", missing.display());
    }
    // With --gradescope the one path is one submission, wherever its code sits inside it.
    let dirs = if args.gradescope.is_some() {
        if args.dirs.len() != 1 {
            bail!("--gradescope writes the results of one submission; give one DIR");
        }
        args.dirs.clone()
    } else {
        expand(&args.dirs)
    };
    let options = ExternalOptions {
        grading: Options {
            time_limit: Duration::from_millis(args.time_limit_ms),
            seed: args.seed,
        },
        limits: Limits {
            memory_bytes: args.memory_mb << 20,
            ..Limits::default()
        },
        build: BuildLimits {
            wall: Duration::from_secs(args.build_limit_s),
            cpu_seconds: args.build_limit_s,
            memory_bytes: args.build_memory_mb << 20,
            ..BuildLimits::default()
        },
        target_dir: args.target_dir.clone().unwrap_or_else(default_target_dir),
        assignment: args.assignment,
        sandbox: sandbox_config,
        seed_per_submission: args.seed_per_submission,
    };
    let show_progress = std::io::stderr().is_terminal();
    let progress = move |line: &str| {
        if show_progress {
            eprintln!("springlab grade: {line}");
        }
    };
    let results = grade_all(&dirs, &options, args.jobs as usize, &progress);
    let mut graded: Vec<(&Path, Report)> = Vec::new();
    let mut errors: Vec<GradeError> = Vec::new();
    for (dir, result) in dirs.iter().zip(results) {
        match result {
            Ok(report) => graded.push((dir, report)),
            Err(e) => errors.push(e),
        }
    }
    // A grader error is the grader's: no file claims a score for it.
    if let Some(e) = errors.iter().find(|e| matches!(e, GradeError::Grader(_))) {
        bail!("{e}");
    }
    // Every file is written before any error is reported.
    if let Some(path) = &args.gradescope
        && let Some((_, report)) = graded.first()
    {
        write_file(path, &serde_json::to_string_pretty(&report.gradescope())?)?;
    }
    if let Some(path) = &args.json {
        let json = if dirs.len() == 1 && graded.len() == 1 {
            graded[0].1.to_json()?
        } else {
            let reports: Vec<&Report> = graded.iter().map(|(_, r)| r).collect();
            serde_json::to_string_pretty(&reports)?
        };
        write_file(path, &json)?;
    }
    if let Some(path) = &args.csv {
        write_file(path, &csv(&graded))?;
    }
    let mut out = std::io::stdout().lock();
    if dirs.len() == 1 {
        if let Some((_, report)) = graded.first() {
            out.write_all(report.table().as_bytes())?;
        }
    } else {
        let width = graded
            .iter()
            .map(|(d, _)| shown_path(d).chars().count())
            .max()
            .unwrap_or(10);
        for (dir, report) in &graded {
            writeln!(
                out,
                "{:<width$}  {:>7} / {:<4}  {}",
                shown_path(dir),
                points(report.score),
                points(report.max_score),
                summary(report)
            )?;
        }
        writeln!(out, "{} submissions graded", graded.len())?;
        if let Some((_, first)) = graded.first()
            && let Some(line) = &first.sandbox
        {
            writeln!(out, "{line}")?;
        }
    }
    // Every problem, one line each; exit status 1 when any submission got no report.
    match errors.len() {
        0 => Ok(()),
        1 => Err(errors.remove(0).into()),
        n => {
            for e in &errors {
                eprintln!("springlab grade: {e}");
            }
            bail!("{n} submissions were not graded (listed above)")
        }
    }
}

/// "all checks passed", why nothing was graded, or the items that lost points.
fn summary(report: &Report) -> String {
    if report
        .items
        .iter()
        .all(|i| i.status == crate::grade::ItemStatus::NotRun)
        && let Some(reason) = report.items.first().and_then(|i| i.reason.as_deref())
    {
        let first = reason.lines().next().unwrap_or_default();
        return format!("not graded: {first}");
    }
    let lost: Vec<String> = report
        .items
        .iter()
        .filter(|i| i.score < i.max_score)
        .map(|i| format!("{} {}", i.id, i.status.label()))
        .collect();
    if lost.is_empty() {
        "all checks passed".to_string()
    } else {
        format!("lost: {}", lost.join(", "))
    }
}

/// A CSV field, quoted when it needs to be.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// One line per submission: `submission,assignment,score,max_score`, then the points of every
/// item (columns named by item id, `assignment.id` when the class mixes assignments).
fn csv(graded: &[(&Path, Report)]) -> String {
    let mut columns: Vec<(String, String)> = Vec::new();
    for (_, report) in graded {
        for item in &report.items {
            let key = (report.assignment.clone(), item.id.clone());
            if !columns.contains(&key) {
                columns.push(key);
            }
        }
    }
    let mixed = graded
        .iter()
        .any(|(_, r)| r.assignment != graded[0].1.assignment);
    let mut out = String::from("submission,assignment,score,max_score");
    for (assignment, id) in &columns {
        out.push(',');
        out.push_str(&field(&if mixed {
            format!("{assignment}.{id}")
        } else {
            id.clone()
        }));
    }
    out.push('\n');
    for (dir, report) in graded {
        out.push_str(&format!(
            "{},{},{},{}",
            field(&dir.display().to_string()),
            report.assignment,
            points(report.score),
            points(report.max_score)
        ));
        for (assignment, id) in &columns {
            out.push(',');
            if *assignment == report.assignment
                && let Some(item) = report.items.iter().find(|i| &i.id == id)
            {
                out.push_str(&points(item.score));
            }
        }
        out.push('\n');
    }
    out
}

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    write_result(path, text.as_bytes()).map_err(anyhow::Error::msg)
}
