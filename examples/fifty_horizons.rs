//! Checks the stability study's limits the hard way: for every method with a reported limit,
//! a run of the whole scene 50 horizons long at 95 % of that limit must not break (no
//! divergence, no energy that keeps rising above ten times the scene's energy scale).
//!
//! `cargo run --release --features harness --example fifty_horizons -- cube-plane [--set key=value ...]`
use springlab::study::stability::{
    StabilityOptions, confirm_steps, energy_scale, load_scene, stability,
};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(name) = args.first() else {
        eprintln!("usage: fifty_horizons SCENE [--set key=value ...]");
        std::process::exit(2);
    };
    let sets: Vec<String> = args[1..]
        .chunks(2)
        .filter(|c| c.len() == 2 && c[0] == "--set")
        .map(|c| c[1].clone())
        .collect();
    let (scene, _) = match load_scene(name, &sets) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let report = match stability(&scene, &StabilityOptions::default(), &mut |_, _| {}) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let scale = energy_scale(&scene);
    for m in &report.methods {
        let Some(limit) = m.max_stable_dt else {
            println!(
                "{:<21} {} (nothing to check)",
                m.method.name(),
                m.stability.name()
            );
            continue;
        };
        let dt = 0.95 * limit;
        let steps = (50.0 * report.horizon / dt).ceil() as u64;
        let c = confirm_steps(&scene, m.method, dt, steps, scale);
        println!(
            "{:<21} limit {limit:.4e} s; {steps} steps at {dt:.4e} s: {}",
            m.method.name(),
            if c.passed {
                "holds".to_string()
            } else {
                format!("BREAKS: {}", c.reason.unwrap_or_default())
            }
        );
    }
}
