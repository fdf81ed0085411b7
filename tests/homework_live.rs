//! Your code in the lesson, headless: real homework crates (built through the grader's sandbox,
//! run as programs of their own) step a lesson step's body beside springlab's reference. Each
//! planted mistake of the courses is reported with the step and the quantity where the two part;
//! the correct crates do not part over the step's horizon; a crate that panics, loops or exits
//! gives its message while the reference keeps going.
//!
//! Builds are shared with `grade_boundary.rs` (one target directory, programs cached by
//! content), and one crate carries several mistakes when each sits in a different method.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::{Duration, Instant};

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::grade::Assignment;
use springlab::grade::build::Builder;
use springlab::grade::live::{
    BuildOptions, Frame, Homework, Live, LiveOptions, Quantity, Reload, Setup, Watcher,
    build_homework, builder,
};
use springlab::lesson::{self, Lesson};
use springlab::physics::Method;
use springlab::simulation::Simulation;
use springlab::tui::{App, Screen, Theme};

const ROPE: &str = include_str!("homework/rope.rs");
const JELLY: &str = include_str!("homework/jelly.rs");
const INTEGRATORS: &str = include_str!("homework/integrators.rs");

fn target() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("grade-builds")
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("homework-live-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

/// `text` with `from` replaced by `to`, which must occur exactly once.
fn patch(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from}");
    text.replace(from, to)
}

/// A homework crate `parent/name` of `assignment` with `lib` as src/lib.rs and `integrators`
/// beside it.
fn homework(parent: &Path, name: &str, assignment: &str, lib: &str, integrators: &str) -> PathBuf {
    let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(parent)
        .args(["homework", "new", name, "--assignment", assignment])
        .output()
        .expect("run springlab");
    assert!(out.status.success(), "{out:?}");
    let dir = parent.join(name);
    std::fs::write(dir.join("src/lib.rs"), lib).expect("write lib.rs");
    std::fs::write(dir.join("src/integrators.rs"), integrators).expect("write");
    dir
}

fn options() -> BuildOptions {
    BuildOptions {
        target_dir: target(),
        call_limit: Duration::from_secs(4),
    }
}

fn the_builder() -> Arc<Builder> {
    builder(&options()).expect("builder")
}

fn lesson(number: u32) -> Lesson {
    lesson::builtin()
        .into_iter()
        .map(|l| l.expect("lesson parses"))
        .find(|l| l.number == number)
        .expect("lesson exists")
}

/// The set-up of lesson `number`'s step `step` (from 1) with `method` if given, over the
/// step's horizon (`seconds` when it has none).
fn setup(
    assignment: Assignment,
    number: u32,
    step: usize,
    method: Option<Method>,
    seconds: f64,
) -> Setup {
    let l = lesson(number);
    let s = &l.steps[step - 1];
    let mut scene = s.build_scene().expect("scene");
    if let Some(m) = method {
        scene.set_method(m);
    }
    let horizon = if s.horizon() > 0.0 {
        s.horizon()
    } else {
        seconds
    };
    Setup::from_scene(assignment, number, &scene, horizon).expect("setup")
}

/// Runs the comparison to its horizon and returns the last frame (and every frame's failure
/// state stays in it).
fn run(dir: &Path, builder: &Arc<Builder>, setup: Setup) -> Frame {
    let built = build_homework(dir, builder, &options()).expect("builds");
    let horizon = setup.horizon;
    let live = Live::start(built.homework, setup, LiveOptions::default());
    live.run_free();
    loop {
        let frame = live
            .next_frame(Duration::from_secs(60))
            .expect("a frame within a minute");
        if frame.finished {
            assert_eq!(frame.step, horizon, "finishes at the horizon");
            return frame;
        }
    }
}

fn parting(frame: &Frame) -> (u64, Quantity) {
    let p = frame
        .parting
        .unwrap_or_else(|| panic!("a parting is reported: {frame:?}"));
    println!("{}", p.describe());
    (p.step, p.quantity)
}

