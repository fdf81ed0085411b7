//! The rope's integrator checks: explicit and semi-implicit Euler one steps and course runs, Verlet with constraint projection, and damping.

use super::*;

// ---------------------------------------------------------------------------------------------
// Integrators

/// The rope of a system: masses and pins from the physics, springs from its model.
fn rope_of(physics: &Physics, state: &State) -> Rope {
    let model = physics.model();
    Rope::from_physics(
        &state.x,
        &state.v,
        |i| model.mass.get(i).copied().unwrap_or(1.0),
        |i| model.inv_mass.get(i).is_some_and(|&w| w == 0.0),
        model.springs(),
    )
}

fn write_back(rope: &Rope, state: &mut State) {
    state.x = rope.masses.iter().map(|m| m.position).collect();
    state.v = rope.masses.iter().map(|m| m.velocity).collect();
}

fn explicit_step<H: RopeHomework>(hw: &H) -> impl Fn(&mut State, f64, &Physics) + '_ {
    move |state, dt, physics| {
        let mut rope = rope_of(physics, state);
        hw.explicit_euler(&mut rope, dt, physics);
        write_back(&rope, state);
    }
}

fn semi_step<H: RopeHomework>(hw: &H) -> impl Fn(&mut State, f64, &Physics) + '_ {
    move |state, dt, physics| {
        let mut rope = rope_of(physics, state);
        hw.semi_implicit_euler(&mut rope, dt, physics);
        write_back(&rope, state);
    }
}

const EXPLICIT: &str =
    "x(t+dt) = x(t) + v(t) dt with the OLD velocity, then v(t+dt) = v(t) + a(t) dt";
const SEMI: &str =
    "v(t+dt) = v(t) + a(t) dt, then x(t+dt) = x(t) + v(t+dt) dt with the NEW velocity";

pub(super) fn semi_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 301);
    check_one_step(&semi_step(hw), &semi_step(&Reference), &mut rng, SEMI)
}

pub(super) fn explicit_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 302);
    check_one_step(
        &explicit_step(hw),
        &explicit_step(&Reference),
        &mut rng,
        EXPLICIT,
    )
}

pub(super) fn explicit_order<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_order(&explicit_step(hw), 1.0, 0.8, 1.3, EXPLICIT)
}

/// The course rope of `nodes` nodes and its physics (gravity (0, -1) px/s²).
fn course_rope(nodes: usize) -> (Rope, Physics) {
    let rope = Reference.rope(COURSE_START, COURSE_END, nodes, 1.0, 100.0, &[0]);
    (rope.clone(), physics_of(&rope, COURSE_GRAVITY))
}

/// The physics of `rope` under `gravity`.
fn physics_of(rope: &Rope, gravity: DVec3) -> Physics {
    let masses: Vec<f64> = rope.masses.iter().map(|m| m.mass).collect();
    let pinned: Vec<bool> = rope.masses.iter().map(|m| m.pinned).collect();
    let mut model = model_of(&masses, &pinned, &rope.springs).unwrap_or_else(|| {
        crate::physics::Model::new(Vec::new(), &[], Vec::new(), DVec3::ZERO, 0.0)
    });
    model.gravity = gravity;
    Physics::from_model(model)
}

/// Steps `rope` with `step`, checking the node count and finiteness.
fn run_rope(
    rope: &mut Rope,
    steps: usize,
    input: &str,
    mut step: impl FnMut(&mut Rope),
) -> CheckResult {
    let n = rope.masses.len();
    set_case(input);
    for _ in 0..steps {
        step(rope);
        if rope.masses.len() != n {
            return Err(wrong(
                input,
                format!("{n} masses"),
                format!("{} masses", rope.masses.len()),
                "update the masses in place; do not add or remove any",
            ));
        }
        let x: Vec<DVec3> = rope.masses.iter().map(|m| m.position).collect();
        finite("position", input, &x)?;
    }
    Ok(())
}

/// Compares positions of two ropes.
fn compare_positions(
    input: &str,
    got: &Rope,
    want: &Rope,
    scale: f64,
    formula: &str,
) -> CheckResult {
    for (i, (g, w)) in got.masses.iter().zip(&want.masses).enumerate() {
        if !close(g.position, w.position, REL, scale) {
            return Err(wrong(
                input,
                format!("node {i} at {}", vec3(w.position)),
                format!("node {i} at {}", vec3(g.position)),
                format!("expected {formula}"),
            ));
        }
    }
    Ok(())
}

pub(super) fn semi_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
    let (start, physics) = course_rope(3);
    let input = "200 semi-implicit steps of dt = 1/64 s of the course rope (3 nodes from (0, 200) \
                 to (-400, 200), k = 100, node 0 pinned, gravity (0, -1))";
    let mut got = start.clone();
    run_rope(&mut got, 200, input, |r| {
        hw.semi_implicit_euler(r, COURSE_DT, &physics);
    })?;
    let mut want = start;
    for _ in 0..200 {
        Reference.semi_implicit_euler(&mut want, COURSE_DT, &physics);
    }
    compare_positions(input, &got, &want, 400.0, SEMI)
}

