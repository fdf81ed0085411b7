//! Results do not depend on the number of threads: 1, 2, 3, 4 and 8 threads (more than this
//! machine's cores: the extra workers oversubscribe it, which changes only the speed) give the
//! same positions and velocities bit for bit on the lattice workloads, with the explicit, RK4
//! and implicit methods.
//!
//! Only one test of this file touches the process-wide pool, on purpose: it sizes the pool
//! through `SPRINGLAB_THREADS` before anything starts it, which no other test may race.

use springlab::bench::{Run, Workload};
use springlab::physics::Method;
use springlab::physics::pool::{MAX_THREADS, Pool, THREADS_ENV, threads_for};

fn bits(s: &springlab::State) -> Vec<u64> {
    s.x.iter()
        .chain(&s.v)
        .flat_map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn lattice_runs_are_bit_identical_for_1_2_3_4_and_8_threads() {
    // SAFETY: the only test of this binary, so no other thread reads the environment now.
    unsafe { std::env::set_var(THREADS_ENV, "8") };
    let pool = Pool::global();
    assert_eq!(pool.threads(), 8, "{THREADS_ENV}=8 sizes the pool");
    let cases = [
        (Workload::JellySe, Method::SemiImplicitEuler, 200),
        (Workload::JellyRk4, Method::Rk4, 60),
        (Workload::Cloth64Se, Method::SemiImplicitEuler, 100),
        (Workload::Cloth64Se, Method::Midpoint, 50),
        (Workload::JellySe, Method::ImplicitEuler, 20),
    ];
    for (w, method, steps) in cases {
        let run = |threads: usize| {
            pool.set_threads(threads);
            let mut r = Run::with_method(w, method);
            r.advance(steps);
            bits(&r.state)
        };
        let one = run(1);
        for threads in [2, 3, 4, 8] {
            assert!(
                run(threads) == one,
                "{w} with {method}: {threads} threads differ from 1"
            );
        }
    }
}

#[test]
fn pool_size_comes_from_the_machine_unless_overridden() {
    assert_eq!(threads_for(None, Some(12)), 12);
    assert_eq!(threads_for(None, None), 1);
    assert_eq!(threads_for(Some(" 3 "), Some(12)), 3);
    assert_eq!(threads_for(Some("1"), Some(12)), 1);
    // Not a whole number ≥ 1: the machine's count.
    assert_eq!(threads_for(Some("0"), Some(4)), 4);
    assert_eq!(threads_for(Some("many"), Some(4)), 4);
    assert_eq!(threads_for(Some("100000"), Some(4)), MAX_THREADS);
    assert_eq!(threads_for(None, Some(1000)), MAX_THREADS);
}
