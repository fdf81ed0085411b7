//! A method of your own outside the registry: semi-implicit (symplectic) Euler written from its
//! formula with the crate's one derivative function, stepped beside the registry's
//! `Method::SemiImplicitEuler` on the oscillator; the two should agree to the last bit.
//!
//! ```text
//! v_{n+1} = v_n + dt a(x_n, v_n)
//! x_{n+1} = x_n + dt v_{n+1}
//! ```
//! where `x` is in m, `v` in m/s, `a` in m/s² and `dt` in s.
//!
//! `cargo run --release --example custom_method`

// Index loops read like the formula (x_i, v_i, a_i), as in the crate's own integrators.
#![allow(clippy::needless_range_loop)]

use glam::DVec3;
use springlab::physics::{Method, MethodParams, Model, State, Workspace, accelerations};

/// One step of the formula above; `a` is scratch of the particle count.
fn my_step(model: &Model, state: &mut State, dt: f64, a: &mut [DVec3]) {
    accelerations(model, &state.x, &state.v, a);
    for i in 0..state.x.len() {
        state.v[i] += dt * a[i];
        state.x[i] += dt * state.v[i];
    }
}

fn main() {
    let scene = springlab::scene::load("oscillator", &[]).expect("a built-in scene");
    let body = &scene.bodies[0];
    let (model, dt) = (&body.model, scene.dt);
    let mut mine = body.state.clone();
    let mut theirs = body.state.clone();
    let mut a = vec![DVec3::ZERO; mine.x.len()];
    let mut work = Workspace::new();
    for _ in 0..1000 {
        my_step(model, &mut mine, dt, &mut a);
        Method::SemiImplicitEuler.step(model, &mut theirs, dt, &MethodParams::default(), &mut work);
    }
    let gap = mine
        .x
        .iter()
        .zip(&theirs.x)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
    println!(
        "after 1000 steps of {dt} s: my x = {:?}, the registry's x = {:?}, largest gap {gap:e} m",
        mine.x[1], theirs.x[1]
    );
}
