//! The uniform Catmull–Rom basis (cardinal spline of tension 0, the BCC `C0` type) and its
//! first two derivatives, and the weighted sum of a window of four control points.

use crate::vec3::{self, V3};

/// Catmull–Rom weights of `P_{i−1}, P_i, P_{i+1}, P_{i+2}` at `t`.
#[inline]
pub fn basis(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// First derivatives of [`basis`].
#[inline]
pub fn basis_d1(t: f64) -> [f64; 4] {
    let t2 = t * t;
    [
        0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
        0.5 * (9.0 * t2 - 10.0 * t),
        0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
        0.5 * (3.0 * t2 - 2.0 * t),
    ]
}

/// Second derivatives of [`basis`].
#[inline]
pub fn basis_d2(t: f64) -> [f64; 4] {
    [
        0.5 * (-6.0 * t + 4.0),
        0.5 * (18.0 * t - 10.0),
        0.5 * (-18.0 * t + 8.0),
        0.5 * (6.0 * t - 2.0),
    ]
}

/// `Σ w_j p_j`, computed as `(Σ w_j)·p_1 + Σ w_j (p_j − p_1)`: the derivative weights sum
/// to zero, so coincident points give an exactly zero derivative (no rounding noise for
/// the tangent fallback and the arc-length quadrature to chase), and positions lose no
/// digits far from the origin.
#[inline]
pub(crate) fn combine(p: &[V3; 4], w: [f64; 4]) -> V3 {
    // Position weights sum to 1, derivative weights to 0 (up to rounding).
    let sum = w[0] + w[1] + w[2] + w[3];
    let base_weight = if sum.abs() > 0.5 { sum } else { 0.0 };
    let mut r = vec3::scale(p[1], base_weight);
    for j in [0, 2, 3] {
        for a in 0..3 {
            r[a] += w[j] * (p[j][a] - p[1][a]);
        }
    }
    r
}