#[test]
fn correct_crates_never_part_from_the_reference() {
    let parent = scratch("correct");
    let b = the_builder();
    let rope = homework(&parent, "rope", "rope", ROPE, INTEGRATORS);
    let cases = [
        // Lesson 1: the rope's semi-implicit Euler; lesson 3: explicit Euler on the rope;
        // lesson 4: Verlet beside semi-implicit Euler, with damping.
        setup(Assignment::Rope, 1, 1, None, 10.0),
        setup(Assignment::Rope, 3, 3, None, 5.0),
        setup(Assignment::Rope, 4, 3, None, 10.0),
    ];
    for s in cases {
        let name = s.integrator.name();
        let frame = run(&rope, &b, s);
        assert_eq!(frame.failure, None, "{name}");
        assert_eq!(frame.parting, None, "{name}: {frame:?}");
        assert!(frame.distance < 1e-9, "{name}: {}", frame.distance);
    }
    let jelly = homework(&parent, "jelly", "jelly", JELLY, INTEGRATORS);
    let s = setup(Assignment::Jelly, 5, 2, Some(Method::Rk4), 0.5);
    let frame = run(&jelly, &b, s);
    assert_eq!(frame.failure, None);
    assert_eq!(frame.parting, None, "{frame:?}");
}

#[test]
fn each_planted_mistake_parts_at_its_step_and_quantity() {
    let parent = scratch("mistakes");
    let b = the_builder();
    // Three mistakes in three methods of one crate: Verlet without its damping factor,
    // explicit Euler adding the acceleration to the position, semi-implicit Euler moving with
    // the old velocity.
    let mut lib = patch(
        ROPE,
        "(1.0 - damping) * (x - m.last_position)",
        "(x - m.last_position)",
    );
    lib = patch(
        &lib,
        "                m.position += dt * m.velocity;\n                m.velocity += dt * a;",
        "                m.position += dt * a;\n                m.velocity += dt * a;",
    );
    lib = patch(
        &lib,
        "                m.velocity += dt * a;\n                m.position += dt * m.velocity;",
        "                m.position += dt * m.velocity;\n                m.velocity += dt * a;",
    );
    let rope = homework(&parent, "rope", "rope", &lib, INTEGRATORS);
    // Verlet without damping: the rope starts at rest (x_0 - x_{-1} = 0), so step 1 agrees;
    // at step 2 the displacement lacks γ of itself, seen first in Verlet's velocity
    // (x_n - x_{n-1})/dt, which divides the position difference by dt.
    let verlet = run(&rope, &b, setup(Assignment::Rope, 4, 3, None, 10.0));
    assert_eq!(parting(&verlet), (2, Quantity::Velocity));
    // x += a dt: wrong from the first step on, in the position.
    let explicit = run(&rope, &b, setup(Assignment::Rope, 3, 3, None, 5.0));
    assert_eq!(parting(&explicit), (1, Quantity::Position));
    // Semi-implicit Euler with the old velocity is explicit Euler: the position lags by dt² a.
    let semi = run(&rope, &b, setup(Assignment::Rope, 1, 1, None, 10.0));
    assert_eq!(parting(&semi), (1, Quantity::Position));

    // The pinned end moves: projection moves both ends of every spring by half.
    let pins = patch(
        ROPE,
        "match (pa, pb) {",
        "match (false && pa, false && pb) {",
    );
    let pins = homework(&parent, "pins", "rope", &pins, INTEGRATORS);
    // The first projection already moves the pin; Verlet's velocity shows it first (the
    // displacement over dt = 1/64 s passes τV before the displacement passes τL).
    let moved = run(&pins, &b, setup(Assignment::Rope, 4, 3, None, 10.0));
    assert_eq!(parting(&moved), (1, Quantity::Velocity));

    // RK4 without k1 in the final combination: wrong from the first step.
    let rk4 = patch(
        &patch(INTEGRATORS, "(k1x[i] + 2.0 * k2x[i]", "(2.0 * k2x[i]"),
        "(k1v[i] + 2.0 * k2v[i]",
        "(2.0 * k2v[i]",
    );
    let jelly = homework(&parent, "jelly", "jelly", JELLY, &rk4);
    let frame = run(
        &jelly,
        &b,
        setup(Assignment::Jelly, 5, 2, Some(Method::Rk4), 0.5),
    );
    // The weights sum to 5/6: the velocity update lacks a sixth of a dt of acceleration at
    // once, the position only dt² of it.
    assert_eq!(parting(&frame), (1, Quantity::Velocity));
}

