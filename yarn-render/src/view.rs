//! The camera, lights and level-of-detail settings of one fiber frame, and their GPU
//! mirror `ViewRaw` (`shaders/fiber_view.wgsl`). Matrices are built in f64 relative to
//! [`crate::PackedYarns::origin`] and rounded once, so a garment far from the world origin
//! keeps sub-fiber precision. Frustum planes are extracted from the world → clip matrix
//! (Gribb & Hartmann) for the conservative culling of DESIGN §2.3 item 8. No equation of
//! the papers lives here; λ itself is in [`crate::passes::lod`].

use crate::{Error, Result};
use nalgebra::{Matrix4, Vector3, Vector4};

/// A camera of the fiber renderer (metres, z-up world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FiberCamera {
    /// Pinhole (or orthographic when `fov_y_deg` is `None`) at `eye` looking at `target`.
    Look {
        /// Eye position.
        eye: [f64; 3],
        /// Point looked at.
        target: [f64; 3],
        /// Up vector (need not be orthogonal to the view direction).
        up: [f64; 3],
        /// Vertical field of view (degrees); `None`: orthographic.
        fov_y_deg: Option<f64>,
        /// Orthographic frame height (metres).
        ortho_height: f64,
    },
    /// The yarn BTF's oblique orthographic camera (DESIGN §4.2, `yarn_ref::Camera::oblique`):
    /// a world point maps to where its view ray crosses `z = z_ref`,
    /// `(p.xy − v.xy/v.z·(p.z − z_ref))`, so pixel centres are texel centres for every view;
    /// pixel `(i, j)` covers `origin + extent·(i, j)/(w, h)` (row 0 at the smallest y).
    Oblique {
        /// Unit direction towards the viewer (`v.z > 0`).
        view: [f64; 3],
        /// Height of the reference plane.
        z_ref: f64,
        /// Corner of the imaged rectangle on the plane.
        origin: [f64; 2],
        /// Size of that rectangle.
        extent: [f64; 2],
    },
    /// Another renderer's camera, as its world → clip matrix (wgpu depth `[0, 1]`), so that
    /// fibers share its depth buffer (`btf render`'s `[[yarns]]`): frustum, LoD scale and
    /// depth all come from this matrix, near and far planes included.
    Matrix {
        /// World → clip, row-major (`clip = view_proj · (p, 1)`).
        view_proj: [[f64; 4]; 4],
        /// Eye position (perspective).
        eye: [f64; 3],
        /// Unit direction towards the camera when the projection is orthographic.
        ortho_to_camera: Option<[f64; 3]>,
    },
}

impl FiberCamera {
    /// A perspective camera.
    pub fn perspective(eye: [f64; 3], target: [f64; 3], up: [f64; 3], fov_y_deg: f64) -> Self {
        FiberCamera::Look { eye, target, up, fov_y_deg: Some(fov_y_deg), ortho_height: 0.0 }
    }

    /// An orthographic camera whose frame is `height` metres tall.
    pub fn orthographic(eye: [f64; 3], target: [f64; 3], up: [f64; 3], height: f64) -> Self {
        FiberCamera::Look { eye, target, up, fov_y_deg: None, ortho_height: height }
    }

    /// The oblique BTF camera (see [`FiberCamera::Oblique`]).
    pub fn oblique(view: [f64; 3], z_ref: f64, origin: [f64; 2], extent: [f64; 2]) -> Self {
        FiberCamera::Oblique { view, z_ref, origin, extent }
    }
}

/// A light of the fiber renderer (the delta lights of `yarn_ref::Light`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FiberLight {
    /// Distant light: unit direction towards it, perpendicular irradiance (linear RGB).
    Directional {
        /// Direction from the scene towards the light.
        to_light: [f64; 3],
        /// Perpendicular irradiance.
        irradiance: [f64; 3],
    },
    /// Isotropic point light.
    Point {
        /// World position.
        position: [f64; 3],
        /// Radiant intensity (W/sr per channel).
        intensity: [f64; 3],
    },
}

/// The most lights one frame takes (`fiber_view.wgsl`).
pub const MAX_LIGHTS: usize = 8;

/// One light as the shaders read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightRaw {
    /// Direction towards the light (w = 0) or origin-relative position (w = 1).
    pub pos_dir: [f32; 4],
    /// Irradiance or intensity.
    pub value: [f32; 4],
}

