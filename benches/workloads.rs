//! One step of each peer-benchmark workload (`docs/workloads.md`): the library's integrator plus the
//! workload's contact projection. `springlab bench` times whole runs of N steps and checks the
//! checksums; this measures the per-step cost with criterion's statistics.
//!
//! Run with `cargo bench --bench workloads`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use springlab::bench::{Run, Workload};

fn one_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("workload step");
    for w in Workload::ALL {
        // The state keeps evolving from sample to sample; every workload stays bounded far past
        // its N steps (dt is well inside each method's stability limit), so the cost per step is
        // representative.
        let mut run = Run::new(w);
        group.bench_function(w.name(), |b| {
            b.iter(|| {
                run.step();
                black_box(&run.state);
            });
        });
    }
    group.finish();
}

criterion_group!(benches, one_step);
criterion_main!(benches);
