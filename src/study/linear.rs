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

use glam::{DMat3, DVec3};
use serde::Serialize;

use super::modes::stiffness_blocks;
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
    blocks: Vec<DMat3>,
    free: Vec<bool>,
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
        let blocks = stiffness_blocks(&model, &base.x);
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
            rigid,
            length,
            omega: if omega_max > 0.0 { omega_max } else { 1.0 },
        }
    }

    /// The perturbation's energy `E(δ)` (module docs).
    fn energy(&self, dx: &[DVec3], dv: &[DVec3]) -> f64 {
        let mut e = 0.0;
        for i in 0..dx.len() {
            if self.free[i] {
                e += 0.5 * self.model.mass[i] * dv[i].length_squared();
            }
        }
        for (s, k) in self.model.springs().iter().zip(&self.blocks) {
            let d = dx[s.b as usize] - dx[s.a as usize];
            e += 0.5 * d.dot(*k * d);
        }
        e
    }

    /// `u ← M⁻¹ K_0 u` (zero on pinned particles).
    fn stiffness_times(&self, u: &mut [DVec3]) {
        let mut y = vec![DVec3::ZERO; u.len()];
        for (s, k) in self.model.springs().iter().zip(&self.blocks) {
            let (a, b) = (s.a as usize, s.b as usize);
            let f = *k * (u[a] - u[b]);
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

    /// Removes the rigid components of `(dx, dv)` (M-orthogonal projection).
    fn remove_rigid(&self, dx: &mut [DVec3], dv: &mut [DVec3]) {
        for mode in &self.rigid {
            for u in [&mut *dx, &mut *dv] {
                let c: f64 = (0..u.len())
                    .map(|i| self.model.mass[i] * u[i].dot(mode[i]))
                    .sum();
                for i in 0..u.len() {
                    u[i] -= c * mode[i];
                }
            }
        }
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
        self.remove_rigid(&mut dx, &mut dv);
        let e = self.energy(&dx, &dv);
        if e.is_nan() || e <= 0.0 {
            return Growth {
                steps: 0,
                stable: true,
                rho: 1.0,
                ratio: None,
                stopped: "decayed",
            };
        }
        let norm = e.sqrt();
        for i in 0..n {
            dx[i] /= norm;
            dv[i] /= norm;
        }
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
            let scale = (0..n)
                .filter(|&i| self.free[i])
                .map(|i| {
                    dx[i]
                        .abs()
                        .max_element()
                        .max(dv[i].abs().max_element() / self.omega)
                })
                .fold(0.0, f64::max);
            if !(scale > 0.0 && scale.is_finite()) {
                return stop(k, log_e, false, "not finite");
            }
            let s = FD_SIZE * self.length / scale;
            for (state, sign) in [(&mut plus, 1.0), (&mut minus, -1.0)] {
                for i in 0..n {
                    state.x[i] = self.base.x[i] + sign * s * dx[i];
                    state.v[i] = self.base.v[i] + sign * s * dv[i];
                    // Verlet's history: the displacement that the velocity implies.
                    state.x_prev[i] = state.x[i] - dt * state.v[i];
                }
                state.history_valid = true;
                method.step(&self.model, state, dt, params, &mut work);
            }
            let inv = 0.5 / s;
            for i in 0..n {
                dx[i] = (plus.x[i] - minus.x[i]) * inv;
                dv[i] = (plus.v[i] - minus.v[i]) * inv;
            }
            self.remove_rigid(&mut dx, &mut dv);
            let g = self.energy(&dx, &dv);
            if !(g.is_finite() && g > 0.0) {
                if g == 0.0 {
                    return stop(k + 1, log_e, true, "decayed");
                }
                return stop(k + 1, log_e, false, "not finite");
            }
            log_e += g.ln();
            let root = g.sqrt();
            for i in 0..n {
                dx[i] /= root;
                dv[i] /= root;
            }
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
