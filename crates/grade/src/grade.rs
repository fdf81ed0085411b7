//! Homework auto-grading: rubrics with the course weights, the student's code in its own
//! process, Gradescope results.
//!
//! # How it fits together
//!
//! - **The student side** is the crate `springlab-homework` (`homework-api/`, no dependencies):
//!   one trait per course assignment (`RopeHomework`, `JellyHomework`, `ClothHomework`), plain
//!   data, a `Physics` handle whose calls go to the grader, and the loop that serves a solution
//!   over a small protocol on stdin/stdout (`springlab_homework::wire`). It holds no physics and
//!   no answers.
//! - **A student crate** comes from `springlab homework new DIR --assignment rope|jelly|cloth`
//!   ([`homework::new_homework`]): `src/lib.rs` with every TODO compiling to a neutral answer,
//!   `src/main.rs` serving it, a copy of the student API, a README with the tasks and formulas,
//!   and `DIR/tests/grade.rs`, which runs `springlab grade` on the crate, so `cargo test` prints the
//!   rubric.
//! - **`springlab grade DIR…`** ([`external::grade_crate`], [`external::grade_all`]) builds each
//!   submission's `src/` against springlab's own manifest ([`build`]), runs it as a separate
//!   program with limits ([`remote`]) and grades it here: the cases, the reference, the time
//!   limits and the report never leave this process.
//! - **The rubrics** run against this crate's copies of the traits ([`RopeHomework`], …, with
//!   `glam` vectors); [`remote::Remote`] implements them by calling the program, and
//!   [`Reference`] implements them with springlab's physics. The library calls [`grade_rope`]
//!   (and [`grade_jelly`], [`grade_cloth`]) grade any implementation in this process; springlab's
//!   own tests use them for planted mistakes.
//!
//! # Safety against student code
//!
//! Every check has a deadline; every call to the program waits at most until then. A panic
//! costs the check in progress; an exit, abort, stack overflow, memory overrun or time-out of
//! the program costs the check in progress and a new program answers the rest ([`runner`] has
//! the scoring rules, [`remote`] the limits). What the program writes (files, stdout) cannot
//! reach a score. Builds and programs run in a sandbox ([`sandbox`]: another user, namespaces,
//! Landlock, seccomp, limits), and the report is written only once it is empty; the threat model,
//! and what is left to a container, is in `docs/grading.md`.
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
//! "Builds and runs" is judged by the grading run itself: a program that was built and graded
//! gets it; `springlab grade` gives 0 when the build fails.
//!
//! References: GAMES101 assignment 8 (Lingqi Yan, 2020); NYCU Computer Animation HW1 2022 (cloth)
//! and 2023 (jelly); Gradescope, "Autograder Specifications" (gradescope-autograders.readthedocs.io,
//! output format of `results.json` and the files of an autograder).

mod assignments;
pub mod autograder;
pub mod build;
mod checks;
mod cloth;
mod collision;
mod data;
pub mod external;
pub mod homework;
mod jelly;
pub mod live;
mod reference;
pub mod remote;
mod report;
mod rope;
pub mod runner;
pub mod sandbox;
mod shared;
mod system;
mod token;
pub mod untrusted;

pub use assignments::{
    Body, Bowl, ClothHomework, ContactCoefficients, DVec3, JellyHomework, Mass, Particle, Plane,
    Rope, RopeHomework, Spring, SpringKind, SpringSetup, State, cloth_index, cube_index,
};
pub use reference::Reference;
pub use report::{
    CheckOutcome, CheckReport, Feedback, ItemReport, ItemStatus, NotGraded, Report, points,
    write_result,
};
pub use runner::{DEFAULT_SEED, DEFAULT_TIME_LIMIT, Options};
pub use system::{Matrix, Physics, flatten, unflatten};

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

    /// The course and assignment, for example "GAMES101 assignment 8 (2020): rope simulation".
    #[must_use]
    pub fn title(self) -> &'static str {
        match self {
            Assignment::Rope => "GAMES101 assignment 8 (2020): rope simulation",
            Assignment::Jelly => "NYCU Computer Animation HW1 (2023): jelly in a bowl",
            Assignment::Cloth => "NYCU Computer Animation HW1 (2022): cloth and spheres",
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
    let mut report = runner::grade(rope::rubric::<H>(), homework, options);
    checks::link_back(&mut report, Assignment::Rope);
    report
}

/// Grades an NYCU 2023 jelly homework (see [`JellyHomework`]).
#[must_use]
pub fn grade_jelly<H: JellyHomework>(homework: H, options: &Options) -> Report {
    let mut report = runner::grade(jelly::rubric::<H>(), homework, options);
    checks::link_back(&mut report, Assignment::Jelly);
    report
}

/// Grades an NYCU 2022 cloth homework (see [`ClothHomework`]).
#[must_use]
pub fn grade_cloth<H: ClothHomework>(homework: H, options: &Options) -> Report {
    let mut report = runner::grade(cloth::rubric::<H>(), homework, options);
    checks::link_back(&mut report, Assignment::Cloth);
    report
}
