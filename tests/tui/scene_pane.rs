//! The lesson app's scene pane: cloth corners pinned by keys, export, the mouse, the camera,
//! the three views and what each draws.

use super::*;

/// A scene file (Form 2) with an `n × n` cloth: struct, shear and bend springs in the lattice
/// order, corners 0 and n - 1 pinned.
fn cloth_scene(n: usize) -> String {
    let mut s = String::from(
        "[world]\ngravity = [0.0, -9.8, 0.0]\n\n[run]\nmethod = \"semi-implicit-euler\"\ndt = 0.001\n\n",
    );
    let h = 1.0 / (n as f64 - 1.0);
    for r in 0..n {
        for c in 0..n {
            let pinned = r == 0 && (c == 0 || c == n - 1);
            s += &format!(
                "[[particles]]\nposition = [{}, 1.0, {}]\nmass = 0.01\npinned = {pinned}\n\n",
                c as f64 * h,
                r as f64 * h
            );
        }
    }
    let kinds: [(&str, &[[i64; 2]]); 3] = [
        ("struct", &[[0, 1], [1, 0]]),
        ("shear", &[[1, 1], [1, -1]]),
        ("bend", &[[0, 2], [2, 0]]),
    ];
    let n = n as i64;
    for (kind, offsets) in kinds {
        for r in 0..n {
            for c in 0..n {
                for [dr, dc] in offsets {
                    let (r2, c2) = (r + dr, c + dc);
                    if (0..n).contains(&r2) && (0..n).contains(&c2) {
                        s += &format!(
                            "[[springs]]\na = {}\nb = {}\nstiffness = 500.0\ndamping = 0.1\nkind = \"{kind}\"\n\n",
                            r * n + c,
                            r2 * n + c2
                        );
                    }
                }
            }
        }
    }
    s
}

fn cloth_app(name: &str, n: usize) -> (App, PathBuf) {
    let dir = temp_dir(name);
    std::fs::write(dir.join("cloth.toml"), cloth_scene(n)).expect("write");
    std::fs::write(
        dir.join("01-cloth.md"),
        "+++\nnumber = 1\nslug = \"cloth\"\ntitle = \"Cloth\"\nsummary = \"A cloth.\"\n+++\n\n\
         +++ step\ntitle = \"Hanging cloth\"\nscene = \"cloth.toml\"\nplots = [\"energy\"]\n+++\nA cloth.\n",
    )
    .expect("write");
    let lessons = lesson::load_dir(&dir).expect("readable");
    let mut app = App::new(lessons, Theme::PLAIN);
    app.open_lesson(0).expect("opens");
    (app, dir)
}

#[test]
fn keys_1_to_4_pin_and_free_cloth_corners() {
    let (mut app, dir) = cloth_app("corners", 5);
    let pinned = |app: &App, i: usize| run(app).sim().scene.bodies[0].model.is_pinned(i);
    assert!(pinned(&app, 0) && pinned(&app, 4));
    assert!(!pinned(&app, 20) && !pinned(&app, 24));
    key(&mut app, KeyCode::Char('1'));
    assert!(!pinned(&app, 0), "corner 1 freed");
    key(&mut app, KeyCode::Char('3'));
    key(&mut app, KeyCode::Char('4'));
    assert!(
        pinned(&app, 20) && pinned(&app, 24),
        "corners 3 and 4 are n(n-1) and n²-1"
    );
    key(&mut app, KeyCode::Char('1'));
    assert!(pinned(&app, 0));
    // A freed corner falls; a pinned one stays put.
    key(&mut app, KeyCode::Char('2'));
    let before = run(&app).sim().scene.bodies[0].state.x.clone();
    for _ in 0..20 {
        key(&mut app, KeyCode::Char('s'));
    }
    let after = &run(&app).sim().scene.bodies[0].state.x;
    assert_eq!(after[0], before[0]);
    assert!(after[4].y < before[4].y);
    // The spring-kind filter cycles.
    for expected in ["struct", "shear", "bend", "none", "all"] {
        key(&mut app, KeyCode::Char('t'));
        assert_eq!(run(&app).spring_filter().name(), expected);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn corner_keys_on_a_scene_without_cloth_say_so() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('1'));
    assert!(run(&app).message().is_some_and(|m| m.contains("cloth")));
    assert!(screen_text(&app, 100, 32).contains("pin the corners of a cloth"));
}

