//! Numbers for messages: a user's number echoed back, estimates rounded, bytes and durations.

/// A user's number echoed back: its shortest exact form (`0.25`, `1000`) between 10⁻⁴ and 10⁶,
/// else scientific (`1e300`, `1e-320`, `1e9`: never 301 digits).
#[must_use]
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// An estimate: whole numbers below 10⁷ exactly, else three significant digits (`1.84e19`).
#[must_use]
pub fn approx(x: f64) -> String {
    if x.is_infinite() {
        return format!("{}more than 1e308", if x < 0.0 { "-" } else { "" });
    }
    if x.is_nan() {
        return "NaN".to_string();
    }
    if x.abs() < 1e7 && x.fract() == 0.0 {
        return format!("{x}");
    }
    if x.abs() < 1e7 && x.abs() >= 1e-3 {
        return format!("{}", (x * 1000.0).round() / 1000.0);
    }
    let s = format!("{x:.2e}");
    match s.split_once('e') {
        Some((mantissa, exponent)) => {
            let m = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{m}e{exponent}")
        }
        None => s,
    }
}

/// Bytes in the largest unit that keeps a leading digit: `3.4 GB`, `512 kB`.
#[must_use]
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 5] = ["bytes", "kB", "MB", "GB", "TB"];
    let mut value = b;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} {}", UNITS[0])
    } else if value >= 1000.0 {
        format!("{} {}", approx(value), UNITS[unit])
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// A duration in seconds as `40 s`, `12 min`, `3.2 h`, `1.2e280 years`.
#[must_use]
pub fn duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "forever".to_string();
    }
    if seconds < 120.0 {
        format!("{} s", seconds.ceil().max(1.0))
    } else if seconds < 7200.0 {
        format!("{} min", (seconds / 60.0).round())
    } else if seconds < 3.0 * 86400.0 {
        format!("{:.1} h", seconds / 3600.0)
    } else if seconds < 3.0 * 31_557_600.0 {
        format!("{:.0} days", seconds / 86400.0)
    } else {
        format!("{} years", approx(seconds / 31_557_600.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_echoed_briefly() {
        assert_eq!(short(1e300), "1e300");
        assert_eq!(short(1e-320), "1e-320");
        assert_eq!(short(-1e300), "-1e300");
        assert_eq!(short(0.015625), "0.015625");
        assert_eq!(short(10.0), "10");
        assert_eq!(short(1e9), "1e9");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(approx(18_446_744_073_709_551_615.0), "1.84e19");
        assert_eq!(approx(1e300), "1e300");
        assert_eq!(approx(4_999_995.0), "4999995");
        assert_eq!(approx(0.999_999_999_999_999_9), "1");
        assert_eq!(approx(f64::INFINITY), "more than 1e308");
        assert_eq!(bytes(3.7e9), "3.7 GB");
        assert_eq!(bytes(2.0 * 1024.0 * 1024.0 * 1024.0), "2.1 GB");
        assert_eq!(bytes(512.0), "512 bytes");
        assert_eq!(duration(30.2), "31 s");
        assert_eq!(duration(3600.0), "60 min");
        assert_eq!(duration(f64::INFINITY), "forever");
    }
}
