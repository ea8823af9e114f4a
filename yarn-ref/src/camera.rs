//! Cameras: a pinhole perspective camera, and the BTF's oblique orthographic camera of
//! DESIGN §4.2.
//!
//! **Image coordinates.** Continuous pixel coordinates `(x, y)` with `x ∈ [0, W)` along
//! a row and `y ∈ [0, H)` down the rows; pixel `(i, j)` covers `[i, i+1) × [j, j+1)`.
//!
//! **Perspective.** Row 0 at the top (`+up`), column 0 at the left; the vertical field of
//! view is given and the horizontal one follows from `W/H`.
//!
//! **Oblique orthographic** (DESIGN §4.2). A view direction `v` (unit, towards the viewer,
//! `v_z > 0`), a reference plane `z = z_ref` and a rectangle `[x0, x0 + X) × [y0, y0 + Y)`
//! on it. Pixel position `(x, y)` is the reference-plane point
//! `p = (x0 + X·x/W, y0 + Y·y/H, z_ref)` — rows run along `+y`, the texel convention of
//! DESIGN §3, so row `j` of the image is texel row `j` of a normtexture — and its ray is the
//! line through `p` along `−v`, started above all geometry. This projection maps a world
//! point `q` to `q.xy − v.xy/v_z·(q_z − z_ref)` with depth `(z_ref − q_z)/v_z`, so pixel
//! centres are texel centres for every view, and sub-pixel jitter averages over the texel's
//! footprint on the reference plane.

use crate::{Error, Result};
use yarn::vec3::{self, V3};

/// A camera (see the module documentation for the conventions).
#[derive(Debug, Clone, PartialEq)]
pub enum Camera {
    /// Pinhole perspective.
    Perspective {
        /// Eye position.
        eye: V3,
        /// Unit viewing direction.
        forward: V3,
        /// Unit image right.
        right: V3,
        /// Unit image up.
        up: V3,
        /// `tan(fov_y / 2)`.
        tan_half_fov_y: f64,
    },
    /// Oblique orthographic onto the reference plane.
    Oblique {
        /// Unit direction towards the viewer (`v_z > 0`).
        view: V3,
        /// Reference plane height.
        z_ref: f64,
        /// Lower corner of the imaged rectangle on the plane.
        origin: [f64; 2],
        /// Size of the rectangle.
        extent: [f64; 2],
    },
}

/// Smallest `v_z` of an oblique view (θ ≤ 89.9°): beyond it the camera's rays would start
/// arbitrarily far away.
pub const MIN_VIEW_Z: f64 = 1.745e-3;

impl Camera {
    /// A perspective camera at `eye` looking at `target`, `up` roughly up, vertical field
    /// of view `fov_y_deg`.
    pub fn perspective(eye: V3, target: V3, up: V3, fov_y_deg: f64) -> Result<Self> {
        let forward = vec3::normalize(vec3::sub(target, eye))
            .ok_or_else(|| Error::Invalid(format!("camera: eye {eye:?} equals target")))?;
        let right = vec3::normalize(vec3::cross(forward, up)).ok_or_else(|| {
            Error::Invalid(format!("camera: up {up:?} is parallel to the view direction"))
        })?;
        if !(fov_y_deg > 0.0 && fov_y_deg < 179.0) {
            return Err(Error::Invalid(format!(
                "camera: field of view {fov_y_deg}° outside (0, 179)"
            )));
        }
        Ok(Camera::Perspective {
            eye,
            forward,
            right,
            up: vec3::cross(right, forward),
            tan_half_fov_y: (0.5 * fov_y_deg.to_radians()).tan(),
        })
    }