/// A Verlet test rope: nodes at `x` moving at `v` (last_position = x - v dt), unit masses,
/// `pinned` flags, springs `(a, b, rest)` of 100 N/m.
fn verlet_rope(
    x: &[DVec3],
    v: &[DVec3],
    pinned: &[bool],
    springs: &[(usize, usize, f64)],
    dt: f64,
) -> Rope {
    let masses = x
        .iter()
        .zip(v)
        .zip(pinned)
        .map(|((&x, &v), &pinned)| Mass {
            position: x,
            velocity: v,
            last_position: x - dt * v,
            mass: 1.0,
            pinned,
        })
        .collect();
    let springs = springs
        .iter()
        .map(|&(a, b, rest_length)| Spring {
            a,
            b,
            rest_length,
            stiffness: 100.0,
            damping: 0.0,
        })
        .collect();
    Rope { masses, springs }
}

const VERLET: &str = "x(t+dt) = x(t) + (1 - γ)[x(t) - x(t-dt)] + a(t) dt², then every spring projected back to its rest length";

/// Points as `(x, y, z), (x, y, z), …` for feedback.
fn listed(points: impl Iterator<Item = DVec3>) -> String {
    points.map(vec3).collect::<Vec<_>>().join(", ")
}

pub(super) fn verlet_free_fall<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 401);
    let dt = 0.01;
    let x: Vec<DVec3> = (0..3).map(|_| rng.vec(1.0)).collect();
    let v: Vec<DVec3> = (0..3)
        .map(|i| if i == 0 { DVec3::ZERO } else { rng.vec(2.0) })
        .collect();
    let start = verlet_rope(&x, &v, &[true, false, false], &[], dt);
    let physics = physics_of(&start, DVec3::new(0.0, -9.8, 0.0));
    let input = format!(
        "three Verlet steps (γ = 0, dt = {dt} s) of three unconnected masses (node 0 pinned) under \
         gravity 9.8 m/s², x = [{}], last_position = [{}]",
        listed(start.masses.iter().map(|m| m.position)),
        listed(start.masses.iter().map(|m| m.last_position))
    );
    let mut got = start.clone();
    let mut want = start;
    for _ in 0..3 {
        run_rope(&mut got, 1, &input, |r| hw.verlet(r, dt, 0.0, &physics))?;
        Reference.verlet(&mut want, dt, 0.0, &physics);
        compare_positions(&input, &got, &want, 1.0, VERLET)?;
    }
    Ok(())
}

pub(super) fn verlet_pinned<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 402);
    let dt = 0.01;
    for pinned_node in [0, 1, 0] {
        let anchor = rng.vec(1.0);
        let free = anchor + rng.unit() * 1.5;
        let x = if pinned_node == 0 {
            [anchor, free]
        } else {
            [free, anchor]
        };
        let pins = [pinned_node == 0, pinned_node == 1];
        let start = verlet_rope(&x, &[DVec3::ZERO; 2], &pins, &[(0, 1, 1.0)], dt);
        let physics = physics_of(&start, DVec3::ZERO);
        let input = format!(
            "one Verlet step (γ = 0, dt = {dt} s) of a spring of rest length 1 stretched to 1.5 \
             between node 0 at {} and node 1 at {}, node {pinned_node} pinned, at rest",
            vec3(x[0]),
            vec3(x[1])
        );
        let mut got = start.clone();
        run_rope(&mut got, 1, &input, |r| hw.verlet(r, dt, 0.0, &physics))?;
        let pin = got.masses[pinned_node].position;
        if pin != anchor {
            return Err(wrong(
                input,
                format!("pinned node {pinned_node} stays at {}", vec3(anchor)),
                format!("it moved to {}", vec3(pin)),
                "a pinned end does not move during projection; the free end takes the whole \
                 correction (and a pinned node never moves in the Verlet update either)",
            ));
        }
        let length = (got.masses[1].position - got.masses[0].position).length();
        if (length - 1.0).abs() > 1e-9 {
            return Err(wrong(
                input,
                "the spring at its rest length 1 after the step",
                format!("length {}", num(length)),
                "after the position update, move the free end along the spring by the whole \
                 error |x_a - x_b| - L0",
            ));
        }
        let mut want = start;
        Reference.verlet(&mut want, dt, 0.0, &physics);
        compare_positions(&input, &got, &want, 1.0, VERLET)?;
    }
    Ok(())
}

