//! The NYCU Computer Animation HW1 (2023, jelly) rubric: 80 of the course's 100 points.
//!
//! | course item | points | here |
//! |---|---|---|
//! | #1 springs | 15 | struct 5, shear 5, bend 5 (sets of pairs on a 10×10×10 and a 3×4×5 lattice) |
//! | #2 forces | 20 | spring force 7, damper force 7, internal force 6 |
//! | #3 collision | 20 | plane 10, bowl 10 |
//! | #4 integrators | 25 | explicit Euler 5, implicit Euler 2.5 + midpoint 2.5, RK4 15 |
//! | report | 20 | graded by hand |
//! | bonus | up to 15 | graded by hand |
//!
//! Collision checks per obstacle: bounce (only within ε and approaching; nothing when farther,
//! moving away, or above the bowl's rim) 4, projection of a particle that went through 3, contact
//! force and friction 3. Internal force: random systems 4, one spring among four particles 2.
//! The spring and damper force and the integrators are described in [`super::shared`].
//!
//! Reference: NYCU Computer Animation HW1 (2023), TODO #1–#4 and the grading sheet (`docs/course.md` §2).

use glam::DVec3;

use super::assignments::{
    Bowl, ContactCoefficients, JellyHomework, Particle, Plane, Spring, State,
};
use super::checks::{
    Rng, check_accumulated, check_damper, check_hooke, check_implicit_linear,
    check_implicit_residual, check_implicit_stable, check_one_step, check_order,
    check_oscillator_run, check_setup, describe_springs, random_springs,
};
use super::collision::{Surface, check_bounce, check_contact_force, check_penetration};
use super::reference::Reference;
use super::report::NotGraded;
use super::runner::{CheckResult, CheckSpec, Ctx, ItemSpec, Rubric, set_case};
use super::shared::{EXPLICIT, MIDPOINT, RK4, shared_items};
use super::system::Physics;
use crate::physics::SpringKind;

shared_items!(JellyHomework, "2. forces", "4. integrators");

/// The course's contact coefficients (2023): ε = 0.01 m, k_r = 0.8, k_f = 0.2.
pub(crate) const COURSE_CONTACT: ContactCoefficients = ContactCoefficients {
    epsilon: 0.01,
    restitution: 0.8,
    friction: 0.2,
};

pub(crate) fn rubric<H: JellyHomework>() -> Rubric<H> {
    let mut items = vec![ItemSpec {
        id: "springs",
        category: "1. springs",
        name: "struct, shear and bend springs",
        checks: vec![
            CheckSpec {
                name: "struct springs: axis neighbours",
                points: 5.0,
                run: springs_struct::<H>,
            },
            CheckSpec {
                name: "shear springs: the other 20 of the 26 neighbours",
                points: 5.0,
                run: springs_shear::<H>,
            },
            CheckSpec {
                name: "bend springs: axis neighbours two apart",
                points: 5.0,
                run: springs_bend::<H>,
            },
        ],
    }];
    items.extend(force_items::<H>());
    items.push(ItemSpec {
        id: "internal_force",
        category: "2. forces",
        name: "internal force",
        checks: vec![
            CheckSpec {
                name: "random systems against the reference",
                points: 4.0,
                run: internal_random::<H>,
            },
            CheckSpec {
                name: "one spring: equal and opposite on its two ends, nothing elsewhere",
                points: 2.0,
                run: internal_single::<H>,
            },
        ],
    });
    items.push(ItemSpec {
        id: "plane",
        category: "3. collision",
        name: "plane",
        checks: vec![
            CheckSpec {
                name: "bounce v' = -k_r v_N + v_T within ε when approaching, nothing otherwise",
                points: 4.0,
                run: plane_bounce::<H>,
            },
            CheckSpec {
                name: "a particle that went through is moved back onto the surface",
                points: 3.0,
                run: plane_penetration::<H>,
            },
            CheckSpec {
                name: "contact force and friction",
                points: 3.0,
                run: plane_contact::<H>,
            },
        ],
    });
    items.push(ItemSpec {
        id: "bowl",
        category: "3. collision",
        name: "bowl",
        checks: vec![
            CheckSpec {
                name: "bounce v' = -k_r v_N + v_T within ε when approaching, nothing otherwise or above the rim",
                points: 4.0,
                run: bowl_bounce::<H>,
            },
            CheckSpec {
                name: "a particle that went through is moved back onto the surface",
                points: 3.0,
                run: bowl_penetration::<H>,
            },
            CheckSpec {
                name: "contact force and friction",
                points: 3.0,
                run: bowl_contact::<H>,
            },
        ],
    });
    items.extend(integrator_items::<H>());
    Rubric {
        assignment: "jelly",
        title: "NYCU Computer Animation HW1 (2023): jelly in a bowl",
        course_max: 100.0,
        not_graded: vec![
            NotGraded {
                name: "the report".to_string(),
                points: 20.0,
                reason: "is graded by hand".to_string(),
            },
            NotGraded {
                name: "the bonus (up to 15 on top)".to_string(),
                points: 0.0,
                reason: "is graded by hand".to_string(),
            },
        ],
        items,
    }
}

