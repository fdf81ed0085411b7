//! The model of a mass-spring system and its one derivative function.
//!
//! # Theory
//!
//! Newton's second law turns the forces on each particle into its acceleration:
//!
//! ```text
//! f_i = m_i g  -  c v_i  +  Σ_springs f_spring→i  +  f_contact,i
//! a_i = f_i / m_i              (a_i = 0 for a pinned particle: 1/m_i = 0)
//! ```
//! where
//! - `m_i`: mass (kg), `g`: gravitational acceleration (m/s²)
//! - `c`: viscous drag coefficient (N·s/m), `v_i`: velocity (m/s)
//! - `f_spring→i`: spring and damper force (N), see [`super::springs`]
//! - `f_contact,i`: normal force and friction of the colliders the particle touches (N), added
//!   last because it depends on the sum of the others; see [`super::collide`]
//!
//! Every explicit integrator calls [`accelerations`] and nothing else to learn about the physics,
//! so the cost of a method is its number of calls ("force evaluations").

use glam::DVec3;

use super::collide::{Collider, ContactParams, World, contact_forces};
use super::springs::Spring;
use super::stencil::{Dynamics, Kernel, Output, Stencil};

/// The physics of one system: masses, springs, gravity, drag and static colliders. It does not
/// change during a step.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Mass of each particle (kg). Used for gravity, energy and collisions.
    pub mass: Vec<f64>,
    /// Inverse mass of each particle (1/kg); zero pins the particle in place.
    pub inv_mass: Vec<f64>,
    /// The springs, in the order the force loop visits them. Private: the caches below are
    /// derived from them, so they change only through methods that rebuild the caches
    /// ([`Model::update_springs`], [`Model::scale_stiffness`], [`Model::set_spring_coefficients`]);
    /// read them with [`Model::springs`].
    pub(in crate::physics) springs: Vec<Spring>,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Viscous drag coefficient `c` in `f = -c v` (N·s/m).
    pub drag: f64,
    /// Static obstacles (empty: no contact code runs). Set with [`Model::with_colliders`].
    pub colliders: Vec<Collider>,
    /// Restitution, friction and contact band of the colliders and dynamic spheres.
    pub contact: ContactParams,
    /// The same springs grouped by lattice offset, for the fast force loop; `None` when the
    /// springs are not a lattice (see [`Stencil::detect`]). Kept in step by [`Model::rebuild`].
    stencil: Option<Stencil>,
    /// Spring indices grouped by colour: no two springs of one colour share a particle, so
    /// constraint projection within a colour is order-independent (red-black Gauss–Seidel on a
    /// chain). Built by [`Model::new`].
    projection_order: Vec<u32>,
    /// `projection_order[colour_starts[c]..colour_starts[c + 1]]` are the springs of colour `c`.
    colour_starts: Vec<usize>,
    /// False when every spring has zero stiffness and damping (pure distance constraints, as in
    /// a Verlet rope): the force loop then skips the springs.
    elastic: bool,
    /// What kinds of springs there are ([`SpringKinds`]), found once per change of the springs.
    kinds: SpringKinds,
    /// The springs at each particle: `incident[incident_start[i]..incident_start[i + 1]]` are
    /// the indices of the springs with an end at particle `i` (for energy changes of a few
    /// particles without a pass over all springs). Built by [`Model::new`].
    incident: Vec<u32>,
    /// A new value whenever the springs change (and for every model built), the same in a
    /// clone: the key of caches kept outside the model (XPBD's rows, `fast/xpbd.rs`).
    revision: SpringsRevision,
    /// See `incident`; `particles + 1` entries.
    incident_start: Vec<u32>,
    /// For each entry `h` of `incident` (a spring at one of its ends), the entry of the same
    /// spring in the list of its other end (for a spring from a particle to itself, its other
    /// entry in the same list).
    incident_twin: Vec<u32>,
}

