//! The systems and checks for integrators: the oscillator and random systems, one steps, runs, fitted convergence orders and the implicit Euler residuals.

use super::*;

// ---------------------------------------------------------------------------------------------
// Systems for the integrators

/// A model from a [`Builder`] with `gravity` (m/s²) and no drag.
fn model_from(builder: Builder, gravity: DVec3) -> (Model, crate::physics::State) {
    builder.build(gravity, 0.0)
}

/// The oscillator of the built-in scene: particle 0 pinned at the origin, particle 1 of 1 kg at
/// `(1.1, 0, 0)`, one spring of rest length 1 m, stiffness 100 N/m and damping `damping` N·s/m,
/// no gravity. Undamped: `x(t) = 1 + 0.1 cos(10 t)` (m).
pub(crate) fn oscillator(damping: f64) -> (Physics, State) {
    let mut b = Builder::new();
    let p0 = b.particle(DVec3::ZERO, 1.0);
    let p1 = b.particle(DVec3::new(1.0, 0.0, 0.0), 1.0);
    b.spring(p0, p1, 100.0, damping, SpringKind::Struct);
    b.x[1] = DVec3::new(1.1, 0.0, 0.0);
    b.pinned[0] = true;
    let (model, state) = model_from(b, DVec3::ZERO);
    (
        Physics::from_model(model),
        State {
            x: state.x,
            v: state.v,
        },
    )
}

/// A random system for one-step checks: 5 particles (particle 0 pinned) of 0.5–2 kg in a 2 m
/// box with velocities up to 1 m/s, 7 springs of 20–200 N/m and 0–2 N·s/m stretched to 1.1–2 ×
/// their rest length (so that their Jacobian needs no clamping), gravity 9.8 m/s² down.
pub(crate) fn random_system(rng: &mut Rng) -> (Physics, State) {
    let n = 5;
    let x: Vec<DVec3> = (0..n).map(|_| rng.vec(1.0)).collect();
    let v: Vec<DVec3> = (0..n)
        .map(|i| if i == 0 { DVec3::ZERO } else { rng.vec(1.0) })
        .collect();
    let masses: Vec<f64> = (0..n).map(|_| rng.range(0.5, 2.0)).collect();
    let mut pinned = vec![false; n];
    pinned[0] = true;
    let mut pairs = BTreeSet::new();
    let mut springs = Vec::new();
    while springs.len() < 7 {
        let (a, b) = (rng.index(n), rng.index(n));
        if a == b || !pairs.insert((a.min(b), a.max(b))) {
            continue;
        }
        let length = (x[b] - x[a]).length();
        springs.push(crate::grade::assignments::Spring {
            a,
            b,
            rest_length: length / rng.range(1.1, 2.0),
            stiffness: rng.range(20.0, 200.0),
            damping: rng.range(0.0, 2.0),
        });
    }
    let mut model = model_of(&masses, &pinned, &springs).unwrap_or_else(|| {
        // Unreachable: every index is below n.
        Model::new(vec![1.0], &[false], Vec::new(), DVec3::ZERO, 0.0)
    });
    model.gravity = DVec3::new(0.0, -9.8, 0.0);
    (Physics::from_model(model), State { x, v })
}

/// Describes a state for feedback.
pub(crate) fn describe_state(state: &State) -> String {
    format!(
        "{} particles; x = [{}]; v = [{}]",
        state.x.len(),
        sample(&state.x, 3, |p| vec3(*p)),
        sample(&state.v, 3, |p| vec3(*p))
    )
}

/// An integrator step under test: advances the state by `dt` with the physics.
pub(crate) type Step<'a> = &'a dyn Fn(&mut State, f64, &Physics);

/// Runs `step` once, checking that it keeps the particle count and stays finite.
pub(crate) fn step_checked(
    step: Step<'_>,
    state: &mut State,
    dt: f64,
    physics: &Physics,
    input: &str,
) -> CheckResult {
    let n = state.x.len();
    set_case(input);
    step(state, dt, physics);
    if state.x.len() != n || state.v.len() != n {
        return Err(wrong(
            input,
            format!("{n} positions and {n} velocities"),
            format!(
                "{} positions and {} velocities",
                state.x.len(),
                state.v.len()
            ),
            "update the vectors in place; do not add or remove particles",
        ));
    }
    finite("x", input, &state.x)?;
    finite("v", input, &state.v)
}