// ---------------------------------------------------------------------------------------------
// Springs

/// The lattices checked: the course's 10×10×10 and a 3×4×5 one that catches swapped axes.
const LATTICES: [[usize; 3]; 2] = [[10, 10, 10], [3, 4, 5]];

fn check_kind<H: JellyHomework>(hw: &H, kind: SpringKind, hint: &str) -> CheckResult {
    for counts in LATTICES {
        let want = Reference.springs(counts);
        let particles = counts.iter().product();
        let label = |i: usize| {
            let (ix, iy, iz) = (
                i % counts[0],
                (i / counts[0]) % counts[1],
                i / (counts[0] * counts[1]),
            );
            format!("({ix},{iy},{iz})")
        };
        let input = format!(
            "springs([{}, {}, {}]): particle (ix, iy, iz) has index ix + nx (iy + ny iz)",
            counts[0], counts[1], counts[2]
        );
        set_case(&input);
        let got = hw.springs(counts);
        check_setup(kind, &input, &got, &want, particles, &label, hint)?;
    }
    Ok(())
}

fn springs_struct<H: JellyHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Struct,
        "struct springs join each particle to (ix+1, iy, iz), (ix, iy+1, iz) and (ix, iy, iz+1) \
         when inside the lattice",
    )
}

fn springs_shear<H: JellyHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Shear,
        "shear springs join the 20 neighbours of the 3×3×3 block that are not axis neighbours: \
         12 face diagonals such as (ix+1, iy-1, iz) and 8 body diagonals such as (ix+1, iy-1, \
         iz+1); generating 10 offsets per particle lists each pair once",
    )
}

fn springs_bend<H: JellyHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Bend,
        "bend springs join each particle to (ix+2, iy, iz), (ix, iy+2, iz) and (ix, iy, iz+2) \
         when inside the lattice",
    )
}

// ---------------------------------------------------------------------------------------------
// Internal force

fn own_internal<H: JellyHomework>(
    hw: &H,
    x: &[DVec3],
    v: &[DVec3],
    springs: &[Spring],
) -> Vec<DVec3> {
    let mut f = vec![DVec3::ZERO; x.len()];
    for s in springs {
        let fa = hw.spring_force(x[s.a], x[s.b], s.stiffness, s.rest_length)
            + hw.damper_force(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
        f[s.a] += fa;
        f[s.b] -= fa;
    }
    f
}

fn check_internal<H: JellyHomework>(
    hw: &H,
    x: &[DVec3],
    v: &[DVec3],
    springs: &[Spring],
) -> CheckResult {
    let input = format!("internal_forces of {}", describe_springs(x, v, springs));
    set_case(&input);
    let got = hw.internal_forces(x, v, springs);
    let want = Reference.internal_forces(x, v, springs);
    let own = || own_internal(hw, x, v, springs);
    let scale = springs
        .iter()
        .map(|s| s.stiffness * s.rest_length + s.damping)
        .sum::<f64>();
    check_accumulated(
        &input,
        &got,
        &want,
        &own,
        scale,
        "N",
        "for every spring f_a = spring + damper force on a, added to a, and -f_a added to b",
    )
}

fn internal_random<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 2001);
    for _ in 0..3 {
        let (x, v, springs) = random_springs(&mut rng, 6, 10);
        check_internal(hw, &x, &v, &springs)?;
    }
    Ok(())
}