#[test]
fn a_panicking_looping_or_exiting_crate_is_a_message_and_the_reference_keeps_going() {
    let parent = scratch("hostile");
    let b = the_builder();
    let verlet = "fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {";
    let explicit = "fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {";
    let semi = "fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {";
    let mut lib = patch(
        ROPE,
        verlet,
        &format!(
            "{verlet}\n        static CALLS: std::sync::atomic::AtomicUsize = \
             std::sync::atomic::AtomicUsize::new(0);\n        \
             if CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) == 11 {{\n            \
             let empty: Vec<usize> = Vec::new();\n            let _ = empty[rope.masses.len()];\n        }}"
        ),
    );
    lib = patch(
        &lib,
        explicit,
        &format!("{explicit}\n        std::process::exit(3);"),
    );
    lib = patch(&lib, semi, &format!("{semi}\n        loop {{}}"));
    let dir = homework(&parent, "hostile", "rope", &lib, INTEGRATORS);

    let panics = run(&dir, &b, setup(Assignment::Rope, 4, 3, None, 10.0));
    let why = panics.failure.expect("the panic is reported");
    assert!(
        why.starts_with("your verlet() panicked at step 12: index out of bounds")
            && why.contains("src/lib.rs:"),
        "{why}"
    );
    assert_eq!(panics.yours, None, "your side stops");
    assert_eq!(panics.reference.len(), 12, "the reference keeps its rope");

    let exits = run(&dir, &b, setup(Assignment::Rope, 3, 3, None, 5.0));
    let why = exits.failure.expect("the exit is reported");
    assert!(
        why.starts_with("your program ended during explicit_euler() at step 1")
            && why.contains("status 3"),
        "{why}"
    );

    // The endless loop: the call's deadline ends it, the reference goes on; stopping never
    // waits for a call in progress.
    let quick = BuildOptions {
        call_limit: Duration::from_millis(500),
        ..options()
    };
    let built = build_homework(&dir, &b, &quick).expect("builds");
    let live = Live::start(
        built.homework,
        setup(Assignment::Rope, 1, 1, None, 10.0),
        LiveOptions::default(),
    );
    live.run_free();
    let failed = loop {
        let frame = live.next_frame(Duration::from_secs(30)).expect("a frame");
        if frame.failure.is_some() {
            break frame;
        }
    };
    let why = failed.failure.expect("failure");
    assert_eq!(
        why, "your semi_implicit_euler() did not return in time at step 1",
        "{why}"
    );
    let later = live
        .next_frame(Duration::from_secs(30))
        .expect("the reference goes on");
    assert!(later.step > failed.step);
    drop(live);

    let built = build_homework(&dir, &b, &quick).expect("builds");
    let live = Live::start(
        built.homework,
        setup(Assignment::Rope, 1, 1, None, 10.0),
        LiveOptions::default(),
    );
    live.run_free();
    std::thread::sleep(Duration::from_millis(100));
    let asked = Instant::now();
    drop(live);
    assert!(
        asked.elapsed() < Duration::from_secs(1),
        "stopping returns while the student's loop runs"
    );
}

/// The next report of `watcher` that is not `Building`, waiting up to a minute.
fn settled(watcher: &Watcher) -> Reload {
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        match watcher.next(Duration::from_millis(200)) {
            Some(Reload::Building) | None => {}
            Some(other) => return other,
        }
    }
    panic!("no build result within a minute");
}

