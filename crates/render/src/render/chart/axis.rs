//! Chart axes: the data range of the series, nice tick values on linear and logarithmic
//! scales, and their labels.

use super::{Chart, Scale};
use crate::render::paint::nice;

/// One tick of an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Tick {
    /// Position in data units.
    pub value: f64,
    /// Label; empty for a minor tick.
    pub label: String,
}

/// An axis: its ends in data units, its scale and its ticks (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Value at the start (left or bottom).
    pub lo: f64,
    /// Value at the end (right or top).
    pub hi: f64,
    /// Linear or log.
    pub scale: Scale,
    /// Ticks from `lo` to `hi`.
    pub ticks: Vec<Tick>,
}

impl Axis {
    /// Nice linear ticks over `[a, b]` with about `n` ticks (module docs). An empty or
    /// degenerate range is widened.
    #[must_use]
    pub fn linear(a: f64, b: f64, n: usize) -> Axis {
        let (mut a, mut b) = if a <= b { (a, b) } else { (b, a) };
        if !(a.is_finite() && b.is_finite()) {
            (a, b) = (0.0, 1.0);
        }
        if b - a <= f64::EPSILON * a.abs().max(b.abs()).max(1e-300) {
            let w = if a == 0.0 { 1.0 } else { 0.1 * a.abs() };
            (a, b) = (a - w, b + w);
        }
        let range = nice(b - a, false);
        let d = nice(range / (n.max(2) - 1) as f64, true);
        let lo = (a / d).floor() * d;
        let hi = (b / d).ceil() * d;
        let decimals = (-d.log10().floor()).max(0.0) as usize;
        let scientific = lo.abs().max(hi.abs()) >= 1e6 || d < 1e-4;
        let count = ((hi - lo) / d).round() as i64;
        let ticks = (0..=count)
            .map(|k| {
                let v = lo + k as f64 * d;
                // Snap values that should be 0 (from lo + k d rounding).
                let v = if v.abs() < 1e-9 * d { 0.0 } else { v };
                Tick {
                    value: v,
                    label: if scientific {
                        scientific_label(v, d)
                    } else {
                        format!("{v:.decimals$}")
                    },
                }
            })
            .collect();
        Axis {
            lo,
            hi,
            scale: Scale::Linear,
            ticks,
        }
    }

    /// Decade ticks over `[a, b]`, `0 < a ≤ b` (module docs). Non-positive input gives 1 to 10.
    #[must_use]
    pub fn log(a: f64, b: f64) -> Axis {
        let (a, b) = if a > 0.0 && b >= a && b.is_finite() {
            (a, b)
        } else {
            (1.0, 10.0)
        };
        let k0 = a.log10().floor() as i32;
        let mut k1 = b.log10().ceil() as i32;
        if k1 <= k0 {
            k1 = k0 + 1;
        }
        let decades = (k1 - k0) as usize;
        let every = decades.div_ceil(8).max(1);
        let mut ticks = Vec::new();
        for k in k0..=k1 {
            let labelled = ((k - k0) as usize).is_multiple_of(every);
            ticks.push(Tick {
                value: 10f64.powi(k),
                label: if labelled {
                    power_of_ten(k)
                } else {
                    String::new()
                },
            });
            if decades <= 6 && k < k1 {
                for m in 2..=9 {
                    ticks.push(Tick {
                        value: f64::from(m) * 10f64.powi(k),
                        label: String::new(),
                    });
                }
            }
        }
        Axis {
            lo: 10f64.powi(k0),
            hi: 10f64.powi(k1),
            scale: Scale::Log,
            ticks,
        }
    }

    /// Fraction `t` of the way from `lo` to `hi` (module docs); `None` for a value a log axis
    /// cannot show or a non-finite value.
    #[must_use]
    pub fn fraction(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        match self.scale {
            Scale::Linear => Some((v - self.lo) / (self.hi - self.lo)),
            Scale::Log => (v > 0.0)
                .then(|| (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())),
        }
    }
}

/// `v` as `m.mmme±k` with as many digits as the spacing `d` needs.
pub(super) fn scientific_label(v: f64, d: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (v.abs().log10().floor() - d.log10().floor()).clamp(0.0, 6.0) as usize;
    let s = format!("{v:.digits$e}");
    s
}

