//! The renderer against golden images, and what frames must show whatever the goldens say.
//!
//! Golden images live in `tests/images/<area>/<name>.png` (320×240). A frame matches when at
//! most 0.05 % of its pixels differ from the golden by more than 3 levels in a channel.
//! `SPRINGLAB_BLESS=1 cargo test --release --test all render::` rewrites the goldens; a failing
//! comparison writes the new image to `target/render-test-output/` for a look.

#[path = "common/render_scenes.rs"]
mod render_scenes;

use std::path::{Path, PathBuf};

use springlab::render::chart::{self, Chart, Series, SeriesStyle};
use springlab::render::export::save_png;
use springlab::render::{
    Camera, Colouring, Overlay, Projection, Quality, Renderer, Style, scene_bounds,
};
use springlab::scene::{self, Scene};
use springlab::simulation::Simulation;
use tiny_skia::Pixmap;

const W: u32 = 320;
const H: u32 = 240;

/// Largest channel difference that counts as equal.
const LEVELS: u8 = 3;
/// Share of pixels allowed to differ by more than [`LEVELS`].
const SHARE: f64 = 0.0005;

fn golden_path(area: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/images")
        .join(area)
        .join(format!("{name}.png"))
}

/// Compares `pixmap` with the golden `area/name`, or writes it when `SPRINGLAB_BLESS` is set.
fn check_golden(area: &str, name: &str, pixmap: &Pixmap) {
    let path = golden_path(area, name);
    if std::env::var_os("SPRINGLAB_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("golden dir");
        save_png(pixmap, &path).expect("write golden");
        return;
    }
    let golden = Pixmap::load_png(&path).unwrap_or_else(|e| {
        panic!(
            "cannot read golden {}: {e}; run with SPRINGLAB_BLESS=1 to create it",
            path.display()
        )
    });
    assert_eq!(
        (golden.width(), golden.height()),
        (pixmap.width(), pixmap.height()),
        "size of {area}/{name}"
    );
    let differing = golden
        .pixels()
        .iter()
        .zip(pixmap.pixels())
        .filter(|(a, b)| {
            let d = |x: u8, y: u8| x.abs_diff(y) > LEVELS;
            d(a.red(), b.red())
                || d(a.green(), b.green())
                || d(a.blue(), b.blue())
                || d(a.alpha(), b.alpha())
        })
        .count();
    let allowed = (SHARE * f64::from(W * H)).floor() as usize;
    if differing > allowed {
        let out = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("target/render-test-output")
            .join(area);
        std::fs::create_dir_all(&out).expect("output dir");
        let actual = out.join(format!("{name}.png"));
        save_png(pixmap, &actual).expect("write actual");
        panic!(
            "{area}/{name}: {differing} pixels differ by more than {LEVELS} levels (allowed {allowed}); \
             this run's image is {}",
            actual.display()
        );
    }
}

fn test_style() -> Style {
    Style {
        quality: Quality::TEST,
        ..Style::default()
    }
}

fn renderer(scene: &Scene, style: Style) -> Renderer {
    Renderer::new(scene, W, H, Projection::default(), style).expect("valid size")
}

fn draw_after(scene: Scene, steps: u64, style: Style) -> Pixmap {
    let r = renderer(&scene, style);
    let mut sim = Simulation::new(scene);
    sim.run(steps, |_| {});
    assert!(sim.diverged.is_none());
    r.draw_simulation(&sim)
}

#[test]
fn golden_rope() {
    let scene = scene::load("rope", &["nodes=8".into()]).expect("rope");
    check_golden("scene", "rope", &draw_after(scene, 40, test_style()));
}

#[test]
fn golden_rope_by_strain() {
    let scene = scene::load("rope", &["nodes=8".into()]).expect("rope");
    let style = Style {
        colouring: Colouring::ByStrain { max_strain: 0.05 },
        ..test_style()
    };
    check_golden("scene", "rope_strain", &draw_after(scene, 40, style));
}

#[test]
fn golden_jelly_in_bowl() {
    let scene = render_scenes::jelly_in_bowl();
    check_golden("scene", "jelly", &draw_after(scene, 0, test_style()));
}

#[test]
fn golden_jelly_springs_by_kind() {
    let style = Style {
        jelly_surface: false,
        ..test_style()
    };
    check_golden(
        "scene",
        "jelly_springs",
        &draw_after(render_scenes::sheared_cube(), 0, style),
    );
}

#[test]
fn golden_cloth_over_sphere() {
    check_golden(
        "scene",
        "cloth",
        &draw_after(render_scenes::draped_cloth(), 0, test_style()),
    );
}

#[test]
fn golden_orthographic_cloth_spheres() {
    let scene = render_scenes::cloth_spheres();
    let r = Renderer::new(
        &scene,
        W,
        H,
        Projection::Orthographic { height: 1.0 },
        test_style(),
    )
    .expect("valid size");
    let overlay = Overlay {
        scene: "cloth-spheres-like".into(),
        method: "semi-implicit-euler".into(),
        dt: 1e-4,
        time: 0.0,
        energy: 0.0,
    };
    check_golden(
        "scene",
        "cloth_spheres_ortho",
        &r.draw(&scene, Some(&overlay)),
    );
}

