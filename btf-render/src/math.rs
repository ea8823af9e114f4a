//! Small linear-algebra helpers for cameras and lights: look-at views and projections in
//! wgpu's clip convention (right-handed world, `z_ndc ∈ [0, 1]`), built on nalgebra.

pub use btf_light::math::{Vec3, any_perpendicular, v3};
use nalgebra::{Matrix4, Point3};

/// A 4×4 `f32` matrix (column-major, as WGSL expects).
pub type Mat4 = Matrix4<f32>;

/// View matrix (world → camera, camera looks down `−z`).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    Matrix4::look_at_rh(&Point3::from(eye), &Point3::from(target), &up)
}

/// Perspective projection to wgpu clip space (`z_ndc = 0` at `near`, 1 at `far`).
pub fn perspective(fov_y_deg: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let f = 1.0 / (fov_y_deg.to_radians() * 0.5).tan();
    let mut m = Mat4::zeros();
    m[(0, 0)] = f / aspect;
    m[(1, 1)] = f;
    m[(2, 2)] = far / (near - far);
    m[(2, 3)] = near * far / (near - far);
    m[(3, 2)] = -1.0;
    m
}

/// Orthographic projection of a `width × height` window to wgpu clip space.
pub fn orthographic(width: f32, height: f32, near: f32, far: f32) -> Mat4 {
    let mut m = Mat4::identity();
    m[(0, 0)] = 2.0 / width;
    m[(1, 1)] = 2.0 / height;
    m[(2, 2)] = 1.0 / (near - far);
    m[(2, 3)] = near / (near - far);
    m
}

/// An `up` vector usable with [`look_at`] for viewing direction `dir` (falls back when
/// `up` is parallel to `dir`).
pub fn safe_up(dir: Vec3, up: Vec3) -> Vec3 {
    if dir.cross(&up).norm() > 1e-4 * dir.norm() * up.norm() { up } else { any_perpendicular(dir) }
}

/// Column-major `[[f32; 4]; 4]` for uniform buffers.
pub fn to_cols(m: &Mat4) -> [[f32; 4]; 4] {
    let mut out = [[0.0; 4]; 4];
    for c in 0..4 {
        for r in 0..4 {
            out[c][r] = m[(r, c)];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector4;

    #[test]
    fn projections_map_near_far_to_0_1() {
        let p = perspective(60.0, 1.5, 0.5, 20.0);
        let near = p * Vector4::new(0.0, 0.0, -0.5, 1.0);
        let far = p * Vector4::new(0.0, 0.0, -20.0, 1.0);
        assert!((near.z / near.w).abs() < 1e-6);
        assert!((far.z / far.w - 1.0).abs() < 1e-6);
        let o = orthographic(4.0, 2.0, 1.0, 9.0);
        let c = o * Vector4::new(2.0, 1.0, -9.0, 1.0);
        assert!((c.x - 1.0).abs() < 1e-6 && (c.y - 1.0).abs() < 1e-6 && (c.z - 1.0).abs() < 1e-6);
    }

    #[test]
    fn look_at_puts_target_on_minus_z() {
        let v = look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::zeros(), Vec3::y());
        let t = v * Vector4::new(0.0, 0.0, 0.0, 1.0);
        assert!((t.z + 5.0).abs() < 1e-6);
        let up = safe_up(Vec3::z(), Vec3::z());
        assert!(up.dot(&Vec3::z()).abs() < 1e-6);
    }
}
