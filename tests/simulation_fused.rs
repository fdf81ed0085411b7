//! `Simulation::advance` takes the fused multi-step passes (`Method::steps`) where nothing but
//! the method acts between steps, and must give what as many single steps give, bit for bit:
//! the same positions, velocities, step and force-evaluation counts, and the same divergence.

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;

/// `scene` (with `sets`), stepped by `method` at `dt`, energy accounting off and colliders
/// and spheres removed (the fused path's conditions).
fn sim(name: &str, sets: &[&str], method: Method, dt: f64) -> Simulation {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut scene = scene::load(name, &sets).expect("built-in scene");
    scene.set_method(method);
    for body in &mut scene.bodies {
        body.model.colliders.clear();
        body.state.spheres.clear();
    }
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    sim.set_accounting(false);
    sim
}

/// `n` single steps against one `advance(n)`: every number the same.
fn same_either_way(name: &str, sets: &[&str], method: Method, dt: f64, n: u64) {
    let mut single = sim(name, sets, method, dt);
    for _ in 0..n {
        single.step();
    }
    let mut fused = sim(name, sets, method, dt);
    fused.advance(n);
    let what = format!("{name} {sets:?} {method} dt {dt}");
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
}

#[test]
fn the_rope_workload_advances_as_single_steps() {
    // 64 nodes of semi-implicit Euler: the small-lattice pass in structure-of-arrays form.
    same_either_way("rope", &["nodes=64"], Method::SemiImplicitEuler, 1e-4, 1000);
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
