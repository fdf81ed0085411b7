//! The course scenes (`cube-plane`, `cube-tilted`, `cube-sphere`, `cube-bowl`, `jelly-bowl`,
//! `cloth-spheres`, `cloth-sphere`) against independent truths: the geometry of the terrains
//! (nothing ends a step inside a collider, and everything lands where the terrain holds it),
//! free fall before the first contact, known lattice counts, energy that collisions never add,
//! and the stability of the methods at the course's and at larger time steps.
//!
//! Run in release mode (`cargo test --release`): the cube has 1000 particles and 12 876 springs.

use std::f64::consts::SQRT_2;
use std::process::Command;

use glam::DVec3;
use springlab::physics::collide::Collider;
use springlab::physics::{Method, SpringKind};
use springlab::scene::{self, Scene};
use springlab::simulation::Simulation;

mod big_steps;

/// The seven course scenes.
const SCENES: [&str; 7] = [
    "cube-plane",
    "cube-tilted",
    "cube-sphere",
    "cube-bowl",
    "jelly-bowl",
    "cloth-spheres",
    "cloth-sphere",
];

/// How far inside a collider a particle may be at the end of a step (m): rounding only.
const INSIDE_TOLERANCE: f64 = 1e-9;

const G: f64 = 9.8;

fn strings(sets: &[&str]) -> Vec<String> {
    sets.iter().map(|s| s.to_string()).collect()
}

fn load(name: &str, sets: &[&str]) -> Scene {
    scene::load(name, &strings(sets)).unwrap_or_else(|e| panic!("{name} {sets:?}: {e}"))
}

/// A simulation of `name` with `sets`, `method` and `dt` (the scene's when `None`).
fn simulation(name: &str, sets: &[&str], method: Option<Method>, dt: Option<f64>) -> Simulation {
    let mut scene = load(name, sets);
    if let Some(m) = method {
        scene.set_method(m);
    }
    let mut sim = Simulation::new(scene);
    if let Some(dt) = dt {
        sim.set_dt(dt);
    }
    sim
}

fn steps_for(sim: &Simulation, time: f64) -> u64 {
    (time / sim.dt()).round() as u64
}

/// The most negative signed distance of any particle to any collider of its body (m), with the
/// particle; `+∞` when nothing is near a collider.
fn deepest(sim: &Simulation) -> (f64, DVec3) {
    let mut worst = (f64::INFINITY, DVec3::ZERO);
    for body in &sim.scene.bodies {
        for &x in &body.state.x {
            for c in &body.model.colliders {
                if let Some(contact) = c.contact(x)
                    && contact.phi < worst.0
                {
                    worst = (contact.phi, x);
                }
            }
        }
    }
    worst
}

/// Runs `steps` steps; after each one asserts that the run has not diverged and that no particle
/// is inside a collider, then calls `each`.
fn run_outside(sim: &mut Simulation, steps: u64, mut each: impl FnMut(&Simulation)) {
    for _ in 0..steps {
        sim.step();
        let label = format!(
            "{} under {} at t = {:.3} s",
            sim.scene.name,
            sim.scene.method_label(),
            sim.time()
        );
        assert!(sim.diverged.is_none(), "{label}: {:?}", sim.diverged);
        let (phi, x) = deepest(sim);
        assert!(
            phi >= -INSIDE_TOLERANCE,
            "{label}: particle at {x} is {phi} m inside a collider"
        );
        each(sim);
    }
}

fn centroid(sim: &Simulation) -> DVec3 {
    let (sum, n) = sim
        .positions()
        .fold((DVec3::ZERO, 0.0), |(s, n), x| (s + x, n + 1.0));
    sum / n
}

fn min_y(sim: &Simulation) -> f64 {
    sim.positions().map(|x| x.y).fold(f64::INFINITY, f64::min)
}

/// Horizontal distance (m) of `x` from the vertical axis through `(axis_x, ·, axis_z)`.
fn from_axis(x: DVec3, axis_x: f64, axis_z: f64) -> f64 {
    (x.x - axis_x).hypot(x.z - axis_z)
}

