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

mod integrators;
use integrators::{
    damping_course_rope, damping_one_step, explicit_one_step, explicit_order, semi_course_rope,
    semi_one_step, verlet_course_rope, verlet_free_fall, verlet_free_pair, verlet_pinned,
};

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
