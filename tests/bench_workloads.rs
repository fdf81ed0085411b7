//! The peer-benchmark workloads against `docs/workloads.md`: set-up bytes bit for bit (SHA-256),
//! checksums after N steps against the C++ f64 reference, run-to-run determinism, and the
//! `springlab bench` command line on bad input.
//!
//! The checksum tests run each workload once for its full N steps; run them with
//! `cargo test --release --test all bench_workloads::`.

use crate::common;
use common::springlab;

use sha2::{Digest, Sha256};
use springlab::bench::{self, REL_TOL, Run, Workload};

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// SHA-256 of the canonical set-up bytes, from `docs/workloads.md`.
fn expected_setup_sha(w: Workload) -> &'static str {
    match w {
        Workload::JellySe | Workload::JellyRk4 => {
            "2998d5d89a68a2ffbb5b5399c5283fdbcb11588749f46363c236cc5aa00d4e96"
        }
        Workload::Cloth64Se => "0f03a18dc799873f3fb6f40d89f011bafbaa56dd86009e9afeaad69ce60e43cb",
        Workload::Cloth128Se => "d42f10ae2054dfcf1d700d982f4d83a108e5d3c0cca1e5fbe71a76d66d05104a",
        Workload::RopeSe | Workload::RopeVerlet => {
            "581e8990f4d069fd9fa12e4362fd0fbbefab86e399e679c3f783f0d167109096"
        }
    }
}

#[test]
fn setup_bytes_match_the_peers_sha256() {
    for w in Workload::ALL {
        assert_eq!(
            sha256_hex(&bench::setup_bytes(w)),
            expected_setup_sha(w),
            "set-up of {w}"
        );
    }
}

#[test]
fn setups_have_the_documented_sizes() {
    // (particles, springs) from the docs/workloads.md table.
    let sizes = [
        (Workload::JellySe, 1000, 12_876),
        (Workload::JellyRk4, 1000, 12_876),
        (Workload::Cloth64Se, 4096, 23_938),
        (Workload::Cloth128Se, 16_384, 97_026),
        (Workload::RopeSe, 64, 63),
        (Workload::RopeVerlet, 64, 63),
    ];
    for (w, particles, springs) in sizes {
        let (model, state) = bench::setup(w);
        assert_eq!(model.particle_count(), particles, "{w}");
        assert_eq!(state.len(), particles, "{w}");
        assert_eq!(model.springs().len(), springs, "{w}");
    }
}

#[test]
fn pinned_particles_are_the_documented_ones() {
    let pinned = |w| {
        let (model, _) = bench::setup(w);
        (0..model.particle_count())
            .filter(|&i| model.is_pinned(i))
            .collect::<Vec<_>>()
    };
    assert_eq!(pinned(Workload::JellySe), Vec::<usize>::new());
    assert_eq!(pinned(Workload::Cloth64Se), vec![0, 63]);
    assert_eq!(pinned(Workload::Cloth128Se), vec![0, 127]);
    assert_eq!(pinned(Workload::RopeSe), vec![0]);
    assert_eq!(pinned(Workload::RopeVerlet), vec![0]);
}

fn assert_checksum(w: Workload) {
    let mut run = Run::new(w);
    run.advance(w.steps());
    let got = run.checksum();
    let reference = w.reference();
    assert!(
        got.agrees(&reference, REL_TOL),
        "{w} after {} steps: got {got:?}, reference {reference:?}, max relative deviation {:.3e}",
        w.steps(),
        got.max_relative_deviation(&reference)
    );
}

#[test]
fn jelly_se_checksum_agrees_with_reference() {
    assert_checksum(Workload::JellySe);
}

#[test]
fn jelly_rk4_checksum_agrees_with_reference() {
    assert_checksum(Workload::JellyRk4);
}

#[test]
fn cloth64_se_checksum_agrees_with_reference() {
    assert_checksum(Workload::Cloth64Se);
}

#[test]
fn cloth128_se_checksum_agrees_with_reference() {
    assert_checksum(Workload::Cloth128Se);
}

#[test]
fn rope_se_checksum_agrees_with_reference() {
    assert_checksum(Workload::RopeSe);
}

#[test]
fn rope_verlet_checksum_agrees_with_reference() {
    assert_checksum(Workload::RopeVerlet);
}