impl Model {
    /// A model with the given masses (kg), pinned flags, springs, gravity (m/s²) and drag (N·s/m).
    ///
    /// # Panics
    /// If `mass` and `pinned` differ in length or a spring refers to a particle out of range.
    #[must_use]
    pub fn new(
        mass: Vec<f64>,
        pinned: &[bool],
        springs: Vec<Spring>,
        gravity: DVec3,
        drag: f64,
    ) -> Model {
        assert_eq!(mass.len(), pinned.len(), "one pinned flag per mass");
        let n = mass.len();
        for s in &springs {
            assert!(
                (s.a as usize) < n && (s.b as usize) < n,
                "spring end out of range"
            );
        }
        let inv_mass = mass
            .iter()
            .zip(pinned)
            .map(|(&m, &p)| if p { 0.0 } else { 1.0 / m })
            .collect();
        let (projection_order, colour_starts) = colour_springs(n, &springs);
        let stencil = Stencil::detect(n, &springs);
        let (incident, incident_start, incident_twin) = incidence(n, &springs);
        Model {
            revision: SpringsRevision::next(),
            incident,
            incident_start,
            incident_twin,
            elastic: any_elastic(&springs),
            kinds: spring_kinds(&springs),
            stencil,
            mass,
            inv_mass,
            springs,
            gravity,
            drag,
            colliders: Vec::new(),
            contact: ContactParams::default(),
            projection_order,
            colour_starts,
        }
    }

    /// The springs, in the order the force loop visits them.
    #[must_use]
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }

    /// Changes every spring with `edit`, then rebuilds what is derived from the springs (the
    /// colouring, the stencil form, the incidence lists), so the model stays consistent.
    ///
    /// # Panics
    /// If `edit` moves a spring's end out of range.
    pub fn update_springs(&mut self, edit: impl FnMut(&mut Spring)) {
        self.springs.iter_mut().for_each(edit);
        let n = self.particle_count();
        for s in &self.springs {
            assert!(
                (s.a as usize) < n && (s.b as usize) < n,
                "spring end out of range"
            );
        }
        self.rebuild();
    }

    /// Multiplies every spring's stiffness (N/m) by `factor`, so that kinds keep their ratios.
    pub fn scale_stiffness(&mut self, factor: f64) {
        self.update_springs(|s| s.stiffness *= factor);
    }

    /// Recomputes what is derived from the springs (the colouring, the stencil form, the
    /// incidence lists). Every method that changes the springs calls it.
    fn rebuild(&mut self) {
        self.revision = SpringsRevision::next();
        let (order, starts) = colour_springs(self.particle_count(), &self.springs);
        self.projection_order = order;
        self.colour_starts = starts;
        self.stencil = Stencil::detect(self.particle_count(), &self.springs);
        self.elastic = any_elastic(&self.springs);
        self.kinds = spring_kinds(&self.springs);
        (self.incident, self.incident_start, self.incident_twin) =
            incidence(self.particle_count(), &self.springs);
    }

    /// The indices of the springs with an end at particle `i`, in spring order.
    #[must_use]
    pub fn springs_at(&self, i: usize) -> &[u32] {
        let (start, end) = (self.incident_start[i], self.incident_start[i + 1]);
        &self.incident[start as usize..end as usize]
    }

    /// The springs' revision: equal in two models (or one model at two times) only when their
    /// springs are the same, one a clone of the other's.
    pub(crate) fn springs_revision(&self) -> SpringsRevision {
        self.revision
    }

    /// For each entry of the springs-at-a-particle lists (`World::incident`), the entry of the
    /// same spring in its other end's list.
    pub(crate) fn incident_twins(&self) -> &[u32] {
        &self.incident_twin
    }

    /// Sets the stiffness (N/m) and damping (N·s/m) of every spring.
    pub fn set_spring_coefficients(&mut self, stiffness: f64, damping: f64) {
        for s in &mut self.springs {
            s.stiffness = stiffness;
            s.damping = damping;
        }
        self.revision = SpringsRevision::next();
        self.kinds = spring_kinds(&self.springs);
        if any_elastic(&self.springs) != self.elastic {
            // Springs became forces or stopped being forces: the stencil may change too.
            self.rebuild();
        } else if let Some(stencil) = &mut self.stencil {
            stencil.set_coefficients(stiffness, damping);
        }
    }

    /// True when the force loop uses the lattice stencil instead of the spring list.
    #[must_use]
    pub fn uses_stencil(&self) -> bool {
        self.stencil.is_some()
    }

    /// The stencil form of the springs, when the force loop uses it.
    #[must_use]
    pub fn stencil(&self) -> Option<&Stencil> {
        self.stencil.as_ref()
    }

    /// The same model with its stencil (if any) computing with `kernel`.
    ///
    /// # Panics
    /// If this CPU cannot run `kernel` (see [`Kernel::is_available`]).
    #[must_use]
    pub fn with_kernel(mut self, kernel: Kernel) -> Model {
        self.stencil = self.stencil.map(|s| s.with_kernel(kernel));
        self
    }

    /// The same model without the stencil form: forces from the spring list only (for tests
    /// and for comparing the two loops).
    #[must_use]
    pub fn without_stencil(mut self) -> Model {
        self.stencil = None;
        self
    }

    /// The same model with `colliders` (normals normalised) and contact coefficients `contact`.
    #[must_use]
    pub fn with_colliders(mut self, colliders: Vec<Collider>, contact: ContactParams) -> Model {
        self.colliders = colliders.into_iter().map(Collider::normalized).collect();
        self.contact = contact;
        self
    }

    /// Number of particles.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.mass.len()
    }

    /// True when particle `i` is pinned (infinite mass).
    #[must_use]
    pub fn is_pinned(&self, i: usize) -> bool {
        self.inv_mass[i] == 0.0
    }

    /// Pins particle `i` (sets its inverse mass to zero). Set its velocity to zero as well, or
    /// use [`super::particles::pin_particle`], which does both.
    pub fn pin(&mut self, i: usize) {
        self.inv_mass[i] = 0.0;
    }

    /// Frees particle `i` again (inverse mass `1/m`).
    pub fn unpin(&mut self, i: usize) {
        self.inv_mass[i] = 1.0 / self.mass[i];
    }

    /// What kinds of springs the model has ([`SpringKinds`]).
    #[must_use]
    pub(crate) fn spring_kinds(&self) -> SpringKinds {
        self.kinds
    }

    /// True when no two springs of a colour share a particle: the colouring did not run out of
    /// colours (a particle with more springs than that would fill the last one).
    #[must_use]
    pub fn colours_disjoint(&self) -> bool {
        self.colour_starts.len() - 1 < COLOURS
    }

    /// The springs grouped by colour (see [`Model::new`]): an iterator of slices of spring indices.
    pub fn spring_colours(&self) -> impl Iterator<Item = &[u32]> {
        self.colour_starts
            .windows(2)
            .map(|w| &self.projection_order[w[0]..w[1]])
    }
}

