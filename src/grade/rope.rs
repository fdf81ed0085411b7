//! The GAMES101 assignment 8 rubric (35 points, all graded here).
//!
//! | item | points | checks |
//! |---|---|---|
//! | builds and runs | 5 | the crate compiled and the grader ran (through `springlab grade`: 0 when the build fails) |
//! | rope construction | 5 | positions 2, masses and pins 1.5, springs 1.5 |
//! | semi-implicit Euler | 5 | Hooke's law 1, net rope forces 1, one step 2, 200 steps of the course rope 1 |
//! | explicit Euler | 5 | one step 3, measured order 1 on the oscillator 2 |
//! | Verlet | 10 | free fall 3, projection with a pinned end 3, projection of two free ends 2, course rope 2 |
//! | damping | 5 | one step with γ = 0.1 3, 100 steps of the dropped course rope with γ = 0.00005 2 |
//!
//! Hooke's law has no item of its own in the course's rubric; it is graded with semi-implicit
//! Euler, the Euler method the course asks students to hand in (explicit Euler is handed in
//! commented out). The Verlet checks use γ = 0, so a Verlet without damping loses only the damping
//! item. The course's −2 penalties (files left in, missing README or screenshots) are for a human.
//!
//! Reference: GAMES101 assignment 8 (2020), §1.1–1.4 and §3 (grading).

use glam::DVec3;

use super::assignments::{Mass, Rope, RopeHomework, Spring, State};
use super::checks::{
    REL, Rng, check_accumulated, check_hooke, check_one_step, check_order, close, finite, num,
    vec3, wrong,
};
use super::reference::{Reference, model_of};
use super::runner::{CheckResult, CheckSpec, Ctx, ItemSpec, Rubric, set_case};
use super::system::Physics;

/// The course rope: `(0, 200) → (-400, 200)` px, node mass 1, k = 100, node 0 pinned.
const COURSE_START: DVec3 = DVec3::new(0.0, 200.0, 0.0);
const COURSE_END: DVec3 = DVec3::new(-400.0, 200.0, 0.0);
/// The course's gravity (px/s²) and step (1/64 s).
const COURSE_GRAVITY: DVec3 = DVec3::new(0.0, -1.0, 0.0);
const COURSE_DT: f64 = 1.0 / 64.0;
/// The course's Verlet damping factor.
const COURSE_DAMPING: f64 = 0.00005;