/// The frame uniform (std140-compatible: every member 16-byte aligned).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewRaw {
    /// Origin-relative world → clip, column-major.
    pub view_proj: [[f32; 4]; 4],
    /// Origin-relative eye; w = 1 perspective, 0 orthographic.
    pub eye: [f32; 4],
    /// Unit viewing direction.
    pub forward: [f32; 4],
    /// Width, height, pixels per metre (at unit depth when perspective), ω^LoD (px).
    pub viewport: [f32; 4],
    /// Frustum planes.
    pub planes: [[f32; 4]; 6],
    /// n_max per ply, n_sub at λ = 1, flags, instance capacity.
    pub lod: [u32; 4],
    /// Lights, lobes, segments, unused.
    pub counts: [u32; 4],
    /// Minimum strip width (px), MSAA samples, unused ×2.
    pub strip: [f32; 4],
    /// Lights.
    pub lights: [LightRaw; MAX_LIGHTS],
    /// Constant ambient radiance (linear RGB), unused.
    pub ambient: [f32; 4],
}

/// The camera matrices of a frame, relative to `origin`.
#[derive(Debug, Clone, Copy)]
pub struct ViewSetup {
    /// Origin-relative world → clip (wgpu depth range `[0, 1]`).
    pub view_proj: Matrix4<f64>,
    /// Origin-relative eye.
    pub eye: Vector3<f64>,
    /// Unit viewing direction.
    pub forward: Vector3<f64>,
    /// Pixels per metre at unit depth (perspective) or per metre (orthographic).
    pub px_per_metre: f64,
    /// Orthographic.
    pub orthographic: bool,
}

