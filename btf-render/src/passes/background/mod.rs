//! The environment map drawn behind the scene (`[output] show_environment = true`): per
//! pixel, the radiance `f · L_env(R_{−δ} ω)` of the camera ray's world direction `ω`, with
//! the environment light's rotation `δ` about `+z` and exposure `f` — the same map, turned
//! the same way, that lights the scene (DESIGN.md §3, Sattler et al. 2003 eq. 11's `f`).
//! Thin cloth (thin-cloth paper eq. 9) then shows it through with its view-dependent
//! alpha, as the paper's flag shows the sky.
//!
//! Computed on the CPU (a bilinear look-up in the equirectangular map per pixel, rows `θ`
//! from `+z`, columns `φ` from `+x` towards `+y`) and written into the colour target before
//! the mesh passes; only without MSAA (a multisampled target cannot be written directly).

use crate::camera::CameraSetup;
use crate::math::Vec3;
use btf_image::EnvMap;
use nalgebra::Vector4;
use std::f32::consts::PI;

/// World direction of the camera ray through the centre of pixel `(x, y)` (row 0 at the
/// top), from the inverse of the camera's world → clip matrix.
fn ray_dir(inv: &crate::math::Mat4, w: u32, h: u32, x: u32, y: u32) -> Vec3 {
    let nx = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ny = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
    let at = |z: f32| {
        let p = inv * Vector4::new(nx, ny, z, 1.0);
        Vec3::new(p.x / p.w, p.y / p.w, p.z / p.w)
    };
    (at(0.75) - at(0.25)).try_normalize(0.0).unwrap_or(Vec3::z())
}

/// Bilinear radiance of `map` in world direction `d` (unit), wrapping in `φ`.
pub fn radiance(map: &EnvMap, d: [f32; 3]) -> [f32; 3] {
    let theta = d[2].clamp(-1.0, 1.0).acos();
    let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
    let (w, h) = (map.width, map.height);
    let u = phi / (2.0 * PI) * w as f32 - 0.5;
    let v = (theta / PI * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
    let (c0, r0) = (u.floor(), v.floor());
    let (fu, fv) = (u - c0, v - r0);
    let col = |c: f32| (c as i64).rem_euclid(w as i64) as usize;
    let row = |r: f32| (r as usize).min(h - 1);
    let px = |c: f32, r: f32| map.pixels[row(r) * w + col(c)];
    let mut out = [0f32; 3];
    for (dc, dr, wgt) in [
        (0.0, 0.0, (1.0 - fu) * (1.0 - fv)),
        (1.0, 0.0, fu * (1.0 - fv)),
        (0.0, 1.0, (1.0 - fu) * fv),
        (1.0, 1.0, fu * fv),
    ] {
        let p = px(c0 + dc, r0 + dr);
        for k in 0..3 {
            out[k] += wgt * p[k];
        }
    }
    out
}

/// The background image, RGBA (alpha 1), row-major from the top row.
pub fn image(
    map: &EnvMap,
    camera: &CameraSetup,
    (w, h): (u32, u32),
    rotation_deg: f64,
    exposure: f32,
) -> Vec<[f32; 4]> {
    let inv = camera.view_proj.try_inverse().unwrap_or_else(crate::math::Mat4::identity);
    let (sin, cos) = rotation_deg.to_radians().sin_cos();
    let (sin, cos) = (sin as f32, cos as f32);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let d = ray_dir(&inv, w, h, x, y);
            // The environment turned by δ: world direction ω sees the map at R_{−δ} ω.
            let e = [cos * d.x + sin * d.y, -sin * d.x + cos * d.y, d.z];
            let l = radiance(map, e);
            out.push([exposure * l[0], exposure * l[1], exposure * l[2], 1.0]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radiance_reproduces_pixel_centres_and_wraps() {
        let map = EnvMap::from_fn(16, |d| d.map(|c| f64::from(1.0 + c as f32))).unwrap();
        // At a pixel centre the look-up returns that pixel.
        let (theta, phi) = (PI * 2.5 / 8.0, 2.0 * PI * 3.5 / 16.0);
        let d = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
        let l = radiance(&map, d);
        assert!((0..3).all(|k| (l[k] - 1.0 - d[k]).abs() < 1e-5), "{l:?} vs {d:?}");
        // Across φ = 0 the two neighbouring columns are blended, not the far end.
        let l = radiance(&map, [1.0, 0.0, 0.0]);
        assert!((l[1] - 1.0).abs() < 1e-5 && l[0] > 1.9, "{l:?}");
    }
}
