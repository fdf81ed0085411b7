//! Good scene files build the scenes they describe (the bad ones are in the parent module).

use super::*;

// --- Good files --------------------------------------------------------------------------------

#[test]
fn builtin_rope_with_16_nodes() {
    let scene = load(
        "rope16.toml",
        "scene = \"rope\"
[params]
nodes = 16
pinned = [0]
start = [0.0, 2.0, 0.0]
mass = 2          # an integer for a number is fine

[run]
method = \"verlet\"
dt = 0.005
time = 2.0
",
    );
    assert_eq!(scene.name, "rope16.toml");
    assert_eq!(scene.particle_count(), 16);
    assert_eq!(scene.spring_count(), 15);
    assert_eq!((scene.dt, scene.duration), (0.005, 2.0));
    let body = &scene.bodies[0];
    assert_eq!(body.method, Method::Verlet);
    assert!(body.model.is_pinned(0));
    assert!((1..16).all(|i| !body.model.is_pinned(i)));
    assert!(body.model.mass.iter().all(|&m| m == 2.0));
    assert_eq!(body.state.x[0], DVec3::new(0.0, 2.0, 0.0));
}

#[test]
fn set_applies_on_top_of_params() {
    let (_, result) = load_with(
        "rope.toml",
        "scene = \"rope\"\n[params]\nnodes = 16\nstiffness = 50\n",
        &["nodes=5"],
    );
    let scene = result.expect("loads");
    assert_eq!(scene.particle_count(), 5);
    assert_eq!(scene.bodies[0].model.springs()[0].stiffness, 50.0);
}

#[test]
fn builtin_file_without_params_equals_the_builtin() {
    let from_file = load("ropes.toml", "scene = \"ropes\"\n");
    let builtin = scene::build_builtin("ropes", &[]).expect("builtin");
    assert_eq!(from_file.bodies, builtin.bodies);
    assert_eq!(
        (from_file.dt, from_file.duration),
        (builtin.dt, builtin.duration)
    );
}

const OSCILLATOR: &str = "
[world]
gravity = [0.0, 0.0, 0.0]

[[particles]]
position = [0.0, 0.0, 0.0]
mass = 1.0
pinned = true

[[particles]]
position = [1.1, 0.0, 0.0]
mass = 1.0

[[springs]]
a = 0
b = 1
stiffness = 100.0
rest_length = 1.0

[run]
method = \"rk4\"
dt = 0.01
time = 10.0
verlet_damping = 0.0
iterations = 0
";

#[test]
fn explicit_oscillator_equals_the_builtin() {
    let file = load("oscillator.toml", OSCILLATOR);
    let builtin = scene::build_builtin("oscillator", &[]).expect("builtin");
    assert_eq!(file.name, "oscillator.toml");
    assert_eq!(file.bodies.len(), 1);
    let (f, b) = (&file.bodies[0], &builtin.bodies[0]);
    assert_eq!(f.label, "oscillator");
    assert_eq!(f.model.mass, b.model.mass);
    assert_eq!(f.model.inv_mass, b.model.inv_mass);
    assert_eq!(f.model.springs(), b.model.springs());
    assert_eq!(f.model.gravity, b.model.gravity);
    assert_eq!(f.model.drag, b.model.drag);
    assert_eq!(f.model, b.model);
    assert_eq!(f.state.x, b.state.x);
    assert_eq!(f.state.v, b.state.v);
    assert_eq!(f.state, b.state);
    assert_eq!(f.method, b.method);
    assert_eq!(f.params, b.params);
    assert_eq!((file.dt, file.duration), (builtin.dt, builtin.duration));
}

#[test]
fn explicit_oscillator_runs_like_the_builtin_under_rk4() {
    let run = |scene: Scene| {
        let mut sim = Simulation::new(scene);
        sim.set_method(Method::Rk4);
        sim.set_dt(0.01);
        sim.run(1000, |_| {});
        assert!(sim.diverged.is_none());
        sim.positions().collect::<Vec<_>>()
    };
    let file = run(load("oscillator.toml", OSCILLATOR));
    let builtin = run(scene::build_builtin("oscillator", &[]).expect("builtin"));
    // Same model, same method, same steps: bit-identical positions.
    assert_eq!(file, builtin);
    // And both follow the exact solution x(t) = 1 + 0.1 cos(10 t) at t = 10 s.
    let exact = 1.0 + 0.1 * (10.0_f64 * 10.0).cos();
    // RK4 phase error after 1000 steps of ω·dt = 0.1: about 1000 · 0.1⁵ / 120 rad · 0.1 m ≈ 1e-5 m.
    assert!((file[1].x - exact).abs() < 2e-5, "{} vs {exact}", file[1].x);
}

