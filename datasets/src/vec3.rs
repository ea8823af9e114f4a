//! Minimal 3-vector helpers on `[f64; 3]` shared by the generators (no linear-algebra crate
//! is needed for the few operations used here).

/// A 3-vector.
pub type V3 = [f64; 3];

/// Dot product.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// Cross product.
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
/// Sum.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// Difference `a - b`.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// Scaled vector.
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Euclidean length.
pub fn length(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// Unit vector along `a`; `fallback` when `a` is zero or not finite.
pub fn normalize_or(a: V3, fallback: V3) -> V3 {
    let l = length(a);
    if l.is_finite() && l > 1e-300 { scale(a, 1.0 / l) } else { fallback }
}
