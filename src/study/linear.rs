//! The measured stability criterion: how fast a small perturbation grows under one step of a
//! method, by power iteration on the step map.
//!
//! # Theory
//!
//! One step of a method is a map `y_{n+1} = Φ_dt(y_n)` of the state `y = (x, v)`. A small
//! perturbation `δ` of the state grows like the step map's Jacobian `J = ∂Φ_dt/∂y` applied
//! again and again, `δ_n = J^n δ_0`, and its size after many steps is governed by the spectral
//! radius `ρ(J)`: the method is linearly stable at `dt` when `ρ ≤ 1`. This study measures it
//! with the method's own code, by central finite differences of [`Method::step`] on copies of
//! the state:
//!
//! ```text
//! J δ ≈ (Φ(y_0 + s δ) - Φ(y_0 - s δ)) / (2 s)        s: |s δx|_max = 10⁻⁶ L
//! E(δ) = ½ Σ m_i |δv_i|² + ½ δxᵀ K_0 δx              the perturbation's energy (J, per s²)
//! δ_{n+1} = J δ_n / √E(J δ_n),   E_n = Π_k E(J δ_k)  (power iteration, growth kept apart)
//! ```
//! where `y_0` is the scene's initial positions at rest, `L` the mean rest length of the springs
//! (m) and `K_0` the stiffness at `y_0` ([`super::modes`]). The Jacobian is always taken about
//! the same `y_0`, **without gravity**: a constant force does not change the force's Jacobian,
//! only where the motion goes, and keeping it would mix the sensitivity of the large motion
//! itself (a rope falling 350 m in one 6 s step) into `J`. With gravity removed and springs at
//! rest length (every built-in scene's start) `y_0` is an equilibrium, `Φ(y_0) = y_0`, and `J`
//! is exactly the method applied to the linearised system `M x'' = -K x - C x'` of
//! [`super::theory`], through the method's own code: the measurement checks the theory and the
//! implementation together. **Free fall is never instability**. Rigid translations and rotations of
//! a body without pinned particles are Jordan blocks of eigenvalue 1 (a uniform velocity
//! perturbation makes the position perturbation grow linearly, never exponentially), and so are
//! the zero-stiffness motions of a flat cloth or a straight rope at rest length (out of plane,
//! sideways). The start vector is taken in the range of `M⁻¹K_0`, which leaves all of them out
//! (`M⁻¹K_0` is self-adjoint in the mass inner product, so its range is orthogonal to its null
//! space, and the linearised dynamics keep the two apart); rigid motions are also projected out
//! after every step. Left in, their drift would grow without bound and drown the rest of `δ`
//! in rounding.
//!
//! **Contacts are excluded**: the colliders and the dynamic spheres are removed from the copy
//! whose Jacobian is taken (at the initial state nothing touches in any built-in scene, and a
//! contact is not differentiable). What contacts do to stability is left to the confirmation
//! run ([`super::stability`]).
//!
//! **The verdict** is the growth criterion of the original study applied to `E_n`: with
//! `N = 2W` power steps and the sin⁴ window `w_j`,
//!
//! ```text
//! Ē_early = Σ_j w_j E_{1+j} / Σ w_j,   Ē_late = Σ_j w_j E_{W+1+j} / Σ w_j
//! stable ⇔ Ē_late ≤ (1 + 10⁻⁶) Ē_early,              ρ ≈ (Ē_late / Ē_early)^(1/(2W))
//! ```
//! so a perturbation growing by `ρ = 1 + 3·10⁻¹⁰` per step over `W = 2000` steps is caught (the
//! window cancels the bounded oscillation of symplectic methods, whose `E` is not exactly
//! conserved). A perturbation that grows 10⁶⁰-fold stops the run as unstable; one that decays
//! 10¹²-fold stops it as stable.
//!
//! Reference: G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, §7.3 (the power
//! method); E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., 1996,
//! §IV.2 (linear stability); J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., 2006,
//! §8.1 (finite-difference Jacobian-vector products).

use std::f64::consts::PI;

