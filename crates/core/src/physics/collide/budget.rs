//! The body's part of the energy budget (module docs of `collide`, "energy budget"): after the
//! responses of a step, the exact rise of the total energy over what they changed, taken out
//! of the kinetic energy (Su, Sheth & Fedkiw 2013, §4: a velocity scaling that restores the
//! energy a position correction raised).
//!
//! ```text
//! ΔE   = Σ_{i changed} [ ½ m_i (|v_i'|² - |v_i|²) - m_i g·(x_i' - x_i) ]
//!      + Σ_{springs at a changed particle} [ E_s(x') - E_s(x) ]
//!      + Σ_{dynamic spheres} [ ½ M (|V'|² - |V|²) - M g·(c' - c) ]
//! K    = Σ_j ½ m_j |v_j|² + Σ_spheres ½ M |V|²          after the responses
//! v_j ← √(1 - min(ΔE, K)/K) v_j,   V ← √(1 - min(ΔE, K)/K) V      when ΔE > 0
//! ```
//! where `m_i` (kg) and `x_i` (m), `v_i` (m/s) are a particle's mass, position and velocity
//! before the responses (primed: after), `g` gravity (m/s²), `E_s` a spring's elastic energy
//! (J), `M` (kg), `c` (m) and `V` (m/s) a dynamic sphere's mass, centre and velocity, and `K`
//! (J) the kinetic energy the scaling takes from. Every spring between two changed particles is
//! counted once, with both ends moved: this is what the per-particle estimates of the responses
//! (each particle's springs measured with its neighbours held) cannot see. After the scaling
//! `E' - E = ΔE - min(ΔE, K) ≤ 0` unless the body has less kinetic energy than the rise (a body
//! at rest that its own springs push into an obstacle).

use glam::DVec3;

use super::{Changes, DynamicSphere, World, spheres_energy};

/// The rise of the total energy (J) over the particles in `changes` (after
/// [`Changes::finish`]: each with its position and velocity before) and the non-kinematic
/// `spheres` (their energy before in `changes.spheres_before`, when `with_spheres`), now at
/// `x`, `v` (module docs). Also returns the size of the terms summed (J), for the rounding.
pub(super) fn energy_rise(
    world: &World,
    x: &[DVec3],
    v: &[DVec3],
    spheres: Option<&[DynamicSphere]>,
    changes: &Changes,
) -> (f64, f64) {
    let before = |j: usize| changes.of(j).map_or(x[j], |c| c.1);
    let (mut rise, mut size) = (0.0, 0.0);
    for &(i, x_old, v_old) in &changes.particles {
        let i = i as usize;
        let m = 1.0 / world.inv_mass[i];
        let kinetic = 0.5 * m * (v[i].length_squared() - v_old.length_squared());
        let gravity = -m * world.gravity.dot(x[i] - x_old);
        rise += kinetic + gravity;
        size += 0.5 * m * (v[i].length_squared() + v_old.length_squared()) + gravity.abs();
        let (Some(&start), Some(&end)) =
            (world.incident_start.get(i), world.incident_start.get(i + 1))
        else {
            continue;
        };
        for &k in &world.incident[start as usize..end as usize] {
            let s = &world.springs[k as usize];
            let (a, b) = (s.a as usize, s.b as usize);
            let other = if a == i { b } else { a };
            if other < i && changes.of(other).is_some() {
                // Counted with the other end, which comes first.
                continue;
            }
            let (new, old) = (s.energy(x), s.energy_between(before(a), before(b)));
            rise += new - old;
            size += new + old;
        }
    }
    if let Some(spheres) = spheres {
        let after = spheres_energy(world.gravity, spheres);
        rise += after - changes.spheres_before;
        size += after.abs() + changes.spheres_before.abs();
    }
    (rise, size)
}

/// True when a rise of `rise` J, summed from terms of total size `size` J, is more than the
/// rounding of that sum: only then does the body pay (a payment changes every velocity).
pub(super) fn above_rounding(rise: f64, size: f64) -> bool {
    rise > 1e-12 * size
}

/// Takes `amount` J (at most all there is) out of the kinetic energy of the free particles
/// (`inv_mass`: 1/kg, zero for a pinned particle, which is left alone) and the non-kinematic
/// `spheres` by one factor on every velocity (module docs); returns what it took (J).
pub fn take_kinetic_with_spheres(
    inv_mass: &[f64],
    v: &mut [DVec3],
    spheres: &mut [DynamicSphere],
    amount: f64,
) -> f64 {
    // `inv_mass.iter().zip(v.iter()).filter(|(w, _)| **w != 0.0).map(|(w, v)| 0.5 *
    // v.length_squared() / w).sum()`: the same sum in the same order, its terms a block at a
    // time (`fast/ledger.rs`).
    let particles = crate::physics::fast::ledger::kinetic_of_free(inv_mass, v);
    let moving = || spheres.iter().filter(|s| !s.kinematic);
    let own: f64 = moving()
        .map(|s| 0.5 * s.mass * s.velocity.length_squared())
        .sum();
    let kinetic = particles + own;
    if amount <= 0.0 || kinetic <= 0.0 {
        return 0.0;
    }
    let taken = amount.min(kinetic);
    let factor = (1.0 - taken / kinetic).max(0.0).sqrt();
    for (w, v) in inv_mass.iter().zip(v.iter_mut()) {
        if *w != 0.0 {
            *v *= factor;
        }
    }
    for s in spheres.iter_mut().filter(|s| !s.kinematic) {
        s.velocity *= factor;
    }
    taken
}
