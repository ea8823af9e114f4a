//! Directions on the hemisphere in tangent space and their spherical angles.
//!
//! Convention (DESIGN.md §3): `+x` along texture `+u`, `+y` along increasing row, `+z` the
//! surface normal; `θ` is measured from `+z`, `φ` from `+x` towards `+y` in `[0°, 360°)`.
//! At the pole `φ` is undefined and reported as 0; a direction exactly at 360° is folded
//! to 0°.

use serde::{Deserialize, Serialize};

/// A direction given by its polar angle `theta_deg` (from the normal) and its azimuth
/// `phi_deg` (from `+x` towards `+y`), both in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Direction {
    /// Polar angle from `+z`, degrees, `[0, 180]`.
    pub theta_deg: f64,
    /// Azimuth from `+x` towards `+y`, degrees, `[0, 360)`.
    pub phi_deg: f64,
}

/// Folds an azimuth in degrees into `[0, 360)`.
pub fn wrap_phi_deg(phi_deg: f64) -> f64 {
    let p = phi_deg.rem_euclid(360.0);
    // rem_euclid may return exactly 360.0 for tiny negative inputs through rounding.
    if p >= 360.0 { 0.0 } else { p }
}

impl Direction {
    /// A direction from angles in degrees; `phi_deg` is wrapped into `[0, 360)`.
    pub fn new(theta_deg: f64, phi_deg: f64) -> Self {
        Direction { theta_deg, phi_deg: wrap_phi_deg(phi_deg) }
    }

    /// The unit vector in tangent space.
    pub fn to_vector(self) -> [f64; 3] {
        let (st, ct) = self.theta_deg.to_radians().sin_cos();
        let (sp, cp) = self.phi_deg.to_radians().sin_cos();
        [st * cp, st * sp, ct]
    }

    /// The direction of a tangent-space vector (need not be normalised). `None` for a zero
    /// or non-finite vector.
    pub fn from_vector(v: [f64; 3]) -> Option<Self> {
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if !(len.is_finite() && len > 0.0) {
            return None;
        }
        let z = (v[2] / len).clamp(-1.0, 1.0);
        let theta_deg = z.acos().to_degrees();
        let rho = (v[0] * v[0] + v[1] * v[1]).sqrt();
        let phi_deg = if rho <= len * 1e-15 { 0.0 } else { v[1].atan2(v[0]).to_degrees() };
        Some(Direction::new(theta_deg, phi_deg))
    }

    /// Cosine of the polar angle (the `z` component of the unit vector).
    pub fn cos_theta(self) -> f64 {
        self.theta_deg.to_radians().cos()
    }

    /// Angle between two directions in degrees.
    pub fn angle_to_deg(self, other: Direction) -> f64 {
        let a = self.to_vector();
        let b = other.to_vector();
        let d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).clamp(-1.0, 1.0);
        d.acos().to_degrees()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_vector_angles() {
        for &(t, p) in &[(0.0, 0.0), (30.0, 45.0), (75.0, 359.9), (89.999, 180.0), (120.0, 10.0)] {
            let d = Direction::new(t, p);
            let back = Direction::from_vector(d.to_vector()).unwrap();
            assert!((back.theta_deg - t).abs() < 1e-9, "{t} {p} -> {back:?}");
            if t > 0.0 {
                let dp = (back.phi_deg - p).abs();
                assert!(dp < 1e-9 || (360.0 - dp) < 1e-9, "{t} {p} -> {back:?}");
            }
        }
    }

    #[test]
    fn phi_360_folds_to_zero_and_pole_has_phi_zero() {
        assert_eq!(Direction::new(30.0, 360.0).phi_deg, 0.0);
        assert_eq!(Direction::new(30.0, -1e-300).phi_deg, 0.0);
        let pole = Direction::from_vector([0.0, 0.0, 2.0]).unwrap();
        assert_eq!((pole.theta_deg, pole.phi_deg), (0.0, 0.0));
        assert!(Direction::from_vector([0.0, 0.0, 0.0]).is_none());
        assert!(Direction::from_vector([f64::NAN, 0.0, 1.0]).is_none());
    }

    #[test]
    fn axes_follow_the_tangent_convention() {
        // +x is phi = 0, +y is phi = 90.
        let x = Direction::from_vector([1.0, 0.0, 0.0]).unwrap();
        let y = Direction::from_vector([0.0, 1.0, 0.0]).unwrap();
        assert_eq!((x.theta_deg, x.phi_deg), (90.0, 0.0));
        assert!((y.phi_deg - 90.0).abs() < 1e-12);
    }
}
