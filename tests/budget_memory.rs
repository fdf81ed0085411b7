//! The memory estimate of `springlab::budget` against the allocations measured while a scene is
//! loaded and stepped: a counting global allocator records the peak of live heap bytes.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use springlab::budget;
use springlab::scene;
use springlab::{Method, Simulation};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

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
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let live = LIVE.fetch_add(new_size - layout.size(), Ordering::SeqCst) + new_size
                    - layout.size();
                PEAK.fetch_max(live, Ordering::SeqCst);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::SeqCst);
            }
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One measurement at a time (the harness runs tests on several threads).
static MEASURE: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Peak live bytes above the level at the start of `f`.
fn peak_of(f: impl FnOnce()) -> usize {
    let _guard = MEASURE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let base = LIVE.load(Ordering::SeqCst);
    PEAK.store(base, Ordering::SeqCst);
    f();
    PEAK.load(Ordering::SeqCst) - base
}

#[test]
fn estimate_matches_measured_peak() {
    let nodes = 200_000usize;
    let text = format!("[[ropes]]\nnodes = {nodes}\nend = [-400.0, 2.0, 0.0]\n");
    for method in Method::ALL {
        let measured = peak_of(|| {
            let mut s = scene::file::from_str(&text, Path::new("big.toml"), &[]).unwrap();
            s.set_method(method);
            let mut sim = Simulation::new(s);
            sim.step();
        });
        let estimate = budget::body_bytes(nodes as f64, (nodes - 1) as f64, &[method], 1.0);
        let ratio = estimate / measured as f64;
        eprintln!("rope, {method}: measured {measured} bytes, estimated {estimate}: {ratio:.3}");
        assert!(
            (0.9..1.1).contains(&ratio),
            "{method}: estimate/measured = {ratio}"
        );
    }
    for (name, set) in [
        ("cube-plane", "n=30"),
        ("cloth-sphere", "n=120"),
        ("jelly-bowl", "n=30"),
    ] {
        for method in [Method::SemiImplicitEuler, Method::Verlet] {
            let mut counts = (0, 0);
            let measured = peak_of(|| {
                let mut s = scene::load(name, &[set.to_string()]).unwrap();
                s.set_method(method);
                counts = (s.particle_count(), s.spring_count());
                let mut sim = Simulation::new(s);
                sim.step();
            });
            let estimate = budget::body_bytes(counts.0 as f64, counts.1 as f64, &[method], 1.0);
            let ratio = estimate / measured as f64;
            eprintln!(
                "{name} {set}, {method}: measured {measured} bytes, estimated {estimate}: {ratio:.3}"
            );
            assert!(
                (0.8..1.2).contains(&ratio),
                "{name}, {method}: estimate/measured = {ratio}"
            );
        }
    }
}

#[test]
fn builtin_sizes_are_the_exact_counts_of_the_builders() {
    // Its allocations would count in another test's measurement.
    let _guard = MEASURE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let cases: &[(&str, &[&str])] = &[
        ("oscillator", &[]),
        ("rope", &[]),
        ("rope", &["nodes=1000"]),
        ("ropes", &["nodes=37"]),
        ("cube-plane", &[]),
        ("cube-tilted", &["n=7", "bodies=3"]),
        ("cube-sphere", &["n=2"]),
        ("cube-bowl", &["n=13"]),
        ("jelly-bowl", &["n=5", "bodies=2"]),
        ("cloth-spheres", &[]),
        ("cloth-sphere", &["n=60"]),
        ("cloth-sphere", &["n=2"]),
    ];
    for def in scene::BUILTIN {
        assert!(
            cases.iter().any(|(name, _)| *name == def.name),
            "{} has no case",
            def.name
        );
    }
    for (name, sets) in cases {
        let sets: Vec<String> = sets.iter().map(|s| (*s).to_string()).collect();
        let def = scene::builtin(name).expect("built-in");
        let mut params = def.default_params();
        for s in &sets {
            params.set_text(s).expect("valid");
        }
        let (particles, springs) = (def.size)(&params);
        let built = scene::load(name, &sets).expect("builds");
        assert_eq!(particles, built.particle_count() as f64, "{name} {sets:?}");
        assert_eq!(springs, built.spring_count() as f64, "{name} {sets:?}");
    }
    // With a spring kind switched off the count is an upper bound.
    let sets = vec!["bend_stiffness=0".to_string(), "bend_damping=0".to_string()];
    let def = scene::builtin("cube-plane").expect("built-in");
    let mut params = def.default_params();
    for s in &sets {
        params.set_text(s).expect("valid");
    }
    let (_, springs) = (def.size)(&params);
    assert!(
        springs
            > scene::load("cube-plane", &sets)
                .expect("builds")
                .spring_count() as f64
    );
}

#[test]
fn a_builtin_over_the_memory_budget_is_refused_before_it_is_built() {
    let limits = budget::Limits {
        memory: 64e6,
        ..budget::Limits::DEFAULT
    };
    let measured = peak_of(|| {
        let e = scene::load_with("ropes", &["nodes=1000000".to_string()], &limits).unwrap_err();
        assert!(
            e.to_string().contains("scene `ropes` would need about"),
            "{e}"
        );
        assert!(
            e.to_string()
                .contains("(2000000 particles, 1999998 springs)"),
            "{e}"
        );
    });
    assert!(
        measured < 1_000_000,
        "{measured} bytes allocated before the refusal"
    );
}
