//! The camera, lights and level-of-detail settings of one fiber frame, and their GPU
//! mirror `ViewRaw` (`shaders/fiber_view.wgsl`). Matrices are built in f64 relative to
//! [`crate::PackedYarns::origin`] and rounded once, so a garment far from the world origin
//! keeps sub-fiber precision. Frustum planes are extracted from the world → clip matrix
//! (Gribb & Hartmann) for the conservative culling of DESIGN §2.3 item 8. No equation of
//! the papers lives here; λ itself is in [`crate::passes::lod`].

use crate::{Error, Result};
use nalgebra::{Matrix4, Vector3, Vector4};

/// A pinhole or orthographic camera (metres, z-up world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberCamera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up vector (need not be orthogonal to the view direction).
    pub up: [f64; 3],
    /// Perspective vertical field of view (degrees), or `None` for orthographic.
    pub fov_y_deg: Option<f64>,
    /// Orthographic frame height (metres).
    pub ortho_height: f64,
}

impl FiberCamera {
    /// A perspective camera.
    pub fn perspective(eye: [f64; 3], target: [f64; 3], up: [f64; 3], fov_y_deg: f64) -> Self {
        FiberCamera { eye, target, up, fov_y_deg: Some(fov_y_deg), ortho_height: 0.0 }
    }

    /// An orthographic camera whose frame is `height` metres tall.
    pub fn orthographic(eye: [f64; 3], target: [f64; 3], up: [f64; 3], height: f64) -> Self {
        FiberCamera { eye, target, up, fov_y_deg: None, ortho_height: height }
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
    /// Minimum strip width (px), unused ×3.
    pub strip: [f32; 4],
    /// Lights.
    pub lights: [LightRaw; MAX_LIGHTS],
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
        let rel = |p: [f64; 3]| Vector3::new(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
        let eye = rel(cam.eye);
        let target = rel(cam.target);
        let fwd = target - eye;
        if !(fwd.norm() > 0.0 && fwd.iter().all(|x| x.is_finite())) {
            return Err(Error::Invalid("fiber camera: eye and target coincide".into()));
        }
        if width == 0 || height == 0 {
            return Err(Error::Invalid(format!("fiber frame of {width} × {height} pixels")));
        }
        let f = fwd.normalize();
        let mut up = Vector3::new(cam.up[0], cam.up[1], cam.up[2]);
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
        let (proj, px_per_metre, orthographic) = match cam.fov_y_deg {
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
                let h = cam.ortho_height;
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
    for (i, l) in lights.iter().enumerate() {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
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