impl ViewSetup {
    /// The setup of `cam` for a `width × height` frame of a scene within `radius` of
    /// `centre` (origin-relative), near and far planes around that sphere.
    pub fn new(
        cam: &FiberCamera,
        origin: [f64; 3],
        centre: [f64; 3],
        radius: f64,
        (width, height): (u32, u32),
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Invalid(format!("fiber frame of {width} × {height} pixels")));
        }
        let (eye, target, up, fov_y_deg, ortho_height) = match *cam {
            FiberCamera::Look { eye, target, up, fov_y_deg, ortho_height } => {
                (eye, target, up, fov_y_deg, ortho_height)
            }
            FiberCamera::Oblique { view, z_ref, origin: o, extent } => {
                return Self::oblique(view, z_ref, o, extent, origin, centre, radius, width);
            }
            FiberCamera::Matrix { view_proj, eye, ortho_to_camera } => {
                return Self::matrix(&view_proj, eye, ortho_to_camera, origin, height);
            }
        };
        let rel = |p: [f64; 3]| Vector3::new(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
        let eye = rel(eye);
        let target = rel(target);
        let fwd = target - eye;
        if !(fwd.norm() > 0.0 && fwd.iter().all(|x| x.is_finite())) {
            return Err(Error::Invalid("fiber camera: eye and target coincide".into()));
        }
        let f = fwd.normalize();
        let mut up = Vector3::new(up[0], up[1], up[2]);
        if up.cross(&f).norm() < 1e-9 {
            up = if f.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
        }
        let s = f.cross(&up).normalize();
        let u = s.cross(&f);
        #[rustfmt::skip]
        let view = Matrix4::new(
            s.x, s.y, s.z, -s.dot(&eye),
            u.x, u.y, u.z, -u.dot(&eye),
            -f.x, -f.y, -f.z, f.dot(&eye),
            0.0, 0.0, 0.0, 1.0,
        );
        let aspect = width as f64 / height as f64;
        let c = Vector3::new(centre[0], centre[1], centre[2]);
        let dist = (c - eye).dot(&f);
        let radius = radius.max(1e-9);
        let far = dist + radius * 1.05;
        let (proj, px_per_metre, orthographic) = match fov_y_deg {
            Some(fov) => {
                if !(fov > 0.0 && fov < 179.0) {
                    return Err(Error::Invalid(format!("fiber camera: fov_y_deg {fov}")));
                }
                let near = (dist - radius * 1.05).max(far * 1e-4).max(1e-6);
                let fy = 1.0 / (0.5 * fov.to_radians()).tan();
                #[rustfmt::skip]
                let p = Matrix4::new(
                    fy / aspect, 0.0, 0.0, 0.0,
                    0.0, fy, 0.0, 0.0,
                    0.0, 0.0, far / (near - far), near * far / (near - far),
                    0.0, 0.0, -1.0, 0.0,
                );
                (p, 0.5 * height as f64 * fy, false)
            }
            None => {
                let h = ortho_height;
                if !(h > 0.0 && h.is_finite()) {
                    return Err(Error::Invalid(format!("fiber camera: ortho_height {h}")));
                }
                let near = dist - radius * 1.05;
                let w = h * aspect;
                #[rustfmt::skip]
                let p = Matrix4::new(
                    2.0 / w, 0.0, 0.0, 0.0,
                    0.0, 2.0 / h, 0.0, 0.0,
                    0.0, 0.0, 1.0 / (near - far), near / (near - far),
                    0.0, 0.0, 0.0, 1.0,
                );
                (p, height as f64 / h, true)
            }
        };
        Ok(ViewSetup { view_proj: proj * view, eye, forward: f, px_per_metre, orthographic })
    }

    /// A given world → clip matrix moved to origin-relative coordinates,
    /// `M · T(origin)`, in f64. Pixels per metre from its rows: perspective
    /// `½ h · |row₁.xyz| / |row₃.xyz|` (row 1 is `f_y · up`, row 3 the unit forward),
    /// orthographic `½ h · |row₁.xyz|` (row 1 is `2/H · up`).
    fn matrix(
        m: &[[f64; 4]; 4],
        eye: [f64; 3],
        ortho_to_camera: Option<[f64; 3]>,
        origin: [f64; 3],
        height: u32,
    ) -> Result<Self> {
        if !(m.iter().flatten().all(|x| x.is_finite()) && eye.iter().all(|x| x.is_finite())) {
            return Err(Error::Invalid("fiber camera: non-finite matrix or eye".into()));
        }
        let world = Matrix4::from_fn(|r, c| m[r][c]);
        let shift = Matrix4::new_translation(&Vector3::new(origin[0], origin[1], origin[2]));
        let view_proj = world * shift;
        let xyz = |r: usize| Vector3::new(m[r][0], m[r][1], m[r][2]);
        let up_scale = xyz(1).norm();
        let (forward, px_per_metre, orthographic) = match ortho_to_camera {
            Some(d) => {
                let d = Vector3::new(d[0], d[1], d[2]);
                if d.norm() <= 0.0 || !d.norm().is_finite() {
                    return Err(Error::Invalid("fiber camera: zero ortho direction".into()));
                }
                (-d.normalize(), 0.5 * height as f64 * up_scale, true)
            }
            None => {
                let f = xyz(3);
                if f.norm() <= 0.0 || !f.norm().is_finite() {
                    return Err(Error::Invalid(
                        "fiber camera: a perspective matrix needs a forward row".into(),
                    ));
                }
                (f.normalize(), 0.5 * height as f64 * up_scale / f.norm(), false)
            }
        };
        let eye = Vector3::new(eye[0] - origin[0], eye[1] - origin[1], eye[2] - origin[2]);
        Ok(ViewSetup { view_proj, eye, forward, px_per_metre, orthographic })
    }

    /// The oblique camera's matrix: clip x, y from the reference-plane entry, depth from
    /// `(z_top − p.z)/v.z` over the scene's height range (all affine in `p`).
    #[allow(clippy::too_many_arguments)]
    fn oblique(
        view: [f64; 3],
        z_ref: f64,
        o: [f64; 2],
        extent: [f64; 2],
        origin: [f64; 3],
        centre: [f64; 3],
        radius: f64,
        width: u32,
    ) -> Result<Self> {
        let n = (view[0] * view[0] + view[1] * view[1] + view[2] * view[2]).sqrt();
        if !(n > 0.0 && view[2] / n >= 1.7e-3) {
            return Err(Error::Invalid(format!(
                "oblique fiber camera: view {view:?} at or below the horizon"
            )));
        }
        if !(extent.iter().all(|e| *e > 0.0 && e.is_finite()) && z_ref.is_finite()) {
            return Err(Error::Invalid(format!("oblique fiber camera: extent {extent:?}")));
        }
        let v = Vector3::new(view[0] / n, view[1] / n, view[2] / n);
        // Origin-relative: p_world = p + origin.
        let (ax, ay) = (v.x / v.z, v.y / v.z);
        let zr = z_ref - origin[2];
        let (ox, oy) = (o[0] - origin[0], o[1] - origin[1]);
        // Depth: 0 at the top of the scene, 1 at its bottom (with margin).
        let r = radius.max(1e-9) * 1.05;
        let (z_top, z_bot) = (centre[2] + r, centre[2] - r);
        let span = (z_top - z_bot) / v.z;
        let (sx, sy) = (2.0 / extent[0], 2.0 / extent[1]);
        #[rustfmt::skip]
        let m = Matrix4::new(
            sx, 0.0, -sx * ax, sx * (ax * zr - ox) - 1.0,
            0.0, -sy, sy * ay, -sy * (ay * zr - oy) + 1.0,
            0.0, 0.0, -1.0 / (v.z * span), z_top / (v.z * span),
            0.0, 0.0, 0.0, 1.0,
        );
        Ok(ViewSetup {
            view_proj: m,
            eye: v * 1e3,
            forward: -v,
            px_per_metre: width as f64 / extent[0],
            orthographic: true,
        })
    }

    /// The six frustum planes `(n, w)`, inside where `n·p + w ≥ 0`, with unit `n`.
    pub fn planes(&self) -> [[f64; 4]; 6] {
        let m = &self.view_proj;
        let row = |i: usize| Vector4::new(m[(i, 0)], m[(i, 1)], m[(i, 2)], m[(i, 3)]);
        let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
        [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2].map(|p| {
            let n = (p.x * p.x + p.y * p.y + p.z * p.z).sqrt().max(1e-30);
            [p.x / n, p.y / n, p.z / n, p.w / n]
        })
    }
}

