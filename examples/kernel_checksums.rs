//! Checksums of the lattice workloads with every stencil kernel this CPU has, and their largest
//! relative deviation from the C++ reference: `cargo run --release --features harness --example kernel_checksums`.
use springlab::bench::{Run, Workload, setup};
use springlab::physics::stencil::Kernel;

fn main() {
    for w in [
        Workload::JellySe,
        Workload::JellyRk4,
        Workload::Cloth64Se,
        Workload::Cloth128Se,
        Workload::RopeSe,
    ] {
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let (model, state) = setup(w);
            let mut run = Run::from_setup(w, model.with_kernel(kernel), state);
            run.advance(w.steps());
            let c = run.checksum();
            println!(
                "{:<12} {:<9} cy {:.15} E {:.12}  deviation {:.2e}",
                w.name(),
                format!("{kernel:?}"),
                c.centroid[1],
                c.energy,
                c.max_relative_deviation(&w.reference())
            );
        }
    }
}