#[test]
fn e_exports_the_current_frame_as_png() {
    let mut app = open("rope");
    key(&mut app, KeyCode::Char('s'));
    key(&mut app, KeyCode::Char('e'));
    // The file goes to the current directory, named after lesson, step and simulation step.
    let name = "springlab-rope-step1-000001.png";
    assert_eq!(run(&app).message(), Some(format!("wrote {name}").as_str()));
    let bytes = std::fs::read(name).expect("the exported file");
    std::fs::remove_file(name).ok();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG signature");
}

#[test]
fn mouse_grabs_drags_and_releases_a_particle() {
    let mut app = open("rope");
    draw(&app, 100, 32); // records where the canvas is
    let run_ref = run(&app);
    let camera = *run_ref.camera();
    let inner = canvas_inner(&app);
    // The cell of particle 1 (the free end).
    // The cell of particle 1 (the free end): its pixel on the pane's braille dots (2 × 4 a
    // cell).
    let view = pane::dot_view(&camera, inner);
    let p = view
        .project(run_ref.sim().scene.bodies[0].state.x[1])
        .expect("in front of the camera");
    let column = inner.x + (p.x / 2.0) as u16;
    let row = inner.y + (p.y / 4.0) as u16;
    let mouse = |kind, column, row| MouseEvent {
        kind,
        column,
        row,
        modifiers: KeyModifiers::NONE,
    };
    assert!(app.handle_mouse(mouse(MouseEventKind::Down(MouseButton::Left), column, row)));
    assert_eq!(run(&app).dragged(), Some((0, 1)));
    assert!(
        run(&app).sim().scene.bodies[0].model.is_pinned(1),
        "held still"
    );
    // Drag 5 rows down: the particle follows in the view plane, at rest.
    assert!(app.handle_mouse(mouse(
        MouseEventKind::Drag(MouseButton::Left),
        column,
        row + 5
    )));
    let state = &run(&app).sim().scene.bodies[0].state;
    // It sits under the centre of the cell, in the view plane of its grab (same depth).
    let q = view.project(state.x[1]).expect("in front");
    assert!((f64::from(q.x) - (f64::from(column - inner.x) + 0.5) * 2.0).abs() < 1e-3);
    assert!((f64::from(q.y) - (f64::from(row + 5 - inner.y) + 0.5) * 4.0).abs() < 1e-3);
    assert!((q.depth - p.depth).abs() < 1e-9);
    assert_eq!(state.v[1], glam::DVec3::ZERO);
    // Stepping while held keeps it there.
    let held = state.x[1];
    key(&mut app, KeyCode::Char('s'));
    assert_eq!(run(&app).sim().scene.bodies[0].state.x[1], held);
    assert!(app.handle_mouse(mouse(
        MouseEventKind::Up(MouseButton::Left),
        column,
        row + 5
    )));
    assert_eq!(run(&app).dragged(), None);
    assert_eq!(
        run(&app).sim().scene.bodies[0].model.inv_mass[1],
        1.0,
        "mass restored"
    );
    // A click far from every particle grabs nothing.
    let far = mouse(MouseEventKind::Down(MouseButton::Left), inner.x, inner.y);
    app.handle_mouse(far);
    assert_eq!(run(&app).dragged(), None);
}

/// The canvas's inner area as drawn at 100 × 32 (the app records it while drawing).
fn canvas_inner(app: &App) -> Rect {
    let terminal = draw(app, 100, 32);
    let buffer = terminal.backend().buffer();
    // The canvas block's top-left corner is the first "┌" on row 1.
    let x = (0..buffer.area.width)
        .find(|&x| buffer[(x, 1)].symbol() == "┌")
        .expect("canvas border");
    let bottom = (2..buffer.area.height)
        .find(|&y| buffer[(x, y)].symbol() == "└")
        .expect("canvas bottom");
    Rect::new(x + 1, 2, buffer.area.width - x - 2, bottom - 2)
}

#[test]
fn arrows_orbit_the_camera() {
    let mut app = open("rope");
    let (yaw, pitch) = run(&app).camera().angles_degrees();
    key(&mut app, KeyCode::Right);
    key(&mut app, KeyCode::Up);
    assert_eq!(run(&app).camera().angles_degrees(), (yaw + 15, pitch + 15));
    for _ in 0..10 {
        key(&mut app, KeyCode::Up);
    }
    assert_eq!(
        run(&app).camera().angles_degrees().1,
        89,
        "elevation stops at 89°"
    );
    // Projection and its inverse agree.
    let view = springlab::render::View::new(run(&app).camera(), 160, 96);
    let p = glam::DVec3::new(0.3, -1.2, 2.5);
    let q = view.project(p).expect("in front");
    let back = view.unproject(f64::from(q.x), f64::from(q.y), q.depth);
    assert!((back - p).length() < 1e-5, "{back} vs {p}");
}

