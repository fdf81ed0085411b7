//! The lesson app driven without a terminal: keys, mouse and explicit wall times go in, the
//! app's state comes out (and, where it matters, what it draws into a `TestBackend`).

use std::path::PathBuf;

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{
    KeyCode, KeyEvent, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
};
use ratatui::layout::Rect;
use ratatui::style::Color;
use springlab::lesson;
use springlab::physics::Method;
use springlab::simulation::Simulation;
use springlab::tui::{App, LessonRun, Screen, Theme, pane};

mod scene_pane;

fn app() -> App {
    App::new(lesson::builtin(), Theme::PLAIN)
}

/// The app with lesson `slug` open at its first step.
fn open(slug: &str) -> App {
    let mut app = app();
    let i = app.find_lesson(slug).expect("lesson exists");
    app.open_lesson(i).expect("lesson opens");
    app
}

fn key(app: &mut App, code: KeyCode) {
    app.handle_key(KeyEvent::new(code, KeyModifiers::NONE));
}

fn keys(app: &mut App, text: &str) {
    for c in text.chars() {
        key(app, KeyCode::Char(c));
    }
}

fn run(app: &App) -> &LessonRun {
    app.lesson().expect("a lesson is open")
}

fn draw(app: &App, width: u16, height: u16) -> Terminal<TestBackend> {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    terminal
}

fn screen_text(app: &App, width: u16, height: u16) -> String {
    draw(app, width, height).backend().to_string()
}

/// A directory of its own under the system's temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("springlab-tui-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn space_toggles_run_and_pause() {
    let mut app = open("hooke");
    assert!(!run(&app).is_running(), "a step opens paused");
    key(&mut app, KeyCode::Char(' '));
    assert!(run(&app).is_running());
    assert!(app.is_animating());
    key(&mut app, KeyCode::Char(' '));
    assert!(!run(&app).is_running());
    assert!(!app.is_animating(), "paused: the loop blocks on input");
}

#[test]
fn paused_ticks_do_not_move_the_simulation() {
    let mut app = open("hooke");
    app.tick(1.0);
    assert_eq!(run(&app).sim().steps, 0);
    assert_eq!(run(&app).sim().time(), 0.0);
}

#[test]
fn single_step_advances_time_by_dt_and_pauses() {
    let mut app = open("hooke");
    let dt = run(&app).sim().dt();
    assert_eq!(dt, 0.01);
    key(&mut app, KeyCode::Char('s'));
    assert_eq!(run(&app).sim().steps, 1);
    assert_eq!(run(&app).sim().time(), dt);
    key(&mut app, KeyCode::Char(' '));
    key(&mut app, KeyCode::Char('s'));
    assert!(!run(&app).is_running(), "s pauses a running simulation");
    assert_eq!(run(&app).sim().steps, 2);
    assert_eq!(run(&app).sim().time(), 2.0 * dt);
}

#[test]
fn m_opens_the_method_chooser_which_picks_by_key_number_or_enter() {
    let mut app = open("hooke");
    let method = |app: &App| run(app).sim().scene.bodies[0].method;
    assert_eq!(method(&app), Method::Rk4, "the step asks for rk4");
    key(&mut app, KeyCode::Char('m'));
    assert!(run(&app).chooser().is_some(), "m opens the chooser");
    assert_eq!(method(&app), Method::Rk4, "opening it changes nothing");
    let text = screen_text(&app, 100, 32);
    for m in Method::ALL {
        assert!(text.contains(m.name()), "the chooser lists {m}:\n{text}");
    }
    // Esc closes it (and stays in the lesson); each method's key picks it and closes it.
    key(&mut app, KeyCode::Esc);
    assert!(run(&app).chooser().is_none());
    for m in Method::ALL {
        key(&mut app, KeyCode::Char('m'));
        key(
            &mut app,
            KeyCode::Char(springlab::tui::lesson_run::method_key(m)),
        );
        assert_eq!(method(&app), m);
        assert!(run(&app).chooser().is_none());
    }
    // Numbers pick by position; arrows and Enter too; Esc closes without a change.
    keys(&mut app, "m2");
    assert_eq!(method(&app), Method::ALL[1]);
    key(&mut app, KeyCode::Char('m'));
    key(&mut app, KeyCode::Down);
    key(&mut app, KeyCode::Enter);
    assert_eq!(method(&app), Method::ALL[2]);
    key(&mut app, KeyCode::Char('m'));
    key(&mut app, KeyCode::Esc);
    assert_eq!(method(&app), Method::ALL[2]);
    assert!(run(&app).chooser().is_none());
    assert!(
        app.lesson().is_some(),
        "Esc in the chooser does not leave the lesson"
    );
}

#[test]
fn the_chooser_gives_a_method_to_one_body_with_tab() {
    let mut app = open("verlet");
    let methods = |app: &App| -> Vec<Method> {
        run(app)
            .sim()
            .scene
            .bodies
            .iter()
            .map(|b| b.method)
            .collect()
    };
    assert_eq!(methods(&app), [Method::SemiImplicitEuler, Method::Verlet]);
    // Tab: the first body only.
    key(&mut app, KeyCode::Char('m'));
    key(&mut app, KeyCode::Tab);
    key(&mut app, KeyCode::Char('r'));
    assert_eq!(methods(&app), [Method::Rk4, Method::Verlet]);
    // Without Tab: every body.
    keys(&mut app, "mx");
    assert_eq!(methods(&app), [Method::Xpbd, Method::Xpbd]);
}

