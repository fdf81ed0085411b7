//! The NYCU Computer Animation HW1 (2022, cloth) rubric: 80 of the course's 100 points.
//!
//! | course item | points | here |
//! |---|---|---|
//! | #1 springs | 15 | struct 5, shear 5, bend 5 (sets of pairs on a 25×25 and a 4×4 cloth) |
//! | #2 forces | 20 | spring force 7, damper force 7, accelerations 6 |
//! | #3 collisions | 20 | sphere–cloth impulse: e = 0 and no impulse when apart or separating 8, e = 0.8 4, pinned particle 3, separation 5 |
//! | #4 integrators | 25 | explicit Euler 5, implicit Euler 2.5, midpoint 2.5, RK4 15 |
//! | report | 20 | graded by hand |
//! | bonus (friction, rolling sphere) | — | graded by hand |
//!
//! The 2022 rubric does not split its 25 integrator points; the 2023 split is used. The sphere
//! impulse is the course's `J = -(1 + e)(v_rel·d̂)/(w_s + w_p)`; the separation removes the
//! whole penetration in proportion to the inverse masses (the course's reference pushed by
//! 0.15 of it, which leaves the cloth inside the sphere for several steps).
//!
//! Reference: NYCU Computer Animation HW1 (2022), TODO #1–#4 (`docs/course.md` §3).

use glam::DVec3;

use super::assignments::{Body, ClothHomework, Spring, State};
use super::checks::{
    REL, Rng, check_accumulated, check_damper, check_hooke, check_implicit_linear,
    check_implicit_residual, check_implicit_stable, check_one_step, check_order,
    check_oscillator_run, check_setup, close, describe_springs, finite, num, random_springs, vec3,
    wrong,
};
use super::reference::Reference;
use super::report::NotGraded;
use super::runner::{CheckResult, CheckSpec, Ctx, ItemSpec, Rubric, set_case};
use super::shared::{EXPLICIT, MIDPOINT, RK4, shared_items};
use super::system::Physics;
use crate::physics::SpringKind;

shared_items!(ClothHomework, "2. forces", "4. integrators");

pub(crate) fn rubric<H: ClothHomework>() -> Rubric<H> {
    let mut items = vec![ItemSpec {
        id: "springs",
        category: "1. springs",
        name: "struct, shear and bend springs",
        checks: vec![
            CheckSpec {
                name: "struct springs: grid neighbours",
                points: 5.0,
                run: springs_struct::<H>,
            },
            CheckSpec {
                name: "shear springs: both diagonals",
                points: 5.0,
                run: springs_shear::<H>,
            },
            CheckSpec {
                name: "bend springs: grid neighbours two apart",
                points: 5.0,
                run: springs_bend::<H>,
            },
        ],
    }];
    items.extend(force_items::<H>());
    items.push(ItemSpec {
        id: "accelerations",
        category: "2. forces",
        name: "accelerations a = w Σf",
        checks: vec![
            CheckSpec {
                name: "random systems with pinned particles against the reference",
                points: 4.0,
                run: accelerations_random::<H>,
            },
            CheckSpec {
                name: "one spring: a_a = w_a f_a, a_b = -w_b f_a, nothing elsewhere",
                points: 2.0,
                run: accelerations_single::<H>,
            },
        ],
    });
    items.push(ItemSpec {
        id: "sphere",
        category: "3. collisions",
        name: "sphere–cloth impulse",
        checks: vec![
            CheckSpec {
                name: "impulse with e = 0 when touching and approaching, none when apart or separating",
                points: 8.0,
                run: sphere_impulse::<H>,
            },
            CheckSpec {
                name: "impulse with e = 0.8",
                points: 4.0,
                run: sphere_restitution::<H>,
            },
            CheckSpec {
                name: "a pinned particle (w = 0) does not move; the sphere bounces off it",
                points: 3.0,
                run: sphere_pinned::<H>,
            },
            CheckSpec {
                name: "separation: pushed apart to touching, in proportion to the inverse masses",
                points: 5.0,
                run: sphere_separation::<H>,
            },
        ],
    });
    items.extend(integrator_items::<H>());
    Rubric {
        assignment: "cloth",
        title: "NYCU Computer Animation HW1 (2022): cloth and spheres",
        course_max: 100.0,
        not_graded: vec![
            NotGraded {
                name: "the report".to_string(),
                points: 20.0,
                reason: "is graded by hand".to_string(),
            },
            NotGraded {
                name: "the bonus (friction, rolling sphere; on top)".to_string(),
                points: 0.0,
                reason: "is graded by hand".to_string(),
            },
        ],
        items,
    }
}

// ---------------------------------------------------------------------------------------------
// Springs

fn check_kind<H: ClothHomework>(hw: &H, kind: SpringKind, hint: &str) -> CheckResult {
    for n in [25, 4] {
        let want = Reference.springs(n);
        let label = |i: usize| format!("({},{})", i / n, i % n);
        let input = format!("springs({n}): particle (row r, column c) has index r n + c");
        set_case(&input);
        let got = hw.springs(n);
        check_setup(kind, &input, &got, &want, n * n, &label, hint)?;
    }
    Ok(())
}

