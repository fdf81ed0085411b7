//! The damped theory of the stability limits: every method's largest stable `dt` from the
//! eigenvalues of the linearised damped system and the method's stability function.
//!
//! # Theory
//!
//! Linearised about a state, small displacements `x` of the free particles obey
//!
//! ```text
//! M x'' = -K x - C x'
//! ```
//! where `M` is the diagonal mass matrix (kg), `K = -∂f/∂x` the stiffness (N/m, as in
//! [`super::modes`]) and `C = -∂f/∂v` the damping (N·s/m): per spring `k_d n nᵀ` assembled like
//! `K`, plus the drag `c I`. When `C = α K + β M` (Rayleigh damping) `K` and `C` share their
//! modes, and each mode `i` of `M⁻¹K` (angular frequency `ω_i`, rad/s) is a damped oscillator
//!
//! ```text
//! u'' + μ_i u' + ω_i² u = 0,       μ_i = α ω_i² + β                       (1/s)
//! λ_i± = -μ_i/2 ± √(μ_i²/4 - ω_i²)                                     (1/s, complex when ω_i > μ_i/2)
//! ```
//! The course's scenes are of this kind: one damper coefficient `k_d` and one stiffness `k` for
//! every spring, springs at rest length (no transverse stiffness), equal masses, so
//! `α = k_d/k` and `β = c/m`. A mode with `μ > 2ω` is overdamped: its fast root
//! `-μ/2 - √(μ²/4 - ω²) ≈ -μ` is a decay, not an oscillation, and that is what limits the
//! explicit methods on the cube (`μ ≈ 1011` 1/s for its stiffest mode, fast root `-976` 1/s).
//!
//! **Stability functions.** A Runge–Kutta type method multiplies a mode's amplitude by `R(z)`,
//! `z = dt λ`, per step; it is stable on that mode while `|R(z)| ≤ 1` for both roots:
//!
//! ```text
//! explicit Euler          R = 1 + z
//! midpoint                R = 1 + z + z²/2
//! RK4                     R = 1 + z + z²/2 + z³/6 + z⁴/24
//! predictor–corrector     R = 1 + z + z²
//! implicit Euler          R = 1 / (1 - z)                    |R| < 1 for Re z < 0: unconditional
//! ```
//! Semi-implicit Euler and Verlet act on `(u, u')` and `(u_n, u_{n-1})` with 2×2 matrices;
//! their eigenvalues `r` solve `r² - t r + d = 0`, stable while `|d| ≤ 1` and `|t| ≤ 1 + d`
//! (the Schur–Cohn conditions for a real quadratic):
//!
//! ```text
//! semi-implicit Euler   t = 2 - dt² ω² - dt μ,             d = 1 - dt μ
//! Verlet                t = 1 + c - dt² ω²/(1 + h),       d = c,
//!                       c = (1 - γ)(1 - h)/(1 + h) - dt μ/(1 + h),   h = r dt / 2
//! ```
//! where Verlet's dampers see the backward-difference velocity `(u_n - u_{n-1})/dt`, `γ` is its
//! damping factor per step and `r` its damping rate (1/s). Verlet with constraint projection
//! and XPBD solve constraints, not these equations: the theory does not cover them.
//!
//! **The limit.** For each mode, the largest `dt` below which every smaller step is stable;
//! the method's limit is the smallest over the spectrum, and the mode that sets it is reported.
//! It is searched on `dt·ω_max` from 0.01 to 100 (the study's range): unstable at 0.01 is
//! "none", stable at 100 "unconditional".
//!
//! **The spectrum.** Up to [`DENSE_MAX`] free coordinates, all the eigenvalues of
//! `M^(-1/2) K M^(-1/2)` by Jacobi rotations: exact. Above, the modes are treated as a continuum
//! `0 ≤ ω ≤ ω_max` (ω_max by power iteration, [`super::modes`]): the limit is then a lower
//! bound, exact when the binding mode is `ω_max` itself (the report says which). When `C` is not
//! Rayleigh (per-kind dampers, stretched springs, unequal masses) each mode is given the
//! smallest and the largest damper-to-spring ratio `k_d/k` of the scene and the smaller limit is
//! kept: an estimate, and the report says so.
//!
//! References: E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
//! Springer 1996, §IV.2 (stability functions); T. Belytschko, T. J. R. Hughes (eds.),
//! *Computational Methods for Transient Analysis*, North-Holland 1983, ch. 2 (Rayleigh damping
//! and the critical time step of damped explicit integration); G. H. Golub, C. F. Van Loan,
//! *Matrix Computations*, 4th ed., 2013, §8.5 (the Jacobi method); E. I. Jury, *Theory and
//! Application of the z-Transform Method*, Wiley 1964 (the conditions for a quadratic).

use serde::Serialize;

pub mod equilibrium;