pub(crate) fn rubric<H: RopeHomework>() -> Rubric<H> {
    Rubric {
        assignment: "rope",
        title: "GAMES101 assignment 8 (2020): rope simulation",
        course_max: 35.0,
        not_graded: Vec::new(),
        items: vec![
            ItemSpec {
                id: "builds",
                category: "",
                name: "builds and runs",
                checks: vec![CheckSpec {
                    name: "the crate compiled and the grader ran it",
                    points: 5.0,
                    run: builds::<H>,
                }],
            },
            ItemSpec {
                id: "rope",
                category: "",
                name: "rope construction",
                checks: vec![
                    CheckSpec {
                        name: "nodes evenly spaced from start to end",
                        points: 2.0,
                        run: rope_positions::<H>,
                    },
                    CheckSpec {
                        name: "node masses, pinned nodes, at rest",
                        points: 1.5,
                        run: rope_masses::<H>,
                    },
                    CheckSpec {
                        name: "a spring between each pair of neighbours, rest length = spacing",
                        points: 1.5,
                        run: rope_springs::<H>,
                    },
                ],
            },
            ItemSpec {
                id: "semi_implicit",
                category: "",
                name: "semi-implicit Euler (with Hooke's law)",
                checks: vec![
                    CheckSpec {
                        name: "Hooke's law on random stretched and compressed springs",
                        points: 1.0,
                        run: hooke::<H>,
                    },
                    CheckSpec {
                        name: "net spring forces on a rope (equal and opposite on both ends)",
                        points: 1.0,
                        run: rope_forces::<H>,
                    },
                    CheckSpec {
                        name: "one step against the reference",
                        points: 2.0,
                        run: semi_one_step::<H>,
                    },
                    CheckSpec {
                        name: "200 steps of the course rope (dt = 1/64)",
                        points: 1.0,
                        run: semi_course_rope::<H>,
                    },
                ],
            },
            ItemSpec {
                id: "explicit",
                category: "",
                name: "explicit Euler",
                checks: vec![
                    CheckSpec {
                        name: "one step against the reference",
                        points: 3.0,
                        run: explicit_one_step::<H>,
                    },
                    CheckSpec {
                        name: "first order on the oscillator (measured)",
                        points: 2.0,
                        run: explicit_order::<H>,
                    },
                ],
            },
            ItemSpec {
                id: "verlet",
                category: "",
                name: "Verlet with constraints",
                checks: vec![
                    CheckSpec {
                        name: "free fall: x + (x - x_last) + a dt², three steps",
                        points: 3.0,
                        run: verlet_free_fall::<H>,
                    },
                    CheckSpec {
                        name: "projection with a pinned end: the pinned end stays, the free end takes all",
                        points: 3.0,
                        run: verlet_pinned::<H>,
                    },
                    CheckSpec {
                        name: "projection of two free ends: half each, rest length restored",
                        points: 2.0,
                        run: verlet_free_pair::<H>,
                    },
                    CheckSpec {
                        name: "the course rope (16 nodes, 640 steps): falls, keeps its lengths, pin holds",
                        points: 2.0,
                        run: verlet_course_rope::<H>,
                    },
                ],
            },
            ItemSpec {
                id: "damping",
                category: "",
                name: "Verlet damping",
                checks: vec![
                    CheckSpec {
                        name: "one step with γ = 0.1: x + (1 - γ)(x - x_last) + a dt²",
                        points: 3.0,
                        run: damping_one_step::<H>,
                    },
                    CheckSpec {
                        name: "100 steps of the course rope, dropped, with γ = 0.00005",
                        points: 2.0,
                        run: damping_course_rope::<H>,
                    },
                ],
            },
        ],
    }
}

fn builds<H: RopeHomework>(_: &H, _: &Ctx) -> CheckResult {
    // Reaching this line means the crate compiled and its grading test runs.
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Rope construction

struct RopeCase {
    start: DVec3,
    end: DVec3,
    nodes: usize,
    mass: f64,
    stiffness: f64,
    pinned: Vec<usize>,
}

impl RopeCase {
    fn describe(&self) -> String {
        format!(
            "rope({}, {}, nodes = {}, node_mass = {}, k = {}, pinned = {:?})",
            vec3(self.start),
            vec3(self.end),
            self.nodes,
            num(self.mass),
            num(self.stiffness),
            self.pinned
        )
    }

    fn build<H: RopeHomework>(&self, hw: &H) -> Rope {
        hw.rope(
            self.start,
            self.end,
            self.nodes,
            self.mass,
            self.stiffness,
            &self.pinned,
        )
    }
}

fn rope_cases(ctx: &Ctx) -> Vec<RopeCase> {
    let mut rng = Rng::new(ctx.seed, 101);
    vec![
        RopeCase {
            start: COURSE_START,
            end: COURSE_END,
            nodes: 3,
            mass: 1.0,
            stiffness: 100.0,
            pinned: vec![0],
        },
        RopeCase {
            start: COURSE_START,
            end: COURSE_END,
            nodes: 16,
            mass: 1.0,
            stiffness: 100.0,
            pinned: vec![0],
        },
        RopeCase {
            start: rng.vec(3.0),
            end: rng.vec(3.0),
            nodes: 2,
            mass: rng.range(0.1, 2.0),
            stiffness: rng.range(10.0, 500.0),
            pinned: Vec::new(),
        },
        RopeCase {
            start: rng.vec(3.0),
            end: rng.vec(3.0),
            nodes: 7,
            mass: rng.range(0.1, 2.0),
            stiffness: rng.range(10.0, 500.0),
            pinned: vec![0, 6],
        },
    ]
}

/// The student's rope for `case`, with the node count checked.
fn built<H: RopeHomework>(hw: &H, case: &RopeCase) -> Result<Rope, super::runner::Failure> {
    let input = case.describe();
    set_case(&input);
    let rope = case.build(hw);
    if rope.masses.len() != case.nodes {
        return Err(wrong(
            input,
            format!("{} masses", case.nodes),
            format!("{} masses", rope.masses.len()),
            "create one Mass per node, including both ends",
        ));
    }
    let x: Vec<DVec3> = rope.masses.iter().map(|m| m.position).collect();
    finite("position", &input, &x)?;
    Ok(rope)
}

fn rope_positions<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    for case in rope_cases(ctx) {
        let rope = built(hw, &case)?;
        let want = case.build(&Reference);
        let scale = (case.end - case.start).length();
        for (i, (g, w)) in rope.masses.iter().zip(&want.masses).enumerate() {
            if !close(g.position, w.position, REL, scale) {
                return Err(wrong(
                    case.describe(),
                    format!("node {i} at {}", vec3(w.position)),
                    format!("node {i} at {}", vec3(g.position)),
                    "node i sits at start + (end - start) · i / (nodes - 1): the first at start, \
                     the last at end",
                ));
            }
        }
    }
    Ok(())
}

