//! One step of every method on the jelly cube (`jelly-se`'s set-up: 1 000 particles, 12 876
//! springs, dt = 1e-4 s) and on the 128×128 cloth (`cloth128-se`'s: 16 384 particles, 97 026
//! springs, dt = 2.5e-5 s), each with the workload's contact rule (see `docs/workloads.md`).
//!
//! `cargo bench -p springlab-benches --bench methods` (or `-- jelly` for one workload). The workload's own method
//! runs with its own parameters; the other methods as `springlab bench` times them
//! ([`Run::with_method`]: Verlet without projection, XPBD with its default substeps). Compare
//! the methods within one run (ratios), not across runs: the machine is shared.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use springlab::bench::{self, Run, Workload};

fn step_every_method(c: &mut Criterion) {
    for w in [Workload::JellySe, Workload::Cloth128Se] {
        let name = if w == Workload::JellySe {
            "jelly"
        } else {
            "cloth128"
        };
        let mut group = c.benchmark_group(format!("method step/{name}"));
        if w == Workload::Cloth128Se {
            // One cloth step takes 0.1–10 ms: fewer samples keep the run to minutes.
            group
                .sample_size(20)
                .measurement_time(Duration::from_secs(4));
        }
        for method in bench::methods_for(w) {
            // The state keeps evolving from sample to sample; every method is stable at the
            // workload's dt for far longer than the samples take (checked by `springlab bench`,
            // which reports any divergence), so the cost per step is representative.
            let mut run = Run::with_method(w, method);
            group.bench_function(BenchmarkId::from_parameter(method.name()), |b| {
                b.iter(|| {
                    run.step();
                    black_box(&run.state);
                });
            });
        }
        group.finish();
    }
}

criterion_group!(benches, step_every_method);
criterion_main!(benches);
