//! Position Verlet (Störmer–Verlet) with damping and distance-constraint projection.
//!
//! ```text
//! x_{n+1} = x_n + (1 - γ) (x_n - x_{n-1}) + a(x_n, v_n) dt²           (r = 0)
//! x_{n+1} = x_n + (1 - γ) (1 - h)/(1 + h) (x_n - x_{n-1}) + a(x_n, v_n) dt² / (1 + h)
//!                                                          h = r dt / 2   (r > 0)
//! then, `iterations` times, project every spring back to its rest length
//! v_{n+1} = (x_{n+1} - x_n) / dt
//! ```
//! where
//! - `x`: positions (m), `x_{n-1}`: the positions one step earlier (m)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`], with
//!   `v_n = (x_n - x_{n-1})/dt` (m/s)
//! - `dt`: the time step (s)
//! - `γ`: the damping factor per step (dimensionless; GAMES101 uses 0.00005)
//! - `r`: the damping rate (1/s), `h = r dt / 2` (dimensionless)
//!
//! The velocity is not a state variable: the last displacement `x_n - x_{n-1}` plays its part.
//! Global error O(dt²): **second order** (the GAMES101 sheet's "fourth order" is the local error
//! of the position in one step; errors accumulate over 1/dt steps) — **while the forces do not
//! depend on the velocity**. The velocity `v_n = (x_n - x_{n-1})/dt` that dampers and drag see is
//! `v(t_n - dt/2)` to second order: half a step late, an O(dt) error in the force, and the
//! method becomes **first order** with spring dampers or drag (measured on the oscillator with
//! k_d = 2 N·s/m: order 1.02; undamped 2.00; `study convergence` shows both rows).
//!
//! **Damping.** GAMES101's factor `(1 - γ)` shrinks the remembered displacement every step: a
//! drag of rate `≈ γ/dt`, so its strength changes with `dt` (γ = 5e-5 is 0.05 1/s at dt = 1 ms
//! and 0.003 1/s at 1/64 s): at a fixed `γ` each dt solves another equation and the runs
//! converge to no solution as dt shrinks; only `γ = r dt` is a fixed drag, and that is first
//! order (it sees the lagging velocity). The rate `r` is the same drag `-r v` at every
//! `dt`, applied with the centred velocity `(x_{n+1} - x_{n-1})/(2 dt)`, which solves for
//! `x_{n+1}` in closed form (the second line): second order. The rope scenes keep GAMES101's
//! `γ = 5e-5` and `r = 0`; the course cubes and cloths have spring dampers and use neither
//! (`γ = 0`, `r = 0`). Both are scene parameters (`verlet_damping`, `verlet_damping_rate`).
//!
//! **Start-up.** The first step needs `x_{-1}`. Taking `x_{-1} = x_0` would be a velocity error
//! of O(dt) and make the method first order; instead, when the state holds no history,
//! `x_{-1} = x_0 - dt v_0 + ½ dt² a_0` (Taylor, error O(dt³)).
//!
//! **Stability on the harmonic oscillator** (γ = 0, r = 0, no projection): the same recurrence
//! as semi-implicit Euler, `x_{n+1} - (2 - dt²ω²) x_n + x_{n-1} = 0`, stable while **dt·ω < 2**
//! (at 2 a double root at -1: linear growth).
//! With a damper (rate μ on the mode), `x_{n+1} = (1 + c - dt²ω²/(1 + h)) x_n - c x_{n-1}`,
//! `c = (1 - γ)(1 - h)/(1 + h) - dt μ/(1 + h)`: stable while both roots lie in the unit circle
//! (see `study::theory`).
//!
//! **Projection** ([`project_distances`]) with `iterations > 0` turns every spring into a rigid
//! rod (an infinitely stiff spring, GAMES101 §1.3): each end moves half the error, a pinned end
//! none. The spring forces still enter `a`, but after projection they are nearly zero.
//!
//! **Fast path.** On a chain (a rope) the projection computes eight rods of a colour at a time
//! with the textbook's operations, so the same bits
//! ([`project_distances_fast`](crate::physics::constraints::project_distances_fast); the
//! workspace's `textbook` flag keeps the loop, and the tests compare the two). On a lattice the
//! accelerations and the dissipated power at `(x_n, v_n)` come from one stencil pass instead of
//! two (`integrators::accelerations_and_power`, the same bits).
//!
//! **Energy accounting**: the dampers' power at `(x_n, v_n)` times `dt` (what the force saw),
//! `½ m (1 - (1 - γ)²) |x_n - x_{n-1}|²/dt²` for the factor, `dt r m |v_centred|²` for the rate,
//! and the drop of the energy across the projection. Inside
//! [`Method::steps`](crate::physics::Method::steps) the drop's two
//! energies are added up eight steps at a time (`fast/energy.rs`, `Batch`), the same bits.
//!
//! Reference: L. Verlet, "Computer 'Experiments' on Classical Fluids", Phys. Rev. 159 (1967);
//! E. Hairer, C. Lubich, G. Wanner, "Geometric numerical integration illustrated by the
//! Störmer–Verlet method", Acta Numerica 12 (2003), §1; T. Jakobsen, "Advanced Character
//! Physics", GDC 2001; GAMES101 assignment 8 (2020), §1.3–1.4.

