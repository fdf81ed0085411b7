//! The lesson app's one camera: following keeps the bodies in view, `r` and entering a step
//! restore the step's first view exactly, zoom, pan and orbit move it as the keys say.

use glam::DVec3;
use ratatui::crossterm::event::{KeyCode, KeyModifiers, MouseEvent, MouseEventKind};
use ratatui::layout::Rect;
use springlab::lesson;
use springlab::render::View;
use springlab::render::camera::ZOOM_STEP;
use springlab::tui::LessonRun;
use springlab::tui::lesson_run::PAN_STEP;

fn lesson_run(slug: &str, step: usize) -> LessonRun {
    let l = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == slug)
        .expect("lesson");
    let mut run = LessonRun::new(l, step).expect("step");
    run.set_aspect(1.75);
    run
}

/// True when every particle of `run` projects inside a 350 × 200 image of its camera.
fn all_in_view(run: &LessonRun) -> bool {
    let view = View::new(run.camera(), 350, 200);
    run.sim().positions().all(|p| {
        view.project(p)
            .is_some_and(|q| (0.0..=350.0).contains(&q.x) && (0.0..=200.0).contains(&q.y))
    })
}

fn centroid(run: &LessonRun) -> DVec3 {
    let n = run.sim().positions().count() as f64;
    run.sim().positions().sum::<DVec3>() / n
}

/// Lesson 5, step 4: the cube slides down the 45° slope, out of the first view.
#[test]
fn following_keeps_the_sliding_cube_in_view_for_8_s() {
    let mut run = lesson_run("jelly", 3);
    assert_eq!(run.sim().scene.name, "cube-tilted");
    assert!(run.follows(), "on by default");
    let start = centroid(&run);
    run.handle_key(KeyCode::Char(' '));
    let mut still = run.clone();
    still.handle_key(KeyCode::Char('f'));
    assert!(!still.follows());
    for frame in 0..240 {
        run.tick(1.0 / 30.0);
        still.tick(1.0 / 30.0);
        assert!(
            all_in_view(&run),
            "a particle left the view at frame {frame}"
        );
    }
    assert!(
        (run.sim().time() - 8.0).abs() < 1e-9,
        "t = {}",
        run.sim().time()
    );
    // The cube travelled (more than 5 m along the slope), and the fixed view lost it.
    assert!((centroid(&run) - start).length() > 5.0);
    let view = View::new(still.camera(), 350, 200);
    let c = view.project(centroid(&still)).expect("in front");
    assert!(
        !((0.0..=350.0).contains(&c.x) && (0.0..=200.0).contains(&c.y)),
        "without following the centroid leaves the view: {c:?}"
    );
}

#[test]
fn r_restores_the_steps_first_view_exactly() {
    let mut run = lesson_run("jelly", 3);
    let first = *run.camera();
    assert_eq!(first, *run.home_camera());
    run.handle_key(KeyCode::Char(' '));
    for _ in 0..30 {
        run.tick(0.1);
    }
    run.handle_key(KeyCode::Char('i'));
    run.handle_key(KeyCode::Left);
    run.handle_key_with(KeyCode::Up, KeyModifiers::SHIFT);
    assert_ne!(*run.camera(), first);
    run.handle_key(KeyCode::Char('r'));
    assert_eq!(*run.camera(), first);
    // The same as a freshly opened step.
    assert_eq!(*lesson_run("jelly", 3).camera(), first);
    // Entering a step starts from its first view too.
    run.handle_key(KeyCode::Char('o'));
    run.handle_key(KeyCode::Char('n'));
    run.handle_key(KeyCode::Char('p'));
    assert_eq!(*run.camera(), first);
    // `c`: the view only, the simulation stays where it is.
    run.handle_key(KeyCode::Char('s'));
    run.handle_key(KeyCode::Right);
    run.handle_key(KeyCode::Char('c'));
    assert_eq!(*run.camera(), first);
    assert_eq!(run.sim().steps, 1);
}

