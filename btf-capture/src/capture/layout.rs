//! What a lab knows about a capture, read from `capture.toml`: the view/light sampling,
//! the image naming, the pinhole intrinsics, the plate's marker layout and the radiometric
//! calibration; and the nominal camera of every view, from which the nominal plane
//! homography `H = K · M · [r₁ r₂ t − c]` (sample mm → image pixels) follows — the
//! pinhole model of Hartley & Zisserman, *Multiple View Geometry*, eq. 8.1 restricted to
//! the plane `z = 0`.
//!
//! Image pixel `(c, r)` covers `[c, c+1) × [r, r+1)`; continuous image coordinates are
//! measured from the top-left corner. The nominal camera of a view looks at the plate
//! centre from the view direction; its image up is the projection of the plate normal
//! (sample `+y` for the frontal view), as the virtual gonioreflectometer does.

use crate::{Error, Result};
use btf_core::{Direction, Ring, Sampling};
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The parsed `capture.toml`.
#[derive(Debug, Clone)]
pub struct CaptureLayout {
    /// Folder holding `capture.toml` and the raw images.
    pub dir: PathBuf,
    /// View and light sampling (the same set of directions).
    pub sampling: Sampling,
    /// Camera intrinsics and sensor.
    pub camera: CameraToml,
    /// Plate geometry and markers.
    pub plate: PlateToml,
    /// Radiometric calibration, when the lab provides one.
    pub radiometry: Option<RadiometryToml>,
    /// The material recipe, passed through to provenance (synthetic captures).
    pub material: serde_json::Value,
}

#[derive(Debug, Deserialize)]
struct CaptureToml {
    version: u32,
    sampling: String,
    directions_deg: Vec<[f64; 2]>,
    rings: Option<Vec<Ring>>,
    camera: CameraToml,
    plate: PlateToml,
    radiometry: Option<RadiometryToml>,
    material: Option<toml::Value>,
}

/// `[camera]` of `capture.toml`.
#[derive(Debug, Clone, Deserialize)]
pub struct CameraToml {
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
    /// Focal length (pixels).
    pub focal_px: f64,
    /// Principal point (pixels from the top-left corner).
    pub principal_point_px: [f64; 2],
    /// Distance from the camera to the plate centre (mm).
    pub distance_mm: f64,
    /// Sensor bits (values are stored left-aligned in 16-bit files).
    pub bits: u32,
}

/// `[plate]` of `capture.toml` (all in sample millimetres, origin at the sample centre).
#[derive(Debug, Clone, Deserialize)]
pub struct PlateToml {
    /// Plate side.
    pub size_mm: f64,
    /// Sample side (centred square).
    pub sample_mm: f64,
    /// Centres of the point markers.
    pub point_markers_mm: Vec<[f64; 2]>,
    /// Radius of the point markers.
    pub marker_radius_mm: f64,
    /// Half-size of the square of border lines, to the line centres.
    pub border_offset_mm: f64,
    /// Width of the border lines.
    pub border_width_mm: f64,
}

/// `[radiometry]` of `capture.toml`.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct RadiometryToml {
    /// DN of a white Lambertian reference at normal incidence under the reference light.
    pub reference_white_dn: f64,
    /// Flat field `cos^k` of the angle to the optical axis.
    pub vignetting_cos_power: f64,
}

fn invalid(path: &Path, field: &str, what: impl Into<String>) -> Error {
    Error::invalid(&path.display().to_string(), field, what)
}

