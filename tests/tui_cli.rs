//! `springlab`, `springlab lesson` and `springlab lessons` through the real binary (without a
//! terminal: the app itself is tested in `tests/tui.rs`).

use std::process::{Command, Output, Stdio};

fn springlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run springlab")
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("springlab-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn lessons_lists_the_builtin_lessons() {
    let out = springlab(&["lessons"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), springlab::lesson::BUILTIN.len(), "{text}");
    assert!(
        lines[0].starts_with(" 1. Building a rope (rope, 4 steps): "),
        "{text}"
    );
    assert!(lines[1].starts_with(" 2. Hooke's law (hooke, "), "{text}");
}

#[test]
fn lessons_dir_lists_broken_files_with_file_and_line_and_fails() {
    let dir = temp_dir("broken");
    std::fs::write(dir.join("01-rope.md"), springlab::lesson::BUILTIN[0].1).expect("write");
    std::fs::write(dir.join("02-bad.md"), "+++\nnumber = \"two\"\n+++\n").expect("write");
    let dir_arg = dir.to_string_lossy().into_owned();
    let out = springlab(&["lessons", "--lessons", &dir_arg]);
    assert!(!out.status.success(), "a broken lesson file is an error");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(" 1. Building a rope"), "{text}");
    assert!(text.contains("02-bad.md:2:"), "file and line: {text}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("1 lesson file(s) failed to load"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn lessons_dir_that_does_not_exist_is_an_error() {
    let out = springlab(&["--lessons", "/no/such/dir", "lessons"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--lessons /no/such/dir: cannot read the directory"),
        "{err}"
    );
}

#[test]
fn unknown_lesson_lists_the_lessons() {
    let out = springlab(&["lesson", "nine"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no lesson `nine`; lessons: 1 (rope), 2 (hooke)"),
        "{err}"
    );
}

#[test]
fn the_app_without_a_terminal_says_what_to_do_instead() {
    for args in [&[][..], &["lesson", "1"][..]] {
        let out = springlab(args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("the lesson app needs a terminal"), "{err}");
        assert!(err.contains("springlab lessons"), "{err}");
    }
}

/// The lesson app's options are the app's: `lesson N --help` and `springlab --help` list them,
/// the other commands' help does not, and `run … --view` is refused as unknown there.
#[test]
fn the_apps_options_belong_to_the_app() {
    let help = |args: &[&str]| String::from_utf8_lossy(&springlab(args).stdout).into_owned();
    for args in [&["--help"][..], &["lesson", "--help"][..]] {
        let text = help(args);
        for option in ["--lessons", "--view", "--no-save", "--theme"] {
            assert!(text.contains(option), "{args:?}: {option}\n{text}");
        }
    }
    for command in [
        "run", "render", "bench", "study", "advise", "grade", "scenes",
    ] {
        let text = help(&[command, "--help"]);
        for option in ["--view", "--no-save", "--theme"] {
            assert!(
                !text.contains(option),
                "{command} --help lists {option}\n{text}"
            );
        }
    }
    let out = springlab(&["run", "rope", "--view", "braille"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unexpected argument '--view'"));
}
