//! The state of a particle system, stored as a struct of arrays.
//!
//! Positions and velocities live in separate contiguous `Vec<DVec3>`s so that the loops over
//! particles read memory in order. Masses are not part of the state: they belong to the
//! [`Model`], which does not change while a simulation runs. Dynamic spheres
//! (cloth scenes) move, so they are part of the state too.

use glam::DVec3;

use super::collide::{Bodies, DynamicSphere};
use super::forces::Model;

/// Positions and velocities of every particle (struct of arrays).
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Positions (m).
    pub x: Vec<DVec3>,
    /// Velocities (m/s).
    pub v: Vec<DVec3>,
    /// Positions one step ago (m), used by position Verlet. Valid only while
    /// [`State::history_valid`] is true.
    pub x_prev: Vec<DVec3>,
    /// True when `x_prev` holds the positions one step of the current `dt` ago. Every method
    /// other than Verlet clears it; Verlet rebuilds `x_prev` from `x` and `v` when it is false.
    pub history_valid: bool,
    /// Moving spheres that collide with the particles and each other (empty in most scenes);
    /// see [`super::collide::step_spheres`].
    pub spheres: Vec<DynamicSphere>,
}

impl State {
    /// A state at positions `x` with velocities `v`.
    ///
    /// # Panics
    /// If `x` and `v` differ in length.
    #[must_use]
    pub fn new(x: Vec<DVec3>, v: Vec<DVec3>) -> State {
        assert_eq!(x.len(), v.len(), "one velocity per position");
        let x_prev = x.clone();
        State {
            x,
            v,
            x_prev,
            history_valid: false,
            spheres: Vec::new(),
        }
    }

    /// The same state with the dynamic spheres `spheres`.
    #[must_use]
    pub fn with_spheres(mut self, spheres: Vec<DynamicSphere>) -> State {
        self.spheres = spheres;
        self
    }

    /// A state at positions `x`, at rest.
    #[must_use]
    pub fn at_rest(x: Vec<DVec3>) -> State {
        let v = vec![DVec3::ZERO; x.len()];
        State::new(x, v)
    }

    /// Number of particles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are no particles.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The mean of all positions (m).
    #[must_use]
    pub fn centroid(&self) -> DVec3 {
        if self.x.is_empty() {
            return DVec3::ZERO;
        }
        self.x.iter().copied().sum::<DVec3>() / self.x.len() as f64
    }
}

impl<'a> From<&'a mut State> for Bodies<'a> {
    /// What collisions change of the state: positions, velocities, Verlet history, spheres.
    fn from(state: &'a mut State) -> Bodies<'a> {
        Bodies {
            x: &mut state.x,
            v: &mut state.v,
            x_prev: &mut state.x_prev,
            history_valid: state.history_valid,
            spheres: &mut state.spheres,
        }
    }
}

/// Pins particle `i` of `model` and stops it: inverse mass 0, velocity 0, and no Verlet
/// displacement (`x_prev = x`), so that it stays exactly where it is under every method.
/// Returns `false` (and changes nothing) when `i` is out of range.
pub fn pin_particle(model: &mut Model, state: &mut State, i: usize) -> bool {
    if i >= model.particle_count() || i >= state.len() {
        return false;
    }
    model.pin(i);
    state.v[i] = DVec3::ZERO;
    state.x_prev[i] = state.x[i];
    true
}
