//! Frames that read right in depth, checked on pixels at projected points: what lies below the
//! floor shows only through the hole, the bowl under the hole is shaded, and a falling body's
//! shadow tells its height. Every colour is compared with the same renderer's picture of the
//! floor without the body, never with a hard-coded value.

use glam::DVec3;
use springlab::render::{Lattice, Projection, Quality, Renderer, Style, View, colour};
use springlab::scene::{self, Scene};
use springlab::simulation::Simulation;
use tiny_skia::Pixmap;

const W: u32 = 480;
const H: u32 = 360;

fn style(shadows: bool) -> Style {
    Style {
        overlay: false,
        shadows,
        quality: Quality::TEST,
        ..Style::default()
    }
}

/// The built-in `name` after `t` seconds of simulated time.
fn scene_at(name: &str, t: f64) -> Scene {
    let scene = scene::load(name, &[]).expect("built-in scene");
    let steps = (t / scene.dt).round() as u64;
    let mut sim = Simulation::new(scene);
    sim.run(steps, |_| {});
    assert!(sim.diverged.is_none(), "{name} diverged");
    assert!((sim.time() - t).abs() < 1e-9, "{}", sim.time());
    sim.scene
}

/// `scene` with every body moved 1 km down, below every floor: the picture of the terrain alone.
fn without_bodies(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for b in &mut s.bodies {
        for p in &mut b.state.x {
            p.y -= 1000.0;
        }
        for p in &mut b.state.x_prev {
            p.y -= 1000.0;
        }
        for sp in &mut b.state.spheres {
            sp.center.y -= 1000.0;
        }
    }
    s
}

fn renderer(scene: &Scene, shadows: bool) -> Renderer {
    Renderer::new(scene, W, H, Projection::default(), style(shadows)).expect("valid size")
}

fn rgb(p: &Pixmap, x: f32, y: f32) -> [f64; 3] {
    assert!(x >= 0.0 && y >= 0.0, "({x}, {y}) inside the image");
    let c = p
        .pixel(x.floor() as u32, y.floor() as u32)
        .expect("inside the image");
    [c.red(), c.green(), c.blue()].map(f64::from)
}

fn sum(c: [f64; 3]) -> f64 {
    c[0] + c[1] + c[2]
}

fn inside_image(x: f32, y: f32) -> bool {
    x >= 2.0 && y >= 2.0 && x < (W - 2) as f32 && y < (H - 2) as f32
}

/// The point where the ray through pixel `(x, y)` meets the plane `y = level` (m).
fn on_plane(view: &View, x: f64, y: f64, level: f64) -> DVec3 {
    let a = view.unproject(x, y, 1.0);
    let b = view.unproject(x, y, 2.0);
    let t = (level - a.y) / (b.y - a.y);
    a + t * (b - a)
}

/// Even-odd test of `(x, y)` against the polygon `poly`, and its distance to the outline (px).
fn inside_and_distance(poly: &[(f32, f32)], x: f32, y: f32) -> (bool, f32) {
    let mut inside = false;
    let mut dist = f32::INFINITY;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            inside = !inside;
        }
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let t = (((x - a.0) * dx + (y - a.1) * dy) / (dx * dx + dy * dy).max(1e-9)).clamp(0.0, 1.0);
        let (px, py) = (a.0 + t * dx - x, a.1 + t * dy - y);
        dist = dist.min((px * px + py * py).sqrt());
    }
    (inside, dist)
}

/// The 2023 terrain: the hole's centre and radius on the floor y = 0, the bowl's centre and
/// radius (`Collider::course_2023_terrain`).
fn terrain_2023() -> (DVec3, f64, DVec3, f64) {
    let a = 9.0 / 2f64.sqrt();
    (DVec3::new(2.0, 0.0, 1.0), a, DVec3::new(2.0, a, 1.0), 9.0)
}

