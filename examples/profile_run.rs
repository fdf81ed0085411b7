//! Steps one workload for profiling:
//! `cargo build --release --features harness --example profile_run`, then
//! `perf record target/release/examples/profile_run <workload> [steps]`.
use springlab::bench::{Run, Workload};

fn main() {
    let mut args = std::env::args().skip(1);
    let workload: Workload = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(Workload::JellySe);
    let steps = args.next().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let mut run = Run::new(workload);
    run.advance(steps);
    println!("{:?}", run.checksum());
}
