//! A scene built from code: a chain of three 1 kg particles hanging from a pinned one, joined by
//! springs of 200 N/m, stepped by RK4 in a `Simulation`; its energy every 0.25 s.
//!
//! `cargo run --release --example scene_from_code`

use glam::DVec3;
use springlab::physics::{Method, MethodParams, SpringKind};
use springlab::scene::builder::Builder;
use springlab::scene::{Body, Scene};
use springlab::{Simulation, physics::particles::pin_particle};

fn main() {
    // Particles (position in m, mass in kg) and springs (stiffness N/m, damping N·s/m); a
    // spring's rest length is the distance of its ends when it is added.
    let mut builder = Builder::new();
    let top = builder.particle(DVec3::ZERO, 1.0);
    let mut previous = top;
    for i in 1..=3 {
        let next = builder.particle(DVec3::new(0.5 * f64::from(i), 0.0, 0.0), 1.0);
        builder.spring(previous, next, 200.0, 0.5, SpringKind::Struct);
        previous = next;
    }
    // Gravity (m/s²) and drag (N·s/m); then the first particle held in place.
    let (mut model, mut state) = builder.build(DVec3::new(0.0, -9.81, 0.0), 0.0);
    pin_particle(&mut model, &mut state, top as usize);

    let scene = Scene {
        name: "chain".to_string(),
        bodies: vec![Body {
            label: "rk4 chain".to_string(),
            model,
            state,
            method: Method::Rk4,
            params: MethodParams::default(),
        }],
        dt: 1e-3,
        duration: 2.0,
    };
    let mut sim = Simulation::new(scene);
    println!("    t (s)   energy (J)   dissipated (J)");
    for _ in 0..8 {
        sim.run(250, |_| {});
        println!(
            "{:9.2} {:12.4} {:16.4}",
            sim.time(),
            sim.energy().total,
            sim.dissipated().total
        );
    }
}