#[test]
fn explicit_defaults() {
    let text = format!(
        "{TWO}velocity = [0, 1, 0]\n[[particles]]\nposition = [0, 3, 4]\nmass = 2\npinned = true\nvelocity = [9, 9, 9]\n[[springs]]\na = 0\nb = 2\nstiffness = 10\n"
    );
    let scene = load("defaults.toml", &text);
    assert_eq!(scene.name, "defaults.toml");
    assert_eq!((scene.dt, scene.duration), (0.01, 10.0));
    let body = &scene.bodies[0];
    assert_eq!(body.label, "defaults");
    assert_eq!(body.method, Method::SemiImplicitEuler);
    assert_eq!(body.params, springlab::MethodParams::default());
    assert_eq!(body.model.gravity, DVec3::new(0.0, -9.8, 0.0));
    assert_eq!(body.model.drag, 0.0);
    assert_eq!(body.state.v[1], DVec3::new(0.0, 1.0, 0.0));
    // A pinned particle starts at rest whatever velocity the file gives.
    assert_eq!(body.state.v[2], DVec3::ZERO);
    assert!(body.model.is_pinned(2));
    let s = &body.model.springs()[0];
    // Rest length defaults to the initial distance |(0, 3, 4)| = 5 m.
    assert_eq!((s.a, s.b, s.rest_length), (0, 2, 5.0));
    assert_eq!(
        (s.stiffness, s.damping, s.kind),
        (10.0, 0.0, SpringKind::Struct)
    );
}

#[test]
fn rope_nodes_come_after_the_particles() {
    let text = "
[[particles]]
position = [5.0, 0.0, 0.0]
mass = 3.0

[[ropes]]
start = [0.0, 0.0, 0.0]
end = [3.0, 0.0, 0.0]
nodes = 4
mass = 0.5
stiffness = 70.0
damping = 0.25
pinned = [0, 3]

[[springs]]
a = 4
b = 0
stiffness = 20.0
kind = \"bend\"
";
    let scene = load("mixed.toml", text);
    let body = &scene.bodies[0];
    assert_eq!(body.model.particle_count(), 5);
    assert_eq!(body.model.springs().len(), 4);
    assert_eq!(body.model.mass, vec![3.0, 0.5, 0.5, 0.5, 0.5]);
    let pinned: Vec<bool> = (0..5).map(|i| body.model.is_pinned(i)).collect();
    assert_eq!(pinned, vec![false, true, false, false, true]);
    assert_eq!(body.state.x[4], DVec3::new(3.0, 0.0, 0.0));
    let rope_spring = &body.model.springs()[0];
    assert_eq!((rope_spring.a, rope_spring.b), (1, 2));
    assert_eq!(
        (
            rope_spring.stiffness,
            rope_spring.damping,
            rope_spring.rest_length
        ),
        (70.0, 0.25, 1.0)
    );
    let last = &body.model.springs()[3];
    assert_eq!((last.a, last.b, last.rest_length), (4, 0, 2.0));
    assert_eq!(last.kind, SpringKind::Bend);
}

#[test]
fn rope_block_defaults_are_the_builtin_rope() {
    let from_file = load("rope.toml", "[[ropes]]\n");
    let builtin = scene::build_builtin("rope", &[]).expect("builtin");
    assert_eq!(from_file.bodies[0].model, builtin.bodies[0].model);
    assert_eq!(from_file.bodies[0].state, builtin.bodies[0].state);
}

#[test]
fn example_scene_files_all_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("scenes/ exists") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = scene::load(path.to_str().expect("utf-8"), &[])
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(scene.particle_count() > 0);
            // Each example runs for a second without diverging.
            let mut sim = Simulation::new(scene);
            let steps = (1.0 / sim.dt()).round() as u64;
            sim.run(steps, |_| {});
            assert!(sim.diverged.is_none(), "{} diverged", path.display());
            names.push(
                path.file_name()
                    .expect("name")
                    .to_string_lossy()
                    .into_owned(),
            );
        }
    }
    for expected in ["rope16.toml", "two_springs.toml", "oscillator.toml"] {
        assert!(names.iter().any(|n| n == expected), "missing {expected}");
    }
}

#[test]
fn example_files_describe_their_scenes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let load = |name: &str| {
        scene::load(dir.join(name).to_str().expect("utf-8"), &[]).expect("example loads")
    };
    let rope = load("rope16.toml");
    assert_eq!((rope.particle_count(), rope.spring_count()), (16, 15));
    let two = load("two_springs.toml");
    assert_eq!((two.particle_count(), two.spring_count()), (3, 2));
    let osc = load("oscillator.toml");
    let builtin = scene::build_builtin("oscillator", &[]).expect("builtin");
    assert_eq!(osc.bodies, builtin.bodies);
}

#[test]
fn module_doc_examples_load() {
    // The two examples in the documentation of `scene::file` are real, loadable files.
    let source = include_str!("../../crates/core/src/scene/file.rs");
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in source.lines().filter_map(|l| l.strip_prefix("//!")) {
        let line = line.strip_prefix(' ').unwrap_or(line);
        match (&mut current, line) {
            (None, "```toml") => current = Some(String::new()),
            (Some(block), "```") => {
                blocks.push(std::mem::take(block));
                current = None;
            }
            (Some(block), text) => {
                block.push_str(text);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    assert_eq!(blocks.len(), 2, "two examples");
    let form1 = load("form1.toml", &blocks[0]);
    assert_eq!(form1.particle_count(), 16);
    assert_eq!(form1.bodies[0].method, Method::Verlet);
    let form2 = load("form2.toml", &blocks[1]);
    // Two particles and a default rope of 8 nodes; one spring plus 7 rope springs.
    assert_eq!((form2.particle_count(), form2.spring_count()), (10, 8));
    assert_eq!(form2.bodies[0].method, Method::Rk4);
}
