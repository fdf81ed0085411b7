//! `springlab homework new` and `springlab grade` through the real binary: the files written,
//! the refusals with their messages, and a crate that does not build, which still gets a
//! report, a Gradescope file and exit code 0.

use crate::common;
use common::springlab;

use std::path::{Path, PathBuf};

/// A fresh, empty scratch directory for test `name`.
fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("springlab-grade-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `springlab homework new ROOT/hw --assignment ASSIGNMENT`: the crate's folder.
fn homework(root: &Path, assignment: &str) -> PathBuf {
    let dir = root.join("hw");
    let out = springlab(&[
        "homework",
        "new",
        dir.to_str().expect("utf-8"),
        "--assignment",
        assignment,
    ]);
    assert!(out.status.success(), "{out:?}");
    dir
}

fn failure(args: &[&str]) -> String {
    let out = springlab(args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn homework_new_writes_a_student_crate_depending_on_this_springlab() {
    for (assignment, main_fn, trait_name) in [
        ("rope", "serve_rope", "RopeHomework"),
        ("jelly", "serve_jelly", "JellyHomework"),
        ("cloth", "serve_cloth", "ClothHomework"),
    ] {
        let dir = scratch(assignment).join("hw");
        let out = springlab(&[
            "homework",
            "new",
            dir.to_str().expect("utf-8"),
            "--assignment",
            assignment,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let manifest: toml::Value = toml::from_str(&text(&dir.join("Cargo.toml"))).expect("TOML");
        assert_eq!(
            manifest["package"]["metadata"]["springlab"]["assignment"].as_str(),
            Some(assignment)
        );
        // The only dependency is the student API, copied into the crate; springlab itself (its
        // physics, its reference) is not reachable from the student's code.
        let deps = manifest["dependencies"].as_table().expect("dependencies");
        assert_eq!(deps.keys().collect::<Vec<_>>(), ["springlab-homework"]);
        assert_eq!(
            deps["springlab-homework"]["path"].as_str(),
            Some("springlab-homework")
        );
        assert!(dir.join("springlab-homework/src/wire.rs").is_file());
        let api_manifest = text(&dir.join("springlab-homework/Cargo.toml"));
        assert!(api_manifest.contains("[dependencies]\n"), "{api_manifest}");
        assert!(!api_manifest.contains("springlab ="), "{api_manifest}");
        // The recorded springlab is the binary that wrote the crate.
        let recorded = manifest["package"]["metadata"]["springlab"]["springlab"]
            .as_str()
            .expect("recorded springlab");
        assert_eq!(
            std::fs::canonicalize(recorded).expect("exists"),
            std::fs::canonicalize(env!("CARGO_BIN_EXE_springlab")).expect("exists")
        );
        assert_eq!(manifest["test"][0]["harness"].as_bool(), Some(false));
        assert!(text(&dir.join("tests/grade.rs")).contains(".arg(\"grade\")"));
        assert!(
            text(&dir.join("src/main.rs"))
                .contains(&format!("springlab_homework::{main_fn}(homework::Student)"))
        );
        assert!(text(&dir.join("src/lib.rs")).contains(&format!("impl {trait_name} for Student")));
        assert!(text(&dir.join("README.md")).contains("## Rubric"));
        let _ = std::fs::remove_dir_all(dir.parent().expect("parent"));
    }
}

#[test]
fn homework_new_refuses_a_non_empty_directory_and_writes_nothing() {
    let dir = scratch("nonempty");
    std::fs::write(dir.join("notes.txt"), "mine").expect("write");
    let err = failure(&[
        "homework",
        "new",
        dir.to_str().expect("utf-8"),
        "--assignment",
        "rope",
    ]);
    assert!(
        err.contains("is not empty; choose a new or empty directory (nothing was written)"),
        "{err}"
    );
    assert!(!dir.join("Cargo.toml").exists());
    assert_eq!(text(&dir.join("notes.txt")), "mine");
    let file = dir.join("notes.txt");
    let err = failure(&[
        "homework",
        "new",
        file.to_str().expect("utf-8"),
        "--assignment",
        "rope",
    ]);
    assert!(err.contains("exists and is not a directory"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn homework_new_names_the_assignments_when_given_another() {
    let err = failure(&[
        "homework",
        "new",
        "/tmp/never-written",
        "--assignment",
        "spring",
    ]);
    assert!(err.contains("possible values: rope, jelly, cloth"), "{err}");
    let err = failure(&["homework", "new", "/tmp/never-written"]);
    assert!(err.contains("--assignment"), "{err}");
}

#[test]
fn grade_refuses_what_is_not_a_homework_crate() {
    let dir = scratch("notacrate");
    let missing = dir.join("missing");
    // A path that is not there is the caller's error (exit 1), never a student's 0.
    for extra in [&[][..], &["--assignment", "rope"][..]] {
        let mut args = vec!["grade", missing.to_str().expect("utf-8")];
        args.extend_from_slice(extra);
        let err = failure(&args);
        assert!(
            err.contains(&format!("{}: no such file or directory", missing.display())),
            "{err}"
        );
    }
    let err = failure(&["grade", dir.to_str().expect("utf-8")]);
    assert!(err.contains("cannot read Cargo.toml"), "{err}");
    std::fs::write(dir.join("Cargo.toml"), "[package]\nname = \"x\"\n").expect("write");
    let err = failure(&["grade", dir.to_str().expect("utf-8")]);
    assert!(
        err.contains("has no [package.metadata.springlab] assignment"),
        "{err}"
    );
    std::fs::write(
        dir.join("Cargo.toml"),
        "[package.metadata.springlab]\nassignment = \"spring\"\n",
    )
    .expect("write");
    let err = failure(&["grade", dir.to_str().expect("utf-8")]);
    assert!(err.contains("unknown assignment `spring`"), "{err}");
    let err = failure(&[
        "grade",
        dir.to_str().expect("utf-8"),
        "--time-limit-ms",
        "0",
    ]);
    assert!(err.contains("time-limit-ms"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_crate_that_does_not_build_scores_zero_with_the_errors_and_exit_code_0() {
    let root = scratch("broken");
    let dir = homework(&root, "jelly");
    // A syntax error: rustc stops at the parser, before the rest of the crate.
    let lib = text(&dir.join("src/lib.rs")).replace("pub struct Student;", "pub struct Student");
    std::fs::write(dir.join("src/lib.rs"), lib).expect("write");
    let results = root.join("results.json");
    let report = root.join("report.json");
    let target = root.join("target");
    let out = springlab(&[
        "grade",
        dir.to_str().expect("utf-8"),
        "--target-dir",
        target.to_str().expect("utf-8"),
        "--gradescope",
        results.to_str().expect("utf-8"),
        "--json",
        report.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("score 0 / 80"), "{stdout}");
    assert!(stdout.contains("the crate did not build"), "{stdout}");
    assert!(
        stdout.contains("after struct name") && stdout.contains("src/lib.rs"),
        "the compiler's message is shown: {stdout}"
    );
    let v: serde_json::Value = serde_json::from_str(&text(&results)).expect("results.json");
    assert_eq!(v["score"].as_f64(), Some(0.0));
    assert_eq!(v["max_score"].as_f64(), Some(80.0));
    let tests = v["tests"].as_array().expect("tests");
    assert_eq!(tests.len(), 10);
    for t in tests {
        assert_eq!(t["score"].as_f64(), Some(0.0));
        assert!(t["max_score"].as_f64().is_some_and(|m| m > 0.0));
        assert!(t["name"].is_string() && t["visibility"] == "visible");
        assert!(
            t["output"]
                .as_str()
                .unwrap_or_default()
                .contains("did not build")
        );
    }
    let r: serde_json::Value = serde_json::from_str(&text(&report)).expect("report.json");
    assert_eq!(r["assignment"], "jelly");
    let _ = std::fs::remove_dir_all(&root);
}

/// A lone `lib.rs` is graded as the folder holding it is (the untouched starter: 5 / 35, "builds
/// and runs"); without `--assignment` the message says to give it.
#[test]
fn a_lone_lib_rs_is_graded_with_its_assignment() {
    let root = scratch("lone");
    let dir = homework(&root, "rope");
    let lone = root.join("solo").join("lib.rs");
    std::fs::create_dir_all(lone.parent().expect("parent")).expect("mkdir");
    std::fs::copy(dir.join("src/lib.rs"), &lone).expect("copy");
    let err = failure(&["grade", lone.to_str().expect("utf-8")]);
    assert!(
        err.contains("a lone file names no assignment; give it with --assignment"),
        "{err}"
    );
    let target = root.join("target");
    let out = springlab(&[
        "grade",
        lone.to_str().expect("utf-8"),
        "--assignment",
        "rope",
        "--target-dir",
        target.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("score 5 / 35"), "{stdout}");
    let _ = std::fs::remove_dir_all(&root);
}
