//! Snapshots of the lesson app drawn into ratatui's `TestBackend` at 100 × 32: the menu, the
//! first step of every lesson (initial state: nothing depends on the wall clock), the help
//! overlay, a diverged run and the "terminal too small" message; and the half-block view of the
//! scene pane with its colours (the cloth with four spheres, the jelly in its bowl), at 120 × 40.
//!
//! After an intended change of the screens, review with `cargo insta review` (or accept with
//! `INSTA_UPDATE=always cargo test --test tui_snapshots`) and commit `tests/snapshots/`.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson;
use springlab::physics::Method;
use springlab::tui::{App, ColourDepth, Graphics, Theme, ViewMode};

fn draw(app: &App, width: u16, height: u16) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    terminal.backend().to_string()
}

/// The app without colours, in the braille view (the half-block views have tests of their own
/// below, with colours).
fn app() -> App {
    App::new(lesson::builtin(), Theme::PLAIN).with_display(
        ViewMode::Braille,
        Graphics::NONE,
        ColourDepth::None,
    )
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

/// The scene pane's cells in a compact text form: one line per row, runs of equal cells as
/// `count×symbol fg/bg`, colours as `#rrggbb` (24-bit) or `@n` (palette entry n).
fn pane_cells(terminal: &Terminal<TestBackend>, pane: ratatui::layout::Rect) -> String {
    use ratatui::style::Color;
    let colour = |c: Color| match c {
        Color::Rgb(r, g, b) => format!("#{r:02x}{g:02x}{b:02x}"),
        Color::Indexed(i) => format!("@{i}"),
        other => format!("{other:?}"),
    };
    let buffer = terminal.backend().buffer();
    let mut out = String::new();
    for y in pane.y..pane.y + pane.height {
        let mut runs: Vec<(usize, String)> = Vec::new();
        for x in pane.x..pane.x + pane.width {
            let c = &buffer[(x, y)];
            let text = format!("{} {}/{}", c.symbol(), colour(c.fg), colour(c.bg));
            match runs.last_mut() {
                Some((n, t)) if *t == text => *n += 1,
                _ => runs.push((1, text)),
            }
        }
        let line: Vec<String> = runs.iter().map(|(n, t)| format!("{n}×{t}")).collect();
        out.push_str(&line.join(" "));
        out.push('\n');
    }
    out
}

/// Lesson `slug` at step `step` (0-based) in the half-block view at colour depth `depth`, run
/// for `seconds` of simulated time in frames of 0.1 s; returns the pane's cells and the set of
/// distinct colours in it.
fn half_blocks(
    slug: &str,
    step: usize,
    seconds: f64,
    depth: ColourDepth,
) -> (String, std::collections::BTreeSet<String>) {
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::HalfBlocks,
        Graphics::NONE,
        depth,
    );
    app.resize(120, 40);
    let i = app.find_lesson(slug).expect("lesson");
    app.open_lesson(i).expect("opens");
    for _ in 0..step {
        key(&mut app, KeyCode::Char('n'));
    }
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..(seconds * 10.0).round() as usize {
        app.tick(0.1);
    }
    key(&mut app, KeyCode::Char(' '));
    let terminal = {
        let mut t = Terminal::new(TestBackend::new(120, 40)).expect("test backend");
        t.draw(|frame| frame.render_widget(&app, frame.area()))
            .expect("draw");
        t
    };
    let run = app.lesson().expect("open");
    let pane =
        springlab::tui::lesson_view::scene_inner(run, ratatui::layout::Rect::new(0, 0, 120, 40));
    let cells = pane_cells(&terminal, pane);
    let buffer = terminal.backend().buffer();
    let mut colours = std::collections::BTreeSet::new();
    for y in pane.y..pane.y + pane.height {
        for x in pane.x..pane.x + pane.width {
            let c = &buffer[(x, y)];
            assert_eq!(c.symbol(), "▀", "every pane cell is a half block");
            colours.insert(format!("{:?}", c.fg));
            colours.insert(format!("{:?}", c.bg));
        }
    }
    (cells, colours)
}

#[test]
fn half_blocks_cloth_with_four_spheres() {
    // Lesson 6, step 2, 1.5 s after the start: the spheres lie in the sagging cloth.
    let (cells, colours) = half_blocks("cloth", 1, 1.5, ColourDepth::TrueColour);
    // Shaded: many colours, not a flat silhouette.
    assert!(colours.len() > 40, "{} colours", colours.len());
    insta::assert_snapshot!("half_blocks_cloth_spheres", cells);
}

#[test]
fn half_blocks_jelly_in_the_bowl_256_colours() {
    // Lesson 5, step 5 (jelly-bowl), 2 s: the jelly has fallen through the hole into the bowl.
    let (cells, colours) = half_blocks("jelly", 4, 2.0, ColourDepth::Palette256);
    assert!(colours.len() > 8, "{} colours", colours.len());
    assert!(
        colours.iter().all(|c| c.starts_with("Indexed(")),
        "only palette colours: {colours:?}"
    );
    insta::assert_snapshot!("half_blocks_jelly_bowl_256", cells);
}

