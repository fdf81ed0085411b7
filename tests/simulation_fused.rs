//! `Simulation::advance` takes the fused multi-step passes (`Method::steps`) where nothing but
//! the method and the colliders' response acts between steps, and must give what as many single
//! steps give, bit for bit:
//! the same positions, velocities, step and force-evaluation counts, and the same divergence;
//! with energy accounting on (as `springlab run` steps), the same energy dissipated and residual.

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::{CHUNK, CHUNK_MAX, Simulation};

/// `scene` (with `sets`), stepped by `method` at `dt`, energy accounting on or off, the
/// colliders and dynamic spheres removed unless `colliders`.
fn sim(
    name: &str,
    sets: &[&str],
    method: Method,
    dt: f64,
    accounting: bool,
    colliders: bool,
) -> Simulation {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut scene = scene::load(name, &sets).expect("built-in scene");
    scene.set_method(method);
    for body in &mut scene.bodies {
        if !colliders {
            body.model.colliders.clear();
            body.state.spheres.clear();
        }
    }
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    sim.set_accounting(accounting);
    sim
}

/// `n` single steps against one `advance(n)`, with energy accounting off and on: every number
/// the same.
fn same_either_way(name: &str, sets: &[&str], method: Method, dt: f64, n: u64) {
    for accounting in [false, true] {
        same_either_way_accounting(name, sets, method, dt, n, accounting, false);
    }
}

/// [`same_either_way`] with the scene's colliders kept; returns the single steps' run and the
/// fused one.
fn same_either_way_accounting(
    name: &str,
    sets: &[&str],
    method: Method,
    dt: f64,
    n: u64,
    accounting: bool,
    colliders: bool,
) -> (Simulation, Simulation) {
    let mut single = sim(name, sets, method, dt, accounting, colliders);
    for _ in 0..n {
        single.step();
    }
    let mut fused = sim(name, sets, method, dt, accounting, colliders);
    fused.advance(n);
    let what = format!("{name} {sets:?} {method} dt {dt} accounting {accounting}");
    let d = |s: &Simulation| {
        let d = s.dissipated();
        [
            d.dampers_and_drag,
            d.contact_forces,
            d.contacts,
            d.method,
            d.total,
        ]
        .map(f64::to_bits)
    };
    assert_eq!(d(&fused), d(&single), "{what}: energy dissipated");
    assert_eq!(
        fused.energy_residual().to_bits(),
        single.energy_residual().to_bits(),
        "{what}: energy residual"
    );
    if accounting && single.diverged.is_none() && name != "cube-plane" {
        // Dampers that work (the cube falls freely as one rigid body, its dampers idle): the
        // comparison is not of zeros.
        assert!(
            single.dissipated().dampers_and_drag > 0.0,
            "{what}: nothing dissipated"
        );
    }
    assert_eq!(fused.steps, single.steps, "{what}: steps");
    assert_eq!(fused.force_evals, single.force_evals, "{what}: evaluations");
    assert_eq!(fused.diverged, single.diverged, "{what}: divergence");
    let bits = |s: &Simulation| -> Vec<u64> {
        s.positions()
            .chain(s.velocities())
            .flat_map(|p| p.to_array())
            .map(f64::to_bits)
            .collect()
    };
    assert!(bits(&fused) == bits(&single), "{what}: states differ");
    (single, fused)
}

#[test]
fn the_rope_workload_advances_as_single_steps() {
    // 64 nodes of semi-implicit Euler: the small-lattice pass in structure-of-arrays form;
    // with dampers and drag, whose power the accounting integrates.
    let sets = ["nodes=64", "damping=0.5", "drag=0.01"];
    same_either_way("rope", &sets, Method::SemiImplicitEuler, 1e-4, 1000);
    // A method with no many-step path: its single steps, chunk by chunk; and the rope
    // workload's rods (no stiffness, 20 projections), whose energy the accounting sums (with
    // some drag, so that the dissipation compared is not zero).
    same_either_way("rope", &sets, Method::Verlet, 1e-3, 300);
    let rods = [
        "nodes=64",
        "stiffness=0",
        "iterations=20",
        "verlet_damping=0",
        "drag=0.01",
    ];
    same_either_way("rope", &rods, Method::Verlet, 1e-3, 700);
}

#[test]
fn a_tiny_scene_takes_longer_chunks() {
    // 64 particles and 63 springs: 64 · 1024 / 127 steps, at most CHUNK_MAX; the 1000 steps
    // are one long chunk and a shorter one, both fused (the rope swings far below 100 m/s).
    let mut rope = sim(
        "rope",
        &["nodes=64"],
        Method::SemiImplicitEuler,
        1e-4,
        true,
        false,
    );
    assert_eq!(rope.chunk_steps(), CHUNK_MAX);
    rope.advance(1000);
    assert_eq!((rope.steps, rope.fused_steps()), (1000, 1000));
    // The jelly cube's 1000 particles and thousands of springs: the plain chunk.
    let cube = sim(
        "cube-plane",
        &[],
        Method::SemiImplicitEuler,
        1e-4,
        true,
        false,
    );
    assert_eq!(cube.chunk_steps(), CHUNK);
}

