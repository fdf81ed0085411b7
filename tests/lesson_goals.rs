//! Every lesson keeps its promises: for every step with a goal, the keys of its "try" item
//! (played through the app with simulated wall time) meet the goal, and when those keys do more
//! than start the run, idling for the goal's time does not; for every prediction, exactly the
//! option the lesson names as the answer is confirmed by a run of its keys.
//!
//! The runs use the app's fixed-dt accumulator with frames of 0.1 s of wall time, as a student
//! would see them (release mode keeps this to seconds).

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson::{self, Goal, GoalProgress, Key, Keys, Lesson, Stroke};
use springlab::physics::{Method, diverge};
use springlab::tui::{App, Theme};

use crate::common::per_lesson;

/// Wall time of one frame (s).
const FRAME: f64 = 0.1;

fn code(key: Key) -> KeyCode {
    match key {
        Key::Char(c) => KeyCode::Char(c),
        Key::Space => KeyCode::Char(' '),
        Key::Enter => KeyCode::Enter,
        Key::Esc => KeyCode::Esc,
        Key::Tab => KeyCode::Tab,
        Key::Up => KeyCode::Up,
        Key::Down => KeyCode::Down,
        Key::Left => KeyCode::Left,
        Key::Right => KeyCode::Right,
        Key::PageUp => KeyCode::PageUp,
        Key::PageDown => KeyCode::PageDown,
    }
}

/// The app at step `step` (0-based) of lesson `index`, its prediction answered with option 1
/// (a step with a prediction waits for an answer before it runs).
fn open_at(index: usize, step: usize) -> App {
    let mut app = App::new(lesson::builtin(), Theme::PLAIN);
    app.open_lesson(index).expect("the lesson opens");
    for _ in 0..step {
        app.handle_key(KeyEvent::new(KeyCode::Char('n'), KeyModifiers::NONE));
    }
    let run = app.lesson().expect("open");
    assert_eq!(run.step_index(), step);
    if run.awaiting_prediction() {
        app.handle_key(KeyEvent::new(KeyCode::Char('1'), KeyModifiers::NONE));
    }
    app
}

/// Plays `keys` through the app; waits advance the run in frames.
fn play(app: &mut App, keys: &Keys) {
    for stroke in &keys.strokes {
        match *stroke {
            Stroke::Key(k) => app.handle_key(KeyEvent::new(code(k), KeyModifiers::NONE)),
            Stroke::Wait(s) => {
                let mut left = s;
                while left > 1e-9 {
                    app.tick(FRAME.min(left));
                    left -= FRAME;
                }
            }
        }
    }
}

/// Runs frames until `claim` is decided for this run (checked after every frame, against the
/// run's time, the speed of its body or bodies and its divergence); its verdict.
fn decide(app: &mut App, claim: &Goal) -> Option<bool> {
    let mut progress = GoalProgress::default();
    let limit = claim.time + 2.0;
    loop {
        let run = app.lesson().expect("open");
        let sim = run.sim();
        let diverged = sim.diverged.is_some();
        let time = sim.diverged.as_ref().map_or(sim.time(), |d| d.time);
        let speed = sim
            .states()
            .enumerate()
            .filter(|(i, _)| claim.body.is_none_or(|b| b == i + 1))
            .map(|(_, s)| diverge::max_speed(s))
            .fold(0.0f64, f64::max);
        if let Some(v) = claim.check(&mut progress, time, speed, diverged) {
            return Some(v);
        }
        if !run.is_running() || time > limit {
            return None;
        }
        app.tick(FRAME);
    }
}

/// Runs frames until the app's own goal verdict is decided (or the run stops or passes its
/// time); the verdict.
fn goal_verdict(app: &mut App, goal: &Goal) -> Option<bool> {
    loop {
        let run = app.lesson().expect("open");
        if let Some(v) = run.run_verdict() {
            return Some(v);
        }
        if !run.is_running() || run.sim().time() > goal.time + 2.0 {
            return None;
        }
        app.tick(FRAME);
    }
}

fn lessons() -> Vec<Lesson> {
    lesson::builtin()
        .into_iter()
        .map(|l| l.expect("built-in lessons load"))
        .collect()
}

/// The registry names of the methods a try item's text lists ("semi-implicit Euler, RK4 and
/// Verlet." is semi-implicit-euler, rk4 and verlet), sorted.
fn method_names(list: &str) -> Vec<String> {
    let mut names: Vec<String> = list
        .trim_end_matches('.')
        .split(", ")
        .flat_map(|part| part.split(" and "))
        .map(|name| name.trim().to_lowercase().replace(' ', "-"))
        .collect();
    names.sort();
    names
}

/// The registry names of the methods the study charts show now, sorted.
fn shown_names(app: &App) -> Vec<String> {
    let shown = app.lesson().expect("open").shown_methods();
    let mut names: Vec<String> = Method::ALL
        .iter()
        .filter(|m| shown[m.index()])
        .map(|m| m.declaration().name.to_string())
        .collect();
    names.sort();
    names
}