/// The menu after lesson 1 was completed (every step opened, its goal met) and lesson 2 begun:
/// ✓ beside lesson 1, the steps done beside each.
#[test]
fn menu_with_progress_marks() {
    use springlab::tui::Progress;
    use springlab::tui::progress::LessonProgress;
    let lessons = lesson::builtin();
    let rope = lessons[0].as_ref().expect("lesson 1");
    let n = rope.steps.len();
    let mut progress = Progress::in_memory();
    progress.update(
        &Progress::key(&rope.source, &rope.slug),
        LessonProgress {
            visited: vec![true; n],
            met: vec![true; n],
            answers: vec![None; n],
        },
    );
    progress.update(
        "hooke",
        LessonProgress {
            visited: vec![true],
            met: vec![],
            answers: vec![],
        },
    );
    let app = app().with_progress(progress);
    assert_eq!(app.lesson_done(0), Some((n, n)));
    assert_eq!(app.lesson_done(1), Some((1, 3)));
    let text = draw(&app, 100, 32);
    // Lesson 1: the lesson's ✓ and one per step (4); lesson 2: its first step.
    assert_eq!(text.matches('✓').count(), 1 + n + 1, "{text}");
    insta::assert_snapshot!("menu_progress", text);
}

/// Lesson 7, step 1 at 120 × 40: the convergence chart and the stability table with explicit
/// Euler, semi-implicit Euler and the predictor–corrector hidden (keys 1, 2, 6).
#[test]
fn lesson_7_charts_with_a_method_subset() {
    let mut app = app();
    let i = app.find_lesson("speed-accuracy").expect("lesson 7");
    app.open_lesson(i).expect("opens");
    for c in ['1', '2', '6'] {
        key(&mut app, KeyCode::Char(c));
    }
    let shown = app.lesson().expect("open").shown_methods();
    for (i, m) in Method::ALL.iter().enumerate() {
        assert_eq!(shown[i], ![0, 1, 5].contains(&i), "{m} shown");
    }
    let text = draw(&app, 120, 40);
    assert!(
        !text.contains("explicit-euler"),
        "hidden in the table:\n{text}"
    );
    assert!(
        text.contains("3mid 1.") && text.contains("4RK4 3.") && !text.contains("1EE"),
        "fitted orders of the shown methods in the legend:\n{text}"
    );
    assert!(text.contains("1e-"), "decade labels:\n{text}");
    insta::assert_snapshot!("lesson_7_subset", text);
}

/// A table wider than the text column at 80 × 24 is clipped with › and scrolls sideways with
/// `l` (then starts with ‹); nothing wraps.
#[test]
fn clipped_code_block_at_80x24() {
    let mut app = app();
    let i = app.find_lesson("speed-accuracy").expect("lesson 7");
    app.open_lesson(i).expect("opens");
    key(&mut app, KeyCode::Char('n'));
    // The step asks for a prediction first and keeps its table back until the answer.
    key(&mut app, KeyCode::Char('1'));
    key(&mut app, KeyCode::PageDown);
    let text = draw(&app, 80, 24);
    assert!(text.contains('›'), "a clipped line ends in ›:\n{text}");
    insta::assert_snapshot!("code_clipped_80x24", text);
    key(&mut app, KeyCode::Char('l'));
    let text = draw(&app, 80, 24);
    assert!(text.contains('‹'), "scrolled lines start with ‹:\n{text}");
    insta::assert_snapshot!("code_scrolled_80x24", text);
}

/// The speed plot of a run that diverged ends at the diverging sample: its top label is at
/// least the speed the status line reports.
#[test]
fn divergence_plot_draws_the_last_sample() {
    let mut app = app();
    let euler = app.find_lesson("euler").expect("lesson 3");
    app.open_lesson(euler).expect("opens");
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..100 {
        app.tick(0.1);
    }
    let d = app
        .lesson()
        .expect("open")
        .sim()
        .diverged
        .clone()
        .expect("diverged");
    let text = draw(&app, 100, 32);
    // The speed chart's top y label: the cell after its left border, one row below its title.
    let lines: Vec<Vec<char>> = text.lines().map(|l| l.chars().collect()).collect();
    let (row, col) = lines
        .iter()
        .enumerate()
        .find_map(|(r, l)| {
            let s: String = l.iter().collect();
            let at = s.find("┌max |v|")?;
            Some((r, s[..at].chars().count()))
        })
        .expect("a speed chart");
    let label: String = lines[row + 1][col + 1..]
        .iter()
        .take_while(|c| **c != '│')
        .collect();
    let top: f64 = label.trim().parse().expect("a number");
    assert!(
        top >= d.max_speed,
        "axis top {top} below the divergence speed {}\n{text}",
        d.max_speed
    );
    insta::assert_snapshot!("divergence_plot", text);
}
