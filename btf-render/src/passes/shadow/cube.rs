//! Cube shadow maps for point lights inside the scene (`[S03 §4.3]` name shadow maps as the
//! alternative to shadow volumes; a single frustum cannot see all around a light
//! that sits among the cloth). Six 90° faces, each a layer of the shadow-map array, looked
//! up in the BTF pass by the major axis of `world − light` (`cube_map_visibility` in
//! `btf/btf_pass.wgsl`, which mirrors [`face_of`] and [`face_view`]).
//!
//! Depth bias: the receiver is moved towards the light by a fraction of its distance
//! ([`relative_bias`]), so the bias scales with the perspective depth spacing instead of
//! being a constant in normalised depth.

use crate::math::{self, Mat4, Vec3};

/// Faces in layer order: +x, −x, +y, −y, +z, −z.
pub const FACES: usize = 6;

/// Axis (the face's viewing direction) of face `f`.
pub fn axis(f: usize) -> Vec3 {
    let s = if f.is_multiple_of(2) { 1.0 } else { -1.0 };
    match f / 2 {
        0 => Vec3::new(s, 0.0, 0.0),
        1 => Vec3::new(0.0, s, 0.0),
        _ => Vec3::new(0.0, 0.0, s),
    }
}

/// Up vector of face `f` (never parallel to its axis).
pub fn up(f: usize) -> Vec3 {
    if f / 2 == 1 { Vec3::z() } else { Vec3::y() }
}

#[cfg(test)]
/// The face a direction from the light falls on (largest |component|; ties to x, then y).
pub fn face_of(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if d.y >= 0.0 { 2 } else { 3 }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// World → face view matrix of a light at `light`.
pub fn face_view(light: Vec3, f: usize) -> Mat4 {
    math::look_at(light, light + axis(f), up(f))
}

/// The projection every face shares: 90° square frustum from `near` to `far`.
pub fn projection(near: f32, far: f32) -> Mat4 {
    math::perspective(90.0, 1.0, near, far)
}

/// Near and far planes for a light at distance `dist` from the centre of a scene sphere of
/// radius `radius`: everything within the sphere lies inside.
pub fn near_far(dist: f32, radius: f32) -> (f32, f32) {
    let far = dist + 1.05 * radius;
    (far * 1e-3, far)
}

/// Fraction of the light distance the receiver moves towards the light before the depth
/// comparison, for faces of `size` texels: about three texels of depth change at 70° from
/// the face normal, plus a floor.
pub fn relative_bias(size: u32) -> f32 {
    0.002 + 6.0 / size as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector4;

    /// Every direction lands inside its face's frustum, and neighbouring faces agree on the
    /// depth of a point on their shared edge.
    #[test]
    fn faces_cover_all_directions() {
        let light = Vec3::new(0.3, -0.2, 0.5);
        let p = projection(0.01, 10.0);
        let mut seen = [false; FACES];
        for i in 0..400 {
            let (t, ph) = (std::f32::consts::PI * (i as f32 + 0.5) / 400.0, i as f32 * 2.399);
            let d = Vec3::new(t.sin() * ph.cos(), t.sin() * ph.sin(), t.cos()) * 2.0;
            let f = face_of(d);
            seen[f] = true;
            let q = light + d;
            let c = p * face_view(light, f) * Vector4::new(q.x, q.y, q.z, 1.0);
            let n = c.xyz() / c.w;
            assert!(c.w > 0.0 && n.x.abs() <= 1.0 + 1e-5 && n.y.abs() <= 1.0 + 1e-5, "{f} {n:?}");
            assert!((0.0..=1.0).contains(&n.z));
        }
        assert!(seen.iter().all(|s| *s));
        // A point on the +x/+y edge: same depth from both faces.
        let q = light + Vec3::new(1.0, 1.0, 0.3);
        let z = |f| {
            let c = p * face_view(light, f) * Vector4::new(q.x, q.y, q.z, 1.0);
            c.z / c.w
        };
        assert!((z(0) - z(2)).abs() < 1e-6);
    }
}