/// Compares a state stepped from `start` with the reference's.
pub(crate) fn compare_states(
    input: &str,
    start: &State,
    got: &State,
    want: &State,
    rel: f64,
    formula: &str,
) -> CheckResult {
    for (what, g, w) in [("x", &got.x, &want.x), ("v", &got.v, &want.v)] {
        if let Some(i) = first_mismatch(g, w, rel, 1.0) {
            let (gi, wi) = (
                g.get(i).copied().unwrap_or(DVec3::NAN),
                w.get(i).copied().unwrap_or(DVec3::NAN),
            );
            let unchanged = got == start;
            let hint = if unchanged {
                format!("the state did not change: is the TODO implemented? Expected {formula}")
            } else {
                format!("expected {formula}")
            };
            return Err(wrong(
                input,
                format!("{what}[{i}] = {}", vec3(wi)),
                format!("{what}[{i}] = {}", vec3(gi)),
                hint,
            ));
        }
    }
    Ok(())
}

/// What the position update of particle `i` did, when it matches a recognisable term: the
/// change of `x` compared with `dt·v` (old velocity), `dt·v'` (new velocity) and `dt·a` (the
/// acceleration at the start).
fn position_update(start: &State, got: &State, dt: f64, physics: &Physics) -> Option<String> {
    let a = physics.accelerations(&start.x, &start.v);
    let i = (0..start.x.len()).find(|&i| got.x.get(i) != start.x.get(i))?;
    let dx = got.x[i] - start.x[i];
    let near = |w: DVec3| close(dx, w, 1e-9, 1e-12);
    let candidates = [
        (
            dt * a[i],
            "dt·a(t), the acceleration, where the velocity belongs",
        ),
        (dt * start.v[i], "dt·v(t), with the OLD velocity"),
        (dt * got.v[i], "dt·v(t+dt), with the NEW velocity"),
    ];
    candidates
        .iter()
        .find(|(w, _)| near(*w))
        .map(|(_, what)| format!("x of particle {i} moved by {what}"))
}

/// One step on three random systems against the reference step, `dt = 0.01` s.
pub(crate) fn check_one_step(
    student: Step<'_>,
    reference: Step<'_>,
    rng: &mut Rng,
    formula: &str,
) -> CheckResult {
    for _ in 0..3 {
        let (physics, start) = random_system(rng);
        let dt = 0.01;
        let input = format!("one step of dt = {dt} s from {}", describe_state(&start));
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        if let Err(Failure::Wrong(mut f)) =
            compare_states(&input, &start, &got, &want, REL, formula)
        {
            if let Some(what) = position_update(&start, &got, dt, &physics) {
                f.hint = format!("{what}; {}", f.hint);
            }
            return Err(Failure::Wrong(f));
        }
    }
    Ok(())
}

/// `steps` steps of `dt` on the undamped oscillator against the reference.
pub(crate) fn check_oscillator_run(
    student: Step<'_>,
    reference: Step<'_>,
    steps: usize,
    dt: f64,
    formula: &str,
) -> CheckResult {
    let (physics, start) = oscillator(0.0);
    let input = format!(
        "{steps} steps of dt = {dt} s on the oscillator (particle 0 pinned at the origin, particle 1 \
         of 1 kg at (1.1, 0, 0), spring 100 N/m of rest length 1 m)"
    );
    let mut want = start.clone();
    let mut got = start.clone();
    for _ in 0..steps {
        reference(&mut want, dt, &physics);
        step_checked(student, &mut got, dt, &physics, &input)?;
    }
    compare_states(&input, &start, &got, &want, 1e-8, formula)
}