/// What Verlet's energy accounting asks of the springs at every step (`integrators/verlet.rs`),
/// kept by the model so that no step walks the springs for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SpringKinds {
    /// Every spring is a rod: no stiffness, a finite rest length.
    pub(crate) rods: bool,
    /// Some spring has a damper.
    pub(crate) dampers: bool,
}

/// An identity of a model's springs ([`Model::springs_revision`]), drawn from a counter of the
/// process. Not part of the model's value: two revisions always compare equal as fields and
/// print alike (so two models built alike are equal, and their `Debug` text, which the lesson
/// app's memo hashes, is the same); compare them with [`SpringsRevision::same`].
#[derive(Clone, Copy, Default)]
pub(crate) struct SpringsRevision(u64);

impl std::fmt::Debug for SpringsRevision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SpringsRevision")
    }
}

impl SpringsRevision {
    /// A revision no model had before.
    fn next() -> SpringsRevision {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        SpringsRevision(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }

    /// True when both are the same revision (0, [`Default`], is none).
    pub(crate) fn same(self, other: SpringsRevision) -> bool {
        self.0 != 0 && self.0 == other.0
    }
}

impl PartialEq for SpringsRevision {
    fn eq(&self, _: &SpringsRevision) -> bool {
        true
    }
}

/// [`SpringKinds`] of `springs`.
pub(crate) fn spring_kinds(springs: &[Spring]) -> SpringKinds {
    (springs.iter()).fold(
        SpringKinds {
            rods: true,
            dampers: false,
        },
        |k, s| SpringKinds {
            rods: k.rods & (s.stiffness == 0.0) & s.rest_length.is_finite(),
            dampers: k.dampers | (s.damping != 0.0),
        },
    )
}

/// True when some spring has a stiffness or a damping (exerts a force).
fn any_elastic(springs: &[Spring]) -> bool {
    springs
        .iter()
        .any(|s| s.stiffness != 0.0 || s.damping != 0.0)
}

/// For every particle, the indices of its springs (counting sort by end, in spring order):
/// `(indices, starts)` with `starts[i]..starts[i + 1]` the range of particle `i`.
fn incidence(particles: usize, springs: &[Spring]) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut starts = vec![0u32; particles + 1];
    for s in springs {
        starts[s.a as usize + 1] += 1;
        starts[s.b as usize + 1] += 1;
    }
    for i in 0..particles {
        starts[i + 1] += starts[i];
    }
    let mut fill = starts.clone();
    let mut indices = vec![0u32; 2 * springs.len()];
    let mut twins = vec![0u32; 2 * springs.len()];
    for (k, s) in springs.iter().enumerate() {
        let mut entries = [0u32; 2];
        for (entry, end) in entries.iter_mut().zip([s.a as usize, s.b as usize]) {
            *entry = fill[end];
            indices[fill[end] as usize] = k as u32;
            fill[end] += 1;
        }
        twins[entries[0] as usize] = entries[1];
        twins[entries[1] as usize] = entries[0];
    }
    (indices, starts, twins)
}

