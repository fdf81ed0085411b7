//! Springs: Hooke's law plus a damper along the spring.
//!
//! # Theory
//!
//! A spring joins particles `a` and `b`. It pulls them together when it is longer than its rest
//! length and pushes them apart when it is shorter (Hooke 1678). A damper in parallel resists only
//! the part of the relative velocity that stretches or compresses the spring, so it does not slow
//! down a rigid rotation of the pair (NYCU Computer Animation HW1, 2021–2023; Baraff & Witkin,
//! "Large Steps in Cloth Simulation", SIGGRAPH 1998, §3.2).
//!
//! ```text
//! d    = x_b - x_a                    vector from a to b
//! L    = |d|                          current length
//! n    = d / L                        unit direction from a to b
//! f_s  = k (L - L0)                   Hooke: tension > 0 when stretched
//! f_d  = k_d ((v_b - v_a) · n)        damper: only the component along n
//! f_a  = (f_s + f_d) n                force on a (towards b when stretched)
//! f_b  = -f_a                         Newton's third law
//! ```
//! where
//! - `x_a`, `x_b`: positions (m), `v_a`, `v_b`: velocities (m/s)
//! - `k`: stiffness (N/m), `k_d`: damping coefficient (N·s/m), `L0`: rest length (m)
//!
//! A spring of zero length has no direction; it exerts no force (rather than NaN).
//! The elastic energy stored is `E = ½ k (L - L0)²` (J).

use glam::DVec3;
use serde::Serialize;

/// What a spring does in a lattice (course terminology, NYCU HW1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpringKind {
    /// Between direct neighbours: resists stretching.
    Struct,
    /// Between diagonal neighbours: resists shearing.
    Shear,
    /// Between neighbours two apart: resists bending.
    Bend,
}

impl SpringKind {
    /// All kinds, in the order lattices generate them.
    pub const ALL: [SpringKind; 3] = [SpringKind::Struct, SpringKind::Shear, SpringKind::Bend];

    /// The lower-case name used in scene files and output.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SpringKind::Struct => "struct",
            SpringKind::Shear => "shear",
            SpringKind::Bend => "bend",
        }
    }

    /// Parses a lower-case name (`struct`, `shear`, `bend`).
    #[must_use]
    pub fn from_name(name: &str) -> Option<SpringKind> {
        SpringKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// One spring between particles `a` and `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// Index of the first particle.
    pub a: u32,
    /// Index of the second particle.
    pub b: u32,
    /// Length at which the spring exerts no force (m).
    pub rest_length: f64,
    /// Hooke stiffness `k` (N/m).
    pub stiffness: f64,
    /// Damper coefficient `k_d` along the spring (N·s/m).
    pub damping: f64,
    /// Role in a lattice.
    pub kind: SpringKind,
}

impl Spring {
    /// Force this spring exerts on particle `a`; particle `b` receives the negative.
    ///
    /// See the module documentation for the formula. Returns zero for a spring of zero length.
    ///
    /// # Panics
    /// If `a` or `b` is out of range of `x` or `v`.
    #[must_use]
    // Always: the spring-list loop of `forces::applied_forces` is this call and little else,
    // and the compiler's own choice changes with how the crate's code is split for compiling.
    #[inline(always)]
    pub fn force_on_a(&self, x: &[DVec3], v: &[DVec3]) -> DVec3 {
        let (a, b) = (self.a as usize, self.b as usize);
        let d = x[b] - x[a];
        let length = d.length();
        if length == 0.0 {
            // No direction: the force is undefined; a resting zero-length spring exerts none.
            return DVec3::ZERO;
        }
        // n = d / L, with one reciprocal instead of three divisions.
        let n = d * length.recip();
        // Hooke's law: tension k (L - L0), positive when stretched.
        let tension = self.stiffness * (length - self.rest_length);
        // Damper: only the relative velocity along the spring, (v_b - v_a) · n.
        let damper = self.damping * (v[b] - v[a]).dot(n);
        (tension + damper) * n
    }

    /// Elastic energy `½ k (L - L0)²` (J) stored at positions `x`.
    #[must_use]
    pub fn energy(&self, x: &[DVec3]) -> f64 {
        self.energy_between(x[self.a as usize], x[self.b as usize])
    }

    /// Elastic energy `½ k (L - L0)²` (J) with its ends at `x_a` and `x_b` (m).
    #[must_use]
    pub fn energy_between(&self, x_a: DVec3, x_b: DVec3) -> f64 {
        let stretch = (x_b - x_a).length() - self.rest_length;
        0.5 * self.stiffness * stretch * stretch
    }

    /// Current length `|x_b - x_a|` (m).
    #[must_use]
    pub fn length(&self, x: &[DVec3]) -> f64 {
        (x[self.b as usize] - x[self.a as usize]).length()
    }
}