/// The terminal sizes every screen is drawn at: degenerate, just below the 80×24 the app
/// needs in each direction, exactly that, and larger.
const SIZES: [(u16, u16); 7] = [
    (1, 1),
    (10, 5),
    (79, 24),
    (80, 23),
    (80, 24),
    (120, 40),
    (200, 60),
];

#[test]
fn the_menu_and_a_cloth_draw_at_every_size_without_panicking() {
    let app = app();
    for &(w, h) in &SIZES {
        draw(&app, w, h);
    }
    let (mut cloth, dir) = cloth_app("sizes", 6);
    key(&mut cloth, KeyCode::Right);
    for &(w, h) in &SIZES {
        draw(&cloth, w, h);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

crate::common::per_lesson!(
    every_screen_draws_at_every_size_without_panicking,
    every_screen_draws,
    every
);

#[test]
fn every_lesson_is_drawn_at_every_size() {
    assert_eq!(
        crate::common::lesson_slugs(),
        every_screen_draws_at_every_size_without_panicking::SLUGS
    );
}

/// Every step of lesson `slug`, with and without the help overlay, drawn at every size; a
/// terminal below 80×24 is told so.
fn every_screen_draws(slug: &str) {
    let mut app = open(slug);
    loop {
        for &(w, h) in &SIZES {
            draw(&app, w, h);
        }
        key(&mut app, KeyCode::Char('?'));
        draw(&app, 80, 24);
        key(&mut app, KeyCode::Char('?'));
        let step = run(&app).step_index();
        key(&mut app, KeyCode::Char('n'));
        if run(&app).step_index() == step {
            break;
        }
    }
    assert_eq!(run(&app).step_index() + 1, run(&app).lesson().steps.len());
    assert!(screen_text(&app, 70, 20).contains("needs at least 80×24"));
}

#[test]
fn no_color_draws_without_colours() {
    let plain = {
        let mut app = app();
        app.open_lesson(1).expect("opens");
        draw(&app, 100, 32)
    };
    let buffer = plain.backend().buffer();
    assert!(
        buffer
            .content()
            .iter()
            .all(|c| c.fg == Color::Reset && c.bg == Color::Reset)
    );
    let mut coloured = App::new(lesson::builtin(), Theme::DARK);
    coloured.open_lesson(1).expect("opens");
    let terminal = draw(&coloured, 100, 32);
    assert!(
        terminal
            .backend()
            .buffer()
            .content()
            .iter()
            .any(|c| c.fg != Color::Reset)
    );
}

#[test]
fn v_cycles_the_views_and_the_status_line_names_the_view() {
    // 120 columns: at 100 the usable dt and the stable limit of lesson 1's first step come
    // before the view's name, which is dropped (the status line drops fields by priority).
    use springlab::tui::{ColourDepth, Graphics, Protocol, ViewMode};
    let mut plain = app();
    plain.open_lesson(0).expect("opens");
    assert_eq!(
        plain.view(),
        ViewMode::HalfBlocks,
        "no protocol: half-blocks"
    );
    assert!(screen_text(&plain, 120, 32).contains("view: halfblocks (v)"));
    key(&mut plain, KeyCode::Char('v'));
    assert_eq!(plain.view(), ViewMode::Braille);
    assert!(screen_text(&plain, 120, 32).contains("view: braille (v)"));
    key(&mut plain, KeyCode::Char('v'));
    assert_eq!(
        plain.view(),
        ViewMode::HalfBlocks,
        "no raster view to go to"
    );
    // With a protocol the raster view is in the cycle (and asked for, it is the start).
    let sixel = Graphics {
        protocol: Some(Protocol::Sixel),
        ..Graphics::NONE
    };
    let mut raster = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        sixel,
        ColourDepth::TrueColour,
    );
    raster.open_lesson(0).expect("opens");
    assert!(screen_text(&raster, 120, 32).contains("view: raster (sixel) (v)"));
    for want in [ViewMode::HalfBlocks, ViewMode::Braille, ViewMode::Raster] {
        key(&mut raster, KeyCode::Char('v'));
        assert_eq!(raster.view(), want);
    }
    // Asking for the raster view without a protocol gives half-blocks.
    let fallback = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        Graphics::NONE,
        ColourDepth::Palette256,
    );
    assert_eq!(fallback.view(), ViewMode::HalfBlocks);
}