use super::modes::stiffness_blocks;
use crate::physics::{Method, MethodParams, Model, StabilityFunction, State};

/// Largest number of free coordinates (3 per free particle) solved densely.
pub const DENSE_MAX: usize = 360;

/// The theory's search range of `dt·ω_max`.
pub const RANGE: [f64; 2] = [0.01, 100.0];

/// Modes of a continuum spectrum sampled below `ω_max`.
const CONTINUUM_SAMPLES: usize = 400;

/// One mode of the linearised system.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Mode {
    /// Angular frequency of the undamped mode `ω` (rad/s).
    pub omega: f64,
    /// Damping rate `μ` in `u'' + μ u' + ω² u = 0` (1/s).
    pub mu: f64,
}

impl Mode {
    /// The two roots `λ± = -μ/2 ± √(μ²/4 - ω²)` as `(re, im)` pairs (1/s).
    #[must_use]
    pub fn roots(&self) -> [(f64, f64); 2] {
        let half = 0.5 * self.mu;
        let disc = half * half - self.omega * self.omega;
        if disc >= 0.0 {
            let s = disc.sqrt();
            [(-half - s, 0.0), (-half + s, 0.0)]
        } else {
            let s = (-disc).sqrt();
            [(-half, s), (-half, -s)]
        }
    }
}

/// The linearised spectrum of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// The modes (several damping variants per frequency when not Rayleigh).
    pub modes: Vec<Mode>,
    /// `ω_max` (rad/s).
    pub omega_max: f64,
    /// True when the modes are all the eigenvalues (dense); false for a continuum.
    pub dense: bool,
    /// `Some((α, β))` when the damping is Rayleigh, `C = α K + β M`.
    pub rayleigh: Option<(f64, f64)>,
    /// How the spectrum was obtained, in words.
    pub how: String,
}

/// The theoretical limit of one method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TheoryLimit {
    /// `conditional`, `none`, `unconditional`, or `not covered` (projection, XPBD).
    pub stability: &'static str,
    /// The largest stable `dt` (s) when conditional.
    pub dt: Option<f64>,
    /// `dt·ω_max` when conditional.
    pub dt_omega: Option<f64>,
    /// The mode that sets the limit, when conditional.
    pub binding: Option<Binding>,
    /// How the limit was obtained, in words.
    pub how: String,
}

/// The mode that sets a limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Binding {
    /// Its undamped angular frequency `ω` (rad/s).
    pub omega: f64,
    /// Its damping rate `μ` (1/s).
    pub mu: f64,
    /// The root `λ` with the larger `|λ|` (1/s): real part.
    pub lambda_re: f64,
    /// Imaginary part (1/s).
    pub lambda_im: f64,
    /// True when this is the stiffest mode `ω_max`.
    pub stiffest: bool,
}

/// The spectrum of `model` linearised at `state` (module docs), `omega_max` (rad/s) from the
/// power iteration.
#[must_use]
pub fn spectrum(model: &Model, state: &State, omega_max: f64) -> Spectrum {
    let free: Vec<usize> = (0..model.particle_count())
        .filter(|&i| !model.is_pinned(i))
        .collect();
    let (ratios, rayleigh_springs) = damper_ratios(model, state);
    let masses: Vec<f64> = free.iter().map(|&i| model.mass[i]).collect();
    let equal_masses = masses.windows(2).all(|w| w[0] == w[1]);
    let beta = masses.first().map_or(0.0, |m| model.drag / m);
    let rayleigh = (rayleigh_springs && (equal_masses || model.drag == 0.0))
        .then_some((ratios.0, if model.drag == 0.0 { 0.0 } else { beta }));
    let (beta_lo, beta_hi) = if model.drag == 0.0 {
        (0.0, 0.0)
    } else {
        let lo = masses
            .iter()
            .fold(f64::INFINITY, |a, m| a.min(model.drag / m));
        let hi = masses.iter().fold(0.0f64, |a, m| a.max(model.drag / m));
        (lo, hi)
    };
    let dense = 3 * free.len() <= DENSE_MAX;
    let omegas2: Vec<f64> = if dense {
        dense_eigenvalues(model, state, &free)
    } else {
        let top = omega_max * omega_max;
        (1..=CONTINUUM_SAMPLES)
            .map(|k| top * (k as f64 / CONTINUUM_SAMPLES as f64).powi(2))
            .collect()
    };
    let mut modes = Vec::new();
    for &w2 in omegas2
        .iter()
        .filter(|w2| **w2 > 1e-12 * omega_max * omega_max)
    {
        let omega = w2.sqrt();
        match rayleigh {
            Some((alpha, beta)) => modes.push(Mode {
                omega,
                mu: alpha * w2 + beta,
            }),
            None => {
                modes.push(Mode {
                    omega,
                    mu: ratios.0 * w2 + beta_lo,
                });
                modes.push(Mode {
                    omega,
                    mu: ratios.1 * w2 + beta_hi,
                });
            }
        }
    }
    let source = if dense {
        format!(
            "all {} modes of M⁻¹K by a dense eigen-solve (Jacobi)",
            omegas2.len()
        )
    } else {
        format!(
            "modes as a continuum 0 < ω ≤ ω_max = {omega_max:.6} rad/s ({} free coordinates, \
             above the dense limit {DENSE_MAX})",
            3 * free.len()
        )
    };
    let how = match rayleigh {
        Some((alpha, beta)) => format!(
            "exact for Rayleigh damping C = αK + βM (α = {alpha:.6e} s, β = {beta:.6e} 1/s), \
             linearised at the initial state; {source}"
        ),
        None => format!(
            "estimated: the damping is not Rayleigh (k_d/k from {:.6e} to {:.6e} s, or \
             stretched springs or unequal masses with drag); each mode given the smallest and \
             the largest ratio; {source}",
            ratios.0, ratios.1
        ),
    };
    Spectrum {
        modes,
        omega_max,
        dense,
        rayleigh,
        how,
    }
}

