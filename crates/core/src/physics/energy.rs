//! Mechanical energy of a mass-spring system.
//!
//! ```text
//! E_kinetic = Σ_i ½ m_i |v_i|²
//! E_gravity = Σ_i -m_i g · x_i          (= Σ m_i 9.8 y_i for g = (0, -9.8, 0))
//! E_elastic = Σ_springs ½ k (L - L0)²
//! ```
//! where `m_i` is in kg, `v_i` in m/s, `x_i` in m, `g` in m/s², `k` in N/m; energies in J.
//! Without damping, drag and collisions the total is conserved by the exact motion, so its drift
//! measures an integrator's error.
//!
//! Dynamic spheres (see [`super::collide::DynamicSphere`]) are bodies of the system too: their
//! `½ m_s |v_s|²` is added to the kinetic and their `-m_s g · c_s` to the gravitational energy
//! (`c_s`: centre, m). A kinematic sphere is driven from outside with infinite mass; it has no
//! energy of its own and is left out.

use serde::Serialize;

use glam::DVec3;

use super::collide::{CALM, Changes, DynamicSphere, World, calm, contact_power, spheres_energy};
use super::forces::{Model, applied_forces};
use super::particles::State;

/// Kinetic, gravitational and elastic energy (J).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Energy {
    /// `Σ ½ m |v|²` (J).
    pub kinetic: f64,
    /// `Σ -m g·x` (J).
    pub gravity: f64,
    /// `Σ ½ k (L - L0)²` (J).
    pub elastic: f64,
    /// Sum of the three (J).
    pub total: f64,
}

impl Energy {
    /// Adds two energies (of two bodies).
    #[must_use]
    pub fn plus(self, other: Energy) -> Energy {
        Energy {
            kinetic: self.kinetic + other.kinetic,
            gravity: self.gravity + other.gravity,
            elastic: self.elastic + other.elastic,
            total: self.total + other.total,
        }
    }
}

/// The energy of `state` under `model`.
#[must_use]
pub fn energy(model: &Model, state: &State) -> Energy {
    // Σ_springs ½ k (L - L0)², `model.springs.iter().map(|s| s.energy(&state.x)).sum()`: the
    // same sum in the same order, its terms a block at a time (`fast/elastic.rs`).
    let elastic = super::fast::elastic::elastic(&model.springs, &state.x);
    energy_with_elastic(model, state, elastic)
}

/// [`energy`] with its elastic term `elastic` (J) computed elsewhere (implicit Euler's energy
/// guard sums it on the lattice).
#[must_use]
pub fn energy_with_elastic(model: &Model, state: &State, elastic: f64) -> Energy {
    let mut kinetic = 0.0;
    let mut gravity = 0.0;
    for ((&m, x), v) in model.mass.iter().zip(&state.x).zip(&state.v) {
        kinetic += 0.5 * m * v.length_squared();
        gravity -= m * model.gravity.dot(*x);
    }
    for s in state.spheres.iter().filter(|s| !s.kinematic) {
        kinetic += 0.5 * s.mass * s.velocity.length_squared();
        gravity -= s.mass * model.gravity.dot(s.center);
    }
    Energy {
        kinetic,
        gravity,
        elastic,
        total: kinetic + gravity + elastic,
    }
}

/// The change of [`energy`] (J) that a collision response made, from what it recorded
/// ([`Changes`], after [`Changes::finish`]): the kinetic and gravitational terms of the
/// particles it changed, the elastic energy of their springs (each spring once, with both ends
/// as they were), and the dynamic spheres' energy. The same number as the difference of two
/// calls of [`energy`] up to rounding, without a pass over every spring: only the springs at a
/// particle that moved are visited (the others add exactly 0 J; the same bits as summing them,
/// `tests/collide.rs`).
#[must_use]
pub fn energy_change(model: &Model, state: &State, changes: &Changes) -> f64 {
    energy_change_of(model, &state.x, &state.v, &state.spheres, changes)
}

