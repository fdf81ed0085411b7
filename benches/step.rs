//! One step of every method on the oscillator and on ropes of 3 and 64 nodes.
//!
//! `cargo bench -p springlab-benches --bench step`. Compare methods within one run (ratios), not across runs: the
//! machine is shared.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use springlab::physics::{Method, Workspace};
use springlab::scene;

fn step_every_method(c: &mut Criterion) {
    let scenes: [(&str, &str, Vec<String>); 3] = [
        ("oscillator", "oscillator", vec![]),
        ("rope-3", "rope", vec![]),
        (
            "rope-64",
            "rope",
            vec!["nodes=64".into(), "stiffness=5000".into()],
        ),
    ];
    for (label, name, sets) in scenes {
        let mut group = c.benchmark_group(format!("step/{label}"));
        for method in Method::ALL {
            let scene = scene::load(name, &sets).expect("built-in scene");
            let body = scene.bodies.into_iter().next().expect("one body");
            let (model, mut state, params) = (body.model, body.state, body.params);
            let mut work = Workspace::new();
            let dt = 1e-4;
            group.bench_function(BenchmarkId::from_parameter(method.name()), |b| {
                b.iter(|| method.step(&model, &mut state, dt, &params, &mut work));
            });
        }
        group.finish();
    }
}

criterion_group!(benches, step_every_method);
criterion_main!(benches);
