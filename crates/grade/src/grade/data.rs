//! The plain data of the homework: masses, springs, ropes, particle states, contact
//! coefficients and bodies, and the one conversion from springlab's physics to them
//! ([`Rope::from_physics`], `From<&physics::Spring>`). The traits that use them are in
//! [`super::assignments`], which re-exports them.

use glam::DVec3;

use crate::physics::SpringKind;

/// One particle of the rope (GAMES101 `Mass`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mass {
    /// Position `x(t)` (m).
    pub position: DVec3,
    /// Velocity `v(t)` (m/s); Verlet does not use it.
    pub velocity: DVec3,
    /// Position one step ago, `x(t - dt)` (m); only Verlet uses it.
    pub last_position: DVec3,
    /// Mass (kg).
    pub mass: f64,
    /// A pinned mass never moves.
    pub pinned: bool,
}

/// A spring between particles `a` and `b` (indices into the particle list).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spring {
    /// Index of the first particle.
    pub a: usize,
    /// Index of the second particle.
    pub b: usize,
    /// Length at which the spring exerts no force (m).
    pub rest_length: f64,
    /// Hooke stiffness `k_s` (N/m).
    pub stiffness: f64,
    /// Damper coefficient `k_d` along the spring (N·s/m); 0 in the rope.
    pub damping: f64,
}

/// A rope: masses joined by springs between neighbours (GAMES101 `Rope`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rope {
    /// The masses, from `start` to `end`.
    pub masses: Vec<Mass>,
    /// The springs, one between each pair of consecutive masses.
    pub springs: Vec<Spring>,
}

impl Rope {
    /// The rope of springlab's particles and springs: mass `i` at `x[i]` with velocity `v[i]`
    /// (last position `x[i]`: at rest for Verlet), `mass(i)` kg, pinned when `pinned(i)`. The one
    /// conversion from springlab's physics to the homework's types.
    pub(crate) fn from_physics(
        x: &[DVec3],
        v: &[DVec3],
        mass: impl Fn(usize) -> f64,
        pinned: impl Fn(usize) -> bool,
        springs: &[crate::physics::Spring],
    ) -> Rope {
        let masses = (0..x.len())
            .map(|i| Mass {
                position: x[i],
                velocity: v[i],
                last_position: x[i],
                mass: mass(i),
                pinned: pinned(i),
            })
            .collect();
        let springs = springs.iter().map(Spring::from).collect();
        Rope { masses, springs }
    }
}

impl From<&crate::physics::Spring> for Spring {
    fn from(s: &crate::physics::Spring) -> Spring {
        Spring {
            a: s.a as usize,
            b: s.b as usize,
            rest_length: s.rest_length,
            stiffness: s.stiffness,
            damping: s.damping,
        }
    }
}

/// Positions and velocities of a particle system (struct of arrays).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    /// Positions (m).
    pub x: Vec<DVec3>,
    /// Velocities (m/s).
    pub v: Vec<DVec3>,
}

/// One spring of a lattice set-up: the pair of particles it joins and its kind.
///
/// The grader compares set-ups as sets of (unordered pair, kind): the order of the list and of
/// `a` and `b` do not matter; a pair listed twice is a mistake.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SpringSetup {
    /// Index of one particle.
    pub a: usize,
    /// Index of the other particle.
    pub b: usize,
    /// Struct, shear or bend.
    pub kind: SpringKind,
}

/// A particle touching a static obstacle: what a collision handler reads and changes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Particle {
    /// Position (m).
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Force accumulated so far this step: gravity, springs, dampers (N).
    pub force: DVec3,
}

/// A plane obstacle: the half-space `(x - point)·normal ≥ 0` is free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point of the plane (m).
    pub point: DVec3,
    /// Unit normal pointing into the free side.
    pub normal: DVec3,
}

/// A bowl: the inside of a sphere, below the rim height (NYCU HW1 2023: radius 9 m centred at
/// `(2, 9/√2, 1)`, rim at `y = 0`, where it meets the hole in the floor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bowl {
    /// Centre of the sphere (m).
    pub center: DVec3,
    /// Radius of the sphere (m).
    pub radius: f64,
    /// The bowl exists only for `y ≤ rim_height` (m); above the rim nothing happens.
    pub rim_height: f64,
}

/// Coefficients of particle–obstacle contact (NYCU HW1: ε = 0.01 m, k_r = 0.8, k_f = 0.2 in 2023).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactCoefficients {
    /// Contact band `ε` (m): closer than this to the surface counts as touching.
    pub epsilon: f64,
    /// Restitution `k_r` (dimensionless): the share of the normal speed kept in a bounce.
    pub restitution: f64,
    /// Friction coefficient `k_f` (dimensionless).
    pub friction: f64,
}

/// A body in a sphere–particle collision: a dynamic sphere's centre or a cloth particle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Body {
    /// Position (m): the sphere's centre or the particle.
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Inverse mass `w = 1/m` (1/kg); 0 for a pinned particle (infinitely heavy).
    pub inverse_mass: f64,
}