impl CaptureLayout {
    /// Reads and checks `DIR/capture.toml`.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("capture.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let t: CaptureToml =
            toml::from_str(&text).map_err(|e| invalid(&path, "toml", e.to_string()))?;
        if t.version != 1 {
            return Err(Error::unsupported(&path.display().to_string(), "capture.toml version"));
        }
        let sampling = match t.rings {
            Some(rings) => Sampling::new(t.sampling.clone(), rings),
            None => Sampling::by_name(&t.sampling),
        }
        .map_err(|e| invalid(&path, "sampling", e.to_string()))?;
        check_directions(&path, &sampling, &t.directions_deg)?;
        let c = &t.camera;
        let plausible = (1..=16384).contains(&c.width)
            && (1..=16384).contains(&c.height)
            && c.focal_px.is_finite()
            && c.focal_px > 0.0
            && c.distance_mm.is_finite()
            && c.distance_mm > 0.0
            && (1..=16).contains(&c.bits);
        if !plausible {
            return Err(invalid(
                &path,
                "camera",
                "size, focal length, distance or bits out of range",
            ));
        }
        let p = &t.plate;
        if p.point_markers_mm.len() < 4 || !(p.sample_mm > 0.0 && p.marker_radius_mm > 0.0) {
            return Err(invalid(&path, "plate", "needs ≥ 4 point markers and positive sizes"));
        }
        let material = match t.material {
            Some(m) => serde_json::to_value(m).unwrap_or_default(),
            None => serde_json::Value::Null,
        };
        Ok(CaptureLayout {
            dir: dir.to_owned(),
            sampling,
            camera: t.camera,
            plate: t.plate,
            radiometry: t.radiometry,
            material,
        })
    }

    /// Path of the raw image of view `j` under light `i`
    /// (`tvTTT_pvPPP/tlTTT_plPPP_tvTTT_pvPPP.png`, rounded integer degrees).
    pub fn image_path(&self, view: usize, light: usize) -> PathBuf {
        let (v, l) = (self.sampling.direction(view), self.sampling.direction(light));
        let f = |x: f64| format!("{:03}", x.round() as i64 % 360);
        let dir = format!("tv{}_pv{}", f(v.theta_deg), f(v.phi_deg));
        let name = format!("tl{}_pl{}_{dir}", f(l.theta_deg), f(l.phi_deg));
        let base = self.dir.join(&dir).join(&name);
        for ext in ["png", "tif", "tiff", "exr"] {
            let p = base.with_extension(ext);
            if p.exists() {
                return p;
            }
        }
        base.with_extension("png")
    }

    /// The camera matrix `K` (pixels; image `v` grows downwards).
    pub fn intrinsics(&self) -> Matrix3<f64> {
        let c = &self.camera;
        let [cx, cy] = c.principal_point_px;
        Matrix3::new(c.focal_px, 0.0, cx, 0.0, -c.focal_px, cy, 0.0, 0.0, 1.0)
    }

    /// Homography sample mm `(x, y, 1)` → image pixels for view `j` with the plate placed
    /// at `p_lab = R · p_sample + t` (`R = I`, `t = 0` is the nominal pose).
    pub fn homography(
        &self,
        view: usize,
        rotation: &Matrix3<f64>,
        t_mm: &Vector3<f64>,
    ) -> Matrix3<f64> {
        let (centre, axes) = self.camera_frame(self.sampling.direction(view));
        let mut plane = Matrix3::zeros();
        plane.set_column(0, &rotation.column(0));
        plane.set_column(1, &rotation.column(1));
        plane.set_column(2, &(t_mm - centre));
        self.intrinsics() * axes * plane
    }

    /// The nominal homography of view `j`.
    pub fn nominal_homography(&self, view: usize) -> Matrix3<f64> {
        self.homography(view, &Matrix3::identity(), &Vector3::zeros())
    }

    /// The plate pose `(R, t)` (`p_lab = R · p_sample + t`, mm) of view `j` behind a
    /// homography `h` (sample mm → pixels): inverting [`CaptureLayout::homography`],
    /// `Aᵀ K⁻¹ h = λ [r₁ r₂ t − c]` (H&Z §8.8, Zhang's plane-based decomposition), with
    /// `λ` the mean length of the first two columns, its sign putting the plate in front
    /// of the camera, and `r₁, r₂` made orthonormal (`r₃ = r₁ × r₂`). `None` for a
    /// degenerate `h`.
    pub fn pose_from_homography(
        &self,
        view: usize,
        h: &Matrix3<f64>,
    ) -> Option<(Matrix3<f64>, Vector3<f64>)> {
        let (centre, axes) = self.camera_frame(self.sampling.direction(view));
        let m = axes.transpose() * self.intrinsics().try_inverse()? * h;
        let (c1, c2) = (m.column(0).into_owned(), m.column(1).into_owned());
        let mut lambda = 0.5 * (c1.norm() + c2.norm());
        // The plate centre lies ahead of the camera: (t − c) points along −view.
        if m.column(2).dot(&centre) > 0.0 {
            lambda = -lambda;
        }
        if lambda.is_nan() || lambda.abs() <= 1e-12 {
            return None;
        }
        let r1 = (c1 / lambda).try_normalize(1e-12)?;
        let r2 = (c2 / lambda - r1 * r1.dot(&(c2 / lambda))).try_normalize(1e-12)?;
        let rotation = Matrix3::from_columns(&[r1, r2, r1.cross(&r2)]);
        Some((rotation, m.column(2) / lambda + centre))
    }

    /// Camera centre (lab mm) and the matrix whose rows are its right, up and forward axes.
    fn camera_frame(&self, view: Direction) -> (Vector3<f64>, Matrix3<f64>) {
        let v = view.to_vector();
        let v = Vector3::new(v[0], v[1], v[2]);
        let forward = -v;
        let up_hint = if v.z > 0.9999 { Vector3::y() } else { Vector3::z() };
        let right = forward.cross(&up_hint).try_normalize(1e-12).unwrap_or(Vector3::x());
        let up = right.cross(&forward);
        let axes = Matrix3::from_rows(&[right.transpose(), up.transpose(), forward.transpose()]);
        (v * self.camera.distance_mm, axes)
    }

    /// Unit vector from a pixel position towards the scene, in the camera frame, and its
    /// cosine to the optical axis (for the flat field).
    pub fn axis_cosine(&self, u: f64, v: f64) -> f64 {
        let [cx, cy] = self.camera.principal_point_px;
        let (dx, dy, f) = (u - cx, v - cy, self.camera.focal_px);
        f / (dx * dx + dy * dy + f * f).sqrt()
    }
}

