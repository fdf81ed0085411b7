//! The rim of a bowl: the one place that says where a bowl collider ends.
//!
//! A bowl ([`super::collide::Collider::Bowl`]) is the inside of a sphere of centre `c` and
//! radius `r` (m) below a horizontal cut at `rim_height` (m). The cut is at most the sphere's
//! equator, so a bowl is at most a hemisphere, and its rim is the circle
//!
//! ```text
//! y   = min(rim_height, c_y)
//! a²  = r² − (c_y − y)²
//! ```
//! where `y` is the height of the rim (m) and `a` its radius (m), centred on the vertical axis
//! through `c`. The collision test, the renderer's mesh and bounds and the terminal drawing all
//! read the rim from here.

use glam::DVec3;

/// The rim circle of a bowl.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rim {
    /// Height of the rim, `min(rim_height, c_y)` (m).
    pub height: f64,
    /// `a² = r² − (c_y − height)²` (m²); negative when the cut lies below the sphere.
    pub radius_squared: f64,
}

impl Rim {
    /// The rim of the bowl cut from the sphere (`center`, `radius`, m) at `rim_height` (m).
    #[must_use]
    pub fn of(center: DVec3, radius: f64, rim_height: f64) -> Rim {
        let height = rim_height.min(center.y);
        Rim {
            height,
            radius_squared: radius * radius - (center.y - height).powi(2),
        }
    }

    /// The rim's radius `a` (m), 0 when the cut misses the sphere.
    #[must_use]
    pub fn radius(&self) -> f64 {
        self.radius_squared.max(0.0).sqrt()
    }

    /// The rim's centre, on the vertical axis through the sphere's `center`.
    #[must_use]
    pub fn center(&self, center: DVec3) -> DVec3 {
        DVec3::new(center.x, self.height, center.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_at_or_above_the_centre_leaves_a_hemisphere() {
        let c = DVec3::new(2.0, 7.0, 1.0);
        for cut in [7.0, 9.0] {
            let rim = Rim::of(c, 7.0, cut);
            assert_eq!(rim.height, 7.0);
            assert_eq!(rim.radius(), 7.0);
            assert_eq!(rim.center(c), c);
        }
    }

    #[test]
    fn the_2023_bowl_meets_the_floor_hole() {
        // Radius 9 centred at height 9/√2, cut at y = 0: the rim is the hole of radius 9/√2.
        let h = 9.0 / 2f64.sqrt();
        let rim = Rim::of(DVec3::new(2.0, h, 1.0), 9.0, 0.0);
        assert_eq!(rim.height, 0.0);
        assert!((rim.radius() - h).abs() < 1e-12, "{}", rim.radius());
    }

    #[test]
    fn a_cut_below_the_sphere_has_no_rim() {
        let rim = Rim::of(DVec3::ZERO, 1.0, -2.0);
        assert!(rim.radius_squared < 0.0);
        assert_eq!(rim.radius(), 0.0);
    }
}
