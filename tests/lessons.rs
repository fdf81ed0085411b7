//! Lesson files: every shipped lesson loads and builds its scenes; malformed files get messages
//! naming the file and line.

use std::path::Path;

use springlab::lesson::{self, GoalKind, GoalProgress, Plot};

#[test]
fn every_lesson_file_loads_and_every_step_builds_its_scene() {
    let lessons = lesson::load_dir(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("lessons")
            .as_path(),
    )
    .expect("lessons/ is readable");
    assert!(lessons.len() >= 4);
    for l in &lessons {
        let l = l.as_ref().unwrap_or_else(|e| panic!("{e}"));
        assert!(!l.steps.is_empty());
        for step in &l.steps {
            let scene = step
                .build_scene()
                .unwrap_or_else(|e| panic!("{}: {e}", l.source));
            assert!(scene.particle_count() >= 2, "{}: {}", l.source, step.title);
            assert!(
                !step.text.is_empty(),
                "{}: step {} has no text",
                l.source,
                step.title
            );
        }
    }
    // Lessons are numbered 1, 2, ... without gaps.
    let numbers: Vec<u32> = lessons
        .iter()
        .map(|l| l.as_ref().map(|l| l.number).unwrap_or(0))
        .collect();
    assert_eq!(numbers, (1..=lessons.len() as u32).collect::<Vec<_>>());
}

#[test]
fn embedded_lessons_are_the_files_in_lessons_dir() {
    for (name, text) in lesson::BUILTIN {
        let on_disk = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("lessons")
                .join(name),
        )
        .expect("embedded lesson exists on disk");
        assert_eq!(&on_disk, text);
    }
    assert!(lesson::builtin().iter().all(Result::is_ok));
}

#[test]
fn steps_carry_scene_parameters_method_plots_and_goal() {
    let lessons = lesson::builtin();
    let rope = lessons[0].as_ref().expect("lesson 1");
    assert_eq!((rope.number, rope.slug.as_str()), (1, "rope"));
    let bridge = &rope.steps[2];
    assert_eq!(
        bridge.params,
        vec![
            "damping=0.5",
            "end=[4.0, 2.0, 0.0]",
            "nodes=9",
            "pinned=[0, 8]",
            "start=[-4.0, 2.0, 0.0]"
        ]
    );
    let scene = bridge.build_scene().expect("bridge");
    assert!(scene.bodies[0].model.is_pinned(8));
    assert_eq!(bridge.plots, vec![Plot::Energy, Plot::Speed]);
    let text = format!(
        "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\ntry = [{{ text = \"run\", keys = \"D*2 space\" }}]\ngoal = {{ kind = \"settle\", time = 8.0, text = \"t\" }}\n+++\ntext\n"
    );
    let parsed = lesson::parse(&text, "goal.md", None).expect("a lesson with a goal");
    let goal = parsed.steps[0].goal.as_ref().expect("goal");
    assert_eq!(goal.kind, GoalKind::Settle);
    assert_eq!(goal.speed, 0.05, "the default settle speed");
    // The goal logic: pending while moving; a slow instant is not enough (a turning point); slow
    // for half a second from before the deadline is met; still moving after it is failed.
    let mut p = GoalProgress::default();
    assert_eq!(goal.check(&mut p, 3.0, 0.5, false), None);
    assert_eq!(goal.check(&mut p, 5.0, 0.01, false), None);
    assert_eq!(
        goal.check(&mut p, 5.1, 0.3, false),
        None,
        "the calm was a turning point"
    );
    assert_eq!(goal.check(&mut p, 7.9, 0.01, false), None);
    assert_eq!(
        goal.check(&mut p, 8.4, 0.01, false),
        Some(true),
        "calm from 7.9 s, before the 8 s deadline"
    );
    let mut late = GoalProgress::default();
    assert_eq!(goal.check(&mut late, 8.2, 0.01, false), None);
    assert_eq!(
        goal.check(&mut late, 8.7, 0.01, false),
        Some(false),
        "calm only from 8.2 s"
    );
    assert_eq!(
        goal.check(&mut GoalProgress::default(), 9.0, 0.5, false),
        Some(false)
    );
    assert_eq!(
        goal.check(&mut GoalProgress::default(), 3.0, 0.0, true),
        Some(false)
    );
}

