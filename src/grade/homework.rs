//! `springlab homework new DIR --assignment rope|jelly|cloth`: writes a student crate.
//!
//! ```text
//! DIR/Cargo.toml       package `homework`, springlab as a path dependency, tests/grade.rs
//!                      without the libtest harness, [package.metadata.springlab] assignment
//! DIR/Cargo.lock       springlab's own lock file: the crate builds with the versions springlab
//!                      was tested with (cargo adds the `homework` entry on first build)
//! DIR/README.md        the tasks, formulas, units and the rubric
//! DIR/src/lib.rs       `pub struct Student;` and every TODO compiling to a neutral answer
//! DIR/tests/grade.rs   `cargo test` grades the crate and prints the rubric
//! DIR/.gitignore       /target
//! ```
//! The dependency path is the absolute path of the springlab crate this binary was built from,
//! `env!("CARGO_MANIFEST_DIR")` at compile time ([`springlab_source_dir`]): moving or deleting
//! that source tree breaks the student crate's build (edit the `path` in its Cargo.toml then).
//! The first `cargo test` compiles springlab and its dependencies inside `DIR/target`, which
//! takes a few minutes on a small machine.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use super::Assignment;

/// The absolute path of the springlab crate this binary was built from (its `Cargo.toml`'s
/// directory), which student crates depend on.
#[must_use]
pub fn springlab_source_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// What can go wrong when writing a student crate.
#[derive(Debug, thiserror::Error)]
pub enum HomeworkError {
    /// The directory exists and has files in it.
    #[error(
        "{} is not empty; choose a new or empty directory (nothing was written)",
        .0.display()
    )]
    NotEmpty(PathBuf),
    /// The path exists and is not a directory.
    #[error("{} exists and is not a directory (nothing was written)", .0.display())]
    NotADirectory(PathBuf),
    /// Creating a directory or writing a file failed.
    #[error("cannot write {}: {source}", .path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The error.
        source: io::Error,
    },
}

const CARGO_TOML: &str = include_str!("templates/Cargo.toml.txt");
const CARGO_LOCK: &str = include_str!("../../Cargo.lock");
const GRADE_RS: &str = include_str!("templates/grade.rs.txt");
const GITIGNORE: &str = "/target\n";

/// `(lib.rs, README.md, title, main function)` of `assignment`.
fn sources(assignment: Assignment) -> (&'static str, &'static str, &'static str, &'static str) {
    match assignment {
        Assignment::Rope => (
            include_str!("templates/rope_lib.rs.txt"),
            include_str!("templates/rope_README.md.txt"),
            "GAMES101 assignment 8 (2020): rope simulation",
            "main_rope",
        ),
        Assignment::Jelly => (
            include_str!("templates/jelly_lib.rs.txt"),
            include_str!("templates/jelly_README.md.txt"),
            "NYCU Computer Animation HW1 (2023): jelly in a bowl",
            "main_jelly",
        ),
        Assignment::Cloth => (
            include_str!("templates/cloth_lib.rs.txt"),
            include_str!("templates/cloth_README.md.txt"),
            "NYCU Computer Animation HW1 (2022): cloth and spheres",
            "main_cloth",
        ),
    }
}

/// The files of a student crate for `assignment`, as `(relative path, contents)`.
#[must_use]
pub fn files(assignment: Assignment) -> Vec<(&'static str, String)> {
    let (lib, readme, title, main_fn) = sources(assignment);
    // A TOML basic string: the path with `\` and `"` escaped.
    let path = toml::Value::String(springlab_source_dir().display().to_string()).to_string();
    let cargo = CARGO_TOML
        .replace("{{TITLE}}", title)
        .replace("{{ASSIGNMENT}}", assignment.name())
        .replace("{{SPRINGLAB_PATH}}", &path);
    vec![
        ("Cargo.toml", cargo),
        ("Cargo.lock", CARGO_LOCK.to_string()),
        (".gitignore", GITIGNORE.to_string()),
        ("README.md", readme.to_string()),
        ("src/lib.rs", lib.to_string()),
        ("tests/grade.rs", GRADE_RS.replace("{{MAIN_FN}}", main_fn)),
    ]
}

/// Writes a student crate for `assignment` into `dir` (created if missing); returns the files
/// written.
///
/// # Errors
/// [`HomeworkError::NotEmpty`] when `dir` has anything in it, [`HomeworkError::NotADirectory`]
/// when it is a file, [`HomeworkError::Io`] when a directory or file cannot be written.
pub fn new_homework(dir: &Path, assignment: Assignment) -> Result<Vec<PathBuf>, HomeworkError> {
    let io_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| HomeworkError::Io { path, source }
    };
    if dir.exists() {
        if !dir.is_dir() {
            return Err(HomeworkError::NotADirectory(dir.to_path_buf()));
        }
        let mut entries = fs::read_dir(dir).map_err(io_error(dir))?;
        if entries.next().is_some() {
            return Err(HomeworkError::NotEmpty(dir.to_path_buf()));
        }
    }
    let mut written = Vec::new();
    for (relative, contents) in files(assignment) {
        let path = dir.join(relative);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(io_error(parent))?;
        }
        fs::write(&path, contents).map_err(io_error(&path))?;
        written.push(path);
    }
    Ok(written)
}