/// [`energy_change`] of the positions `x` (m), velocities `v` (m/s) and dynamic `spheres` after
/// the response.
#[must_use]
pub fn energy_change_of(
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    spheres: &[DynamicSphere],
    changes: &Changes,
) -> f64 {
    energy_change_calm(model, x, v, spheres, changes, false)
}

/// [`energy_change_of`], told by `calm_elsewhere` that every particle the response did not
/// change was calm before it (and so still is; a summary of the parts, `collide::Prepared`):
/// then only the changed particles are checked, not every one. The same result.
#[must_use]
pub fn energy_change_calm(
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    spheres: &[DynamicSphere],
    changes: &Changes,
    calm_elsewhere: bool,
) -> f64 {
    LEDGER.with(|ledger| {
        let ledger = &mut *ledger.borrow_mut();
        ledger.change(model, x, v, changes, calm_elsewhere)
    }) + spheres_energy(model.gravity, spheres)
        - changes.spheres_before
}

thread_local! {
    /// A thread's scratch of [`energy_change_calm`] (reused, so a response does not allocate).
    static LEDGER: std::cell::RefCell<Ledger> = std::cell::RefCell::new(Ledger::default());
}

/// The scratch of [`energy_change_calm`]: which particles moved, which entries of the
/// springs-at-a-particle lists hold a spring to sum, each record's two terms.
#[derive(Default)]
struct Ledger {
    /// Bit `i % 64` of word `i / 64`: recorded particle `i` moved or is not calm.
    moved: Vec<u64>,
    /// Bit `h % 64` of word `h / 64`: entry `h` of `World::incident` is a spring to sum there.
    owned: Vec<u64>,
    /// Each record's kinetic and gravitational terms (J).
    terms: Vec<[f64; 2]>,
}