#[test]
fn the_lattices_advance_as_single_steps() {
    // The jelly cube without its plane: the thread team's passes on two or more threads.
    for method in [Method::SemiImplicitEuler, Method::Rk4] {
        same_either_way("cube-plane", &[], method, 1e-4, 130);
    }
    same_either_way("cloth-sphere", &[], Method::SemiImplicitEuler, 1e-4, 70);
}

#[test]
fn a_body_that_lands_on_a_collider_advances_as_single_steps() {
    // The jelly cube 0.1 m above its plane: it falls for about 0.14 s, lands and rests on it,
    // all in fused chunks, the response after each step taken between two steps of a chunk.
    // The responses acted (energy taken out by contacts), every number is the single steps',
    // and every chunk was fused (300 steps: four chunks of 64 and one of 44).
    for method in [Method::SemiImplicitEuler, Method::Rk4] {
        for accounting in [false, true] {
            let (single, fused) = same_either_way_accounting(
                "cube-plane",
                &["offset=[0, -4.9, 0]"],
                method,
                1e-3,
                300,
                accounting,
                true,
            );
            let lowest = single
                .positions()
                .map(|p| p.y)
                .fold(f64::INFINITY, f64::min);
            assert!(
                lowest < -0.99,
                "{method}: the cube reached the plane ({lowest})"
            );
            if accounting {
                assert!(
                    single.dissipated().contacts > 0.0,
                    "{method}: no response acted"
                );
            }
            assert_eq!(fused.fused_steps(), 300, "{method}: steps in fused chunks");
        }
    }
}

#[test]
fn every_method_lands_on_a_collider_as_its_single_steps() {
    // The methods without a many-step path on the landing cube: Verlet and XPBD keep a history
    // (x_prev) that the response moves with the particle, so their steps stay single steps
    // there and `advance` gives the single steps' numbers, energy included.
    for method in Method::ALL {
        if method.declaration().energy_guard || method.declaration().many.is_some() {
            continue;
        }
        let (single, _) = same_either_way_accounting(
            "cube-plane",
            &["offset=[0, -4.9, 0]"],
            method,
            1e-3,
            300,
            true,
            true,
        );
        assert!(
            single.dissipated().contacts > 0.0,
            "{method}: no response acted"
        );
    }
}

#[test]
fn a_cloth_on_spheres_advances_as_single_steps() {
    // The course cloth of 2024 touches its sphere (kinematic, at rest) from the first step, and
    // 2022's four spheres (dynamic, in free fall, radius 1 m at 1.5 m apart: they overlap and
    // push each other apart): the spheres move and respond between two steps of a chunk. Every
    // number is the single steps', the spheres' too, and every chunk was fused.
    let cases: [(&str, &[&str], u64); 2] = [
        ("cloth-sphere", &[], 70),
        ("cloth-spheres", &["n=10", "sphere_radius=1"], 300),
    ];
    for (name, sets, n) in cases {
        for accounting in [false, true] {
            let (single, fused) = same_either_way_accounting(
                name,
                sets,
                Method::SemiImplicitEuler,
                1e-4,
                n,
                accounting,
                true,
            );
            assert_eq!(fused.fused_steps(), n, "{name}: steps in fused chunks");
            let spheres = |s: &Simulation| -> Vec<u64> {
                s.states()
                    .flat_map(|s| &s.spheres)
                    .flat_map(|s| s.center.to_array().into_iter().chain(s.velocity.to_array()))
                    .map(f64::to_bits)
                    .collect()
            };
            assert!(
                spheres(&fused) == spheres(&single),
                "{name}: spheres differ"
            );
            if name == "cloth-sphere" && accounting {
                assert!(
                    single.dissipated().contacts != 0.0,
                    "{name}: no response acted"
                );
            }
            if name == "cloth-spheres" {
                let first = single.states().flat_map(|s| &s.spheres).next();
                let x = first.map_or(f64::NAN, |s| s.center.x);
                assert!(x < -0.76, "{name}: the spheres were not pushed apart ({x})");
            }
        }
    }
}

#[test]
fn a_diverging_run_stops_at_the_same_step() {
    // Semi-implicit Euler far beyond its limit ω dt = 2: the fused chunk is refused and the
    // steps are taken one by one, up to the same diverging step.
    same_either_way(
        "rope",
        &["nodes=64", "stiffness=1e6"],
        Method::SemiImplicitEuler,
        0.05,
        500,
    );
}
