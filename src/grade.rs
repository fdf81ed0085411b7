//! Homework auto-grading: student crates, rubrics with the course weights, Gradescope results,
//! safe against any student code.
//!
//! # How it fits together
//!
//! - **The tasks** are traits ([`RopeHomework`], [`JellyHomework`], [`ClothHomework`]), one per
//!   course assignment, with one method per TODO of the original course and plain data
//!   ([`DVec3`], [`Rope`], [`State`], …). [`Reference`] implements all three with springlab's
//!   physics.
//! - **A student crate** comes from `springlab homework new DIR --assignment rope|jelly|cloth`
//!   ([`homework::new_homework`]): `Cargo.toml` depending on springlab by path, `src/lib.rs` with
//!   every TODO compiling to a neutral answer, a README with the tasks and formulas, and
//!   `tests/grade.rs`, a test without the libtest harness whose `main` calls [`main_rope`] (or
//!   [`main_jelly`], [`main_cloth`]). So `cargo test` in the crate grades it and prints the rubric.
//! - **The library call** [`grade_rope`] (and [`grade_jelly`], [`grade_cloth`]) runs every check
//!   of the rubric against the student's implementation and returns a [`Report`]: points per
//!   item, and for every failed check the input, the expected and the actual answer and a hint.
//! - **`springlab grade DIR`** ([`external::grade_crate`]) builds the crate's grading test with
//!   `cargo test --release --no-run`, runs it with [`REPORT_ENV`] naming a file for the JSON
//!   report, reads it back, prints the table and writes `--json` / `--gradescope` files. A crate
//!   that does not build scores zero on every item, with the compiler's errors as feedback.
//!
//! # Safety against student code
//!
//! Every check runs on its own thread under [`std::panic::catch_unwind`], with the panic hook
//! silenced for grading threads and a time limit ([`Options::time_limit`]); a panic, a NaN or
//! infinite number, or a timeout scores zero for that item only and says why (details in
//! `src/grade/runner.rs`). A timed-out thread
//! cannot be stopped and is abandoned: **the grading process should exit once grading is done**,
//! which the generated `tests/grade.rs` does by returning from `main`. The grader is not a
//! sandbox: code that aborts the process or overflows the stack ends the run (`springlab grade`
//! reports it), and code that means harm can do anything the user can. Grade untrusted
//! submissions in a container, as Gradescope does.
//!
//! # Determinism
//!
//! Random cases come from a seeded generator ([`Options::seed`], [`DEFAULT_SEED`]); the same seed
//! gives the same cases, the same scores and the same feedback.
//!
//! # Rubrics
//!
//! | assignment | graded here | left out |
//! |---|---|---|
//! | rope (GAMES101 A8 2020) | builds and runs 5, rope 5, semi-implicit Euler 5, explicit Euler 5, Verlet 10, damping 5 = 35 of 35 | the −2 penalties for the hand-in's files |
//! | jelly (NYCU HW1 2023) | springs 15, forces 20, collision 20 (plane 10, bowl 10), integrators 25 (explicit 5, implicit 2.5 + midpoint 2.5, RK4 15) = 80 of 100 | report 20, bonus up to 15 |
//! | cloth (NYCU HW1 2022) | springs 15, forces 20, collisions 20, integrators 25 = 80 of 100 | report 20, bonus |
//!
//! "Builds and runs" is judged by the grading run itself: through the library call it is always
//! awarded (a test that runs has been built); `springlab grade` gives 0 when the build fails.
//!
//! References: GAMES101 assignment 8 (Lingqi Yan, 2020); NYCU Computer Animation HW1 2022 (cloth)
//! and 2023 (jelly); Gradescope, "Autograder Specifications" (gradescope-autograders.readthedocs.io,
//! output format of `results.json`).

mod assignments;
mod checks;
mod cloth;
mod collision;
pub mod external;
pub mod homework;
mod jelly;
mod reference;
mod report;
mod rope;
mod runner;
mod shared;
mod system;

use std::process::ExitCode;
use std::time::Duration;

pub use assignments::{
    Body, Bowl, ClothHomework, ContactCoefficients, DVec3, JellyHomework, Mass, Particle, Plane,
    Rope, RopeHomework, Spring, SpringKind, SpringSetup, State, cloth_index, cube_index,
};
pub use reference::Reference;
pub use report::{
    CheckOutcome, CheckReport, Feedback, ItemReport, ItemStatus, NotGraded, Report, points,
};
pub use runner::{DEFAULT_SEED, DEFAULT_TIME_LIMIT, Options};
pub use system::{Matrix, Physics, flatten, unflatten};

/// Environment variable naming a file for the JSON report of a grading test (set by
/// `springlab grade`; the generated `tests/grade.rs` writes the report there when it is set).
pub const REPORT_ENV: &str = "SPRINGLAB_GRADE_REPORT";

/// Environment variable overriding the time limit of one check, in milliseconds.
pub const TIME_LIMIT_ENV: &str = "SPRINGLAB_GRADE_TIME_LIMIT_MS";