// ------------------------------------------------------------------ building the scenes

#[test]
fn every_scene_is_listed_builds_with_course_values_and_counts() {
    for name in SCENES {
        let def = scene::builtin(name).unwrap_or_else(|| panic!("{name} is not built in"));
        assert!(!def.summary.is_empty());
        let s = load(name, &[]);
        assert_eq!(s.name, name);
        assert_eq!(s.bodies.len(), 1, "{name}");
        assert_eq!(s.bodies[0].method, Method::SemiImplicitEuler, "{name}");
    }
    // Cube and jelly: 10³ particles of 1 kg, 2700 struct + 7776 shear + 2400 bend springs, all
    // K = 2000 N/m, D = 60 N·s/m, dt = 1 ms, corner at offset + (0, L, 0), edge 4 m.
    for (name, corner, friction) in [
        ("cube-plane", DVec3::new(0.0, 9.0, 0.0), 0.3),
        ("cube-tilted", DVec3::new(0.0, 9.0, 0.0), 0.3),
        ("cube-sphere", DVec3::new(0.0, 9.0, 0.0), 0.3),
        ("cube-bowl", DVec3::new(0.0, 9.0, 0.0), 0.3),
        ("jelly-bowl", DVec3::new(-4.8, 11.0, 0.0), 0.2),
    ] {
        let s = load(name, &[]);
        assert_eq!((s.particle_count(), s.spring_count()), (1000, 12_876));
        assert_eq!(s.dt, 0.001);
        let b = &s.bodies[0];
        assert!(b.model.mass.iter().all(|&m| m == 1.0));
        assert!(b.model.inv_mass.iter().all(|&w| w == 1.0), "nothing pinned");
        assert!(
            b.model
                .springs()
                .iter()
                .all(|s| (s.stiffness, s.damping) == (2000.0, 60.0))
        );
        assert_eq!(b.model.gravity, DVec3::new(0.0, -G, 0.0));
        assert_eq!(b.model.drag, 0.0);
        assert_eq!(b.state.x[0], corner, "{name}");
        assert!((b.state.x[999] - corner - DVec3::splat(4.0)).length() < 1e-12);
        assert_eq!(b.model.contact.restitution, 0.8);
        assert_eq!(b.model.contact.friction, friction);
        assert_eq!(b.model.contact.epsilon, 0.01);
        assert!(b.state.spheres.is_empty());
    }
    // Only the terrain of each scene.
    let colliders = |name| load(name, &[]).bodies[0].model.colliders.clone();
    assert_eq!(colliders("cube-plane"), vec![Collider::course_2021_plane()]);
    // (Model::with_colliders normalises the normal again, which may change its last bit.)
    assert_eq!(
        colliders("cube-tilted"),
        vec![Collider::course_2021_tilted_plane().normalized()]
    );
    assert_eq!(
        colliders("cube-sphere"),
        vec![Collider::course_2021_sphere()]
    );
    assert_eq!(colliders("cube-bowl"), vec![Collider::course_2021_bowl()]);
    let terrain: Vec<Collider> = Collider::course_2023_terrain()
        .into_iter()
        .map(Collider::normalized)
        .collect();
    assert_eq!(colliders("jelly-bowl"), terrain);

    // Cloth: 25² particles, 1200 + 1152 + 1150 springs, corners pinned, no static collider.
    for (name, height, k, spheres) in [
        ("cloth-spheres", 0.0, 25_000.0, 4),
        ("cloth-sphere", 1.0, 20_000.0, 1),
    ] {
        let s = load(name, &[]);
        assert_eq!((s.particle_count(), s.spring_count()), (625, 3502));
        assert_eq!(s.dt, 1e-4);
        let b = &s.bodies[0];
        assert!(b.model.colliders.is_empty());
        assert_eq!(b.model.drag, 3.4e-4);
        assert!(
            b.model
                .springs()
                .iter()
                .all(|s| (s.stiffness, s.damping) == (k, 750.0))
        );
        let pinned: Vec<usize> = (0..625).filter(|&i| b.model.is_pinned(i)).collect();
        assert_eq!(pinned, vec![0, 24, 600, 624]);
        assert!(b.state.x.iter().all(|x| x.y == height));
        assert_eq!(b.state.x[0], DVec3::new(-2.0, height, -2.0));
        assert_eq!(b.state.x[624], DVec3::new(2.0, height, 2.0));
        assert_eq!(b.state.spheres.len(), spheres);
        assert_eq!(b.model.contact.sphere_particle_restitution, 0.0);
        assert_eq!(b.model.contact.sphere_sphere_restitution, 0.8);
    }
    let s = load("cloth-spheres", &[]);
    for sphere in &s.bodies[0].state.spheres {
        assert_eq!(sphere.radius, 0.5);
        assert_eq!(sphere.mass, 125.0);
        assert!(!sphere.kinematic);
        assert_eq!(sphere.center.y, 1.0);
        assert_eq!(sphere.center.x.abs(), 0.75);
        assert_eq!(sphere.center.z.abs(), 0.75);
    }
    let s = load("cloth-sphere", &[]);
    let sphere = s.bodies[0].state.spheres[0];
    assert!(sphere.kinematic);
    assert_eq!((sphere.center, sphere.radius), (DVec3::ZERO, 1.0));
    assert_eq!(sphere.velocity, DVec3::ZERO);
}

