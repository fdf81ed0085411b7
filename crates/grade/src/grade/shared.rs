//! Rubric items the jelly (2023) and the cloth (2022) have in common: the spring and damper
//! force, and the four integrators. The two traits are separate (each mirrors its course), so the
//! items are generated for each by [`shared_items!`].
//!
//! | item | points | checks |
//! |---|---|---|
//! | spring force | 7 | random stretched pairs 3.5, random compressed pairs 3.5 |
//! | damper force | 7 | random pairs 4, only the velocity along the spring is damped 3 |
//! | explicit Euler | 5 | one step on random systems 3, 100 oscillator steps 1, measured order 1 |
//! | implicit Euler | 2.5 | exact on the linear oscillator 1, stable at dt·ω = 10 1, solves the implicit equation 0.5 |
//! | midpoint | 2.5 | one step 1, 100 oscillator steps 0.5, measured order 2 1 |
//! | RK4 | 15 | one step 6, 100 oscillator steps 3, measured order 4 6 |
//!
//! The 2023 rubric gives "implicit + midpoint" 5 points together; here they are two items of 2.5,
//! so that a broken implicit step does not take the midpoint's points with it. The course's
//! "implicit Euler" was a predictor–corrector (`docs/course.md` §4): it passes none of the implicit
//! checks, which ask for a real backward Euler step.

/// Force and integrator constants shared by the generated items.
pub(crate) const EXPLICIT: &str = "x' = x + dt v (OLD velocity), v' = v + dt a(x, v)";
pub(crate) const MIDPOINT: &str = "x_mid = x + dt/2 v, v_mid = v + dt/2 a(x, v); \
     x' = x + dt v_mid, v' = v + dt a(x_mid, v_mid)";
pub(crate) const RK4: &str = "k1 = (v, a(x, v)), k2, k3 at half steps, k4 at a full step; \
     x' = x + dt/6 (k1x + 2 k2x + 2 k3x + k4x), v' = v + dt/6 (k1v + 2 k2v + 2 k3v + k4v)";

