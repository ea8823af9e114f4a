//! Arc length of a `YarnCurve` by adaptive Gauss–Legendre quadrature of `‖C'(u)‖` per
//! segment (the speed is smooth inside a segment, so the 7-point rule against its two
//! halves converges fast; segment boundaries, where C² breaks, are never inside a panel),
//! the rest length coordinate (cumulative arc length at the control points, [W19 §5]), and
//! the inverse map from a length coordinate to the curve parameter.

use super::YarnCurve;
use crate::quad;
use crate::vec3;

/// Relative tolerance of the arc-length quadrature (per segment, against its chord-ish
/// length scale).
const REL_TOL: f64 = 1e-13;

impl YarnCurve {
    /// Arc length of segment `seg` (virtual index on closed curves) between local
    /// parameters `t0 ≤ t1` in `[0, 1]`.
    fn segment_arc(&self, seg: isize, t0: f64, t1: f64) -> f64 {
        if t1 <= t0 {
            return 0.0;
        }
        let w = [-1, 0, 1, 2].map(|d| self.control_point(seg + d));
        let speed = |t: f64| vec3::length(super::combine(&w, super::basis_d1(t)));
        let scale = vec3::distance(w[1], w[2]) + vec3::distance(w[0], w[3]) + 1e-300;
        quad::adaptive(t0, t1, REL_TOL * scale, speed)
    }

    /// Arc length between parameters `u0` and `u1` (signed: negative if `u1 < u0`).
    pub fn arc_length(&self, u0: f64, u1: f64) -> f64 {
        if u1 < u0 {
            return -self.arc_length(u1, u0);
        }
        let (u0, u1) = if self.closed {
            (u0, u1)
        } else {
            let m = self.segment_count() as f64;
            (u0.clamp(0.0, m), u1.clamp(0.0, m))
        };
        let (mut s, mut t) = (u0.floor(), u0 - u0.floor());
        let mut total = 0.0;
        while s < u1 {
            let t_end = (u1 - s).min(1.0);
            total += self.segment_arc(s as isize, t, t_end);
            s += 1.0;
            t = 0.0;
        }
        total
    }

    /// Length of segment `i`.
    pub fn segment_length(&self, i: usize) -> f64 {
        self.segment_arc(i as isize, 0.0, 1.0)
    }

    /// Total length (one period for a closed curve).
    pub fn length(&self) -> f64 {
        (0..self.segment_count()).map(|i| self.segment_length(i)).sum()
    }

    /// Sets the length coordinates to the rest arc length from the first control point
    /// (and `length_wrap` to the period length of a closed curve).
    pub fn set_rest_length_coords(&mut self) {
        let n = self.points.len();
        let mut z = 0.0;
        self.length_coords[0] = 0.0;
        for i in 0..n - 1 {
            z += self.segment_length(i);
            self.length_coords[i + 1] = z;
        }
        self.length_wrap = if self.closed { z + self.segment_length(n - 1) } else { 0.0 };
    }

    /// The curve parameter `u` whose length coordinate is `z`. Closed curves wrap (any
    /// `z`); open curves return `None` outside `[z_0, z_{n−1}]`. Inside a segment the
    /// cubic z(t) is solved by safeguarded Newton iteration (bisection on the bracket).
    pub fn param_at_length_coord(&self, z: f64) -> Option<f64> {
        let n = self.points.len();
        let (z, base) = if self.closed {
            let w = self.length_wrap;
            if w <= 0.0 {
                return None;
            }
            let k = ((z - self.length_coords[0]) / w).floor();
            (z - k * w, k * self.segment_count() as f64)
        } else {
            if z < self.length_coords[0] || z > self.length_coords[n - 1] {
                return None;
            }
            (z, 0.0)
        };
        // The segment whose end values bracket z.
        let seg_count = self.segment_count() as isize;
        let mut lo = 0isize;
        let mut hi = seg_count - 1;
        while lo < hi {
            let mid = (lo + hi + 1) / 2;
            if self.length_coord_at(mid) <= z { lo = mid } else { hi = mid - 1 }
        }
        let seg = lo;
        let (za, zb) = (self.length_coord_at(seg), self.length_coord_at(seg + 1));
        if zb <= za {
            return Some(base + seg as f64);
        }
        let (mut a, mut b) = (0.0, 1.0);
        let mut t = ((z - za) / (zb - za)).clamp(0.0, 1.0);
        for _ in 0..60 {
            let u = seg as f64 + t;
            let f = self.length_coord(u) - z;
            if f.abs() <= 1e-15 * zb.abs().max(1e-300) {
                break;
            }
            if f > 0.0 {
                b = t
            } else {
                a = t
            }
            let d = self.length_coord_derivative(u);
            let newton = t - f / d;
            t = if d > 0.0 && newton > a && newton < b { newton } else { 0.5 * (a + b) };
            if b - a < 1e-16 {
                break;
            }
        }
        Some(base + seg as f64 + t)
    }
}
