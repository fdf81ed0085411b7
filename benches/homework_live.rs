//! The cost of `springlab lesson N --homework`: CPU time per simulated second of the comparison
//! (the reference's step, the student's step, the measurements) per lesson body and method,
//! against the real-time budget of one second, with the student's integrator
//!
//! - `in-process`: springlab's own answers in this process (no boundary: the floor),
//! - `single`: a homework crate's program, one request per step (protocol version 2's way),
//! - `batched`: the same program with the app's settings (`LiveOptions::default()`: up to 64
//!   steps per request, `wire`'s STEPS).
//!
//! Each step of `single` and `batched` also crosses the boundary twice per `Physics` request
//! (one for the Euler methods, two for midpoint, four for RK4). The crates are the correct
//! solutions of `tests/homework/`, built through the grader (sandbox, cache by content).
//!
//! What is timed is CPU time, not wall time: this process's (every thread, `getrusage`) plus
//! the student's program's (`/proc/PID/schedstat` of this process's descendants, Linux; 0
//! elsewhere), so that a loaded machine does not inflate it. Criterion's "time" is the CPU time
//! of one step; after each group one line gives the CPU seconds per simulated second of each
//! variant (one simulated second run free from the step's start): real time needs it well
//! below 1, beside the lesson's own simulation and drawing; the wall time of that second
//! beside it (run free, on an otherwise idle machine: below 1 s keeps up with the lesson). dt is 1/64 s for the ropes (64 steps
//! per simulated second) and 1 ms for the jelly (1000).
//!
//! `cargo bench -p springlab-benches --bench homework_live -- --warm-up-time 1 --measurement-time 3 jelly`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use nix::sys::resource::{UsageWho, getrusage};
use springlab::grade::Assignment;
use springlab::grade::build::Builder;
use springlab::grade::homework::new_homework;
use springlab::grade::live::{
    BuildOptions, Homework, Live, LiveOptions, Setup, build_homework, builder,
};
use springlab::lesson;
use springlab::physics::Method;

const ROPE: &str = include_str!("../tests/homework/rope.rs");
const JELLY: &str = include_str!("../tests/homework/jelly.rs");
const INTEGRATORS: &str = include_str!("../tests/homework/integrators.rs");

fn options(target: &Path) -> BuildOptions {
    BuildOptions {
        target_dir: target.to_path_buf(),
        call_limit: Duration::from_secs(10),
    }
}

/// A correct crate of `assignment` in `parent/name`, built.
fn built(parent: &Path, b: &Arc<Builder>, assignment: Assignment, lib: &str) -> Homework {
    let dir = parent.join(assignment.name());
    let _ = std::fs::remove_dir_all(&dir);
    new_homework(&dir, assignment).expect("crate written");
    std::fs::write(dir.join("src/lib.rs"), lib).expect("lib.rs");
    std::fs::write(dir.join("src/integrators.rs"), INTEGRATORS).expect("integrators.rs");
    build_homework(&dir, b, &options(parent))
        .expect("builds")
        .homework
}

/// The scene of step `step` of lesson `number`.
fn lesson_scene(number: u32, step: usize) -> springlab::scene::Scene {
    let l = lesson::builtin()
        .into_iter()
        .map(|l| l.expect("lesson parses"))
        .find(|l| l.number == number)
        .expect("lesson exists");
    l.steps[step - 1].build_scene().expect("scene")
}

fn setup(assignment: Assignment, number: u32, step: usize, method: Option<Method>) -> Setup {
    let mut scene = lesson_scene(number, step);
    if let Some(m) = method {
        scene.set_method(m);
    }
    Setup::from_scene(assignment, number, &scene, 0.0).expect("setup")
}

/// CPU time of this process (every thread, those that ended too) and of its descendants (the
/// student's program and its sandbox), in ns.
fn cpu_ns() -> u128 {
    let own = getrusage(UsageWho::RUSAGE_SELF).map_or(0, |u| {
        let t = |v: nix::sys::time::TimeVal| {
            u128::try_from(v.tv_sec()).unwrap_or(0) * 1_000_000_000
                + u128::try_from(v.tv_usec()).unwrap_or(0) * 1000
        };
        t(u.user_time()) + t(u.system_time())
    });
    own + descendants_ns()
}

