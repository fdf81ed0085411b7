//! A contact constraint of implicit Euler's solve (see the module docs of
//! [`super::implicit_euler`], "Contacts"): the textbook loop and the lattice path
//! ([`super::implicit_lattice`]) both read it, so it lives apart from either.

use glam::DVec3;

/// One contact constraint: particle `i` gets the velocity change `dv_n` (m/s) along the unit
/// `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Constraint {
    pub(super) i: usize,
    pub(super) normal: DVec3,
    pub(super) dv_n: f64,
    /// The dynamic sphere it touches (index into `State::spheres`), `None` for a collider.
    pub(super) sphere: Option<usize>,
}
