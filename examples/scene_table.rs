//! The README's table: for every built-in scene and method, the largest stable dt found by
//! `study::stability` (linear limit, damped theory, confirmed limit) and the springs·steps per
//! second at the scene's own dt (median of 3 timed runs of 0.3 s of wall time).
//!
//! `cargo run --release --example scene_table > table.md`
use std::time::Instant;

use springlab::physics::Method;
use springlab::scene::BUILTIN;
use springlab::simulation::Simulation;
use springlab::study::stability::{StabilityOptions, load_scene, stability};

fn throughput(name: &str, method: Method) -> f64 {
    let mut rates = Vec::new();
    for _ in 0..3 {
        let (mut scene, _) = load_scene(name, &[]).expect("built-in");
        scene.set_method(method);
        let springs = scene.spring_count().max(1) as f64;
        let mut sim = Simulation::new(scene);
        let start = Instant::now();
        // Step in batches until 0.3 s of wall time or divergence.
        while start.elapsed().as_secs_f64() < 0.3 && sim.diverged.is_none() {
            sim.run(10, |_| {});
        }
        rates.push(sim.steps as f64 * springs / start.elapsed().as_secs_f64());
    }
    rates.sort_by(f64::total_cmp);
    rates[1]
}

fn main() {
    println!(
        "| scene | ω_max (rad/s) | method | confirmed max stable dt | dt·ω_max | linear dt·ω_max | damped theory dt·ω_max | springs·steps/s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for def in BUILTIN {
        let (scene, _) = load_scene(def.name, &[]).expect("built-in");
        let report = match stability(&scene, &StabilityOptions::default(), &mut |_, _| {}) {
            Ok(r) => r,
            Err(e) => {
                println!(
                    "| {} | — | — | study failed: {e} | — | — | — | — |",
                    def.name
                );
                continue;
            }
        };
        let z = |class: &str, z: Option<f64>| match (class, z) {
            (_, Some(z)) => format!("{z:.3}"),
            ("unconditional", None) => "any (> 100)".to_string(),
            ("none", None) => "none (< 0.01)".to_string(),
            (other, None) => other.to_string(),
        };
        for m in &report.methods {
            let dt = match (m.stability.name(), m.max_stable_dt) {
                (_, Some(dt)) => format!("{dt:.3e} s"),
                ("unconditional", None) => "any".to_string(),
                _ => "none".to_string(),
            };
            println!(
                "| {} | {:.1} | {} | {} | {} | {} | {} | {:.3e} |",
                def.name,
                report.omega_max,
                m.method.name(),
                dt,
                z(m.stability.name(), m.limit_dt_omega),
                z(m.linear_stability.name(), m.linear_dt_omega),
                z(m.damped_theory.stability, m.damped_theory.dt_omega),
                throughput(def.name, m.method)
            );
        }
        eprintln!("{} done", def.name);
    }
}