#[test]
fn overrides_change_what_they_name() {
    // Three cubes of 4³, rotated, with per-kind coefficients; bend springs dropped.
    let s = load(
        "cube-bowl",
        &[
            "bodies=3",
            "n=4",
            "edge=2",
            "mass=0.5",
            "stiffness=1500",
            "struct_damping=5",
            "shear_stiffness=800",
            "bend_stiffness=0",
            "bend_damping=0",
            "rotation=30",
            "friction=0.5",
            "restitution=0.25",
            "gravity=1.62",
            "offset=[1,8,1]",
        ],
    );
    assert_eq!(s.bodies.len(), 3);
    assert_eq!(s.method_label(), "semi-implicit-euler");
    for (i, b) in s.bodies.iter().enumerate() {
        assert_eq!(b.model.particle_count(), 64);
        // n = 4: struct 3·3·16 = 144, shear 2·9·4·3 + 4·27 = 324, no bend.
        let kinds = |k| b.model.springs().iter().filter(|s| s.kind == k).count();
        assert_eq!(
            [SpringKind::Struct, SpringKind::Shear, SpringKind::Bend].map(kinds),
            [144, 324, 0]
        );
        for s in b.model.springs() {
            let expected = match s.kind {
                SpringKind::Struct => (1500.0, 5.0),
                SpringKind::Shear => (800.0, 60.0),
                SpringKind::Bend => unreachable!(),
            };
            assert_eq!((s.stiffness, s.damping), expected);
        }
        assert!(b.model.mass.iter().all(|&m| m == 0.5));
        assert_eq!(b.model.gravity.y, -1.62);
        assert_eq!(
            (b.model.contact.friction, b.model.contact.restitution),
            (0.5, 0.25)
        );
        // Centre of body i: offset + (0, L, -2 L i) + L/2, L = 2; the rotation keeps it.
        let c = b.state.centroid();
        let expected = DVec3::new(2.0, 11.0, 2.0 - 4.0 * i as f64);
        assert!((c - expected).length() < 1e-12, "body {i}: {c}");
        // Rotated by 30° about (1, 0, 1): the edge 0 → 3 (along x) is no longer along x and
        // keeps its length; its angle to x is 30° rotated about an axis 45° off x.
        let edge = b.state.x[3] - b.state.x[0];
        assert!((edge.length() - 2.0).abs() < 1e-12);
        let axis = DVec3::new(1.0, 0.0, 1.0) / SQRT_2;
        let expected = glam::DQuat::from_axis_angle(axis, 30f64.to_radians()) * DVec3::X * 2.0;
        assert!((edge - expected).length() < 1e-12);
    }
    // Method names: one when they agree, a list when they differ.
    let mut s = load("cube-plane", &["bodies=2", "n=2"]);
    s.bodies[1].method = Method::Rk4;
    assert_eq!(s.method_label(), "semi-implicit-euler,rk4");

    // Cloth: size, pins by corner key, coefficients, the sphere's velocity and radius.
    let s = load(
        "cloth-sphere",
        &[
            "n=9",
            "pinned=[1, 4]",
            "stiffness=1000",
            "sphere_velocity=[0,0,5]",
            "sphere_radius=0.5",
            "drag=0",
        ],
    );
    let b = &s.bodies[0];
    let pinned: Vec<usize> = (0..81).filter(|&i| b.model.is_pinned(i)).collect();
    assert_eq!(pinned, vec![0, 80]);
    assert_eq!(s.spring_count(), 2 * 9 * 8 + 2 * 64 + 2 * 9 * 7);
    assert!(b.model.springs().iter().all(|s| s.stiffness == 1000.0));
    assert_eq!(b.state.spheres[0].velocity, DVec3::new(0.0, 0.0, 5.0));
    assert_eq!(b.state.spheres[0].radius, 0.5);
    let s = load("cloth-sphere", &["pinned=[]"]);
    assert!(!(0..625).any(|i| s.bodies[0].model.is_pinned(i)));
    let s = load(
        "cloth-spheres",
        &["pinned=[2,3]", "n=3", "sphere_radius=0.25"],
    );
    let b = &s.bodies[0];
    let pinned: Vec<usize> = (0..9).filter(|&i| b.model.is_pinned(i)).collect();
    assert_eq!(pinned, vec![2, 6]);
    assert!(
        b.state
            .spheres
            .iter()
            .all(|s| s.mass == 1000.0 * 0.25f64.powi(3))
    );
}

