//! The vector vocabulary of the lighting code: `f32` 3-vectors (nalgebra), as the meshes
//! and frames store them. Camera matrices live with the renderer (`btf_render::math`).
//! The BVH and the ray lanes keep their own `[f32; 3]` helpers on purpose: their operation
//! order is shared bit for bit between the scalar and the SIMD paths.

use nalgebra::Vector3;

/// A 3-vector of `f32`.
pub type Vec3 = Vector3<f32>;

/// Converts `[x, y, z]` to a vector.
pub fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Some unit vector perpendicular to `n` (for frames without a preferred direction).
pub fn any_perpendicular(n: Vec3) -> Vec3 {
    let a = if n.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    n.cross(&a).normalize()
}
