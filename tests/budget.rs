//! Every input gets bounded work: one test per row of the table of extreme inputs (issue 11),
//! through the real binary, and the budget's room for every built-in scene, scene file, lesson
//! step and README example.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use clap::Parser;
use springlab::budget::{self, Limits};
use springlab::cli::{self, Cli};

fn springlab_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run springlab")
}

fn springlab(args: &[&str]) -> Output {
    springlab_in(Path::new("."), args)
}

/// The one line on stderr of a run that must fail with exit status 1 and print nothing else.
fn refusal_in(dir: &Path, args: &[&str]) -> String {
    let out = springlab_in(dir, args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}: nothing on stdout");
    assert_eq!(err.lines().count(), 1, "{args:?}: one line, got {err}");
    assert!(err.starts_with("springlab: "), "{args:?}: {err}");
    err
}

fn refusal(args: &[&str]) -> String {
    refusal_in(Path::new("."), args)
}

/// A temporary directory, removed when dropped; it reads as its path.
struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

fn temp_dir(name: &str) -> Scratch {
    Scratch(
        tempfile::Builder::new()
            .prefix(&format!("springlab-budget-{name}-"))
            .tempdir()
            .expect("temp dir"),
    )
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

// ---------------------------------------------------------------------------------------------
// Row 1: step counts of a run.

#[test]
fn a_run_of_too_many_steps_is_refused_naming_the_count_and_the_limit() {
    let err = refusal(&["run", "rope", "--dt", "1e-300", "--time", "1"]);
    assert!(
        err.contains("run rope would take 1e300 steps (1 s at dt = 1e-300 s); at most 1e9 steps per run (use --force to run anyway)"),
        "{err}"
    );
    let err = refusal(&["run", "rope", "--time", "1e300"]);
    // 1e300 s / (1/64 s) = 6.4e301 steps.
    assert!(
        err.contains("would take 6.4e301 steps (1e300 s at dt = 0.015625 s)"),
        "{err}"
    );
    let err = refusal(&["run", "rope", "--steps", "18446744073709551615"]);
    assert!(err.contains("would take 1.84e19 steps"), "{err}");
    assert!(err.contains("at most 1e9 steps per run"), "{err}");

    let dir = temp_dir("dt-file");
    std::fs::write(
        dir.join("tiny.toml"),
        "scene = \"rope\"\n[run]\ndt = 1e-300\ntime = 1\n",
    )
    .expect("write");
    let err = refusal_in(&dir, &["run", "tiny.toml"]);
    assert!(
        err.contains("run tiny.toml would take 1e300 steps"),
        "{err}"
    );

    // The same run with --force is allowed past the budget (here: a short one to show the flag).
    let out = springlab(&["run", "rope", "--dt", "1e-3", "--time", "1", "--force"]);
    assert!(out.status.success());
}

// Row 2: studies whose runs are too long.

#[test]
fn studies_of_too_many_steps_are_refused() {
    let cases: [(&[&str], &str); 4] = [
        (
            &["study", "convergence", "oscillator", "--levels", "64"],
            "study convergence oscillator would take 2.95e22 steps",
        ),
        (
            &["study", "convergence", "oscillator", "--dt", "1e-300"],
            "study convergence oscillator would take 1.28e302 steps",
        ),
        (
            &["study", "convergence", "oscillator", "--time", "1e300"],
            "study convergence oscillator would take 2.56e304 steps",
        ),
        (
            &["study", "work-precision", "rope", "--levels", "40"],
            "study work-precision rope would take 5.63e14 steps",
        ),
    ];
    for (args, expected) in cases {
        let err = refusal(args);
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(
            err.contains("at most 1e9 steps per run (use --force"),
            "{err}"
        );
    }
    let err = refusal(&["study", "stability", "rope", "--horizon", "1e300"]);
    assert!(
        err.contains("would take 1.73e303 steps (the smallest probe: 1e300 s"),
        "{err}"
    );
}

// Row 3: allowed but long studies: an estimate up front, progress on a terminal, Ctrl-C.

/// Starts `args`, returns the first line of stderr, the child (still running) and the rest of
/// its stderr.
fn first_stderr_line(
    args: &[&str],
) -> (
    String,
    std::process::Child,
    BufReader<std::process::ChildStderr>,
) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut stderr = BufReader::new(child.stderr.take().expect("stderr"));
    let mut line = String::new();
    stderr.read_line(&mut line).expect("read");
    (line, child, stderr)
}