/// The other kernels this CPU has: the best one, which every run takes by default, is what the
/// checksum tests above run.
#[test]
fn every_kernel_this_cpu_has_gives_the_reference_checksums() {
    use springlab::physics::stencil::Kernel;
    let others = Kernel::ALL
        .into_iter()
        .filter(|&k| k.is_available() && k != Kernel::best());
    for w in [Workload::JellySe, Workload::Cloth64Se, Workload::RopeSe] {
        for kernel in others.clone() {
            let (model, state) = bench::setup(w);
            let mut run = Run::from_setup(w, model.with_kernel(kernel), state);
            run.advance(w.steps());
            let got = run.checksum();
            assert!(
                got.agrees(&w.reference(), REL_TOL),
                "{w} with {kernel:?}: {got:?}, deviation {:.3e}",
                got.max_relative_deviation(&w.reference())
            );
        }
    }
}

#[test]
fn rope_se_is_bit_identical_run_to_run() {
    let run = || {
        let mut r = Run::new(Workload::RopeSe);
        r.advance(Workload::RopeSe.steps());
        r.state
    };
    let (a, b) = (run(), run());
    let bits = |s: &springlab::State| {
        s.x.iter()
            .chain(&s.v)
            .flat_map(|p| p.to_array().map(f64::to_bits))
            .collect::<Vec<u64>>()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn lattice_runs_are_bit_identical_with_one_thread_and_with_two() {
    use springlab::physics::pool::Pool;
    let bits = |s: &springlab::State| {
        s.x.iter()
            .chain(&s.v)
            .flat_map(|p| p.to_array().map(f64::to_bits))
            .collect::<Vec<u64>>()
    };
    let pool = Pool::global();
    let all = pool.threads();
    for w in [Workload::JellySe, Workload::Cloth64Se] {
        let run = |threads: usize| {
            // Other tests may run meanwhile with this setting: it changes their speed only.
            pool.set_threads(threads);
            let mut r = Run::new(w);
            r.advance(300);
            r.state
        };
        let (one, two) = (run(1), run(2));
        assert!(bits(&one) == bits(&two), "{w}: 1 and 2 threads differ");
    }
    pool.set_threads(all);
}

#[test]
fn checksum_comparison_uses_relative_tolerance_and_absolute_floor() {
    let r = bench::REFERENCE_ROPE_SE;
    let mut c = r;
    assert!(c.agrees(&r, REL_TOL));
    c.energy = r.energy * (1.0 + 5e-9);
    assert!(c.agrees(&r, REL_TOL));
    c.energy = r.energy * (1.0 + 2e-8);
    assert!(!c.agrees(&r, REL_TOL));
    // cz = 0 in the reference: a tiny absolute deviation is fine, a real one is not.
    let mut c = r;
    c.centroid[2] = 1e-13;
    assert!(c.agrees(&r, REL_TOL));
    c.centroid[2] = 1e-6;
    assert!(!c.agrees(&r, REL_TOL));
    c.centroid[2] = f64::NAN;
    assert!(!c.agrees(&r, REL_TOL));
}

#[test]
fn workload_names_round_trip_and_unknown_names_list_the_known_ones() {
    for w in Workload::ALL {
        assert_eq!(w.name().parse::<Workload>(), Ok(w));
    }
    let err = "jelly".parse::<Workload>().unwrap_err().to_string();
    assert_eq!(
        err,
        "unknown workload `jelly`; expected one of: jelly-se, jelly-rk4, cloth64-se, \
         cloth128-se, rope-se, rope-verlet"
    );
}

#[test]
fn cli_rejects_an_unknown_workload_with_the_known_names() {
    let out = springlab(&["bench", "rope-se", "rope"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("unknown workload `rope`; expected one of: jelly-se, jelly-rk4"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty(), "nothing is run before validation");
}

#[test]
fn cli_rejects_zero_repeats() {
    let out = springlab(&["bench", "rope-se", "--repeats", "0"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--repeats"), "{stderr}");
}

#[test]
fn cli_json_has_the_design_shape() {
    let out = springlab(&["bench", "rope-verlet", "--json", "--repeats", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let w = &v["workloads"][0];
    assert_eq!(w["workload"], "rope-verlet");
    assert_eq!(w["method"], "verlet");
    assert_eq!(w["particles"], 64);
    assert_eq!(w["springs"], 63);
    assert_eq!(w["steps"], 10_000);
    assert!(w["steps_per_second"].as_f64().is_some_and(|s| s > 0.0));
    assert!(
        w["spring_steps_per_second"]
            .as_f64()
            .is_some_and(|s| s > 0.0)
    );
    assert_eq!(w["centroid"].as_array().map(Vec::len), Some(3));
    assert!(w["energy"].is_f64());
    assert_eq!(w["checksum_ok"], true);
    assert!(w["reference"]["energy"].is_f64());
    assert!(
        out.stderr.is_empty(),
        "no progress when stderr is not a terminal"
    );
    // The machine's ceiling: the fastest kernel here, per thread, on every thread of the pool.
    let c = &v["ceiling"];
    let best = springlab::physics::stencil::Kernel::best();
    assert_eq!(c["kernel"], format!("{best:?}"));
    let (per_thread, threads) = (
        c["per_thread"].as_f64().expect("per_thread"),
        c["threads"].as_u64().expect("threads"),
    );
    assert!(per_thread > 0.0 && threads >= 1, "{c}");
    // `springs_per_second` is `per_thread · threads` in the program; the JSON reader (serde_json
    // without `float_roundtrip`) may read a printed float back 1 ulp off, so compare within a
    // relative 1e-12 (thousands of ulps, far below any real mistake such as a missing factor).
    let total = c["springs_per_second"]
        .as_f64()
        .expect("springs_per_second");
    let expected = per_thread * threads as f64;
    assert!(
        (total - expected).abs() <= 1e-12 * expected,
        "{total} vs {expected}: {c}"
    );
}

#[test]
fn cli_table_states_each_workloads_share_of_the_ceiling() {
    // The rope with every method for a moment: rows with one, two and four force evaluations a
    // step, each against the same ceiling.
    let out = springlab(&["bench", "rope-se", "--repeats", "1", "--budget", "0.05"]);
    assert!(out.status.success());
    let table = String::from_utf8_lossy(&out.stdout);
    let last = table.lines().last().expect("the ceiling line");
    // "… = 3.8e9 springs/s": the ceiling of the whole machine.
    let ceiling: f64 = last
        .rsplit(" = ")
        .next()
        .and_then(|t| t.trim_end_matches(" springs/s").parse().ok())
        .expect("the ceiling");
    // Force evaluations a step: one for semi-implicit Euler, two for the midpoint method, four
    // for RK4 (each evaluates every spring once).
    for (method, evaluations) in [
        ("semi-implicit-euler", 1.0),
        ("midpoint", 2.0),
        ("rk4", 4.0),
    ] {
        let row = table
            .lines()
            .find(|l| {
                let mut f = l.split_whitespace();
                f.next() == Some("rope-se") && f.next() == Some(method)
            })
            .unwrap_or_else(|| panic!("a row for {method}:\n{table}"));
        // The row: springs·steps/s, then the share in per cent.
        let fields: Vec<&str> = row.split_whitespace().collect();
        let spring_steps: f64 = fields[6].parse().expect("springs·steps/s");
        let share: f64 = fields[7].trim_end_matches('%').parse().expect("a share");
        // The table prints the share rounded to 1 % (±0.5) and both rates to 4 significant
        // digits (each within a relative 5e-4 of the value the share was computed from), so
        // the share recomputed from the printed rates is within 0.5 + share · 1e-3 (+ a float
        // margin).
        let recomputed = 100.0 * evaluations * spring_steps / ceiling;
        assert!(
            (share - recomputed).abs() <= 0.5 + recomputed * 1.0e-3 + 1e-9,
            "{row}\n{last}"
        );
    }
}

#[test]
fn bench_times_every_method_on_a_spring_workload() {
    let out = springlab(&[
        "bench",
        "rope-se",
        "--json",
        "--repeats",
        "1",
        "--budget",
        "0.05",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let entries = v["workloads"].as_array().expect("entries");
    let methods: Vec<&str> = entries
        .iter()
        .map(|w| w["method"].as_str().unwrap_or(""))
        .collect();
    // The workload's own method first, then every other method in the order of Method::ALL.
    let mut expected = vec!["semi-implicit-euler"];
    expected.extend(
        springlab::Method::ALL
            .iter()
            .map(|m| m.name())
            .filter(|&n| n != "semi-implicit-euler"),
    );
    assert_eq!(methods, expected);
    assert_eq!(entries[0]["reference_method"], true);
    assert_eq!(entries[0]["checksum_ok"], true);
    for w in &entries[1..] {
        assert_eq!(w["workload"], "rope-se");
        assert_eq!(w["reference_method"], false);
        assert!(w["reference"].is_null());
        assert!(w["steps"].as_u64().is_some_and(|n| n > 0));
        assert!(
            w["spring_steps_per_second"]
                .as_f64()
                .is_some_and(|s| s > 0.0)
        );
    }
    // RK4 costs four force evaluations a step, midpoint two.
    assert_eq!(entries[3]["force_evals_per_step"], 4);
    assert_eq!(entries[2]["force_evals_per_step"], 2);
    // Explicit Euler blows up on this stiff rope at dt = 1e-4 (|1 + i dt ω| > 1): reported.
    assert!(entries[1]["diverged_at"].as_u64().is_some());
    let bad = springlab(&["bench", "rope-se", "--budget", "nan"]);
    assert!(
        String::from_utf8_lossy(&bad.stderr)
            .contains("--budget NaN: expected a wall time in seconds >= 0")
    );
}
