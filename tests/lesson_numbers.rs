//! Numbers in lesson text cannot drift from the code: every number a student reads is either a
//! placeholder computed when the step opens (checked here to resolve), one of the step's own
//! inputs (its dt, scene parameters, goal or prediction values: the run uses exactly those), or
//! listed below with the check or the definition that makes it true. A new number in a lesson
//! fails this test until it is one of those.

use springlab::lesson::{self, Step, numbers};
use springlab::physics::Method;
use springlab::study::{self, theory};

/// The numbers a student reads in `step` outside code, inline code and placeholders: the text,
/// the try items, the goal and the prediction.
fn prose_numbers(step: &Step) -> Vec<String> {
    let mut prose = String::new();
    let mut fenced = false;
    let mut previous_blank = true;
    let mut in_code = false;
    for line in step.text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if line.trim().is_empty() {
            previous_blank = true;
            in_code = false;
            continue;
        }
        if line.starts_with("    ") && (previous_blank || in_code) {
            in_code = true;
            previous_blank = false;
            continue;
        }
        previous_blank = false;
        prose.push_str(line);
        prose.push('\n');
    }
    for t in &step.try_list {
        prose.push_str(&t.text);
        prose.push('\n');
    }
    if let Some(g) = &step.goal {
        prose.push_str(&g.text);
        prose.push('\n');
    }
    if let Some(p) = &step.predict {
        prose.push_str(&p.question);
        prose.push('\n');
        prose.push_str(&p.explain);
        for o in &p.options {
            prose.push('\n');
            prose.push_str(&o.text);
        }
    }
    // Placeholders and inline code out.
    let mut clean = String::new();
    let mut rest = prose.as_str();
    while let Some(i) = rest.find("{{") {
        clean.push_str(&rest[..i]);
        rest = rest[i..].find("}}").map_or("", |j| &rest[i + j + 2..]);
    }
    clean.push_str(rest);
    let mut out = Vec::new();
    let mut code = false;
    let chars: Vec<char> = clean.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '`' {
            code = !code;
            i += 1;
            continue;
        }
        let starts = c.is_ascii_digit()
            && !code
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || matches!(chars[i - 1], '_' | '.')));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < chars.len()
            && (chars[j].is_ascii_digit()
                || (chars[j] == '.' && chars.get(j + 1).is_some_and(char::is_ascii_digit))
                || (chars[j] == 'e'
                    && chars
                        .get(j + 1)
                        .is_some_and(|d| *d == '-' || d.is_ascii_digit()))
                || (chars[j] == '-' && j > 0 && chars[j - 1] == 'e'))
        {
            j += 1;
        }
        out.push(chars[i..j].iter().collect());
        i = j;
    }
    out
}

