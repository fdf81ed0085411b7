//! The peer-benchmark workloads: six fixed mass-spring runs shared with the C++/Eigen, Taichi,
//! Warp and NumPy peers (`docs/workloads.md`), stepped with the library's own integrators.
//!
//! | workload | particles | springs | method | dt (s) | steps N |
//! |---|---|---|---|---|---|
//! | `jelly-se`    | 1 000  | 12 876 | semi-implicit Euler | 1e-4   | 10 000 |
//! | `jelly-rk4`   | 1 000  | 12 876 | RK4                 | 1e-4   | 10 000 |
//! | `cloth64-se`  | 4 096  | 23 938 | semi-implicit Euler | 5e-5   | 4 000 |
//! | `cloth128-se` | 16 384 | 97 026 | semi-implicit Euler | 2.5e-5 | 5 000 |
//! | `rope-se`     | 64     | 63     | semi-implicit Euler | 1e-4   | 10 000 |
//! | `rope-verlet` | 64     | 63 constraints | position Verlet, 20 projection passes | 1e-3 | 10 000 |
//!
//! # Theory
//!
//! Every spring workload uses the force model of [`crate::physics::springs`] with the same
//! stiffness `k` (N/m) and damping `k_d` (N·s/m) for every spring, gravity
//! `g = (0, -9.8, 0)` m/s² and no drag. After each step a *benchmark contact rule* (not one of the
//! course colliders) projects the particles:
//!
//! ```text
//! ground (jelly):  if y < 0 { y = 0; if v_y < 0 { v_y = -e v_y } }
//! sphere (cloth):  dd = x - c; if |dd| < R { n = dd/|dd|; x = c + R n;
//!                                           v_n = v·n; if v_n < 0 { v -= v_n n } }
//! ```
//! where `e = 0.8` is the restitution, `c = (0.5, 0.6, 0.5)` m the sphere's centre and
//! `R = 0.35` m its radius. RK4 applies the contact once, after the full step.
//!
//! `rope-verlet` has no spring forces: its 63 springs have `k = k_d = 0` and serve only as
//! distance constraints, projected 20 times per step in red-black Gauss–Seidel order (the
//! library's greedy colouring of a chain). It starts with `x_prev = x` (the rope at rest), not
//! with the library's Taylor start-up.
//!
//! After N steps each peer prints a checksum: the centroid (plain mean of the positions, m) and
//! the total energy (J)
//!
//! ```text
//! E = Σ_i ½ m |v_i|² + Σ_i m 9.8 y_i + Σ_springs ½ k (L - L0)²
//! ```
//! (no spring term for `rope-verlet`, whose velocity is `v = (x - x_prev) / dt`).
//!
//! The set-up is reproduced bit for bit: [`setup_bytes`] serialises it in the canonical layout
//! whose SHA-256 `docs/workloads.md` lists.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use crate::physics::integrators::Projection;
use crate::physics::{Method, MethodParams, Model, SpringKind, State, Workspace};
use crate::scene::builder::Builder;

mod measure;
pub use measure::{BenchResult, measure, measure_method, methods_for};

/// Gravitational acceleration of every workload (m/s²).
pub const GRAVITY: DVec3 = DVec3::new(0.0, -9.8, 0.0);

/// Relative tolerance on every checksum value for an f64 implementation (`docs/workloads.md`).
pub const REL_TOL: f64 = 1e-8;

/// Absolute floor of the checksum comparison (m or J), for reference values that are exactly
/// zero (the rope's `cz`).
pub const ABS_FLOOR: f64 = 1e-12;

/// One of the six peer-benchmark workloads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Workload {
    /// 10×10×10 jelly cube dropped on the ground, semi-implicit Euler.
    JellySe,
    /// The same cube, classic RK4.
    JellyRk4,
    /// 64×64 cloth falling on a sphere, semi-implicit Euler.
    Cloth64Se,
    /// 128×128 cloth falling on a sphere, semi-implicit Euler.
    Cloth128Se,
    /// 64-node rope pinned at one end, stiff springs, semi-implicit Euler.
    RopeSe,
    /// 64-node rope of distance constraints, position Verlet with projection.
    RopeVerlet,
}

