//! Implicit Euler's linear solve: the assembled system `A Δv = b` of one step, matrix-free, and
//! preconditioned conjugate gradients on it with pinned rows filtered and the contacts'
//! normal components prescribed (Shewchuk §B3; Baraff & Witkin §5.3).
//!
//! **Reported solve.** [`SolveStats`] holds the conjugate-gradient iterations (over all passes)
//! and the final relative residual of the last step; a solve that stops above its tolerance, or
//! whose right-hand side or residual is not finite (an overflowing stiffness), is not
//! `converged`, and a simulation reports that as a divergence. CG stops at `|r| ≤ tol·|b|`,
//! `tol = 10⁻³` by default (`cg_tolerance`): the one Newton step's own error is far larger
//! (`tests/integrators.rs` keeps the solve's share under a tenth).

use glam::{DMat3, DVec3};
use serde::Serialize;

use super::Constraint;
use crate::physics::fast::implicit_constraint::SphereRows;
use crate::physics::forces::Model;

/// How the last linear solve went.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SolveStats {
    /// Conjugate-gradient iterations taken, over all contact passes of the step.
    pub iterations: u32,
    /// Final relative residual `|r| / |b|` (NaN when the system was not finite).
    pub relative_residual: f64,
    /// True when the residual reached the tolerance (or the right-hand side was zero).
    pub converged: bool,
    /// Solves taken (1 + contact passes).
    pub passes: u32,
    /// Particles whose normal velocity the contacts prescribed.
    pub constrained: u32,
}

impl SolveStats {
    /// Adds one solve of `iterations` that ended at relative residual `residual`.
    pub(super) fn record(&mut self, iterations: u32, residual: f64, converged: bool) {
        self.iterations += iterations;
        self.relative_residual = residual;
        self.converged = converged;
        self.passes += 1;
    }
}

impl Default for SolveStats {
    fn default() -> SolveStats {
        SolveStats {
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
            passes: 0,
            constrained: 0,
        }
    }
}

impl SolveStats {
    /// Why the solve failed, in words; `None` when it converged.
    #[must_use]
    pub fn failure(&self, tolerance: f64) -> Option<String> {
        if self.converged {
            return None;
        }
        Some(if self.relative_residual.is_finite() {
            format!(
                "implicit Euler: the linear solve did not converge ({} conjugate-gradient \
                 iterations, relative residual {:.3e} > tolerance {tolerance:.1e})",
                self.iterations, self.relative_residual
            )
        } else {
            "implicit Euler: the linear solve overflowed (a force, the matrix or the residual \
             is not finite)"
                .to_string()
        })
    }
}

/// The assembled system `A Δv = b` of one step.
pub(super) struct System<'a> {
    pub(super) model: &'a Model,
    pub(super) dt: f64,
    pub(super) blocks: &'a [DMat3],
    pub(super) diag_inv: &'a [DMat3],
    pub(super) rhs: &'a [DVec3],
}

