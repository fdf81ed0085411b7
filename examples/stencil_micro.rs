//! Per-call CPU time of the stencil force loop alone (one thread), for tuning.
use glam::DVec3;
use springlab::bench::{Workload, setup};
use springlab::physics::stencil::Kernel;

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
    // SAFETY: writes one timespec.
    unsafe { clock_gettime(3, &mut t) };
    t.seconds as f64 + t.nanoseconds as f64 * 1e-9
}

fn main() {
    let mut cases: Vec<(String, springlab::Model, springlab::State)> = Vec::new();
    for n in [16usize, 24, 32] {
        let mut b = springlab::scene::builder::Builder::new();
        springlab::scene::lattice::cloth(
            &mut b,
            &springlab::scene::lattice::ClothSpec::w2_cloth(n),
        );
        let (m, s) = b.build(DVec3::ZERO, 0.0);
        cases.push((format!("cloth{n}"), m, s));
    }
    for w in [Workload::JellySe, Workload::Cloth64Se, Workload::Cloth128Se] {
        let (m, s) = setup(w);
        cases.push((w.name().to_string(), m, s));
    }
    let only = std::env::args().nth(1);
    for (name, model, state) in cases {
        if only.as_ref().is_some_and(|o| *o != name) {
            continue;
        }
        for kernel in Kernel::ALL
            .into_iter()
            .filter(|k| k.is_available())
            .rev()
            .take(if std::env::args().nth(1).is_some() {
                1
            } else {
                3
            })
        {
            let st = model.stencil().unwrap().clone().with_kernel(kernel);
            let mut f = vec![DVec3::ZERO; state.len()];
            let calls = 200_000 / state.len().max(1) * 10;
            let mut best = f64::INFINITY;
            for _ in 0..5 {
                let t = cpu();
                for _ in 0..calls {
                    st.add_forces_in_parts(&state.x, &state.v, &mut f, 1);
                }
                best = best.min((cpu() - t) / calls as f64);
            }
            let slots = st.group_count() * state.len();
            println!(
                "{:<12} {:?}: {:8.2} us/call  {:6.2} ns/slot",
                name,
                kernel,
                best * 1e6,
                best * 1e9 / slots as f64
            );
        }
    }
}
