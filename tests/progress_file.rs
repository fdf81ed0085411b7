//! The student's progress file is never lost (issue 28, item 2): a corrupted file is kept aside
//! with its content, one bad lesson does not lose the others, saves do not write through links.
#![cfg(unix)]

use std::fs;
use std::path::Path;

use springlab::tui::Progress;
use springlab::tui::progress::LessonProgress;

fn record(visited: usize) -> LessonProgress {
    LessonProgress {
        visited: vec![true; visited],
        met: vec![false; visited],
        answers: vec![None; visited],
    }
}

/// The files of `dir` whose names start with `prefix`.
fn starting(dir: &Path, prefix: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = fs::read_dir(dir)
        .expect("list")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

#[test]
fn a_file_that_is_not_json_is_kept_beside_a_new_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("progress.json");
    let garbage = b"{\"version\":1,\"lessons\":{\"rope\":{\"visited\":[tru";
    fs::write(&path, garbage).expect("write");
    let mut progress = Progress::load(&path);
    let notice = progress.notice().expect("told").to_string();
    assert!(notice.contains("it is not valid JSON"), "{notice}");
    assert!(notice.contains("a new one is started"), "{notice}");
    assert!(progress.lesson("rope").is_none());
    // The old content is kept, under the name the notice gives.
    let aside = starting(dir.path(), "progress.json.unreadable-");
    assert_eq!(aside.len(), 1, "{aside:?}");
    assert!(notice.contains(&aside[0].display().to_string()), "{notice}");
    assert_eq!(fs::read(&aside[0]).expect("aside"), garbage);
    // The next save starts a fresh file and leaves the kept one alone.
    assert_eq!(progress.update("hooke", record(2)), None);
    let again = Progress::load(&path);
    assert_eq!(again.notice(), None);
    assert_eq!(again.lesson("hooke"), Some(&record(2)));
    assert_eq!(fs::read(&aside[0]).expect("aside"), garbage);
}

#[test]
fn one_bad_field_loses_only_that_field() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("progress.json");
    let text = r#"{"version":1,"lessons":{
        "rope":{"visited":[true,true],"met":"yes","answers":[1,null]},
        "hooke":{"visited":[true],"met":[true],"answers":[0]}}}"#;
    fs::write(&path, text).expect("write");
    let progress = Progress::load(&path);
    let notice = progress.notice().expect("told");
    assert!(
        notice.contains("lesson `rope`: `met` could not be read"),
        "{notice}"
    );
    assert!(
        notice.contains("the progress of 2 lesson(s) that could be read goes on"),
        "{notice}"
    );
    let rope = progress.lesson("rope").expect("rope kept");
    assert_eq!(rope.visited, [true, true]);
    assert!(rope.met.is_empty());
    assert_eq!(rope.answers, [Some(1), None]);
    assert_eq!(
        progress.lesson("hooke"),
        Some(&LessonProgress {
            visited: vec![true],
            met: vec![true],
            answers: vec![Some(0)],
        })
    );
    // The original is kept byte for byte; what was read is saved at once.
    let aside = starting(dir.path(), "progress.json.unreadable-");
    assert_eq!(fs::read_to_string(&aside[0]).expect("aside"), text);
    let again = Progress::load(&path);
    assert_eq!(again.notice(), None);
    assert_eq!(again.lesson("rope"), progress.lesson("rope"));
    assert_eq!(again.lesson("hooke"), progress.lesson("hooke"));
}

#[test]
fn a_link_at_a_temporary_name_is_never_written_through() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("progress.json");
    let victim = dir.path().join("victim");
    fs::write(&victim, "precious").expect("write");
    // The fixed name the old save used, and the names of our temporary files.
    std::os::unix::fs::symlink(&victim, dir.path().join("progress.json.tmp")).expect("link");
    let mut progress = Progress::load(&path);
    assert_eq!(progress.update("rope", record(1)), None);
    assert_eq!(fs::read_to_string(&victim).expect("victim"), "precious");
    assert!(
        fs::symlink_metadata(dir.path().join("progress.json.tmp"))
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(Progress::load(&path).lesson("rope"), Some(&record(1)));
    // No temporary file is left.
    assert!(starting(dir.path(), ".progress.json.").is_empty());
}

#[test]
fn a_directory_at_the_path_is_left_and_progress_kept_in_memory() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("progress.json");
    fs::create_dir(&path).expect("mkdir");
    let mut progress = Progress::load(&path);
    assert!(
        progress
            .notice()
            .is_some_and(|n| n.contains("is not a regular file")),
        "{:?}",
        progress.notice()
    );
    assert_eq!(progress.path(), None);
    assert_eq!(progress.update("rope", record(1)), None);
    assert_eq!(progress.lesson("rope"), Some(&record(1)));
    assert!(path.is_dir());
}

#[test]
fn a_failed_save_leaves_the_old_file_and_no_temporary_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("sub").join("progress.json");
    let mut progress = Progress::load(&path);
    assert_eq!(progress.update("rope", record(1)), None);
    let saved = fs::read(&path).expect("saved");
    // A file where the directory must be: the next save fails, once, with a message.
    let blocked = dir.path().join("blocked").join("progress.json");
    fs::write(dir.path().join("blocked"), "a file").expect("write");
    let mut other = Progress::load(&blocked);
    let e = other.update("rope", record(2)).expect("an error");
    assert!(e.starts_with("progress not saved to "), "{e}");
    assert_eq!(other.update("rope", record(3)), None, "said once");
    assert_eq!(fs::read(&path).expect("unchanged"), saved);
    assert_eq!(
        fs::read_dir(dir.path().join("sub")).expect("list").count(),
        1
    );
}