/// `((min, max) of k_d/k over the springs, whether C = (k_d/k) K exactly)`. A spring longer
/// than its rest length has transverse stiffness but no transverse damping: not proportional.
fn damper_ratios(model: &Model, state: &State) -> ((f64, f64), bool) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    let mut proportional = true;
    for s in model.springs() {
        if s.stiffness > 0.0 {
            let r = s.damping / s.stiffness;
            lo = lo.min(r);
            hi = hi.max(r);
            let length = s.length(&state.x);
            if length > s.rest_length * (1.0 + 1e-12) && s.damping > 0.0 {
                proportional = false;
            }
        } else if s.damping > 0.0 {
            proportional = false;
        }
    }
    if lo > hi {
        (lo, hi) = (0.0, 0.0);
    }
    proportional &= hi - lo <= 1e-12 * hi;
    ((lo, hi), proportional)
}

/// The eigenvalues `ω²` of `M^(-1/2) K M^(-1/2)` over the free coordinates (1/s²).
fn dense_eigenvalues(model: &Model, state: &State, free: &[usize]) -> Vec<f64> {
    let n = 3 * free.len();
    let mut index = vec![usize::MAX; model.particle_count()];
    for (k, &i) in free.iter().enumerate() {
        index[i] = k;
    }
    let mut a = vec![0.0; n * n];
    let blocks = stiffness_blocks(model, &state.x);
    for (s, k) in model.springs().iter().zip(&blocks) {
        add_spring_block(&mut a, n, index[s.a as usize], index[s.b as usize], k);
    }
    // Scale: A_ij / √(m_i m_j).
    for (p, &i) in free.iter().enumerate() {
        for (q, &j) in free.iter().enumerate() {
            let s = (model.inv_mass[i] * model.inv_mass[j]).sqrt();
            for r in 0..3 {
                for c in 0..3 {
                    a[(3 * p + r) * n + 3 * q + c] *= s;
                }
            }
        }
    }
    jacobi_eigenvalues(&mut a, n)
}

/// Adds a spring's 3×3 stiffness block `k` between the free particles `ia` and `ib` (row index
/// in the free set; `usize::MAX` for a pinned end) to the dense `n × n` matrix `a`: `+k` on
/// both diagonal blocks, `-k` on both off-diagonal ones.
pub(crate) fn add_spring_block(a: &mut [f64], n: usize, ia: usize, ib: usize, k: &glam::DMat3) {
    let cols = [k.x_axis, k.y_axis, k.z_axis];
    for (p, q, sign) in [(ia, ia, 1.0), (ib, ib, 1.0), (ia, ib, -1.0), (ib, ia, -1.0)] {
        if p == usize::MAX || q == usize::MAX {
            continue;
        }
        for (c, col) in cols.iter().enumerate() {
            for r in 0..3 {
                a[(3 * p + r) * n + 3 * q + c] += sign * col[r];
            }
        }
    }
}

/// The eigenvalues of the symmetric `n × n` matrix `a` (row-major, destroyed) by cyclic Jacobi
/// rotations (Golub & Van Loan §8.5.3), ascending.
#[must_use]
pub fn jacobi_eigenvalues(a: &mut [f64], n: usize) -> Vec<f64> {
    jacobi_rotate(a, n, None);
    let mut values: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
    values.sort_by(f64::total_cmp);
    values
}

