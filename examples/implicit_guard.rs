//! What implicit Euler's energy guard costs on the 2022 cloth with four spheres: 3 s of
//! `cloth-spheres` with implicit Euler at dt = 0.005 s, guard on and off, and semi-implicit
//! Euler at dt = 1e-4 s, interleaved for `ROUNDS` rounds (default 3); wall times and the
//! ratios to semi-implicit Euler, with the solves and CG iterations of the implicit runs.
//!
//! `cargo run --release --example implicit_guard [ROUNDS]`
use std::time::Instant;

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;

fn run(method: Method, dt: f64, guard: bool, accounting: bool) -> (f64, String) {
    let mut s = scene::load("cloth-spheres", &[]).expect("built-in scene");
    s.set_method(method);
    let mut sim = Simulation::new(s);
    sim.set_dt(dt);
    sim.set_energy_guard(guard);
    sim.set_accounting(accounting);
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

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
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