#[test]
fn bad_settings_give_their_messages() {
    let cases: [(&str, &str, &str); 12] = [
        (
            "cube-plane",
            "bodies=0",
            "`bodies` = 0 is out of range: allowed 1 ..= 10",
        ),
        (
            "cube-bowl",
            "n=1",
            "`n` = 1 is out of range: allowed 2 ..= 40",
        ),
        ("jelly-bowl", "n=41", "`n` = 41 is out of range"),
        (
            "cube-tilted",
            "friction=-1",
            "`friction` = -1 is out of range: allowed 0 ..= 10",
        ),
        (
            "cube-sphere",
            "restitution=1.5",
            "`restitution` = 1.5 is out of range: allowed 0 ..= 1",
        ),
        (
            "cube-plane",
            "edge=0",
            "`edge` = 0 is out of range: allowed 1e-6 ..= 1e6 (m)",
        ),
        (
            "cube-plane",
            "struct_stiffness=-2",
            "`struct_stiffness` = -2 is out of range: allowed -1 ..= 1e9 (N/m)",
        ),
        (
            "cube-plane",
            "rotation=abc",
            "`rotation` = abc: expected a number",
        ),
        (
            "cloth-sphere",
            "pinned=[0]",
            "`pinned` = 0 is out of range: allowed 1 ..= 4",
        ),
        (
            "cloth-sphere",
            "sphere_velocity=[1,2]",
            "`sphere_velocity` = [1,2]: expected a vector [x, y, z]",
        ),
        (
            "cloth-spheres",
            "sphere_radius=0",
            "`sphere_radius` = 0 is out of range: allowed 1e-6 ..= 1e6 (m)",
        ),
        (
            "cloth-spheres",
            "spheres=3",
            "unknown parameter `spheres` for scene `cloth-spheres`; known parameters: n, mass",
        ),
    ];
    for (name, set, message) in cases {
        match scene::load(name, &strings(&[set])) {
            Ok(_) => panic!("{name} --set {set} was accepted"),
            Err(e) => {
                let text = e.to_string();
                assert!(text.contains(message), "{name} {set}: got `{text}`");
            }
        }
    }
    // Through the binary: one line on stderr, exit code 1.
    let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(["run", "jelly-bowl", "--set", "bodies=0"])
        .output()
        .expect("run springlab");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("springlab: ") && err.contains("`bodies` = 0 is out of range"),
        "{err}"
    );
}