#[test]
fn jelly_below_the_floor_shows_only_through_the_hole() {
    let scene = scene_at("jelly-bowl", 3.0);
    let (hole, a, _, _) = terrain_2023();
    let (w, h) = (960, 720);
    let mut checked = 0;
    // Low cameras, from which the floor in front of the hole hides the jelly's lower part.
    for (shadows, elevation) in [(false, 4.0), (true, 4.0), (false, 8.0), (true, 8.0)] {
        let mut r =
            Renderer::new(&scene, w, h, Projection::default(), style(shadows)).expect("valid size");
        r.camera.elevation = f64::to_radians(elevation);
        r.refit(&scene);
        let view = View::new(&r.camera, w, h);
        let frame = r.draw(&scene, None);
        let floor_only = r.draw(&without_bodies(&scene), None);
        let outline: Vec<(f32, f32)> = (0..360)
            .map(|k| {
                let phi = std::f64::consts::TAU * f64::from(k) / 360.0;
                let p = view
                    .project(hole + a * DVec3::new(phi.cos(), 0.0, phi.sin()))
                    .expect("in front");
                (p.x, p.y)
            })
            .collect();
        let x = &scene.bodies[0].state.x;
        let above: Vec<DVec3> = x.iter().copied().filter(|p| p.y > 0.0).collect();
        // Points of the jelly's outer faces: 4 × 4 in each cell.
        let faces = Lattice::detect(&scene.bodies[0].model).expect("a block");
        let mut surface = Vec::new();
        for q in faces.quads() {
            let [a, b, c, d] = q.map(|i| x[i as usize]);
            for i in 0..4 {
                for j in 0..4 {
                    let (u, v) = ((f64::from(i) + 0.5) / 4.0, (f64::from(j) + 0.5) / 4.0);
                    surface.push(a.lerp(b, u).lerp(d.lerp(c, u), v));
                }
            }
        }
        // The lattice spacing: 4 m over 9 cells.
        let cell = 4.0 / 9.0;
        for &p in surface.iter().filter(|p| p.y < -0.05) {
            let q = view.project(p).expect("in front");
            let (in_hole, d_hole) = inside_and_distance(&outline, q.x, q.y);
            if in_hole
                || d_hole < 3.0
                || !(2.0..(w - 2) as f32).contains(&q.x)
                || !(2.0..(h - 2) as f32).contains(&q.y)
            {
                continue;
            }
            // Where the ray to it crosses the floor, and whether the jelly's part above the
            // floor lies across the ray before that (within a cell of a particle).
            let s = on_plane(&view, f64::from(q.x), f64::from(q.y), 0.0);
            let covered = above.iter().any(|&c| {
                let d = (s - view.eye).normalize();
                let t = (c - view.eye).dot(d);
                t < (s - view.eye).length() && (view.eye + t * d - c).length() < cell
            });
            if covered {
                continue;
            }
            let (got, floor) = (rgb(&frame, q.x, q.y), rgb(&floor_only, q.x, q.y));
            if shadows {
                // The floor's colour, perhaps darkened by a shadow: the same hue.
                let k = sum(got) / sum(floor);
                assert!(
                    (0.45..=1.01).contains(&k)
                        && (0..3).all(|c| (got[c] - k * floor[c]).abs() <= 6.0),
                    "particle {p} at ({}, {}): {got:?}, floor {floor:?}",
                    q.x,
                    q.y
                );
            } else {
                assert!(
                    (0..3).all(|c| (got[c] - floor[c]).abs() <= 3.0),
                    "particle {p} at ({}, {}): {got:?}, floor {floor:?}",
                    q.x,
                    q.y
                );
            }
            checked += 1;
        }
    }
    assert!(
        checked >= 20,
        "only {checked} points of the jelly lie below the floor outside the hole on screen"
    );
}

#[test]
fn the_bowl_under_the_hole_is_shaded_not_flat() {
    let real = scene_at("jelly-bowl", 3.0);
    let scene = without_bodies(&real);
    let (hole, a, c, r) = terrain_2023();
    for shadows in [false, true] {
        // The camera of the real frame; the jelly itself moved out of the way.
        let ren = renderer(&real, shadows);
        let view = View::new(&ren.camera, W, H);
        let frame = ren.draw(&scene, None);
        let inside = colour::BOWL_INSIDE;
        let base = [inside.r, inside.g, inside.b].map(f64::from);
        let mut levels = std::collections::BTreeSet::new();
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for py in (0..H).step_by(3) {
            for px in (0..W).step_by(3) {
                let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
                // Seen through the hole, well inside its rim: the bowl's far wall, where the
                // ray leaves the bowl's sphere below the floor.
                let s = on_plane(&view, x, y, 0.0);
                if (s - hole).length() > a - 0.4 {
                    continue;
                }
                let d = (s - view.eye).normalize();
                let b = d.dot(s - c);
                let exit = s + (-b + (b * b - ((s - c).length_squared() - r * r)).sqrt()) * d;
                assert!(exit.y < 0.0);
                let got = rgb(&frame, px as f32, py as f32);
                let k = sum(got) / sum(base);
                assert!(
                    (0..3).all(|ch| (got[ch] - k * base[ch]).abs() <= 4.0),
                    "pixel ({px}, {py}) is not the bowl's inside: {got:?}"
                );
                levels.insert(sum(got) as u32 / 3);
                lo = lo.min(sum(got));
                hi = hi.max(sum(got));
            }
        }
        assert!(lo.is_finite(), "the hole is on screen");
        assert!(
            levels.len() >= 10 && hi / lo > 1.2,
            "a shading gradient: {} levels, brightest/darkest {}",
            levels.len(),
            hi / lo
        );
    }
}

