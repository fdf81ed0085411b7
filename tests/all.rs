//! The integration tests as one test binary: one link of the crate instead of one per file.
//!
//! Every file of `tests/` is a module here, except those that need a process of their own,
//! declared as `[[test]]` targets in `Cargo.toml` (the crate sets `autotests = false`):
//! - `threads.rs` sets `SPRINGLAB_THREADS` before the worker pool starts, which no other test
//!   may race;
//! - `budget_memory.rs` and `parsers_prop.rs` measure allocations with a counting global
//!   allocator (one per binary, and no other test allocating meanwhile);
//! - `tui_snapshots.rs` and `tui_layout.rs`: insta names snapshot files after the module path,
//!   and the committed snapshots carry the names of a binary of their own.
//!
//! `every_test_file_runs` below fails when a file of `tests/` is in neither list, so a new
//! test file cannot be left out silently. Run one file's tests with a filter:
//! `cargo test --release --test all cli_run::`.

mod common;

mod advise;
mod bench_workloads;
mod budget;
mod cli_progress;
mod cli_run;
mod cli_scene_files;
mod collide;
mod contact_energy;
mod course_scenes;
mod doc_numbers;
mod grade_boundary;
mod grade_cli;
mod grade_mistakes;
mod grade_reference;
mod grade_report;
mod grade_sandbox;
mod grade_timeout;
mod homework_live;
mod integrators;
mod lattice;
mod lesson8;
mod lesson8_app;
mod lesson_goals;
mod lesson_numbers;
mod lesson_prop;
mod lesson_spoilers;
mod lessons;
mod links;
mod nothing_lost;
mod physics;
mod progress_file;
mod recorded_numbers;
mod render;
mod render_cli;
mod render_depth;
mod resolution_limit;
mod run_accuracy;
mod scene_files;
mod simulation_fused;
mod study_convergence;
mod study_stability;
mod study_usable;
mod tui;
mod tui_burst;
mod tui_camera;
mod tui_charts;
mod tui_cli;
mod tui_export;
mod tui_raster;
mod tui_signals;
mod tui_theme;
mod tui_usable;

/// Every `tests/*.rs` file is a module of this binary or a `[[test]]` target of its own.
#[test]
fn every_test_file_runs() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let this = include_str!("all.rs");
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("Cargo.toml");
    let mut missing = Vec::new();
    let mut names: Vec<String> = std::fs::read_dir(root.join("tests"))
        .expect("tests/")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter_map(|n| n.strip_suffix(".rs").map(str::to_string))
        .filter(|n| n != "all")
        .collect();
    names.sort();
    assert!(names.len() > 30, "tests/ lists {} files", names.len());
    for name in names {
        let module = this.lines().any(|l| l == format!("mod {name};"));
        let target = manifest.contains(&format!("path = \"tests/{name}.rs\""));
        if !module && !target {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "tests/{{{}}}.rs run nowhere: add `mod NAME;` to tests/all.rs (or a [[test]] in Cargo.toml)",
        missing.join(",")
    );
}