fn error_of(text: &str) -> String {
    match lesson::parse(text, "bad.md", None) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const HEADER: &str = "+++\nnumber = 9\nslug = \"x\"\ntitle = \"X\"\nsummary = \"s\"\n+++\n";

#[test]
fn malformed_lessons_name_the_file_and_line() {
    let cases: Vec<(String, &str)> = vec![
        ("just text\n".into(), "bad.md:1: expected the lesson header"),
        (
            "+++\nnumber = 1\n".into(),
            "bad.md:1: front matter opened here is never closed",
        ),
        (
            HEADER.into(),
            "bad.md:6: a lesson needs at least one `+++ step`",
        ),
        (
            "+++\nnumber = 1\nslug = \"a\"\ntitle = \"t\"\nsummary = \"s\"\ncolour = 3\n+++\n"
                .into(),
            "bad.md:6:1: unknown field `colour`",
        ),
        (
            "+++\nnumber = \"one\"\nslug = \"a\"\ntitle = \"t\"\nsummary = \"s\"\n+++\n".into(),
            "bad.md:2:10:",
        ),
        (
            format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"nosuch\"\n+++\ntext\n"),
            // At the `scene` line, with every built-in scene named to the end.
            "bad.md:9:9: step \"a\": unknown scene `nosuch`",
        ),
        (
            format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"nosuch\"\n+++\ntext\n"),
            "(or give a path to a .toml scene file)",
        ),
        (
            format!(
                "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\nparams = {{ nodes = 1 }}\n+++\ntext\n"
            ),
            "bad.md:10:12: step \"a\": `nodes` = 1 is out of range",
        ),
        (
            // A parameter on a line of its own: that line and column.
            format!(
                "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\nparams = {{ mass = 1.0,\n    nodes = \"two\" }}\n+++\ntext\n"
            ),
            "bad.md:11:5: step \"a\": `nodes` = two: expected a whole number",
        ),
        (
            format!(
                "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\nparams = {{ colour = 1 }}\n+++\n"
            ),
            "bad.md:10:12: step \"a\": unknown parameter `colour` for scene `rope`",
        ),
        (
            format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\nmethod = \"euler\"\n+++\n"),
            "bad.md:10:10: unknown method `euler`",
        ),
        (
            format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\ndt = -1.0\n+++\n"),
            "bad.md:10:6: dt = -1: expected a time step in seconds > 0",
        ),
        (
            format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\nplots = [\"pie\"]\n+++\n"),
            "bad.md:10:10: unknown variant `pie`",
        ),
        (
            format!(
                "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\ngoal = {{ kind = \"win\", time = 1.0, text = \"t\" }}\n+++\n"
            ),
            "unknown variant `win`",
        ),
        (
            format!(
                "{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\ngoal = {{ kind = \"settle\", time = 0.0, text = \"t\" }}\n+++\n"
            ),
            "bad.md:10:8: goal: expected time > 0",
        ),
        (
            format!("{HEADER}+++ step\nscene = \"rope\"\n+++\n"),
            "missing field `title`",
        ),
        (
            format!("{HEADER}+++\ntitle = \"a\"\nscene = \"rope\"\n+++\n"),
            "bad.md:7: expected `+++ step`",
        ),
    ];
    let step = |front: &str| {
        format!("{HEADER}+++ step\ntitle = \"a\"\nscene = \"rope\"\n{front}\n+++\ntext\n")
    };
    let more: Vec<(String, &str)> = vec![
        (
            step("try = [{ text = \"x\", keys = \"space blah\" }]"),
            "bad.md:10:8: keys: unknown key `blah`",
        ),
        (
            step("try = [{ text = \"x\", keys = \"D*0\" }]"),
            "a repeat count is 1 to 100",
        ),
        (
            step("goal = { kind = \"diverge\", time = 1.0, text = \"t\" }"),
            "goal: expected a try item with `keys` that reaches it",
        ),
        (
            step(
                "try = [\"plain\"]\ngoal = { kind = \"diverge\", time = 1.0, try = 1, text = \"t\" }",
            ),
            "goal: try = 1: expected the number (from 1) of a try item with keys",
        ),
        (
            step(
                "try = [{ text = \"x\", keys = \"space\" }]\ngoal = { kind = \"diverge\", time = 1.0, body = 1, text = \"t\" }",
            ),
            "goal: `body` applies to `settle` only",
        ),
        (
            step(
                "predict = { question = \"q\", answer = 3, expect = \"survive\", time = 1.0, keys = \"space\", options = [{ text = \"a\" }, { text = \"b\" }] }",
            ),
            "predict: answer = 3: expected the number (from 1) of an option, at most 2",
        ),
        (
            step(
                "predict = { question = \"q\", answer = 1, time = 1.0, keys = \"space\", options = [{ text = \"a\" }, { text = \"b\" }] }",
            ),
            "predict: option 1: expected `expect` = survive, diverge or settle",
        ),
        (
            step(
                "predict = { question = \"q\", answer = 1, expect = \"survive\", time = 1.0, options = [{ text = \"a\" }, { text = \"b\" }] }",
            ),
            "predict: option 1: expected `keys` (on the option or the prediction)",
        ),
        (
            step("camera = { body = 2 }"),
            "bad.md:10:10: camera: body = 2: expected the number (from 1) of one of the scene's 1 bodies",
        ),
        (
            step("camera = { body = 0 }"),
            "bad.md:10:10: camera: body = 0: expected the number (from 1)",
        ),
        (
            step("speed = \"fast\""),
            "bad.md:10:9: speed: expected simulated seconds per wall second from 1/64 to 64, or \"machine\"",
        ),
        (
            step("speed = 100.0"),
            "bad.md:10:9: speed: expected simulated seconds per wall second from 1/64 to 64",
        ),
        (
            step("camera = { rope = 1 }"),
            "bad.md:10:12: unknown field `rope`, expected `body`",
        ),
    ];
    for (text, expected) in cases.into_iter().chain(more) {
        let message = error_of(&text);
        assert!(
            message.contains(expected),
            "expected `{expected}` in `{message}`"
        );
    }
}

/// A step slower than real time is refused unless it says so: `speed = "machine"` opens it in
/// real time (the machine's pace when it cannot keep up), free of the real-time budget only.
#[test]
fn a_step_below_real_time_needs_speed_machine() {
    let step = |front: &str| {
        format!(
            "{HEADER}+++ step\ntitle = \"a\"\nscene = \"jelly-bowl\"\nmethod = \"midpoint\"\ndt = 8.5e-5\n{front}+++\ntext\n"
        )
    };
    assert!(
        error_of(&step("")).contains("a lesson runs in real time"),
        "the full jelly at 8.5e-5 s is over the real-time budget"
    );
    let l = lesson::parse(&step("speed = \"machine\"\n"), "ok.md", None).expect("loads");
    assert_eq!(l.steps[0].speed, Some(1.0));
    // Its run's limits still hold: a budget-breaking dt is refused whatever the speed.
    assert!(error_of(&step("speed = \"machine\"\n").replace("8.5e-5", "1e-9")).contains("bad.md"));
}
