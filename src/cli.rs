//! The command line: clap definitions, validation into options, and dispatch.
//!
//! The command-line contract:
//! ```text
//! springlab [--lessons DIR] [--view raster|halfblocks|braille]   the lesson menu (terminal app)
//! springlab lesson <N|slug> [--view …]                            one lesson
//! springlab lessons                  list the lessons
//! springlab scenes
//! springlab run <scene|file.toml> [--method M] [--dt S] [--steps N | --time T]
//!               [--set key=value ...] [--json] [--csv FILE]
//! springlab bench [workload ...] [--json] [--repeats R]
//! springlab render <scene|file> --frames N [--every K] [--size WxH] [--out DIR] [--gif F]
//!                 [--apng F] [--energy-chart F] [--method M] [--dt S] [--set key=value ...]
//! springlab study stability <scene|file.toml> [--methods a,b] [--horizon T] [--set key=value ...]
//!               [--json]
//! springlab homework new <DIR> --assignment rope|jelly|cloth
//! springlab grade <DIR> [--json F] [--gradescope F] [--time-limit-ms MS] [--seed S]
//! ```

mod bench;
mod grade;
mod lessons;
mod render;
mod run;
mod scenes;
mod study;
mod study_chart;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// springlab: mass-spring systems, their integrators, and where each one fails.
#[derive(Debug, Parser)]
#[command(name = "springlab", version, about, long_about = None)]
pub struct Cli {
    /// What to do; without one, opens the lesson menu.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Load the lessons (*.md) from this directory instead of the built-in ones.
    #[arg(long, global = true, value_name = "DIR")]
    pub lessons: Option<PathBuf>,
    /// How the lesson app draws the scene: raster (the terminal's graphics protocol: kitty,
    /// sixel or iTerm2), halfblocks (colour text cells) or braille. Default: raster when the
    /// terminal answers a graphics protocol, else halfblocks.
    #[arg(long, global = true, value_name = "VIEW", value_parser = parse_view)]
    pub view: Option<crate::tui::ViewMode>,
}

fn parse_view(s: &str) -> Result<crate::tui::ViewMode, String> {
    crate::tui::ViewMode::parse(s)
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open one lesson in the terminal app.
    Lesson {
        /// The lesson's number or short name (see `springlab lessons`).
        #[arg(value_name = "N|SLUG")]
        which: String,
    },
    /// List the lessons (and the errors of lesson files that do not load).
    Lessons,
    /// Run a scene headless and print a summary (or JSON).
    Run(run::RunArgs),
    /// List the built-in scenes with their parameters.
    Scenes,
    /// Time the peer-benchmark workloads and check their checksums.
    Bench(bench::BenchArgs),
    /// Draw a scene's frames as PNG files, a GIF or an APNG, and its energy chart.
    Render(render::RenderArgs),
    /// Studies: stability limits, convergence orders, work-precision.
    Study {
        /// The study to run.
        #[command(subcommand)]
        command: study::StudyCommand,
    },
    /// Write a homework crate for students (`homework new DIR --assignment rope|jelly|cloth`).
    Homework(grade::HomeworkArgs),
    /// Build and grade a homework crate; print the rubric, write JSON or Gradescope results.
    Grade(grade::GradeArgs),
}

/// Parses the process arguments and runs the command; prints errors and returns the exit code.
#[must_use]
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let dir = cli.lessons.as_deref();
    let result = match cli.command {
        Some(Command::Lesson { which }) => lessons::open(dir, &which, cli.view),
        Some(Command::Lessons) => lessons::list(dir),
        Some(Command::Run(args)) => run::run(&args),
        Some(Command::Scenes) => scenes::list(),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Render(args)) => render::run(&args),
        Some(Command::Study { command }) => study::run(&command),
        Some(Command::Homework(args)) => grade::homework(&args),
        Some(Command::Grade(args)) => grade::grade(&args),
        None => lessons::menu(dir, cli.view),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (`springlab scenes | head`) is the reader's choice, not an error.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("springlab: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