pub(super) fn verlet_free_pair<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 403);
    let dt = 0.01;
    for _ in 0..3 {
        let a = rng.vec(1.0);
        let b = a + rng.unit() * rng.range(1.2, 2.0);
        let v = [rng.vec(0.5), rng.vec(0.5)];
        let start = verlet_rope(&[a, b], &v, &[false, false], &[(0, 1, 1.0)], dt);
        let physics = physics_of(&start, DVec3::ZERO);
        let input = format!(
            "one Verlet step (γ = 0, dt = {dt} s) of two free unit masses at {} and {} moving at \
             {} and {}, joined by a spring of rest length 1",
            vec3(a),
            vec3(b),
            vec3(v[0]),
            vec3(v[1])
        );
        let mut got = start.clone();
        run_rope(&mut got, 1, &input, |r| hw.verlet(r, dt, 0.0, &physics))?;
        let length = (got.masses[1].position - got.masses[0].position).length();
        if (length - 1.0).abs() > 1e-9 {
            return Err(wrong(
                input,
                "the spring at its rest length 1 after the step",
                format!("length {}", num(length)),
                "each free end moves half the error |x_a - x_b| - L0 along the spring",
            ));
        }
        let mut want = start;
        Reference.verlet(&mut want, dt, 0.0, &physics);
        compare_positions(&input, &got, &want, 1.0, VERLET)?;
    }
    Ok(())
}

pub(super) fn verlet_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
    let (start, physics) = course_rope(16);
    let input = "640 Verlet steps (10 frames at 64 steps per frame, γ = 0.00005) of the course rope \
                 with 16 nodes from (0, 200) to (-400, 200), node 0 pinned, gravity (0, -1)";
    let mut got = start.clone();
    run_rope(&mut got, 640, input, |r| {
        hw.verlet(r, COURSE_DT, COURSE_DAMPING, &physics);
    })?;
    let mut want = start.clone();
    for _ in 0..640 {
        Reference.verlet(&mut want, COURSE_DT, COURSE_DAMPING, &physics);
    }
    if got.masses[0].position != COURSE_START {
        return Err(wrong(
            input,
            format!("node 0 pinned at {}", vec3(COURSE_START)),
            format!("node 0 at {}", vec3(got.masses[0].position)),
            "a pinned node never moves, neither in the update nor in the projection",
        ));
    }
    for s in &start.springs {
        let length = (got.masses[s.b].position - got.masses[s.a].position).length();
        if (length - s.rest_length).abs() > 0.01 * s.rest_length {
            return Err(wrong(
                input,
                format!(
                    "every spring within 1 % of its rest length {} px",
                    num(s.rest_length)
                ),
                format!("spring ({}, {}) has length {} px", s.a, s.b, num(length)),
                "project every spring back to its rest length after each position update",
            ));
        }
    }
    let drop = |r: &Rope| COURSE_START.y - r.masses[15].position.y;
    if drop(&got) < 0.5 * drop(&want) {
        return Err(wrong(
            input,
            format!("the free end falls about {} px", num(drop(&want))),
            format!("it fell {} px", num(drop(&got))),
            "the rope hardly moves: is the Verlet update implemented?",
        ));
    }
    Ok(())
}

pub(super) fn damping_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 501);
    let dt = 0.01;
    let gamma = 0.1;
    let x: Vec<DVec3> = (0..3).map(|_| rng.vec(1.0)).collect();
    let v: Vec<DVec3> = (0..3).map(|_| rng.unit() * rng.range(1.0, 3.0)).collect();
    let start = verlet_rope(&x, &v, &[false; 3], &[], dt);
    let physics = physics_of(&start, DVec3::new(0.0, -9.8, 0.0));
    let input = format!(
        "one Verlet step with γ = {gamma}, dt = {dt} s of three free masses moving at about 1–3 m/s \
         under gravity 9.8 m/s²: x = [{}], last_position = [{}]",
        listed(start.masses.iter().map(|m| m.position)),
        listed(start.masses.iter().map(|m| m.last_position))
    );
    let mut got = start.clone();
    run_rope(&mut got, 1, &input, |r| hw.verlet(r, dt, gamma, &physics))?;
    let mut want = start;
    Reference.verlet(&mut want, dt, gamma, &physics);
    compare_positions(
        &input,
        &got,
        &want,
        1.0,
        "x(t+dt) = x(t) + (1 - γ)[x(t) - x(t-dt)] + a(t) dt²: the damping factor scales the last \
         displacement",
    )
}

pub(super) fn damping_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
    // Nothing pinned, so that only the damping is graded here, not the pinning.
    let start = Reference.rope(COURSE_START, COURSE_END, 3, 1.0, 100.0, &[]);
    let physics = physics_of(&start, COURSE_GRAVITY);
    let input = "100 Verlet steps with the course's γ = 0.00005, dt = 1/64 s, of the course rope \
                 dropped (3 nodes from (0, 200) to (-400, 200), none pinned, gravity (0, -1))";
    let mut got = start.clone();
    run_rope(&mut got, 100, input, |r| {
        hw.verlet(r, COURSE_DT, COURSE_DAMPING, &physics);
    })?;
    let mut want = start;
    for _ in 0..100 {
        Reference.verlet(&mut want, COURSE_DT, COURSE_DAMPING, &physics);
    }
    compare_positions(
        input,
        &got,
        &want,
        400.0,
        "x(t+dt) = x(t) + (1 - γ)[x(t) - x(t-dt)] + a(t) dt² with γ = 0.00005: the difference from \
         undamped Verlet is small but measurable",
    )
}
