//! Time per call of the stencil force loop alone: CPU time on one thread, and the best wall
//! time over many calls with the work split into 1 and 2 parts (threads), for tuning.
//!
//! `cargo run --release --features harness --example stencil_micro [case]`, cases: cloth16, cloth24, cloth32 and
//! the lattice workloads.
use std::time::Instant;

use glam::DVec3;
use springlab::bench::{Workload, setup};
use springlab::physics::stencil::Kernel;
use springlab::scene::builder::Builder;
use springlab::scene::lattice::{ClothSpec, cloth};

#[repr(C)]
struct Timespec {
    seconds: i64,
    nanoseconds: i64,
}

unsafe extern "C" {
    fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
}

/// Seconds this thread has run on a CPU (Linux `CLOCK_THREAD_CPUTIME_ID`).
fn cpu() -> f64 {
    let mut t = Timespec {
        seconds: 0,
        nanoseconds: 0,
    };
    // SAFETY: `clock_gettime` writes one timespec to a valid pointer.
    unsafe { clock_gettime(3, &mut t) };
    t.seconds as f64 + t.nanoseconds as f64 * 1e-9
}

fn main() {
    let only = std::env::args().nth(1);
    let mut cases: Vec<(String, springlab::Model, springlab::State)> = Vec::new();
    for n in [16usize, 24, 32] {
        let mut b = Builder::new();
        cloth(&mut b, &ClothSpec::w2_cloth(n));
        let (m, s) = b.build(DVec3::ZERO, 0.0);
        cases.push((format!("cloth{n}"), m, s));
    }
    for w in [
        Workload::JellySe,
        Workload::Cloth64Se,
        Workload::Cloth128Se,
        Workload::RopeSe,
    ] {
        let (m, s) = setup(w);
        cases.push((w.name().to_string(), m, s));
    }
    println!("case         kernel    cpu/call(1 part)  best wall/call: 1 part   2 parts");
    for (name, model, state) in cases {
        if only.as_ref().is_some_and(|o| *o != name) {
            continue;
        }
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()).rev() {
            let st = model
                .stencil()
                .expect("a lattice")
                .clone()
                .with_kernel(kernel);
            let mut f = vec![DVec3::ZERO; state.len()];
            let calls = (2_000_000 / state.len()).clamp(10, 100_000);
            let mut cpu_best = f64::INFINITY;
            let mut wall = [f64::INFINITY; 2];
            for _ in 0..5 {
                let t = cpu();
                for _ in 0..calls {
                    st.add_forces_in_parts(&state.x, &state.v, &mut f, 1);
                }
                cpu_best = cpu_best.min((cpu() - t) / calls as f64);
                for (parts, best) in wall.iter_mut().enumerate() {
                    for _ in 0..calls {
                        let t = Instant::now();
                        st.add_forces_in_parts(&state.x, &state.v, &mut f, parts + 1);
                        *best = best.min(t.elapsed().as_secs_f64());
                    }
                }
            }
            println!(
                "{name:<12} {:<9} {:>10.2} us {:>18.2} us {:>9.2} us",
                format!("{kernel:?}"),
                cpu_best * 1e6,
                wall[0] * 1e6,
                wall[1] * 1e6
            );
        }
    }
}
