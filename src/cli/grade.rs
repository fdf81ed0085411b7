//! `springlab homework new` and `springlab grade`: student crates and their grading.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use clap::{Args, Subcommand};

use crate::grade::external::{ExternalOptions, grade_crate};
use crate::grade::homework::{new_homework, springlab_source_dir};
use crate::grade::{Assignment, Options};

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
}

/// Options of `springlab grade`.
#[derive(Debug, Args)]
pub struct GradeArgs {
    /// A crate made by `springlab homework new`.
    pub dir: PathBuf,
    /// Also write the report as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Also write Gradescope's results.json to this file.
    #[arg(long, value_name = "FILE")]
    pub gradescope: Option<PathBuf>,
    /// Time limit of one check, in milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 10_000,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub time_limit_ms: u64,
    /// Seed of the random cases.
    #[arg(long, default_value_t = crate::grade::DEFAULT_SEED)]
    pub seed: u64,
}

/// `springlab homework new DIR --assignment A`.
///
/// # Errors
/// When DIR is not empty or cannot be written.
pub fn homework(args: &HomeworkArgs) -> anyhow::Result<()> {
    let HomeworkCommand::New { dir, assignment } = &args.command;
    let written = new_homework(dir, *assignment)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "wrote the {} homework crate to {}:",
        assignment.name(),
        dir.display()
    )?;
    for path in &written {
        writeln!(out, "  {}", path.display())?;
    }
    let source = springlab_source_dir();
    if !source.join("Cargo.toml").is_file() {
        eprintln!(
            "springlab: warning: springlab's source is no longer at {}; edit the springlab path \
             in {} before building",
            source.display(),
            dir.join("Cargo.toml").display()
        );
    }
    writeln!(
        out,
        "next: cd {} && cargo test   (the first build compiles springlab, a few minutes)",
        dir.display()
    )?;
    Ok(())
}

/// `springlab grade DIR [--json F] [--gradescope F]`: prints the rubric; exit code 0 whatever
/// the score.
///
/// # Errors
/// When DIR is not a homework crate, cargo cannot be run, or an output file cannot be written.
pub fn grade(args: &GradeArgs) -> anyhow::Result<()> {
    let options = ExternalOptions {
        grading: Options {
            time_limit: Duration::from_millis(args.time_limit_ms),
            seed: args.seed,
        },
        ..ExternalOptions::default()
    };
    let show_progress = std::io::stderr().is_terminal();
    let mut progress = |line: &str| {
        if show_progress {
            eprintln!("springlab grade: {line}");
        }
    };
    let report = grade_crate(&args.dir, &options, &mut progress)?;
    if let Some(path) = &args.json {
        write_file(path, &report.to_json()?)?;
    }
    if let Some(path) = &args.gradescope {
        write_file(path, &serde_json::to_string_pretty(&report.gradescope())?)?;
    }
    let mut out = std::io::stdout().lock();
    out.write_all(report.table().as_bytes())?;
    Ok(())
}

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}
