//! The answer's limit as the spacing goes to zero, and whether the answer has settled in time.
//!
//! # Richardson extrapolation
//!
//! Three levels with spacings `h_1 > h_2 > h_3` (m, `h = size/(n - 1)`) and values `O_1, O_2,
//! O_3` of one component are fitted by
//!
//! ```text
//! O(h) = O_∞ + C h^p
//!
//! (O_1 - O_2) / (O_2 - O_3) = (h_1^p - h_2^p) / (h_2^p - h_3^p)      solved for p (bisection)
//! O_∞ = O_3 - (O_2 - O_3) h_3^p / (h_2^p - h_3^p)
//! ```
//! where `p` is the observed order of the spatial error (dimensionless), `O_∞` the extrapolated
//! limit and `C` a constant (in the component's unit per m^p). With equal ratios `r = h_1/h_2 =
//! h_2/h_3` this is the textbook `p = ln((O_1 - O_2)/(O_2 - O_3)) / ln r` and `O_∞ = O_3 + (O_3 -
//! O_2)/(r^p - 1)`. It needs the differences to keep their sign (monotone convergence); then the
//! right-hand side grows with `p` from `ln(h_1/h_2)/ln(h_2/h_3)` (as `p → 0`) to infinity, so the
//! order is unique. The limit's **uncertainty** is the change of the limit when the three levels
//! move one level coarser (`|O_∞(L-2, L-1, L) - O_∞(L-3, L-2, L-1)|`), and at least the
//! extrapolation's own correction `|O_∞ - O_3|` when fewer than four levels were run (Roache's
//! grid convergence index uses the correction times a safety factor of 1.25 to 3; here the
//! spread between two extrapolations is measured instead).
//!
//! A level is **within X of the limit** when `|O(n) - O_∞| + u ≤ X` for every component; the
//! answer stops changing from the first level from which every finer level is within X of it.
//!
//! # Settled in time
//!
//! An observable taken at `T` while the body still moves is not the scene's answer at rest. The
//! study compares every level's observation at `T` with its own at `0.8 T` (the sample four
//! twentieths earlier): the answer is **settled** when
//!
//! ```text
//! |O(T) - O(0.8 T)| ≤ X / 10
//! ```
//! for every component (m, or s for times): over the last fifth of the run it moved less than a
//! tenth of the tolerance. Otherwise the study says it is not settled and by how much it moved;
//! a later `--time` is then the honest way to observe it at rest.
//!
//! References: L. F. Richardson, "The deferred approach to the limit", Phil. Trans. R. Soc. A
//! 226 (1927) 299–349; P. J. Roache, "Quantification of uncertainty in computational fluid
//! dynamics", Annu. Rev. Fluid Mech. 29 (1997) 123–160; I. B. Celik et al., "Procedure for
//! estimation and reporting of uncertainty due to discretization in CFD applications", J. Fluids
//! Eng. 130 (2008) 078001 (the iteration for `p` with unequal ratios).

use serde::Serialize;

use crate::study::observe::{Observation, Unit};

/// The settling window: the run's last fifth (the observation `SETTLE_SAMPLES` samples before
/// the end, of [`crate::study::observe::SAMPLES`]).
pub const SETTLE_SAMPLES: usize = 4;

/// The settling criterion: the change over the window is at most this fraction of `X`.
pub const SETTLE_FRACTION: f64 = 0.1;

/// One Richardson extrapolation from three levels (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Extrapolation {
    /// The observed order `p`.
    pub order: f64,
    /// The extrapolated value `O_∞`.
    pub limit: f64,
}

/// The Richardson extrapolation of `values` at spacings `h` (coarse to fine, `h` decreasing),
/// or `None` when the differences change sign, vanish, or no order in (0, 64) fits.
#[must_use]
pub fn richardson(h: [f64; 3], values: [f64; 3]) -> Option<Extrapolation> {
    let [h1, h2, h3] = h;
    let [o1, o2, o3] = values;
    if !(h1 > h2 && h2 > h3 && h3 > 0.0) || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let (d12, d23) = (o1 - o2, o2 - o3);
    if d12 == 0.0 || d23 == 0.0 || d12.signum() != d23.signum() {
        return None;
    }
    let target = d12 / d23;
    // (h1^p - h2^p)/(h2^p - h3^p), written with ratios for accuracy.
    let ratio = |p: f64| {
        let (a, b) = ((h1 / h2).powf(p), (h3 / h2).powf(p));
        (a - 1.0) / (1.0 - b)
    };
    let (mut lo, mut hi) = (1e-9, 64.0);
    if !(ratio(lo) < target && target < ratio(hi)) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if ratio(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let b = (h3 / h2).powf(p);
    Some(Extrapolation {
        order: p,
        limit: o3 - d23 * b / (1.0 - b),
    })
}

/// The limit of one component over the levels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ComponentLimit {
    /// The component's name (its headline: a point's height, a trajectory's last height).
    pub name: String,
    /// Its unit.
    pub unit: Unit,
    /// The three levels used (`n`), coarse to fine.
    pub levels: [i64; 3],
    /// The observed order `p`.
    pub order: f64,
    /// The extrapolated limit `O_∞`.
    pub limit: f64,
    /// Its uncertainty `u` (module docs).
    pub uncertainty: f64,
    /// The extrapolation one level coarser, when there were four levels.
    pub previous: Option<Extrapolation>,
}

