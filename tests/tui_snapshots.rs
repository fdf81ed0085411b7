//! Snapshots of the lesson app drawn into ratatui's `TestBackend` at 100 × 32: the menu, the
//! first step of every lesson (initial state: nothing depends on the wall clock), the help
//! overlay, a diverged run and the "terminal too small" message.
//!
//! After an intended change of the screens, review with `cargo insta review` (or accept with
//! `INSTA_UPDATE=always cargo test --test tui_snapshots`) and commit `tests/snapshots/`.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson;
use springlab::tui::{App, Theme};

fn draw(app: &App, width: u16, height: u16) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    terminal.backend().to_string()
}

fn app() -> App {
    App::new(lesson::builtin(), Theme { color: false })
}

fn key(app: &mut App, code: KeyCode) {
    app.handle_key(KeyEvent::new(code, KeyModifiers::NONE));
}

#[test]
fn menu() {
    insta::assert_snapshot!("menu", draw(&app(), 100, 32));
}

#[test]
fn first_step_of_every_lesson() {
    let mut app = app();
    let lessons = app.lessons().to_vec();
    for (i, l) in lessons.iter().enumerate() {
        let l = l.as_ref().expect("built-in lessons load");
        app.open_lesson(i).expect("opens");
        insta::assert_snapshot!(format!("lesson_{}_step_1", l.number), draw(&app, 100, 32));
    }
}

#[test]
fn help_overlay() {
    let mut app = app();
    app.open_lesson(0).expect("opens");
    key(&mut app, KeyCode::Char('?'));
    insta::assert_snapshot!("help", draw(&app, 100, 32));
}

#[test]
fn diverged_run_shows_where_it_stopped() {
    let mut app = app();
    let euler = app.find_lesson("euler").expect("lesson 3");
    app.open_lesson(euler).expect("opens");
    // Explicit Euler on the rope (step 3) blows up within seconds.
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..100 {
        app.tick(0.1);
    }
    let run = app.lesson().expect("open");
    assert!(run.sim().diverged.is_some());
    assert!(!run.is_running());
    insta::assert_snapshot!("diverged", draw(&app, 100, 32));
}

#[test]
fn small_terminal_gets_a_message() {
    let mut app = app();
    app.open_lesson(0).expect("opens");
    insta::assert_snapshot!("too_small", draw(&app, 70, 20));
}

#[test]
fn smallest_supported_terminal() {
    let mut app = app();
    app.open_lesson(1).expect("opens");
    insta::assert_snapshot!("lesson_2_step_1_80x24", draw(&app, 80, 24));
}

/// A 3D scene of two bodies: a 4 × 4 × 4 jelly cube over a floor, beside a sphere and a bowl,
/// and a 5 × 5 cloth with a dynamic sphere under it.
fn scene_3d() -> springlab::Scene {
    use glam::DVec3;
    use springlab::physics::collide::{Collider, ContactParams, DynamicSphere};
    use springlab::scene::builder::Builder;
    use springlab::scene::lattice::{self, ClothSpec, CubeSpec, KindCoefficients};
    use springlab::scene::{Body, Scene};
    use springlab::{Method, MethodParams};

    let mut b = Builder::new();
    lattice::cube(
        &mut b,
        &CubeSpec {
            counts: [4, 4, 4],
            edge_length: DVec3::splat(1.0),
            coefficients: KindCoefficients::uniform(500.0, 5.0),
            offset: DVec3::new(-2.5, 1.0, -0.5),
            ..CubeSpec::default()
        },
    );
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    let model = model.with_colliders(
        vec![
            Collider::plane(DVec3::ZERO, DVec3::Y),
            Collider::sphere(DVec3::new(0.0, 0.5, 2.0), 0.5),
            Collider::bowl(DVec3::new(2.0, 1.0, 0.0), 1.0, 1.0),
        ],
        ContactParams::default(),
    );
    let cube = Body {
        label: "cube".into(),
        model,
        state,
        method: Method::SemiImplicitEuler,
        params: MethodParams::default(),
    };
    let mut b = Builder::new();
    lattice::cloth(
        &mut b,
        &ClothSpec {
            n: 5,
            origin: DVec3::new(-0.5, 2.5, 1.5),
            size: [1.0, 1.0],
            coefficients: KindCoefficients::uniform(500.0, 1.0),
            pinned: lattice::corners(5),
            ..ClothSpec::default()
        },
    );
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.0);
    let state = state.with_spheres(vec![DynamicSphere::new(DVec3::new(0.0, 2.0, 2.0), 0.3)]);
    let cloth = Body {
        label: "cloth".into(),
        model,
        state,
        method: Method::SemiImplicitEuler,
        params: MethodParams::default(),
    };
    Scene {
        name: "test-3d".into(),
        bodies: vec![cube, cloth],
        dt: 0.001,
        duration: 1.0,
    }
}

#[test]
fn three_d_scene_with_colliders_and_two_bodies() {
    let mut app = app();
    app.open_lesson(0).expect("opens");
    app.lesson_mut().expect("open").set_scene(scene_3d());
    insta::assert_snapshot!("scene_3d", draw(&app, 100, 32));
    // Orbiting, the kinds filter and a few steps draw at every angle.
    for _ in 0..24 {
        key(&mut app, KeyCode::Right);
        key(&mut app, KeyCode::Down);
        key(&mut app, KeyCode::Char('t'));
        key(&mut app, KeyCode::Char('s'));
        draw(&app, 100, 32);
    }
    // The cloth is the second body: its corners answer keys 1-4.
    let pinned = |app: &App| {
        app.lesson().expect("open").sim().scene.bodies[1]
            .model
            .is_pinned(24)
    };
    assert!(pinned(&app));
    key(&mut app, KeyCode::Char('4'));
    assert!(!pinned(&app));
}