impl Workload {
    /// All workloads, in the order of `docs/workloads.md`.
    pub const ALL: [Workload; 6] = [
        Workload::JellySe,
        Workload::JellyRk4,
        Workload::Cloth64Se,
        Workload::Cloth128Se,
        Workload::RopeSe,
        Workload::RopeVerlet,
    ];

    /// The name on the command line and in the peers' output, for example `jelly-se`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Workload::JellySe => "jelly-se",
            Workload::JellyRk4 => "jelly-rk4",
            Workload::Cloth64Se => "cloth64-se",
            Workload::Cloth128Se => "cloth128-se",
            Workload::RopeSe => "rope-se",
            Workload::RopeVerlet => "rope-verlet",
        }
    }

    /// The integration method.
    #[must_use]
    pub fn method(self) -> Method {
        match self {
            Workload::JellyRk4 => Method::Rk4,
            Workload::RopeVerlet => Method::Verlet,
            _ => Method::SemiImplicitEuler,
        }
    }

    /// The time step (s).
    #[must_use]
    pub fn dt(self) -> f64 {
        match self {
            Workload::JellySe | Workload::JellyRk4 | Workload::RopeSe => 1e-4,
            Workload::Cloth64Se => 5e-5,
            Workload::Cloth128Se => 2.5e-5,
            Workload::RopeVerlet => 1e-3,
        }
    }

    /// The number of steps N after which the checksum is defined.
    #[must_use]
    pub fn steps(self) -> u64 {
        match self {
            Workload::Cloth64Se => 4_000,
            Workload::Cloth128Se => 5_000,
            _ => 10_000,
        }
    }

    /// The method settings: Verlet damping 0.00005 and 20 projection passes (used by
    /// `rope-verlet` only).
    #[must_use]
    pub fn params(self) -> MethodParams {
        MethodParams {
            verlet_damping: 0.00005,
            iterations: 20,
            ..MethodParams::default()
        }
    }

    /// The reference checksum after [`Workload::steps`] steps (C++ f64 reference, `docs/workloads.md`).
    #[must_use]
    pub fn reference(self) -> Checksum {
        match self {
            Workload::JellySe => REFERENCE_JELLY_SE,
            Workload::JellyRk4 => REFERENCE_JELLY_RK4,
            Workload::Cloth64Se => REFERENCE_CLOTH64_SE,
            Workload::Cloth128Se => REFERENCE_CLOTH128_SE,
            Workload::RopeSe => REFERENCE_ROPE_SE,
            Workload::RopeVerlet => REFERENCE_ROPE_VERLET,
        }
    }

    /// The contact rule applied after each step.
    fn contact(self) -> Contact {
        match self {
            Workload::JellySe | Workload::JellyRk4 => Contact::Ground { restitution: 0.8 },
            Workload::Cloth64Se | Workload::Cloth128Se => Contact::Sphere {
                centre: DVec3::new(0.5, 0.6, 0.5),
                radius: 0.35,
            },
            Workload::RopeSe | Workload::RopeVerlet => Contact::None,
        }
    }
}

impl fmt::Display for Workload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for Workload {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// A workload name that is not one of [`Workload::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown workload `{0}`; expected one of: {names}", names = workload_names())]
pub struct UnknownWorkload(pub String);

/// The names of all workloads, comma separated.
#[must_use]
pub fn workload_names() -> String {
    Workload::ALL.map(Workload::name).join(", ")
}

impl FromStr for Workload {
    type Err = UnknownWorkload;

