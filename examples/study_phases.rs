//! The parts of `springlab study stability` that are not stepping, timed alone, with a
//! checksum of their results (so that two builds are compared for speed and for bits):
//!
//! - `growth [SCENE] [R]`: the linear probes' power iteration (`study::linear`) of explicit
//!   Euler and Verlet at three `dt·ω_max` each just below, at and above their limits on
//!   `jelly-bowl`, so that every probe runs its whole window (4 000 power steps): the
//!   perturbation's energy, the rigid-mode projection and two steps of the method per power step;
//!   `R` (1 to 3) probes per method.
//! - `stiffest [SCENE]`: the stiffest-state run (a run of the scene over 2 s with `ω_max` sampled
//!   401 times by a warm-started power iteration, `study::modes::omega_max_from`).
//! - `energy [SCENE]`: the scene's energy (kinetic, gravitational, elastic) 20 000 times: the
//!   confirmation and usable-dt runs' energy looks.
//! - `blocks [SCENE]`: how many of the springs' stiffness blocks `K_s` at the start are distinct
//!   bit for bit (the lattices repeat a few directions).
//!
//! `SPRINGLAB_THREADS=1 /usr/bin/time -f "%U" cargo run --release --features harness --example
//! study_phases growth`: compare CPU times of two builds interleaved, and their printed lines.
use std::time::Instant;

use glam::DMat3;
use springlab::physics::Method;
use springlab::study::linear::Linearisation;
use springlab::study::modes::omega_max;
use springlab::study::stability::stiffest;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map_or("growth", String::as_str);
    let name = args.get(2).map_or("jelly-bowl", String::as_str);
    let scene = springlab::scene::load(name, &[]).expect("a built-in scene");
    let body = &scene.bodies[0];
    let t = Instant::now();
    match what {
        "growth" => {
            let w = omega_max(&body.model, &body.state).omega;
            let lin = Linearisation::new(&body.model, &body.state, w);
            let probes: usize = args.get(3).map_or(3, |s| s.parse().expect("a count"));
            let cases = [
                (Method::ExplicitEuler, [0.3756, 0.3760, 0.3764]),
                (Method::Verlet, [0.3516, 0.3519, 0.3523]),
            ];
            for (method, zs) in cases {
                for z in zs.iter().take(probes) {
                    let dt = z / w;
                    let g = lin.growth(method, &body.params, dt, 4000);
                    println!(
                        "{} dt·ω = {z}: {} power steps, stable {}, ρ bits {:016x}",
                        method.name(),
                        g.steps,
                        g.stable,
                        g.rho.to_bits()
                    );
                }
            }
        }
        "stiffest" => {
            let s = stiffest(&scene, 2.0).expect("a body with stiffness");
            println!(
                "{} samples, t = {} s, ω_max bits {:016x}",
                s.samples,
                s.time,
                s.omega_max.to_bits()
            );
        }
        "energy" => {
            // The energy looks of the confirmation and usable-dt runs.
            let mut sum = 0.0;
            for _ in 0..20_000 {
                sum += springlab::physics::energy(&body.model, &body.state).total;
            }
            println!("energy sum bits {:016x}", sum.to_bits());
        }
        "blocks" => {
            for body in &scene.bodies {
                let x = &body.state.x;
                let mut distinct = std::collections::HashSet::new();
                for s in body.model.springs() {
                    let d = x[s.b as usize] - x[s.a as usize];
                    let length = d.length();
                    let k = if length == 0.0 {
                        DMat3::ZERO
                    } else {
                        let n = d / length;
                        let nn = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
                        let t = (1.0 - s.rest_length / length).max(0.0);
                        s.stiffness * (nn + t * (DMat3::IDENTITY - nn))
                    };
                    distinct.insert(k.to_cols_array().map(f64::to_bits));
                }
                println!(
                    "{name}: {} springs, {} distinct blocks K_s at the start",
                    body.model.springs().len(),
                    distinct.len()
                );
            }
        }
        _ => {
            eprintln!("usage: study_phases growth|stiffest|energy|blocks [SCENE] [PROBES]");
            std::process::exit(2);
        }
    }
    eprintln!("{what}: {:.3} s", t.elapsed().as_secs_f64());
}
