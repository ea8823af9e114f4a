//! Coulomb friction in velocity form, Chen et al. 2003 §4.1.3 ([C03 eq. 3]): during a step
//! of `dt`, a node pressed with normal force `F_n` may lose at most `K_d |F_n| dt / m` of
//! its tangential speed (dynamic friction); if its tangential speed is below
//! `K_s |F_n| dt / m` it sticks (static friction). Applied to the velocity so that friction
//! can stop a node but never reverse it, which an explicit force cannot promise.

use crate::vec3::{V3, dot, length, scale, sub};

/// Coefficients of friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// Static coefficient `K_s`.
    pub static_coef: f64,
    /// Dynamic coefficient `K_d`.
    pub dynamic_coef: f64,
}

impl Friction {
    /// The velocity `v` (relative to the surface) after friction against a surface of unit
    /// normal `n` pressing with `normal_force` (N) on mass `m` for `dt`.
    pub fn apply(&self, v: V3, n: V3, normal_force: f64, m: f64, dt: f64) -> V3 {
        let vn = dot(v, n);
        let vt = sub(v, scale(n, vn));
        let speed = length(vt);
        let budget = normal_force * dt / m;
        if speed <= self.static_coef * budget {
            return scale(n, vn);
        }
        let keep = (1.0 - self.dynamic_coef * budget / speed).max(0.0);
        sub(v, scale(vt, 1.0 - keep))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticks_below_the_static_threshold_and_slows_above() {
        let f = Friction { static_coef: 1.0, dynamic_coef: 0.5 };
        let n = [0.0, 0.0, 1.0];
        // Budget: F dt / m = 1 × 0.01 / 0.1 = 0.1 m/s.
        let v = f.apply([0.05, 0.0, 0.2], n, 1.0, 0.1, 0.01);
        assert_eq!(v, [0.0, 0.0, 0.2]);
        let v = f.apply([1.0, 0.0, 0.0], n, 1.0, 0.1, 0.01);
        assert!((v[0] - 0.95).abs() < 1e-12, "{v:?}");
    }
}