/// Σ of the CPU time (ns, `/proc/PID/schedstat`, the main thread: the student's program has
/// no other) of every process below this one.
fn descendants_ns() -> u128 {
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return 0;
    };
    // (pid, parent, ns)
    let procs: Vec<(u32, u32, u128)> = dir
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter_map(|pid| {
            let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
            // The fields after the command name: state, ppid, …
            let rest = &stat[stat.rfind(')')? + 2..];
            let ppid = rest.split(' ').nth(1)?.parse().ok()?;
            let sched = std::fs::read_to_string(format!("/proc/{pid}/schedstat")).ok()?;
            let ns = sched.split(' ').next()?.parse().ok()?;
            Some((pid, ppid, ns))
        })
        .collect();
    let mut below = vec![std::process::id()];
    let mut total = 0;
    let mut i = 0;
    while i < below.len() {
        for &(pid, parent, ns) in &procs {
            if parent == below[i] {
                below.push(pid);
                total += ns;
            }
        }
        i += 1;
    }
    total
}

/// CPU time of `steps` steps of the comparison, run free, in runs of at most 256 steps from
/// the step's start (explicit Euler's rope blows up after a few thousand).
fn run(homework: &Homework, setup: &Setup, steps: u64, options: LiveOptions) -> Duration {
    timed(homework, setup, steps, options).0
}

/// [`run`]'s CPU time and its wall time.
fn timed(
    homework: &Homework,
    setup: &Setup,
    steps: u64,
    options: LiveOptions,
) -> (Duration, Duration) {
    let mut left = steps;
    let wall = std::time::Instant::now();
    let start = cpu_ns();
    while left > 0 {
        let setup = Setup {
            horizon: left.min(256),
            ..setup.clone()
        };
        left -= setup.horizon;
        let live = Live::start(homework.clone(), setup, options);
        live.run_free();
        while let Some(frame) = live.next_frame(Duration::from_secs(600)) {
            assert_eq!(frame.failure, None);
            if frame.finished {
                break;
            }
        }
    }
    let ns = cpu_ns().saturating_sub(start);
    (
        Duration::from_nanos(u64::try_from(ns).unwrap_or(u64::MAX)),
        wall.elapsed(),
    )
}

fn boundary(c: &mut Criterion) {
    let parent = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-homework-live");
    std::fs::create_dir_all(&parent).expect("scratch");
    let b = builder(&options(&parent)).expect("builder");
    let rope = built(&parent, &b, Assignment::Rope, ROPE);
    let jelly = built(&parent, &b, Assignment::Jelly, JELLY);
    let cases = [
        (
            "rope/lesson1 semi_implicit",
            &rope,
            setup(Assignment::Rope, 1, 1, None),
        ),
        (
            "rope/lesson3 explicit",
            &rope,
            setup(Assignment::Rope, 3, 3, None),
        ),
        (
            "rope/lesson4 verlet",
            &rope,
            setup(Assignment::Rope, 4, 3, None),
        ),
        (
            "jelly/lesson5 explicit",
            &jelly,
            setup(Assignment::Jelly, 5, 5, Some(Method::ExplicitEuler)),
        ),
        (
            "jelly/lesson5 midpoint",
            &jelly,
            setup(Assignment::Jelly, 5, 5, Some(Method::Midpoint)),
        ),
        (
            "jelly/lesson5 rk4",
            &jelly,
            setup(Assignment::Jelly, 5, 5, Some(Method::Rk4)),
        ),
    ];
    let single = LiveOptions {
        ahead: 1,
        ..LiveOptions::default()
    };
    for (name, program, s) in cases {
        let mut group = c.benchmark_group(format!("homework step/{name}"));
        group.sample_size(10);
        let own = Homework::reference(s.assignment);
        let variants = [
            ("in-process", &own, single),
            ("single", program, single),
            ("batched", program, LiveOptions::default()),
        ];
        // The variants the command line's filter let run.
        let mut measured = Vec::new();
        for (variant, homework, options) in variants {
            group.bench_function(variant, |bench| {
                if !measured.contains(&variant) {
                    measured.push(variant);
                }
                bench.iter_custom(|iters| run(homework, &s, iters, options));
            });
        }
        group.finish();
        // One simulated second from the step's start, each way measured.
        let second = (1.0 / s.dt).round() as u64;
        let line: Vec<String> = variants
            .iter()
            .filter(|(variant, ..)| measured.contains(variant))
            .map(|(variant, homework, options)| {
                let (cpu, wall) = timed(homework, &s, second, *options);
                format!(
                    "{variant} {:.3} (wall {:.3} s)",
                    cpu.as_secs_f64(),
                    wall.as_secs_f64()
                )
            })
            .collect();
        if !line.is_empty() {
            println!(
                "homework step/{name}: CPU s per simulated s (budget 1): {}",
                line.join(", ")
            );
        }
    }
}