/// Lesson 3, step 3: explicit Euler on the rope blows up; the view may have widened, `r` brings
/// it back.
#[test]
fn after_a_divergence_r_brings_the_view_back() {
    let mut run = lesson_run("euler", 2);
    let first = *run.camera();
    run.handle_key(KeyCode::Char(' '));
    for _ in 0..200 {
        run.tick(0.1);
    }
    assert!(run.sim().diverged.is_some());
    assert!(run.camera().distance <= 10.0 * first.distance * (1.0 + 1e-12));
    run.handle_key(KeyCode::Char('r'));
    assert_eq!(*run.camera(), first);
}

#[test]
fn zoom_pan_and_orbit_keys() {
    // The rope: nothing moves while paused, so following does not interfere.
    let mut run = lesson_run("rope", 0);
    let first = *run.camera();
    run.handle_key(KeyCode::Char('f'));
    run.handle_key(KeyCode::Char('o'));
    assert!((run.camera().distance - first.distance * ZOOM_STEP).abs() < 1e-9);
    run.handle_key(KeyCode::Char('i'));
    run.handle_key(KeyCode::Char('i'));
    assert!((run.camera().distance - first.distance / ZOOM_STEP).abs() < 1e-9);
    // The wheel zooms like i / o, over the pane only.
    let pane = Rect::new(10, 2, 60, 20);
    let wheel = |kind, column| MouseEvent {
        kind,
        column,
        row: 5,
        modifiers: KeyModifiers::NONE,
    };
    let before = run.camera().distance;
    assert!(run.handle_mouse(wheel(MouseEventKind::ScrollDown, 20), pane));
    assert!((run.camera().distance - before * ZOOM_STEP).abs() < 1e-9);
    assert!(!run.handle_mouse(wheel(MouseEventKind::ScrollDown, 2), pane));
    // Shift + arrow: a tenth of the visible height along the camera's right vector.
    let cam = *run.camera();
    run.handle_key_with(KeyCode::Right, KeyModifiers::SHIFT);
    let (right, up, _) = cam.basis();
    let moved = run.camera().target - cam.target;
    assert!((moved - PAN_STEP * cam.visible_height() * right).length() < 1e-12);
    assert!(moved.dot(up).abs() < 1e-12);
    // Arrows orbit by 15°.
    let (orbit, elevation) = run.camera().angles_degrees();
    run.handle_key(KeyCode::Right);
    run.handle_key(KeyCode::Up);
    assert_eq!(run.camera().angles_degrees(), (orbit + 15, elevation + 15));
}

#[test]
fn following_never_moves_a_camera_whose_bodies_are_in_view() {
    // The pinned rope swings inside its first view: following leaves the camera alone.
    let mut run = lesson_run("rope", 0);
    let first = *run.camera();
    run.handle_key(KeyCode::Char(' '));
    for _ in 0..50 {
        run.tick(0.1);
        assert_eq!(*run.camera(), first);
    }
}

#[test]
fn the_mouse_picks_through_the_grid_of_the_view_shown() {
    use ratatui::crossterm::event::MouseButton;
    use springlab::tui::pane::grid_view;
    // A raster view on 9 × 17-pixel cells: the particle is found where the image shows it.
    let mut run = lesson_run("rope", 0);
    let pane = Rect::new(40, 2, 58, 18);
    let grid = (9, 17);
    run.set_grid(grid);
    let target = run.sim().scene.bodies[0].state.x[1];
    let view = grid_view(run.camera(), pane, grid);
    let q = view.project(target).expect("in front");
    let column = pane.x + (q.x / 9.0) as u16;
    let row = pane.y + (q.y / 17.0) as u16;
    let down = MouseEvent {
        kind: MouseEventKind::Down(MouseButton::Left),
        column,
        row,
        modifiers: KeyModifiers::NONE,
    };
    assert!(run.handle_mouse(down, pane));
    assert_eq!(run.dragged(), Some((0, 1)));
    // Dragged one row down, it sits under that cell's centre in the same grid.
    let drag = MouseEvent {
        kind: MouseEventKind::Drag(MouseButton::Left),
        row: row + 1,
        ..down
    };
    assert!(run.handle_mouse(drag, pane));
    let moved = view
        .project(run.sim().scene.bodies[0].state.x[1])
        .expect("in front");
    assert!((f64::from(moved.y) - (f64::from(row + 1 - pane.y) + 0.5) * 17.0).abs() < 1e-2);
    assert!((moved.depth - q.depth).abs() < 1e-9);
}

