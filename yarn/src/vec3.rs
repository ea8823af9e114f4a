//! Small `f64` vector helpers on `[f64; 3]` (no linear-algebra crate: the crate needs only
//! dot and cross products, rotations about an axis and normalisation with a fallback).

/// A 3-vector (metres for positions, unitless for directions).
pub type V3 = [f64; 3];

/// `a + b`.
#[inline]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a − b`.
#[inline]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `s·a`.
#[inline]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `a + s·b`.
#[inline]
pub fn add_scaled(a: V3, b: V3, s: f64) -> V3 {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

/// `a·b`.
#[inline]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b`.
#[inline]
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `‖a‖`.
#[inline]
pub fn length(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `‖a − b‖`.
#[inline]
pub fn distance(a: V3, b: V3) -> f64 {
    length(sub(a, b))
}

/// `a/‖a‖`, or `None` when `‖a‖` is zero or not finite.
#[inline]
pub fn normalize(a: V3) -> Option<V3> {
    let l = length(a);
    (l > 0.0 && l.is_finite()).then(|| scale(a, 1.0 / l))
}

/// `a/‖a‖`, or `fallback` when `a` has no direction.
#[inline]
pub fn normalize_or(a: V3, fallback: V3) -> V3 {
    normalize(a).unwrap_or(fallback)
}

/// The part of `v` perpendicular to the unit vector `t`.
#[inline]
pub fn reject(v: V3, t: V3) -> V3 {
    add_scaled(v, t, -dot(v, t))
}

/// Rotates `v` by `angle` (radians, right-handed) about the unit `axis` (Rodrigues).
pub fn rotate(v: V3, axis: V3, angle: f64) -> V3 {
    let (s, c) = angle.sin_cos();
    let k_x_v = cross(axis, v);
    let k_d_v = dot(axis, v);
    [
        v[0] * c + k_x_v[0] * s + axis[0] * k_d_v * (1.0 - c),
        v[1] * c + k_x_v[1] * s + axis[1] * k_d_v * (1.0 - c),
        v[2] * c + k_x_v[2] * s + axis[2] * k_d_v * (1.0 - c),
    ]
}

/// The signed angle (radians, in `(−π, π]`) that rotates `a` onto `b` about the unit
/// `axis`, both taken perpendicular to it.
pub fn signed_angle(a: V3, b: V3, axis: V3) -> f64 {
    dot(cross(a, b), axis).atan2(dot(a, b))
}

/// Any unit vector perpendicular to the unit `t`: world `+z` made perpendicular, or `+x`
/// where `t` is within 18° of `±z` (z-up world: the natural "up" first).
pub fn any_perpendicular(t: V3) -> V3 {
    let up = if t[2].abs() < 0.95 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
    normalize_or(reject(up, t), [0.0, 1.0, 0.0])
}

/// Linear interpolation `a + (b − a)·t`.
#[inline]
pub fn lerp(a: V3, b: V3, t: f64) -> V3 {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// True when every component is finite.
#[inline]
pub fn is_finite(a: V3) -> bool {
    a.iter().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_and_signed_angle_agree() {
        let axis = [0.0, 0.0, 1.0];
        let v = [1.0, 0.0, 0.0];
        for k in -7..=7 {
            let a = k as f64 * 0.4;
            let w = rotate(v, axis, a);
            let back = signed_angle(v, w, axis);
            let wrapped =
                (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            assert!((back - wrapped).abs() < 1e-12, "{a}: {back} vs {wrapped}");
            assert!((length(w) - 1.0).abs() < 1e-15);
        }
        let p = any_perpendicular([0.0, 0.0, 1.0]);
        assert!(dot(p, [0.0, 0.0, 1.0]).abs() < 1e-15 && (length(p) - 1.0).abs() < 1e-15);
    }
}