#[test]
fn a_save_rebuilds_the_crate_and_reports_the_first_compiler_error_or_reloaded() {
    let parent = scratch("watch");
    let dir = homework(&parent, "rope", "rope", ROPE, INTEGRATORS);
    let watcher = Watcher::start(&dir, the_builder(), options()).expect("watch");
    assert_eq!(
        watcher.next(Duration::from_secs(5)).map(|r| r.status()),
        Some("building…".to_string())
    );
    let Reload::Reloaded(first) = settled(&watcher) else {
        panic!("the first build succeeds");
    };
    assert_eq!(first.assignment, Assignment::Rope);
    // A save with a type error: the compiler's first error, bounded.
    let broken = patch(
        ROPE,
        "        let d = b - a;\n        let l = d.length();",
        "        let d = b - a;\n        let l: u8 = d.length();",
    );
    std::fs::write(dir.join("src/lib.rs"), &broken).expect("save");
    let Reload::Failed(why) = settled(&watcher) else {
        panic!("the broken save does not build");
    };
    assert!(
        why.starts_with("your crate did not build: error[E0308]: mismatched types"),
        "{why}"
    );
    assert!(why.lines().count() <= 12 && why.len() <= 1300, "{why}");
    // The fix: reloaded, and the new program is the correct one.
    std::fs::write(dir.join("src/lib.rs"), ROPE).expect("save");
    let Reload::Reloaded(fixed) = settled(&watcher) else {
        panic!("the fixed crate builds");
    };
    let live = Live::start(
        fixed.homework.clone(),
        setup(Assignment::Rope, 3, 3, None, 1.0),
        LiveOptions::default(),
    );
    live.run_free();
    let last = std::iter::from_fn(|| live.next_frame(Duration::from_secs(30)))
        .find(|f| f.finished)
        .expect("finishes");
    assert_eq!(last.parting, None);
}

/// The app, headless, on lesson 4 with the crate in `dir` attached; runs until the screen
/// (120×40) shows `wanted` and returns it.
fn app_until(dir: &Path, wanted: &str) -> (App, String) {
    let mut app = App::new(lesson::builtin(), Theme::PLAIN)
        .with_homework_options(Some(dir.to_path_buf()), options());
    let i = app.find_lesson("verlet").expect("lesson 4");
    app.open_lesson(i).expect("opens");
    app.handle_key(KeyEvent::new(KeyCode::Char(' '), KeyModifiers::NONE));
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        app.tick(0.05);
        let mut terminal = Terminal::new(TestBackend::new(120, 40)).expect("backend");
        terminal
            .draw(|frame| frame.render_widget(&app, frame.area()))
            .expect("draw");
        let text = terminal.backend().to_string();
        if text.contains(wanted) {
            return (app, text);
        }
        assert!(Instant::now() < deadline, "never shown: {wanted}\n{text}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn the_app_shows_both_ropes_the_parting_and_a_failure_and_quits_at_once() {
    let parent = scratch("app");
    let lib = patch(
        ROPE,
        "(1.0 - damping) * (x - m.last_position)",
        "(x - m.last_position)",
    );
    let undamped = homework(&parent, "undamped", "rope", &lib, INTEGRATORS);
    let (_, text) = app_until(&undamped, "parted at step 2");
    assert!(text.contains("── yours ── reference"), "{text}");
    assert!(text.contains("verlet()"), "{text}");

    let verlet = "fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {";
    let lib = patch(
        ROPE,
        verlet,
        &format!(
            "{verlet}\n        static CALLS: std::sync::atomic::AtomicUsize = \
             std::sync::atomic::AtomicUsize::new(0);\n        \
             if CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) == 11 {{\n            \
             let empty: Vec<usize> = Vec::new();\n            let _ = empty[rope.masses.len()];\n        }}"
        ),
    );
    let panics = homework(&parent, "panics", "rope", &lib, INTEGRATORS);
    let (mut app, _) = app_until(
        &panics,
        "your verlet() panicked at step 12: index out of bounds",
    );
    let asked = Instant::now();
    app.handle_key(KeyEvent::new(KeyCode::Char('q'), KeyModifiers::NONE));
    assert!(matches!(app.screen(), Screen::Menu), "q leaves the lesson");
    drop(app);
    assert!(
        asked.elapsed() < Duration::from_secs(1),
        "q answers at once"
    );
}

#[test]
fn a_failed_check_names_the_lesson_that_shows_it_live() {
    let parent = scratch("see-it");
    let lib = patch(
        ROPE,
        "(1.0 - damping) * (x - m.last_position)",
        "(x - m.last_position)",
    );
    homework(&parent, "undamped", "rope", &lib, INTEGRATORS);
    let t = target();
    let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(&parent)
        .args(["grade", "undamped", "--target-dir"])
        .arg(&t)
        .output()
        .expect("run springlab grade");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("score 30 / 35"), "{stdout}");
    // The damping item fails; its hint names lesson 4; the passing items name nothing.
    assert_eq!(
        stdout
            .matches("see it: springlab lesson 4 --homework .")
            .count(),
        stdout.matches("): failed").count(),
        "{stdout}"
    );
    assert!(
        stdout.contains("see it: springlab lesson 4 --homework ."),
        "{stdout}"
    );
    assert!(!stdout.contains("see it: springlab lesson 3"), "{stdout}");
}

