//! [`DVec3`]: a 3-D vector of `f64` with the arithmetic the homework needs.
//!
//! The same names as `glam::DVec3` (which springlab uses), so code written against either reads
//! the same: `a + b`, `a - b`, `2.0 * a`, `a / 2.0`, `-a`, `a.dot(b)`, `a.cross(b)`,
//! `a.length()`, `a.normalize()`, `DVec3::ZERO`, `DVec3::new(x, y, z)`, `a.x`.

use std::fmt;
use std::iter::Sum;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, MulAssign, Neg, Sub, SubAssign,
};

/// A 3-D vector of `f64` (positions in m, velocities in m/s, forces in N, …).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DVec3 {
    /// First component.
    pub x: f64,
    /// Second component (up, in every assignment).
    pub y: f64,
    /// Third component.
    pub z: f64,
}

impl DVec3 {
    /// `(0, 0, 0)`.
    pub const ZERO: DVec3 = DVec3::new(0.0, 0.0, 0.0);
    /// `(1, 1, 1)`.
    pub const ONE: DVec3 = DVec3::new(1.0, 1.0, 1.0);
    /// `(1, 0, 0)`.
    pub const X: DVec3 = DVec3::new(1.0, 0.0, 0.0);
    /// `(0, 1, 0)`.
    pub const Y: DVec3 = DVec3::new(0.0, 1.0, 0.0);
    /// `(0, 0, 1)`.
    pub const Z: DVec3 = DVec3::new(0.0, 0.0, 1.0);
    /// Every component NaN.
    pub const NAN: DVec3 = DVec3::new(f64::NAN, f64::NAN, f64::NAN);

    /// The vector `(x, y, z)`.
    #[must_use]
    pub const fn new(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3 { x, y, z }
    }

    /// `(v, v, v)`.
    #[must_use]
    pub const fn splat(v: f64) -> DVec3 {
        DVec3::new(v, v, v)
    }

    /// `[x, y, z]`.
    #[must_use]
    pub const fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// The vector of `[x, y, z]`.
    #[must_use]
    pub const fn from_array(a: [f64; 3]) -> DVec3 {
        DVec3::new(a[0], a[1], a[2])
    }

    /// Dot product `a·b = a_x b_x + a_y b_y + a_z b_z`.
    #[must_use]
    pub fn dot(self, other: DVec3) -> f64 {
        self.x * other.x + self.y * other.y + self.z * other.z
    }

    /// Cross product `a × b`.
    #[must_use]
    pub fn cross(self, other: DVec3) -> DVec3 {
        DVec3::new(
            self.y * other.z - self.z * other.y,
            self.z * other.x - self.x * other.z,
            self.x * other.y - self.y * other.x,
        )
    }

    /// `|a|²`.
    #[must_use]
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }

    /// `|a|`.
    #[must_use]
    pub fn length(self) -> f64 {
        self.length_squared().sqrt()
    }

    /// `|a - b|`.
    #[must_use]
    pub fn distance(self, other: DVec3) -> f64 {
        (self - other).length()
    }

    /// `a / |a|`: NaN for the zero vector (as glam).
    #[must_use]
    pub fn normalize(self) -> DVec3 {
        self / self.length()
    }

    /// `a / |a|`, or zero when `|a|` is zero or not finite.
    #[must_use]
    pub fn normalize_or_zero(self) -> DVec3 {
        let l = self.length();
        if l > 0.0 && l.is_finite() {
            self / l
        } else {
            DVec3::ZERO
        }
    }

    /// True when no component is NaN or infinite.
    #[must_use]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// True when some component is NaN.
    #[must_use]
    pub fn is_nan(self) -> bool {
        self.x.is_nan() || self.y.is_nan() || self.z.is_nan()
    }

    /// Component-wise absolute value.
    #[must_use]
    pub fn abs(self) -> DVec3 {
        DVec3::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
}

impl fmt::Display for DVec3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {}, {}]", self.x, self.y, self.z)
    }
}