#[test]
fn drag_gamma_and_passes_keys_change_the_model_and_rebase_the_energy() {
    let mut app = open("verlet");
    keys(&mut app, " ");
    for _ in 0..10 {
        app.tick(0.1);
    }
    keys(&mut app, " ");
    let body = |app: &App, b: usize| run(app).sim().scene.bodies[b].clone();
    assert_eq!(body(&app, 0).model.drag, 0.0);
    // A: the first press sets c/m = 0.25 1/s, then ×2; a: ÷2 down to 0.
    keys(&mut app, "A");
    assert_eq!(body(&app, 0).model.drag, 0.25);
    assert_eq!(body(&app, 1).model.drag, 0.25);
    assert_eq!(
        run(&app).sim().energy_residual(),
        0.0,
        "rebased after the edit"
    );
    keys(&mut app, "AA");
    assert_eq!(body(&app, 0).model.drag, 1.0);
    keys(&mut app, "aaa");
    assert_eq!(body(&app, 0).model.drag, 0.0);
    // G: γ × 10 from the scene's 5e-5, capped at 0.5; g: ÷ 10, to 0 below 5e-5.
    keys(&mut app, "G");
    assert!((body(&app, 1).params.verlet_damping - 5e-4).abs() < 1e-15);
    keys(&mut app, "GGGG");
    assert_eq!(body(&app, 1).params.verlet_damping, 0.5);
    assert!(
        run(&app).message().is_some_and(|m| m.contains("1/s")),
        "the rate γ/dt is shown"
    );
    keys(&mut app, "ggggg");
    assert_eq!(body(&app, 1).params.verlet_damping, 0.0);
    // J: passes × 2 (0 → 1); j: ÷ 2.
    assert_eq!(body(&app, 1).params.iterations, 1);
    keys(&mut app, "JJJ");
    assert_eq!(body(&app, 1).params.iterations, 8);
    keys(&mut app, "jjjj");
    assert_eq!(body(&app, 1).params.iterations, 0);
    keys(&mut app, "J");
    assert_eq!(body(&app, 1).params.iterations, 1);
}

#[test]
fn plus_and_minus_double_and_halve_dt() {
    let mut app = open("hooke");
    key(&mut app, KeyCode::Char('+'));
    assert_eq!(run(&app).sim().dt(), 0.02);
    key(&mut app, KeyCode::Char('-'));
    key(&mut app, KeyCode::Char('-'));
    assert_eq!(run(&app).sim().dt(), 0.005);
    // Time already simulated stays; new steps use the new dt.
    key(&mut app, KeyCode::Char('s'));
    assert_eq!(run(&app).sim().time(), 0.005);
}

#[test]
fn reset_restores_the_initial_state_bit_for_bit() {
    let mut app = open("rope");
    let step = run(&app).step().clone();
    let fresh = step.build_scene().expect("scene builds");
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..30 {
        app.tick(1.0 / 30.0);
    }
    assert!(run(&app).sim().steps > 50);
    key(&mut app, KeyCode::Char('r'));
    let sim = run(&app).sim();
    assert!(!run(&app).is_running(), "r pauses");
    assert_eq!((sim.steps, sim.time()), (0, 0.0));
    for (body, fresh) in sim.scene.bodies.iter().zip(&fresh.bodies) {
        assert_eq!(
            body.state, fresh.state,
            "positions, velocities, x_prev bit for bit"
        );
    }
    // And the run from there repeats the first one exactly.
    let mut reference = Simulation::new(fresh);
    reference.run(40, |_| {});
    for _ in 0..40 {
        key(&mut app, KeyCode::Char('s'));
    }
    let sim = run(&app).sim();
    assert_eq!(sim.time(), reference.time());
    assert!(
        sim.positions()
            .zip(reference.positions())
            .all(|(a, b)| a == b)
    );
}

#[test]
fn reset_keeps_the_chosen_method_and_dt() {
    let mut app = open("euler");
    keys(&mut app, "ms+ss");
    key(&mut app, KeyCode::Char('r'));
    let sim = run(&app).sim();
    assert_eq!(sim.scene.bodies[0].method, Method::SemiImplicitEuler);
    assert_eq!(sim.dt(), 0.04);
    assert_eq!(sim.time(), 0.0);
}

#[test]
fn n_and_p_move_between_steps() {
    let mut app = open("rope");
    let count = run(&app).lesson().steps.len();
    key(&mut app, KeyCode::Char('p'));
    assert_eq!(run(&app).step_index(), 0, "no step before the first");
    assert!(run(&app).message().is_some());
    key(&mut app, KeyCode::Char('n'));
    assert_eq!(run(&app).step_index(), 1);
    // Step 2 of lesson 1 is the rope with 3 nodes.
    assert_eq!(run(&app).sim().scene.particle_count(), 3);
    for _ in 0..count - 2 {
        key(&mut app, KeyCode::Char('n'));
    }
    assert_eq!(run(&app).step_index(), count - 1);
    // A new step starts paused at t = 0 with the step's own dt (step 4 asks for 0.004).
    assert_eq!(run(&app).sim().dt(), 0.004);
    assert_eq!(run(&app).sim().time(), 0.0);
    key(&mut app, KeyCode::Char('p'));
    assert_eq!(run(&app).step_index(), count - 2);
    key(&mut app, KeyCode::Char('n'));
    // `n` on the last step opens the next lesson.
    key(&mut app, KeyCode::Char('n'));
    assert_eq!(run(&app).lesson().slug, "hooke");
    assert_eq!(run(&app).step_index(), 0);
    // And on the last step of the last lesson it says so.
    let last = app.lessons().len() - 1;
    app.open_lesson(last).expect("opens");
    let steps = run(&app).lesson().steps.len();
    for _ in 0..steps + 1 {
        key(&mut app, KeyCode::Char('n'));
    }
    assert_eq!(app.selected(), last);
    assert!(
        run(&app)
            .message()
            .is_some_and(|m| m.contains("last lesson"))
    );
}