use glam::DVec3;
use serde::Serialize;

use super::modes::Blocks;
use crate::physics::fast::quadratic;
use crate::physics::{Method, MethodParams, Model, State, Workspace};
use crate::random::XorShift64Star;

/// `Ē_late / Ē_early` above `1 +` this is growth.
pub const TOLERANCE: f64 = 1e-6;
/// A perturbation energy this many times its start stops the run: unstable. Large, because a
/// stable but non-normal step map can first amplify a perturbation by many orders (Verlet with
/// one projection pass at dt·ω = 80 multiplies the energy by 10⁶ in the first step, then
/// shrinks it by 0.5 per step).
pub const GROWTH_STOP: f64 = 1e60;
/// A perturbation energy this fraction of its start stops the run: stable.
pub const DECAY_STOP: f64 = 1e-12;
/// The finite-difference size, relative to the mean rest length.
pub const FD_SIZE: f64 = 1e-6;

/// One measurement of the perturbation growth at one `dt`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Growth {
    /// Power steps taken (each two steps of the method).
    pub steps: u64,
    /// The verdict.
    pub stable: bool,
    /// The estimated spectral radius `ρ` of the step map (per step).
    pub rho: f64,
    /// `Ē_late / Ē_early` when the run went to the end, else null.
    pub ratio: Option<f64>,
    /// Why the run stopped: `window`, `grew`, `decayed` or `not finite`.
    pub stopped: &'static str,
}

/// A body prepared for finite differences of its step map.
#[derive(Clone, Debug)]
pub struct Linearisation {
    model: Model,
    base: State,
    blocks: Blocks,
    free: Vec<bool>,
    /// `½ m_i` (the perturbation's kinetic energy).
    half_mass: Vec<f64>,
    /// Rigid modes (translations and rotations) when no particle is pinned: M-orthonormal.
    rigid: Vec<Vec<DVec3>>,
    length: f64,
    omega: f64,
}

impl Linearisation {
    /// `model` at `state` without its colliders and dynamic spheres (contacts excluded), with
    /// `omega_max` (rad/s) for the scale of velocities.
    #[must_use]
    pub fn new(model: &Model, state: &State, omega_max: f64) -> Linearisation {
        let mut model = model.clone();
        model.colliders.clear();
        model.gravity = DVec3::ZERO;
        let mut base = state.clone();
        base.spheres.clear();
        base.v.fill(DVec3::ZERO);
        let n = model.particle_count();
        let free: Vec<bool> = (0..n).map(|i| !model.is_pinned(i)).collect();
        let blocks = Blocks::new(&model, &base.x);
        let half_mass = model.mass.iter().map(|m| 0.5 * m).collect();
        let length = if model.springs().is_empty() {
            1.0
        } else {
            let l = model.springs().iter().map(|s| s.rest_length).sum::<f64>()
                / model.springs().len() as f64;
            if l > 0.0 { l } else { 1.0 }
        };
        let rigid = if free.iter().all(|&f| f) && n > 1 {
            rigid_modes(&model, &base.x)
        } else {
            Vec::new()
        };
        Linearisation {
            model,
            base,
            blocks,
            free,
            half_mass,
            rigid,
            length,
            omega: if omega_max > 0.0 { omega_max } else { 1.0 },
        }
    }

    /// `e + Σ_s ½ δx_sᵀ K_s δx_s` (`δx_s = δx_b - δx_a`), added in spring order
    /// ([`quadratic::spring_energy`]: the terms a block of springs at a time).
    fn elastic(&self, e: f64, dx: &[DVec3]) -> f64 {
        quadratic::spring_energy(e, &self.blocks.ends, self.blocks.six(), dx)
    }