    fn from_str(s: &str) -> Result<Workload, UnknownWorkload> {
        Workload::ALL
            .into_iter()
            .find(|w| w.name() == s)
            .ok_or_else(|| UnknownWorkload(s.to_string()))
    }
}

/// The result every peer prints after N steps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Checksum {
    /// Mean position `(cx, cy, cz)` (m).
    pub centroid: [f64; 3],
    /// Total energy `E` (J), see the module documentation.
    pub energy: f64,
}

impl Checksum {
    /// True when every value is within `rel_tol` of `reference`, relative to the reference
    /// value, with an absolute floor of [`ABS_FLOOR`]:
    /// `|a - b| <= max(rel_tol |b|, ABS_FLOOR)` for `cx`, `cy`, `cz` and `E`.
    ///
    /// A NaN value never agrees.
    #[must_use]
    pub fn agrees(&self, reference: &Checksum, rel_tol: f64) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= (rel_tol * b.abs()).max(ABS_FLOOR);
        self.centroid
            .iter()
            .zip(&reference.centroid)
            .all(|(&a, &b)| close(a, b))
            && close(self.energy, reference.energy)
    }

    /// The largest relative deviation from `reference` over the four values (each relative to
    /// `max(|reference value|, ABS_FLOOR)`).
    #[must_use]
    pub fn max_relative_deviation(&self, reference: &Checksum) -> f64 {
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(ABS_FLOOR);
        self.centroid
            .iter()
            .zip(&reference.centroid)
            .map(|(&a, &b)| rel(a, b))
            .fold(rel(self.energy, reference.energy), f64::max)
    }
}

/// `jelly-se` after 10 000 steps.
pub const REFERENCE_JELLY_SE: Checksum = Checksum {
    centroid: [0.45, 0.623460865208, 0.45],
    energy: 6477.4512462,
};
/// `jelly-rk4` after 10 000 steps.
pub const REFERENCE_JELLY_RK4: Checksum = Checksum {
    centroid: [0.45, 0.624484756424, 0.45],
    energy: 6484.05709526,
};
/// `cloth64-se` after 4 000 steps.
pub const REFERENCE_CLOTH64_SE: Checksum = Checksum {
    centroid: [0.5, 0.885055977476, 0.443992378974],
    energy: 9.72445584777,
};
/// `cloth128-se` after 5 000 steps.
pub const REFERENCE_CLOTH128_SE: Checksum = Checksum {
    centroid: [0.5, 0.92952267214, 0.487972098877],
    energy: 9.79459382544,
};
/// `rope-se` after 10 000 steps.
pub const REFERENCE_ROPE_SE: Checksum = Checksum {
    centroid: [-0.454248073641, 0.971656712835, 0.0],
    energy: 9.78089681978,
};
/// `rope-verlet` after 10 000 steps.
pub const REFERENCE_ROPE_VERLET: Checksum = Checksum {
    centroid: [-0.327208156111, 0.62841742562, 0.0],
    energy: 6.60831200289,
};

// ---------------------------------------------------------------------------------------------
// Set-up
// ---------------------------------------------------------------------------------------------

/// A lattice offset `(dx, dy, dz)` in lattice units.
type Offset3 = (i64, i64, i64);

/// Lattice offsets of the jelly cube's springs, by kind, in canonical order.
const JELLY_OFFSETS: [(SpringKind, &[Offset3]); 3] = [
    (SpringKind::Struct, &[(1, 0, 0), (0, 1, 0), (0, 0, 1)]),
    (
        SpringKind::Shear,
        &[
            (1, 1, 0),
            (1, -1, 0),
            (1, 0, 1),
            (1, 0, -1),
            (0, 1, 1),
            (0, 1, -1),
            (1, 1, 1),
            (1, 1, -1),
            (1, -1, 1),
            (1, -1, -1),
        ],
    ),
    (SpringKind::Bend, &[(2, 0, 0), (0, 2, 0), (0, 0, 2)]),
];

