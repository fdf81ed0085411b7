//! CPU time per call of `accelerations` (stencil and spring list), per semi-implicit Euler
//! step taken one at a time (`Method::step`) and per step of 1000 taken in one call
//! (`Method::steps`, the bench's path) on the 64-node rope of `rope-se`:
//! `cargo run --release --features harness --example rope_micro`. Then the same `Method::steps` on a 16×16 cloth
//! (256 particles, the largest "small" lattice; four offset groups, δ = 1, 15, 16, 17).
use glam::DVec3;
use springlab::bench::{Workload, setup};
use springlab::physics::{Method, MethodParams, SpringKind, Workspace, accelerations};
use springlab::scene::builder::Builder;
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
    let mut b = Builder::new();
    let n = 16i32;
    for r in 0..n {
        for c in 0..n {
            b.particle(
                DVec3::new(f64::from(c) * 0.1, 1.0, f64::from(r) * 0.1),
                0.02,
            );
        }
    }
    b.pinned[0] = true;
    b.pinned[n as usize - 1] = true;
    for (dr, dc) in [(0, 1), (1, 0), (1, 1), (1, -1)] {
        for r in 0..n {
            for c in 0..n {
                let (qr, qc) = (r + dr, c + dc);
                if (0..n).contains(&qr) && (0..n).contains(&qc) {
                    let (p, q) = ((r * n + c) as u32, (qr * n + qc) as u32);
                    b.spring(p, q, 500.0, 0.05, SpringKind::Struct);
                }
            }
        }
    }
    let (cloth, cloth_state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.3);
    for _ in 0..3 {
        let mut s = cloth_state.clone();
        let mut w = Workspace::new();
        let t = cpu();
        for _ in 0..20 {
            Method::SemiImplicitEuler.steps(
                &cloth,
                &mut s,
                1e-4,
                &MethodParams::default(),
                &mut w,
                1000,
            );
        }
        std::hint::black_box(&s);
        println!(
            "16×16 cloth: SE steps(1000) {:.0} ns/step",
            (cpu() - t) / 20_000.0 * 1e9
        );
    }
}