/// Environment variable overriding the seed of the random cases (a decimal `u64`).
pub const SEED_ENV: &str = "SPRINGLAB_GRADE_SEED";

/// The three assignments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Assignment {
    /// GAMES101 assignment 8 (2020): the rope.
    Rope,
    /// NYCU Computer Animation HW1 (2023): the jelly in a bowl.
    Jelly,
    /// NYCU Computer Animation HW1 (2022): the cloth and the spheres.
    Cloth,
}

impl Assignment {
    /// All assignments.
    pub const ALL: [Assignment; 3] = [Assignment::Rope, Assignment::Jelly, Assignment::Cloth];

    /// The command-line name: `rope`, `jelly`, `cloth`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Assignment::Rope => "rope",
            Assignment::Jelly => "jelly",
            Assignment::Cloth => "cloth",
        }
    }

    /// Parses a command-line name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Assignment> {
        Assignment::ALL.into_iter().find(|a| a.name() == name)
    }

    /// The report of an assignment in which nothing ran (the crate did not build, or the grading
    /// process crashed or hung): every item at zero with `reason`.
    #[must_use]
    pub fn not_run(self, reason: &str, options: &Options) -> Report {
        match self {
            Assignment::Rope => runner::not_run(&rope::rubric::<Reference>(), reason, options),
            Assignment::Jelly => runner::not_run(&jelly::rubric::<Reference>(), reason, options),
            Assignment::Cloth => runner::not_run(&cloth::rubric::<Reference>(), reason, options),
        }
    }

    /// Grades the reference implementation (full marks; a self-test of the grader).
    #[must_use]
    pub fn grade_reference(self, options: &Options) -> Report {
        match self {
            Assignment::Rope => grade_rope(Reference, options),
            Assignment::Jelly => grade_jelly(Reference, options),
            Assignment::Cloth => grade_cloth(Reference, options),
        }
    }
}

/// Grades a GAMES101 rope homework (see [`RopeHomework`] and the module's rubric table).
#[must_use]
pub fn grade_rope<H: RopeHomework>(homework: H, options: &Options) -> Report {
    runner::grade(rope::rubric::<H>(), homework, options)
}

/// Grades an NYCU 2023 jelly homework (see [`JellyHomework`]).
#[must_use]
pub fn grade_jelly<H: JellyHomework>(homework: H, options: &Options) -> Report {
    runner::grade(jelly::rubric::<H>(), homework, options)
}

/// Grades an NYCU 2022 cloth homework (see [`ClothHomework`]).
#[must_use]
pub fn grade_cloth<H: ClothHomework>(homework: H, options: &Options) -> Report {
    runner::grade(cloth::rubric::<H>(), homework, options)
}

/// [`Options`] from the environment: [`TIME_LIMIT_ENV`] and [`SEED_ENV`] when set and valid,
/// the defaults otherwise (an invalid value is reported on stderr and ignored).
#[must_use]
pub fn options_from_env() -> Options {
    let mut options = Options::default();
    if let Ok(text) = std::env::var(TIME_LIMIT_ENV) {
        match text.trim().parse::<u64>() {
            Ok(ms) if ms > 0 => options.time_limit = Duration::from_millis(ms),
            _ => eprintln!(
                "springlab grade: ignoring {TIME_LIMIT_ENV}={text:?} (expected milliseconds > 0)"
            ),
        }
    }
    if let Ok(text) = std::env::var(SEED_ENV) {
        match text.trim().parse::<u64>() {
            Ok(seed) => options.seed = seed,
            Err(_) => eprintln!(
                "springlab grade: ignoring {SEED_ENV}={text:?} (expected an unsigned integer)"
            ),
        }
    }
    options
}

/// The `main` of a rope crate's `tests/grade.rs`: grades `homework` with [`options_from_env`],
/// prints the rubric table, writes the JSON report to [`REPORT_ENV`] if set. Succeeds whatever
/// the score; fails only when the report cannot be written.
#[must_use]
pub fn main_rope<H: RopeHomework>(homework: H) -> ExitCode {
    finish_main(&grade_rope(homework, &options_from_env()))
}

/// The `main` of a jelly crate's `tests/grade.rs` (see [`main_rope`]).
#[must_use]
pub fn main_jelly<H: JellyHomework>(homework: H) -> ExitCode {
    finish_main(&grade_jelly(homework, &options_from_env()))
}

/// The `main` of a cloth crate's `tests/grade.rs` (see [`main_rope`]).
#[must_use]
pub fn main_cloth<H: ClothHomework>(homework: H) -> ExitCode {
    finish_main(&grade_cloth(homework, &options_from_env()))
}

fn finish_main(report: &Report) -> ExitCode {
    print!("{}", report.table());
    let Some(path) = std::env::var_os(REPORT_ENV) else {
        return ExitCode::SUCCESS;
    };
    let written = report
        .to_json()
        .map_err(std::io::Error::other)
        .and_then(|json| std::fs::write(&path, json));
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!(
                "springlab grade: cannot write the report to {}: {e}",
                std::path::Path::new(&path).display()
            );
            ExitCode::FAILURE
        }
    }
}