impl From<[f64; 3]> for DVec3 {
    fn from(a: [f64; 3]) -> DVec3 {
        DVec3::from_array(a)
    }
}

impl From<DVec3> for [f64; 3] {
    fn from(v: DVec3) -> [f64; 3] {
        v.to_array()
    }
}

macro_rules! componentwise {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for DVec3 {
            type Output = DVec3;
            fn $f(self, o: DVec3) -> DVec3 {
                DVec3::new(self.x $op o.x, self.y $op o.y, self.z $op o.z)
            }
        }
        impl $tra for DVec3 {
            fn $fa(&mut self, o: DVec3) {
                *self = *self $op o;
            }
        }
    };
}

componentwise!(Add, add, AddAssign, add_assign, +);
componentwise!(Sub, sub, SubAssign, sub_assign, -);
componentwise!(Mul, mul, MulAssign, mul_assign, *);
componentwise!(Div, div, DivAssign, div_assign, /);

impl Mul<f64> for DVec3 {
    type Output = DVec3;
    fn mul(self, s: f64) -> DVec3 {
        DVec3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Mul<DVec3> for f64 {
    type Output = DVec3;
    fn mul(self, v: DVec3) -> DVec3 {
        v * self
    }
}

impl MulAssign<f64> for DVec3 {
    fn mul_assign(&mut self, s: f64) {
        *self = *self * s;
    }
}

impl Div<f64> for DVec3 {
    type Output = DVec3;
    fn div(self, s: f64) -> DVec3 {
        DVec3::new(self.x / s, self.y / s, self.z / s)
    }
}

impl DivAssign<f64> for DVec3 {
    fn div_assign(&mut self, s: f64) {
        *self = *self / s;
    }
}

impl Neg for DVec3 {
    type Output = DVec3;
    fn neg(self) -> DVec3 {
        DVec3::new(-self.x, -self.y, -self.z)
    }
}

impl Index<usize> for DVec3 {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("DVec3 index {i} out of range (0, 1 or 2)"),
        }
    }
}

impl IndexMut<usize> for DVec3 {
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        match i {
            0 => &mut self.x,
            1 => &mut self.y,
            2 => &mut self.z,
            _ => panic!("DVec3 index {i} out of range (0, 1 or 2)"),
        }
    }
}

impl Sum for DVec3 {
    fn sum<I: Iterator<Item = DVec3>>(iter: I) -> DVec3 {
        iter.fold(DVec3::ZERO, |a, b| a + b)
    }
}

impl<'a> Sum<&'a DVec3> for DVec3 {
    fn sum<I: Iterator<Item = &'a DVec3>>(iter: I) -> DVec3 {
        iter.fold(DVec3::ZERO, |a, b| a + *b)
    }
}

#[cfg(test)]
mod tests {
    use super::DVec3;

    #[test]
    fn arithmetic_matches_the_formulas() {
        let a = DVec3::new(1.0, 2.0, 3.0);
        let b = DVec3::new(-2.0, 0.5, 4.0);
        assert_eq!(a + b, DVec3::new(-1.0, 2.5, 7.0));
        assert_eq!(a - b, DVec3::new(3.0, 1.5, -1.0));
        assert_eq!(2.0 * a, a * 2.0);
        assert_eq!(a / 2.0, DVec3::new(0.5, 1.0, 1.5));
        assert_eq!(a.dot(b), -2.0 + 1.0 + 12.0);
        // a × b is perpendicular to both.
        let c = a.cross(b);
        assert_eq!(c.dot(a), 0.0);
        assert_eq!(c.dot(b), 0.0);
        assert_eq!(DVec3::new(3.0, 4.0, 0.0).length(), 5.0);
        assert!(DVec3::ZERO.normalize().is_nan());
        assert_eq!(DVec3::ZERO.normalize_or_zero(), DVec3::ZERO);
        assert_eq!([a, b].iter().sum::<DVec3>(), a + b);
        assert_eq!(a[2], 3.0);
    }
}