/// Every step of `dir`'s program on `setup`, to the horizon, with up to `ahead` steps per
/// request: the student's positions and energy of each step.
fn every_step(dir: &Path, b: &Arc<Builder>, setup: &Setup, ahead: u32) -> Vec<(Vec<u64>, u64)> {
    let built = build_homework(dir, b, &options()).expect("builds");
    let options = LiveOptions {
        frame_every: 1,
        ahead,
        ..LiveOptions::default()
    };
    let live = Live::start(built.homework, setup.clone(), options);
    live.run_free();
    let mut steps = Vec::new();
    loop {
        let frame = live
            .next_frame(Duration::from_secs(60))
            .expect("a frame within a minute");
        assert_eq!(frame.failure, None);
        if frame.finished {
            return steps;
        }
        let x = frame.yours.expect("your body");
        let bits = x
            .iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect();
        steps.push((bits, frame.energy_yours.expect("energy").to_bits()));
    }
}

#[test]
fn many_steps_per_request_give_the_bodies_of_one_call_per_step_bit_for_bit() {
    let parent = scratch("batched");
    let b = the_builder();
    let rope = homework(&parent, "rope", "rope", ROPE, INTEGRATORS);
    let verlet = setup(Assignment::Rope, 4, 3, None, 10.0);
    let single = every_step(&rope, &b, &verlet, 1);
    assert_eq!(single.len() as u64, verlet.horizon);
    assert_eq!(every_step(&rope, &b, &verlet, 64), single, "Verlet rope");

    // The 4×4×4 cube falls onto the plane y = -1 within its first second: the collision
    // response between steps drops the steps a request computed past a contact.
    let jelly = homework(&parent, "jelly", "jelly", JELLY, INTEGRATORS);
    let rk4 = setup(Assignment::Jelly, 5, 2, Some(Method::Rk4), 1.6);
    let single = every_step(&jelly, &b, &rk4, 1);
    let lowest = single
        .iter()
        .flat_map(|(x, _)| x.chunks(3).map(|p| f64::from_bits(p[1])))
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest < -0.95,
        "the cube reaches the plane: lowest y {lowest}"
    );
    assert_eq!(every_step(&jelly, &b, &rk4, 64), single, "RK4 jelly");
}