crate::common::per_lesson!(
    no_step_starts_with_the_camera_moving,
    camera_still_at_start,
    every
);

#[test]
fn every_lesson_starts_its_steps_with_the_camera_still() {
    assert_eq!(
        crate::common::lesson_slugs(),
        no_step_starts_with_the_camera_moving::SLUGS
    );
}

/// The first view of each step of lesson `slug` frames it; following moves it only once a body
/// nears the edge.
fn camera_still_at_start(slug: &str) {
    let l = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == slug)
        .expect("a built-in lesson");
    for step in 0..l.steps.len() {
        let mut run = LessonRun::new(l.clone(), step).expect("step");
        run.set_aspect(1.75);
        let first = *run.camera();
        run.handle_key(KeyCode::Char(' '));
        run.tick(0.02);
        assert_eq!(
            *run.camera(),
            first,
            "lesson {} step {}",
            l.number,
            step + 1
        );
    }
}

/// The box of the particles of `body` (every body when `None`) in a `w × h` image of `camera`:
/// `(x_min, y_min, x_max, y_max)` in pixels; `None` when one is behind the eye.
fn projected_box(
    run: &LessonRun,
    camera: &springlab::render::Camera,
    body: Option<usize>,
    (w, h): (u32, u32),
) -> Option<(f64, f64, f64, f64)> {
    let view = View::new(camera, w, h);
    let mut b = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for (i, scene_body) in run.sim().scene.bodies.iter().enumerate() {
        if body.is_some_and(|k| k != i) {
            continue;
        }
        for p in &scene_body.state.x {
            let q = view.project(*p)?;
            let (x, y) = (f64::from(q.x), f64::from(q.y));
            b = (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y));
        }
    }
    Some(b)
}

/// Lesson 4, step 2 is about the Verlet rope's stretch; its front matter names it
/// (`camera = { body = 2 }`). The semi-implicit rope beside it stretches many times its length
/// and, framed with it, the Verlet rope would be a short line at the pins.
#[test]
fn lesson_4_step_2_frames_the_verlet_rope() {
    let verlet = |target: bool| {
        let mut l = lesson::builtin()
            .into_iter()
            .flatten()
            .find(|l| l.slug == "verlet")
            .expect("lesson 4");
        assert_eq!(l.steps[1].camera_body, Some(2));
        if !target {
            l.steps[1].camera_body = None;
        }
        let mut run = LessonRun::new(l, 1).expect("step 2");
        run.set_aspect(1.75);
        run.handle_key(KeyCode::Char(' '));
        run
    };
    let (mut framed, mut whole) = (verlet(true), verlet(false));
    assert_eq!(
        framed.sim().scene.bodies[1].method,
        springlab::physics::Method::Verlet
    );
    let (w, h) = (350, 200);
    // The share of the pane the Verlet rope spans: its box's width over the pane's width or its
    // height over the pane's height, whichever is larger; the largest over the run (the rope
    // hanging straight down).
    let share =
        |b: (f64, f64, f64, f64)| ((b.2 - b.0) / f64::from(w)).max((b.3 - b.1) / f64::from(h));
    let (mut framed_most, mut whole_most) = (0.0f64, 0.0f64);
    for _ in 0..180 {
        framed.tick(1.0 / 30.0);
        whole.tick(1.0 / 30.0);
        let b = projected_box(&framed, framed.camera(), Some(1), (w, h)).expect("in front");
        let t = framed.sim().time();
        assert!(
            b.0 >= 0.0 && b.1 >= 0.0 && b.2 <= f64::from(w) && b.3 <= f64::from(h),
            "t = {t:.2} s: the Verlet rope leaves the pane: {b:?}"
        );
        framed_most = framed_most.max(share(b));
        let o = projected_box(&whole, whole.camera(), Some(1), (w, h)).expect("in front");
        whole_most = whole_most.max(share(o));
    }
    assert!((framed.sim().time() - 6.0).abs() < 1e-9);
    assert!(
        framed_most >= 0.75,
        "the Verlet rope spans at most {:.0} % of the pane",
        100.0 * framed_most
    );
    // Framing both ropes, the Verlet rope is a short line by the pins.
    assert!(
        whole_most < 0.5,
        "framed with the stretching rope, the Verlet rope still spans {:.0} %",
        100.0 * whole_most
    );
}