impl System<'_> {
    /// `out = A p`, pinned rows zero.
    pub(super) fn apply(&self, p: &[DVec3], out: &mut [DVec3]) {
        let model = self.model;
        for (i, o) in out.iter_mut().enumerate() {
            *o = (model.mass[i] + self.dt * model.drag) * p[i];
        }
        for (s, block) in model.springs.iter().zip(self.blocks) {
            let (ia, ib) = (s.a as usize, s.b as usize);
            let y = *block * (p[ia] - p[ib]);
            out[ia] += y;
            out[ib] -= y;
        }
        for (i, o) in out.iter_mut().enumerate() {
            if model.inv_mass[i] == 0.0 {
                *o = DVec3::ZERO;
            }
        }
    }

    /// Preconditioned conjugate gradients on `A Δv = b` with pinned rows filtered and the
    /// constrained particles' normal components prescribed (Shewchuk §B3; Baraff & Witkin §5.3),
    /// the touched dynamic spheres' velocities solved with them (`spheres`, the rows of
    /// [`SphereRows`]). Writes `Δv` into `cg[0]`; returns the iterations, the final relative
    /// residual and whether it reached the tolerance.
    pub(super) fn solve(
        &self,
        constraints: &[Constraint],
        (tolerance, max_iterations): (f64, u32),
        cg: &mut [Vec<DVec3>; 4],
        warm: bool,
        spheres: &mut SphereRows,
    ) -> (u32, f64, bool) {
        let n = self.rhs.len();
        let [dv, r, p, ap] = cg;
        // S: remove the constrained normal components (sorted by particle).
        let filter = |v: &mut [DVec3]| {
            for c in constraints {
                v[c.i] -= v[c.i].dot(c.normal) * c.normal;
            }
        };
        // Δv starts at z: the prescribed normal velocity changes, and elsewhere zero, or a
        // warm start (the previous pass's solution, which changed only near contacts, or the
        // last step's Δv). A warm start whose residual is not below |b| is dropped for zero.
        let mut warm = warm;
        let b_norm2 = loop {
            if !warm {
                dv.fill(DVec3::ZERO);
            }
            for c in constraints {
                let along = dv[c.i].dot(c.normal);
                dv[c.i] += (spheres.target(c) - along) * c.normal;
            }
            // r = S (b - A z), pinned rows zero.
            self.apply(dv, ap);
            let mut b_norm2 = 0.0;
            for i in 0..n {
                let b = if self.model.inv_mass[i] != 0.0 {
                    self.rhs[i]
                } else {
                    DVec3::ZERO
                };
                b_norm2 += b.length_squared();
                r[i] = if self.model.inv_mass[i] != 0.0 {
                    b - ap[i]
                } else {
                    DVec3::ZERO
                };
            }
            let (b_spheres, r_spheres) = spheres.first_residual(constraints, |i| r[i]);
            b_norm2 += b_spheres;
            filter(r);
            let r_norm2 = r.iter().map(|r| r.length_squared()).sum::<f64>() + r_spheres;
            if warm && r_norm2 >= b_norm2 {
                warm = false;
                continue;
            }
            break b_norm2;
        };
        if !b_norm2.is_finite() {
            return (0, f64::NAN, false);
        }
        // Relative to |b|, but never below the smallest normal number: a state so close to rest
        // that |b|² underflows has nothing left to solve for.
        let tol2 = (tolerance * tolerance * b_norm2).max(f64::MIN_POSITIVE);
        // z = S P⁻¹ r, stored in p as the first search direction.
        let mut rz = 0.0;
        for i in 0..n {
            p[i] = self.diag_inv[i] * r[i];
        }
        filter(p);
        for i in 0..n {
            rz += r[i].dot(p[i]);
        }
        rz += spheres.first_direction();
        let mut r_norm2: f64 = r.iter().map(|r| r.length_squared()).sum();
        r_norm2 += spheres.first_residual_norm2();
        let mut iterations = 0;
        while r_norm2 > tol2 && iterations < max_iterations {
            // T p (the tied particles' normal parts from the spheres), A T p, then Tᵀ: the
            // spheres' rows gathered and the constrained normal parts filtered out.
            spheres.expand(constraints, &mut p[..]);
            self.apply(p, ap);
            let mut p_ap: f64 = p.iter().zip(ap.iter()).map(|(p, q)| p.dot(*q)).sum();
            p_ap += spheres.gather(constraints, |i| ap[i]);
            filter(p);
            filter(ap);
            if p_ap.is_nan() || p_ap <= 0.0 {
                break;
            }
            let alpha = rz / p_ap;
            r_norm2 = 0.0;
            for i in 0..n {
                dv[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
                r_norm2 += r[i].length_squared();
            }
            let (rr_spheres, rz_spheres) = spheres.descend(alpha, constraints, &mut dv[..]);
            r_norm2 += rr_spheres;
            // z = S P⁻¹ r
            for i in 0..n {
                ap[i] = self.diag_inv[i] * r[i];
            }
            filter(ap);
            let rz_new: f64 =
                r.iter().zip(ap.iter()).map(|(r, z)| r.dot(*z)).sum::<f64>() + rz_spheres;
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = ap[i] + beta * p[i];
            }
            spheres.redirect(beta);
            iterations += 1;
        }
        let residual = if b_norm2 > 0.0 {
            (r_norm2 / b_norm2).sqrt()
        } else {
            0.0
        };
        let converged = r_norm2.is_finite() && r_norm2 <= tol2;
        (iterations, residual, converged)
    }
}