/// Generates, for the homework trait `$tr`, `force_items` (spring and damper force) and
/// `integrator_items` (explicit Euler, implicit Euler, midpoint, RK4) with the check functions
/// they call.
macro_rules! shared_items {
    ($tr:ident, $category_forces:expr, $category_integrators:expr) => {
        /// The spring and damper force items.
        pub(crate) fn force_items<H: $tr>() -> Vec<ItemSpec<H>> {
            vec![
                ItemSpec {
                    id: "spring_force",
                    category: $category_forces,
                    name: "spring force",
                    checks: vec![
                        CheckSpec {
                            name: "random stretched springs against the reference",
                            points: 3.5,
                            run: spring_stretched::<H>,
                        },
                        CheckSpec {
                            name: "random compressed springs against the reference",
                            points: 3.5,
                            run: spring_compressed::<H>,
                        },
                    ],
                },
                ItemSpec {
                    id: "damper_force",
                    category: $category_forces,
                    name: "damper force",
                    checks: vec![
                        CheckSpec {
                            name: "random pairs against the reference",
                            points: 4.0,
                            run: damper_random::<H>,
                        },
                        CheckSpec {
                            name: "only the velocity along the spring is damped (adding a rotation changes nothing)",
                            points: 3.0,
                            run: damper_rotation::<H>,
                        },
                    ],
                },
            ]
        }

        /// The four integrator items.
        pub(crate) fn integrator_items<H: $tr>() -> Vec<ItemSpec<H>> {
            vec![
                ItemSpec {
                    id: "explicit",
                    category: $category_integrators,
                    name: "explicit Euler",
                    checks: vec![
                        CheckSpec {
                            name: "one step on random systems against the reference",
                            points: 3.0,
                            run: explicit_one_step::<H>,
                        },
                        CheckSpec {
                            name: "100 steps of the oscillator against the reference",
                            points: 1.0,
                            run: explicit_run::<H>,
                        },
                        CheckSpec {
                            name: "first order on the oscillator (measured)",
                            points: 1.0,
                            run: explicit_order::<H>,
                        },
                    ],
                },
                ItemSpec {
                    id: "implicit",
                    category: $category_integrators,
                    name: "implicit (backward) Euler",
                    checks: vec![
                        CheckSpec {
                            name: "exact backward Euler on the linear oscillator",
                            points: 1.0,
                            run: implicit_linear::<H>,
                        },
                        CheckSpec {
                            name: "stable at dt·ω = 10 (the amplitude shrinks)",
                            points: 1.0,
                            run: implicit_stable::<H>,
                        },
                        CheckSpec {
                            name: "solves v' = v + dt a(x', v') on a nonlinear 3-D system",
                            points: 0.5,
                            run: implicit_residual::<H>,
                        },
                    ],
                },
                ItemSpec {
                    id: "midpoint",
                    category: $category_integrators,
                    name: "midpoint",
                    checks: vec![
                        CheckSpec {
                            name: "one step on random systems against the reference",
                            points: 1.0,
                            run: midpoint_one_step::<H>,
                        },
                        CheckSpec {
                            name: "100 steps of the oscillator against the reference",
                            points: 0.5,
                            run: midpoint_run::<H>,
                        },
                        CheckSpec {
                            name: "second order on the oscillator (measured)",
                            points: 1.0,
                            run: midpoint_order::<H>,
                        },
                    ],
                },
                ItemSpec {
                    id: "rk4",
                    category: $category_integrators,
                    name: "RK4",
                    checks: vec![
                        CheckSpec {
                            name: "one step on random systems against the reference",
                            points: 6.0,
                            run: rk4_one_step::<H>,
                        },
                        CheckSpec {
                            name: "100 steps of the oscillator against the reference",
                            points: 3.0,
                            run: rk4_run::<H>,
                        },
                        CheckSpec {
                            name: "fourth order on the oscillator (measured)",
                            points: 6.0,
                            run: rk4_order::<H>,
                        },
                    ],
                },
            ]
        }

        fn spring_pair<H: $tr>(hw: &H) -> impl Fn(DVec3, DVec3, DVec3, DVec3, f64, f64) -> DVec3 + '_ {
            move |xa, xb, _, _, k, l| hw.spring_force(xa, xb, k, l)
        }

        fn damper_pair<H: $tr>(hw: &H) -> impl Fn(DVec3, DVec3, DVec3, DVec3, f64, f64) -> DVec3 + '_ {
            move |xa, xb, va, vb, kd, _| hw.damper_force(xa, xb, va, vb, kd)
        }

        fn spring_stretched<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1001);
            check_hooke(&spring_pair(hw), &spring_pair(&Reference), &mut rng, true)
        }

        fn spring_compressed<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1002);
            check_hooke(&spring_pair(hw), &spring_pair(&Reference), &mut rng, false)
        }

        fn damper_random<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1003);
            check_damper(&damper_pair(hw), &damper_pair(&Reference), &mut rng, false)
        }

        fn damper_rotation<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1004);
            check_damper(&damper_pair(hw), &damper_pair(&Reference), &mut rng, true)
        }

        fn explicit_one_step<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1101);
            check_one_step(
                &|s: &mut State, dt, p: &Physics| hw.explicit_euler(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::explicit_euler(&Reference, s, dt, p),
                &mut rng,
                EXPLICIT,
            )
        }

        fn explicit_run<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_oscillator_run(
                &|s: &mut State, dt, p: &Physics| hw.explicit_euler(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::explicit_euler(&Reference, s, dt, p),
                100,
                0.01,
                EXPLICIT,
            )
        }

        fn explicit_order<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_order(&|s: &mut State, dt, p: &Physics| hw.explicit_euler(s, dt, p), 1.0, 0.8, 1.3, EXPLICIT)
        }

        fn implicit_linear<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_implicit_linear(
                &|s: &mut State, dt, p: &Physics| hw.implicit_euler(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::implicit_euler(&Reference, s, dt, p),
            )
        }

        fn implicit_stable<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_implicit_stable(&|s: &mut State, dt, p: &Physics| hw.implicit_euler(s, dt, p))
        }

        fn implicit_residual<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1102);
            check_implicit_residual(
                &|s: &mut State, dt, p: &Physics| hw.implicit_euler(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::implicit_euler(&Reference, s, dt, p),
                &mut rng,
            )
        }

        fn midpoint_one_step<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1103);
            check_one_step(
                &|s: &mut State, dt, p: &Physics| hw.midpoint(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::midpoint(&Reference, s, dt, p),
                &mut rng,
                MIDPOINT,
            )
        }

        fn midpoint_run<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_oscillator_run(
                &|s: &mut State, dt, p: &Physics| hw.midpoint(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::midpoint(&Reference, s, dt, p),
                100,
                0.01,
                MIDPOINT,
            )
        }

        fn midpoint_order<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_order(&|s: &mut State, dt, p: &Physics| hw.midpoint(s, dt, p), 2.0, 1.7, 2.4, MIDPOINT)
        }

        fn rk4_one_step<H: $tr>(hw: &H, ctx: &Ctx) -> CheckResult {
            let mut rng = Rng::new(ctx.seed, 1104);
            check_one_step(
                &|s: &mut State, dt, p: &Physics| hw.rk4(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::rk4(&Reference, s, dt, p),
                &mut rng,
                RK4,
            )
        }

        fn rk4_run<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_oscillator_run(
                &|s: &mut State, dt, p: &Physics| hw.rk4(s, dt, p),
                &|s: &mut State, dt, p: &Physics| <Reference as $tr>::rk4(&Reference, s, dt, p),
                100,
                0.01,
                RK4,
            )
        }

        fn rk4_order<H: $tr>(hw: &H, _: &Ctx) -> CheckResult {
            check_order(&|s: &mut State, dt, p: &Physics| hw.rk4(s, dt, p), 4.0, 3.5, 4.6, RK4)
        }
    };
}

pub(crate) use shared_items;
