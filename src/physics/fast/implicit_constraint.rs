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
