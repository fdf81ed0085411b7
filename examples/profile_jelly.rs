//! Steps the jelly-se workload for profiling: `perf record target/release/examples/profile_jelly`.
use springlab::bench::{Workload, setup};
use springlab::physics::{Method, MethodParams, Workspace};

fn main() {
    let (model, mut state) = setup(Workload::JellySe);
    let mut w = Workspace::new();
    for _ in 0..20_000 {
        Method::SemiImplicitEuler.step(&model, &mut state, 1e-4, &MethodParams::default(), &mut w);
    }
    println!("{}", state.centroid());
}
