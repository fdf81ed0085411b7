//! CPU time per call of `accelerations` (stencil and spring list), per semi-implicit Euler
//! step taken one at a time (`Method::step`) and per step of 1000 taken in one call
//! (`Method::steps`, the bench's path) on the 64-node rope of `rope-se`:
//! `cargo run --release --example rope_micro`.
use glam::DVec3;
use springlab::bench::{Workload, setup};
use springlab::physics::{Method, MethodParams, Workspace, accelerations};
#[repr(C)]
struct Timespec {
    seconds: i64,
    nanoseconds: i64,
}
unsafe extern "C" {
    fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
}
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
    let (model, state) = setup(Workload::RopeSe);
    let mut a = vec![DVec3::ZERO; 64];
    let n = 200_000;
    for _ in 0..3 {
        let t = cpu();
        for _ in 0..n {
            accelerations(&model, &state.x, &state.v, &mut a);
            std::hint::black_box(&a);
        }
        let acc = (cpu() - t) / n as f64;
        let mut s = state.clone();
        let mut w = Workspace::new();
        let t = cpu();
        for _ in 0..n {
            Method::SemiImplicitEuler.step(&model, &mut s, 1e-4, &MethodParams::default(), &mut w);
        }
        let step = (cpu() - t) / n as f64;
        let list = model.clone().without_stencil();
        let t = cpu();
        for _ in 0..n {
            accelerations(&list, &state.x, &state.v, &mut a);
            std::hint::black_box(&a);
        }
        let accl = (cpu() - t) / n as f64;
        let mut s = state.clone();
        let t = cpu();
        for _ in 0..n / 1000 {
            Method::SemiImplicitEuler.steps(
                &model,
                &mut s,
                1e-4,
                &MethodParams::default(),
                &mut w,
                1000,
            );
        }
        let many = (cpu() - t) / (n / 1000 * 1000) as f64;
        std::hint::black_box(&s);
        println!(
            "accelerations {:.0} ns  (list {:.0} ns)  SE step {:.0} ns  SE steps(1000) {:.0} ns/step",
            acc * 1e9,
            accl * 1e9,
            step * 1e9,
            many * 1e9
        );
    }
}