/// Centroid of the `cube-plane` cube and the point of the plane y = -1 right under it.
fn under(scene: &Scene) -> (DVec3, DVec3) {
    let x = &scene.bodies[0].state.x;
    let c = x.iter().copied().sum::<DVec3>() / x.len() as f64;
    (c, DVec3::new(c.x, -1.0, c.z))
}

#[test]
fn the_floor_right_under_a_falling_cube_is_darker_than_beside_it() {
    let scene = scene_at("cube-plane", 0.5);
    let (c, u) = under(&scene);
    assert!(c.y > 6.0, "still falling, high above the plane: {c}");
    let lit = renderer(&scene, true);
    let plain = renderer(&scene, false);
    assert_eq!(lit.camera, plain.camera);
    let view = View::new(&lit.camera, W, H);
    let (s, n, empty) = (
        lit.draw(&scene, None),
        plain.draw(&scene, None),
        plain.draw(&without_bodies(&scene), None),
    );
    // Beside: 6 m towards the light along the floor, away from any shadow.
    let l = colour::LIGHT;
    let beside = u + 6.0 * DVec3::new(l.x, 0.0, l.z).normalize();
    let mut ratio = Vec::new();
    for p in [u, beside] {
        let q = view.project(p).expect("in front");
        assert!(inside_image(q.x, q.y), "{p} at ({}, {})", q.x, q.y);
        // Floor there, not the cube.
        assert_eq!(
            rgb(&n, q.x, q.y),
            rgb(&empty, q.x, q.y),
            "{p} shows the floor"
        );
        ratio.push(sum(rgb(&s, q.x, q.y)) / sum(rgb(&n, q.x, q.y)));
    }
    assert!(
        ratio[1] > 0.98,
        "beside the cube the floor is lit: {ratio:?}"
    );
    assert!(
        ratio[0] < ratio[1] - 0.03,
        "right under the cube the floor is darker: {ratio:?}"
    );
}

#[test]
fn a_falling_cube_s_shadow_closes_in_on_the_point_under_it() {
    // Shadow pixels: darker with shadows than without, where the floor shows. Their centroid,
    // taken back onto the plane, is the shadow's centre; its distance from the point under the
    // cube shrinks with the height, h tan θ for the sun's part (θ: the light's angle from the
    // vertical), on the side away from the light.
    let l = colour::LIGHT.normalize();
    let tan = (l.x * l.x + l.z * l.z).sqrt() / l.y;
    let mut offsets = Vec::new();
    for t in [0.25, 0.75, 1.25] {
        let scene = scene_at("cube-plane", t);
        let (c, u) = under(&scene);
        let lit = renderer(&scene, true);
        let plain = renderer(&scene, false);
        let view = View::new(&lit.camera, W, H);
        let (s, n, empty) = (
            lit.draw(&scene, None),
            plain.draw(&scene, None),
            plain.draw(&without_bodies(&scene), None),
        );
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for py in 0..H {
            for px in 0..W {
                let (x, y) = (px as f32, py as f32);
                let floor = rgb(&empty, x, y);
                let plain_px = rgb(&n, x, y);
                if plain_px != floor {
                    continue;
                }
                let d = sum(plain_px) - sum(rgb(&s, x, y));
                if d > 6.0 {
                    sx += d * (f64::from(px) + 0.5);
                    sy += d * (f64::from(py) + 0.5);
                    sw += d;
                }
            }
        }
        assert!(sw > 0.0, "a shadow at t = {t}");
        let w = on_plane(&view, sx / sw, sy / sw, -1.0);
        let offset = w - u;
        // Away from the light.
        assert!(
            offset.dot(l) < 0.0,
            "t = {t}: shadow at {w}, under the cube {u}"
        );
        let h = c.y + 1.0;
        offsets.push((t, offset.length(), h * tan));
    }
    for k in 1..offsets.len() {
        assert!(
            offsets[k].1 < offsets[k - 1].1 - 0.3,
            "the shadow's offset shrinks as the cube falls: (t, offset, h tan θ) = {offsets:?}"
        );
    }
    for &(t, got, sun) in &offsets {
        assert!(
            got <= 1.1 * sun,
            "t = {t}: offset {got} m, at most the sun's h tan θ = {sun} m"
        );
    }
}
