//! `springlab run <file.toml>`: the binary prints `file:line:col: message` for a bad scene file
//! and exits non-zero; a good file runs.

use crate::common;
use common::springlab;

use std::path::PathBuf;

/// Writes `text` to `name` in a directory unique to this process and test.
fn write(test: &str, name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "springlab-cli-scene-files-{}-{test}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).expect("create temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write scene file");
    path
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn bad_scene_file_prints_file_line_column_and_fails() {
    let path = write(
        "bad",
        "rope.toml",
        "# a rope with a bad mass\n[[ropes]]\nnodes = 4\nmass = -1\n",
    );
    let p = path.to_str().expect("utf-8 path");
    let out = springlab(&["run", p]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "stderr: {stderr}");
    assert_ne!(out.status.code(), Some(0));
    assert!(
        stderr.contains(&format!(
            "{p}:4:8: `mass` = -1 is out of range: allowed 1e-6 ..= 1e6 (kg)"
        )),
        "stderr: {stderr}"
    );
    assert!(text(&out.stdout).is_empty(), "no summary on error");
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
}

#[test]
fn unknown_key_in_a_scene_file_fails_with_its_position() {
    let path = write(
        "unknown",
        "oops.toml",
        "scene = \"rope\"\n[params]\nnodes = 5\nstifness = 3\n",
    );
    let p = path.to_str().expect("utf-8 path");
    let out = springlab(&["run", p]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "stderr: {stderr}");
    assert!(
        stderr.contains(&format!("{p}:4:1: unknown parameter `stifness`")),
        "stderr: {stderr}"
    );
    assert!(
        stderr.contains("stiffness"),
        "lists the known keys: {stderr}"
    );
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
}

#[test]
fn set_on_an_explicit_scene_file_fails() {
    let path = write(
        "set",
        "one.toml",
        "[[particles]]\nposition = [0, 0, 0]\nmass = 1\n",
    );
    let p = path.to_str().expect("utf-8 path");
    let out = springlab(&["run", p, "--set", "gravity=0"]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "stderr: {stderr}");
    assert!(stderr.contains("--set applies only"), "stderr: {stderr}");
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
}

#[test]
fn good_scene_file_runs_with_json_output() {
    let path = write(
        "good",
        "drop.toml",
        "[[particles]]\nposition = [0, 10, 0]\nmass = 1\n[run]\nmethod = \"rk4\"\ndt = 0.01\ntime = 1.0\n",
    );
    let p = path.to_str().expect("utf-8 path");
    let out = springlab(&["run", p, "--json"]);
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["scene"], "drop.toml");
    assert_eq!(json["method"], "rk4");
    assert_eq!(json["steps"], 100);
    assert_eq!(json["particles"], 1);
    // Free fall for 1 s from 10 m: RK4 is exact on constant acceleration, y = 10 - 4.9.
    let y = json["positions"][0][1].as_f64().expect("y");
    assert!((y - 5.1).abs() < 1e-9, "y = {y}");
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
}