/// The Richardson limit of every component from the all-kinds `levels` (`(n, spacing h,
/// observation)`, coarse to fine, only those that did not diverge): one entry per component,
/// `None` where it cannot be extrapolated (fewer than three levels, non-monotone).
#[must_use]
pub fn limits(levels: &[(i64, f64, &Observation)]) -> Vec<Option<ComponentLimit>> {
    let Some(&(_, _, finest)) = levels.last() else {
        return Vec::new();
    };
    let count = finest.components.len();
    let three = |k: usize, c: usize| -> Option<Extrapolation> {
        let l = levels.get(k..k + 3)?;
        let h = [l[0].1, l[1].1, l[2].1];
        let v = [0, 1, 2].map(|i| {
            l[i].2
                .components
                .get(c)
                .map_or(f64::NAN, super::super::observe::Component::headline)
        });
        richardson(h, v)
    };
    (0..count)
        .map(|c| {
            let last = levels.len().checked_sub(3)?;
            let e = three(last, c)?;
            let previous = last.checked_sub(1).and_then(|k| three(k, c));
            let finest_value = finest.components[c].headline();
            let uncertainty = match previous {
                Some(p) => (e.limit - p.limit).abs(),
                None => (e.limit - finest_value).abs(),
            };
            Some(ComponentLimit {
                name: finest.components[c].headline_name(),
                unit: finest.components[c].unit,
                levels: [levels[last].0, levels[last + 1].0, levels[last + 2].0],
                order: e.order,
                limit: e.limit,
                uncertainty,
                previous,
            })
        })
        .collect()
}

/// How far an observation is from the limits: `|O - O_∞| + u` per unit (m, s), the largest
/// over the components; infinite when a component has no limit.
#[must_use]
pub fn distance(o: &Observation, limits: &[Option<ComponentLimit>]) -> (f64, f64) {
    let (mut metres, mut seconds) = (0.0f64, 0.0f64);
    for (c, l) in o.components.iter().zip(limits) {
        let d = l.as_ref().map_or(f64::INFINITY, |l| {
            (c.headline() - l.limit).abs() + l.uncertainty
        });
        let d = if d.is_nan() { f64::INFINITY } else { d };
        match c.unit {
            Unit::Metre => metres = metres.max(d),
            Unit::Second => seconds = seconds.max(d),
        }
    }
    if limits.len() != o.components.len() {
        metres = f64::INFINITY;
    }
    (metres, seconds)
}

/// Whether one run's answer had settled (module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Settling {
    /// The start of the window (s): `0.8 T`.
    pub from: f64,
    /// The largest change of a position or length over the window (m).
    pub metres: f64,
    /// The largest change of a time over the window (s).
    pub seconds: f64,
    /// Whether both are within `X / 10`.
    pub settled: bool,
}

/// The settling of a run from its snapshots at `k T / K` (`k = 1 … K`), or `None` when it has
/// too few (a diverged run).
#[must_use]
pub fn settling(snapshots: &[Observation], horizon: f64, tolerance: f64) -> Option<Settling> {
    let k = snapshots.len();
    let earlier = snapshots.get(k.checked_sub(SETTLE_SAMPLES + 1)?)?;
    let last = snapshots.last()?;
    let from = horizon * (k - SETTLE_SAMPLES) as f64 / k as f64;
    let d = last.difference(earlier, horizon);
    let bound = SETTLE_FRACTION * tolerance;
    Some(Settling {
        from,
        metres: d.metres,
        seconds: d.seconds,
        settled: d.metres <= bound && d.seconds <= bound,
    })
}

/// The criterion in words, for the output.
#[must_use]
pub fn settling_rule(tolerance: f64) -> String {
    format!(
        "settled when the answer at T differs from the one at 0.8 T by at most X/10 = {} (m, or s \
         for times): it moved less than a tenth of the tolerance over the run's last fifth",
        SETTLE_FRACTION * tolerance
    )
}

/// The definition of the limit in words, for the output.
#[must_use]
pub fn limit_rule(tolerance: f64) -> String {
    format!(
        "Richardson extrapolation O(h) = O_∞ + C h^p through the three finest levels (h = spacing, \
         p the observed order), uncertainty u = the change of O_∞ when the three levels move one \
         coarser (the correction |O_∞ - O_finest| with only three levels); a level is within X = \
         {tolerance} of the limit when |O(n) - O_∞| + u ≤ X for every component (a point \
         compared by its height, a trajectory by its last height)"
    )
}
