//! Assembling particles and springs into a [`Model`] and its initial [`State`].

use glam::DVec3;

use crate::physics::{Model, Spring, SpringKind, State};

/// Collects particles and springs; [`Builder::build`] turns them into a model and a state.
#[derive(Clone, Debug, Default)]
pub struct Builder {
    /// Positions (m).
    pub x: Vec<DVec3>,
    /// Velocities (m/s).
    pub v: Vec<DVec3>,
    /// Masses (kg).
    pub mass: Vec<f64>,
    /// Pinned flags.
    pub pinned: Vec<bool>,
    /// Springs.
    pub springs: Vec<Spring>,
}

impl Builder {
    /// An empty builder.
    #[must_use]
    pub fn new() -> Builder {
        Builder::default()
    }

    /// Number of particles so far.
    #[must_use]
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when no particle has been added.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Reserves room for `particles` more particles and `springs` more springs, so that a large
    /// scene takes exactly the memory it needs (growth by doubling could take twice as much).
    pub fn reserve(&mut self, particles: usize, springs: usize) {
        self.x.reserve(particles);
        self.v.reserve(particles);
        self.mass.reserve(particles);
        self.pinned.reserve(particles);
        self.springs.reserve(springs);
    }

    /// Adds a particle at `x` (m) at rest with mass `mass` (kg); returns its index.
    pub fn particle(&mut self, x: DVec3, mass: f64) -> u32 {
        self.x.push(x);
        self.v.push(DVec3::ZERO);
        self.mass.push(mass);
        self.pinned.push(false);
        (self.x.len() - 1) as u32
    }

    /// Adds a spring between `a` and `b` whose rest length is their current distance.
    pub fn spring(&mut self, a: u32, b: u32, stiffness: f64, damping: f64, kind: SpringKind) {
        let rest_length = (self.x[b as usize] - self.x[a as usize]).length();
        self.springs.push(Spring {
            a,
            b,
            rest_length,
            stiffness,
            damping,
            kind,
        });
    }

    /// The model (with `gravity` in m/s² and `drag` in N·s/m) and the initial state.
    #[must_use]
    pub fn build(self, gravity: DVec3, drag: f64) -> (Model, State) {
        let mut state = State::new(self.x, self.v);
        // A pinned particle does not move: make sure it starts at rest.
        for (v, &p) in state.v.iter_mut().zip(&self.pinned) {
            if p {
                *v = DVec3::ZERO;
            }
        }
        let model = Model::new(self.mass, &self.pinned, self.springs, gravity, drag);
        (model, state)
    }
}

/// A rope: `nodes` particles evenly spaced from `start` to `end`, a spring between neighbours.
#[derive(Clone, Debug, PartialEq)]
pub struct RopeSpec {
    /// First node (m).
    pub start: DVec3,
    /// Last node (m).
    pub end: DVec3,
    /// Number of nodes, at least 2.
    pub nodes: usize,
    /// Mass of each node (kg).
    pub node_mass: f64,
    /// Stiffness of each spring (N/m).
    pub stiffness: f64,
    /// Damping of each spring (N·s/m).
    pub damping: f64,
    /// Indices (within the rope) of the pinned nodes.
    pub pinned: Vec<usize>,
}

/// Adds a rope (GAMES101 assignment 8, `Rope::Rope`) to `builder`; returns its first particle index.
///
/// Node `i` sits at `start + (end - start) · i / (nodes - 1)`; springs join nodes `i` and `i + 1`
/// with the initial spacing as rest length.
///
/// # Panics
/// If `nodes < 2` or a pinned index is `>= nodes` (scenes validate these first).
pub fn rope(builder: &mut Builder, spec: &RopeSpec) -> u32 {
    assert!(spec.nodes >= 2, "a rope needs at least 2 nodes");
    let first = builder.len() as u32;
    let last = (spec.nodes - 1) as f64;
    for i in 0..spec.nodes {
        // Evenly spaced: the fraction i / (nodes - 1) of the way from start to end.
        let x = spec.start + (spec.end - spec.start) * (i as f64 / last);
        builder.particle(x, spec.node_mass);
    }
    for &p in &spec.pinned {
        assert!(p < spec.nodes, "pinned node out of range");
        builder.pinned[first as usize + p] = true;
    }
    for i in 0..spec.nodes as u32 - 1 {
        builder.spring(
            first + i,
            first + i + 1,
            spec.stiffness,
            spec.damping,
            SpringKind::Struct,
        );
    }
    first
}