fn rope_masses<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    for case in rope_cases(ctx) {
        let rope = built(hw, &case)?;
        for (i, m) in rope.masses.iter().enumerate() {
            let pinned = case.pinned.contains(&i);
            let problem = if (m.mass - case.mass).abs() > 1e-12 * case.mass {
                Some((
                    format!("node {i} of mass {} kg", num(case.mass)),
                    format!("mass {} kg", num(m.mass)),
                    "every node has mass node_mass",
                ))
            } else if m.pinned != pinned {
                Some((
                    format!("node {i} pinned = {pinned}"),
                    format!("pinned = {}", m.pinned),
                    "pin exactly the nodes listed in `pinned` (the course's loop over pinned_nodes)",
                ))
            } else if m.velocity != DVec3::ZERO || m.last_position != m.position {
                Some((
                    format!("node {i} at rest: velocity 0, last_position = position"),
                    format!(
                        "velocity {}, last_position {}",
                        vec3(m.velocity),
                        vec3(m.last_position)
                    ),
                    "a new rope is at rest; Verlet reads last_position, so set it to the position",
                ))
            } else {
                None
            };
            if let Some((expected, got, hint)) = problem {
                return Err(wrong(case.describe(), expected, got, hint));
            }
        }
    }
    Ok(())
}