impl Ledger {
    /// The particles' part of [`energy_change_calm`] (without the spheres): the records'
    /// terms, and the springs at them that moved, in the textbook sum's order (record by
    /// record, each record's springs in the order of its list after its terms).
    fn change(
        &mut self,
        model: &Model,
        x: &[DVec3],
        v: &[DVec3],
        changes: &Changes,
        calm_elsewhere: bool,
    ) -> f64 {
        let records = &changes.particles;
        let gravity = model.gravity;
        // Each record's kinetic and gravitational terms, independent of each other; which
        // recorded particles moved (or are not calm); whether the records are in particle
        // order, each once (`Changes::finish` makes them so).
        let Ledger {
            moved,
            owned,
            terms,
        } = self;
        moved.clear();
        moved.resize(x.len().div_ceil(64), 0);
        terms.clear();
        let (mut records_calm, mut in_order, mut last) = (true, true, None);
        for &(i, x_old, v_old) in records {
            in_order &= last.is_none_or(|last| last < i);
            last = Some(i);
            let i = i as usize;
            let here = calm(x[i]);
            records_calm &= here;
            if x[i] != x_old || !here {
                moved[i / 64] |= 1 << (i % 64);
            }
            let m = model.mass[i];
            terms.push([
                0.5 * m * (v[i].length_squared() - v_old.length_squared()),
                m * gravity.dot(x[i] - x_old),
            ]);
        }
        let moved = |j: usize| moved.get(j / 64).is_none_or(|w| w >> (j % 64) & 1 == 1);
        let before = |j: usize| changes.of(j).map_or(x[j], |c| c.1);
        let all_calm = if calm_elsewhere {
            records_calm
        } else {
            super::fast::energy::all_below(x, CALM)
        };
        let mut delta = 0.0;
        if !(all_calm && in_order) {
            // The textbook loop: every spring at every record, those whose two ends are where
            // they were (and calm) left out, each spring once (at its first recorded end).
            for (&(i, ..), &[kinetic, lift]) in records.iter().zip(terms.iter()) {
                delta += kinetic;
                delta -= lift;
                let i = i as usize;
                let i_still = !moved(i);
                for &s in model.springs_at(i) {
                    let s = &model.springs[s as usize];
                    let (a, b) = (s.a as usize, s.b as usize);
                    let other = if a == i { b } else { a };
                    if i_still && !moved(other) && calm(x[other]) {
                        // Both ends where they were: 0 J.
                        continue;
                    }
                    if other < i && changes.of(other).is_some() {
                        // Counted with the other end, which comes first.
                        continue;
                    }
                    delta += s.energy(x) - s.energy_between(before(a), before(b));
                }
            }
            return delta;
        }
        // Every position calm: a spring whose two ends are where they were adds `E_s - E_s`,
        // exactly 0 J, and the sum never holds -0 (it starts at +0), so adding it does
        // nothing: only the springs at a moved particle are summed. Most records are
        // velocities the body's payment scaled. Each such spring is marked at the entry of
        // the springs-at-a-particle lists where the loop above sums it (its first recorded
        // end, `World::incident`, whose lists follow each other in particle order as the
        // records do), so the sum walks the records and the marks together: the same terms
        // in the same order. A zero gravitational term (a particle that did not move) is
        // left out: `d - (+0) = d` for every `d`.
        let world = World::from(model);
        let (incident, start) = (world.incident, world.incident_start);
        let twins = model.incident_twins();
        // Every mark lies in a record's list, and only those lists are read: a few records (a
        // large cloth's pushes) clear their lists' words only, not the whole bitmap of two bits
        // per spring; many (a payment) clear it all at once.
        let words = incident.len().div_ceil(64);
        let sparse = 16 * records.len() < x.len() && owned.len() >= words;
        if sparse {
            for &(j, ..) in records {
                let list = start[j as usize] as usize..start[j as usize + 1] as usize;
                if !list.is_empty() {
                    owned[list.start / 64..=(list.end - 1) / 64].fill(0);
                }
            }
        } else {
            owned.clear();
            owned.resize(words, 0);
        }
        let mut mark = |h: usize| owned[h / 64] |= 1 << (h % 64);
        for &(j, ..) in records {
            let j = j as usize;
            if !moved(j) {
                continue;
            }
            for h in start[j] as usize..start[j + 1] as usize {
                let k = incident[h];
                let s = &model.springs[k as usize];
                let other = if s.a as usize == j { s.b } else { s.a } as usize;
                if other < j && changes.of(other).is_some() {
                    if moved(other) {
                        // Marked from the other end's own list.
                        continue;
                    }
                    // Summed at the other end: its entry of this spring (the spring's one
                    // entry in that list, `other != j`).
                    mark(twins[h] as usize);
                } else {
                    mark(h);
                }
            }
        }
        // The marks of record i's list, in list order, after its terms (the lists follow each
        // other in particle order, as the records do): a few records look in their own lists,
        // many walk the whole bitmap once with a cursor.
        let spring = |k: usize| {
            let s = &model.springs[incident[k] as usize];
            let (a, b) = (s.a as usize, s.b as usize);
            s.energy(x) - s.energy_between(before(a), before(b))
        };
        // The first mark at or after `from` and before `end`, a word at a time.
        let next = |from: usize, end: usize| {
            let mut w = from / 64;
            let mut bits = owned.get(w).map_or(0, |&b| b & (u64::MAX << (from % 64)));
            while bits == 0 {
                w += 1;
                if 64 * w >= end {
                    return None;
                }
                bits = *owned.get(w)?;
            }
            Some(64 * w + bits.trailing_zeros() as usize).filter(|&k| k < end)
        };
        let mut cursor = if sparse {
            usize::MAX
        } else {
            next(0, incident.len()).unwrap_or(usize::MAX)
        };
        for (&(i, ..), &[kinetic, lift]) in records.iter().zip(terms.iter()) {
            delta += kinetic;
            if lift.to_bits() != 0 {
                delta -= lift;
            }
            let (first, end) = (start[i as usize] as usize, start[i as usize + 1] as usize);
            if sparse {
                let mut h = first;
                while let Some(k) = next(h, end) {
                    delta += spring(k);
                    h = k + 1;
                }
            } else {
                while cursor < end {
                    delta += spring(cursor);
                    cursor = next(cursor + 1, incident.len()).unwrap_or(usize::MAX);
                }
            }
        }
        delta
    }
}