#[test]
fn scene_file_form_names_a_course_scene() {
    let text = "scene = \"jelly-bowl\"\n\n[params]\nn = 4\nfriction = 0.25\n\n[run]\nmethod = \"rk4\"\ndt = 0.002\n";
    let s = scene::file::from_str(
        text,
        std::path::Path::new("jelly.toml"),
        &strings(&["bodies=2"]),
    )
    .expect("loads");
    assert_eq!(s.particle_count(), 128);
    assert_eq!(s.bodies[0].method, Method::Rk4);
    assert_eq!(s.dt, 0.002);
    assert_eq!(s.bodies[1].model.contact.friction, 0.25);
    assert_eq!(s.bodies[0].model.colliders.len(), 2);
    // The example files are the built-in scenes with their [params].
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for file in [
        "jelly_bowl.toml",
        "cubes_tilted.toml",
        "cloth_spheres_implicit.toml",
        "cloth_sphere_moving.toml",
    ] {
        let path = dir.join(file);
        let s = scene::load(path.to_str().expect("utf-8"), &[])
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(s.particle_count() > 0);
    }
}

#[test]
fn every_scene_runs_a_few_steps_under_every_method() {
    for name in SCENES {
        for method in Method::ALL {
            // Small lattices keep this quick (two cubes, to run several bodies); the course sizes
            // run in the other tests.
            let sets: &[&str] = if name.starts_with("cloth") {
                &["n=7"]
            } else {
                &["n=4", "bodies=2"]
            };
            let mut sim = simulation(name, sets, Some(method), None);
            sim.run(20, |_| {});
            assert!(sim.diverged.is_none(), "{name} {method}");
            assert_eq!(sim.steps, 20);
            let report = sim.report(0.0);
            let json = serde_json::to_value(&report).expect("json");
            assert_eq!(json["method"], method.name());
            // Only scenes with dynamic spheres carry the key.
            assert_eq!(
                json.get("spheres").is_some(),
                name.starts_with("cloth"),
                "{name}"
            );
        }
    }
}

// ------------------------------------------------------------------ the 2021 cube

#[test]
fn cube_plane_falls_freely_then_rests_on_the_plane() {
    let mut sim = simulation("cube-plane", &[], None, None);
    // The bottom face (y = 9) reaches the plane y = -1 after t = √(2 · 10 / g).
    let landing = (2.0 * 10.0 / G).sqrt();
    let mut first_contact = None;
    run_outside(&mut sim, 4000, |s| {
        let t = s.time();
        if t <= 1.0 {
            // Free fall: y_c = 11 - g t²/2, to semi-implicit Euler's O(dt) error g t dt/2.
            let y = 11.0 - 0.5 * G * t * t;
            assert!((centroid(s).y - y).abs() < G * t * s.dt(), "t = {t}");
        }
        if first_contact.is_none() && min_y(s) < -1.0 + 0.01 {
            first_contact = Some(t);
        }
    });
    let t = first_contact.expect("the cube reached the plane");
    assert!(
        (t - landing).abs() < 0.01,
        "contact at {t} s, expected {landing}"
    );
    // It bounces once (k_r = 0.8) and is at rest on the plane after 4 s: nothing below it,
    // centroid half an edge above it (less the sag of a soft cube), no motion left.
    assert!(min_y(&sim) >= -1.0 - INSIDE_TOLERANCE);
    let c = centroid(&sim);
    assert!((c.y - 1.0).abs() < 0.1, "{c}");
    assert!((c.x - 2.0).abs() < 1e-6 && (c.z - 2.0).abs() < 1e-6, "{c}");
    let e = sim.energy();
    assert!(e.kinetic < 0.1, "{e:?}");
}