/// CPU seconds (per thread name, from `/proc/self/task`; "program" for the student's program)
/// since `before`.
fn threads_cpu() -> Vec<(String, f64)> {
    let tick = 100.0; // USER_HZ on Linux
    let mut out: Vec<(String, f64)> = Vec::new();
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return out;
    };
    for e in dir.flatten() {
        let path = e.path();
        let Ok(stat) = std::fs::read_to_string(path.join("stat")) else {
            continue;
        };
        let Some(close) = stat.rfind(')') else {
            continue;
        };
        let name = stat[stat.find('(').map_or(0, |i| i + 1)..close].to_string();
        let fields: Vec<&str> = stat[close + 2..].split(' ').collect();
        let ticks: f64 = fields.get(11).and_then(|u| u.parse().ok()).unwrap_or(0.0)
            + fields.get(12).and_then(|u| u.parse().ok()).unwrap_or(0.0);
        match out.iter_mut().find(|(n, _)| *n == name) {
            Some((_, t)) => *t += ticks / tick,
            None => out.push((name, ticks / tick)),
        }
    }
    out.push(("program".to_string(), descendants_ns() as f64 * 1e-9));
    out
}

/// The app's way: the lesson's own simulation of the step's scene, stepped a frame of
/// `per_frame` steps at a time on this thread (with its pool, or alone), each step offered to
/// the comparison's reference (`Live::handover`), the comparison then let advance to it; the
/// CPU seconds per simulated second of each thread over `seconds`, and the steps the reference
/// took from the lesson.
fn beside_lesson(
    homework: &Homework,
    number: u32,
    step: usize,
    method: Method,
    seconds: f64,
    alone: bool,
) -> (Vec<(String, f64)>, u64, u64) {
    let mut scene = lesson_scene(number, step);
    scene.set_method(method);
    let setup = Setup::from_scene(homework.assignment(), number, &scene, 0.0).expect("setup");
    let steps = (seconds / setup.dt).round() as u64;
    let mut sim = springlab::simulation::Simulation::new(scene);
    let live = Live::start(homework.clone(), setup, LiveOptions::default());
    let handover = live.handover();
    let before = threads_cpu();
    let per_frame = 32;
    let mut behind = 0;
    while sim.steps < steps {
        let mut frame = || {
            for _ in 0..per_frame {
                sim.step();
                if let Some(h) = &handover {
                    h.offer(&sim, 0);
                }
            }
        };
        if alone {
            springlab::physics::pool::alone(frame);
        } else {
            frame();
        }
        live.advance_to(sim.steps);
        if let Some(f) = live.drain().last() {
            behind = sim.steps - f.step;
        }
    }
    while let Some(f) = live.next_frame(Duration::from_secs(600)) {
        if f.step >= steps {
            break;
        }
    }
    let after = threads_cpu();
    let taken = handover.as_ref().map_or(0, |h| h.taken());
    let per_second: Vec<(String, f64)> = after
        .into_iter()
        .map(|(name, t)| {
            let t0 = before
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0.0, |(_, t)| *t);
            (name, (t - t0) / seconds)
        })
        .filter(|(_, t)| *t > 0.0)
        .collect();
    (per_second, taken, behind)
}

/// Lesson 5 step 5's jelly, each explicit method, beside the lesson's own simulation (the
/// app's way, its reference taking the lesson's steps): CPU seconds per simulated second by
/// thread, the lesson's simulation with its pool and alone.
fn lesson_beside(c: &mut Criterion) {
    let mut group = c.benchmark_group("beside the lesson");
    let mut wanted = false;
    group.bench_function("jelly", |bench| {
        wanted = true;
        bench.iter(|| 0);
    });
    group.finish();
    if !wanted {
        return;
    }
    let parent = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-homework-live");
    std::fs::create_dir_all(&parent).expect("scratch");
    let b = builder(&options(&parent)).expect("builder");
    let jelly = built(&parent, &b, Assignment::Jelly, JELLY);
    for method in [Method::ExplicitEuler, Method::Midpoint, Method::Rk4] {
        for alone in [false, true] {
            let (threads, taken, behind) = beside_lesson(&jelly, 5, 5, method, 3.0, alone);
            let total: f64 = threads.iter().map(|(_, t)| t).sum();
            let split: Vec<String> = threads.iter().map(|(n, t)| format!("{n} {t:.3}")).collect();
            println!(
                "beside the lesson/jelly {} (lesson {}): CPU s per simulated s {total:.3} = {}; \
                 {taken} steps taken from the lesson, {behind} behind",
                method.declaration().name,
                if alone { "alone" } else { "with its pool" },
                split.join(", ")
            );
        }
    }
}

criterion_group!(benches, boundary, lesson_beside);
criterion_main!(benches);