fn internal_single<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 2002);
    let (x, v, _) = random_springs(&mut rng, 4, 0);
    let springs = [Spring {
        a: 3,
        b: 1,
        rest_length: 0.5 * (x[1] - x[3]).length(),
        stiffness: 300.0,
        damping: 4.0,
    }];
    check_internal(hw, &x, &v, &springs)
}

// ---------------------------------------------------------------------------------------------
// Collision

/// A plane for case `i`: the course floor `y = 0` first, then tilted random planes.
fn plane(rng: &mut Rng, i: usize) -> Surface {
    let plane = if i == 0 {
        Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        }
    } else {
        Plane {
            point: rng.vec(2.0),
            normal: rng.unit(),
        }
    };
    Surface::Plane(plane)
}

/// A bowl for case `i`: the course bowl first, then random hemispheres.
fn bowl(rng: &mut Rng, i: usize) -> Surface {
    let a = 9.0 / 2f64.sqrt();
    let bowl = if i == 0 {
        Bowl {
            center: DVec3::new(2.0, a, 1.0),
            radius: 9.0,
            rim_height: 0.0,
        }
    } else {
        let center = rng.vec(3.0);
        Bowl {
            center,
            radius: rng.range(4.0, 10.0),
            rim_height: center.y,
        }
    };
    Surface::Bowl(bowl)
}

fn plane_fn<H: JellyHomework>(hw: &H) -> impl Fn(&Surface, &mut Particle) + '_ {
    move |s, p| {
        if let Surface::Plane(plane) = s {
            hw.plane_collision(plane, p, &COURSE_CONTACT);
        }
    }
}

fn bowl_fn<H: JellyHomework>(hw: &H) -> impl Fn(&Surface, &mut Particle) + '_ {
    move |s, p| {
        if let Surface::Bowl(bowl) = s {
            hw.bowl_collision(bowl, p, &COURSE_CONTACT);
        }
    }
}

fn plane_bounce<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3001);
    check_bounce(
        &plane_fn(hw),
        &plane_fn(&Reference),
        &mut rng,
        &plane,
        &COURSE_CONTACT,
    )
}

fn plane_penetration<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3002);
    check_penetration(
        &plane_fn(hw),
        &plane_fn(&Reference),
        &mut rng,
        &plane,
        &COURSE_CONTACT,
    )
}

fn plane_contact<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3003);
    check_contact_force(
        &plane_fn(hw),
        &plane_fn(&Reference),
        &mut rng,
        &plane,
        &COURSE_CONTACT,
    )
}

fn bowl_bounce<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3101);
    check_bounce(
        &bowl_fn(hw),
        &bowl_fn(&Reference),
        &mut rng,
        &bowl,
        &COURSE_CONTACT,
    )
}

fn bowl_penetration<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3102);
    check_penetration(
        &bowl_fn(hw),
        &bowl_fn(&Reference),
        &mut rng,
        &bowl,
        &COURSE_CONTACT,
    )
}

fn bowl_contact<H: JellyHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 3103);
    check_contact_force(
        &bowl_fn(hw),
        &bowl_fn(&Reference),
        &mut rng,
        &bowl,
        &COURSE_CONTACT,
    )
}
