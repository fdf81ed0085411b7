//! Why a scene with impacts is stable only a little below the damped theory at rest: runs the
//! scene to time `T` (the squeezed state of an impact), then measures the growth rate of
//! perturbations of the step map linearised there (contacts excluded, as in the study's linear
//! test) at each dt, beside the same at the initial state at rest.
//!
//! `cargo run --release --features harness --example squeezed_linearisation -- jelly-bowl rk4 2.5e-3 1.6425 \
//!  2.45e-3,2.65e-3,2.75e-3,2.84e-3`
//!
//! A rate that is the same at every dt is the motion's own (the squeezed lattice is not an
//! equilibrium); one that rises with dt is the method's instability there.
use springlab::physics::Method;
use springlab::simulation::Simulation;
use springlab::study::linear::Linearisation;
use springlab::study::stability::load_scene;
use springlab::study::{modes, theory};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 5 {
        eprintln!("usage: squeezed_linearisation SCENE METHOD RUN_DT TIME DT,DT,...");
        std::process::exit(2);
    }
    let parse = |s: &str| -> f64 { s.parse().unwrap_or_else(|_| panic!("not a number: {s}")) };
    let method: Method = a[1].parse().expect("a method");
    let (run_dt, time) = (parse(&a[2]), parse(&a[3]));
    let dts: Vec<f64> = a[4].split(',').map(parse).collect();
    let (scene, _) = load_scene(&a[0], &[]).expect("a scene");
    let rest = scene.bodies[0].clone();
    let mut scene_run = scene;
    scene_run.set_method(method);
    let mut sim = Simulation::new(scene_run);
    sim.set_dt(run_dt);
    sim.set_accounting(false);
    sim.run((time / run_dt).round() as u64, |_| {});
    let squeezed = &sim.scene.bodies[0];
    for (what, body) in [("at rest", &rest), ("squeezed", squeezed)] {
        let omega = modes::omega_max(&body.model, &body.state).omega;
        let spectrum = theory::spectrum(&body.model, &body.state, omega);
        let limit = theory::limit(method, &body.params, &spectrum);
        println!(
            "{what} (t = {:.4} s): ω_max = {omega:.3} rad/s, damped theory {:?} s",
            if what == "at rest" { 0.0 } else { sim.time() },
            limit.dt
        );
        let lin = Linearisation::new(&body.model, &body.state, omega);
        for &dt in &dts {
            let g = lin.growth(method, &body.params, dt, 4000);
            println!(
                "  dt {dt:.4e} s: ρ = {:.6} per step, rate ln ρ / dt = {:+.1} 1/s ({})",
                g.rho,
                g.rho.ln() / dt,
                g.stopped
            );
        }
    }
}
