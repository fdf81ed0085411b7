//! The command line: clap definitions, validation into options, and dispatch.
//!
//! The command-line contract:
//! ```text
//! springlab [--lessons DIR] [--view raster|halfblocks|braille]   the lesson menu (terminal app)
//! springlab lesson <N|slug> [--view …] [--no-save]                one lesson
//! springlab lessons                  list the lessons
//! springlab scenes [scene] [--method M]
//! springlab run <scene|file.toml> [--method M] [--dt S] [--steps N | --time T]
//!               [--set key=value ...] [--json] [--csv FILE]
//! springlab bench [workload ...] [--json] [--repeats R]
//! springlab render <scene|file> --frames N [--every K] [--size WxH] [--out DIR] [--gif F]
//!                 [--apng F] [--energy-chart F] [--method M] [--dt S] [--set key=value ...]
//! springlab study stability <scene|file.toml> [--methods a,b] [--horizon T] [--set key=value ...]
//!               [--json]
//! springlab study resolution <scene> [--n 4,6,8] [--method M] [--time T] [--tolerance X]
//!               [--no-kinds] [--set key=value ...] [--json] [--png F]
//! springlab advise <scene|file.toml> --tolerance X [--time T] [--methods a,b] [--n 4,6,8]
//!               [--no-kinds] [--set key=value ...] [--json]
//! springlab homework new <DIR> --assignment rope|jelly|cloth
//! springlab homework autograder --assignment A --out autograder.zip
//! springlab grade <DIR> [DIR ...] [--assignment A] [--json F] [--gradescope F] [--csv F]
//!               [--jobs N] [--target-dir DIR] [--time-limit-ms MS] [--memory-mb MB] [--seed S]
//! ```

mod advise;
mod bench;
mod grade;
pub mod interrupt;
mod lessons;
mod progress;
mod render;
mod run;
mod scenes;
mod study;
mod study_chart;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::budget::{Estimate, Limits};
use interrupt::Interrupted;

/// springlab: mass-spring systems, their integrators, and where each one fails.
#[derive(Debug, Parser)]
#[command(name = "springlab", version, about, long_about = None)]
pub struct Cli {
    /// What to do; without one, opens the lesson menu.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The lesson app's options (also after `lesson N`).
    #[command(flatten)]
    pub app: AppArgs,
}

/// The lesson app's options: given before a subcommand or after `lesson N`, and listed in the
/// help of those two only.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct AppArgs {
    /// Load the lessons (*.md) from this directory instead of the built-in ones.
    #[arg(long, value_name = "DIR")]
    pub lessons: Option<PathBuf>,
    /// How the lesson app draws the scene: raster (the terminal's graphics protocol: kitty,
    /// sixel or iTerm2), halfblocks (colour text cells) or braille. Default: raster when the
    /// terminal answers a graphics protocol, else halfblocks.
    #[arg(long, value_name = "VIEW", value_parser = parse_view)]
    pub view: Option<crate::tui::ViewMode>,
    /// Keep the lesson progress (goals met, predictions) in memory only: nothing is written to
    /// the user's data directory (a classroom machine).
    #[arg(long)]
    pub no_save: bool,
    /// The lesson app's colours: for a light or a dark terminal background. Default: the
    /// background the terminal reports (dark when it does not answer).
    #[arg(long, value_name = "light|dark", value_parser = parse_theme)]
    pub theme: Option<crate::tui::Background>,
}

impl AppArgs {
    /// These options, each given here or else in `outer` (the ones before the subcommand).
    #[must_use]
    pub fn or(self, outer: AppArgs) -> AppArgs {
        AppArgs {
            lessons: self.lessons.or(outer.lessons),
            view: self.view.or(outer.view),
            no_save: self.no_save || outer.no_save,
            theme: self.theme.or(outer.theme),
        }
    }
}