/// `lights` in the frame uniform's layout (at most [`MAX_LIGHTS`]).
pub fn lights_raw(lights: &[FiberLight], origin: [f64; 3]) -> Result<[LightRaw; MAX_LIGHTS]> {
    if lights.len() > MAX_LIGHTS {
        return Err(Error::Limit(format!(
            "{} lights; the fiber renderer takes at most {MAX_LIGHTS}",
            lights.len()
        )));
    }
    let mut out = [LightRaw::default(); MAX_LIGHTS];
    // Finite, non-negative and within f32 (no NaN or infinity reaches a pixel).
    let value_ok =
        |v: [f64; 3]| v.iter().all(|x| x.is_finite() && *x >= 0.0 && *x <= f32::MAX as f64);
    for (i, l) in lights.iter().enumerate() {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let (value, what) = match *l {
            FiberLight::Directional { irradiance, .. } => (irradiance, "irradiance"),
            FiberLight::Point { intensity, .. } => (intensity, "intensity"),
        };
        if !value_ok(value) {
            return Err(Error::Invalid(format!("light {i}: {what} {value:?} (finite, ≥ 0)")));
        }
        out[i] = match *l {
            FiberLight::Directional { to_light, irradiance } => {
                let n = (to_light.iter().map(|x| x * x).sum::<f64>()).sqrt();
                if !(n > 0.0 && n.is_finite()) {
                    return Err(Error::Invalid(format!("light {i}: direction {to_light:?}")));
                }
                let d = f(to_light.map(|x| x / n));
                let e = f(irradiance);
                LightRaw { pos_dir: [d[0], d[1], d[2], 0.0], value: [e[0], e[1], e[2], 0.0] }
            }
            FiberLight::Point { position, intensity } => {
                if !position.iter().all(|x| x.is_finite() && x.abs() <= 1e30) {
                    return Err(Error::Invalid(format!("light {i}: position {position:?}")));
                }
                let p = f([0, 1, 2].map(|a| position[a] - origin[a]));
                let e = f(intensity);
                LightRaw { pos_dir: [p[0], p[1], p[2], 1.0], value: [e[0], e[1], e[2], 0.0] }
            }
        };
    }
    Ok(out)
}

/// Column-major f32 of an f64 matrix.
pub fn to_cols(m: &Matrix4<f64>) -> [[f32; 4]; 4] {
    let mut out = [[0.0; 4]; 4];
    for c in 0..4 {
        for r in 0..4 {
            out[c][r] = m[(r, c)] as f32;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_with_non_finite_or_negative_values_are_refused_by_index() {
        let ok = FiberLight::Directional { to_light: [0.0, 0.0, 1.0], irradiance: [1.0; 3] };
        let bad = [
            (
                FiberLight::Directional {
                    to_light: [0.0, 0.0, 1.0],
                    irradiance: [f64::NAN, 1.0, 1.0],
                },
                "irradiance",
            ),
            (FiberLight::Point { position: [0.0; 3], intensity: [-1.0, 1.0, 1.0] }, "intensity"),
            (FiberLight::Point { position: [0.0; 3], intensity: [1e300; 3] }, "intensity"),
            (
                FiberLight::Point { position: [f64::INFINITY, 0.0, 0.0], intensity: [1.0; 3] },
                "position",
            ),
            (FiberLight::Directional { to_light: [0.0; 3], irradiance: [1.0; 3] }, "direction"),
        ];
        for (l, what) in bad {
            let e = lights_raw(&[ok, l], [0.0; 3]).unwrap_err().to_string();
            assert!(e.contains("light 1") && e.contains(what), "{e}");
        }
        let raw = lights_raw(&[ok], [0.0; 3]).unwrap();
        assert_eq!(raw[0].value, [1.0, 1.0, 1.0, 0.0]);
    }
}