#[test]
fn a_program_of_another_protocol_version_is_told_to_update() {
    let parent = scratch("old-version");
    let b = the_builder();
    // Before `main` (the grader's own main.rs) runs, this program answers the greeting as a
    // program built against protocol version 2 would, then waits for the end of its input.
    let old = format!(
        "{ROPE}\n\
         #[used]\n\
         #[unsafe(link_section = \".init_array\")]\n\
         static OLD_PROGRAM: extern \"C\" fn() = old_program;\n\
         extern \"C\" fn old_program() {{\n\
             use std::io::{{Read, Write}};\n\
             use springlab_homework::wire::{{self, Wire}};\n\
             let mut input = std::io::stdin().lock();\n\
             let mut len = [0u8; 4];\n\
             input.read_exact(&mut len).expect(\"length\");\n\
             let mut hello = vec![0u8; u32::from_le_bytes(len) as usize];\n\
             input.read_exact(&mut hello).expect(\"hello\");\n\
             let mut token = [0u8; wire::TOKEN_LEN];\n\
             token.copy_from_slice(&hello[5..5 + wire::TOKEN_LEN]);\n\
             let mut greeting = vec![wire::to_grader::HELLO];\n\
             2u32.put(&mut greeting);\n\
             \"rope\".to_string().put(&mut greeting);\n\
             let mut out = std::io::stdout().lock();\n\
             out.write_all(&wire::reply_frame(&token, &greeting)).expect(\"write\");\n\
             out.flush().expect(\"flush\");\n\
             let _ = input.read_to_end(&mut Vec::new());\n\
             std::process::exit(0);\n\
         }}\n"
    );
    let dir = homework(&parent, "old", "rope", &old, INTEGRATORS);
    let built = build_homework(&dir, &b, &options()).expect("builds");
    let live = Live::start(
        built.homework,
        setup(Assignment::Rope, 1, 1, None, 10.0),
        LiveOptions::default(),
    );
    live.advance_to(1);
    let frame = live.next_frame(Duration::from_secs(60)).expect("a frame");
    let why = frame.failure.expect("the program is refused");
    assert_eq!(
        why,
        format!(
            "your program did not start: the program speaks version 2 of the grader's protocol \
             (its rope homework was built against another copy of springlab-homework); this \
             springlab speaks version {}: update the crate's springlab-homework and build it \
             again",
            springlab_homework::wire::VERSION
        )
    );
    assert_eq!(frame.yours, None);
}

#[test]
fn implicit_euler_on_the_thousand_particle_jelly_is_refused_with_its_reason() {
    // Lesson 5's implicit Euler step: the 10×10×10 jelly. A dense Jacobian of 1000 particles
    // is 3000 × 3000 numbers (68 MiB), over the 16 MiB a message may hold; the reference
    // keeps going.
    let s = setup(Assignment::Jelly, 5, 7, None, 1.0);
    assert_eq!(s.model.particle_count(), 1000);
    assert_eq!(s.integrator.name(), "implicit_euler");
    let live = Live::start(
        springlab::grade::live::Homework::reference(Assignment::Jelly),
        s,
        LiveOptions {
            frame_every: 1,
            ..LiveOptions::default()
        },
    );
    live.advance_to(2);
    let first = live.next_frame(Duration::from_secs(60)).expect("a frame");
    assert_eq!(
        first.failure.as_deref(),
        Some(
            "your implicit_euler() is not run on this body: a Jacobian of 1000 particles is a \
             dense 3000 × 3000 matrix (68 MiB), more than the 16 MiB a message between \
             springlab and your program may hold; implicit Euler with Physics's dense \
             Jacobians is for bodies of at most 482 particles"
        )
    );
    assert_eq!(first.yours, None);
    let second = live
        .next_frame(Duration::from_secs(60))
        .expect("the reference goes on");
    assert_eq!((first.step, second.step), (1, 2));
}