/// Lesson 5, step 4: following keeps the sliding cube whole in the pane at 4 s and 6 s, away
/// from its edges and at a fifth of its height or more, and so does the `e` export (read back from its
/// pixels: the cube is the only red in the picture).
#[test]
fn the_sliding_cube_stays_whole_in_the_pane_and_the_export() {
    let mut run = lesson_run("jelly", 3);
    let (w, h) = (350, 200);
    run.handle_key(KeyCode::Char(' '));
    let tmp = tempfile::tempdir().expect("temp dir");
    for (frames, at) in [(120, 4.0), (60, 6.0)] {
        for _ in 0..frames {
            run.tick(1.0 / 30.0);
        }
        assert!(
            (run.sim().time() - at).abs() < 1e-6,
            "t = {}",
            run.sim().time()
        );
        let b = projected_box(&run, run.camera(), None, (w, h)).expect("in front");
        // Whole, with a margin of a twentieth of the pane on every side.
        let (mx, my) = (0.05 * f64::from(w), 0.05 * f64::from(h));
        assert!(
            b.0 >= mx && b.1 >= my && b.2 <= f64::from(w) - mx && b.3 <= f64::from(h) - my,
            "t = {at} s: the cube is not whole in the pane: {b:?}"
        );
        assert!(
            (b.3 - b.1) / f64::from(h) >= 0.2,
            "t = {at} s: the cube is {:.0} % of the pane's height",
            100.0 * (b.3 - b.1) / f64::from(h)
        );
        // The export: the picture between its caption bands.
        let path = tmp.path().join(format!("cube-{at}.png"));
        crate::tui_export::export_run(&run, &path).expect("export");
        let (iw, ih, rgba) = crate::tui_export::read_png(&path);
        let size = springlab::tui::export::export_size(run.aspect());
        let (top, bottom) = crate::tui_export::bands(&run, size);
        assert_eq!((iw, ih), (size.0, size.1 + top + bottom));
        let mut red = (u32::MAX, u32::MAX, 0, 0);
        let mut count = 0u64;
        for y in top..top + size.1 {
            for x in 0..iw {
                let i = ((y * iw + x) * 4) as usize;
                let (r, g, bl) = (
                    i32::from(rgba[i]),
                    i32::from(rgba[i + 1]),
                    i32::from(rgba[i + 2]),
                );
                if r > g + 60 && r > bl + 60 {
                    red = (
                        red.0.min(x),
                        red.1.min(y - top),
                        red.2.max(x),
                        red.3.max(y - top),
                    );
                    count += 1;
                }
            }
        }
        assert!(count > 0, "t = {at} s: no cube in the export");
        let (ex, ey) = (size.0 / 40, size.1 / 40);
        assert!(
            red.0 >= ex && red.1 >= ey && red.2 < size.0 - ex && red.3 < size.1 - ey,
            "t = {at} s: the cube touches the export's edge: {red:?} in {size:?}"
        );
        assert!(
            f64::from(red.3 - red.1) / f64::from(size.1) >= 0.2,
            "t = {at} s: the cube is {} of {} rows of the export",
            red.3 - red.1,
            size.1
        );
    }
}
