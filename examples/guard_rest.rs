//! What implicit Euler's energy guard costs once the 2022 cloth's four spheres lie at rest in it:
//! `cloth-spheres` with implicit Euler at dt = 0.005 s for `SECONDS` simulated seconds (default
//! 15), guard on and off; per simulated second the wall time, the linear solves, the halved steps
//! so far, the energy and its terms, and the fastest sphere. The spheres come to rest at about
//! t = 6 s; from then on each step's energy rises by about a joule that the next steps take out
//! (see `simulation.rs`, "Implicit Euler's energy guard").
//!
//! `cargo run --release --example guard_rest [SECONDS]`

use std::time::Instant;

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;

fn main() {
    let secs: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(15);
    for guard in [true, false] {
        let mut s = scene::load("cloth-spheres", &[]).expect("built-in scene");
        s.set_method(Method::ImplicitEuler);
        let mut sim = Simulation::new(s);
        sim.set_dt(0.005);
        sim.set_energy_guard(guard);
        let start = Instant::now();
        let mut last = (0.0, 0u64);
        for sec in 1..=secs {
            sim.run(200, |_| {});
            let wall = start.elapsed().as_secs_f64();
            let r = sim.solver_report();
            let e = sim.energy();
            let sph: f64 = sim.scene.bodies[0]
                .state
                .spheres
                .iter()
                .map(|s| s.velocity.length())
                .fold(0.0, f64::max);
            println!(
                "guard {guard} t {sec:2} s: wall {:.3} s this second, solves {}, halved {}, E {:.3} (K {:.4}, G {:.2}, U {:.2}), max sphere |v| {sph:.4}",
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
