//! Distance constraints: projection for position Verlet and the compliant XPBD solve.
//!
//! # Theory
//!
//! A distance constraint between particles `a` and `b` asks that their distance equal the rest
//! length:
//!
//! ```text
//! C(x) = |x_b - x_a| - L0 = 0
//! ```
//!
//! **Projection** (Jakobsen, "Advanced Character Physics", GDC 2001; GAMES101 assignment 8 §1.3–1.4)
//! moves both ends along the spring so that `C = 0` again, each in proportion to its inverse mass:
//!
//! ```text
//! d      = x_b - x_a,   L = |d|
//! corr   = d (L - L0) / L                  the whole error, as a vector from a to b
//! x_a   += w_a / (w_a + w_b) · corr         a moves towards b when stretched
//! x_b   -= w_b / (w_a + w_b) · corr
//! ```
//! where `w = 1/m` (1/kg), zero for a pinned end. With equal masses each end moves half; a pinned
//! end does not move and the free end takes all of it. Constraints are visited colour by colour
//! (see [`Model::spring_colours`]): Gauss–Seidel, red-black on a chain. The shares
//! `w_a / (w_a + w_b)` are computed once per step ([`prepare_rods`]), not once per pass.
//!
//! **Fast path.** [`project_distances`] is the textbook loop. On a chain (a rope) the rods of
//! one colour are projected eight at a time with the same operations, so with the same bits
//! ([`project_distances_fast`], `fast/chain.rs`, tested against the loop).
//!
//! **XPBD** (Macklin, Müller & Chentanez, "XPBD: Position-Based Simulation of Compliant
//! Constrained Dynamics", MIG 2016, eq. 18 and 26) treats a spring of stiffness `k` as a
//! constraint of compliance `α = 1/k` and a damper `k_d` as constraint damping `β = k_d`:
//!
//! ```text
//! α̃   = α / h²                          time-step scaled compliance
//! γ   = α β / h                          damping ratio of the step
//! Δλ  = (-C - α̃ λ - γ ∇C·(x - x_prev)) / ((1 + γ) (w_a + w_b) + α̃)
//! λ  += Δλ
//! x_a += w_a Δλ ∇C_a = -w_a Δλ n,   x_b += w_b Δλ ∇C_b = w_b Δλ n
//! ```
//! where `h` is the substep (s), `n = (x_b - x_a)/L` and `λ` the accumulated Lagrange multiplier (N·s²).

use glam::DVec3;

use super::forces::Model;
use super::stencil::Kernel;
pub use crate::physics::fast::chain::{ChainScratch, project_chain};

/// One distance constraint ready for projection: its ends, its rest length and the share of
/// the correction each end takes, `w_a / (w_a + w_b)` and `w_b / (w_a + w_b)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rod {
    /// First end.
    pub a: u32,
    /// Second end.
    pub b: u32,
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// `w_a / (w_a + w_b)` (dimensionless).
    pub share_a: f64,
    /// `w_b / (w_a + w_b)` (dimensionless).
    pub share_b: f64,
}

/// The springs of `model` as rods in projection order (colour by colour, see
/// [`Model::spring_colours`]), with the shares of the current inverse masses; a spring between
/// two pinned particles is left out (neither end can move). Reuses `rods`' allocation.
///
/// The shares depend only on the masses, so computing them once per step instead of once per
/// pass saves two divisions per constraint and pass.
pub fn prepare_rods(model: &Model, rods: &mut Vec<Rod>) {
    rods.clear();
    for colour in model.spring_colours() {
        for &s in colour {
            let s = &model.springs[s as usize];
            let (w_a, w_b) = (model.inv_mass[s.a as usize], model.inv_mass[s.b as usize]);
            let w = w_a + w_b;
            if w == 0.0 {
                continue;
            }
            rods.push(Rod {
                a: s.a,
                b: s.b,
                rest_length: s.rest_length,
                share_a: w_a / w,
                share_b: w_b / w,
            });
        }
    }
}

/// Projects every rod to its rest length, `iterations` times over the list (Gauss–Seidel in
/// the order of [`prepare_rods`]).
///
/// Pinned particles (share 0) never move; a rod of zero length is skipped.
///
/// # Panics
/// If a rod's end is out of range of `x`.
pub fn project_distances(rods: &[Rod], x: &mut [DVec3], iterations: u32) {
    for _ in 0..iterations {
        for rod in rods {
            let (a, b) = (rod.a as usize, rod.b as usize);
            let d = x[b] - x[a];
            let length = d.length();
            if length == 0.0 {
                continue;
            }
            // corr = d (L - L0) / L: the whole stretch, as a vector from a to b.
            let corr = d * ((length - rod.rest_length) / length);
            x[a] += rod.share_a * corr;
            x[b] -= rod.share_b * corr;
        }
    }
}

/// [`project_distances`] with the same result bit for bit, eight rods at a time when the rods
/// form a chain (a rope: [`project_chain`], see `fast/chain.rs`); the textbook loop
/// otherwise. `scratch` holds the chain's arrays between calls.
///
/// # Panics
/// If a rod's end is out of range of `x`.
pub fn project_distances_fast(
    rods: &[Rod],
    x: &mut [DVec3],
    iterations: u32,
    scratch: &mut ChainScratch,
) {
    if !project_chain(rods, x, iterations, scratch, Kernel::best()) {
        project_distances(rods, x, iterations);
    }
}

/// One XPBD pass over all springs as compliant constraints (see the module docs).
///
/// `lambda` holds one multiplier per spring and accumulates over the passes of a substep;
/// `x_prev` are the positions at the start of the substep; `h` is the substep (s).
pub fn xpbd_solve(model: &Model, x: &mut [DVec3], x_prev: &[DVec3], lambda: &mut [f64], h: f64) {
    for colour in model.spring_colours() {
        for &si in colour {
            let s = &model.springs[si as usize];
            let (a, b) = (s.a as usize, s.b as usize);
            let (w_a, w_b) = (model.inv_mass[a], model.inv_mass[b]);
            if w_a + w_b == 0.0 || s.stiffness <= 0.0 {
                // Two pinned ends cannot move; zero stiffness means infinite compliance: no force.
                continue;
            }
            let d = x[b] - x[a];
            let length = d.length();
            if length == 0.0 {
                continue;
            }
            let n = d / length;
            // C = L - L0 and its gradients ∇C_b = n, ∇C_a = -n.
            let c = length - s.rest_length;
            // α̃ = α / h² with α = 1/k.
            let alpha_tilde = 1.0 / (s.stiffness * h * h);
            // γ = α β / h with β = k_d.
            let gamma = s.damping / (s.stiffness * h);
            // ∇C·(x - x_prev) = n · (Δx_b - Δx_a): how fast the constraint is changing.
            let c_dot = n.dot((x[b] - x_prev[b]) - (x[a] - x_prev[a]));
            let lambda_i = &mut lambda[si as usize];
            let delta_lambda = (-c - alpha_tilde * *lambda_i - gamma * c_dot)
                / ((1.0 + gamma) * (w_a + w_b) + alpha_tilde);
            *lambda_i += delta_lambda;
            x[a] -= w_a * delta_lambda * n;
            x[b] += w_b * delta_lambda * n;
        }
    }
}