#[test]
fn collisions_never_add_energy_to_the_undamped_cube() {
    // No dampers: springs, gravity and contact only, so any energy the run gains would come from
    // the collision response. Semi-implicit Euler's own energy error is bounded and small; the
    // bounces (k_r = 0.8) and friction remove energy.
    let mut sim = simulation("cube-plane", &["damping=0", "n=6"], None, None);
    let initial = sim.energy().total;
    let mut highest = initial;
    run_outside(&mut sim, 3000, |s| highest = highest.max(s.energy().total));
    let end = sim.energy().total;
    assert!(
        highest <= initial * (1.0 + 1e-6),
        "energy rose from {initial} J to {highest} J"
    );
    // The impact took away a lot: at least 1 - 0.8² of the kinetic energy at impact, part of it
    // stored in the springs' vibration.
    assert!(end < initial, "{end} >= {initial}");
    let impact = 216.0 * G * 10.0;
    assert!(
        initial - end > 0.2 * impact,
        "lost only {} J",
        initial - end
    );
}

#[test]
fn cube_tilted_tips_over_and_slides_down_the_slope() {
    let mut sim = simulation("cube-tilted", &[], None, None);
    let edge = |s: &Simulation| s.scene.bodies[0].state.x[9] - s.scene.bodies[0].state.x[0];
    // Until the first contact (the uphill bottom edge, 9/√2 m above the slope) nothing turns.
    let normal = DVec3::new(1.0, 1.0, 0.0) / SQRT_2;
    let mut touched = false;
    let mut after_landing = None;
    run_outside(&mut sim, 2600, |s| {
        let phi_min = s
            .positions()
            .map(|x| x.dot(normal))
            .fold(f64::INFINITY, f64::min);
        if phi_min < 0.01 {
            touched = true;
        }
        if !touched {
            assert!((edge(s) - DVec3::new(4.0, 0.0, 0.0)).length() < 1e-9);
        }
        if touched && after_landing.is_none() && s.time() >= 1.6 {
            after_landing = Some((centroid(s), edge(s)));
        }
    });
    assert!(touched);
    let (c0, e0) = after_landing.expect("ran past 1.6 s");
    let (c1, e1) = (centroid(&sim), edge(&sim));
    // Down the slope: along (1, -1, 0)/√2, not across it (z stays by symmetry).
    let downhill = DVec3::new(1.0, -1.0, 0.0) / SQRT_2;
    let moved = c1 - c0;
    assert!(moved.length() > 3.0, "moved {moved}");
    assert!(moved.normalize().dot(downhill) > 0.95, "moved {moved}");
    assert!((c1.z - 2.0).abs() < 1e-6);
    // It stays on the slope: its centroid no lower than a half-diagonal of a face above it.
    assert!(c1.dot(normal) > 1.0, "{c1}");
    // And it turned: about z, by more than 30° since landing, and more than 30° since the start.
    let angle = |a: DVec3, b: DVec3| a.angle_between(b).to_degrees();
    assert!(angle(e0, e1) > 30.0, "{e0} → {e1}");
    assert!(angle(DVec3::X, e1) > 30.0, "{e1}");
    assert!(e1.z.abs() < 0.1);
}

#[test]
fn cube_sphere_lands_on_the_ball_and_slides_off() {
    let mut sim = simulation("cube-sphere", &[], None, None);
    let ball = DVec3::new(0.0, -1.0, 0.0);
    let mut closest = f64::INFINITY;
    run_outside(&mut sim, 2500, |s| {
        for x in s.positions() {
            closest = closest.min((x - ball).length() - 3.0);
        }
    });
    assert!(
        closest < 0.01,
        "the cube never touched the ball ({closest} m)"
    );
    // Off-centre landing: it leaves towards +x, +z, symmetrically in x and z. The slide off the
    // top of a ball is an unstable motion that grows any difference between the two halves: the
    // energy budget of the contacts sums each particle's springs in the particle's own order, and
    // those rounding-level (1e-16 J) differences between mirror particles grow to a few 1e-4 m
    // over the slide; 1 mm (1e-4 of the 7 m travelled) still tells a symmetric slide from a
    // lopsided one.
    let c = centroid(&sim);
    assert!(c.x > 3.0 && (c.x - c.z).abs() < 1e-3, "{c}");
}