#[test]
fn accumulator_turns_wall_time_into_whole_steps() {
    let mut app = open("hooke");
    key(&mut app, KeyCode::Char(' '));
    // 0.1 s of wall time at dt = 0.01 s: 10 steps.
    app.tick(0.1);
    assert_eq!(run(&app).sim().steps, 10);
    assert_eq!(run(&app).last_frame_steps(), 10);
    // Less than a step waits in the accumulator.
    app.tick(0.004);
    assert_eq!(run(&app).sim().steps, 10);
    assert!((run(&app).accumulator() - 0.004).abs() < 1e-12);
    app.tick(0.007);
    assert_eq!(run(&app).sim().steps, 11);
    assert!((run(&app).accumulator() - 0.001).abs() < 1e-9);
    // Capped: at most the cap per frame, and the backlog is dropped, not carried.
    app.lesson_mut().expect("open").set_max_steps_per_frame(4);
    app.tick(0.1);
    assert_eq!(run(&app).sim().steps, 15);
    assert_eq!(run(&app).accumulator(), 0.0);
    app.tick(0.02);
    assert_eq!(run(&app).sim().steps, 17);
}

#[test]
fn brackets_change_the_cap_and_speed_scales_wall_time() {
    let mut app = open("hooke");
    let cap = run(&app).max_steps_per_frame();
    key(&mut app, KeyCode::Char(']'));
    assert_eq!(run(&app).max_steps_per_frame(), 2 * cap);
    key(&mut app, KeyCode::Char('['));
    key(&mut app, KeyCode::Char('['));
    assert_eq!(run(&app).max_steps_per_frame(), cap / 2);
    // Half speed: 0.1 s of wall time is 0.05 s of simulated time.
    key(&mut app, KeyCode::Char('<'));
    key(&mut app, KeyCode::Char(' '));
    app.tick(0.1);
    assert_eq!(run(&app).sim().steps, 5);
}

#[test]
fn real_time_factor_and_steps_per_second_come_from_the_wall_times_given() {
    let mut app = open("hooke");
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..40 {
        app.tick(1.0 / 60.0);
    }
    // dt = 0.01 s against frames of 1/60 s: a frame takes one or two steps and the rest waits
    // in the accumulator. Nothing is dropped, so the factor is exactly 1 (to rounding), not the
    // 0.98–1.02 that whole steps alone would give.
    let rtf = run(&app).real_time_factor().expect("measured after 0.5 s");
    assert!((rtf - 1.0).abs() < 1e-9, "{rtf}");
    let sps = run(&app).steps_per_second().expect("measured");
    assert!((sps - 100.0).abs() < 5.0, "{sps}");
    // Capped at one step a frame, 0.01 s of every 0.025 s frame is kept and the rest dropped:
    // ×0.4 (80 frames: at least one half-second window of capped frames only).
    app.lesson_mut().expect("open").set_max_steps_per_frame(1);
    for _ in 0..80 {
        app.tick(0.025);
    }
    let rtf = run(&app).real_time_factor().expect("measured");
    assert!((rtf - 0.4).abs() < 1e-9, "{rtf}");
    // Half speed, nothing dropped: exactly 0.5 simulated seconds per wall second.
    app.lesson_mut()
        .expect("open")
        .set_max_steps_per_frame(4096);
    key(&mut app, KeyCode::Char('<'));
    for _ in 0..80 {
        app.tick(1.0 / 60.0);
    }
    let rtf = run(&app).real_time_factor().expect("measured");
    assert!((rtf - 0.5).abs() < 1e-9, "{rtf}");
}

#[test]
fn stiffness_and_damping_keys_scale_every_spring() {
    let mut app = open("hooke");
    assert_eq!(run(&app).uniform_stiffness(), Some(100.0));
    assert_eq!(
        run(&app).omega_max(),
        Some(10.0),
        "ω = √(k/m) for one spring"
    );
    key(&mut app, KeyCode::Char('K'));
    assert_eq!(run(&app).uniform_stiffness(), Some(150.0));
    key(&mut app, KeyCode::Char('k'));
    key(&mut app, KeyCode::Char('k'));
    assert!((run(&app).uniform_stiffness().expect("uniform") - 100.0 / 1.5).abs() < 1e-9);
    // Damping starts from zero at 1 % of critical, 2√(k m).
    let k = run(&app).uniform_stiffness().expect("uniform");
    assert_eq!(run(&app).uniform_damping(), Some(0.0));
    key(&mut app, KeyCode::Char('D'));
    let first = 0.01 * 2.0 * (k * 1.0f64).sqrt();
    assert!((run(&app).uniform_damping().expect("uniform") - first).abs() < 1e-12);
    key(&mut app, KeyCode::Char('D'));
    assert!((run(&app).uniform_damping().expect("uniform") - 1.5 * first).abs() < 1e-12);
    key(&mut app, KeyCode::Char('d'));
    key(&mut app, KeyCode::Char('d'));
    assert_eq!(run(&app).uniform_damping(), Some(0.0), "back to none");
}

