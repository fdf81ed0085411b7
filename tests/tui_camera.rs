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

#[test]
fn no_step_starts_with_the_camera_moving() {
    // The first view frames the step; following moves it only once a body nears the edge.
    for l in lesson::builtin().into_iter().flatten() {
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
}
