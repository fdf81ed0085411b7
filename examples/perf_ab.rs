//! Timing of the peer workloads that survives a busy machine: many short rounds, one and two
//! threads interleaved, reporting the best round (the machine's speed when nothing else ran) and
//! the median, plus the main thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`, Linux x86-64), which
//! time slicing by other processes does not inflate.
//!
//! `cargo run --release --features harness --example perf_ab [workload ...] [--rounds N] [--ms M]`
use std::time::Instant;

use springlab::bench::{Run, Workload, setup};
use springlab::physics::pool::Pool;

#[repr(C)]
struct Timespec {
    seconds: i64,
    nanoseconds: i64,
}

unsafe extern "C" {
    fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
}

/// Nanoseconds this thread has run on a CPU (Linux `CLOCK_THREAD_CPUTIME_ID`).
fn thread_cpu_ns() -> Option<u64> {
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = Timespec {
        seconds: 0,
        nanoseconds: 0,
    };
    // SAFETY: `clock_gettime` writes one `timespec` (two 64-bit fields on x86-64 Linux) to a
    // valid pointer and reads nothing else.
    let ok = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0;
    ok.then(|| t.seconds as u64 * 1_000_000_000 + t.nanoseconds as u64)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut workloads = Vec::new();
    let (mut rounds, mut ms) = (15usize, 20.0f64);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rounds" => rounds = args.next().and_then(|s| s.parse().ok()).expect("N"),
            "--ms" => ms = args.next().and_then(|s| s.parse().ok()).expect("M"),
            w => workloads.push(w.parse::<Workload>().expect("a workload name")),
        }
    }
    if workloads.is_empty() {
        workloads = Workload::ALL.to_vec();
    }
    let pool = Pool::global();
    let most = pool.threads();
    let counts: Vec<usize> = if most > 1 { vec![1, most] } else { vec![1] };
    println!(
        "{:<12} {:>7} {:>12} {:>12} {:>12}   (steps/s; best and median of {rounds} rounds of ~{ms} ms)",
        "workload", "threads", "best", "median", "cpu-best"
    );
    for w in workloads {
        let (model, state) = setup(w);
        // Steps per round: about `ms` milliseconds, from a short calibration.
        let mut run = Run::from_setup(w, model.clone(), state.clone());
        let t = Instant::now();
        run.advance(50);
        let per_step = t.elapsed().as_secs_f64() / 50.0;
        let steps = ((ms * 1e-3 / per_step) as u64).clamp(10, w.steps());
        let mut wall: Vec<Vec<f64>> = vec![Vec::new(); counts.len()];
        let mut cpu: Vec<Vec<f64>> = vec![Vec::new(); counts.len()];
        for _ in 0..rounds {
            for (k, &threads) in counts.iter().enumerate() {
                pool.set_threads(threads);
                run.state.clone_from(&state);
                let c0 = thread_cpu_ns();
                let t = Instant::now();
                run.advance(steps);
                wall[k].push(t.elapsed().as_secs_f64() / steps as f64);
                if let (Some(a), Some(b)) = (c0, thread_cpu_ns()) {
                    cpu[k].push((b - a) as f64 * 1e-9 / steps as f64);
                }
            }
        }
        pool.set_threads(most);
        for (k, &threads) in counts.iter().enumerate() {
            let best = wall[k].iter().copied().fold(f64::INFINITY, f64::min);
            let cpu_best = cpu[k].iter().copied().fold(f64::INFINITY, f64::min);
            println!(
                "{:<12} {:>7} {:>12.0} {:>12.0} {:>12.0}",
                w.name(),
                threads,
                1.0 / best,
                1.0 / median(wall[k].clone()),
                1.0 / cpu_best
            );
        }
    }
}