#[test]
fn a_chain_has_omega_twice_that_of_one_spring() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char('n'));
    // 16 nodes, k = 400 N/m, m = 1 kg: interior rows give 4k/m.
    let omega = run(&app).omega_max().expect("springs");
    assert!((omega - 2.0 * 400f64.sqrt()).abs() < 1e-9, "{omega}");
}

#[test]
fn oscillator_exact_solution_matches_rk4() {
    let mut app = open("hooke");
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..100 {
        app.tick(0.01);
    }
    let run = run(&app);
    let o = run.oscillator().expect("the oscillator is detected");
    assert_eq!((o.rest_length, o.stiffness, o.mass), (1.0, 100.0, 1.0));
    assert!((o.u0 - 0.1).abs() < 1e-15, "A = x_1(0) - L0");
    let t = run.sim().time();
    assert!((o.exact(t) - (1.0 + 0.1 * (10.0 * t).cos())).abs() < 1e-12);
    assert!((o.position(run.sim()) - o.exact(t)).abs() < 1e-6);
}

#[test]
fn damped_exact_solution_solves_the_equation() {
    let app = open("hooke");
    let base = *run(&app).oscillator().expect("oscillator");
    // Under-, critically and over-damped: m u'' + k_d u' + k u = 0 by finite differences,
    // u(0) = u0 and u'(0) = v0.
    for damping in [2.0, 20.0, 50.0] {
        let o = springlab::tui::plots::Oscillator {
            damping,
            v0: 0.3,
            ..base
        };
        let u = |t: f64| o.exact(t) - o.rest_length;
        assert!((u(0.0) - o.u0).abs() < 1e-12);
        let h = 1e-5;
        assert!(((u(h) - u(-h)) / (2.0 * h) - 0.3).abs() < 1e-6, "{damping}");
        for t in [0.05, 0.2, 0.7] {
            let d1 = (u(t + h) - u(t - h)) / (2.0 * h);
            let d2 = (u(t + h) - 2.0 * u(t) + u(t - h)) / (h * h);
            let residual = o.mass * d2 + damping * d1 + o.stiffness * u(t);
            assert!(residual.abs() < 1e-4, "k_d {damping}, t {t}: {residual}");
        }
    }
}

#[test]
fn divergence_stops_the_run_and_meets_the_diverge_goal() {
    let mut app = open("euler");
    // Explicit Euler at dt·ω = 0.2 grows slowly; dt·ω = 1.6 blows up fast.
    keys(&mut app, "+++ ");
    for _ in 0..200 {
        app.tick(0.1);
        if !run(&app).is_running() {
            break;
        }
    }
    let run = run(&app);
    let d = run.sim().diverged.as_ref().expect("diverged");
    assert!(!run.is_running());
    assert_eq!(run.goal_state(), Some(true), "goal: make it blow up");
    assert!(d.time <= 60.0);
    // The diverging sample is recorded: the history ends at the divergence with its speed
    // (the 7th quantity of a sample), the largest of the run.
    let last = run.history().bins.last().expect("samples");
    assert_eq!(last.t1, d.time);
    assert_eq!(last.hi[6], d.max_speed);
    assert!(run.history().bins.iter().all(|b| b.hi[6] <= d.max_speed));
    let text = screen_text(&app, 100, 32);
    assert!(
        text.contains(&format!("unstable at step {}", d.step)),
        "{text}"
    );
    // Space does not restart a diverged run; r does.
    key(&mut app, KeyCode::Char(' '));
    assert!(!self::run(&app).is_running());
    key(&mut app, KeyCode::Char('r'));
    assert!(self::run(&app).sim().diverged.is_none());
    assert_eq!(self::run(&app).run_verdict(), None, "r starts a new run");
    assert_eq!(
        self::run(&app).goal_state(),
        Some(true),
        "a met goal stays met"
    );
}

#[test]
fn q_goes_back_from_lesson_to_menu_to_quit() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('q'));
    assert!(matches!(app.screen(), Screen::Menu));
    assert!(!app.should_quit());
    key(&mut app, KeyCode::Enter);
    assert!(app.lesson().is_some(), "Enter opens the selected lesson");
    key(&mut app, KeyCode::Esc);
    assert!(matches!(app.screen(), Screen::Menu));
    key(&mut app, KeyCode::Esc);
    assert!(app.should_quit());
}

#[test]
fn ctrl_c_quits_from_anywhere() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('?'));
    app.handle_key(KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL));
    assert!(app.should_quit());
}

#[test]
fn help_overlay_opens_with_question_mark_and_closes_with_any_key() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('?'));
    assert!(app.help_shown());
    assert!(screen_text(&app, 100, 32).contains("springlab keys"));
    // Keys go to the overlay, not the lesson.
    key(&mut app, KeyCode::Char(' '));
    assert!(!app.help_shown());
    assert!(!run(&app).is_running());
    key(&mut app, KeyCode::Char('q'));
    assert!(matches!(app.screen(), Screen::Menu));
}