/// The power that the dissipative forces take out of the particles at positions `x` (m) and
/// velocities `v` (m/s), split by source (W, each ≥ 0):
///
/// ```text
/// P_dampers = Σ_springs k_d ((v_b - v_a)·n)²          the damper force times the stretch rate
/// P_drag    = Σ_free c |v_i|²
/// P_contact = -Σ_i f_contact,i · v_i                  normal force and friction, see collide
/// ```
/// where `k_d` is a damper coefficient (N·s/m), `n` its spring's unit direction, `c` the viscous
/// drag (N·s/m). `scratch` (one entry per particle) receives the forces before contact; it is
/// used only when the model has colliders.
///
/// Integrated over a step with the method's own stages (see [`crate::physics::integrators`]),
/// these powers give the energy dissipated, so that
/// `E_kinetic + E_gravity + E_elastic + dissipated = E_0` for an exact integrator.
#[must_use]
pub fn dissipated_power(model: &Model, x: &[DVec3], v: &[DVec3], scratch: &mut [DVec3]) -> Power {
    let mut dampers = 0.0;
    for s in model.springs.iter().filter(|s| s.damping != 0.0) {
        let (a, b) = (s.a as usize, s.b as usize);
        let d = x[b] - x[a];
        let length = d.length();
        if length == 0.0 {
            continue;
        }
        let rate = (v[b] - v[a]).dot(d) / length;
        dampers += s.damping * rate * rate;
    }
    let mut drag = 0.0;
    if model.drag != 0.0 {
        for (v, &w) in v.iter().zip(&model.inv_mass) {
            if w != 0.0 {
                drag += model.drag * v.length_squared();
            }
        }
    }
    let contact = if model.colliders.is_empty() {
        0.0
    } else {
        applied_forces(model, x, v, scratch);
        contact_power(model, x, v, scratch)
    };
    Power {
        dampers_and_drag: dampers + drag,
        contact,
    }
}

/// Dissipated power by source (W); see [`dissipated_power`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Power {
    /// Spring dampers and viscous drag (W).
    pub dampers_and_drag: f64,
    /// Contact forces and friction of the colliders (W).
    pub contact: f64,
}

impl Power {
    /// `self + w p`: one term of a quadrature.
    #[must_use]
    pub fn plus(self, w: f64, p: Power) -> Power {
        Power {
            dampers_and_drag: self.dampers_and_drag + w * p.dampers_and_drag,
            contact: self.contact + w * p.contact,
        }
    }
}

/// Energy taken out of a system (J), by where it went. Positive: removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Dissipated {
    /// By spring dampers and viscous drag: their power integrated with the method's stages (J).
    pub dampers_and_drag: f64,
    /// By the colliders' contact forces and friction during the steps (J).
    pub contact_forces: f64,
    /// By what happens between steps: collision responses (bounces, projection), sphere
    /// impulses, and implicit Euler's contact constraints (J). Work done on the system by a
    /// driven (kinematic) sphere counts negative.
    pub contacts: f64,
    /// By the method itself on purpose: Verlet's damping factor and its constraint projection
    /// (J).
    pub method: f64,
    /// The sum (J).
    pub total: f64,
}

impl Dissipated {
    /// The sum of two (of two steps, or of two bodies), with `total` recomputed.
    #[must_use]
    pub fn plus(self, o: Dissipated) -> Dissipated {
        Dissipated {
            dampers_and_drag: self.dampers_and_drag + o.dampers_and_drag,
            contact_forces: self.contact_forces + o.contact_forces,
            contacts: self.contacts + o.contacts,
            method: self.method + o.method,
            total: 0.0,
        }
        .summed()
    }