#[test]
fn long_studies_announce_their_cost_and_stop_on_ctrl_c() {
    let (line, mut child, _) =
        first_stderr_line(&["study", "stability", "rope", "--set", "nodes=1000000"]);
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        line.starts_with("springlab: study stability rope: about "),
        "{line}"
    );
    assert!(line.contains("1000000 particles, 999999 springs"), "{line}");
    assert!(line.contains("Ctrl-C stops it"), "{line}");

    let (line, mut child, mut rest) =
        first_stderr_line(&["study", "convergence", "rope", "--set", "nodes=100000"]);
    assert!(
        line.starts_with("springlab: study convergence rope: about "),
        "{line}"
    );
    assert!(line.contains("100000 particles, 99999 springs"), "{line}");
    // Ctrl-C: exit status 130 and one line saying so.
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(status.success());
    let mut tail = String::new();
    std::io::Read::read_to_string(&mut rest, &mut tail).expect("read");
    assert_eq!(child.wait().expect("wait").code(), Some(130));
    assert_eq!(
        tail,
        "springlab: interrupted (Ctrl-C); unfinished outputs were removed\n"
    );
}

#[test]
fn progress_shows_on_a_terminal_and_not_in_a_pipe() {
    // `script` gives the run a pseudo-terminal; what the terminal shows comes back on stdout.
    let command = format!(
        "{} study convergence rope --set nodes=100000 --methods rk4",
        env!("CARGO_BIN_EXE_springlab")
    );
    let out = Command::new("timeout")
        .args(["-s", "KILL", "3", "script", "-qfec", &command, "/dev/null"])
        .output()
        .expect("run script (util-linux) for a pseudo-terminal");
    let screen = String::from_utf8_lossy(&out.stdout);
    // The bar: label, position/length (1 method × 4 levels), elapsed time, time left.
    assert!(
        screen.contains("study convergence rope")
            && screen.contains(" 0/4 ")
            && screen.contains(" left"),
        "no progress bar on the terminal: {screen}"
    );
    // Piped: no progress, only the result.
    let out = springlab(&[
        "study",
        "convergence",
        "rope",
        "--set",
        "nodes=200",
        "--methods",
        "rk4",
    ]);
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

// Rows 4 and 5: memory of scene files.

#[test]
fn a_hundred_byte_file_of_five_million_particles_is_refused_with_its_memory() {
    let dir = temp_dir("five");
    let text = "[[ropes]]\nnodes = 1000000\n".repeat(5);
    assert!(text.len() < 150);
    std::fs::write(dir.join("five.toml"), &text).expect("write");
    let err = refusal_in(&dir, &["run", "five.toml"]);
    // 5e6 particles and 5e6 - 5 springs at the byte counts of the real structures (every
    // method, implicit Euler's lattice solver included).
    let bytes = budget::BASE_BYTES
        + budget::PARSE_BYTES * text.len() as f64
        + budget::body_bytes(5e6, 5e6 - 5.0, &springlab::Method::ALL, 1.0);
    assert!(bytes > 5.5e9 && bytes < 6.5e9, "{bytes}");
    let expected = format!(
        "scene file five.toml would need about {} of memory (5000000 particles, 4999995 springs); at most 2.1 GB (use --force to run anyway)",
        budget::bytes(bytes)
    );
    assert!(err.contains(&expected), "{err}\nexpected {expected}");
}

#[test]
fn a_fifty_megabyte_scene_file_is_refused_before_it_is_parsed() {
    let dir = temp_dir("big");
    let particle = "[[particles]]\nposition = [0.0, 0.0, 0.0]\nmass = 1.0\n";
    let text = particle.repeat(50_000_000 / particle.len() + 1);
    std::fs::write(dir.join("big.toml"), &text).expect("write");
    let err = refusal_in(&dir, &["run", "big.toml"]);
    assert!(
        err.contains(&format!(
            "big.toml is {}; scene and lesson files may be at most 16.8 MB (use --force to read it anyway)",
            budget::bytes(text.len() as f64)
        )),
        "{err}"
    );
}

// Row 6: render size, and outputs that are complete or absent.

#[test]
fn a_render_larger_than_4k_is_refused() {
    let dir = temp_dir("size");
    let err = refusal_in(
        &dir,
        &[
            "render",
            "rope",
            "--frames",
            "3",
            "--size",
            "8192x8192",
            "--gif",
            "g.gif",
        ],
    );
    assert!(
        err.contains("render rope: --size 8192x8192 is 6.71e7 pixels per frame; at most 8294400 (3840x2160) (use --force to run anyway)"),
        "{err}"
    );
    let err = refusal_in(
        &dir,
        &[
            "render",
            "rope",
            "--frames",
            "1000000",
            "--size",
            "3840x2160",
            "--gif",
            "g.gif",
        ],
    );
    assert!(
        err.contains(
            "would draw 8.29e12 pixels (1000000 frames of --size 3840x2160); at most 1e10"
        ),
        "{err}"
    );
    assert!(files_in(&dir).is_empty());
}

#[test]
fn a_render_killed_half_way_leaves_no_file_at_the_target_path() {
    let dir = temp_dir("kill");
    let mut child = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args([
            "render",
            "cloth-spheres",
            "--frames",
            "5000",
            "--gif",
            "g.gif",
            "--apng",
            "a.png",
        ])
        .current_dir(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    // Wait until the GIF is being written (its temporary file has data), then kill -9.
    let start = Instant::now();
    loop {
        let writing = files_in(&dir).iter().any(|n| {
            n.starts_with(".g.gif.")
                && std::fs::metadata(dir.join(n)).is_ok_and(|m| m.len() > 10_000)
        });
        if writing || start.elapsed() > Duration::from_secs(60) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().expect("kill -9");
    child.wait().expect("wait");
    let names = files_in(&dir);
    assert!(!names.contains(&"g.gif".to_string()), "{names:?}");
    assert!(!names.contains(&"a.png".to_string()), "{names:?}");
    assert!(
        names.iter().any(|n| n.starts_with(".g.gif.")),
        "it was writing: {names:?}"
    );
}

#[test]
fn a_render_stopped_by_ctrl_c_removes_every_output() {
    let dir = temp_dir("int");
    let child = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args([
            "render",
            "cloth-spheres",
            "--frames",
            "5000",
            "--gif",
            "g.gif",
            "--out",
            "fr",
        ])
        .current_dir(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // Frames are staged in a hidden folder inside `fr` until the render finishes.
    let staged = |dir: &std::path::Path| {
        std::fs::read_dir(dir.join("fr")).is_ok_and(|entries| {
            entries
                .filter_map(Result::ok)
                .any(|e| e.path().join("frame_00002.png").exists())
        })
    };
    let start = Instant::now();
    while !staged(&dir) && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(130));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("interrupted (Ctrl-C); unfinished outputs were removed")
    );
    // `fr` was made by the render: it is removed with the staged frames and the GIF's file.
    assert_eq!(files_in(&dir), Vec::<String>::new());
}

// Row 7: every output path is checked before simulating.

#[test]
fn an_unwritable_output_fails_before_the_simulation() {
    let dir = temp_dir("paths");
    let err = refusal_in(
        &dir,
        &[
            "render",
            "cloth-spheres",
            "--frames",
            "200",
            "--gif",
            "g.gif",
            "--energy-chart",
            "/sys/kernel/e.png",
        ],
    );
    assert!(err.contains("cannot write /sys/kernel/e.png"), "{err}");
    assert!(
        files_in(&dir).is_empty(),
        "nothing written: {:?}",
        files_in(&dir)
    );
    let err = refusal_in(
        &dir,
        &["render", "rope", "--frames", "2", "--apng", "missing/a.png"],
    );
    assert!(
        err.contains("cannot write missing/a.png: directory missing does not exist"),
        "{err}"
    );
    std::fs::write(dir.join("file"), "x").expect("write");
    let err = refusal_in(&dir, &["render", "rope", "--frames", "2", "--out", "file"]);
    assert!(
        err.contains("cannot write file: it exists and is not a directory"),
        "{err}"
    );
    let err = refusal_in(&dir, &["run", "rope", "--csv", "/sys/kernel/r.csv"]);
    assert!(err.contains("cannot write /sys/kernel/r.csv"), "{err}");
    let err = refusal_in(
        &dir,
        &["study", "convergence", "oscillator", "--png", "nodir/c.png"],
    );
    assert!(
        err.contains("cannot write nodir/c.png: directory nodir does not exist"),
        "{err}"
    );
}

// Rows 8 and 9: a time step longer than the run.

#[test]
fn a_time_step_longer_than_the_run_is_refused() {
    let err = refusal(&["run", "rope", "--dt", "1e300"]);
    assert!(
        err.contains("--dt 1e300 s is longer than the run (the scene's duration 10 s)"),
        "{err}"
    );
    let err = refusal(&["run", "rope", "--dt", "2", "--time", "1"]);
    assert!(
        err.contains("--dt 2 s is longer than the run (--time 1 s)"),
        "{err}"
    );
    let err = refusal(&["study", "convergence", "oscillator", "--dt", "1e300"]);
    assert!(
        err.contains("--dt 1e300 s is longer than the time the error is measured at (--time 1 s)"),
        "{err}"
    );
    let dir = temp_dir("long-dt");
    std::fs::write(
        dir.join("s.toml"),
        "scene = \"rope\"\n[run]\ntime = 2\ndt = 1e300\n",
    )
    .expect("write");
    let err = refusal_in(&dir, &["run", "s.toml"]);
    assert!(
        err.contains("s.toml:4:6: `dt` = 1e300 s is longer than the run (`time` = 2 s)"),
        "{err}"
    );
    let err = refusal(&[
        "render", "rope", "--time", "1", "--dt", "5", "--gif", "x.gif",
    ]);
    assert!(
        err.contains("--dt 5 s is longer than the run (--time 1 s)"),
        "{err}"
    );
}

// Row 10: physically meaningless parameters.

#[test]
fn denormal_masses_and_overflowing_stiffness_are_out_of_range() {
    let dir = temp_dir("ranges");
    std::fs::write(
        dir.join("tiny.toml"),
        "[[particles]]\nposition = [0.0, 0.0, 0.0]\nmass = 1e-320\n",
    )
    .expect("write");
    let err = refusal_in(&dir, &["run", "tiny.toml"]);
    assert!(
        err.contains("tiny.toml:3:8: `mass` = 1e-320 is out of range: allowed 1e-6 ..= 1e6 (kg)"),
        "{err}"
    );
    let err = refusal(&["run", "rope", "--set", "stiffness=1e308"]);
    assert!(
        err.contains("`stiffness` = 1e308 is out of range: allowed 0 ..= 1e9 (N/m)"),
        "{err}"
    );
    let err = refusal(&["run", "cube-plane", "--set", "mass=1e-320"]);
    assert!(
        err.contains("`mass` = 1e-320 is out of range: allowed 1e-6 ..= 1e6 (kg)"),
        "{err}"
    );
    let err = refusal(&["run", "cloth-sphere", "--set", "damping=1e300"]);
    assert!(
        err.contains("`damping` = 1e300 is out of range: allowed 0 ..= 1e9 (N·s/m)"),
        "{err}"
    );
    // Inside the ranges the force stays finite: the stiffest spring on the lightest mass.
    let out = springlab(&[
        "run",
        "oscillator",
        "--set",
        "stiffness=1e9",
        "--set",
        "mass=1e-6",
        "--steps",
        "10",
        "--json",
    ]);
    assert!(out.status.success());
}

// Row 11: one clear line each.

#[test]
fn cosmetic_messages_say_each_thing_once_and_briefly() {
    // An OS error once.
    let err = refusal(&["run", "missing.toml"]);
    assert_eq!(
        err.trim_end(),
        "springlab: cannot read scene file missing.toml: No such file or directory (os error 2)"
    );
    // Huge numbers in short form.
    let err = refusal(&["study", "stability", "rope", "--horizon", "1e300"]);
    assert!(err.len() < 300 && err.contains("1e300"), "{err}");
    let err = refusal(&["run", "rope", "--time", "-1e300"]);
    assert_eq!(
        err.trim_end(),
        "springlab: --time -1e300: expected a duration in seconds >= 0"
    );
    // Non-finite vectors: "finite".
    let err = refusal(&["run", "rope", "--set", "start=[nan,0,0]"]);
    assert!(
        err.contains("`start` = [NaN, 0, 0]: expected a vector [x, y, z] of finite numbers"),
        "{err}"
    );
    // A negative step count.
    let out = springlab(&["run", "rope", "--steps", "-5"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains(
            "invalid value '-5' for '--steps <STEPS>': expected a whole number of steps >= 0"
        ),
        "{err}"
    );
}

#[test]
fn duplicate_lesson_numbers_and_slugs_are_rejected_with_file_and_line() {
    let dir = temp_dir("lessons");
    let lesson = |number: u32, slug: &str| {
        format!(
            "+++\nnumber = {number}\nslug = \"{slug}\"\ntitle = \"T\"\nsummary = \"S\"\n+++\n\n+++ step\ntitle = \"s\"\nscene = \"rope\"\n+++\nText.\n"
        )
    };
    std::fs::write(dir.join("a.md"), lesson(1, "one")).expect("write");
    std::fs::write(dir.join("b.md"), lesson(1, "two")).expect("write");
    std::fs::write(dir.join("c.md"), lesson(3, "one")).expect("write");
    let lessons = springlab::lesson::load_dir(&dir).expect("load");
    let errors: Vec<String> = lessons
        .iter()
        .filter_map(|l| l.as_ref().err().map(ToString::to_string))
        .collect();
    let a = dir.join("a.md").display().to_string();
    let b = dir.join("b.md").display().to_string();
    let c = dir.join("c.md").display().to_string();
    assert_eq!(
        errors,
        vec![
            format!(
                "{b}:2: lesson number 1 is already used by {a}:2; give each lesson its own number"
            ),
            format!(
                "{c}:3: lesson slug \"one\" is already used by {a}:3; give each lesson its own slug"
            ),
        ]
    );
    assert_eq!(lessons.iter().filter(|l| l.is_ok()).count(), 1);
    // The built-in lessons have distinct numbers and slugs.
    assert!(springlab::lesson::builtin().iter().all(Result::is_ok));
}

// ---------------------------------------------------------------------------------------------
// Room: what ships passes the budget with a margin.

/// The default limits divided by `room`.
fn tight(room: f64) -> Limits {
    let d = Limits::DEFAULT;
    Limits {
        steps: d.steps / room,
        work: d.work / room,
        memory: d.memory / room,
        frame_pixels: d.frame_pixels / room,
        total_pixels: d.total_pixels / room,
        file_bytes: d.file_bytes / room as u64,
    }
}

fn estimate_of(line: &str) -> Option<budget::Estimate> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let cli = Cli::try_parse_from(&words).unwrap_or_else(|e| panic!("{line}: {e}"));
    let command = cli.command?;
    cli::estimate(&command).unwrap_or_else(|e| panic!("{line}: {e}"))
}

#[test]
fn readme_examples_pass_with_ten_times_room() {
    let readme = std::fs::read_to_string("README.md").expect("README");
    let mut checked = 0;
    for line in readme.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if !line.starts_with("springlab ") || line.contains("homework") || line.contains("grade") {
            continue;
        }
        if let Some(e) = estimate_of(line) {
            e.check(&tight(10.0))
                .unwrap_or_else(|err| panic!("{line}: {err}"));
            checked += 1;
        }
    }
    assert!(checked >= 15, "{checked} README examples checked");
}

#[test]
fn builtin_scenes_scene_files_and_lesson_steps_pass_with_room() {
    let mut targets: Vec<String> = springlab::scene::BUILTIN
        .iter()
        .map(|d| d.name.to_string())
        .collect();
    for entry in std::fs::read_dir("scenes").expect("scenes/") {
        targets.push(entry.expect("entry").path().display().to_string());
    }
    for target in &targets {
        for method in springlab::Method::ALL {
            let run = format!("springlab run {target} --method {method}");
            estimate_of(&run)
                .expect("run")
                .check(&tight(10.0))
                .unwrap_or_else(|e| panic!("{run}: {e}"));
        }
        let render = format!("springlab render {target} --frames 100 --gif x.gif");
        estimate_of(&render)
            .expect("render")
            .check(&tight(10.0))
            .unwrap_or_else(|e| panic!("{render}: {e}"));
        let study = format!("springlab study stability {target}");
        estimate_of(&study)
            .expect("study")
            .check(&tight(5.0))
            .unwrap_or_else(|e| panic!("{study}: {e}"));
        if !target.ends_with(".toml") {
            // The convergence study applies `--set iterations=0`, which files without `scene =`
            // do not take.
            let study = format!("springlab study convergence {target}");
            estimate_of(&study)
                .expect("study")
                .check(&tight(5.0))
                .unwrap_or_else(|e| panic!("{study}: {e}"));
        }
    }
    for lesson in springlab::lesson::builtin() {
        let lesson = lesson.expect("built-in lesson");
        for step in &lesson.steps {
            let scene = step.build_scene().expect("step scene");
            let dt = scene.dt;
            let e = budget::run("lesson step", &scene, dt, (scene.duration / dt).round());
            e.check(&tight(10.0))
                .unwrap_or_else(|err| panic!("{}: {err}", step.title));
        }
    }
}
