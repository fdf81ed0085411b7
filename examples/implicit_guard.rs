//! What implicit Euler's energy guard costs on the 2022 cloth with four spheres, `cloth-spheres`
//! with implicit Euler at dt = 0.005 s, guard on and off:
//!
//! - `implicit_guard [ROUNDS]`: 3 s of it, and semi-implicit Euler at dt = 1e-4 s, interleaved for
//!   `ROUNDS` rounds (default 3); wall times and the ratios to semi-implicit Euler, with the
//!   solves and CG iterations of the implicit runs.
//! - `implicit_guard --rest [SECONDS]`: `SECONDS` simulated seconds (default 15), and per
//!   simulated second the wall time, the linear solves, the halved steps so far, the energy and
//!   its terms, and the fastest sphere. The spheres come to rest at about t = 6 s; from then on
//!   each step's energy rises by about a joule that the next steps take out (see `simulation.rs`,
//!   "Implicit Euler's energy guard").
//!
//! `cargo run --release --features harness --example implicit_guard [ROUNDS | --rest [SECONDS]]`
use std::time::Instant;

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;

/// `cloth-spheres` stepped by `method` at `dt`, with the energy guard and accounting as given.
fn simulation(method: Method, dt: f64, guard: bool, accounting: bool) -> Simulation {
    let mut s = scene::load("cloth-spheres", &[]).expect("built-in scene");
    s.set_method(method);
    let mut sim = Simulation::new(s);
    sim.set_dt(dt);
    sim.set_energy_guard(guard);
    sim.set_accounting(accounting);
    sim
}

fn run(method: Method, dt: f64, guard: bool, accounting: bool) -> (f64, String) {
    let mut sim = simulation(method, dt, guard, accounting);
    let steps = (3.0 / dt).round() as u64;
    let start = Instant::now();
    sim.run(steps, |_| {});
    let wall = start.elapsed().as_secs_f64();
    let r = sim.solver_report();
    let solver = if method == Method::ImplicitEuler {
        format!(
            "{} solves, {:.1} CG iterations per solve, {} halved",
            r.solves, r.iterations_mean, r.halved_steps
        )
    } else {
        String::new()
    };
    (wall, solver)
}

/// The guard on and off once the spheres rest: one line per simulated second.
fn rest(seconds: usize) {
    for guard in [true, false] {
        let mut sim = simulation(Method::ImplicitEuler, 0.005, guard, true);
        let start = Instant::now();
        let mut last = (0.0, 0u64);
        for sec in 1..=seconds {
            sim.run(200, |_| {});
            let wall = start.elapsed().as_secs_f64();
            let r = sim.solver_report();
            let e = sim.energy();
            let sphere: f64 = sim.scene.bodies[0]
                .state
                .spheres
                .iter()
                .map(|s| s.velocity.length())
                .fold(0.0, f64::max);
            println!(
                "guard {guard} t {sec:2} s: wall {:.3} s this second, solves {}, halved {}, E {:.3} (K {:.4}, G {:.2}, U {:.2}), max sphere |v| {sphere:.4}",
                wall - last.0,
                r.solves - last.1,
                r.halved_steps,
                e.total,
                e.kinetic,
                e.gravity,
                e.elastic
            );
            last = (wall, r.solves);
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "--rest") {
        rest(args.get(1).and_then(|s| s.parse().ok()).unwrap_or(15));
        return;
    }
    let rounds: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(3);
    for round in 1..=rounds {
        let (se, _) = run(Method::SemiImplicitEuler, 1e-4, true, true);
        let (on, s_on) = run(Method::ImplicitEuler, 0.005, true, true);
        let (off, s_off) = run(Method::ImplicitEuler, 0.005, false, true);
        println!(
            "round {round}: semi-implicit {se:.3} s; implicit, guard on {on:.3} s ({:.2}x; {s_on}); \
             guard off {off:.3} s ({:.2}x; {s_off})",
            se / on,
            se / off
        );
    }
}