#[test]
fn cube_bowl_catches_the_cube() {
    let mut sim = simulation("cube-bowl", &[], None, None);
    let (center, radius) = (DVec3::new(2.0, 7.0, 1.0), 7.0);
    run_outside(&mut sim, 3000, |_| {});
    // Everything is in the bowl: below the rim and within its radius of the centre.
    for x in sim.positions() {
        assert!(x.y < 7.0, "{x} above the rim");
        assert!((x - center).length() <= radius + INSIDE_TOLERANCE, "{x}");
    }
    let c = centroid(&sim);
    assert!(from_axis(c, 2.0, 1.0) < 3.0, "{c}");
    assert!(c.y < 4.0, "{c}");
    assert!(min_y(&sim) > -INSIDE_TOLERANCE, "below the bowl's bottom");
}

// ------------------------------------------------------------------ the 2023 jelly

/// Where the 2023 terrain holds the jelly: under the floor only inside the hole, and there
/// within the bowl.
fn assert_in_2023_terrain(label: &str, positions: impl Iterator<Item = DVec3>) {
    let hole = 9.0 / SQRT_2;
    let bowl = DVec3::new(2.0, hole, 1.0);
    for x in positions {
        if x.y < 0.0 {
            assert!(
                from_axis(x, 2.0, 1.0) <= hole + 1e-9,
                "{label}: {x} under the floor outside the hole"
            );
            assert!(
                (x - bowl).length() <= 9.0 + 1e-9,
                "{label}: {x} outside the bowl"
            );
        }
    }
}

#[test]
fn jelly_bowl_rk4_json_ends_in_the_bowl() {
    let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args([
            "run",
            "jelly-bowl",
            "--method",
            "rk4",
            "--dt",
            "0.001",
            "--time",
            "5",
            "--json",
        ])
        .output()
        .expect("run springlab");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert!(v["diverged"].is_null(), "{}", v["diverged"]);
    assert_eq!(
        (v["steps"].as_u64(), v["particles"].as_u64()),
        (Some(5000), Some(1000))
    );
    assert!(v.get("spheres").is_none(), "no spheres in the jelly scene");
    let positions: Vec<DVec3> = v["positions"]
        .as_array()
        .expect("positions")
        .iter()
        .map(|p| {
            let c: Vec<f64> = p
                .as_array()
                .expect("[x, y, z]")
                .iter()
                .map(|c| c.as_f64().expect("number"))
                .collect();
            DVec3::new(c[0], c[1], c[2])
        })
        .collect();
    assert_in_2023_terrain("rk4", positions.iter().copied());
    for x in &positions {
        let phi: f64 = Collider::course_2023_terrain()
            .iter()
            .filter_map(|c| c.contact(*x).map(|c| c.phi))
            .fold(f64::INFINITY, f64::min);
        assert!(phi >= -1e-9, "{x} inside the terrain by {phi}");
    }
    // The jelly fell through the hole: its centroid is in the bowl, over the hole, and far
    // below where it started (y = 13).
    let c = positions.iter().sum::<DVec3>() / positions.len() as f64;
    let bowl = DVec3::new(2.0, 9.0 / SQRT_2, 1.0);
    assert!((c - bowl).length() < 9.0, "{c}");
    assert!(from_axis(c, 2.0, 1.0) < 9.0 / SQRT_2, "{c}");
    assert!(c.y < 2.0, "{c}");
    let below = positions.iter().filter(|x| x.y < 0.0).count();
    assert!(below > 100, "only {below} particles under the floor");
}
