//! Ray–capsule intersection: a capsule is the set of points within `r` of the segment
//! `[a, b]` (a cylinder with two half-ball caps), the shape of one fiber segment.
//!
//! **Entry only.** [`entry`] returns where a ray *enters* the capsule: `t` of the first
//! point of the ray inside it. A ray whose origin lies inside the capsule has no entry and
//! is never reported: the renderer spawns rays from a fiber's axis (fiber BCSDF) or from
//! just outside its surface (Lambert), and this rule is what keeps them from hitting the
//! fiber they leave. The entry into a union of convex pieces is the smallest entry of its
//! pieces, so the capsule's is the minimum of the infinite cylinder's near root (kept where
//! it lies between the two end planes) and the two balls' near roots.
//!
//! **Robustness** (DESIGN §4.4). Everything is in `f64`. The ray origin is first moved to
//! the point of the ray closest to the segment's midpoint, so the quadratics are solved
//! with lengths of the capsule's size, not of the camera distance (a 5 µm fiber seen from
//! 10 cm away would otherwise lose every digit of `r²` in `|o − a|² − r²`). A ray parallel
//! to the axis (grazing along it: the cylinder's quadratic degenerates) is caught by the
//! caps; a zero-length segment is a ball; a zero or negative radius never hits.

use yarn::vec3::{self, V3};

/// An entry point: ray distance and the position along the segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CapsuleHit {
    /// Ray distance (in units of the ray direction's length; directions are unit here).
    pub t: f64,
    /// `v ∈ [0, 1]`: the hit's projection onto the segment, 0 at `a`, 1 at `b`.
    pub v: f64,
}

/// Squared distance from `p` to the segment `[a, b]`, and the segment parameter of the
/// closest point.
#[inline]
pub fn segment_distance2(a: V3, b: V3, p: V3) -> (f64, f64) {
    let ba = vec3::sub(b, a);
    let pa = vec3::sub(p, a);
    let baba = vec3::dot(ba, ba);
    let v = if baba > 0.0 { (vec3::dot(pa, ba) / baba).clamp(0.0, 1.0) } else { 0.0 };
    let d = vec3::sub(pa, vec3::scale(ba, v));
    (vec3::dot(d, d), v)
}

