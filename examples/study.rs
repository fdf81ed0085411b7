//! A study from code: the largest stable time step of three methods on the GAMES101 rope,
//! found by the stability study (perturbation growth, bisection, confirmation run), beside the
//! Gershgorin bound on the rope's fastest frequency.
//!
//! `cargo run --release --example study`

use springlab::physics::Method;
use springlab::study::{max_stable_dt, modes::spring_gershgorin};

fn main() {
    let scene = springlab::scene::load("rope", &[]).expect("a built-in scene");
    let omega = spring_gershgorin(&scene.bodies[0].model).sqrt();
    println!("rope: ω_max ≤ {omega:.2} rad/s (Gershgorin)");
    for method in [
        Method::ExplicitEuler,
        Method::SemiImplicitEuler,
        Method::Rk4,
    ] {
        match max_stable_dt(&scene, method) {
            Ok(Some(0.0)) => {
                println!(
                    "{:>22}: no stable dt (undamped, it gains energy at every dt)",
                    method.name()
                );
            }
            Ok(Some(dt)) => println!(
                "{:>22}: dt ≤ {dt:.5} s (dt times the bound: {:.3})",
                method.name(),
                dt * omega
            ),
            Ok(None) => println!("{:>22}: stable at every dt probed", method.name()),
            Err(e) => println!("{:>22}: {e}", method.name()),
        }
    }
}