fn parse_theme(s: &str) -> Result<crate::tui::Background, String> {
    crate::tui::Background::parse(s)
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
        /// A homework crate whose integrators step the lesson's body beside the reference,
        /// rebuilt on every save (`H` in the app detaches and attaches it).
        #[arg(long, value_name = "DIR")]
        homework: Option<std::path::PathBuf>,
        /// The lesson app's options.
        #[command(flatten)]
        app: AppArgs,
    },
    /// List the lessons (and the errors of lesson files that do not load).
    Lessons {
        /// List the lessons (*.md) of this directory instead of the built-in ones.
        #[arg(long, value_name = "DIR")]
        lessons: Option<PathBuf>,
    },
    /// Run a scene headless and print a summary (or JSON).
    Run(run::RunArgs),
    /// List the built-in scenes with their own parameters (`--method M`: that method's too).
    Scenes(scenes::ScenesArgs),
    /// Time the peer-benchmark workloads and check their checksums.
    Bench(bench::BenchArgs),
    /// Draw a scene's frames as PNG files, a GIF or an APNG, and its energy chart.
    Render(render::RenderArgs),
    /// The cheapest resolution, method and time step whose error on the scene's observable is
    /// within a tolerance, with a stability margin of 1.5, verified by a run.
    Advise(advise::AdviseArgs),
    /// Studies: stability limits, convergence orders, work-precision, resolution.
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
    if let Err(e) = crate::physics::stencil::Kernel::from_environment() {
        eprintln!("springlab: {e}");
        return ExitCode::FAILURE;
    }
    let outer = cli.app;
    let result = match cli.command {
        Some(Command::Lesson {
            which,
            homework,
            app,
        }) => {
            let app = app.or(outer);
            lessons::open(
                app.lessons.as_deref(),
                &which,
                app.view,
                (app.no_save, app.theme),
                homework.as_deref(),
            )
        }
        Some(Command::Lessons { lessons }) => {
            lessons::list(lessons.as_deref().or(outer.lessons.as_deref()))
        }
        Some(Command::Run(args)) => run::run(&args),
        Some(Command::Scenes(args)) => scenes::list(&args),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Render(args)) => render::run(&args),
        Some(Command::Study { command }) => study::run(&command),
        Some(Command::Advise(args)) => advise::run(&args),
        Some(Command::Homework(args)) => grade::homework(&args),
        Some(Command::Grade(args)) => grade::grade(&args),
        None => lessons::menu(
            outer.lessons.as_deref(),
            outer.view,
            (outer.no_save, outer.theme),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (`springlab scenes | head`) is the reader's choice, not an error.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) if e.chain().any(|c| c.is::<Interrupted>()) => {
            eprintln!("springlab: {e}");
            ExitCode::from(interrupt::exit_status())
        }
        // A failure caused by the stop itself (an output that gave up waiting for a FIFO's
        // reader): the stop's message and status.
        Err(e) if interrupt::requested() && is_interrupted_io(&e) => {
            eprintln!("springlab: {Interrupted}");
            ExitCode::from(interrupt::exit_status())
        }
        Err(e) => {
            eprintln!("springlab: {}", message(&e));
            ExitCode::FAILURE
        }
    }
}

/// True when an I/O error in `e`'s chain is [`std::io::ErrorKind::Interrupted`].
fn is_interrupted_io(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::Interrupted)
    })
}

/// The error and its causes joined by `: `, each said once: a cause whose text the message
/// already contains (an OS error that a wrapper quoted) is not repeated.
#[must_use]
pub fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

/// The budget estimate of a command that runs something (`run`, `render`, `study`, `bench`)
/// without running it; `None` for the others. Scenes are loaded without limits.
///
/// # Errors
/// The command's own checks of its inputs.
pub fn estimate(command: &Command) -> anyhow::Result<Option<Estimate>> {
    let none = Limits::NONE;
    Ok(match command {
        Command::Run(args) => Some(run::prepare(args, &none)?.3),
        Command::Render(args) => Some(render::prepare(args, &none)?.2),
        Command::Study { command } => Some(study::estimate(command, &none)?),
        Command::Advise(args) => Some(advise::prepare(args, &none)?.1),
        Command::Bench(args) => Some(bench::estimate(
            &bench::selected(&args.workloads)?,
            args.repeats,
            args.budget,
        )),
        _ => None,
    })
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
