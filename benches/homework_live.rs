//! The cost of the process boundary in `springlab lesson N --homework`: one step of the
//! comparison (the reference's step, the student's step, the measurements) per lesson body and
//! method, with the student's integrator
//!
//! - `in-process`: springlab's own answers in this process (no boundary: the floor),
//! - `single`: a homework crate's program, one request per step (protocol version 2's way),
//! - `batched`: the same program, up to 64 steps per request (`wire`'s STEPS).
//!
//! Each step of `single` and `batched` also crosses the boundary twice per `Physics` request
//! (one for the Euler methods, two for midpoint, four for RK4). The crates are the correct
//! solutions of `tests/homework/`, built through the grader (sandbox, cache by content).
//! Real time is one step per `dt`: 15.6 ms for the ropes (dt = 1/64 s), 1 ms for the jelly.
//!
//! `cargo bench --bench homework_live -- --warm-up-time 1 --measurement-time 3 jelly`.
//! Compare within one run (ratios): the machine is shared.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
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

fn setup(assignment: Assignment, number: u32, step: usize, method: Option<Method>) -> Setup {
    let l = lesson::builtin()
        .into_iter()
        .map(|l| l.expect("lesson parses"))
        .find(|l| l.number == number)
        .expect("lesson exists");
    let mut scene = l.steps[step - 1].build_scene().expect("scene");
    if let Some(m) = method {
        scene.set_method(m);
    }
    Setup::from_scene(assignment, number, &scene, 0.0).expect("setup")
}

/// Time of `steps` steps of the comparison, run free, in runs of at most 256 steps from the
/// step's start (explicit Euler's rope blows up after a few thousand).
fn run(homework: &Homework, setup: &Setup, steps: u64, ahead: u32) -> Duration {
    let options = LiveOptions {
        frame_every: 64,
        ahead,
        ..LiveOptions::default()
    };
    let mut left = steps;
    let start = Instant::now();
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
    start.elapsed()
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
    for (name, program, s) in cases {
        let mut group = c.benchmark_group(format!("homework step/{name}"));
        group.sample_size(10);
        let own = Homework::reference(s.assignment);
        group.bench_function("in-process", |bench| {
            bench.iter_custom(|iters| run(&own, &s, iters, 1));
        });
        group.bench_function("single", |bench| {
            bench.iter_custom(|iters| run(program, &s, iters, 1));
        });
        group.bench_function("batched", |bench| {
            bench.iter_custom(|iters| run(program, &s, iters, 64));
        });
        group.finish();
    }
}

criterion_group!(benches, boundary);
criterion_main!(benches);