/// Every frame of `setup`'s comparison run beside `lesson`, a simulation of the same step that
/// hands its steps over as the app's lesson run does, in rounds of `round` steps (the lesson
/// ahead, then the comparison catching up); the steps the reference took from it and whether
/// the hand-over was still on at the end, and the lesson's simulation.
fn beside_the_lesson(
    homework: Homework,
    setup: Setup,
    mut lesson: Simulation,
    round: u64,
) -> (Vec<Frame>, u64, bool, Simulation) {
    let horizon = setup.horizon;
    let live = Live::start(homework, setup, LiveOptions::default());
    let handover = live
        .handover()
        .expect("a lattice with an explicit method hands over");
    let mut frames = Vec::new();
    while lesson.steps < horizon {
        for _ in 0..round.min(horizon - lesson.steps) {
            assert!(lesson.step().is_none(), "the lesson's body stays finite");
            handover.offer(&lesson, 1);
        }
        live.advance_to(lesson.steps);
        loop {
            let f = live
                .next_frame(Duration::from_secs(60))
                .expect("a frame within a minute");
            let done = f.step >= lesson.steps;
            frames.push(f);
            if done {
                break;
            }
        }
    }
    (frames, handover.taken(), handover.is_on(), lesson)
}

/// Lesson 5's step `step` with `method`: its comparison over `steps` steps and the lesson's
/// own simulation of it.
fn jelly_step(step: usize, method: Method, steps: u64) -> (Setup, Simulation) {
    let mut scene = lesson(5).steps[step - 1].build_scene().expect("scene");
    scene.set_method(method);
    let mut setup = Setup::from_scene(Assignment::Jelly, 5, &scene, 0.0).expect("setup");
    setup.horizon = steps;
    (setup, Simulation::new(scene))
}

#[test]
fn the_reference_takes_the_lessons_own_steps_with_the_same_bits_and_refuses_an_edited_lesson() {
    // The reference stepping alone and the reference taking the lesson's steps give the same
    // frames bit for bit (positions, distances, energies, parting): for each explicit method
    // on the 1000-particle jelly, and through contacts on the cube on its plane.
    let cases = [
        (5, Method::ExplicitEuler, 64),
        (5, Method::Midpoint, 64),
        (5, Method::Rk4, 64),
        (2, Method::Rk4, 1500),
    ];
    for (step, method, steps) in cases {
        let (setup, lesson) = jelly_step(step, method, steps);
        let own = Homework::reference(Assignment::Jelly);
        let alone = Live::start(own.clone(), setup.clone(), LiveOptions::default());
        alone.run_free();
        let mut want = Vec::new();
        while let Some(f) = alone.next_frame(Duration::from_secs(60)) {
            let done = f.finished;
            want.push(Frame {
                finished: false,
                ..f
            });
            if done {
                break;
            }
        }
        let (got, taken, on, lesson) = beside_the_lesson(own, setup, lesson, 16);
        let name = format!("lesson 5 step {step}, {}", method.declaration().name);
        assert!(on, "{name}: the hand-over is still on");
        // All but the first steps, computed both ways before the lesson's are trusted.
        assert!(
            taken + 16 >= steps,
            "{name}: {taken} of {steps} steps taken"
        );
        let last = want.last().expect("frames").clone();
        assert_eq!(got.last(), Some(&last), "{name}: the last frame");
        for f in &got {
            let same = want
                .iter()
                .find(|w| w.step == f.step)
                .expect("a frame there");
            assert_eq!(f, same, "{name}: frame of step {}", f.step);
        }
        if step == 2 {
            // The cube reached its plane: the collision response acted on the lesson's body.
            let contacts = lesson.dissipated().contacts;
            assert!(contacts != 0.0, "{name}: a contact happened ({contacts} J)");
        }
    }

    // An edited lesson (stiffer springs) is not the reference's body: found in the first
    // steps, the hand-over ends and the reference steps alone (no parting from itself).
    let (setup, mut lesson) = jelly_step(5, Method::Rk4, 32);
    for body in &mut lesson.scene.bodies {
        body.model.update_springs(|s| s.stiffness *= 1.5);
    }
    let (frames, taken, on, _) =
        beside_the_lesson(Homework::reference(Assignment::Jelly), setup, lesson, 16);
    assert!(!on, "the hand-over ended");
    assert_eq!(taken, 0);
    let last = frames.last().expect("frames");
    assert_eq!(last.parting, None, "{last:?}");
    assert_eq!(last.distance, 0.0);
}