/// Numbers that are the step's own inputs: dt, scene parameters, goal and prediction values.
fn inputs(step: &Step) -> Vec<f64> {
    let mut v = Vec::new();
    if let Some(dt) = step.dt {
        v.push(dt);
    }
    for p in &step.params {
        let value = p.split_once('=').map_or("", |(_, v)| v);
        for part in value.trim_matches(['[', ']']).split(',') {
            if let Ok(x) = part.trim().parse::<f64>() {
                v.push(x);
            }
        }
    }
    if let Some(g) = &step.goal {
        v.extend([g.time, g.speed]);
    }
    if let Some(p) = &step.predict {
        for o in &p.options {
            v.extend([o.claim.time, o.claim.speed]);
        }
    }
    v
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// The damped theory's limit of `method` on the built-in scene `name` (s).
fn limit(name: &str, method: Method) -> f64 {
    let scene = springlab::scene::load(name, &[]).expect("scene");
    let b = &scene.bodies[0];
    let omega = study::omega_max(&b.model, &b.state).omega;
    let s = theory::spectrum(&b.model, &b.state, omega);
    theory::limit(method, &b.params, &s)
        .dt
        .expect("conditional")
}

/// `(lesson number, number as written, why it is true)`: checked below where a check exists,
/// else a definition, a label or a count the reason states.
const EXPLAINED: &[(u32, &str, &str)] = &[
    // Lesson 1.
    (
        1,
        "0",
        "particle 0: the pinned node's index (`pinned = [0]`, a scene default)",
    ),
    (1, "1", "particle 1: an index"),
    (
        1,
        "4",
        "A×4 gives c = 0.25 · 2³ = 2 N·s/m: the try keys, shown beside the text",
    ),
    // Lesson 2.
    (2, "2", "2√(k m): the formula of critical damping"),
    (2, "1.5", "D multiplies k_d by COEFFICIENT_FACTOR (checked)"),
    (2, "5", "D×5: the try keys"),
    // Lesson 3.
    (3, "3", "+ + doubles dt twice; also the goal's 3 s"),
    (
        3,
        "2",
        "dt·ω < 2: semi-implicit Euler's limit (checked: dt < 0.2 s at ω = 10)",
    ),
    (3, "4", "+×4: the try keys"),
    (3, "0.16", "dt = 0.02 · 2³ after three presses of +"),
    (3, "1.6", "dt·ω = 0.16 · 10"),
    (3, "1", "order 1 / indices"),
    (
        3,
        "64",
        "the rope's dt = 1/64 s (the scene's default, checked)",
    ),
    (
        3,
        "1000",
        "the divergence check |v| > 1000 m/s (diverge.rs, checked)",
    ),
    (3, "10", "the goal's 10 s"),
    // Lesson 4.
    (4, "2", "second order; 2 N·s/m in the placeholder's scene"),
    (4, "1", "first order; one pass"),
    (4, "0.05", "γ = 5e-5 × 10³ after G×3 (checked)"),
    (4, "3", "G three times"),
    (4, "4", "J×4 = 16 passes"),
    (4, "10", "G multiplies γ by 10 (checked)"),
    (
        4,
        "0.00005",
        "GAMES101's γ, the rope scenes' default (checked)",
    ),
    (4, "0.0032", "γ/dt = 5e-5 · 64 (checked)"),
    (4, "64", "dt = 1/64 s, the ropes' default"),
    // Lesson 5.
    (5, "4", "a 4×4×4 cube (`n = 4`)"),
    (5, "6", "six axis neighbours of a lattice particle"),
    (5, "3", "3 springs per particle: half of 6; a 3×3×3 block"),
    (
        5,
        "20",
        "26 - 6 neighbours of a 3×3×3 block: the shear springs' partners (checked by the counts)",
    ),
    (5, "10", "the course's 10×10×10 cube"),
    (
        5,
        "45",
        "the slope's normal (1,1,0)/√2 is at 45° (scene definition)",
    ),
    (5, "1", "normal (1,1,0)"),
    (5, "0", "normal (1,1,0); y = 0"),
    (5, "2", "√2"),
    (5, "2023", "the NYCU course year"),
    (5, "9", "the bowl's radius 9 (checked)"),
    (5, "6.36", "9/√2 (checked)"),
    (5, "1998", "Baraff & Witkin 1998 (a citation)"),
    // Lesson 6.
    (6, "1", "corner 1"),
    (6, "4", "the cloth spans 4 m × 4 m (checked)"),
    (6, "2024", "the NYCU course year"),
    (6, "6.25e-5", "5e-4 / 2³ after three presses of -"),
    (6, "5e-4", "this step's dt"),
    (
        6,
        "0.001",
        "the 2024 report's failing dt (a citation; about four times springlab's limit, checked)",
    ),
    (6, "0.0006", "the 2024 report's value (a citation)"),
    (6, "0.0011", "the 2024 report's value (a citation)"),
    (6, "0.0015", "the 2024 report's value (a citation)"),
    (
        6,
        "10",
        "10⁻³, implicit Euler's default CG tolerance (checked)",
    ),
    (
        6,
        "3",
        "3 s of the goal; 'three times as many passes' (checked)",
    ),
    // Lesson 7.
    (7, "1", "slope 1 / order 1 / key 1"),
    (
        7,
        "2",
        "slope 2; key 2; dt·ω = 2; a damper of 2 N·s/m (the placeholder's scene)",
    ),
    (7, "4", "slope 4; RK4; a bench of 4 × 24 bytes"),
    (7, "1.5", "dt·ω = 0.15 · 10"),
    (7, "3", "key 3"),
    (7, "5", "key 5"),
    (7, "6", "key 6"),
    (7, "8", "key 8"),
    (7, "2024", "the NYCU course year"),
    (7, "1e-4", "the course's cloth dt (checked: the scene's dt)"),
    (7, "16", "2⁴: RK4's error per halving of dt"),
    (7, "24", "bytes of a position or velocity (3 × f64)"),
    (
        7,
        "30",
        "a count: the floating-point operations of one spring's Hooke and damper force as crates/core/src/physics/springs.rs writes it (two of them slow: the square root and the division)",
    ),
    (7, "512", "AVX-512"),
    // Lesson 8 (issue 14).
    (
        8,
        "20",
        "the observable is sampled at 20 instants (study::observe, a definition)",
    ),
    (8, "1", "a count / slope"),
    (
        8,
        "2",
        "the observable chart reads the observable every 2 ms of simulated time (lesson_run/observed.rs SAMPLE_EVERY)",
    ),
    (
        8,
        "16",
        "four presses of + double dt four times: 2⁴ = 16 (checked)",
    ),
    (8, "1.36e-3", "advise's dt 8.49e-5 s × 16 (checked)"),
    (
        8,
        "3",
        "T = 3 s of the cloth's observable (the study's definition)",
    ),
    (
        8,
        "0.01",
        "the tolerance X the step chooses (an input of the commands it names)",
    ),
    (
        8,
        "35",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (8, "25", "the course's n = 25 cloth (the scene's default)"),
    (
        8,
        "2.13e-2",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "0.77",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "0.4642",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "0.7465",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "0.8462",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (8, "9", "the study's coarsest level n = 9"),
    (8, "49", "the study's finest level n = 49"),
    (
        8,
        "1.5",
        "advise's stability margin 1.5 (a definition in study::advise)",
    ),
    (
        8,
        "4",
        "X/4: the reference's agreement (a definition in study::advise)",
    ),
    (
        8,
        "2.5",
        "T = 2.5 s on jelly-bowl (the observable's definition)",
    ),
    (8, "5", "the coarser jelly n = 5 (advise's levels)"),
    (8, "7", "the coarser jelly n = 7 (advise's levels)"),
    (8, "10", "the course's n = 10 jelly (the scene's default)"),
    (
        8,
        "2.0e-2",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs (advise's recording, which tests/recorded_numbers.rs pins to the code)",
    ),
    (
        8,
        "2.5e-2",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "1.5e-2",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "8.49e-5",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "24",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "6.54e-3",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
    (
        8,
        "2.9",
        "quoted output of a study that runs for minutes: checked against its recording in docs/studies/ by tests/lesson8.rs, which re-runs the cheapest levels",
    ),
];

#[test]
fn every_number_in_the_lessons_is_an_input_a_placeholder_or_explained() {
    let mut unexplained = Vec::new();
    for l in lesson::builtin() {
        let l = l.expect("loads");
        for step in &l.steps {
            let own = inputs(step);
            for n in prose_numbers(step) {
                let x: f64 = n.parse().expect("a number");
                let explained = EXPLAINED
                    .iter()
                    .any(|(ln, s, _)| *ln == l.number && *s == n);
                if !explained && !own.iter().any(|&v| same(v, x)) {
                    unexplained.push(format!("lesson {} \"{}\": {n}", l.number, step.title));
                }
            }
        }
    }
    assert!(
        unexplained.is_empty(),
        "numbers without a source:\n{}",
        unexplained.join("\n")
    );
}

/// The entries above marked "checked".
#[test]
fn the_explained_numbers_hold() {
    use springlab::tui::lesson_run::{COEFFICIENT_FACTOR, FIRST_DRAG_RATE, FIRST_VERLET_GAMMA};
    // Lesson 8, step 4: it opens in real time (`speed = "machine"`: its result as soon as the
    // machine steps it, not the 20 s that 1/8 of real time took); + four times multiplies dt
    // by 16.
    let eight = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.number == 8)
        .expect("lesson 8");
    let advise = &eight.steps[3];
    assert_eq!(advise.speed, Some(1.0));
    let dt = advise.dt.expect("advise's dt");
    assert_eq!(format!("{:.2e}", dt * 2f64.powi(4)), "1.36e-3");
    // Lesson 1: A×4 from no drag on 1 kg nodes: c = 0.25 · 2³ = 2 N·s/m.
    assert_eq!(FIRST_DRAG_RATE * 8.0, 2.0);
    // Lesson 2: D and K multiply by 1.5.
    assert_eq!(COEFFICIENT_FACTOR, 1.5);
    // Lesson 3: semi-implicit Euler's limit on the oscillator is dt·ω = 2, ω = 10 rad/s.
    assert!((limit("oscillator", Method::SemiImplicitEuler) - 0.2).abs() < 1e-4);
    let rope = springlab::scene::load("rope", &[]).expect("rope");
    assert_eq!(rope.dt, 1.0 / 64.0);
    let mut state = rope.bodies[0].state.clone();
    state.v[1].x = 1000.001;
    assert!(
        springlab::physics::diverge::check(&state, 1, 0.1).is_some(),
        "|v| > 1000 m/s diverges"
    );
    state.v[1].x = 999.999;
    assert!(springlab::physics::diverge::check(&state, 1, 0.1).is_none());
    // Lesson 4: γ starts at GAMES101's 5e-5 (the ropes' default), ×10 per G; its rate γ/dt.
    let ropes = springlab::scene::load("ropes", &[]).expect("ropes");
    assert_eq!(ropes.bodies[1].params.verlet_damping, 5e-5);
    assert_eq!(FIRST_VERLET_GAMMA, 5e-5);
    assert!((5e-5 * 1000.0f64 - 0.05).abs() < 1e-15, "G×3");
    assert!((5e-5f64 / (1.0 / 64.0) - 0.0032).abs() < 1e-15);
    assert!((5e-5f64 / 1e-3 - 0.05).abs() < 1e-15);
    // Lesson 5: the 2023 bowl has radius 9 and the hole radius 9/√2 ≈ 6.36.
    let bowl = crate::common::jelly_bowl();
    assert_eq!(bowl.0, 9.0);
    assert_eq!(format!("{:.2}", 9.0 / 2f64.sqrt()), "6.36");
    assert!(
        (bowl.1 - 9.0 / 2f64.sqrt()).abs() < 1e-12,
        "centred 6.36 m above the floor"
    );
    // Lesson 6: the cloth spans 4 m; the 2024 report's explicit 0.001 s is about four times
    // springlab's limit on cloth-spheres.
    let cloth = springlab::scene::load("cloth-spheres", &[]).expect("cloth");
    let xs = cloth.bodies[0].state.x.iter().map(|p| p.x);
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    assert!((hi - lo - 4.0).abs() < 1e-12);
    let ratio = 0.001 / limit("cloth-spheres", Method::ExplicitEuler);
    assert!((3.5..4.5).contains(&ratio), "about four times: {ratio}");
    // Lesson 7: the course's cloth dt.
    assert_eq!(cloth.dt, 1e-4);
}

/// Lesson 6 step 4: for 3 s of cloth-spheres, implicit Euler at dt = 0.005 s makes about a sixth
/// of the passes over the springs (force evaluations + conjugate-gradient iterations) that
/// semi-implicit Euler's 30 000 force evaluations at the course's dt make, with about seven
/// iterations per step (6.77 with the spheres' velocities inside the solve).
#[test]
fn implicit_euler_on_the_cloth_costs_about_a_sixth_of_the_passes() {
    let mut scene = springlab::scene::load("cloth-spheres", &[]).expect("cloth");
    scene.set_method(Method::ImplicitEuler);
    let mut sim = springlab::simulation::Simulation::new(scene);
    sim.set_dt(0.005);
    sim.run(600, |_| {});
    assert!(sim.diverged.is_none());
    let solver = sim.solver_report();
    let passes = sim.force_evals as f64 + solver.solves as f64 * solver.iterations_mean;
    let ratio = passes / (3.0 / 1e-4);
    assert!(
        (1.0 / 7.0..1.0 / 5.0).contains(&ratio),
        "about a sixth: {ratio}"
    );
    // "stops at a relative residual of 10⁻³"
    assert_eq!(
        springlab::physics::MethodParams::default().cg_tolerance,
        1e-3
    );
    assert!(
        (6.0..8.0).contains(&solver.iterations_mean),
        "about seven iterations: {solver:?}"
    );
    // The contacts with the spheres are held from step to step; a step solves again only when
    // they change. None is retaken as halves.
    assert_eq!((solver.solves, solver.halved_steps), (600, 0));
    assert!(solver.contact_passes_max >= 2 && solver.constrained_max > 0);
}

/// Every placeholder of the built-in lessons resolves to a value (none is left as `?`), and a
/// few of them equal what the studies compute independently.
#[test]
fn placeholders_resolve_and_match_the_studies() {
    for l in lesson::builtin() {
        let l = l.expect("loads");
        for step in &l.steps {
            if !step.text.contains("{{") {
                continue;
            }
            let filled = numbers::fill(&step.text, &step.scene, &step.params, None);
            assert!(!filled.contains("{{"), "{}: {filled}", l.source);
            assert!(
                !filled.contains(numbers::UNKNOWN),
                "lesson {} \"{}\": {filled}",
                l.number,
                step.title
            );
        }
    }
    let fill = |t: &str, scene: &str| numbers::fill(t, scene, &[], None);
    assert_eq!(
        fill("{{limit_dt:semi-implicit-euler}}", "oscillator"),
        "0.2"
    );
    assert_eq!(fill("{{limit_dt:explicit-euler}}", "oscillator"), "none");
    assert_eq!(fill("{{limit_dt:implicit-euler}}", "oscillator"), "any dt");
    assert_eq!(
        fill(
            "{{param:stiffness}} {{springs}} {{particles}}",
            "cube-plane"
        ),
        "2000 12 876 1000"
    );
    assert_eq!(
        fill(
            "{{springs:struct}} {{springs:shear}} {{springs:bend}}",
            "cube-plane"
        ),
        "2700 7776 2400"
    );
    assert_eq!(fill("{{springs*30}}", "cube-plane"), "390 000");
    assert_eq!(fill("{{omega_max}}", "oscillator"), "10");
    let order: f64 = fill("{{order:rk4}}", "oscillator")
        .parse()
        .expect("a number");
    assert!((order - 4.0).abs() < 0.1, "{order}");
    let damped: f64 = fill("{{order:verlet@oscillator damping=2}}", "rope")
        .parse()
        .expect("a number");
    assert!(
        (damped - 1.0).abs() < 0.1,
        "Verlet with a damper is first order: {damped}"
    );
    let linear: f64 = fill("{{stable_dt_omega:rk4}}", "oscillator")
        .parse()
        .expect("a number");
    assert!((linear - 8f64.sqrt()).abs() < 1e-3, "{linear}");
    let crossover: f64 = fill("{{crossover:rk4,verlet}}", "rope")
        .parse()
        .expect("a number");
    assert!((1e-4..1e-2).contains(&crossover), "{crossover}");
    // Bad placeholders are errors at load, with the line.
    let bad = "+++\nnumber = 9\nslug = \"x\"\ntitle = \"X\"\nsummary = \"s\"\n+++\n+++ step\ntitle = \"a\"\nscene = \"rope\"\n+++\nline one\nthe {{limit_dt:euler}} here\n";
    let e = lesson::parse(bad, "bad.md", None).expect_err("unknown method");
    assert_eq!(e.line, 12, "{e}");
    assert!(e.message.contains("unknown method `euler`"), "{e}");
    let bad = bad.replace("limit_dt:euler", "colour");
    let e = lesson::parse(&bad, "bad.md", None).expect_err("unknown placeholder");
    assert!(e.message.contains("unknown placeholder"), "{e}");
}

/// Lesson 7's work-precision step compares numbers it computes: RK4 is cheaper than
/// semi-implicit Euler at "every error measured" (the crossover lies above semi-implicit
/// Euler's largest error, the one at the largest dt), and semi-implicit Euler's error at the
/// largest dt is "the largest of the one-evaluation methods" it names.
#[test]
fn work_precision_comparisons_in_lesson_7_hold() {
    let l = lesson::builtin()
        .into_iter()
        .map(|l| l.expect("loads"))
        .find(|l| l.number == 7)
        .expect("lesson 7");
    let step = l
        .steps
        .iter()
        .find(|s| s.text.contains("{{crossover:rk4,semi-implicit-euler}}"))
        .expect("the work-precision step");
    assert!(step.text.contains("every error measured"), "{}", step.text);
    assert!(
        step.text
            .contains("the largest of the one-evaluation methods")
    );
    let value = |p: &str| -> f64 {
        let s = numbers::fill(p, &step.scene, &step.params, None);
        s.parse().unwrap_or_else(|_| panic!("{p} = {s}"))
    };
    let crossover = value("{{crossover:rk4,semi-implicit-euler}}");
    let sie = value("{{wp_error:semi-implicit-euler}}");
    let ee = value("{{wp_error:explicit-euler}}");
    let verlet = value("{{wp_error:verlet}}");
    assert!(
        crossover > sie,
        "crossover {crossover} m, largest error {sie} m"
    );
    assert!(
        sie > ee && sie > verlet,
        "SIE {sie}, EE {ee}, Verlet {verlet}"
    );
}