#[test]
fn the_raster_view_shows_the_encoded_frame() {
    use springlab::tui::{ColourDepth, Graphics, Protocol, ViewMode};
    let kitty = Graphics {
        protocol: Some(Protocol::Kitty),
        ..Graphics::NONE
    };
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        kitty,
        ColourDepth::TrueColour,
    );
    app.resize(100, 32);
    app.open_lesson(0).expect("opens");
    assert!(app.submit_raster(), "a frame is sent to the encoder");
    assert!(!app.submit_raster(), "nothing new to send");
    assert!(app.encoder().is_some(), "an encoder thread");
    let mut waited = 0;
    while app.encoder().is_some_and(|e| e.busy()) && waited < 2000 {
        std::thread::sleep(std::time::Duration::from_millis(1));
        waited += 1;
        if app.poll_raster() {
            break;
        }
    }
    let frame = app.encoder().and_then(|e| e.latest()).expect("a frame");
    let inner = canvas_inner(&app);
    assert_eq!(
        (frame.cells.width, frame.cells.height),
        (inner.width, inner.height)
    );
    // The pane now holds kitty's placeholders, not half blocks.
    let terminal = draw(&app, 100, 32);
    let cell = &terminal.backend().buffer()[(inner.x + 3, inner.y + 3)];
    assert!(cell.symbol().contains('\u{10EEEE}'), "{:?}", cell.symbol());
}

#[test]
fn a_raster_frame_of_another_lesson_is_never_shown() {
    use springlab::tui::{ColourDepth, Graphics, Protocol, ViewMode};
    let kitty = Graphics {
        protocol: Some(Protocol::Kitty),
        ..Graphics::NONE
    };
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        kitty,
        ColourDepth::TrueColour,
    );
    app.resize(100, 32);
    app.open_lesson(0).expect("opens");
    assert!(app.submit_raster());
    let wait = |app: &mut App| {
        for _ in 0..2000 {
            if app.poll_raster() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        panic!("no frame within 2 s");
    };
    wait(&mut app);
    let placeholder = |app: &App| {
        let inner = canvas_inner(app);
        let terminal = draw(app, 100, 32);
        terminal.backend().buffer()[(inner.x + 3, inner.y + 3)]
            .symbol()
            .contains('\u{10EEEE}')
    };
    assert!(placeholder(&app), "lesson 1's frame is shown");
    // Lesson 1 again, from the menu: a new run, whose versions start at 0 again.
    key(&mut app, KeyCode::Char('q'));
    app.open_lesson(0).expect("opens");
    assert!(
        !placeholder(&app),
        "the old frame is not shown: half-blocks until the new one"
    );
    assert!(app.submit_raster(), "the new run's first frame is sent");
    wait(&mut app);
    assert!(placeholder(&app));
}

/// The braille view puts a particle's mark in the cell its spring is drawn through: the pinned
/// ■ of lesson 1's first step has the spring's braille dots beside it in its own row.
#[test]
fn particle_marks_sit_on_the_braille_line() {
    let mut app = App::new(lesson::builtin(), Theme::PLAIN).with_display(
        springlab::tui::ViewMode::Braille,
        springlab::tui::Graphics::NONE,
        springlab::tui::ColourDepth::None,
    );
    for (w, h) in [(100, 32), (120, 40), (80, 24), (97, 31)] {
        app.resize(w, h);
        app.open_lesson(0).expect("opens");
        let text = screen_text(&app, w, h);
        let (row, line) = text
            .lines()
            .enumerate()
            .find(|(_, l)| l.contains('■'))
            .expect("the pinned particle is marked");
        let chars: Vec<char> = line.chars().collect();
        let at = chars.iter().position(|&c| c == '■').expect("■");
        let braille = |c: char| ('\u{2801}'..='\u{28ff}').contains(&c);
        assert!(
            braille(chars[at - 1]) || braille(chars[at + 1]),
            "{w}×{h}: the spring passes through the row of ■ (row {row}):\n{text}"
        );
    }
}

/// Lesson 1's first step says particle 0, the pinned one, is on the right: it is, in the step's
/// first view.
#[test]
fn lesson_1_pins_the_particle_on_the_right() {
    let app = App::new(lesson::builtin(), Theme::PLAIN).with_display(
        springlab::tui::ViewMode::Braille,
        springlab::tui::Graphics::NONE,
        springlab::tui::ColourDepth::None,
    );
    let mut app = app;
    app.open_lesson(0).expect("opens");
    let text = screen_text(&app, 100, 32);
    let column = |mark: char| {
        text.lines()
            .find_map(|l| l.chars().position(|c| c == mark))
            .unwrap_or_else(|| panic!("{mark} drawn:\n{text}"))
    };
    assert!(
        column('■') > column('•'),
        "the pinned ■ right of the free •:\n{text}"
    );
    assert!(run(&app).text().contains("on the **right**"));
    assert!(run(&app).sim().scene.bodies[0].model.is_pinned(0));
}