fn springs_struct<H: ClothHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Struct,
        "struct springs join (r, c) to (r, c+1) and (r+1, c) when inside the cloth",
    )
}

fn springs_shear<H: ClothHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Shear,
        "shear springs join (r, c) to (r+1, c+1) and (r+1, c-1) when inside the cloth",
    )
}

fn springs_bend<H: ClothHomework>(hw: &H, _: &Ctx) -> CheckResult {
    check_kind(
        hw,
        SpringKind::Bend,
        "bend springs join (r, c) to (r, c+2) and (r+2, c) when inside the cloth",
    )
}

// ---------------------------------------------------------------------------------------------
// Accelerations

fn check_accelerations<H: ClothHomework>(
    hw: &H,
    x: &[DVec3],
    v: &[DVec3],
    w: &[f64],
    springs: &[Spring],
) -> CheckResult {
    let input = format!(
        "spring_accelerations of {}; inverse masses {:?}",
        describe_springs(x, v, springs),
        w.iter().map(|w| num(*w)).collect::<Vec<_>>()
    );
    set_case(&input);
    let got = hw.spring_accelerations(x, v, w, springs);
    let want = Reference.spring_accelerations(x, v, w, springs);
    let own = || {
        let mut own = vec![DVec3::ZERO; x.len()];
        for s in springs {
            let fa = hw.spring_force(x[s.a], x[s.b], s.stiffness, s.rest_length)
                + hw.damper_force(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
            own[s.a] += w[s.a] * fa;
            own[s.b] -= w[s.b] * fa;
        }
        own
    };
    let scale = springs
        .iter()
        .map(|s| s.stiffness * s.rest_length + s.damping)
        .sum::<f64>()
        * w.iter().copied().fold(0.0, f64::max);
    check_accumulated(
        &input,
        &got,
        &want,
        &own,
        scale,
        "m/s²",
        "a_i = w_i Σ f_i with f_a = spring + damper force on a and -f_a on b (w = 0: no motion)",
    )
}

fn accelerations_random<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 4001);
    for _ in 0..3 {
        let (x, v, springs) = random_springs(&mut rng, 6, 10);
        let mut w: Vec<f64> = (0..6).map(|_| rng.range(0.5, 2.0)).collect();
        w[rng.index(6)] = 0.0;
        check_accelerations(hw, &x, &v, &w, &springs)?;
    }
    Ok(())
}

fn accelerations_single<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 4002);
    let (x, v, _) = random_springs(&mut rng, 4, 0);
    let springs = [Spring {
        a: 2,
        b: 0,
        rest_length: 0.5 * (x[0] - x[2]).length(),
        stiffness: 300.0,
        damping: 4.0,
    }];
    check_accelerations(hw, &x, &v, &[0.5, 1.0, 2.0, 1.0], &springs)
}

// ---------------------------------------------------------------------------------------------
// Sphere–cloth impulse

/// A sphere and a particle: `gap` is the particle's distance from the surface (m; < 0 inside),
/// `vn` the normal relative velocity `(v_p - v_s)·d̂` (m/s; < 0 approaching).
struct SphereCase {
    sphere: Body,
    radius: f64,
    particle: Body,
    restitution: f64,
}

impl SphereCase {
    /// A case with the gap, normal relative velocity and particle inverse mass drawn from the
    /// given ranges.
    fn new(
        rng: &mut Rng,
        gap: [f64; 2],
        vn: [f64; 2],
        w_particle: [f64; 2],
        restitution: f64,
    ) -> SphereCase {
        let gap = rng.range(gap[0], gap[1]);
        let vn = rng.range(vn[0], vn[1]);
        let w_particle = rng.range(w_particle[0], w_particle[1]);
        let radius = rng.range(0.3, 1.0);
        let center = rng.vec(2.0);
        let d = rng.unit();
        let v_sphere = rng.vec(0.5);
        let v_particle = v_sphere + vn * d + rng.perpendicular(d) * rng.range(0.0, 1.0);
        SphereCase {
            sphere: Body {
                x: center,
                v: v_sphere,
                inverse_mass: if rng.range(0.0, 1.0) < 0.5 {
                    1.0 / 125.0
                } else {
                    rng.range(0.001, 0.5)
                },
            },
            radius,
            particle: Body {
                x: center + d * (radius + gap),
                v: v_particle,
                inverse_mass: w_particle,
            },
            restitution,
        }
    }

    fn describe(&self) -> String {
        format!(
            "sphere at {} moving {} (radius {} m, w = {} 1/kg); particle at {} moving {} (w = {} \
             1/kg, {} m from the surface); restitution {}",
            vec3(self.sphere.x),
            vec3(self.sphere.v),
            num(self.radius),
            num(self.sphere.inverse_mass),
            vec3(self.particle.x),
            vec3(self.particle.v),
            num(self.particle.inverse_mass),
            num((self.particle.x - self.sphere.x).length() - self.radius),
            num(self.restitution)
        )
    }