use glam::DVec3;

use crate::physics::constraints::{prepare_rods, project_distances, project_distances_fast};
#[cfg(test)]
use crate::physics::fast::energy::kinetic_gravity;
use crate::physics::fast::energy::{all_below, kinetic_gravity_pair, kinetic_gravity_terms};
use crate::physics::forces::Model;

use crate::physics::integrators::declaration::{
    Declaration, OscillatorLimit, Scratch, StabilityFunction,
};
use crate::physics::integrators::{MethodParams, Workspace, accelerations_and_power};
use crate::physics::particles::State;

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "verlet",
    label: "Vlt",
    key: 'v',
    colour: 15,
    order: 2,
    evaluations: |p| 1.0 + f64::from(p.iterations),
    oscillator: OscillatorLimit::Below(2.0),
    stability: |p| {
        if p.iterations > 0 {
            return StabilityFunction::NotCovered(
                "Verlet with constraint projection: the projection is not part of the linear theory",
            );
        }
        // x_{n+1} = (1 + c - dt²ω²/(1 + h)) x_n - c x_{n-1} (module docs).
        StabilityFunction::TwoStep(|p, dt, w2, mu| {
            let h = 0.5 * p.verlet_damping_rate * dt;
            let keep = 1.0 - p.verlet_damping;
            let c = keep * (1.0 - h) / (1.0 + h) - dt * mu / (1.0 + h);
            (1.0 + c - dt * dt * w2 / (1.0 + h), c)
        })
    },
    params: &["verlet_damping", "verlet_damping_rate", "iterations"],
    // The springs as rods, in projection order.
    scratch: Scratch {
        particle: 0.0,
        spring: size_of::<crate::physics::constraints::Rod>() as f64,
    },
    fused: false,
    energy_guard: false,
    step,
    many: None,
};

fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let Workspace {
        a,
        rods,
        chain,
        textbook,
        account,
        dissipated,
        power_f,
        energy_terms,
        energy_batch,
        step_dissipated,
        ..
    } = work;
    let (account, textbook) = (*account, *textbook);
    // a_n = a(x_n, v_n), and the power of the dampers and drag, which saw
    // v_n = (x_n - x_{n-1})/dt: D += dt P(x_n, v_n), when accounting. Without dampers, drag,
    // colliders or a stencil's pass, `dissipated_power` adds nothing to its `+0` sums: `+0`
    // (`Power::default`), not computed. What kinds of springs there are the model keeps
    // (`Model::spring_kinds`: rods only, some damper), found once, not walked every step. On a
    // lattice the accelerations and the power come from one pass (`accelerations_and_power`).
    let kinds = account.then(|| model.spring_kinds());
    let no_power = kinds.is_some_and(|k| !k.dampers)
        && model.drag == 0.0
        && model.colliders.is_empty()
        && model.stencil().is_none();
    let power = accelerations_and_power(
        model,
        &state.x,
        &state.v,
        a,
        account && !no_power,
        textbook,
        power_f,
    );
    let dt2 = dt * dt;
    if !state.history_valid {
        // x_{-1} = x_0 - dt v_0 + ½ dt² a_0 (backward Taylor step, error O(dt³)).
        for i in 0..state.x.len() {
            state.x_prev[i] = state.x[i] - dt * state.v[i] + 0.5 * dt2 * a[i];
        }
    }
    dissipated.add_power(dt, power);
    let keep = 1.0 - params.verlet_damping;
    let rate = params.verlet_damping_rate;
    let inv_dt2 = 1.0 / dt2;
    for i in 0..state.x.len() {
        let x_n = state.x[i];
        let d_n = x_n - state.x_prev[i];
        if rate == 0.0 {
            // x_{n+1} = x_n + (1 - γ)(x_n - x_{n-1}) + a_n dt²
            state.x[i] = x_n + keep * d_n + dt2 * a[i];
        } else {
            // Centred rate damping, h = r dt / 2:
            // x_{n+1} = x_n + (1 - γ) (1 - h)/(1 + h) (x_n - x_{n-1}) + a_n dt² / (1 + h)
            let h = 0.5 * rate * dt;
            state.x[i] = x_n + keep * ((1.0 - h) / (1.0 + h)) * d_n + dt2 * a[i] / (1.0 + h);
            if account && model.inv_mass[i] != 0.0 {
                // Power r m |v_c|², v_c = (x_{n+1} - x_{n-1}) / (2 dt), over dt.
                let v_c = (state.x[i] - state.x_prev[i]) / (2.0 * dt);
                dissipated.method += dt * rate * model.mass[i] * v_c.length_squared();
            }
        }
        if account && keep != 1.0 && model.inv_mass[i] != 0.0 {
            // γ removes ½ m (1 - (1 - γ)²) |d_n / dt|² of the remembered motion.
            dissipated.method +=
                0.5 * model.mass[i] * (1.0 - keep * keep) * d_n.length_squared() * inv_dt2;
        }
        state.x_prev[i] = x_n;
    }
    if params.iterations > 0 {
        let only_rods = kinds.is_some_and(|k| k.rods);
        let (mass, gravity) = (&model.mass, model.gravity);
        // Inside `Method::steps` the energies before and after the projection go to the
        // batch, which adds their share to this step's entry with those of the next steps.
        let batched = account && energy_batch.on;
        if batched && energy_batch.full() {
            energy_batch.finish(step_dissipated);
        }
        // The energy before the projection: its elastic term now, its kinetic and
        // gravitational terms kept and summed beside those after (`fast/energy.rs`), as
        // `mechanical_energy` sums each.
        let elastic_before = if !account {
            0.0
        } else {
            if batched {
                energy_batch.before(mass, gravity, &state.x, &state.x_prev, dt);
            } else {
                kinetic_gravity_terms(mass, gravity, &state.x, &state.x_prev, dt, energy_terms);
            }
            elastic_energy(model, &state.x, only_rods)
        };
        prepare_rods(model, rods);
        if textbook {
            project_distances(rods, &mut state.x, params.iterations);
        } else {
            // The same operations, eight rods at a time on a chain (`fast/chain.rs`).
            project_distances_fast(rods, &mut state.x, params.iterations, chain);
        }
        if account {
            let elastic_after = elastic_energy(model, &state.x, only_rods);
            if batched {
                let elastic = (elastic_before, elastic_after);
                energy_batch.after(mass, gravity, &state.x, &state.x_prev, dt, elastic);
            } else {
                let (e_before, e) =
                    kinetic_gravity_pair(mass, gravity, &state.x, &state.x_prev, dt, energy_terms);
                let before = e_before + elastic_before;
                let after = e + elastic_after;
                // Projection is inelastic: what it takes out (or, rarely, puts in).
                dissipated.method += before - after;
            }
        }
    }
    let inv_dt = 1.0 / dt;
    for i in 0..state.x.len() {
        // v_{n+1} = (x_{n+1} - x_n) / dt
        state.v[i] = (state.x[i] - state.x_prev[i]) * inv_dt;
    }
    state.history_valid = true;
    1
}

/// Kinetic (with the implied velocities `(x - x_prev)/dt`), gravitational and elastic energy (J).
///
/// A spring without stiffness (a rod that only the projection holds) adds `½·0·(L - L0)²`,
/// which is `+0` whenever `|x_b - x_a|²` and `L0` are finite (then `L - L0` is finite, and
/// `(0·s)·s` is `+0` for every finite `s`): it adds `+0.0` without the square root, the same
/// sum bit for bit (tested); otherwise the term is computed. When every spring is such a rod
/// (`rods`, [`rods_only`]) and every coordinate is below [`BOUNDED`] in magnitude (so every
/// `|x_b - x_a|² ≤ 3 (2·10¹⁵⁰)²` is finite), every term is `+0`, and the sum of them is the sum
/// of one (the sum of none, `-0`, without springs): no spring is read.
#[cfg(test)]
fn mechanical_energy(model: &Model, x: &[DVec3], x_prev: &[DVec3], dt: f64, rods: bool) -> f64 {
    // e = Σ ½ m |(x - x_prev)/dt|² - m g·x in particle order, its terms a block at a time
    // with the widest vectors (`fast/energy.rs`, the same bits as the loop).
    let e = kinetic_gravity(&model.mass, model.gravity, x, x_prev, dt);
    e + elastic_energy(model, x, rods)
}