fn rope_springs<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    for case in rope_cases(ctx) {
        let rope = built(hw, &case)?;
        let input = case.describe();
        if rope.springs.len() != case.nodes - 1 {
            return Err(wrong(
                input,
                format!("{} springs", case.nodes - 1),
                format!("{} springs", rope.springs.len()),
                "one spring between each pair of consecutive nodes",
            ));
        }
        let spacing = (case.end - case.start).length() / (case.nodes - 1) as f64;
        let mut seen = vec![false; case.nodes - 1];
        for s in &rope.springs {
            let (lo, hi) = (s.a.min(s.b), s.a.max(s.b));
            if hi >= case.nodes || hi != lo + 1 || seen[lo] {
                return Err(wrong(
                    input,
                    "springs (0, 1), (1, 2), …, each once",
                    format!("a spring ({}, {})", s.a, s.b),
                    "join node i to node i + 1, for i = 0 … nodes - 2",
                ));
            }
            seen[lo] = true;
            if (s.rest_length - spacing).abs() > 1e-9 * spacing
                || s.stiffness != case.stiffness
                || s.damping != 0.0
            {
                return Err(wrong(
                    input,
                    format!(
                        "spring ({lo}, {hi}): rest length {} (the initial spacing), stiffness {}, damping 0",
                        num(spacing),
                        num(case.stiffness)
                    ),
                    format!(
                        "rest length {}, stiffness {}, damping {}",
                        num(s.rest_length),
                        num(s.stiffness),
                        num(s.damping)
                    ),
                    "the rest length is the distance between the two nodes as built",
                ));
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Forces

fn hooke<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let student = |xa, xb, _, _, k, l| hw.spring_force(xa, xb, k, l);
    let reference = |xa, xb, _, _, k, l| Reference.spring_force(xa, xb, k, l);
    let mut rng = Rng::new(ctx.seed, 201);
    check_hooke(&student, &reference, &mut rng, true)?;
    check_hooke(&student, &reference, &mut rng, false)
}

/// A random rope of `n` nodes along x (0.5 m apart, jittered), node 0 pinned, moving.
fn random_rope(rng: &mut Rng, n: usize) -> Rope {
    let masses: Vec<Mass> = (0..n)
        .map(|i| {
            let position = DVec3::new(0.5 * i as f64, 0.0, 0.0) + rng.vec(0.1);
            let velocity = if i == 0 { DVec3::ZERO } else { rng.vec(1.0) };
            Mass {
                position,
                velocity,
                last_position: position,
                mass: rng.range(0.5, 2.0),
                pinned: i == 0,
            }
        })
        .collect();
    let springs = (0..n - 1)
        .map(|i| Spring {
            a: i,
            b: i + 1,
            rest_length: (masses[i + 1].position - masses[i].position).length()
                * rng.range(0.8, 1.2),
            stiffness: rng.range(20.0, 200.0),
            damping: 0.0,
        })
        .collect();
    Rope { masses, springs }
}

fn describe_rope(rope: &Rope) -> String {
    let nodes: Vec<String> = rope
        .masses
        .iter()
        .take(3)
        .map(|m| vec3(m.position))
        .collect();
    let springs: Vec<String> = rope
        .springs
        .iter()
        .take(3)
        .map(|s| {
            format!(
                "({}, {}, L0 {}, k {})",
                s.a,
                s.b,
                num(s.rest_length),
                num(s.stiffness)
            )
        })
        .collect();
    format!(
        "a rope of {} nodes at [{}, …], springs [{}, …]",
        rope.masses.len(),
        nodes.join(", "),
        springs.join(", ")
    )
}

fn rope_forces<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 202);
    for _ in 0..3 {
        let rope = random_rope(&mut rng, 6);
        let input = describe_rope(&rope);
        set_case(&input);
        let got = hw.spring_forces(&rope);
        let want = Reference.spring_forces(&rope);
        // The student's own Hooke forces, accumulated correctly: a wrong spring_force is charged
        // in the Hooke check, not again here.
        let own = || {
            let mut own = vec![DVec3::ZERO; rope.masses.len()];
            for s in &rope.springs {
                let f = hw.spring_force(
                    rope.masses[s.a].position,
                    rope.masses[s.b].position,
                    s.stiffness,
                    s.rest_length,
                );
                own[s.a] += f;
                own[s.b] -= f;
            }
            own
        };
        let scale = rope
            .springs
            .iter()
            .map(|s| s.stiffness * s.rest_length)
            .sum::<f64>();
        check_accumulated(
            &input,
            &got,
            &want,
            &own,
            scale,
            "N",
            "for each spring, f on end a and -f on end b, summed per mass",
        )?;
    }
    Ok(())
}

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

fn semi_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 301);
    check_one_step(&semi_step(hw), &semi_step(&Reference), &mut rng, SEMI)
}

fn explicit_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 302);
    check_one_step(
        &explicit_step(hw),
        &explicit_step(&Reference),
        &mut rng,
        EXPLICIT,
    )
}

fn explicit_order<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
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

fn semi_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
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

fn verlet_free_fall<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
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

fn verlet_pinned<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
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

fn verlet_free_pair<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
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

fn verlet_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
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

fn damping_one_step<H: RopeHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
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

fn damping_course_rope<H: RopeHomework>(hw: &H, _: &Ctx) -> CheckResult {
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
