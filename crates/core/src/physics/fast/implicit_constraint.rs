//! A contact constraint of implicit Euler's solve (see the module docs of
//! [`crate::physics::integrators`], implicit Euler, "Contacts"): the textbook loop and the lattice path
//! ([`super::implicit_lattice`]) both read it, so it lives apart from either.

use glam::DVec3;

/// One contact constraint: particle `i` gets the velocity change `dv_n` (m/s) along the unit
/// `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Constraint {
    pub(crate) i: usize,
    pub(crate) normal: DVec3,
    pub(crate) dv_n: f64,
    /// The dynamic sphere it touches (index into `State::spheres`), `None` for a collider.
    pub(crate) sphere: Option<usize>,
}

/// Rows of a velocity-sized vector that [`SphereRows`] changes: the textbook's
/// `[DVec3]` and the lattice's structure of arrays both implement it.
pub(crate) trait Rows {
    /// Adds `d` to row `i`.
    fn add_row(&mut self, i: usize, d: DVec3);
}

impl Rows for [DVec3] {
    fn add_row(&mut self, i: usize, d: DVec3) {
        self[i] += d;
    }
}

/// The dynamic spheres inside implicit Euler's solve: each sphere that a constraint touches
/// is three more unknowns, its velocity change `ΔV` (m/s), and a constrained particle's normal
/// velocity is tied to it (the contact is a constraint between the two bodies, not against a
/// sphere that moves on regardless):
///
/// ```text
/// (v_i + Δv_i)·N_i = (V + ΔV)·N_i + u_i        particle i on the sphere, u_i ≤ 0
/// M ΔV = M g dt - Σ_i J_i N_i                  the sphere's row: weight and reactions
/// ```
/// where `V` (m/s) and `M` (kg) are the sphere's velocity at the step's start and its mass, `g`
/// gravity (m/s²), `u_i` (m/s) the relative normal velocity that lands the particle on the
/// sphere (never apart faster: `u_i ≤ 0`) and `J_i` (N·s) the contact impulse. In the unknowns
/// `q` (the particles' `Δv` with the constrained normal parts removed, and the spheres' `ΔV`)
/// the velocities are `Δv = T q + z` and the system is `Tᵀ A T q = Tᵀ (b - A z)` with the
/// sphere's diagonal block `M I` added to `A` (reduced coordinates of a linear constraint:
/// Witkin, "Constrained Dynamics", SIGGRAPH 2001 course notes; Baraff & Witkin 1998 §5.3
/// for the particle's own constraint). It is symmetric positive definite, so the same
/// conjugate gradients solve it. The pair then moves as one along `N` (an inelastic contact
/// solved with the step): the impulses' work on particles and sphere together is
/// `Σ_i J_i u_i - |Σ_i J_i N_i|² / (2M) ≤ 0`. With the reaction added after the solve instead
/// (the sphere's `V` held during it), the pair gained up to `J² / (2M)` per contact.
///
/// The CG products below: `expand` writes `T q` (the particles' normal parts from `ΔV`),
/// `gather` the sphere rows of `Tᵀ A T q`, `descend` and `redirect` the sphere rows of the
/// update; the preconditioner of a sphere row is `(M I + Σ_i a_i N_i N_iᵀ)⁻¹` with
/// `a_i = 1 / (N_iᵀ D_i⁻¹ N_i)` (`D_i` the particle's diagonal block).
#[derive(Clone, Debug, Default)]
pub(crate) struct SphereRows {
    /// Per sphere: its mass (kg) while it is in the solve (dynamic and touched), else zero.
    mass: Vec<f64>,
    /// `M g dt` (N·s) per sphere in the solve.
    rhs: Vec<DVec3>,
    /// The inverse preconditioner blocks (1/kg).
    pre: Vec<glam::DMat3>,
    /// `ΔV` (m/s): the current estimate of each sphere's velocity change over the step
    /// (`g dt` for a dynamic sphere not in the solve, zero for a kinematic one).
    pub(crate) dv: Vec<DVec3>,
    r: Vec<DVec3>,
    p: Vec<DVec3>,
    ap: Vec<DVec3>,
    /// The last step's `ΔV` (m/s) and its `dt` (s), for the warm start.
    last: Vec<DVec3>,
    last_dt: f64,
}