fn check_directions(path: &Path, s: &Sampling, dirs: &[[f64; 2]]) -> Result<()> {
    if dirs.len() != s.len() {
        return Err(invalid(
            path,
            "directions_deg",
            format!("{} directions, but sampling {} has {}", dirs.len(), s.describe(), s.len()),
        ));
    }
    for (i, d) in dirs.iter().enumerate() {
        let e = s.direction(i);
        let dphi = ((d[1] - e.phi_deg + 540.0) % 360.0 - 180.0).abs();
        if (d[0] - e.theta_deg).abs() > 1e-6 || (e.theta_deg > 0.0 && dphi > 1e-6) {
            return Err(invalid(
                path,
                "directions_deg",
                format!(
                    "direction {i} is {d:?}, the sampling says [{}, {}]",
                    e.theta_deg, e.phi_deg
                ),
            ));
        }
    }
    Ok(())
}

/// Applies a homography to a point.
pub fn apply(h: &Matrix3<f64>, p: [f64; 2]) -> [f64; 2] {
    let q = h * Vector3::new(p[0], p[1], 1.0);
    [q.x / q.z, q.y / q.z]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 1280×960 camera at 600 mm; views at the pole and 75° (four azimuths).
    pub(crate) fn layout() -> CaptureLayout {
        let ring = |theta_deg: f64, count: usize| Ring { theta_deg, count, phi_offset_deg: 0.0 };
        CaptureLayout {
            dir: PathBuf::from("."),
            sampling: Sampling::new("rings", vec![ring(0.0, 1), ring(75.0, 4)]).unwrap(),
            camera: CameraToml {
                width: 1280,
                height: 960,
                focal_px: 2304.0,
                principal_point_px: [640.0, 480.0],
                distance_mm: 600.0,
                bits: 12,
            },
            plate: PlateToml {
                size_mm: 140.0,
                sample_mm: 80.0,
                point_markers_mm: vec![[0.0, 0.0]; 4],
                marker_radius_mm: 2.0,
                border_offset_mm: 42.0,
                border_width_mm: 1.0,
            },
            radiometry: None,
            material: serde_json::Value::Null,
        }
    }

    #[test]
    fn pose_is_recovered_from_its_homography() {
        let l = layout();
        // A 1.5° tilt about a skew axis and a few millimetres of shift.
        let axis = nalgebra::Unit::new_normalize(Vector3::new(0.3, -0.8, 0.5));
        let r = *nalgebra::Rotation3::from_axis_angle(&axis, 1.5f64.to_radians()).matrix();
        let t = Vector3::new(1.0, -2.0, 0.5);
        for view in 0..l.sampling.len() {
            // Any scale of the homography (even negative) describes the same pose.
            let h = l.homography(view, &r, &t) * -3.7;
            let (r_est, t_est) = l.pose_from_homography(view, &h).unwrap();
            assert!((r_est - r).amax() < 1e-9, "view {view}: {r_est} vs {r}");
            assert!((t_est - t).amax() < 1e-6, "view {view}: {t_est} vs {t}");
        }
        assert!(l.pose_from_homography(0, &Matrix3::zeros()).is_none());
    }
}
