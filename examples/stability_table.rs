//! The table of docs/stability.md: for every scene named (default: rope, cube-plane,
//! jelly-bowl, cloth-spheres) and every method, the damped theory at rest, the measured linear
//! limit (against that theory), the damped theory at the scene's stiffest state, and the scene
//! limit (the whole scene confirmed by runs, against the theory at rest).
//!
//! `cargo run --release --features harness --example stability_table [SCENE ...] > table.md`
use springlab::study::stability::{StabilityOptions, load_scene, stability};
use springlab::study::theory::TheoryLimit;

fn seconds(class: &str, dt: Option<f64>) -> String {
    match dt {
        Some(dt) => format!("{dt:.4e} s"),
        None => class.to_string(),
    }
}

fn versus(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => format!(" ({:+.1} %)", 100.0 * (a / b - 1.0)),
        _ => String::new(),
    }
}

fn theory(t: &TheoryLimit) -> String {
    seconds(t.stability, t.dt)
}

fn main() {
    let mut scenes: Vec<String> = std::env::args().skip(1).collect();
    if scenes.is_empty() {
        scenes = ["rope", "cube-plane", "jelly-bowl", "cloth-spheres"]
            .map(String::from)
            .to_vec();
    }
    println!(
        "| scene | method | damped theory | linear (vs theory) | theory at the stiffest state | \
         scene (vs theory) |"
    );
    println!("|---|---|---|---|---|---|");
    let mut notes = Vec::new();
    for name in &scenes {
        let (scene, _) = match load_scene(name, &[]) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(2);
            }
        };
        let r = match stability(&scene, &StabilityOptions::default(), &mut |_, _| {}) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(2);
            }
        };
        for m in &r.methods {
            println!(
                "| {name} | {} | {} | {}{} | {} | {}{} |",
                m.method.name(),
                theory(&m.damped_theory),
                seconds(m.linear_stability.name(), m.linear_max_dt),
                versus(m.linear_max_dt, m.theory_dt),
                theory(&m.stiffest_theory),
                seconds(m.stability.name(), m.max_stable_dt),
                versus(m.max_stable_dt, m.theory_dt),
            );
        }
        let s = &r.stiffest_state;
        notes.push(format!(
            "- {name}: ω_max = {:.2} rad/s at rest, {:.2} rad/s ({:+.1} %) at t = {:.3} s of a \
             run with {} at dt = {:e} s",
            r.omega_max,
            s.omega_max,
            100.0 * (s.ratio - 1.0),
            s.time,
            s.method.name(),
            s.dt
        ));
        eprintln!("{name} done");
    }
    println!("\nThe stiffest states:\n");
    for n in notes {
        println!("{n}");
    }
}
