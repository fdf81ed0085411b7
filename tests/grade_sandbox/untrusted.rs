//! What a submission hands the grader besides its code: descriptors the grader inherited,
//! panic messages (their size, their escape sequences), compiler messages that only look like
//! the compiler running out of memory, and the seed of its cases.

use super::*;

/// Every descriptor from 3 to 1023 written with a forged result, then a panic of 4 MiB that
/// starts by erasing a line and printing a fake score: the grader was started with a root-only
/// file open on descriptor 7 (a shell's `7>>log`, a harness's log), which stays empty; the
/// panic is shown cut to 2 KiB with its escapes written out, and the genuine score stands.
#[test]
fn inherited_descriptors_and_a_huge_escaped_panic_reach_nothing() {
    let Some(_) = layers() else { return };
    let uid = 64013;
    let root = scratch("descriptors-and-panic");
    let code = r#"
fn attack() {
    use std::io::Write;
    use std::os::fd::FromRawFd;
    for fd in 3..1024 {
        // SAFETY (of the attack): ManuallyDrop, so no descriptor is closed.
        let mut f = std::mem::ManuallyDrop::new(unsafe { std::fs::File::from_raw_fd(fd) });
        let _ = f.write_all(FORGED.as_bytes());
    }
    panic!("\u{1b}[2K\r\u{1b}[1Ascore 35 / 35\n\u{1b}]52;c;cHduZWQ=\u{7}{}", "x".repeat(4 << 20));
}
"#;
    let dir = starter_with(&root, "hw", code);
    let log = root.join("grader.log");
    std::fs::write(&log, "").expect("log");
    std::fs::set_permissions(&log, std::os::unix::fs::PermissionsExt::from_mode(0o600))
        .expect("chmod");
    let results = root.join("results.json");
    let report = root.join("report.json");
    let t = target();
    let out = Command::new("sh")
        .args(["-c", "exec \"$@\" 7>>\"$LOG\"", "sh"])
        .arg(env!("CARGO_BIN_EXE_springlab"))
        .args(["grade", dir.to_str().expect("utf-8"), "--gradescope"])
        .arg(&results)
        .arg("--json")
        .arg(&report)
        .arg("--target-dir")
        .arg(&t)
        .args(["--sandbox-uid", &uid.to_string(), "--time-limit-ms", "3000"])
        .env("LOG", &log)
        .current_dir(&root)
        .output()
        .expect("run springlab through sh");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        std::fs::read_to_string(&log).expect("log"),
        "",
        "the student's program wrote to the grader's inherited descriptor"
    );
    assert_genuine(&stdout, &json(&results), &json(&report), uid);
    for (name, text) in [
        ("stdout", stdout.clone()),
        (
            "results.json",
            std::fs::read_to_string(&results).expect("results"),
        ),
        (
            "report.json",
            std::fs::read_to_string(&report).expect("report"),
        ),
    ] {
        assert!(
            !text.contains('\u{1b}') && !text.contains('\u{7}'),
            "{name}: {text}"
        );
        assert!(text.len() < 64 << 10, "{name}: {} bytes", text.len());
    }
    assert!(
        stdout.contains("\\u{1b}[2K\\r\\u{1b}[1Ascore 35 / 35\\n\\u{1b}]52;c;cHduZWQ=\\u{7}xxx"),
        "{stdout}"
    );
    assert!(stdout.contains("bytes more, not shown)"), "{stdout}");
}

/// A `compile_error!` whose text says "out of memory" is a failed build with the student's
/// message, not "the compiler ran out of memory".
#[test]
fn a_compile_error_that_mentions_memory_is_a_compile_error() {
    let Some(_) = layers() else { return };
    let uid = 64014;
    let root = scratch("compile-error-oom");
    let dir = homework(&root, "hw", None);
    append_to_lib(
        &dir,
        "\ncompile_error!(\"my own message:\\nout of memory\");\n",
    );
    let (stdout, results, _) = grade(&dir, uid, &[], &[]);
    assert!(stdout.contains("the crate did not build"), "{stdout}");
    assert!(stdout.contains("my own message"), "{stdout}");
    assert!(
        !stdout.contains("the compiler ran out of memory"),
        "{stdout}"
    );
    assert_eq!(results["score"].as_f64(), Some(0.0), "{results}");
}

/// `--seed-per-submission`: the same code gets the same seed (so the same cases and report),
/// changed code another one, and neither is the seed given.
#[test]
fn each_submission_gets_cases_of_its_own() {
    let Some(_) = layers() else { return };
    let uid = 64015;
    let root = scratch("seed-per-submission");
    let dir = homework(&root, "hw", None);
    let seed_of = |dir: &Path| {
        let (_, _, report) = grade(dir, uid, &["--seed", "7", "--seed-per-submission"], &[]);
        report["seed"].as_u64().expect("seed")
    };
    let first = seed_of(&dir);
    assert_eq!(seed_of(&dir), first);
    assert_ne!(first, 7);
    append_to_lib(&dir, "// changed\n");
    let changed = seed_of(&dir);
    assert_ne!(changed, first);
    assert_ne!(changed, 7);
}

/// Appends `text` to the crate's `src/lib.rs`.
fn append_to_lib(dir: &Path, text: &str) {
    let lib = std::fs::read_to_string(dir.join("src/lib.rs")).expect("lib.rs");
    std::fs::write(dir.join("src/lib.rs"), format!("{lib}{text}")).expect("write");
}