/// Cyclic Jacobi rotations of the symmetric `n × n` matrix `a` (row-major) until it is diagonal
/// (Golub & Van Loan §8.5.3); each rotation is also applied to the columns of `vectors` when
/// given (start it at the identity to get the eigenvectors).
pub(crate) fn jacobi_rotate(a: &mut [f64], n: usize, mut vectors: Option<&mut [f64]>) {
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-30 * diag.max(f64::MIN_POSITIVE) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (a[p * n + p], a[q * n + q]);
                // t = tan θ with cot 2θ = (a_qq - a_pp) / (2 a_pq), the smaller root.
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                if let Some(v) = vectors.as_deref_mut() {
                    for k in 0..n {
                        let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                        v[k * n + p] = c * vkp - s * vkq;
                        v[k * n + q] = s * vkp + c * vkq;
                    }
                }
            }
        }
    }
}

/// Schur–Cohn: both roots of `r² - t r + d` within the unit circle (to rounding).
fn quadratic_stable(t: f64, d: f64) -> bool {
    const EPS: f64 = 1e-12;
    d.abs() <= 1.0 + EPS && t.abs() <= 1.0 + d + EPS
}

/// Whether `method` is stable on `mode` at `dt` (module docs), by its stability function
/// (its declaration).
fn stable_on(method: Method, params: &MethodParams, mode: &Mode, dt: f64) -> bool {
    let (w2, mu) = (mode.omega * mode.omega, mode.mu);
    match (method.declaration().stability)(params) {
        StabilityFunction::TwoStep(f) => {
            let (t, d) = f(params, dt, w2, mu);
            quadratic_stable(t, d)
        }
        StabilityFunction::OneStep(r) => mode.roots().iter().all(|&(re, im)| {
            let (a, b) = r((dt * re, dt * im));
            (a * a + b * b).sqrt() <= 1.0 + 1e-12
        }),
        // `limit` answers before asking.
        StabilityFunction::NotCovered(_) => true,
    }
}

/// The largest `dt` (s) such that `method` is stable on `mode` at every smaller step, searched
/// on `dt·ω_max` in [`RANGE`]: `Some(0)` when unstable at the floor, `None` when stable at the
/// ceiling.
fn mode_limit(method: Method, params: &MethodParams, mode: &Mode, omega_max: f64) -> Option<f64> {
    let [lo, hi] = RANGE;
    let steps = 600;
    let z_at = |k: usize| lo * (hi / lo).powf(k as f64 / steps as f64);
    let mut last_stable = None;
    for k in 0..=steps {
        let z = z_at(k);
        if stable_on(method, params, mode, z / omega_max) {
            last_stable = Some(z);
            continue;
        }
        let Some(mut a) = last_stable else {
            return Some(0.0);
        };
        let mut b = z;
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if stable_on(method, params, mode, m / omega_max) {
                a = m;
            } else {
                b = m;
            }
        }
        return Some(a / omega_max);
    }
    None
}

/// The theoretical limit of `method` (with `params`) over `spectrum` (module docs).
#[must_use]
pub fn limit(method: Method, params: &MethodParams, spectrum: &Spectrum) -> TheoryLimit {
    let not_covered = |why: &str| TheoryLimit {
        stability: "not covered",
        dt: None,
        dt_omega: None,
        binding: None,
        how: why.to_string(),
    };
    if let StabilityFunction::NotCovered(why) = (method.declaration().stability)(params) {
        return not_covered(why);
    }
    let omega_max = spectrum.omega_max;
    let mut best: Option<(f64, &Mode)> = None;
    for mode in &spectrum.modes {
        if let Some(dt) = mode_limit(method, params, mode, omega_max)
            && best.is_none_or(|(b, _)| dt < b)
        {
            best = Some((dt, mode));
        }
    }
    let how = spectrum.how.clone();
    match best {
        None => TheoryLimit {
            stability: "unconditional",
            dt: None,
            dt_omega: None,
            binding: None,
            how,
        },
        Some((0.0, _)) => TheoryLimit {
            stability: "none",
            dt: None,
            dt_omega: None,
            binding: None,
            how,
        },
        Some((dt, mode)) => {
            let [a, b] = mode.roots();
            let (re, im) = if a.0.hypot(a.1) >= b.0.hypot(b.1) {
                a
            } else {
                b
            };
            let stiffest = (mode.omega - omega_max).abs() <= 1e-9 * omega_max
                || (spectrum.dense
                    && spectrum
                        .modes
                        .iter()
                        .all(|m| m.omega <= mode.omega * (1.0 + 1e-9)));
            let bound = if !spectrum.dense && !stiffest {
                " — a lower bound: the binding ω lies inside the continuum"
            } else {
                ""
            };
            TheoryLimit {
                stability: "conditional",
                dt: Some(dt),
                dt_omega: Some(dt * omega_max),
                binding: Some(Binding {
                    omega: mode.omega,
                    mu: mode.mu,
                    lambda_re: re,
                    lambda_im: im.abs(),
                    stiffest,
                }),
                how: format!("{how}{bound}"),
            }
        }
    }
}
