//! Helpers shared by the integration tests.
#![allow(dead_code)]

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;

/// A small deterministic pseudo-random generator (xorshift64*), so tests need no dependency.
pub struct Rng(pub u64);

impl Rng {
    /// A float in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
        lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
    }
}

/// The oscillator scene (ω = 10 rad/s) with `method`, `amplitude` and extra `--set`s.
pub fn oscillator(method: Method, sets: &[&str]) -> Simulation {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut scene = scene::load("oscillator", &sets).expect("built-in oscillator");
    scene.set_method(method);
    Simulation::new(scene)
}

/// Position x of the oscillator's moving particle.
pub fn oscillator_x(sim: &Simulation) -> f64 {
    sim.scene.bodies[0].state.x[1].x
}

/// Least-squares slope of log(error) against log(dt).
pub fn fitted_order(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(dt, e)| (dt.ln(), e.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// Runs this build's `springlab` binary with `args`.
pub fn springlab(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .output()
        .expect("run springlab")
}

/// `springlab args…`, which must succeed, and the one JSON object it prints.
pub fn json(args: &[&str]) -> serde_json::Value {
    let out = springlab(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The first place `needle` occurs in `hay`.
pub fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Waits until `ready()` holds; a hang guard, not a timing assertion.
pub fn wait_for(what: &str, mut ready: impl FnMut() -> bool) {
    let start = std::time::Instant::now();
    while !ready() {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(300),
            "never happened: {what}"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// `springlab args…` with `SPRINGLAB_THREADS=threads`: its JSON.
pub fn json_on_threads(args: &[&str], threads: &str) -> serde_json::Value {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .env("SPRINGLAB_THREADS", threads)
        .output()
        .expect("run springlab");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The built-in `jelly-bowl`'s bowl: its radius (m) and the height of its centre (m).
pub fn jelly_bowl() -> (f64, f64) {
    use springlab::physics::collide::Collider;
    let jelly = scene::load("jelly-bowl", &[]).expect("jelly");
    jelly.bodies[0]
        .model
        .colliders
        .iter()
        .find_map(|c| match c {
            Collider::Bowl { radius, center, .. } => Some((*radius, center.y)),
            _ => None,
        })
        .expect("a bowl")
}

/// One test per built-in lesson: `per_lesson!(module, check, [name: "slug", …])` (or `every`,
/// all of them) makes a module `module` holding, for each lesson, a test `name` that calls
/// `super::check("slug")`, and `module::SLUGS`, the slugs in that order. A long check over every lesson becomes one test per
/// lesson, so that the test threads share the lessons instead of one thread playing them all;
/// each file compares its lists with [`lesson_slugs`] (a new lesson cannot be left out).
macro_rules! per_lesson {
    // Every built-in lesson, the one list of them.
    ($module:ident, $check:ident, every) => {
        crate::common::per_lesson!(
            $module,
            $check,
            [
                rope: "rope",
                hooke: "hooke",
                euler: "euler",
                verlet: "verlet",
                jelly: "jelly",
                cloth: "cloth",
                speed_accuracy: "speed-accuracy",
                model: "model",
            ]
        );
    };
    ($module:ident, $check:ident, [$($lesson:ident: $slug:literal),* $(,)?]) => {
        mod $module {
            pub const SLUGS: &[&str] = &[$($slug),*];
            $(
                #[test]
                fn $lesson() {
                    super::$check($slug);
                }
            )*
        }
    };
}
pub(crate) use per_lesson;

/// The slugs of the built-in lessons, in the course's order.
pub fn lesson_slugs() -> Vec<String> {
    springlab::lesson::builtin()
        .into_iter()
        .map(|l| l.expect("built-in lessons load").slug)
        .collect()
}