/// The text inside the help overlay's border, row by row, and its closing line.
fn help_rows(app: &App, width: u16, height: u16) -> (Vec<String>, String) {
    let terminal = draw(app, width, height);
    let buffer = terminal.backend().buffer();
    let cell = |x: u16, y: u16| buffer[(x, y)].symbol().to_owned();
    let row = |y: u16| (0..width).map(|x| cell(x, y)).collect::<String>();
    let top = (0..height)
        .find(|&y| row(y).contains("┌ springlab keys "))
        .expect("the overlay is drawn");
    let left = (0..width).find(|&x| cell(x, top) == "┌").expect("a corner");
    let right = (left..width)
        .find(|&x| cell(x, top) == "┐")
        .expect("a corner");
    let inner: Vec<String> = (top + 1..height)
        .take_while(|&y| cell(left, y) == "│")
        .map(|y| (left + 1..right).map(|x| cell(x, y)).collect())
        .collect();
    let (closing, body) = inner.split_last().expect("a closing line");
    (body.to_vec(), closing.trim().to_owned())
}

/// On an 80 × 24 terminal the help overlay is taller than the screen: it scrolls with the
/// arrows and pages, and every key can be read with its whole description (wrapped beside
/// the key column, never cut at the border); any other key still closes it.
#[test]
fn help_overlay_scrolls_on_80x24_and_shows_every_key_whole() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('?'));
    let mut rows: Vec<Option<String>> = Vec::new();
    let mut last_page = (0, 0);
    for page in 0.. {
        assert!(page < 10, "PgDn never reached the last row");
        let (body, closing) = help_rows(&app, 80, 24);
        // "rows a–b of n · ↑/↓ PgUp/PgDn scroll · any other key closes"
        let numbers: Vec<usize> = closing
            .split(|c: char| !c.is_ascii_digit())
            .filter_map(|n| n.parse().ok())
            .take(3)
            .collect();
        assert!(closing.ends_with("any other key closes"), "{closing}");
        let [a, b, n] = numbers[..] else {
            panic!("no row numbers in {closing:?}")
        };
        assert_eq!(body.len(), b + 1 - a, "{closing}");
        rows.resize(n, None);
        for (i, row) in body.into_iter().enumerate() {
            rows[a - 1 + i] = Some(row);
        }
        if b == n {
            last_page = (a, b);
            break;
        }
        key(&mut app, KeyCode::PageDown);
        assert!(
            app.help_shown(),
            "PgDn scrolls the overlay, it does not close it"
        );
    }
    // Each entry: its key row and the rows indented past the key column below it.
    let mut entries: Vec<String> = Vec::new();
    for row in rows.into_iter().map(|r| r.expect("every row was shown")) {
        let row = row.trim_end();
        match entries.last_mut() {
            Some(last) if row.starts_with(&" ".repeat(12)) => {
                last.push(' ');
                last.push_str(row.trim_start());
            }
            _ => entries.push(row.to_owned()),
        }
    }
    for (k, what) in springlab::tui::help::LESSON_KEYS {
        if !k.is_empty() {
            let entry = format!("  {k:<10}{what}");
            assert!(entries.contains(&entry), "{entry:?} not in {entries:#?}");
        }
    }
    // Back up and home; then a key that does not scroll closes the overlay, and goes no
    // further (the lesson does not start).
    key(&mut app, KeyCode::Up);
    let (_, closing) = help_rows(&app, 80, 24);
    let (a, b) = last_page;
    assert!(
        closing.starts_with(&format!("rows {}–{} of", a - 1, b - 1)),
        "{closing}"
    );
    key(&mut app, KeyCode::Home);
    let (body, closing) = help_rows(&app, 80, 24);
    assert!(closing.starts_with("rows 1–"), "{closing}");
    assert!(body[0].starts_with("  space     run / pause"), "{body:?}");
    key(&mut app, KeyCode::Char(' '));
    assert!(!app.help_shown());
    assert!(!run(&app).is_running());
    // Where everything fits, every key closes it, the arrows too.
    key(&mut app, KeyCode::Char('?'));
    let (_, closing) = help_rows(&app, 100, 40);
    assert_eq!(closing, "any key closes this help");
    key(&mut app, KeyCode::Down);
    assert!(!app.help_shown());
}

#[test]
fn menu_keys_choose_and_open_lessons() {
    let mut app = app();
    key(&mut app, KeyCode::Down);
    key(&mut app, KeyCode::Down);
    assert_eq!(app.selected(), 2);
    key(&mut app, KeyCode::Up);
    assert_eq!(app.selected(), 1);
    key(&mut app, KeyCode::Char('4'));
    assert_eq!(run(&app).lesson().number, 4);
    key(&mut app, KeyCode::Char('q'));
    key(&mut app, KeyCode::Char('9'));
    assert!(matches!(app.screen(), Screen::Menu));
    assert_eq!(app.menu_message(), Some("there is no lesson 9"));
}

#[test]
fn lessons_are_found_by_number_or_slug() {
    let app = app();
    assert_eq!(app.find_lesson("2"), app.find_lesson("hooke"));
    assert_eq!(app.find_lesson("HOOKE"), Some(1));
    assert_eq!(app.find_lesson("nope"), None);
    assert_eq!(app.find_lesson("0"), None);
}