/// Wall time (s) a student watches after a try item that does not reach the goal.
const WATCH: f64 = 0.5;

per_lesson!(
    a_student_playing_every_try_list_in_order_meets_every_goal,
    student_walk,
    every
);

per_lesson!(
    every_goal_is_met_by_its_try_keys_and_action_goals_not_by_idling,
    goals_met,
    [
        rope: "rope",
        hooke: "hooke",
        euler: "euler",
        verlet: "verlet",
        jelly: "jelly",
        cloth: "cloth",
        model: "model",
    ]
);

per_lesson!(
    every_prediction_is_confirmed_by_a_run_of_its_answer_and_only_that,
    predictions_confirmed,
    [
        euler: "euler",
        verlet: "verlet",
        jelly: "jelly",
        speed_accuracy: "speed-accuracy",
        model: "model",
    ]
);

/// The per-lesson lists above name every lesson, every lesson with a goal and every lesson with
/// a prediction, in the course's order.
#[test]
fn every_lesson_with_a_goal_or_a_prediction_has_its_tests() {
    let all = lessons();
    let slugs = |has: &dyn Fn(&Lesson) -> bool| -> Vec<String> {
        all.iter()
            .filter(|l| has(l))
            .map(|l| l.slug.clone())
            .collect()
    };
    assert_eq!(
        crate::common::lesson_slugs(),
        a_student_playing_every_try_list_in_order_meets_every_goal::SLUGS
    );
    assert_eq!(
        slugs(&|l| l.steps.iter().any(|s| s.goal.is_some())),
        every_goal_is_met_by_its_try_keys_and_action_goals_not_by_idling::SLUGS
    );
    assert_eq!(
        slugs(&|l| l.steps.iter().any(|s| s.predict.is_some())),
        every_prediction_is_confirmed_by_a_run_of_its_answer_and_only_that::SLUGS
    );
    let goals: usize = all
        .iter()
        .map(|l| l.steps.iter().filter(|s| s.goal.is_some()).count())
        .sum();
    assert!(goals >= 8, "only {goals} goals");
    for n in [3, 4, 5, 7] {
        assert!(
            all.iter()
                .any(|l| l.number == n && l.steps.iter().any(|s| s.predict.is_some())),
            "lesson {n} has a prediction"
        );
    }
}

/// The built-in lesson `slug` and its index in the menu.
fn lesson(slug: &str) -> (usize, Lesson) {
    lessons()
        .into_iter()
        .enumerate()
        .find(|(_, l)| l.slug == slug)
        .unwrap_or_else(|| panic!("no built-in lesson {slug}"))
}

/// A student moving through lesson `slug` with `n`: at each step the prediction answered (with
/// option 1: the try keys must work whatever was predicted), then exactly the keys of each try
/// item in the order the lesson lists them, from the state the previous items and steps left,
/// watching half a second after each; the goal's item must meet the goal, and the screen say so.
fn student_walk(slug: &str) {
    let (li, l) = lesson(slug);
    let mut goals = 0;
    let mut played = 0;
    let mut app = App::new(lesson::builtin(), Theme::PLAIN);
    app.open_lesson(li).expect("the lesson opens");
    for (si, step) in l.steps.iter().enumerate() {
        if si > 0 {
            app.handle_key(KeyEvent::new(KeyCode::Char('n'), KeyModifiers::NONE));
        }
        assert_eq!(app.lesson().expect("open").step_index(), si);
        if app.lesson().expect("open").awaiting_prediction() {
            app.handle_key(KeyEvent::new(KeyCode::Char('1'), KeyModifiers::NONE));
        }
        let goal_keys = step.goal_keys().map(|k| k as *const Keys);
        for (ti, item) in step.try_list.iter().enumerate() {
            let Some(keys) = &item.keys else { continue };
            let at = format!(
                "lesson {} step {} \"{}\" try {} ({keys})",
                l.number,
                si + 1,
                step.title,
                ti + 1
            );
            play(&mut app, keys);
            played += 1;
            if let Some(named) = item.text.strip_prefix("Show only ") {
                assert_eq!(
                    shown_names(&app),
                    method_names(named),
                    "{at}: the methods shown are the ones the item names"
                );
            }
            if goal_keys == Some(keys as *const Keys) {
                let goal = step.goal.as_ref().expect("goal keys belong to a goal");
                let verdict = goal_verdict(&mut app, goal);
                let run = app.lesson().expect("open");
                assert_eq!(
                    verdict,
                    Some(true),
                    "{at}: goal not met (t = {:.3} s, dt = {} s, diverged {:?})",
                    run.sim().time(),
                    run.sim().dt(),
                    run.sim().diverged
                );
                assert_eq!(run.goal_state(), Some(true), "{at}: the screen says met");
                goals += 1;
            } else {
                play(
                    &mut app,
                    &Keys::parse(&format!("wait:{WATCH}")).expect("a wait"),
                );
            }
        }
    }
    assert!(played > 0, "lesson {slug}: no try item has keys");
    let all = l.steps.iter().filter(|s| s.goal.is_some()).count();
    assert_eq!(goals, all, "lesson {slug}: every goal was played");
}

