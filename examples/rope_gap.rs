//! `springlab run` against `springlab bench` on the rope workloads, in one process: thread CPU
//! time per step (ns), min and median of interleaved rounds, of the bench's `Run::advance`, of
//! `Simulation::advance` on the run's scene in pieces as `run` takes them (with and without
//! the energy accounting), of `Method::steps` alone in 512-step calls, and of the bench's and
//! the scene's body without accounting side by side.
//!
//! `cargo run --release --features harness --example rope_gap [rope-se|rope-verlet] [ROUNDS]`
//! (`ONLY_RUN=1`: the accounted run alone, for a profiler; `SCENE_BODY=1`: `Method::steps` on
//! the scene's body instead of the bench's).
use springlab::bench::{Run, Workload};
use springlab::budget::Limits;
use springlab::scene;
use springlab::simulation::Simulation;

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
    unsafe { clock_gettime(3, &mut t) };
    t.seconds as f64 + t.nanoseconds as f64 * 1e-9
}
fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let w = args.get(1).map_or("rope-se", String::as_str);
    let rounds: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(30);
    let rope = "nodes=64 start=[0,1,0] end=[1,1,0] mass=0.015625";
    let (workload, extra, method, dt, steps) = if w == "rope-se" {
        (
            Workload::RopeSe,
            "stiffness=50000 damping=1",
            "semi-implicit-euler",
            1e-4,
            10_000u64,
        )
    } else {
        (
            Workload::RopeVerlet,
            "stiffness=0 iterations=20 verlet_damping=0",
            "verlet",
            1e-3,
            10_000u64,
        )
    };
    let sets: Vec<String> = rope
        .split(' ')
        .chain(extra.split(' '))
        .map(String::from)
        .collect();
    let mut sc = scene::load_with("rope", &sets, &Limits::forced(true)).unwrap();
    sc.set_method(method.parse().unwrap());
    let mut base = Simulation::new(sc);
    base.set_dt(dt);
    let mut bench = Run::new(workload);
    let state0 = bench.state.clone();
    let (mut b, mut on, mut off) = (vec![], vec![], vec![]);
    for _ in 0..rounds {
        if std::env::var_os("ONLY_RUN").is_some() {
            let mut sim = base.clone();
            let mut done = 0;
            while done < steps {
                let piece = (steps - done).min(4 * sim.chunk_steps());
                sim.advance(piece);
                done += piece;
            }
            std::hint::black_box(&sim);
            continue;
        }
        bench.state.clone_from(&state0);
        let t = cpu();
        bench.advance(steps);
        b.push((cpu() - t) / steps as f64 * 1e9);
        for (acc, out) in [(true, &mut on), (false, &mut off)] {
            let mut sim = base.clone();
            if !acc {
                sim.set_accounting(false);
            }
            let t = cpu();
            let mut done = 0;
            while done < steps {
                let piece = (steps - done).min(4 * sim.chunk_steps());
                sim.advance(piece);
                done += piece;
            }
            out.push((cpu() - t) / steps as f64 * 1e9);
            std::hint::black_box(&sim);
        }
    }
    if std::env::var_os("ONLY_RUN").is_some() {
        return;
    }
    // Method::steps alone, with and without accounting, 512-step calls.
    let scene_body = std::env::var("SCENE_BODY").is_ok();
    let (model, st0, params) = if scene_body {
        let b = &base.scene.bodies[0];
        (b.model.clone(), b.state.clone(), b.params)
    } else {
        let (m, s) = springlab::bench::setup(workload);
        (m, s, workload.params())
    };
    let (mut ms_on, mut ms_off) = (vec![], vec![]);
    for _ in 0..rounds {
        for (acc, out) in [(true, &mut ms_on), (false, &mut ms_off)] {
            let mut work = springlab::physics::Workspace::new();
            work.account = acc;
            let mut st = st0.clone();
            let t = cpu();
            let mut done = 0;
            while done < steps {
                let piece = (steps - done).min(512);
                workload
                    .method()
                    .steps(&model, &mut st, dt, &params, &mut work, piece);
                done += piece;
            }
            out.push((cpu() - t) / steps as f64 * 1e9);
            std::hint::black_box(&st);
        }
    }
    let (a, b2) = (stats(ms_on), stats(ms_off));
    println!(
        "  Method::steps(512) acct {:.2}/{:.2}  noacct {:.2}/{:.2}",
        a.0, a.1, b2.0, b2.1
    );
    // Bench set-up against the scene's body, both without accounting, interleaved.
    let b0 = &base.scene.bodies[0];
    let (bmodel, bst, bparams) = (b0.model.clone(), b0.state.clone(), b0.params);
    let (wm, ws) = springlab::bench::setup(workload);
    let wp = workload.params();
    let (mut xs, mut xb) = (vec![], vec![]);
    for _ in 0..rounds {
        for (m, s0, p, out) in [(&wm, &ws, &wp, &mut xb), (&bmodel, &bst, &bparams, &mut xs)] {
            let mut work = springlab::physics::Workspace::new();
            let mut st = s0.clone();
            let t = cpu();
            let mut done = 0;
            while done < steps {
                let piece = (steps - done).min(512);
                workload.method().steps(m, &mut st, dt, p, &mut work, piece);
                done += piece;
            }
            out.push((cpu() - t) / steps as f64 * 1e9);
        }
    }
    let (a, b2) = (stats(xs), stats(xb));
    println!(
        "  noacct scene body {:.2}/{:.2}  bench body {:.2}/{:.2}",
        a.0, a.1, b2.0, b2.1
    );
    let (bm, bd) = stats(b);
    let (nm, nd) = stats(on);
    let (fm, fd) = stats(off);
    println!(
        "{w}: ns/step min/median  bench {bm:.2}/{bd:.2}  run {nm:.2}/{nd:.2} ({:.1}%/{:.1}%)  run-noacct {fm:.2}/{fd:.2} ({:.1}%/{:.1}%)",
        100.0 * bm / nm,
        100.0 * bd / nd,
        100.0 * bm / fm,
        100.0 * bd / fd
    );
}
