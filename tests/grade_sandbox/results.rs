//! Where results go: a FIFO or link at the report path is refused, grader failures are the
//! grader's errors (exit 1, a failure result), never a student's zero.

use super::*;

/// `springlab grade dir OUTPUT_FLAG path` as sandbox uid 64012: its exit status and stderr.
fn grade_into(root: &Path, dir: &Path, flag: &str, path: &Path) -> (bool, String) {
    let t = target();
    let out = springlab(
        root,
        &[
            "grade",
            dir.to_str().expect("utf-8"),
            flag,
            path.to_str().expect("utf-8"),
            "--target-dir",
            t.to_str().expect("utf-8"),
            "--sandbox-uid",
            "64012",
        ],
        &[],
    );
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A FIFO (and a symbolic link) at the report path: refused with a message and a non-zero exit,
/// never blocked on or followed.
#[test]
fn a_fifo_or_link_at_the_report_path_is_refused() {
    let root = scratch("fifo");
    let dir = homework(&root, "hw", None);
    let fifo = root.join("results.json");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    let (ok, stderr) = grade_into(&root, &dir, "--gradescope", &fifo);
    assert!(!ok);
    assert!(
        stderr.contains("refusing to write a result over a FIFO"),
        "{stderr}"
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(&fifo)
            .expect("fifo")
            .file_type()
            .is_fifo()
    );
    // A symbolic link to a file elsewhere: that file is left as it was.
    let elsewhere = root.join("elsewhere.txt");
    std::fs::write(&elsewhere, "mine").expect("write");
    let link = root.join("report.json");
    std::os::unix::fs::symlink(&elsewhere, &link).expect("symlink");
    let (ok, stderr) = grade_into(&root, &dir, "--json", &link);
    assert!(!ok);
    assert!(stderr.contains("over a symbolic link"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&elsewhere).expect("read"), "mine");
}

/// A grader-side failure (an unwritable --target-dir) is the grader's error: a non-zero status
/// and no score written, never the student's "0 / 35".
#[test]
fn an_unwritable_target_dir_is_a_grader_error_not_a_zero() {
    let root = scratch("grader-error");
    let dir = homework(&root, "hw", None);
    let blocked = root.join("not-a-dir");
    std::fs::write(&blocked, "a file where the target directory would be").expect("write");
    let results = root.join("results.json");
    let out = springlab(
        &root,
        &[
            "grade",
            dir.to_str().expect("utf-8"),
            "--gradescope",
            results.to_str().expect("utf-8"),
            "--target-dir",
            blocked.join("t").to_str().expect("utf-8"),
        ],
        &[],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stdout}");
    assert!(stderr.contains("grader error"), "{stderr}");
    assert!(stderr.contains("cannot make the build cache"), "{stderr}");
    assert!(!stdout.contains("score 0"), "{stdout}");
    assert!(!results.exists());
}

/// `run_autograder` when the grader itself fails (here: its target directory is a file): a
/// failure result saying so, never nothing and never a file the submission wrote.
#[test]
fn run_autograder_writes_a_failure_result_when_the_grader_fails() {
    let root = scratch("autograder-fails");
    let source = root.join("source");
    std::fs::create_dir_all(&source).expect("source");
    let files =
        springlab::grade::autograder::files(springlab::grade::Assignment::Rope, Vec::new(), 7);
    let (_, script, _) = files
        .iter()
        .find(|(name, _, _)| name == "run_autograder")
        .expect("run_autograder");
    std::fs::write(source.join("run_autograder"), script).expect("write");
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_springlab"), source.join("springlab"))
        .expect("link");
    std::fs::write(source.join("target"), "a file where the cache would be").expect("write");
    std::fs::create_dir_all(root.join("submission")).expect("submission");
    std::fs::write(root.join("submission/lib.rs"), ROPE).expect("lib.rs");
    // A results.json the submission might have left: replaced.
    std::fs::create_dir_all(root.join("results")).expect("results");
    std::fs::write(root.join("results/results.json"), r#"{"score": 35}"#).expect("write");
    let out = Command::new("bash")
        .arg(source.join("run_autograder"))
        .env("SPRINGLAB_AUTOGRADER_ROOT", &root)
        .output()
        .expect("run run_autograder");
    assert!(out.status.success(), "{out:?}");
    let results = json(&root.join("results/results.json"));
    assert_eq!(results["score"].as_f64(), Some(0.0), "{results}");
    let output = results["output"].as_str().unwrap_or_default();
    assert!(output.contains("autograder itself failed"), "{output}");
    let stderr = std::fs::read_to_string(root.join("results/grader-stderr.txt")).expect("stderr");
    assert!(stderr.contains("grader error"), "{stderr}");
}

/// `setup.sh` with a toolchain that cannot build the student API (an old rustc that does not know
/// edition 2024): the set-up fails with a message instead of passing and giving every
/// submission 0.
#[test]
fn setup_fails_loudly_when_the_toolchain_cannot_build_the_api() {
    let root = scratch("setup-old-rustc");
    let source = root.join("source");
    std::fs::create_dir_all(&source).expect("source");
    let files =
        springlab::grade::autograder::files(springlab::grade::Assignment::Rope, Vec::new(), 7);
    let (_, script, _) = files
        .iter()
        .find(|(name, _, _)| name == "setup.sh")
        .expect("setup.sh");
    std::fs::write(source.join("setup.sh"), script).expect("write");
    std::fs::write(source.join("run_autograder"), "").expect("write");
    std::fs::copy(env!("CARGO_BIN_EXE_springlab"), source.join("springlab")).expect("copy");
    // A rustc that reports an old version and refuses edition 2024, as rustc 1.80 does.
    let sysroot = root.join("old-toolchain");
    let bin = sysroot.join("bin");
    std::fs::create_dir_all(&bin).expect("bin");
    let rustc = bin.join("rustc");
    std::fs::write(
        &rustc,
        format!(
            "#!/bin/sh\ncase \"$*\" in\n  *sysroot*) echo {sysroot:?} ;;\n  \
             *-vV*) printf 'rustc 1.80.0 (old)\\nhost: x86_64-unknown-linux-gnu\\n' ;;\n  \
             *) echo \"error: invalid value for '--edition': 2024\" >&2; exit 1 ;;\nesac\n",
            sysroot = sysroot.display().to_string()
        ),
    )
    .expect("write rustc");
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&rustc, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    let out = Command::new("bash")
        .arg(source.join("setup.sh"))
        .current_dir(&source)
        .env_clear()
        .env("HOME", &root)
        .env("PATH", format!("{}:/usr/bin:/bin", bin.display()))
        .output()
        .expect("run setup.sh");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "setup.sh passed: {stderr}");
    assert!(stderr.contains("cannot build the student API"), "{stderr}");
    assert!(stderr.contains("rustc 1.80.0"), "{stderr}");
    assert!(
        stderr.contains("setup.sh: the grader cannot run"),
        "{stderr}"
    );
}