/// `10` followed by the exponent in superscript digits, for example `10⁻³`.
pub(super) fn power_of_ten(k: i32) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if k < 0 {
        s.push('⁻');
    }
    for c in k.unsigned_abs().to_string().chars() {
        s.push(SUP[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// The data range of every series on one axis (`x` when `first`), leaving out what `scale`
/// cannot show.
pub(super) fn data_range(chart: &Chart, first: bool, scale: Scale) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    for s in &chart.series {
        for &(x, y) in s.points.iter().chain(s.band.iter().flatten()) {
            let v = if first { x } else { y };
            let other = if first { y } else { x };
            let other_scale = if first { chart.y_scale } else { chart.x_scale };
            let ok = |v: f64, sc: Scale| v.is_finite() && (sc == Scale::Linear || v > 0.0);
            if !ok(v, scale) || !ok(other, other_scale) {
                continue;
            }
            range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
        }
    }
    range
}

/// Share of the data range left free beyond the data at each end of an axis (on a log axis, of
/// the range in decades), so that nothing is drawn on the frame.
pub(super) const MARGIN: f64 = 0.04;

pub(super) fn make_axis(
    range: Option<(f64, f64)>,
    fixed: Option<(f64, f64)>,
    scale: Scale,
) -> Axis {
    let (a, b) = fixed.or(range).unwrap_or(match scale {
        Scale::Linear => (0.0, 1.0),
        Scale::Log => (1.0, 10.0),
    });
    let mut axis = match scale {
        Scale::Linear => Axis::linear(a, b, 6),
        Scale::Log => Axis::log(a, b),
    };
    let ends = match fixed {
        // A fixed range is kept exactly.
        Some((lo, hi)) if lo < hi && (scale == Scale::Linear || lo > 0.0) => Some((lo, hi)),
        Some(_) => None,
        None if b > a => Some(match scale {
            Scale::Linear => (a - MARGIN * (b - a), b + MARGIN * (b - a)),
            Scale::Log => {
                let span = b.log10() - a.log10();
                (
                    10f64.powf(a.log10() - MARGIN * span),
                    10f64.powf(b.log10() + MARGIN * span),
                )
            }
        }),
        None => None,
    };
    if let Some((lo, hi)) = ends {
        axis.lo = lo;
        axis.hi = hi;
        // Only ticks inside stay (or outside by rounding only).
        let inside = axis.clone();
        axis.ticks.retain(|t| {
            inside
                .fraction(t.value)
                .is_some_and(|f| (-1e-9..=1.0 + 1e-9).contains(&f))
        });
    }
    if scale == Scale::Log && axis.ticks.iter().filter(|t| !t.label.is_empty()).count() < 2 {
        // Less than two decades in view: label 1, 2 and 5 times each power of ten, or every
        // tick when that is still less than two labels.
        let nice_125 = |v: f64| {
            let m = v / 10f64.powf(v.log10().floor());
            [1.0, 2.0, 5.0, 10.0].iter().any(|n| (m - n).abs() < 1e-6)
        };
        let all = axis.ticks.iter().filter(|t| nice_125(t.value)).count() < 2;
        for t in &mut axis.ticks {
            if all || nice_125(t.value) {
                t.label = format_number(t.value);
            }
        }
    }
    axis
}

/// A short label for `v`: plain decimals between 0.001 and 10 000 (three significant digits at
/// most), else `m×10ᵏ`.
pub(super) fn format_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return if a == 0.0 { "0".into() } else { format!("{v}") };
    }
    let k = a.log10().floor() as i32;
    if (-3..4).contains(&k) {
        let decimals = (2 - k).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        return s;
    }
    let m = v / 10f64.powi(k);
    if (m.abs() - 1.0).abs() < 1e-9 {
        let sign = if v < 0.0 { "-" } else { "" };
        return format!("{sign}{}", power_of_ten(k));
    }
    let m = format!("{m:.2}");
    let m = m.trim_end_matches('0').trim_end_matches('.');
    format!("{m}×{}", power_of_ten(k))
}