/// The entry of the ray `o + t·d` (`d` unit) into the capsule `(a, b, r)` with
/// `t_min < t < t_max`, or `None` (a miss, or the origin is inside).
pub fn entry(a: V3, b: V3, r: f64, o: V3, d: V3, t_min: f64, t_max: f64) -> Option<CapsuleHit> {
    if r <= 0.0 || r.is_nan() {
        return None;
    }
    let r2 = r * r;
    if segment_distance2(a, b, o).0 < r2 {
        return None;
    }
    // Re-centre on the ray point closest to the midpoint.
    let m = vec3::scale(vec3::add(a, b), 0.5);
    let t0 = vec3::dot(vec3::sub(m, o), d);
    let o2 = vec3::add_scaled(o, d, t0);
    let ba = vec3::sub(b, a);
    let baba = vec3::dot(ba, ba);
    let mut best = f64::INFINITY;
    if baba > 0.0 {
        let oa = vec3::sub(o2, a);
        let bard = vec3::dot(ba, d);
        let baoa = vec3::dot(ba, oa);
        let rdoa = vec3::dot(d, oa);
        let oaoa = vec3::dot(oa, oa);
        let k2 = baba - bard * bard;
        // k2 = |ba|² sin² of the ray–axis angle; below ~1e-12 the cylinder root is lost in
        // rounding and the ray runs along the axis: the caps decide.
        if k2 > 1e-12 * baba {
            let k1 = baba * rdoa - baoa * bard;
            let k0 = baba * oaoa - baoa * baoa - r2 * baba;
            let h = k1 * k1 - k2 * k0;
            if h >= 0.0 {
                let t = (-k1 - h.sqrt()) / k2;
                let y = baoa + t * bard;
                if (0.0..=baba).contains(&y) {
                    best = t;
                }
            }
        }
    }
    for c in [a, b] {
        let oc = vec3::sub(o2, c);
        let bb = vec3::dot(d, oc);
        let cc = vec3::dot(oc, oc) - r2;
        let h = bb * bb - cc;
        if h >= 0.0 {
            let t = -bb - h.sqrt();
            if t < best {
                best = t;
            }
        }
        if baba == 0.0 {
            break;
        }
    }
    let t = t0 + best;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let p = vec3::add_scaled(o, d, t);
    let v = if baba > 0.0 { (vec3::dot(vec3::sub(p, a), ba) / baba).clamp(0.0, 1.0) } else { 0.0 };
    Some(CapsuleHit { t, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: V3 = [0.0, 0.0, 0.0];
    const B: V3 = [1.0, 0.0, 0.0];

    #[test]
    fn perpendicular_ray_hits_the_cylinder_at_distance_minus_radius() {
        let h = entry(A, B, 0.25, [0.5, 0.0, 3.0], [0.0, 0.0, -1.0], 0.0, 10.0).unwrap();
        assert!((h.t - 2.75).abs() < 1e-14 && (h.v - 0.5).abs() < 1e-14);
        // Offset by y = 0.2: the entry is at z = √(0.25² − 0.2²) = 0.15.
        let h = entry(A, B, 0.25, [0.3, 0.2, 3.0], [0.0, 0.0, -1.0], 0.0, 10.0).unwrap();
        assert!((h.t - (3.0 - 0.15)).abs() < 1e-14);
        assert!(entry(A, B, 0.25, [0.3, 0.26, 3.0], [0.0, 0.0, -1.0], 0.0, 10.0).is_none());
        // t_max and t_min are exclusive bounds.
        assert!(entry(A, B, 0.25, [0.5, 0.0, 3.0], [0.0, 0.0, -1.0], 0.0, 2.7).is_none());
        assert!(entry(A, B, 0.25, [0.5, 0.0, 3.0], [0.0, 0.0, -1.0], 2.8, 9.0).is_none());
    }

    #[test]
    fn caps_catch_rays_along_the_axis_and_beyond_the_ends() {
        // Exactly along the axis: the cylinder quadratic degenerates, the ball at a hits.
        let h = entry(A, B, 0.25, [-2.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, 10.0).unwrap();
        assert!((h.t - 1.75).abs() < 1e-14 && h.v == 0.0);
        // Beyond the end b, from above: the cap's top at x = 1.1 is at √(0.25² − 0.1²).
        let h = entry(A, B, 0.25, [1.1, 0.0, 1.0], [0.0, 0.0, -1.0], 0.0, 10.0).unwrap();
        assert!((h.t - (1.0 - (0.0625f64 - 0.01).sqrt())).abs() < 1e-14 && h.v == 1.0);
        // A zero-length segment is a ball.
        let h = entry(A, A, 0.5, [0.0, 0.0, 2.0], [0.0, 0.0, -1.0], 0.0, 10.0).unwrap();
        assert!((h.t - 1.5).abs() < 1e-14);
        assert!(entry(A, B, 0.0, [0.5, 0.0, 2.0], [0.0, 0.0, -1.0], 0.0, 10.0).is_none());
        assert!(entry(A, B, f64::NAN, [0.5, 0.0, 2.0], [0.0, 0.0, -1.0], 0.0, 10.0).is_none());
    }

    #[test]
    fn origin_inside_or_on_the_surface_never_hits() {
        assert!(entry(A, B, 0.25, [0.5, 0.0, 0.0], [0.0, 0.0, 1.0], 0.0, 10.0).is_none());
        assert!(entry(A, B, 0.25, [0.5, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, 10.0).is_none());
        // On the surface, leaving outwards.
        assert!(entry(A, B, 0.25, [0.5, 0.0, 0.25], [0.0, 0.6, 0.8], 0.0, 10.0).is_none());
    }

    #[test]
    fn a_tiny_fiber_far_away_keeps_its_digits() {
        // A 5 µm fiber seen from 10 cm: the entry is 10 cm − 5 µm to 1e-12 relative.
        let (a, b, r) = ([0.0, 0.0, 0.0], [1e-4, 0.0, 0.0], 5e-6);
        let o = [5e-5, 0.0, 0.1];
        let h = entry(a, b, r, o, [0.0, 0.0, -1.0], 0.0, 1.0).unwrap();
        assert!((h.t - (0.1 - 5e-6)).abs() < 1e-15, "{}", h.t - (0.1 - 5e-6));
        // Grazing the silhouette: at offset 0.999 r the entry depth is r·√(1 − 0.999²).
        let o = [5e-5, 0.999 * r, 0.1];
        let h = entry(a, b, r, o, [0.0, 0.0, -1.0], 0.0, 1.0).unwrap();
        let want = 0.1 - r * (1.0f64 - 0.999 * 0.999).sqrt();
        assert!((h.t - want).abs() < 1e-13 * 0.1 + 1e-3 * r * 0.045, "{}", h.t - want);
        let o = [5e-5, 1.001 * r, 0.1];
        assert!(entry(a, b, r, o, [0.0, 0.0, -1.0], 0.0, 1.0).is_none());
    }

    #[test]
    fn oblique_rays_agree_with_brute_force_marching() {
        // A diagonal capsule; rays from many directions against a fine march of the
        // distance function (step 1e-5, so the entry is known to 1e-5).
        let (a, b, r) = ([0.1, -0.2, 0.3], [0.7, 0.4, -0.1], 0.15);
        let mut rng = crate::rng::Rng::new(&[7]);
        for _ in 0..200 {
            let [u1, u2, u3] = rng.uniform3();
            let z = 2.0 * u1 - 1.0;
            let phi = std::f64::consts::TAU * u2;
            let s = (1.0 - z * z).sqrt();
            let d = [s * phi.cos(), s * phi.sin(), z];
            let target = [0.4 + 0.3 * (u3 - 0.5), 0.1, 0.1];
            let o = vec3::add_scaled(target, d, -2.0);
            let got = entry(a, b, r, o, d, 0.0, 10.0).map(|h| h.t);
            let mut want = None;
            let mut t = 0.0;
            while t < 4.0 {
                if segment_distance2(a, b, vec3::add_scaled(o, d, t)).0 < r * r {
                    want = Some(t);
                    break;
                }
                t += 1e-5;
            }
            match (got, want) {
                (Some(g), Some(w)) => assert!((g - w).abs() < 2e-5, "{g} vs {w}"),
                (None, None) => {}
                (g, w) => {
                    // Only a ray grazing within the march step may disagree.
                    let closest = (0..400_000)
                        .map(|i| segment_distance2(a, b, vec3::add_scaled(o, d, i as f64 * 1e-5)).0)
                        .fold(f64::INFINITY, f64::min);
                    assert!((closest.sqrt() - r).abs() < 1e-4, "{g:?} vs {w:?}");
                }
            }
        }
    }
}
