//! Property tests of the parsers users feed: scene files, `--set` and lesson files. Arbitrary
//! input never panics, and a scene file never allocates beyond its memory budget: a counting
//! allocator records the peak of live heap bytes while each file is parsed and built.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use proptest::prelude::*;
use springlab::budget::Limits;
use springlab::lesson;
use springlab::scene::{self, SceneError};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// One measurement at a time (the test harness runs tests on several threads).
static MEASURE: Mutex<()> = Mutex::new(());

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
            PEAK.fetch_max(live, Ordering::SeqCst);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Tokens that make TOML-like scene files: section headers, keys, extreme numbers, punctuation.
const SCENE_TOKENS: &[&str] = &[
    "[[ropes]]\n",
    "[[particles]]\n",
    "[[springs]]\n",
    "[run]\n",
    "[world]\n",
    "[params]\n",
    "scene = \"rope\"\n",
    "scene = \"cloth-sphere\"\n",
    "scene = \"nope\"\n",
    "nodes = ",
    "mass = ",
    "stiffness = ",
    "damping = ",
    "position = ",
    "velocity = ",
    "start = ",
    "end = ",
    "a = ",
    "b = ",
    "pinned = ",
    "dt = ",
    "time = ",
    "method = ",
    "gravity = ",
    "drag = ",
    "rest_length = ",
    "kind = ",
    "iterations = ",
    "substeps = ",
    "n = ",
    "bodies = ",
    "\"verlet\"",
    "\"shear\"",
    "0",
    "1",
    "2",
    "-1",
    "3.5",
    "1e-320",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "1000000",
    "999999",
    "9223372036854775807",
    "-9223372036854775808",
    "1e6",
    "1e-300",
    "[0.0, 1.0, 2.0]",
    "[nan, 0, 0]",
    "[1e300, 0, 0]",
    "[0]",
    "[0, 1]",
    "[",
    "]",
    ",",
    "=",
    "\"",
    "\n",
    " ",
    "true",
    "{",
    "}",
    "#",
    "é",
    "\u{0}",
];

fn scene_text() -> impl Strategy<Value = String> {
    prop_oneof![
        proptest::collection::vec(proptest::sample::select(SCENE_TOKENS), 0..60)
            .prop_map(|tokens| tokens.concat()),
        any::<String>(),
    ]
}

/// Form 2 files with rope blocks of any size: the loader must refuse before building what does
/// not fit in the budget.
fn rope_file() -> impl Strategy<Value = String> {
    proptest::collection::vec(2i64..1_000_000, 1..6).prop_map(|nodes| {
        nodes
            .iter()
            .map(|n| format!("[[ropes]]\nnodes = {n}\n"))
            .collect::<String>()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn scene_files_never_panic(text in scene_text()) {
        let _guard = MEASURE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let limits = Limits { memory: 64e6, ..Limits::DEFAULT };
        match scene::file::from_str_with(&text, Path::new("p.toml"), &[], &limits) {
            Ok(s) => prop_assert!(s.particle_count() > 0),
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    #[test]
    fn scene_files_never_allocate_beyond_the_budget(text in rope_file()) {
        let _guard = MEASURE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let budget = 32.0 * 1024.0 * 1024.0;
        let limits = Limits { memory: budget, ..Limits::DEFAULT };
        let base = LIVE.load(Ordering::SeqCst);
        PEAK.store(base, Ordering::SeqCst);
        let result = scene::file::from_str_with(&text, Path::new("ropes.toml"), &[], &limits);
        let peak = PEAK.load(Ordering::SeqCst) - base;
        prop_assert!(peak as f64 <= budget, "peak {peak} bytes over the budget {budget}");
        if let Err(e) = result {
            prop_assert!(matches!(e, SceneError::Budget(_)), "{e}");
            prop_assert!(e.to_string().contains("would need about"), "{e}");
        }
    }

    #[test]
    fn set_assignments_never_panic_and_stay_in_range(
        key in proptest::sample::select(&["nodes", "mass", "stiffness", "damping", "start", "pinned",
                                          "gravity", "n", "bodies", "iterations", "nope", ""][..]),
        value in prop_oneof![
            proptest::sample::select(SCENE_TOKENS).prop_map(str::to_string),
            any::<String>(),
            any::<f64>().prop_map(|x| x.to_string()),
        ],
        scene_name in proptest::sample::select(&["rope", "cube-plane", "cloth-sphere"][..]),
    ) {
        let def = scene::builtin(scene_name).expect("built-in");
        let mut params = def.default_params();
        let text = format!("{key}={value}");
        if params.set_text(&text).is_ok() {
            for (name, v) in params.iter() {
                let spec = params.spec(name).expect("declared");
                prop_assert!(spec.check(v.clone()).is_ok(), "{name} = {v} escaped its range");
            }
        }
        // Without `=`: a clear error, never a panic.
        prop_assert!(params.set_text(&value.replace('=', "")).is_err());
    }

    #[test]
    fn lesson_files_never_panic(
        header in proptest::collection::vec(proptest::sample::select(&[
            "+++\n", "+++ step\n", "number = 1\n", "number = -1\n", "number = 99999999999\n",
            "slug = \"a\"\n", "title = \"t\"\n", "summary = \"s\"\n", "scene = \"rope\"\n",
            "scene = \"x.toml\"\n", "params = { nodes = 3 }\n", "params = { nodes = 1e300 }\n",
            "dt = 1e-300\n", "dt = nan\n", "method = \"rk4\"\n", "plots = [\"energy\"]\n",
            "goal = { kind = \"settle\", time = 1.0, text = \"x\" }\n", "goal = 3\n",
            "Text.\n", "\n", "[", "\"", "é",
        ][..]), 0..40),
        noise in any::<String>(),
    ) {
        let text = header.concat();
        let _ = lesson::parse(&text, "p.md", None);
        let _ = lesson::parse(&noise, "p.md", None);
        let mixed = format!("{text}{noise}");
        if let Err(e) = lesson::parse(&mixed, "p.md", None) {
            prop_assert!(e.to_string().starts_with("p.md:"), "{e}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// `--set` of any size on a built-in scene: refused before it is built when over the budget.
    #[test]
    fn set_never_allocates_beyond_the_budget(
        case in prop_oneof![
            (1i64..=1_000_000).prop_map(|n| ("rope", format!("nodes={n}"))),
            (1i64..=1_000_000).prop_map(|n| ("ropes", format!("nodes={n}"))),
            (2i64..=40).prop_map(|n| ("cube-plane", format!("n={n}"))),
            (2i64..=200).prop_map(|n| ("cloth-sphere", format!("n={n}"))),
        ],
    ) {
        let _guard = MEASURE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let budget = 32.0 * 1024.0 * 1024.0;
        let limits = Limits { memory: budget, ..Limits::DEFAULT };
        let (name, set) = case;
        let base = LIVE.load(Ordering::SeqCst);
        PEAK.store(base, Ordering::SeqCst);
        let result = scene::load_with(name, std::slice::from_ref(&set), &limits);
        let peak = PEAK.load(Ordering::SeqCst) - base;
        prop_assert!(peak as f64 <= budget, "{name} {set}: peak {peak} bytes over {budget}");
        if let Err(e) = result {
            prop_assert!(
                matches!(e, SceneError::Budget(_)) || e.to_string().contains("out of range"),
                "{e}"
            );
        }
    }
}