/// Least-squares slope of `ln(error)` against `ln(dt)`.
pub(crate) fn fitted_order(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(dt, e)| (dt.ln(), e.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// The measured order of `student` on the oscillator: error of `x(1 s)` against the exact
/// `1 + 0.1 cos(10 t)` at `dt = 0.02, 0.01, 0.005, 0.0025` s, accepted in `[lo, hi]`.
pub(crate) fn check_order(
    student: Step<'_>,
    order: f64,
    lo: f64,
    hi: f64,
    formula: &str,
) -> CheckResult {
    let time: f64 = 1.0;
    let exact = 1.0 + 0.1 * (10.0 * time).cos();
    let mut points = Vec::new();
    let input = "the oscillator x(t) = 1 + 0.1 cos(10 t) m run to t = 1 s with dt = 0.02, 0.01, \
                 0.005, 0.0025 s";
    let mut moved = false;
    for k in 0..4 {
        let dt = 0.02 / f64::from(1u32 << k);
        let steps = (time / dt).round() as usize;
        let (physics, start) = oscillator(0.0);
        let mut state = start.clone();
        for _ in 0..steps {
            step_checked(student, &mut state, dt, &physics, input)?;
        }
        moved |= state != start;
        points.push((dt, (state.x[1].x - exact).abs()));
    }
    let errors = points
        .iter()
        .map(|&(_, e)| num(e))
        .collect::<Vec<_>>()
        .join(", ");
    if points.iter().any(|&(_, e)| e == 0.0 || !e.is_finite()) {
        return Err(wrong(
            input,
            format!("errors shrinking like dt^{}", num(order)),
            format!("errors {errors} m"),
            "an error of exactly zero or not finite: the step does not integrate the oscillator",
        ));
    }
    let measured = fitted_order(&points);
    if (lo..=hi).contains(&measured) {
        return Ok(());
    }
    // What the errors do as dt halves: the last ratio says whether they still shrink.
    let last_ratio = points[3].1 / points[2].1;
    let hint = if !moved {
        format!("the state never changed: the step is not advanced at all; expected {formula}")
    } else if last_ratio > 0.85 || measured.abs() < 0.3 {
        format!(
            "the error stays the same size when dt shrinks (last ratio {}): the steps converge, \
             but to another motion than the oscillator's, so some update adds the wrong \
             quantity; expected {formula}",
            num(last_ratio)
        )
    } else if measured < order {
        let rk4 = if order == 4.0 {
            " (RK4: every slope k1..k4 enters both updates with weights 1, 2, 2, 1)"
        } else {
            ""
        };
        format!(
            "a method of order {} should shrink the error {}× when dt halves; yours shrinks it \
             {}×: a stage or a weight is probably wrong{rk4}; expected {formula}",
            num(order),
            num(2f64.powf(order)),
            num(2f64.powf(measured))
        )
    } else {
        format!("higher than expected: are you using a different method? Expected {formula}")
    };
    Err(wrong(
        input,
        format!("order {} (accepted {}–{})", num(order), num(lo), num(hi)),
        format!("order {} (errors {errors} m)", num(measured)),
        hint,
    ))
}

// ---------------------------------------------------------------------------------------------
// Implicit Euler

/// The backward Euler residuals of a step from `(x, v)` to `(x', v')`:
/// `max_i |v'_i - v_i - dt a_i(x', v')|` (m/s) and `max_i |x'_i - x_i - dt v'_i|` (m).
pub(crate) fn implicit_residuals(
    physics: &Physics,
    start: &State,
    end: &State,
    dt: f64,
) -> (f64, f64) {
    let a = physics.accelerations(&end.x, &end.v);
    let mut rv: f64 = 0.0;
    let mut rx: f64 = 0.0;
    for i in 0..start.x.len() {
        rv = rv.max((end.v[i] - start.v[i] - dt * a[i]).length());
        rx = rx.max((end.x[i] - start.x[i] - dt * end.v[i]).length());
    }
    (rv, rx)
}

/// Backward Euler is exact on a linear system: one step on the oscillator (undamped at
/// `dt = 0.05` s, damped 2 N·s/m at `dt = 0.1` s) against the reference's Newton step.
pub(crate) fn check_implicit_linear(student: Step<'_>, reference: Step<'_>) -> CheckResult {
    for (damping, dt) in [(0.0, 0.05), (2.0, 0.1)] {
        let (physics, mut start) = oscillator(damping);
        start.v[1] = DVec3::new(-0.3, 0.0, 0.0);
        let input = format!(
            "one step of dt = {dt} s on the oscillator (spring 100 N/m, damper {damping} N·s/m) \
             from x1 = (1.1, 0, 0) m, v1 = (-0.3, 0, 0) m/s"
        );
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        compare_states(
            &input,
            &start,
            &got,
            &want,
            1e-7,
            "the solution of v' = v + dt a(x + dt v', v'), x' = x + dt v': for a linear spring one \
             Newton step (I - dt J_v - dt² J_x) Δv = dt (a + dt J_x v) solves it exactly; a \
             predictor–corrector (explicit prediction, one re-evaluation) does not",
        )?;
    }
    Ok(())
}

/// Backward Euler is unconditionally stable: 50 steps at `dt·ω = 10` on the undamped oscillator
/// must shrink the amplitude below half and never grow it.
pub(crate) fn check_implicit_stable(student: Step<'_>) -> CheckResult {
    let (physics, mut state) = oscillator(0.0);
    let dt = 1.0;
    let amplitude = |s: &State| (s.x[1] - DVec3::X).length();
    let initial = amplitude(&state);
    let input = "50 steps of dt = 1 s (dt·ω = 10) on the undamped oscillator from amplitude 0.1 m";
    for step in 1..=50 {
        step_checked(student, &mut state, dt, &physics, input)?;
        let a = amplitude(&state);
        if a > initial * 1.01 {
            return Err(wrong(
                input,
                "the amplitude never grows; backward Euler damps it by 1/|1 - i dt ω| ≈ 0.1 per step",
                format!("amplitude {} m after step {step}", num(a)),
                "the step is not implicit: explicit Euler and the predictor–corrector blow up at \
                 dt·ω = 10; solve for the end-of-step velocity instead of predicting it",
            ));
        }
    }
    let last = amplitude(&state);
    if last > 0.5 * initial {
        return Err(wrong(
            input,
            "an amplitude below 0.05 m after 50 steps (backward Euler loses energy at large dt)",
            format!("amplitude {} m", num(last)),
            "the state hardly changes: is the step implemented?",
        ));
    }
    Ok(())
}

/// On a nonlinear 3-D system the step must solve backward Euler at least as well as one Newton
/// step: residual of `v' = v + dt a(x', v')` at most twice the reference's (plus 1e-9 m/s), and
/// `x' = x + dt v'` to round-off.
pub(crate) fn check_implicit_residual(
    student: Step<'_>,
    reference: Step<'_>,
    rng: &mut Rng,
) -> CheckResult {
    for _ in 0..3 {
        let (physics, start) = random_system(rng);
        let dt = 0.02;
        let input = format!("one step of dt = {dt} s from {}", describe_state(&start));
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        let (ref_v, _) = implicit_residuals(&physics, &start, &want, dt);
        let (rv, rx) = implicit_residuals(&physics, &start, &got, dt);
        let scale = got.v.iter().map(|v| v.length()).fold(1.0, f64::max);
        if rx > 1e-9 * scale * dt.max(1.0) {
            return Err(wrong(
                input,
                "x' = x + dt v' with the NEW velocity",
                format!("|x' - x - dt v'| up to {} m", num(rx)),
                "backward Euler moves the positions with the end-of-step velocity v'",
            ));
        }
        if rv > 2.0 * ref_v + 1e-9 {
            return Err(wrong(
                input,
                format!(
                    "|v' - v - dt a(x', v')| ≤ {} m/s (twice one Newton step's residual)",
                    num(2.0 * ref_v + 1e-9)
                ),
                format!("residual {} m/s", num(rv)),
                "the end state does not satisfy v' = v + dt a(x', v'): solve (I - dt J_v - dt² J_x) \
                 Δv = dt (a + dt J_x v) with physics.jacobian_x / jacobian_v and Matrix::solve",
            ));
        }
    }
    Ok(())
}
