//! Geometry of the hemicube faces for the rasteriser of [`super::raster`] (Sattler et al.
//! 2003, §5.2): which face pyramid holds a tangent-space point, the face-coordinate bounds
//! of a triangle clipped to a pyramid (Sutherland–Hodgman against the planes through the
//! origin), of a box (`q / m` ranges), and the pixel masks of a rectangle of pixels.
//!
//! Face coordinates follow [`crate::hemicube`]: the face with major axis `m` and sign `s`
//! maps a direction `p` to `u = p_u / (s p_m)`, `v = p_v / (s p_m)`.

use super::bvh::dot;
use crate::hemicube::Face;

/// Inclusive pixel rectangle on one face.
#[derive(Debug, Clone, Copy)]
pub(super) struct Rect {
    pub(super) face: usize,
    pub(super) c0: usize,
    pub(super) c1: usize,
    pub(super) r0: usize,
    pub(super) r1: usize,
}

/// Range of `q / m` over `q ∈ [q0, q1]`, `m ∈ (max(m0, 0), m1]` (`m1 > 0`).
pub(super) fn ratio_range(q0: f32, q1: f32, m0: f32, m1: f32) -> (f32, f32) {
    let ml = m0.max(0.0);
    let lo = if q0 >= 0.0 {
        q0 / m1
    } else if ml > 0.0 {
        q0 / ml
    } else {
        f32::NEG_INFINITY
    };
    let hi = if q1 <= 0.0 {
        q1 / m1
    } else if ml > 0.0 {
        q1 / ml
    } else {
        f32::INFINITY
    };
    (lo, hi)
}

/// The face whose pyramid holds tangent point `p` with room `tol` to its planes.
pub(super) fn face_of(p: &[f32; 3], tol: f32) -> Option<usize> {
    let [x, y, z] = *p;
    let (ax, ay) = (x.abs(), y.abs());
    if z - ax > tol && z - ay > tol {
        return Some(0);
    }
    if z <= tol {
        return None;
    }
    if ax - ay > tol && ax - z > tol {
        return Some(if x > 0.0 { 1 } else { 2 });
    }
    if ay - ax > tol && ay - z > tol {
        return Some(if y > 0.0 { 3 } else { 4 });
    }
    None
}

/// Bounds in face coordinates of the part of the triangle inside `face`'s pyramid (planes
/// widened by `tol`).
pub(super) fn face_bounds(
    face: &Face,
    corners: &[[f32; 3]; 3],
    tol: f32,
) -> Option<((f32, f32), (f32, f32))> {
    let s = face.sign;
    // Planes through the origin bounding the face's pyramid: value ≥ 0 inside.
    let planes: [[f32; 3]; 5] = {
        let mut p = [[0f32; 3]; 5];
        for (k, (axis, sg)) in
            [(face.u, 1.0), (face.u, -1.0), (face.v, 1.0), (face.v, -1.0), (2, 0.0)]
                .into_iter()
                .enumerate()
        {
            if k < 4 {
                p[k][face.major] = s;
                p[k][axis] -= sg;
            } else {
                p[k][2] = 1.0;
            }
        }
        p
    };
    let mut poly = [[0f32; 3]; 12];
    poly[..3].copy_from_slice(corners);
    let mut n = 3;
    for plane in &planes {
        let val = |p: &[f32; 3]| dot(*p, *plane) + tol;
        if poly[..n].iter().all(|p| val(p) >= 0.0) {
            continue;
        }
        if poly[..n].iter().all(|p| val(p) < 0.0) {
            return None;
        }
        let mut out = [[0f32; 3]; 12];
        let mut m = 0;
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (va, vb) = (val(&a), val(&b));
            if va >= 0.0 {
                out[m] = a;
                m += 1;
            }
            if (va >= 0.0) != (vb >= 0.0) && m < 12 {
                let w = va / (va - vb);
                out[m] = [0, 1, 2].map(|k| a[k] + w * (b[k] - a[k]));
                m += 1;
            }
        }
        poly = out;
        n = m;
    }
    let (mut u, mut v) = ((f32::MAX, f32::MIN), (f32::MAX, f32::MIN));
    for p in &poly[..n] {
        let m = s * p[face.major];
        if m <= 4.0 * tol {
            // A point next to the origin: any direction of the face.
            return Some(((-1.0, 1.0), (face.v_min, 1.0)));
        }
        let (pu, pv) = (p[face.u] / m, p[face.v] / m);
        u = (u.0.min(pu), u.1.max(pu));
        v = (v.0.min(pv), v.1.max(pv));
    }
    (n > 0).then_some((u, v))
}

/// Distance from the tangent-space `z` axis to the box `lo..hi` (0 when it crosses it).
pub(super) fn xy_distance(lo: &[f32; 3], hi: &[f32; 3]) -> f32 {
    let gap = |a: usize| lo[a].max(-hi[a]).max(0.0);
    // In f64: no libm call, no overflow (callers keep a 10 % safety factor).
    let (x, y) = (gap(0) as f64, gap(1) as f64);
    (x * x + y * y).sqrt() as f32
}

/// Bits `a..=b` of a word (`a ≤ b < 64`).
pub(super) fn span_mask(a: usize, b: usize) -> u64 {
    (u64::MAX >> (63 - b)) & (u64::MAX << a)
}
