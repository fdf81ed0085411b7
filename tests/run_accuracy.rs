//! `run` flags a run that stayed bounded but created more energy than the scene has (issue 26):
//! the report's `not_accurate` holds the residual when `|E + D - E₀| > |E₀|`.
//!
//! The truth: on the undamped rope (E₀ ≈ 60 J) RK4 is linearly stable only up to
//! `dt ω_max = 2√2` (its stability function `1 + z + z²/2 + z³/6 + z⁴/24` has modulus 1 on the
//! imaginary axis at `|z| = 2√2`), `ω_max` the rope's highest frequency at rest. Just above that
//! limit the stiff mode grows until the nonlinearity saturates it: the run never diverges, yet its
//! energy ends orders of magnitude above E₀. Well below the limit RK4's residual is a tiny
//! fraction of E₀.

use springlab::Method;
use springlab::scene;
use springlab::simulation::Simulation;
use springlab::study::modes::omega_max;

/// RK4 on `rope` at `dt` for 100 s: the report.
fn rope_rk4(dt_of_limit: f64) -> springlab::simulation::RunReport {
    let mut scene = scene::load("rope", &[]).expect("built-in");
    scene.set_method(Method::Rk4);
    let body = &scene.bodies[0];
    let omega = omega_max(&body.model, &body.state).omega;
    let limit = 2.0 * 2f64.sqrt() / omega;
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt_of_limit * limit);
    sim.set_accounting(true);
    let steps = (100.0 / sim.dt()).round() as u64;
    sim.run(steps, |_| {});
    sim.report(0.0)
}

#[test]
fn rope_just_above_rk4s_linear_limit_is_bounded_but_not_accurate() {
    let r = rope_rk4(1.05);
    assert!(
        r.diverged.is_none(),
        "expected a bounded run: {:?}",
        r.diverged
    );
    let created = r.not_accurate.expect("flagged as not accurate");
    assert!(
        created.abs() > r.energy_initial.abs(),
        "{created} J against E0 {} J",
        r.energy_initial
    );
}

#[test]
fn rope_well_below_the_limit_is_not_flagged() {
    let r = rope_rk4(0.25);
    assert!(r.diverged.is_none());
    assert_eq!(r.not_accurate, None, "residual {:?}", r.residual);
}