    /// The same with `total` set to the sum of the parts.
    #[must_use]
    pub fn summed(mut self) -> Dissipated {
        self.total = self.dampers_and_drag + self.contact_forces + self.contacts + self.method;
        self
    }

    /// Adds `dt · p` (one step's quadrature of the powers `p`, W) to the force parts.
    pub fn add_power(&mut self, dt: f64, p: Power) {
        self.dampers_and_drag += dt * p.dampers_and_drag;
        self.contact_forces += dt * p.contact;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::springs::{Spring, SpringKind};

    /// The change as its formula reads (the module docs of `collide/budget.rs`): every record's
    /// kinetic and gravitational terms, then every spring at it once (at its first recorded
    /// end), with both ends as they were, none left out.
    fn in_full(model: &Model, x: &[DVec3], v: &[DVec3], changes: &Changes) -> f64 {
        let before = |j: usize| changes.of(j).map_or(x[j], |c| c.1);
        let mut delta = 0.0;
        for &(i, x_old, v_old) in &changes.particles {
            let i = i as usize;
            let m = model.mass[i];
            delta += 0.5 * m * (v[i].length_squared() - v_old.length_squared());
            delta -= m * model.gravity.dot(x[i] - x_old);
            for &k in model.springs_at(i) {
                let s = &model.springs[k as usize];
                let (a, b) = (s.a as usize, s.b as usize);
                let other = if a == i { b } else { a };
                if other < i && changes.of(other).is_some() {
                    continue;
                }
                delta += s.energy(x) - s.energy_between(before(a), before(b));
            }
        }
        delta
    }

    /// The sum over the moved springs only, walked with the records (`Ledger::change`), is the
    /// formula's sum bit for bit: on a lattice of 9 × 9 particles (more than a word of bits)
    /// with bend springs, a spring from a particle to itself and a spring twice, for records
    /// of a few particles, of every particle (a payment), of particles that moved or only
    /// slowed, at coordinates of ±0, and with a particle far away, infinite or NaN, recorded
    /// or not (no shortcut then); with and without `calm_elsewhere` where it holds.
    #[test]
    fn the_moved_springs_sum_to_the_formulas_bits() {
        let side = 9u32;
        let n = (side * side) as usize;
        let spring = |a: u32, b: u32, rest_length: f64| Spring {
            a,
            b,
            rest_length,
            stiffness: 500.0 + f64::from(a % 7) * 100.0,
            damping: 0.0,
            kind: SpringKind::Struct,
        };
        let mut springs = Vec::new();
        for r in 0..side {
            for c in 0..side {
                let i = r * side + c;
                for (dr, dc, rest) in [(0, 1, 0.1), (1, 0, 0.1), (1, 1, 0.14), (0, 2, 0.2)] {
                    let (r2, c2) = (r + dr, c + dc);
                    if r2 < side && c2 < side {
                        springs.push(spring(i, r2 * side + c2, rest));
                    }
                }
            }
        }
        springs.push(spring(40, 40, 0.0));
        springs.push(spring(70, 71, 0.05));
        let mut generator = crate::random::XorShift64Star::new(2);
        let mut random = move || generator.unit();
        let mass: Vec<f64> = (0..n).map(|_| 0.01 + random()).collect();
        let model = Model::new(
            mass,
            &vec![false; n],
            springs,
            DVec3::new(0.0, -9.8, 0.0),
            0.0,
        );
        let (mut shortcuts, mut paid, mut few) = (0, 0, 0);
        for round in 0..400 {
            let mut x: Vec<DVec3> = (0..n)
                .map(|i| {
                    let (r, c) = ((i as u32 / side) as f64, (i as u32 % side) as f64);
                    DVec3::new(0.1 * c, 0.01 * random(), 0.1 * r) + 0.01 * random()
                })
                .collect();
            let mut v: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(random(), random(), random()) - 0.5)
                .collect();
            if round % 5 == 0 {
                // Coordinates of ±0.
                x[3] = DVec3::new(0.0, -0.0, 0.0);
                x[12] = DVec3::new(-0.0, 0.0, -0.0);
            }
            let every = round % 3 == 0;
            // Now and then a few records (fewer than one particle in 16: the ledger then clears
            // and reads only their lists' marks).
            let share = if round % 7 == 1 { 0.03 } else { 0.15 };
            let mut changes = Changes::default();
            for i in 0..n {
                if !(every || random() < share) {
                    continue;
                }
                let (mut x_old, v_old) = (x[i], v[i] * (1.0 + random()));
                if random() < 0.2 {
                    x_old += DVec3::new(random(), random(), random()) * 0.01;
                }
                if round % 5 == 0 && i == 3 {
                    x_old = DVec3::new(-0.0, 0.0, -0.0);
                }
                changes.record(i, x_old, v_old);
            }
            changes.finish(n);
            let far = [None, None, Some(1e60), Some(f64::INFINITY), Some(f64::NAN)][round % 5];
            if let Some(far) = far {
                // A recorded particle or not (the last one).
                let i = if round % 2 == 0 { 80 } else { 17 };
                x[i].y = far;
                v[i].x = far;
            }
            let full = in_full(&model, &x, &v, &changes);
            let all_calm = x.iter().all(|p| calm(*p));
            let calm_elsewhere = (0..n)
                .filter(|&i| changes.of(i).is_none())
                .all(|i| calm(x[i]));
            for told in [false, true] {
                if told && !calm_elsewhere {
                    continue;
                }
                let fast = energy_change_calm(&model, &x, &v, &[], &changes, told);
                assert!(
                    fast.to_bits() == full.to_bits() || (fast.is_nan() && full.is_nan()),
                    "round {round}, told {told}: {fast} J vs {full} J"
                );
            }
            shortcuts += usize::from(all_calm);
            paid += usize::from(every && all_calm);
            few += usize::from(
                all_calm && !changes.particles.is_empty() && 16 * changes.particles.len() < n,
            );
        }
        assert!(
            shortcuts > 120 && paid > 40 && few > 10,
            "{shortcuts} {paid} {few}"
        );
    }