    /// `(sphere, particle)` after the student's and the reference's handler.
    fn run<H: ClothHomework>(
        &self,
        hw: &H,
    ) -> Result<([Body; 2], [Body; 2]), super::runner::Failure> {
        let (mut s, mut p) = (self.sphere, self.particle);
        set_case(&self.describe());
        hw.sphere_collision(&mut s, self.radius, &mut p, self.restitution);
        finite(
            "(sphere x, v, particle x, v)",
            &self.describe(),
            &[s.x, s.v, p.x, p.v],
        )?;
        let (mut rs, mut rp) = (self.sphere, self.particle);
        Reference.sphere_collision(&mut rs, self.radius, &mut rp, self.restitution);
        Ok(([s, p], [rs, rp]))
    }
}

/// Compares the chosen fields (`velocities`, `positions`) of the two bodies.
fn compare_bodies(
    case: &SphereCase,
    got: &[Body; 2],
    want: &[Body; 2],
    velocities: bool,
    positions: bool,
    hint: &str,
) -> CheckResult {
    for (who, g, w) in [("sphere", got[0], want[0]), ("particle", got[1], want[1])] {
        let mut fields = Vec::new();
        if velocities {
            fields.push(("v", g.v, w.v));
        }
        if positions {
            fields.push(("x", g.x, w.x));
        }
        for (what, gv, wv) in fields {
            if !close(gv, wv, REL, 1.0) {
                return Err(wrong(
                    case.describe(),
                    format!("{who} {what}' = {}", vec3(wv)),
                    format!("{who} {what}' = {}", vec3(gv)),
                    hint,
                ));
            }
        }
    }
    Ok(())
}

const IMPULSE: &str = "touching when |x_p - x_s| < r and approaching when v_rel = (v_p - v_s)·d̂ < 0 \
     with d̂ = (x_p - x_s)/|x_p - x_s|; then J = -(1 + e) v_rel / (w_s + w_p), v_s -= w_s J d̂, \
     v_p += w_p J d̂";

fn sphere_impulse<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 5001);
    for _ in 0..3 {
        // Touching and approaching: impulse.
        let case = SphereCase::new(&mut rng, [-0.05, -0.001], [-3.0, -0.5], [0.5, 2.0], 0.0);
        let (got, want) = case.run(hw)?;
        compare_bodies(&case, &got, &want, true, false, IMPULSE)?;
        // Apart: nothing at all.
        let case = SphereCase::new(&mut rng, [0.01, 0.5], [-3.0, -0.5], [0.5, 2.0], 0.0);
        let (got, want) = case.run(hw)?;
        compare_bodies(
            &case,
            &got,
            &want,
            true,
            true,
            "the particle is outside the sphere (|x_p - x_s| ≥ r): no collision, nothing changes",
        )?;
        // Touching but separating: no impulse.
        let case = SphereCase::new(&mut rng, [-0.05, -0.001], [0.2, 2.0], [0.5, 2.0], 0.0);
        let (got, want) = case.run(hw)?;
        compare_bodies(
            &case,
            &got,
            &want,
            true,
            false,
            "v_rel = (v_p - v_s)·d̂ > 0: the bodies already separate, so no impulse",
        )?;
    }
    Ok(())
}

fn sphere_restitution<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 5002);
    for _ in 0..4 {
        let case = SphereCase::new(&mut rng, [-0.05, -0.001], [-3.0, -0.5], [0.5, 2.0], 0.8);
        let (got, want) = case.run(hw)?;
        compare_bodies(&case, &got, &want, true, false, IMPULSE)?;
    }
    Ok(())
}

fn sphere_pinned<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 5003);
    for _ in 0..3 {
        let case = SphereCase::new(&mut rng, [-0.05, -0.001], [-3.0, -0.5], [0.0, 0.0], 0.0);
        let (got, want) = case.run(hw)?;
        if got[1].x != case.particle.x || got[1].v != case.particle.v {
            return Err(wrong(
                case.describe(),
                "the pinned particle keeps its position and velocity",
                format!("particle x' = {}, v' = {}", vec3(got[1].x), vec3(got[1].v)),
                "a pinned particle has w = 0: every change of it is multiplied by w_p",
            ));
        }
        compare_bodies(
            &case,
            &got,
            &want,
            true,
            true,
            "with w_p = 0 the sphere takes the whole impulse J = -(1 + e) v_rel / w_s and the \
             whole separation",
        )?;
    }
    Ok(())
}

fn sphere_separation<H: ClothHomework>(hw: &H, ctx: &Ctx) -> CheckResult {
    let mut rng = Rng::new(ctx.seed, 5004);
    for vn in [[-2.0, -0.5], [0.5, 2.0], [-4.0, -1.0], [0.2, 1.0]] {
        let case = SphereCase::new(&mut rng, [-0.1, -0.01], vn, [0.5, 2.0], 0.0);
        let (got, want) = case.run(hw)?;
        compare_bodies(
            &case,
            &got,
            &want,
            false,
            true,
            "after the impulse, remove the penetration p = r - |x_p - x_s|: x_s -= w_s/(w_s + w_p) \
             p d̂, x_p += w_p/(w_s + w_p) p d̂ (also when they already separate)",
        )?;
    }
    Ok(())
}