/// Colours of [`colour_springs`] (a bit set per particle): the last takes every spring that
/// finds all the others taken at its ends, so only that one may hold springs sharing a
/// particle.
const COLOURS: usize = 64;

/// Greedy edge colouring in spring order: each spring takes the smallest colour not yet used at
/// either end. A chain `(0,1), (1,2), ...` gets colours 0, 1, 0, 1, ... (red-black).
fn colour_springs(particles: usize, springs: &[Spring]) -> (Vec<u32>, Vec<usize>) {
    // used[p] = bit set of the colours already taken at particle p (the first `COLOURS`);
    // a lattice needs at most twice its neighbour count, far below 64.
    let mut used = vec![0u64; particles];
    let mut colour_of = Vec::with_capacity(springs.len());
    let mut colours = 0usize;
    for s in springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let taken = used[a] | used[b];
        let colour = ((!taken).trailing_zeros() as usize).min(COLOURS - 1);
        used[a] |= 1 << colour;
        used[b] |= 1 << colour;
        colours = colours.max(colour + 1);
        colour_of.push(colour);
    }
    let mut starts = vec![0usize; colours + 1];
    for &c in &colour_of {
        starts[c + 1] += 1;
    }
    for c in 0..colours {
        starts[c + 1] += starts[c];
    }
    let mut fill = starts.clone();
    let mut order = vec![0u32; springs.len()];
    for (i, &c) in colour_of.iter().enumerate() {
        order[fill[c]] = i as u32;
        fill[c] += 1;
    }
    (order, starts)
}

/// Net force on every particle (N): gravity, drag, springs and contact. Pure and allocation-free.
///
/// ```text
/// f_i = m_i g - c v_i + Σ_springs f_spring→i + f_contact,i
/// ```
/// Pinned particles get their force too (it is ignored when divided by their infinite mass),
/// except the contact force, which they never need.
///
/// # Panics
/// If `x`, `v` or `f` is shorter than the model's particle count.
pub fn forces(model: &Model, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
    if let Some(stencil) = &model.stencil {
        // The same sums, contact included, in one pass per thread (see `stencil`).
        stencil.write(
            x,
            v,
            [f, &mut [], &mut []],
            &mut [],
            Output::Forces(model.dynamics(true)),
        );
        return;
    }
    applied_forces(model, x, v, f);
    // Contact: it cancels what pushes into a surface, so it comes after everything else.
    if !model.colliders.is_empty() {
        contact_forces(model, x, v, f);
    }
}

/// The forces before contact (N): weight, drag and springs, `f_i = m_i g - c v_i + Σ f_spring→i`.
/// [`forces`] adds the contact forces to these. Pure and allocation-free.
///
/// # Panics
/// If `x`, `v` or `f` is shorter than the model's particle count.
pub fn applied_forces(model: &Model, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
    let n = model.particle_count();
    let (v, f) = (&v[..n], &mut f[..n]);
    if let Some(stencil) = &model.stencil {
        // The same sums, grouped by lattice offset for speed and split between the cores
        // (see `stencil`); weight and drag are added by each thread for its own particles.
        stencil.write(
            x,
            v,
            [f, &mut [], &mut []],
            &mut [],
            Output::Forces(model.dynamics(false)),
        );
    } else {
        // External forces: weight m g and viscous drag -c v.
        for ((f_i, &m_i), &v_i) in f.iter_mut().zip(&model.mass).zip(v) {
            *f_i = m_i * model.gravity - model.drag * v_i;
        }
        // Internal forces: each spring pushes its ends with equal and opposite forces.
        if model.elastic {
            for s in &model.springs {
                let f_a = s.force_on_a(x, v);
                f[s.a as usize] += f_a;
                f[s.b as usize] -= f_a;
            }
        }
    }
}

/// Acceleration of every particle (m/s²): `a_i = f_i / m_i`, zero for pinned particles.
///
/// This is the one derivative function every explicit integrator calls. Pure and
/// allocation-free: it writes into `a`, which is overwritten.
///
/// # Panics
/// If `x`, `v` or `a` is shorter than the model's particle count.
pub fn accelerations(model: &Model, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
    if let Some(stencil) = &model.stencil {
        // Forces, contact and a = f w in one pass per thread (bit-identical to the two steps
        // below).
        let output = Output::Accelerations(model.dynamics(true));
        stencil.write(x, v, [a, &mut [], &mut []], &mut [], output);
        return;
    }
    forces(model, x, v, a);
    for (a_i, &w_i) in a.iter_mut().zip(&model.inv_mass) {
        // a = f / m, with w = 1/m (zero for a pinned particle).
        *a_i *= w_i;
    }
}