impl SphereRows {
    /// At a step's start: every dynamic sphere's `ΔV` is `g dt` (its free fall, `gravity` in
    /// m/s², `dt` in s), or with `warm` the last step's `ΔV` scaled by the ratio of the steps (a
    /// sphere resting on the cloth changes its velocity by about nothing, not by `g dt`); a
    /// kinematic one's zero; none is in the solve yet. `dynamic` gives each sphere's mass (kg)
    /// when it is dynamic.
    pub(crate) fn begin_step(
        &mut self,
        dynamic: impl ExactSizeIterator<Item = Option<f64>>,
        gravity: DVec3,
        dt: f64,
        warm: bool,
    ) {
        let n = dynamic.len();
        for v in [
            &mut self.rhs,
            &mut self.dv,
            &mut self.r,
            &mut self.p,
            &mut self.ap,
        ] {
            v.clear();
            v.resize(n, DVec3::ZERO);
        }
        self.pre.clear();
        self.pre.resize(n, glam::DMat3::ZERO);
        self.mass.clear();
        self.mass.resize(n, 0.0);
        let warm = warm && self.last.len() == n && self.last_dt > 0.0;
        for (k, m) in dynamic.enumerate() {
            if m.is_some() {
                self.dv[k] = if warm {
                    self.last[k] * (dt / self.last_dt)
                } else {
                    dt * gravity
                };
            }
            // The weight's impulse, kept for the rows (the mass stays zero until a constraint
            // touches the sphere).
            self.rhs[k] = m.unwrap_or(0.0) * dt * gravity;
        }
    }

    /// At a step's end: keeps its `ΔV` for the next step's warm start (`dt` in s).
    pub(crate) fn remember(&mut self, dt: f64) {
        self.last.clone_from(&self.dv);
        self.last_dt = dt;
    }

    /// Before a solve with `constraints`: the dynamic spheres that a constraint touches enter
    /// the solve (their mass from `dynamic`, as in [`SphereRows::begin_step`]); one that left it
    /// falls freely again (`ΔV = g dt`, from its row's `M g dt / M`). `diag_inv(i)` is the
    /// inverse diagonal block of particle `i` (1/kg), for the preconditioner.
    pub(crate) fn prepare(
        &mut self,
        dynamic: impl Iterator<Item = Option<f64>>,
        constraints: &[Constraint],
        diag_inv: impl Fn(usize) -> glam::DMat3,
    ) {
        for (k, m) in dynamic.enumerate().take(self.mass.len()) {
            let touched = m.is_some() && constraints.iter().any(|c| c.sphere == Some(k));
            let mass = if touched { m.unwrap_or(0.0) } else { 0.0 };
            if mass == 0.0 && self.mass[k] != 0.0 {
                self.dv[k] = self.rhs[k] / self.mass[k];
            }
            self.mass[k] = mass;
            self.pre[k] = glam::DMat3::from_diagonal(DVec3::splat(mass));
        }
        for c in constraints {
            if let Some(k) = self.linked(c) {
                let a = 1.0 / c.normal.dot(diag_inv(c.i) * c.normal);
                if a.is_finite() {
                    self.pre[k] += a * outer(c.normal);
                }
            }
        }
        for (pre, &m) in self.pre.iter_mut().zip(&self.mass) {
            if m > 0.0 {
                *pre = pre.inverse();
            }
        }
    }

    /// The sphere in the solve that `c` ties its particle to.
    fn linked(&self, c: &Constraint) -> Option<usize> {
        c.sphere
            .filter(|&k| self.mass.get(k).is_some_and(|&m| m > 0.0))
    }

    /// True when some sphere is in the solve.
    pub(crate) fn any(&self) -> bool {
        self.mass.iter().any(|&m| m > 0.0)
    }

    /// The prescribed normal velocity change of `c`'s particle (m/s): `dv_n`, plus `ΔV·N` when
    /// it is tied to a sphere in the solve.
    pub(crate) fn target(&self, c: &Constraint) -> f64 {
        c.dv_n + self.linked(c).map_or(0.0, |k| self.dv[k].dot(c.normal))
    }

