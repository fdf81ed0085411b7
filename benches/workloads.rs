//! One step of each peer-benchmark workload (`docs/workloads.md`): the library's integrator plus the
//! workload's contact projection. `springlab bench` times whole runs of N steps and checks the
//! checksums; this measures the per-step cost with criterion's statistics.
//!
//! Also the spring kernels' ceiling on data in the first-level cache (`kernel_ceiling`).
//!
//! Run with `cargo bench -p springlab-benches --bench workloads`.

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

/// A hundred steps of each workload in one [`Run::advance`] call, as `springlab bench` takes
/// them (`Method::steps`): semi-implicit Euler on the rope keeps the particles in the stencil's
/// layout between the steps, and semi-implicit Euler and RK4 on the jelly and the cloths run the
/// hundred steps as one team of threads (`stencil/team.rs`), so this is less than a hundred
/// times one step.
fn hundred_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("workload 100 steps");
    for w in Workload::ALL {
        let mut run = Run::new(w);
        group.bench_function(w.name(), |b| {
            b.iter(|| {
                run.advance(100);
                black_box(&run.state);
            });
        });
    }
    group.finish();
}

/// The ceiling of the streaming loop (`crates/core/src/physics/fast/stencil/ceiling.rs`): a thousand chunks of
/// eight springs with each kernel this CPU has, operands in the first-level cache. 8 000 springs
/// over the time per iteration is the kernel's springs per second on one thread.
fn kernel_ceiling(c: &mut Criterion) {
    use springlab::physics::stencil::{Kernel, ceiling::Rope};
    let mut group = c.benchmark_group("spring kernel, 8000 springs");
    let rope = Rope::default();
    for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
        group.bench_function(format!("{kernel:?}"), |b| {
            b.iter(|| black_box(rope.evaluate(kernel, 1000)));
        });
    }
    group.finish();
}

criterion_group!(benches, one_step, hundred_steps, kernel_ceiling);
criterion_main!(benches);