/// Every goal of lesson `slug` is met by its try keys from the step's start; a goal that asks
/// for an action is not met by starting the run and idling.
fn goals_met(slug: &str) {
    let (li, l) = lesson(slug);
    let mut checked = 0;
    for (si, step) in l.steps.iter().enumerate() {
        let Some(goal) = &step.goal else { continue };
        let keys = step
            .goal_keys()
            .expect("a goal has its keys (checked at load)");
        let at = format!(
            "lesson {} step {} \"{}\" ({keys})",
            l.number,
            si + 1,
            step.title
        );
        let mut app = open_at(li, si);
        play(&mut app, keys);
        assert!(
            app.lesson().expect("open").is_running()
                || app.lesson().expect("open").run_verdict().is_some(),
            "{at}: the keys leave the run paused"
        );
        let verdict = goal_verdict(&mut app, goal);
        let run = app.lesson().expect("open");
        assert_eq!(
            verdict,
            Some(true),
            "{at}: goal not met (t = {:.3} s, diverged {:?})",
            run.sim().time(),
            run.sim().diverged
        );
        assert_eq!(
            run.goal_state(),
            Some(true),
            "{at}: the screen shows it met"
        );
        if keys.is_action() {
            let mut idle = open_at(li, si);
            play(&mut idle, &Keys::parse("space").expect("space"));
            let verdict = goal_verdict(&mut idle, goal);
            assert_ne!(
                verdict,
                Some(true),
                "{at}: idling for {} s meets a goal that asks for an action",
                goal.time
            );
        }
        checked += 1;
    }
    assert!(checked > 0, "lesson {slug} has no goal");
}

/// For every prediction of lesson `slug`, a run of each option's keys confirms its claim
/// exactly when the option is the answer.
fn predictions_confirmed(slug: &str) {
    let (li, l) = lesson(slug);
    let mut predictions = 0;
    for (si, step) in l.steps.iter().enumerate() {
        let Some(p) = &step.predict else { continue };
        predictions += 1;
        for (oi, option) in p.options.iter().enumerate() {
            let at = format!(
                "lesson {} step {} option {} \"{}\" ({})",
                l.number,
                si + 1,
                oi + 1,
                option.text,
                option.keys
            );
            let mut app = open_at(li, si);
            play(&mut app, &option.keys);
            let holds = decide(&mut app, &option.claim);
            let t = app.lesson().expect("open").sim().time();
            assert!(
                holds.is_some(),
                "{at}: the run did not decide (t = {t:.3} s)"
            );
            assert_eq!(
                holds == Some(true),
                oi == p.answer,
                "{at}: the claim {} at t = {t:.3} s, but the answer is option {}",
                if holds == Some(true) {
                    "holds"
                } else {
                    "fails"
                },
                p.answer + 1
            );
            if oi == 0 {
                answer_and_explanation_show_at_80x24(&mut app, p, &at);
            }
        }
    }
    assert!(predictions > 0, "lesson {slug} has no prediction");
}

/// Once the run of the student's answer has decided, the answer and the start of the
/// explanation are on the 80 × 24 screen.
fn answer_and_explanation_show_at_80x24(app: &mut App, p: &lesson::Prediction, at: &str) {
    for _ in 0..200 {
        if app.lesson().expect("open").revealed().is_some() {
            break;
        }
        app.tick(FRAME);
    }
    assert!(
        app.lesson().expect("open").revealed().is_some(),
        "{at}: not revealed"
    );
    let mut terminal =
        ratatui::Terminal::new(ratatui::backend::TestBackend::new(80, 24)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(&*app, frame.area()))
        .expect("draw");
    let screen = terminal.backend().to_string();
    let left: String = screen
        .lines()
        .map(|l| l.trim_matches('"').chars().take(40).collect::<String>())
        .collect::<Vec<_>>()
        .join(" ");
    let squeeze = |s: &str| {
        s.replace(['`', '*', '"'], "")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    let text = squeeze(&left);
    let answer = format!("Answer: {})", p.answer + 1);
    assert!(
        text.contains(&answer),
        "{at}: no \"{answer}\" at 80x24\n{screen}"
    );
    let opening: Vec<&str> = p.explain.split_whitespace().take(4).collect();
    let opening = squeeze(&opening.join(" "));
    assert!(
        text.contains(&opening),
        "{at}: the explanation (\"{opening} …\") is not at 80x24\n{screen}"
    );
}
