//! A/B timing of the stencil force loop against the spring list on the peer workloads.
//! `cargo run --release --example stencil_ab`
use std::time::Instant;

use springlab::bench::{Workload, setup};
use springlab::physics::{Method, MethodParams, Workspace};

fn time(model: &springlab::Model, state: &springlab::State, steps: u32, dt: f64) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let mut s = state.clone();
        let mut w = Workspace::new();
        let t = Instant::now();
        for _ in 0..steps {
            Method::SemiImplicitEuler.step(model, &mut s, dt, &MethodParams::default(), &mut w);
        }
        best = best.min(t.elapsed().as_secs_f64() / f64::from(steps));
    }
    best
}

fn main() {
    for w in [
        Workload::JellySe,
        Workload::Cloth64Se,
        Workload::Cloth128Se,
        Workload::RopeSe,
    ] {
        let (model, state) = setup(w);
        let list = model.clone().without_stencil();
        let steps = if w == Workload::RopeSe { 20_000 } else { 300 };
        let a = time(&model, &state, steps, w.dt());
        let b = time(&list, &state, steps, w.dt());
        println!(
            "{:<12} stencil {} : {:>9.0} steps/s   list: {:>9.0} steps/s   ratio {:.2}",
            w.name(),
            model.uses_stencil(),
            1.0 / a,
            1.0 / b,
            b / a
        );
    }
}