/// Lattice offsets `(dr, dc)` (row, column) of the cloth's springs, by kind, in canonical order.
const CLOTH_OFFSETS: [(SpringKind, &[(i64, i64)]); 3] = [
    (SpringKind::Struct, &[(0, 1), (1, 0)]),
    (SpringKind::Shear, &[(1, 1), (1, -1)]),
    (SpringKind::Bend, &[(0, 2), (2, 0)]),
];

/// The 10×10×10 jelly cube: particle `p = ix + 10 iy + 100 iz` at `(ix h, 1 + iy h, iz h)`,
/// `h = 0.1` m, 1 kg each, `k = 2000` N/m, `k_d = 10` N·s/m, nothing pinned.
fn jelly(b: &mut Builder) {
    const SIDE: i64 = 10;
    let h = 0.1;
    let (stiffness, damping, mass) = (2000.0, 10.0, 1.0);
    for iz in 0..SIDE {
        for iy in 0..SIDE {
            for ix in 0..SIDE {
                let x = DVec3::new(ix as f64 * h, 1.0 + iy as f64 * h, iz as f64 * h);
                b.particle(x, mass);
            }
        }
    }
    let inside = |i: i64| (0..SIDE).contains(&i);
    for (kind, offsets) in JELLY_OFFSETS {
        for p in 0..SIDE * SIDE * SIDE {
            let (ix, iy, iz) = (p % SIDE, (p / SIDE) % SIDE, p / (SIDE * SIDE));
            for &(dx, dy, dz) in offsets {
                let (qx, qy, qz) = (ix + dx, iy + dy, iz + dz);
                if inside(qx) && inside(qy) && inside(qz) {
                    let q = qx + SIDE * qy + SIDE * SIDE * qz;
                    // Rest length = initial distance sqrt(d.x² + d.y² + d.z²), as glam computes it.
                    b.spring(p as u32, q as u32, stiffness, damping, kind);
                }
            }
        }
    }
}

/// The `n`×`n` cloth: particle `p = r n + c` at `(c h, 1, r h)`, `h = 1/(n-1)` m,
/// `1/n²` kg each, `k = 5000` N/m, `k_d = 0.02` N·s/m, particles `0` and `n - 1` pinned.
fn cloth(b: &mut Builder, n: i64) {
    let h = 1.0 / (n - 1) as f64;
    let mass = 1.0 / (n * n) as f64;
    let (stiffness, damping) = (5000.0, 0.02);
    for r in 0..n {
        for c in 0..n {
            b.particle(DVec3::new(c as f64 * h, 1.0, r as f64 * h), mass);
        }
    }
    b.pinned[0] = true;
    b.pinned[(n - 1) as usize] = true;
    let inside = |i: i64| (0..n).contains(&i);
    for (kind, offsets) in CLOTH_OFFSETS {
        for p in 0..n * n {
            let (r, c) = (p / n, p % n);
            for &(dr, dc) in offsets {
                let (qr, qc) = (r + dr, c + dc);
                if inside(qr) && inside(qc) {
                    b.spring(p as u32, (qr * n + qc) as u32, stiffness, damping, kind);
                }
            }
        }
    }
}

/// The 64-node rope: node `i` at `(i h, 1, 0)`, `h = 1/63` m, `1/64` kg each, node 0 pinned,
/// springs `(i, i + 1)` of stiffness `k` (N/m) and damping `k_d` (N·s/m).
fn rope(b: &mut Builder, stiffness: f64, damping: f64) {
    const NODES: u32 = 64;
    let h = 1.0 / f64::from(NODES - 1);
    let mass = 1.0 / f64::from(NODES);
    for i in 0..NODES {
        b.particle(DVec3::new(f64::from(i) * h, 1.0, 0.0), mass);
    }
    b.pinned[0] = true;
    for i in 0..NODES - 1 {
        b.spring(i, i + 1, stiffness, damping, SpringKind::Struct);
    }
}

