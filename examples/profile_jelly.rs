//! Steps the jelly-se workload for profiling: `perf record target/release/examples/profile_jelly [steps]`.
use springlab::bench::{Run, Workload};

fn main() {
    let steps = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let mut run = Run::new(Workload::JellySe);
    run.advance(steps);
    println!("{:?}", run.checksum());
}