    /// `u ← M⁻¹ K_0 u` (zero on pinned particles).
    fn stiffness_times(&self, u: &mut [DVec3]) {
        let mut y = vec![DVec3::ZERO; u.len()];
        for (s, &[a, b]) in self.blocks.ends.iter().enumerate() {
            let (a, b) = (a as usize, b as usize);
            let f = Blocks::mul(&self.blocks.at(s), u[a] - u[b]);
            y[a] += f;
            y[b] -= f;
        }
        for (i, u) in u.iter_mut().enumerate() {
            *u = if self.free[i] {
                y[i] * self.model.inv_mass[i]
            } else {
                DVec3::ZERO
            };
        }
    }

    /// Removes the rigid components of the perturbation `(δx, δv)` (M-orthogonal projection);
    /// returns its kinetic energy `Σ ½ m_i |δv_i|²` over the free particles (J per s²):
    ///
    /// ```text
    /// for each rigid mode e_k:   c = Σ_i m_i u_i·e_k,i,   u ← u - c e_k     (u = δx, then δv)
    /// ```
    /// one mode and one vector at a time, the kinetic energy after the last mode. Each pass is
    /// done for `δx` and `δv` together, the terms eight particles at a time and their sums in
    /// particle order ([`quadratic::components`], [`quadratic::remove`],
    /// [`quadratic::kinetic`]): the same sums in the same order, so the same bits.
    fn project(&self, dx: &mut [DVec3], dv: &mut [DVec3]) -> f64 {
        let mass = &self.model.mass;
        for mode in &self.rigid {
            let c = quadratic::components(mass, mode, dx, dv);
            quadratic::remove(mode, c, dx, dv);
        }
        quadratic::kinetic(0.0, &self.half_mass, &self.free, dv)
    }

    /// `δ ← δ / root`, and the scale of the finite differences: the largest `|δx|` or `|δv|/ω`
    /// component of a free particle.
    fn normalise(&self, dx: &mut [DVec3], dv: &mut [DVec3], root: f64) -> f64 {
        // The divisions several at a time (`quadratic::divide`), then the scale.
        quadratic::divide(dx, root);
        quadratic::divide(dv, root);
        let mut scale = 0.0;
        for i in 0..dx.len() {
            if self.free[i] {
                scale = f64::max(
                    scale,
                    dx[i]
                        .abs()
                        .max_element()
                        .max(dv[i].abs().max_element() / self.omega),
                );
            }
        }
        scale
    }