    /// The oblique orthographic camera of view `view` (towards the viewer) onto
    /// `[origin, origin + extent)` of the plane `z = z_ref`.
    pub fn oblique(view: V3, z_ref: f64, origin: [f64; 2], extent: [f64; 2]) -> Result<Self> {
        let view = vec3::normalize(view).ok_or_else(|| {
            Error::Invalid(format!("oblique camera: view {view:?} is not a direction"))
        })?;
        if view[2] < MIN_VIEW_Z {
            return Err(Error::Invalid(format!(
                "oblique camera: view {view:?} is {:.3}° from the normal (at most 89.9°: a view at \
                 or below the horizon sees no reference plane)",
                view[2].clamp(-1.0, 1.0).acos().to_degrees()
            )));
        }
        if !(extent.iter().all(|e| *e > 0.0 && e.is_finite())
            && origin.iter().all(|o| o.is_finite())
            && z_ref.is_finite())
        {
            return Err(Error::Invalid(format!(
                "oblique camera: rectangle {origin:?} + {extent:?} at z = {z_ref} must be finite and non-empty"
            )));
        }
        Ok(Camera::Oblique { view, z_ref, origin, extent })
    }

    /// The ray `(origin, unit direction)` through continuous pixel position `(x, y)` of a
    /// `w × h` image; an oblique ray starts at height `top` (above every fiber) or on the
    /// reference plane if that is higher.
    pub fn ray(&self, x: f64, y: f64, w: usize, h: usize, top: f64) -> (V3, V3) {
        match self {
            Camera::Perspective { eye, forward, right, up, tan_half_fov_y } => {
                let aspect = w as f64 / h as f64;
                let sx = (2.0 * x / w as f64 - 1.0) * tan_half_fov_y * aspect;
                let sy = (1.0 - 2.0 * y / h as f64) * tan_half_fov_y;
                let d = vec3::add_scaled(vec3::add_scaled(*forward, *right, sx), *up, sy);
                (*eye, vec3::normalize_or(d, *forward))
            }
            Camera::Oblique { view, z_ref, origin, extent } => {
                let p = [
                    origin[0] + extent[0] * x / w as f64,
                    origin[1] + extent[1] * y / h as f64,
                    *z_ref,
                ];
                let start = top.max(*z_ref) + 1e-9 * (1.0 + extent[0].abs() + extent[1].abs());
                let o = vec3::add_scaled(p, *view, (start - z_ref) / view[2]);
                (o, vec3::scale(*view, -1.0))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oblique_rays_cross_the_reference_plane_at_texel_centres() {
        let v = btf_core::Direction::new(60.0, 215.0).to_vector();
        let cam = Camera::oblique(v, 0.3, [1.0, 2.0], [4.0, 8.0]).unwrap();
        for (i, j) in [(0usize, 0usize), (3, 7), (15, 2)] {
            let (o, d) = cam.ray(i as f64 + 0.5, j as f64 + 0.5, 16, 16, 0.9);
            assert!(o[2] > 0.9);
            let t = (0.3 - o[2]) / d[2];
            let p = vec3::add_scaled(o, d, t);
            let want = [1.0 + 4.0 * (i as f64 + 0.5) / 16.0, 2.0 + 8.0 * (j as f64 + 0.5) / 16.0];
            assert!((p[0] - want[0]).abs() < 1e-12 && (p[1] - want[1]).abs() < 1e-12);
            assert!((vec3::length(d) - 1.0).abs() < 1e-12 && vec3::dot(d, v) < -0.999_999);
        }
        assert!(Camera::oblique([1.0, 0.0, 0.0], 0.0, [0.0; 2], [1.0; 2]).is_err());
        assert!(Camera::oblique([0.0, 0.0, 1.0], 0.0, [0.0; 2], [0.0, 1.0]).is_err());
    }

    #[test]
    fn perspective_centre_ray_looks_at_the_target() {
        let cam =
            Camera::perspective([0.0, -3.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 40.0).unwrap();
        let (o, d) = cam.ray(32.0, 16.0, 64, 32, 0.0);
        let want = vec3::normalize([0.0, 3.0, -1.0]).unwrap();
        assert_eq!(o, [0.0, -3.0, 1.0]);
        assert!(vec3::distance(d, want) < 1e-12);
        // The top edge is 20° above the centre ray.
        let (_, top) = cam.ray(32.0, 0.0, 64, 32, 0.0);
        assert!((vec3::dot(top, want).acos().to_degrees() - 20.0).abs() < 1e-9);
        assert!(Camera::perspective([0.0; 3], [0.0; 3], [0.0, 0.0, 1.0], 40.0).is_err());
    }
}