impl Model {
    /// Weight, drag, masses and (when `contact`) the colliders, for the stencil's fused passes.
    pub fn dynamics(&self, contact: bool) -> Dynamics<'_> {
        Dynamics {
            mass: &self.mass,
            inv_mass: &self.inv_mass,
            gravity: self.gravity,
            drag: self.drag,
            colliders: if contact { &self.colliders } else { &[] },
            contact: &self.contact,
        }
    }
}

impl<'a> From<&'a Model> for World<'a> {
    /// What the colliders read of the model: colliders, contact coefficients, gravity and
    /// inverse masses.
    fn from(model: &'a Model) -> World<'a> {
        World {
            colliders: &model.colliders,
            contact: &model.contact,
            gravity: model.gravity,
            inv_mass: &model.inv_mass,
            springs: &model.springs,
            incident: &model.incident,
            incident_start: &model.incident_start,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::springs::SpringKind;

    /// Two models built alike are equal and print alike (the lesson app keeps spectra under a
    /// hash of the `Debug` text), though their springs' revisions differ; a change of the
    /// springs gives a new revision, a clone keeps it.
    #[test]
    fn the_springs_revision_is_an_identity_not_a_value() {
        let build = || {
            let spring = Spring {
                a: 0,
                b: 1,
                rest_length: 1.0,
                stiffness: 10.0,
                damping: 0.0,
                kind: SpringKind::Struct,
            };
            Model::new(vec![1.0; 2], &[true, false], vec![spring], DVec3::ZERO, 0.0)
        };
        let (first, second) = (build(), build());
        assert_eq!(first, second);
        assert_eq!(format!("{first:?}"), format!("{second:?}"));
        assert!(!first.springs_revision().same(second.springs_revision()));
        let mut clone = first.clone();
        assert!(clone.springs_revision().same(first.springs_revision()));
        clone.scale_stiffness(2.0);
        assert!(!clone.springs_revision().same(first.springs_revision()));
        let before = clone.springs_revision();
        clone.set_spring_coefficients(5.0, 0.1);
        assert!(!clone.springs_revision().same(before));
    }

    /// Every entry's twin holds the same spring, in the list of the spring's other end (the
    /// other entry of the same list for a spring from a particle to itself), and twins pair up:
    /// on random springs with repeated pairs and springs from a particle to itself.
    #[test]
    fn each_entry_of_the_incidence_lists_knows_its_twin() {
        let mut generator = crate::random::XorShift64Star::new(0x7715_0000_0000_0047);
        for particles in [1, 2, 5, 40] {
            let springs: Vec<Spring> = (0..3 * particles)
                .map(|_| {
                    let end = |g: &mut crate::random::XorShift64Star| {
                        (g.unit() * particles as f64) as u32 % particles as u32
                    };
                    let (a, b) = (end(&mut generator), end(&mut generator));
                    Spring {
                        a,
                        b,
                        rest_length: 1.0,
                        stiffness: 1.0,
                        damping: 0.0,
                        kind: SpringKind::Struct,
                    }
                })
                .collect();
            let (incident, start, twins) = incidence(particles, &springs);
            let list = |p: u32| start[p as usize] as usize..start[p as usize + 1] as usize;
            let mut self_springs = 0;
            for (h, &twin) in twins.iter().enumerate() {
                let (k, twin) = (incident[h], twin as usize);
                let s = &springs[k as usize];
                assert_eq!(
                    incident[twin], k,
                    "entry {h}: its twin holds another spring"
                );
                assert_eq!(twins[twin] as usize, h, "entry {h}: twins do not pair up");
                assert_ne!(twin, h, "entry {h} is its own twin");
                // The list that holds h is one end's; the twin lies in the other end's.
                let here = if list(s.a).contains(&h) { s.a } else { s.b };
                assert!(list(here).contains(&h), "entry {h} in neither end's list");
                let there = if here == s.a { s.b } else { s.a };
                assert!(
                    list(there).contains(&twin),
                    "entry {h}: twin not at the other end"
                );
                self_springs += usize::from(s.a == s.b);
            }
            assert!(
                particles > 5 || self_springs > 0,
                "{particles}: no spring to itself"
            );
        }
    }
}
