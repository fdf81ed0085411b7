//! `springlab homework new DIR --assignment rope|jelly|cloth`: writes a student crate.
//!
//! ```text
//! DIR/Cargo.toml              package `homework`; depends only on ./springlab-homework;
//!                             [package.metadata.springlab] assignment and the springlab binary
//! DIR/springlab-homework/     the student API (traits, plain data, the protocol loop; no
//!                             dependencies, no physics, no reference), as embedded in springlab
//! DIR/README.md               the tasks, formulas, units and the rubric
//! DIR/src/lib.rs              `pub struct Student;` and every TODO compiling to a neutral answer
//! DIR/src/main.rs             the program: serves `Student` to the grader
//! DIR/tests/grade.rs          `cargo test` runs `springlab grade DIR` and prints the rubric
//! DIR/.gitignore              /target
//! ```
//! The crate builds offline in about a second and does not depend on springlab's source tree.
//! `DIR/tests/grade.rs` finds springlab through `$SPRINGLAB`, else the absolute path of the binary
//! that wrote the crate ([`std::env::current_exe`]), else `springlab` on PATH.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use super::Assignment;

/// The student API crate (`homework-api/` in springlab's repository) as `(relative path,
/// contents)`: written into every homework crate and into the grader's build directory.
pub const API_FILES: [(&str, &str); 8] = [
    (
        "Cargo.toml",
        include_str!("../../../../homework-api/Cargo.toml"),
    ),
    (
        "src/channel.rs",
        include_str!("../../../../homework-api/src/channel.rs"),
    ),
    (
        "src/lib.rs",
        include_str!("../../../../homework-api/src/lib.rs"),
    ),
    (
        "src/matrix.rs",
        include_str!("../../../../homework-api/src/matrix.rs"),
    ),
    (
        "src/physics.rs",
        include_str!("../../../../homework-api/src/physics.rs"),
    ),
    (
        "src/serve.rs",
        include_str!("../../../../homework-api/src/serve.rs"),
    ),
    (
        "src/vec3.rs",
        include_str!("../../../../homework-api/src/vec3.rs"),
    ),
    (
        "src/wire.rs",
        include_str!("../../../../homework-api/src/wire.rs"),
    ),
];

/// The directory of the API crate inside a homework crate.
pub const API_DIR: &str = "springlab-homework";

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
const GRADE_RS: &str = include_str!("templates/grade.rs.txt");
const MAIN_RS: &str = include_str!("templates/main.rs.txt");
const GITIGNORE: &str = "/target\n";

/// `(lib.rs, README.md, title)` of `assignment`.
fn sources(assignment: Assignment) -> (&'static str, &'static str, &'static str) {
    match assignment {
        Assignment::Rope => (
            include_str!("templates/rope_lib.rs.txt"),
            include_str!("templates/rope_README.md.txt"),
            "GAMES101 assignment 8 (2020): rope simulation",
        ),
        Assignment::Jelly => (
            include_str!("templates/jelly_lib.rs.txt"),
            include_str!("templates/jelly_README.md.txt"),
            "NYCU Computer Animation HW1 (2023): jelly in a bowl",
        ),
        Assignment::Cloth => (
            include_str!("templates/cloth_lib.rs.txt"),
            include_str!("templates/cloth_README.md.txt"),
            "NYCU Computer Animation HW1 (2022): cloth and spheres",
        ),
    }
}

/// The files of a student crate for `assignment`, as `(relative path, contents)`; `springlab`
/// is the binary its `DIR/tests/grade.rs` runs.
#[must_use]
pub fn files(assignment: Assignment, springlab: &Path) -> Vec<(String, String)> {
    let (lib, readme, title) = sources(assignment);
    let exe = springlab.display().to_string();
    let cargo = CARGO_TOML
        .replace("{{TITLE}}", title)
        .replace("{{ASSIGNMENT}}", assignment.name())
        // A TOML basic string: the path with `\\` and `"` escaped.
        .replace(
            "{{SPRINGLAB}}",
            &toml::Value::String(exe.clone()).to_string(),
        );
    let mut out = vec![
        ("Cargo.toml".to_string(), cargo),
        (".gitignore".to_string(), GITIGNORE.to_string()),
        ("README.md".to_string(), readme.to_string()),
        ("src/lib.rs".to_string(), lib.to_string()),
        (
            "src/main.rs".to_string(),
            MAIN_RS.replace("{{ASSIGNMENT}}", assignment.name()),
        ),
        (
            "tests/grade.rs".to_string(),
            // A Rust string literal: Debug escapes what needs escaping.
            GRADE_RS.replace("{{SPRINGLAB}}", &format!("{exe:?}")),
        ),
    ];
    for (relative, contents) in API_FILES {
        out.push((format!("{API_DIR}/{relative}"), contents.to_string()));
    }
    out
}

/// The springlab binary running now (its absolute path), recorded in new homework crates.
#[must_use]
pub fn this_springlab() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|p| p.canonicalize().ok())
        .unwrap_or_else(|| PathBuf::from("springlab"))
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
    for (relative, contents) in files(assignment, &this_springlab()) {
        let path = dir.join(&relative);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(io_error(parent))?;
        }
        fs::write(&path, contents).map_err(io_error(&path))?;
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::API_FILES;

    #[test]
    fn every_file_of_the_api_crate_is_embedded() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../homework-api");
        let mut on_disk = vec!["Cargo.toml".to_string()];
        for entry in std::fs::read_dir(root.join("src")).expect("homework-api/src") {
            let name = entry.expect("entry").file_name();
            on_disk.push(format!("src/{}", name.to_string_lossy()));
        }
        on_disk.sort();
        let mut embedded: Vec<String> = API_FILES.iter().map(|(p, _)| p.to_string()).collect();
        embedded.sort();
        assert_eq!(embedded, on_disk);
    }
}