/// The elastic term of [`mechanical_energy`] (J): the sum of the springs' energies in spring
/// order, rods as `+0` (see there).
fn elastic_energy(model: &Model, x: &[DVec3], rods: bool) -> f64 {
    if rods && bounded(x) {
        let zeros = std::iter::repeat_n(0.0, model.springs.len().min(1));
        return zeros.sum::<f64>();
    }
    let elastic = model.springs.iter().map(|s| {
        let rod = s.stiffness == 0.0
            && s.rest_length.is_finite()
            && (x[s.b as usize] - x[s.a as usize])
                .length_squared()
                .is_finite();
        if rod { 0.0 } else { s.energy(x) }
    });
    elastic.sum::<f64>()
}

/// A coordinate below this in magnitude (m) keeps a spring's squared length finite
/// ([`mechanical_energy`]).
const BOUNDED: f64 = 1e150;

/// True when every spring of `model` is a rod of [`mechanical_energy`]: no stiffness, a finite
/// rest length.
#[cfg(test)]
fn rods_only(model: &Model) -> bool {
    model.spring_kinds().rods
}

/// True when every coordinate of `x` is below [`BOUNDED`] in magnitude (false for NaN), every
/// coordinate tested eight at a time (`fast/energy.rs`).
fn bounded(x: &[DVec3]) -> bool {
    all_below(x, BOUNDED)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::energy::Power;
    use crate::physics::springs::{Spring, SpringKind};

    /// [`mechanical_energy`] as the textbook writes it: every spring's `½ k (L - L0)²`.
    fn textbook(model: &Model, x: &[DVec3], x_prev: &[DVec3], dt: f64) -> f64 {
        let mut e = 0.0;
        for i in 0..x.len() {
            let v = (x[i] - x_prev[i]) / dt;
            e += 0.5 * model.mass[i] * v.length_squared()
                - model.mass[i] * model.gravity.dot(x[i]);
        }
        e + model.springs.iter().map(|s| s.energy(x)).sum::<f64>()
    }

    fn spring(a: u32, b: u32, rest_length: f64, stiffness: f64) -> Spring {
        Spring {
            a,
            b,
            rest_length,
            stiffness,
            damping: 0.0,
            kind: SpringKind::Struct,
        }
    }

    /// The step's shortcut: without dampers, drag or colliders the dissipated power is
    /// `Power::default()` bit for bit (positions and velocities with NaN, infinities and
    /// signed zeros), and the model's `spring_kinds` finds a damper wherever one is, also after
    /// the springs change.
    #[test]
    fn without_dampers_the_power_is_zero_bit_for_bit() {
        use crate::physics::energy::dissipated_power;
        let x = vec![
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(f64::NAN, 0.9, -0.0),
            DVec3::new(0.3, f64::INFINITY, -0.1),
            DVec3::new(-0.2, 1.3, 0.4),
        ];
        let v = vec![DVec3::new(-0.0, 2.0, f64::NAN), DVec3::ZERO, DVec3::splat(-1.0), DVec3::X];
        let springs = vec![spring(0, 1, 0.25, 0.0), spring(1, 2, 0.5, 100.0), spring(2, 3, 0.1, 0.0)];
        let mut model = Model::new(
            vec![0.1, 0.2, 0.3, 0.4],
            &[true, false, false, false],
            springs,
            DVec3::new(0.0, -9.81, 0.0),
            0.0,
        );
        assert!(!model.spring_kinds().dampers && !model.spring_kinds().rods);
        let mut scratch = Vec::new();
        let p = dissipated_power(&model, &x, &v, &mut scratch);
        let zero = Power::default();
        assert_eq!(p.dampers_and_drag.to_bits(), zero.dampers_and_drag.to_bits());
        assert_eq!(p.contact.to_bits(), zero.contact.to_bits());
        model.update_springs(|s| {
            if s.a == 2 {
                s.damping = 0.5;
            }
        });
        assert!(model.spring_kinds().dampers);
        model.set_spring_coefficients(0.0, 0.0);
        assert!(!model.spring_kinds().dampers && model.spring_kinds().rods);
        model.update_springs(|s| s.rest_length = f64::INFINITY);
        assert!(!model.spring_kinds().rods);
    }

    /// `Method::steps` (its accounting batched, `fast::energy::Batch`) against as many single
    /// steps: every step's dissipated energy, the last one and the states bit for bit, over
    /// batch lengths around `BATCH`, two calls in a row, rods, springs and dampers.
    #[test]
    fn many_steps_account_as_single_steps_bit_for_bit() {
        use crate::physics::Method;
        use crate::physics::energy::Dissipated;
        let bits = |d: &Dissipated| {
            [d.dampers_and_drag, d.contact_forces, d.contacts, d.method, d.total].map(f64::to_bits)
        };
        let n = 37;
        for (stiffness, damping) in [(0.0, 0.0), (300.0, 0.0), (0.0, 0.4)] {
            let springs: Vec<Spring> = (0..n as u32 - 1)
                .map(|i| Spring {
                    damping,
                    ..spring(i, i + 1, 0.05, stiffness)
                })
                .collect();
            let x: Vec<DVec3> = (0..n)
                .map(|i| {
                    let f = i as f64;
                    DVec3::new(0.05 * f, 1.0 + 0.01 * (0.7 * f).sin(), 0.002 * f)
                })
                .collect();
            let mut pinned = vec![false; n];
            pinned[0] = true;
            let gravity = DVec3::new(0.0, -9.81, 0.0);
            let model = Model::new(vec![0.02; n], &pinned, springs, gravity, 0.0);
            let start = State::new(x, vec![DVec3::ZERO; n]);
            for (iterations, verlet_damping) in [(20, 0.0), (5, 5e-5)] {
                let params = MethodParams {
                    iterations,
                    verlet_damping,
                    ..MethodParams::default()
                };
                for steps in [1, 2, 7, 8, 9, 16, 17, 30] {
                    let (mut one, mut many) = (start.clone(), start.clone());
                    let (mut w1, mut wn) = (Workspace::new(), Workspace::new());
                    (w1.account, wn.account) = (true, true);
                    for _ in 0..2 {
                        let mut want = Vec::new();
                        for _ in 0..steps {
                            Method::Verlet.step(&model, &mut one, 1e-3, &params, &mut w1);
                            want.push(bits(&w1.dissipated));
                        }
                        Method::Verlet.steps(&model, &mut many, 1e-3, &params, &mut wn, steps);
                        let got: Vec<_> = wn.step_dissipated.iter().map(bits).collect();
                        assert_eq!(got, want, "k {stiffness} steps {steps}");
                        assert_eq!(bits(&wn.dissipated), bits(&w1.dissipated));
                        for (a, b) in one.x.iter().zip(&many.x) {
                            assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn rods_without_stiffness_add_the_textbook_energy_bit_for_bit() {
        let x = vec![
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.3, 0.9, -0.1),
            DVec3::new(0.3, 0.9, -0.1),
            DVec3::new(-0.2, 1.3, 0.4),
        ];
        let x_prev: Vec<DVec3> = x.iter().map(|p| *p + DVec3::new(1e-3, -2e-3, 0.5e-3)).collect();
        let cases = [
            // Rods only (the sum of +0 terms), rods between stiff springs, stretched and at
            // rest, a rod of zero length and a negative zero difference, a rod of infinite rest
            // length, no springs at all.
            vec![spring(0, 1, 0.25, 0.0), spring(1, 3, 0.5, 0.0)],
            vec![spring(0, 1, 0.25, 0.0), spring(1, 2, 0.0, 0.0), spring(2, 3, 0.1, 500.0)],
            vec![spring(2, 1, 0.0, 0.0), spring(0, 3, 1.0, 2.0e4), spring(3, 1, 0.7, 0.0)],
            vec![spring(0, 1, 0.25, 0.0), spring(1, 3, f64::INFINITY, 0.0)],
            Vec::new(),
        ];
        // The positions, then a coordinate that is infinite, NaN, huge (a squared length that
        // overflows) and large but bounded.
        let mut positions = vec![x.clone()];
        for c in [f64::INFINITY, f64::NAN, 1e200, -1e149] {
            let mut p = x.clone();
            p[3] = DVec3::new(c, 0.0, 0.0);
            positions.push(p);
        }
        for springs in cases {
            let model = Model::new(
                vec![0.1, 0.2, 0.3, 0.4],
                &[true, false, false, false],
                springs,
                DVec3::new(0.0, -9.81, 0.0),
                0.0,
            );
            // As `step` asks, and the loop over every spring.
            for rods in [rods_only(&model), false] {
                for x in &positions {
                    for dt in [1e-3, 1.0 / 60.0] {
                        let (fast, slow) = (
                            mechanical_energy(&model, x, &x_prev, dt, rods),
                            textbook(&model, x, &x_prev, dt),
                        );
                        assert!(
                            fast.to_bits() == slow.to_bits() || fast.is_nan() && slow.is_nan(),
                            "{fast} {slow} {x:?}"
                        );
                    }
                }
            }
        }
    }
}