#[test]
fn a_malformed_lesson_shows_its_error_in_the_menu() {
    let dir = temp_dir("malformed");
    std::fs::write(
        dir.join("01-rope.md"),
        lesson::BUILTIN[0].1, // a good lesson beside the bad one
    )
    .expect("write");
    std::fs::write(
        dir.join("02-broken.md"),
        "+++\nnumber = 2\nslug = \"broken\"\ntitle = \"Broken\"\nsummary = \"x\"\n+++\n\n\
         +++ step\ntitle = \"A\"\nscene = \"no-such-scene\"\n+++\nText.\n",
    )
    .expect("write");
    let lessons = lesson::load_dir(&dir).expect("readable");
    let mut app = App::new(lessons, Theme::PLAIN);
    let text = screen_text(&app, 100, 32);
    assert!(text.contains("Building a rope"), "{text}");
    assert!(text.contains("this lesson has an error"), "{text}");
    assert!(
        text.contains("02-broken.md:10:9"),
        "file, line and column: {text}"
    );
    assert!(text.contains("unknown scene"), "{text}");
    // Choosing it does not crash: the menu says why it cannot open.
    key(&mut app, KeyCode::Down);
    key(&mut app, KeyCode::Enter);
    assert!(matches!(app.screen(), Screen::Menu));
    assert!(
        app.menu_message()
            .is_some_and(|m| m.contains("cannot be opened"))
    );
    assert!(screen_text(&app, 100, 32).contains("cannot be opened"));
    // The good lesson still opens.
    key(&mut app, KeyCode::Up);
    key(&mut app, KeyCode::Enter);
    assert!(app.lesson().is_some());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Progress goes to the file given, survives a restart, and a met goal is met again when the
/// lesson is opened anew; `Progress::in_memory` writes nothing.
#[test]
fn progress_is_saved_and_restored() {
    use springlab::tui::Progress;
    let dir = temp_dir("progress");
    let path = dir.join("progress.json");
    let hooke = |progress: Progress| {
        let mut app = App::new(lesson::builtin(), Theme::PLAIN).with_progress(progress);
        let i = app.find_lesson("hooke").expect("lesson 2");
        app.open_lesson(i).expect("opens");
        app
    };
    let mut app = hooke(Progress::load(&path));
    // Step 3: bring the oscillator to rest by raising the damping (its try keys).
    keys(&mut app, "nn");
    for _ in 0..5 {
        key(&mut app, KeyCode::Char('D'));
    }
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..40 {
        app.tick(0.1);
    }
    assert_eq!(run(&app).goal_state(), Some(true));
    assert!(path.exists(), "written when the goal was met");
    let text = std::fs::read_to_string(&path).expect("readable");
    assert!(text.contains("\"hooke\""), "{text}");
    // A new app with the same file: lesson 2 shows its three steps done and the goal met.
    let app = hooke(Progress::load(&path));
    assert_eq!(app.lesson_done(1), Some((3, 3)));
    let mut app = app;
    keys(&mut app, "nn");
    assert_eq!(
        run(&app).goal_state(),
        Some(true),
        "re-entering keeps the met goal"
    );
    assert_eq!(
        run(&app).run_verdict(),
        None,
        "while this run has not decided"
    );
    // In memory: nothing is written.
    let other = dir.join("other.json");
    let mut app = hooke(Progress::in_memory());
    keys(&mut app, "nn");
    assert!(!other.exists() && app.progress().path().is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A step with a prediction waits for the answer before it runs, records it, and shows the
/// answer once a run is decided.
#[test]
fn a_prediction_is_asked_before_the_run_and_answered_after_it() {
    let mut app = open("euler");
    key(&mut app, KeyCode::Char('n'));
    assert!(run(&app).awaiting_prediction());
    key(&mut app, KeyCode::Char(' '));
    assert!(!run(&app).is_running(), "no run before the answer");
    assert!(run(&app).message().is_some_and(|m| m.contains("predict")));
    // Option 1 (explicit Euler), then the experiment of option 1.
    key(&mut app, KeyCode::Char('1'));
    assert_eq!(run(&app).answer(), Some(0));
    assert!(!run(&app).awaiting_prediction());
    keys(&mut app, "me+++ ");
    for _ in 0..300 {
        app.tick(0.1);
        if run(&app).revealed().is_some() {
            break;
        }
    }
    let revealed = run(&app)
        .revealed()
        .expect("revealed after the run decided")
        .to_string();
    assert!(revealed.contains("blew up"), "{revealed}");
    assert!(revealed.contains("2) semi-implicit Euler"), "{revealed}");
    assert!(revealed.contains("✗ you predicted 1)"), "{revealed}");
    let text = screen_text(&app, 120, 40);
    assert!(text.contains("✗ you predicted"), "{text}");
}

/// The status line shows the method's limit on the scene by the damped theory, and marks a dt
/// beyond it.
#[test]
fn status_line_shows_the_damped_limit() {
    use springlab::tui::lesson_run::Limit;
    // The oscillator under semi-implicit Euler: dt·ω < 2, ω = 10 rad/s.
    let mut app = open("euler");
    key(&mut app, KeyCode::Char('n'));
    let (limit, omega) = run(&app).limit().expect("a limit").clone();
    assert!((omega - 10.0).abs() < 1e-9);
    let Limit::Below(dt) = limit else {
        panic!("conditional: {limit:?}")
    };
    assert!((dt - 0.2).abs() < 1e-3, "{dt}");
    // Kept back until the prediction (which method survives dt·ω = 1.6) is answered.
    let before = screen_text(&app, 120, 40);
    assert!(before.contains("limit: after your prediction"), "{before}");
    assert!(!before.contains("stable below"), "{before}");
    key(&mut app, KeyCode::Char('1'));
    // Shown beside the usable dt, which is lower here (tests/tui_usable.rs).
    assert!(screen_text(&app, 120, 40).contains("stable below 0.2 s"));
    keys(&mut app, "++++");
    assert!(screen_text(&app, 120, 40).contains("✗ over limit"));
    // Explicit Euler without damping: unstable at every dt; with the damper, a limit.
    let mut app = open("euler");
    assert_eq!(run(&app).limit().map(|l| l.0.clone()), Some(Limit::Never));
    keys(&mut app, "DDDDDDDDDD");
    assert!(matches!(
        run(&app).limit().map(|l| l.0.clone()),
        Some(Limit::Below(_))
    ));
    // The jelly: the dampers set semi-implicit Euler's limit far below dt·ω = 2.
    let mut app = open("jelly");
    keys(&mut app, "nn");
    let (limit, omega) = run(&app).limit().expect("a limit").clone();
    let Limit::Below(dt) = limit else {
        panic!("conditional: {limit:?}")
    };
    assert!(dt * omega < 0.5, "dt·ω = {}", dt * omega);
}

/// Every live edit of the model (stiffness, damping, drag, γ, passes, dt, the method, a pin)
/// restarts the energy accounting from the present state: right after the key the energy
/// error `E + D - E_0` is zero, where the run before it had accumulated one (so the plot of
/// the method's energy error does not jump by the edit's change of energy). One test per
/// lesson, so that the test threads share them.
mod every_live_edit_rebases_the_energy_accounting {
    #[test]
    fn verlet() {
        super::edits_rebase(
            "verlet",
            &["K", "k", "D", "d", "A", "a", "G", "g", "J", "j", "+", "-"],
        );
    }

    #[test]
    fn euler() {
        super::edits_rebase("euler", &["me", "ms", "mr", "mi"]);
    }

    #[test]
    fn cloth() {
        super::edits_rebase("cloth", &["1", "2"]);
    }
}

/// Each of `edits` pressed after a short run of lesson `slug` leaves no energy error.
fn edits_rebase(slug: &str, edits: &[&str]) {
    let mut app = open(slug);
    for edit in edits {
        keys(&mut app, " ");
        for _ in 0..3 {
            app.tick(0.1);
        }
        keys(&mut app, " ");
        let sim = run(&app).sim();
        assert!(sim.diverged.is_none(), "{slug} {edit}");
        let before = sim.energy_residual();
        assert!(
            before != 0.0,
            "{slug} before {edit}: the run has an energy error"
        );
        keys(&mut app, edit);
        let after = run(&app).sim().energy_residual();
        assert!(
            after.abs() <= 1e-12 * run(&app).sim().energy().total.abs().max(1.0),
            "{slug} {edit}: energy error {after} J right after the edit (was {before} J)"
        );
    }
}

/// A prediction about the bodies of one run (lesson 4 step 3: which rope comes to rest) is
/// revealed with what each body did in the student's run, not a bare "kept going".
#[test]
fn a_per_body_prediction_reveals_each_body() {
    let mut app = open("verlet");
    keys(&mut app, "nn");
    assert!(run(&app).awaiting_prediction());
    keys(&mut app, "2GGG ");
    for _ in 0..300 {
        app.tick(0.1);
        if run(&app).revealed().is_some() {
            break;
        }
    }
    let revealed = run(&app).revealed().expect("revealed").to_string();
    assert!(
        revealed.contains("the semi-implicit Euler rope (left) still moving"),
        "{revealed}"
    );
    assert!(
        revealed.contains("the Verlet rope (right) at rest"),
        "{revealed}"
    );
    assert!(revealed.contains("✓ you predicted it"), "{revealed}");
}

/// A progress file kept aside: the menu's notice, wrapped, shows where the old file went on an
/// 80×24 screen, and stays while the student moves through the list.
#[test]
fn the_notice_of_a_progress_file_kept_aside_is_read_whole_at_80x24() {
    use springlab::tui::Progress;
    let dir = temp_dir("notice");
    let path = dir.join("progress.json");
    std::fs::write(&path, "garbage{{{ not json").expect("write");
    let progress = Progress::load(&path);
    let notice = progress.notice().expect("told").to_string();
    let aside = notice
        .split_whitespace()
        .find(|w| w.contains("progress.json.unreadable-"))
        .expect("the notice names the file kept aside")
        .to_string();
    let mut app = App::new(lesson::builtin(), Theme::PLAIN).with_progress(progress);
    for _ in 0..2 {
        let text: String = screen_text(&app, 80, 24)
            .split_whitespace()
            .collect::<String>()
            .replace('"', "");
        let words: String = notice.split_whitespace().collect();
        assert!(
            text.contains(&words),
            "the whole notice:\n{}",
            screen_text(&app, 80, 24)
        );
        assert!(text.contains(&aside));
        key(&mut app, KeyCode::Down);
    }
    key(&mut app, KeyCode::Char('9'));
    assert_eq!(app.menu_message(), Some("there is no lesson 9"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The message of `+` gives dt to four significant digits, as the status line does (1.359e-3 s,
/// not 0.001 s).
#[test]
fn the_dt_message_has_the_status_lines_digits() {
    let mut app = open("model");
    keys(&mut app, "nnn");
    if run(&app).awaiting_prediction() {
        key(&mut app, KeyCode::Char('1'));
    }
    keys(&mut app, "++++");
    let dt = run(&app).sim().dt();
    let message = run(&app).message().expect("a message").to_string();
    assert_eq!(
        message,
        format!("dt = {} s", springlab::tui::status::precise(dt))
    );
    assert!(message.contains("e-3") || dt >= 1e-2, "{message}");
}

/// PgDn moves the step's text by what the screen shows less one row: at 80 × 24 with a
/// prediction below it (lesson 3 step 2: three rows of text), the last row of one page is the
/// first of the next, so no line is skipped.
#[test]
fn page_down_moves_by_the_rows_shown_and_skips_no_line() {
    let mut app = open("euler");
    keys(&mut app, "n");
    assert!(
        run(&app).awaiting_prediction(),
        "lesson 3 step 2 asks first"
    );
    key(&mut app, KeyCode::Char('2'));
    // The text rows: below the header, above the row holding the scroll hint.
    let text_rows = |app: &App| -> Vec<String> {
        let screen = screen_text(app, 80, 24);
        let left: Vec<String> = screen
            .lines()
            .map(|l| l.trim_matches('"').chars().take(40).collect())
            .collect();
        let hint = left
            .iter()
            .position(|l| l.contains("PgDn") || l.contains("PgUp"))
            .expect("the text scrolls at 80x24");
        left[1..hint]
            .iter()
            .map(|l| l.trim_end().to_string())
            .collect()
    };
    let mut page = text_rows(&app);
    assert!(page.len() >= 2, "{page:?}");
    for _ in 0..40 {
        let before = run(&app).text_scroll();
        key(&mut app, KeyCode::PageDown);
        let next = text_rows(&app);
        if run(&app).text_scroll() == before || next == page {
            break;
        }
        // The next page starts on the last row of this one (or, on the last page, which
        // stops at the text's end, higher up): never below it.
        let first = next.first().expect("a row");
        assert!(
            page.contains(first),
            "a line was skipped:\n{page:?}\n{next:?}"
        );
        if page.last() != Some(first) {
            break; // the last page
        }
        page = next;
    }
}

/// Lesson 8's charts carry their legend in the title and the time unit on the last label: no
/// axis title or legend box is drawn over the data (the observable chart's `t (s)` sat on its
/// last data row), and the resolution chart names every curve of the recorded study.
#[test]
fn lesson_8_charts_name_their_curves_in_the_title_and_keep_the_data_clear() {
    let mut app = open("model");
    keys(&mut app, "nn");
    let text = screen_text(&app, 160, 48);
    assert!(!text.contains("t (s)"), "{text}");
    assert!(
        text.contains("3.00 s│"),
        "the unit on the last time label:\n{text}"
    );
    let title = text
        .lines()
        .find(|l| l.contains("┌sag:"))
        .unwrap_or_else(|| panic!("the resolution chart's title:\n{text}"));
    for kinds in ["all", "no-bend", "no-shear"] {
        assert!(title.contains(&format!(" {kinds}")), "{kinds} in {title}");
    }
}

/// Lesson 7's log-log charts keep their legend box clear: no curve shows through beside a
/// method's name (every name is padded to the box's width).
#[test]
fn the_study_charts_legend_box_is_clear_of_curves() {
    let app = open("speed-accuracy");
    let text = screen_text(&app, 120, 40);
    let mut rows = 0;
    for line in text.lines() {
        // A legend row: "│1EE 1.06  │" inside the chart's frame.
        for (i, _) in line.match_indices("││") {
            let rest: String = line[i + "││".len()..]
                .chars()
                .take_while(|c| *c != '│')
                .collect();
            if rest.chars().next().is_some_and(|c| c.is_ascii_digit()) {
                rows += 1;
                assert!(
                    !rest.chars().any(|c| ('\u{2800}'..='\u{28ff}').contains(&c)),
                    "a curve inside the legend: {rest:?}\n{text}"
                );
            }
        }
    }
    assert!(rows >= 9, "the nine methods' legend rows:\n{text}");
}

/// At 80 columns a step's two plots do not fit side by side: one shows, its border says
/// "Tab: plot 1 of 2", and Tab turns to the other (lesson 4 step 1's stretch plot).
#[test]
fn tab_turns_to_the_plot_that_does_not_fit() {
    let mut app = open("verlet");
    let first = screen_text(&app, 80, 24);
    assert!(first.contains("Tab: plot 1 of 2"), "{first}");
    assert!(!first.contains("max |L/L0 - 1|"), "{first}");
    key(&mut app, KeyCode::Tab);
    let second = screen_text(&app, 80, 24);
    assert!(
        second.contains("max |L/L0 - 1|"),
        "the stretch plot:\n{second}"
    );
    assert!(second.contains("Tab: plot 2 of 2"), "{second}");
    // Wide enough for both: no hint.
    assert!(!screen_text(&app, 160, 48).contains("Tab: plot"));
}