    /// A few records after other records on the same thread (the ledger's marks reused): a
    /// spring between two moved records is summed once, at its first end, though an earlier
    /// call marked it at its second; the formula's bits.
    #[test]
    fn a_few_records_after_others_sum_each_spring_once() {
        let side = 9u32;
        let n = (side * side) as usize;
        let mut springs = Vec::new();
        for i in 0..n as u32 - 1 {
            springs.push(Spring {
                a: i,
                b: i + 1,
                rest_length: 0.1,
                stiffness: 1000.0,
                damping: 0.0,
                kind: SpringKind::Struct,
            });
        }
        let model = Model::new(
            vec![0.5; n],
            &vec![false; n],
            springs,
            DVec3::new(0.0, -9.8, 0.0),
            0.0,
        );
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(0.1 * i as f64, 0.0, 0.0))
            .collect();
        let v = vec![DVec3::X; n];
        let moved = |records: &[usize]| {
            let mut changes = Changes::default();
            for &i in records {
                changes.record(i, x[i] + DVec3::new(0.0, 0.001 * i as f64, 0.0), DVec3::Y);
            }
            changes.finish(n);
            changes
        };
        // Many records (the bitmap sized), then particle 41 alone (its springs marked at its
        // own entries), then 40 and 41 (their spring summed at 40's entry only).
        for records in [(0..n).collect::<Vec<_>>(), vec![41], vec![40, 41]] {
            let changes = moved(&records);
            let full = in_full(&model, &x, &v, &changes);
            let fast = energy_change_calm(&model, &x, &v, &[], &changes, true);
            assert_eq!(
                fast.to_bits(),
                full.to_bits(),
                "{records:?}: {fast} J vs {full} J"
            );
        }
    }
}