/// The model and initial state of `workload`, bit for bit as `docs/workloads.md` defines them.
///
/// For `rope-verlet` the springs have zero stiffness and damping (pure distance constraints)
/// and the state's history is valid with `x_prev = x`, so Verlet starts from rest.
#[must_use]
pub fn setup(workload: Workload) -> (Model, State) {
    let mut b = Builder::new();
    match workload {
        Workload::JellySe | Workload::JellyRk4 => jelly(&mut b),
        Workload::Cloth64Se => cloth(&mut b, 64),
        Workload::Cloth128Se => cloth(&mut b, 128),
        Workload::RopeSe => rope(&mut b, 50_000.0, 1.0),
        Workload::RopeVerlet => rope(&mut b, 0.0, 0.0),
    }
    let (model, mut state) = b.build(GRAVITY, 0.0);
    if workload == Workload::RopeVerlet {
        // x_prev = x: the rope starts at rest (docs/workloads.md), not with the Taylor start-up.
        state.x_prev.clone_from(&state.x);
        state.history_valid = true;
    }
    (model, state)
}

/// The canonical set-up bytes of `workload`: all initial positions as little-endian f64
/// `(x, y, z)` per particle, then per spring `u32 i, u32 j, f64 rest_length` (little-endian),
/// in canonical order. Their SHA-256 is listed in `docs/workloads.md`.
#[must_use]
pub fn setup_bytes(workload: Workload) -> Vec<u8> {
    let (model, state) = setup(workload);
    let mut bytes = Vec::with_capacity(state.len() * 24 + model.springs().len() * 16);
    for p in &state.x {
        for c in p.to_array() {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for s in model.springs() {
        bytes.extend_from_slice(&s.a.to_le_bytes());
        bytes.extend_from_slice(&s.b.to_le_bytes());
        bytes.extend_from_slice(&s.rest_length.to_le_bytes());
    }
    bytes
}

// ---------------------------------------------------------------------------------------------
// Contact rules (benchmark definitions, not the course colliders)
// ---------------------------------------------------------------------------------------------

/// The contact projection a workload applies after each step.
#[derive(Clone, Copy, Debug)]
enum Contact {
    None,
    /// The plane `y = 0`, restitution `e` (dimensionless), no friction.
    Ground {
        restitution: f64,
    },
    /// A fixed sphere (m), inelastic and frictionless.
    Sphere {
        centre: DVec3,
        radius: f64,
    },
}

impl Contact {
    /// The rule as the integrator's end-of-step [`Projection`]: a method with a fused last
    /// pass applies it to each tile of particles inside that pass (on the pass's threads, while
    /// the tile is in cache), any other method to all particles after its step. Every particle
    /// is projected on its own, so the result does not depend on where or in which order.
    fn projection(self) -> Option<Projection> {
        match self {
            Contact::None => None,
            Contact::Ground { restitution } => Some(Projection(Arc::new(move |x, v| {
                ground(x, v, restitution);
            }))),
            Contact::Sphere { centre, radius } => Some(Projection(Arc::new(move |x, v| {
                sphere(x, v, centre, radius);
            }))),
        }
    }
}

/// `if y < 0 { y = 0; if v_y < 0 { v_y = -e v_y } }` for every particle (positions `x`,
/// velocities `v`).
fn ground(x: &mut [DVec3], v: &mut [DVec3], restitution: f64) {
    for (x, v) in x.iter_mut().zip(v.iter_mut()) {
        if x.y < 0.0 {
            x.y = 0.0;
            if v.y < 0.0 {
                // Bounce: v_y = -e v_y, the normal velocity reversed and scaled by e.
                v.y *= -restitution;
            }
        }
    }
}

/// Pushes every particle inside the sphere out to its surface and removes the inward normal
/// velocity (positions `x`, velocities `v`).
fn sphere(x: &mut [DVec3], v: &mut [DVec3], centre: DVec3, radius: f64) {
    // A particle with |dd|² at least (1 + 1e-9) R² has fl(√|dd|²) ≥ R, so it fails the exact
    // test below: skip its square root (the rule's decisions and results are unchanged).
    let far = radius * radius * (1.0 + 1e-9);
    for (x, v) in x.iter_mut().zip(v.iter_mut()) {
        // First the height alone: |dd|² is a sum of non-negative squares, and a rounded sum
        // is never below one of its rounded terms, so dd_y² ≥ far already means |dd|² ≥ far
        // (one subtraction and one product instead of three of each; a cloth above the
        // sphere stops here).
        let dy = x.y - centre.y;
        if dy * dy >= far {
            continue;
        }
        let dd = *x - centre;
        let squared = dd.length_squared();
        if squared >= far || squared.is_nan() {
            continue;
        }
        let dist = squared.sqrt();
        if dist < radius {
            // Outward normal n = dd / |dd| (divided, as the peers do).
            let nn = dd / dist;
            *x = centre + radius * nn;
            let vn = v.dot(nn);
            if vn < 0.0 {
                *v -= vn * nn;
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Running
// ---------------------------------------------------------------------------------------------

/// A workload in motion: its model, state, method scratch space and step count.
#[derive(Clone, Debug)]
pub struct Run {
    /// Which workload.
    pub workload: Workload,
    /// Masses, springs, gravity.
    pub model: Model,
    /// Positions and velocities (and `x_prev` for Verlet).
    pub state: State,
    /// Steps taken since the set-up.
    pub steps: u64,
    /// Force evaluations taken since the set-up (4 per step for RK4).
    pub force_evals: u64,
    method: Method,
    dt: f64,
    params: MethodParams,
    work: Workspace,
}

impl Run {
    /// `workload` at its initial state ([`setup`]).
    #[must_use]
    pub fn new(workload: Workload) -> Run {
        let (model, state) = setup(workload);
        Run::from_setup(workload, model, state)
    }

    /// `workload` starting from a given model and state (for example clones of one [`setup`]).
    #[must_use]
    pub fn from_setup(workload: Workload, model: Model, state: State) -> Run {
        Run {
            workload,
            model,
            state,
            steps: 0,
            force_evals: 0,
            method: workload.method(),
            dt: workload.dt(),
            params: workload.params(),
            work: Workspace {
                projection: workload.contact().projection(),
                ..Workspace::new()
            },
        }
    }

    /// `workload` at its initial state, stepped with `method` instead of its own, as
    /// [`measure_method`] times it: Verlet without projection or damping (`iterations = 0`,
    /// `verlet_damping = 0`) so that every method integrates the same spring forces; XPBD with
    /// the library's default substeps.
    #[must_use]
    pub fn with_method(workload: Workload, method: Method) -> Run {
        let mut run = Run::new(workload);
        if method != workload.method() {
            run.method = method;
            run.params = MethodParams {
                iterations: 0,
                verlet_damping: 0.0,
                ..MethodParams::default()
            };
        }
        run
    }

    /// The method this run steps with.
    #[must_use]
    pub fn method(&self) -> Method {
        self.method
    }

    /// One step of the library's integrator, which ends with the workload's contact projection
    /// (its [`Workspace::projection`]).
    #[inline]
    pub fn step(&mut self) {
        self.force_evals += self.method.step(
            &self.model,
            &mut self.state,
            self.dt,
            &self.params,
            &mut self.work,
        );
        self.steps += 1;
    }

    /// `n` steps.
    pub fn advance(&mut self, n: u64) {
        // [`Method::steps`]: `n` times [`Run::step`], the same numbers; a method may take them
        // in one call where no contact projection runs between the steps (semi-implicit Euler
        // on the rope).
        self.force_evals += self.method.steps(
            &self.model,
            &mut self.state,
            self.dt,
            &self.params,
            &mut self.work,
            n,
        );
        self.steps += n;
    }

    /// The centroid and energy of the current state (see the module documentation).
    #[must_use]
    pub fn checksum(&self) -> Checksum {
        checksum(self.workload, &self.model, &self.state)
    }
}

/// The checksum of `state`: centroid (plain mean of positions, m) and total energy (J).
///
/// For `rope-verlet` the velocity is `(x - x_prev) / dt` and the spring term is omitted.
#[must_use]
pub fn checksum(workload: Workload, model: &Model, state: &State) -> Checksum {
    let n = state.len() as f64;
    let mut sum = DVec3::ZERO;
    for &x in &state.x {
        sum += x;
    }
    let centroid = sum / n;
    let verlet = workload == Workload::RopeVerlet;
    let dt = workload.dt();
    let (mut kinetic, mut gravity, mut elastic) = (0.0, 0.0, 0.0);
    for i in 0..state.len() {
        let m = model.mass[i];
        let v = if verlet {
            (state.x[i] - state.x_prev[i]) / dt
        } else {
            state.v[i]
        };
        kinetic += 0.5 * m * v.dot(v);
        gravity += m * 9.8 * state.x[i].y;
    }
    if !verlet {
        for s in model.springs() {
            let d = state.x[s.b as usize] - state.x[s.a as usize];
            let stretch = d.length() - s.rest_length;
            elastic += 0.5 * s.stiffness * stretch * stretch;
        }
    }
    Checksum {
        centroid: centroid.to_array(),
        energy: kinetic + gravity + elastic,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sphere rule as the peers write it (docs/workloads.md): no shortcut.
    fn sphere_textbook(x: &mut [DVec3], v: &mut [DVec3], centre: DVec3, radius: f64) {
        for (x, v) in x.iter_mut().zip(v.iter_mut()) {
            let dd = *x - centre;
            let dist = dd.length();
            if dist < radius {
                let nn = dd / dist;
                *x = centre + radius * nn;
                let vn = v.dot(nn);
                if vn < 0.0 {
                    *v -= vn * nn;
                }
            }
        }
    }

    #[test]
    fn the_sphere_rule_with_its_shortcuts_is_the_peers_rule_bit_for_bit() {
        let (centre, radius) = (DVec3::new(0.5, 0.6, 0.5), 0.35);
        let mut rng = crate::random::XorShift64Star::new(0x5b4e_7e00);
        let mut noise = || rng.symmetric();
        // Random points in a box around the sphere, points on and next to its surface (in
        // every direction, so also just above and below it in y), and a NaN.
        let mut x: Vec<DVec3> = (0..4000)
            .map(|_| centre + 0.5 * DVec3::new(noise(), noise(), noise()))
            .collect();
        for k in 0..2000 {
            let n = DVec3::new(noise(), noise(), noise()).normalize_or(DVec3::Y);
            let n = if k % 4 == 0 {
                DVec3::Y * n.y.signum()
            } else {
                n
            };
            let r = radius * (1.0 + (k % 7) as f64 * 1e-10 - 3e-10);
            x.push(centre + r * n);
        }
        x.push(DVec3::new(f64::NAN, 0.6, 0.5));
        let v: Vec<DVec3> = (0..x.len())
            .map(|_| DVec3::new(noise(), noise(), noise()))
            .collect();
        let (mut x1, mut v1) = (x.clone(), v.clone());
        let (mut x2, mut v2) = (x.clone(), v.clone());
        sphere(&mut x1, &mut v1, centre, radius);
        sphere_textbook(&mut x2, &mut v2, centre, radius);
        let bits = |p: &[DVec3]| -> Vec<u64> {
            p.iter()
                .flat_map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        assert!(bits(&x1) == bits(&x2) && bits(&v1) == bits(&v2));
        let moved = x1.iter().zip(&x).filter(|(a, b)| a != b).count();
        let skipped_by_height = x
            .iter()
            .filter(|p| (p.y - centre.y) * (p.y - centre.y) >= radius * radius * (1.0 + 1e-9))
            .count();
        assert!(moved > 1000, "only {moved} particles projected");
        assert!(
            skipped_by_height > 1000,
            "only {skipped_by_height} decided by height"
        );
    }
}