    /// The sphere rows of the first residual, from the particles' unfiltered residual
    /// `r = b - A Δv` (`r(i)`, N·s): `r_s = M g dt - M ΔV + Σ_i N_i (N_i·r_i)`. Returns
    /// `(Σ |b_s|², Σ |r_s|²)` over the spheres in the solve (N²·s²).
    pub(crate) fn first_residual(
        &mut self,
        constraints: &[Constraint],
        r: impl Fn(usize) -> DVec3,
    ) -> (f64, f64) {
        for k in 0..self.mass.len() {
            self.r[k] = self.rhs[k] - self.mass[k] * self.dv[k];
        }
        for c in constraints {
            if let Some(k) = self.linked(c) {
                self.r[k] += c.normal.dot(r(c.i)) * c.normal;
            }
        }
        let mut sums = (0.0, 0.0);
        for k in 0..self.mass.len() {
            if self.mass[k] > 0.0 {
                sums.0 += self.rhs[k].length_squared();
                sums.1 += self.r[k].length_squared();
            } else {
                self.r[k] = DVec3::ZERO;
            }
        }
        sums
    }

    /// `Σ |r_s|²` over the spheres in the solve (N²·s²).
    pub(crate) fn first_residual_norm2(&self) -> f64 {
        self.r.iter().map(|r| r.length_squared()).sum()
    }

    /// The first search direction's sphere rows `p_s = P⁻¹ r_s`; returns `r_s·p_s`.
    pub(crate) fn first_direction(&mut self) -> f64 {
        let mut rz = 0.0;
        for k in 0..self.mass.len() {
            self.p[k] = self.pre[k] * self.r[k];
            rz += self.r[k].dot(self.p[k]);
        }
        rz
    }

    /// `T q`: adds to each tied particle's row of `p` (whose normal part is zero) the normal
    /// part of its sphere's direction, `N (N·p_s)`.
    pub(crate) fn expand<R: Rows + ?Sized>(&self, constraints: &[Constraint], p: &mut R) {
        for c in constraints {
            if let Some(k) = self.linked(c) {
                p.add_row(c.i, self.p[k].dot(c.normal) * c.normal);
            }
        }
    }

    /// The sphere rows of `Tᵀ A T p` from the particles' `A T p` (`ap(i)`, before the filter):
    /// `M p_s + Σ_i N_i (N_i·(A T p)_i)`. Returns `Σ M |p_s|²`, the spheres' part of `pᵀ A p`.
    pub(crate) fn gather(
        &mut self,
        constraints: &[Constraint],
        ap: impl Fn(usize) -> DVec3,
    ) -> f64 {
        let mut p_ap = 0.0;
        for k in 0..self.mass.len() {
            self.ap[k] = self.mass[k] * self.p[k];
            p_ap += self.mass[k] * self.p[k].length_squared();
        }
        for c in constraints {
            if let Some(k) = self.linked(c) {
                self.ap[k] += c.normal.dot(ap(c.i)) * c.normal;
            }
        }
        p_ap
    }

    /// The sphere rows of a CG step `α`: `ΔV += α p_s`, `r_s -= α (A p)_s`, and the tied
    /// particles' `Δv` gets the normal part `α N (N·p_s)` (their rows of `p` have none).
    /// Writes `z_s = P⁻¹ r_s` into the direction's scratch and returns `(|r_s|², r_s·z_s)`.
    pub(crate) fn descend<R: Rows + ?Sized>(
        &mut self,
        alpha: f64,
        constraints: &[Constraint],
        dv: &mut R,
    ) -> (f64, f64) {
        for c in constraints {
            if let Some(k) = self.linked(c) {
                dv.add_row(c.i, alpha * self.p[k].dot(c.normal) * c.normal);
            }
        }
        let (mut rr, mut rz) = (0.0, 0.0);
        for k in 0..self.mass.len() {
            if self.mass[k] == 0.0 {
                continue;
            }
            self.dv[k] += alpha * self.p[k];
            self.r[k] -= alpha * self.ap[k];
            // `ap` is free now: it holds z_s until `redirect`.
            self.ap[k] = self.pre[k] * self.r[k];
            rr += self.r[k].length_squared();
            rz += self.r[k].dot(self.ap[k]);
        }
        (rr, rz)
    }

    /// The new direction's sphere rows, `p_s = z_s + β p_s`.
    pub(crate) fn redirect(&mut self, beta: f64) {
        for k in 0..self.mass.len() {
            if self.mass[k] > 0.0 {
                self.p[k] = self.ap[k] + beta * self.p[k];
            }
        }
    }
}

/// The outer product `n nᵀ`.
fn outer(n: DVec3) -> glam::DMat3 {
    glam::DMat3::from_cols(n * n.x, n * n.y, n * n.z)
}