fn sample_chart() -> Chart {
    // A convergence plot: error ∝ dt^p for p = 1, 2, 4, with markers, on log-log axes.
    let dts: Vec<f64> = (0..6).map(|k| 0.1 / 2f64.powi(k)).collect();
    let line = |p: i32, c: f64| dts.iter().map(|&dt| (dt, c * dt.powi(p))).collect();
    Chart::new(
        "Convergence on the oscillator",
        "time step dt (s)",
        "error |x - x_exact| (m)",
    )
    .log_log()
    .with(Series::line("explicit Euler", line(1, 0.5)).with_style(SeriesStyle::LineAndPoints))
    .with(Series::line("midpoint", line(2, 0.3)).with_style(SeriesStyle::LineAndPoints))
    .with(Series::scatter("RK4", line(4, 0.2)))
}

#[test]
fn golden_log_log_chart() {
    check_golden(
        "chart",
        "convergence",
        &chart::draw_with(&sample_chart(), W, H, Quality::TEST),
    );
}

#[test]
fn golden_energy_chart() {
    // Energies of the oscillator: kinetic and elastic exchange, the total stays.
    let points = |f: fn(f64) -> f64| {
        (0..=200)
            .map(|k| (k as f64 * 0.01, f(k as f64 * 0.01)))
            .collect()
    };
    let chart = Chart::new("Energy: oscillator", "time t (s)", "energy E (J)")
        .with(Series::line(
            "kinetic",
            points(|t| 0.5 * (10.0 * t).sin().powi(2)),
        ))
        .with(Series::line(
            "elastic",
            points(|t| 0.5 * (10.0 * t).cos().powi(2)),
        ))
        .with(Series::line("total", points(|_| 0.5)));
    check_golden(
        "chart",
        "energy",
        &chart::draw_with(&chart, W, H, Quality::TEST),
    );
}

#[test]
fn two_renders_of_the_same_scene_are_identical() {
    let scene = render_scenes::jelly_in_bowl();
    let a = renderer(&scene, Style::default()).draw(&scene, None);
    let b = renderer(&scene.clone(), Style::default()).draw(&scene, None);
    assert!(a.data() == b.data(), "same pixels");
    let chart_a = chart::draw(&sample_chart(), W, H);
    let chart_b = chart::draw(&sample_chart(), W, H);
    assert!(chart_a.data() == chart_b.data());
}

/// Mean row of the pixels that are clearly the jelly's red (none: `None`).
fn red_centroid_row(p: &Pixmap) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, c) in p.pixels().iter().enumerate() {
        let (r, g, b) = (
            i32::from(c.red()),
            i32::from(c.green()),
            i32::from(c.blue()),
        );
        if r > g + 60 && r > b + 60 {
            sum += (i / p.width() as usize) as f64;
            n += 1;
        }
    }
    (n > 50).then(|| sum / n as f64)
}

#[test]
fn frames_show_the_jelly_falling() {
    let scene = render_scenes::jelly_bowl_sized(4);
    let r = renderer(&scene, Style::default());
    let mut sim = Simulation::new(scene);
    let mut rows = Vec::new();
    for _ in 0..4 {
        rows.push(red_centroid_row(&r.draw_simulation(&sim)).expect("the jelly is in view"));
        sim.run(250, |_| {});
    }
    // Free fall from rest: the jelly drops 0, 0.31, 1.2, 2.8 m at t = 0, 0.25, 0.5, 0.75 s.
    for w in rows.windows(2) {
        assert!(
            w[1] > w[0] + 1.0,
            "the jelly moves down the image: {rows:?}"
        );
    }
}

#[test]
fn cloth_is_drawn_as_a_shaded_surface() {
    let scene = render_scenes::draped_cloth();
    let p = renderer(&scene, Style::default()).draw(&scene, None);
    // Blue cloth pixels in many shades: Lambert shading varies over the drape.
    let mut shades = std::collections::BTreeSet::new();
    let mut blue = 0;
    for c in p.pixels() {
        if i32::from(c.blue()) > i32::from(c.red()) + 60 {
            blue += 1;
            shades.insert(c.blue() / 4);
        }
    }
    assert!(
        blue > 3000,
        "the cloth covers a good part of the image ({blue} px)"
    );
    assert!(
        shades.len() > 15,
        "shaded, not flat: {} shades",
        shades.len()
    );
}

#[test]
fn default_camera_frames_everything() {
    for scene in [
        render_scenes::jelly_bowl(),
        render_scenes::cloth_spheres(),
        render_scenes::draped_cloth(),
        scene::load("ropes", &[]).expect("ropes"),
    ] {
        for (w, h) in [(320u32, 240u32), (240, 320), (640, 200)] {
            let cam = Camera::for_scene(&scene, f64::from(w) / f64::from(h), Projection::default());
            let view = springlab::render::View::new(&cam, w, h);
            for c in scene_bounds(&scene).corners() {
                let p = view.project(c).expect("in front of the camera");
                assert!(
                    (0.0..=w as f32).contains(&p.x) && (0.0..=h as f32).contains(&p.y),
                    "{} corner {c} at ({}, {}) in {w}x{h}",
                    scene.name,
                    p.x,
                    p.y
                );
            }
        }
    }
}

#[test]
fn bad_sizes_are_errors() {
    let scene = render_scenes::draped_cloth();
    for (w, h) in [(0, 10), (10, 0), (8193, 10), (10, 9000)] {
        let e = Renderer::new(&scene, w, h, Projection::default(), Style::default())
            .expect_err("out of range");
        assert!(e.to_string().contains("1 to 8192 pixels"), "{e}");
        assert!(chart::try_draw(&sample_chart(), w, h).is_err());
    }
}