    /// The growth of a perturbation under `method` with `params` at `dt` (s) over `steps`
    /// power steps (module docs). Deterministic.
    #[must_use]
    pub fn growth(&self, method: Method, params: &MethodParams, dt: f64, steps: u64) -> Growth {
        let n = self.model.particle_count();
        let w = steps.div_ceil(2).max(1);
        let (mut dx, mut dv) = start_vector(n, &self.free);
        // Start in the range of M⁻¹K_0: no component along a zero-stiffness direction (a rigid
        // motion, or a flat cloth's out-of-plane motion), whose position part would drift
        // linearly and drown the rest in rounding.
        self.stiffness_times(&mut dx);
        self.stiffness_times(&mut dv);
        let kinetic = self.project(&mut dx, &mut dv);
        let e = self.elastic(kinetic, &dx);
        if e.is_nan() || e <= 0.0 {
            return Growth {
                steps: 0,
                stable: true,
                rho: 1.0,
                ratio: None,
                stopped: "decayed",
            };
        }
        // δ is divided by this at the top of each power step.
        let mut root = e.sqrt();
        let mut work = Workspace::new();
        let mut plus = self.base.clone();
        let mut minus = self.base.clone();
        let mut log_e = 0.0f64;
        let (mut early, mut late) = (0.0, 0.0);
        let stop = |taken: u64, log_e: f64, stable: bool, stopped| Growth {
            steps: taken,
            stable,
            rho: (log_e / (2.0 * taken.max(1) as f64)).exp(),
            ratio: None,
            stopped,
        };
        for k in 0..2 * w {
            // s such that the largest position (or velocity / ω) component is FD_SIZE L.
            let scale = self.normalise(&mut dx, &mut dv, root);
            if !(scale > 0.0 && scale.is_finite()) {
                return stop(k, log_e, false, "not finite");
            }
            let s = FD_SIZE * self.length / scale;
            for (state, s) in [(&mut plus, s), (&mut minus, -s)] {
                // y_0 ± s δ, with Verlet's history: the displacement that the velocity implies
                // (x_prev = x - dt v).
                let base = (&self.base.x[..], &self.base.v[..]);
                let out = (&mut state.x[..], &mut state.v[..], &mut state.x_prev[..]);
                quadratic::offset(base, s, (&dx, &dv), dt, out);
                state.history_valid = true;
                method.step(&self.model, state, dt, params, &mut work);
            }
            // J δ = (Φ(y_0 + s δ) - Φ(y_0 - s δ)) / (2 s)
            let inv = 0.5 / s;
            quadratic::central_difference(&plus.x, &minus.x, inv, &mut dx);
            quadratic::central_difference(&plus.v, &minus.v, inv, &mut dv);
            let kinetic = self.project(&mut dx, &mut dv);
            let g = self.elastic(kinetic, &dx);
            if !(g.is_finite() && g > 0.0) {
                if g == 0.0 {
                    return stop(k + 1, log_e, true, "decayed");
                }
                return stop(k + 1, log_e, false, "not finite");
            }
            log_e += g.ln();
            root = g.sqrt();
            if log_e > GROWTH_STOP.ln() {
                return stop(k + 1, log_e, false, "grew");
            }
            if log_e < DECAY_STOP.ln() {
                return stop(k + 1, log_e, true, "decayed");
            }
            let j = k % w;
            // w_j = sin⁴(π (j + ½) / W)
            let sj = (PI * (j as f64 + 0.5) / w as f64).sin();
            let weight = (sj * sj) * (sj * sj) * log_e.exp();
            if k < w {
                early += weight;
            } else {
                late += weight;
            }
        }
        let ratio = late / early;
        Growth {
            steps: 2 * w,
            stable: ratio <= 1.0 + TOLERANCE,
            rho: ratio.powf(1.0 / (2 * w) as f64),
            ratio: Some(ratio),
            stopped: "window",
        }
    }
}

/// The six rigid modes (translations along x, y, z; rotations about the centre of mass),
/// orthonormal in the mass inner product `Σ m_i u_i·w_i`.
fn rigid_modes(model: &Model, x: &[DVec3]) -> Vec<Vec<DVec3>> {
    let n = x.len();
    let mass: f64 = model.mass.iter().sum();
    let centre = x
        .iter()
        .zip(&model.mass)
        .map(|(x, m)| *x * *m)
        .sum::<DVec3>()
        / mass;
    let mut basis: Vec<Vec<DVec3>> = Vec::new();
    let candidates = [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .map(|e| vec![e; n])
        .chain(
            [DVec3::X, DVec3::Y, DVec3::Z]
                .into_iter()
                .map(|e| x.iter().map(|p| e.cross(*p - centre)).collect()),
        );
    for mut u in candidates {
        for b in &basis {
            let c: f64 = (0..n).map(|i| model.mass[i] * u[i].dot(b[i])).sum();
            for i in 0..n {
                u[i] -= c * b[i];
            }
        }
        let norm: f64 = (0..n)
            .map(|i| model.mass[i] * u[i].length_squared())
            .sum::<f64>()
            .sqrt();
        if norm > 1e-9 * mass.sqrt() {
            for p in &mut u {
                *p /= norm;
            }
            basis.push(u);
        }
    }
    basis
}

/// A fixed pseudo-random perturbation (xorshift64*), zero on pinned particles.
fn start_vector(n: usize, free: &[bool]) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut random = XorShift64Star::new(0x2545_F491_4F6C_DD1D);
    let mut next = || random.symmetric();
    let mut dx = vec![DVec3::ZERO; n];
    let mut dv = vec![DVec3::ZERO; n];
    for i in 0..n {
        let a = DVec3::new(next(), next(), next());
        let b = DVec3::new(next(), next(), next());
        if free[i] {
            dx[i] = a;
            dv[i] = b;
        }
    }
    (dx, dv)
}
