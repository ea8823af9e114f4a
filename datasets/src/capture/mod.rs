//! The virtual gonioreflectometer: raw photographs of a synthetic sample on its holder
//! plate, as a capture lab would take them (Sattler et al. 2003, §3.1–3.2 and Fig. 5).
//!
//! The plate (dark, 140 mm square) carries the sample (80 mm square, the material's
//! normtexture) framed by four white border lines, and nine white point markers: eight
//! around the frame and one orientation marker that breaks the plate's symmetry. For every
//! view direction a pinhole camera at 600 mm looks at the plate centre; for every light
//! direction a distant lamp lights it. The robot holding the plate misplaces it a little
//! for every view (a random rotation of `pose_noise_deg` and shift of `pose_noise_mm`);
//! the sensor adds natural `cos⁴` vignetting, shot and read noise, and quantises to 12
//! bits, stored left-aligned in 16-bit RGB PNGs (`DN << 4`).
//!
//! `capture.toml` describes what a lab knows (nominal geometry, intrinsics, marker layout,
//! sampling, naming, the material recipe); the true poses go to `truth.toml`, which capture
//! processing must never read. The ground truth of the rectified result is the same
//! material (recorded kind, size and seed) averaged over each output texel's square and
//! seen from the true camera position (`btf capture score`; `--nominal`: orthographic at
//! the nominal directions) — a texel stands for its square, and the material has detail
//! finer than a texel.
//!
//! **Image orientation.** A right-handed camera above the sample sees it unmirrored: in
//! the frontal image (θ_v = 0) image right is sample `+x` and image up is sample `+y`, so
//! image rows run along `−y` — the opposite of normtexture rows (DESIGN.md §3). Rectifying
//! with the marker layout (in sample millimetres) takes care of it.

pub mod render;

pub use render::{CaptureReport, capture};

use crate::material::MaterialSpec;
use serde::Serialize;

/// Everything that defines a virtual capture.
#[derive(Debug, Clone)]
pub struct CaptureSpec {
    /// The material on the plate, and the view/light sampling (`material.sampling`).
    pub material: MaterialSpec,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Standard deviation of the robot's rotation error per view (degrees).
    pub pose_noise_deg: f64,
    /// Standard deviation of the robot's position error per view and axis (mm).
    pub pose_noise_mm: f64,
    /// Read noise (DN, standard deviation).
    pub read_noise_dn: f64,
    /// Shot-noise variance per DN of signal.
    pub shot_noise_per_dn: f64,
    /// Exponent scale of the `cos⁴` vignetting (0 = none, 1 = natural).
    pub vignetting: f64,
    /// Seed of poses and noise.
    pub seed: u64,
    /// Rays per pixel side: `k²` stratified rays average the pixel's area as a real sensor
    /// does (1 = one ray through the pixel centre, the original point-sampled images).
    pub supersample: usize,
}

impl CaptureSpec {
    /// Defaults: 320×240 pixels, 1° and 1 mm pose errors (the robot tolerance issue #4 names), 2 DN read noise, 0.5 DN²/DN
    /// shot noise, natural vignetting.
    pub fn new(material: MaterialSpec) -> Self {
        CaptureSpec {
            material,
            width: 320,
            height: 240,
            pose_noise_deg: 1.0,
            pose_noise_mm: 1.0,
            read_noise_dn: 2.0,
            shot_noise_per_dn: 0.5,
            vignetting: 1.0,
            seed: 1,
            supersample: 1,
        }
    }
}

/// Plate side (mm).
pub const PLATE_MM: f64 = 140.0;
/// Sample side (mm).
pub const SAMPLE_MM: f64 = 80.0;
/// Camera distance from the plate centre (mm).
pub const CAMERA_DISTANCE_MM: f64 = 600.0;
/// Distance of the border lines' centre lines from the plate centre (mm).
pub const BORDER_OFFSET_MM: f64 = 46.0;
/// Width of the border lines (mm).
pub const BORDER_WIDTH_MM: f64 = 3.0;
/// Radius of the point markers (mm).
pub const MARKER_RADIUS_MM: f64 = 4.0;
/// Albedo of the plate and of the white markers.
pub const PLATE_ALBEDO: f64 = 0.04;
/// Albedo of the markers.
pub const MARKER_ALBEDO: f64 = 0.85;

/// Centres (mm, sample frame) of the point markers; the last one is the orientation marker.
pub fn point_markers() -> Vec<[f64; 2]> {
    let a = 60.0;
    vec![[-a, -a], [0.0, -a], [a, -a], [a, 0.0], [a, a], [0.0, a], [-a, a], [-a, 0.0], [30.0, a]]
}

/// Radiometric albedo of the plate at `(x, y)` mm (outside the sample), 0 off the plate.
pub fn plate_albedo(x: f64, y: f64) -> f64 {
    let h = PLATE_MM / 2.0;
    if x.abs() > h || y.abs() > h {
        return 0.0;
    }
    let markers = point_markers();
    if markers.iter().any(|m| (x - m[0]).powi(2) + (y - m[1]).powi(2) <= MARKER_RADIUS_MM.powi(2)) {
        return MARKER_ALBEDO;
    }
    let (o, w) = (BORDER_OFFSET_MM, BORDER_WIDTH_MM / 2.0);
    let on_line = |u: f64, v: f64| (u.abs() - o).abs() <= w && v.abs() <= o + w;
    if on_line(x, y) || on_line(y, x) { MARKER_ALBEDO } else { PLATE_ALBEDO }
}

/// `capture.toml`: what the lab knows.
#[derive(Debug, Serialize)]
pub struct CaptureDescription {
    /// Format version.
    pub version: u32,
    /// Name of the view and light sampling and its directions in index order.
    pub sampling: String,
    /// The sampling's rings (so that custom samplings can be rebuilt).
    pub rings: Vec<btf_core::Ring>,
    /// `[θ, φ]` in degrees of every direction (index order).
    pub directions_deg: Vec<[f64; 2]>,
    /// Image naming pattern.
    pub naming: String,
    /// Camera intrinsics and sensor.
    pub camera: CameraDescription,
    /// Plate and sample geometry.
    pub plate: PlateDescription,
    /// The lab's radiometric calibration (light reference and flat field).
    pub radiometry: RadiometryDescription,
    /// How the material was made (to regenerate the ground truth).
    pub material: serde_json::Value,
}

/// Camera part of `capture.toml`.
#[derive(Debug, Serialize)]
pub struct CameraDescription {
    /// Pixels.
    pub width: usize,
    /// Pixels.
    pub height: usize,
    /// Focal length (pixels).
    pub focal_px: f64,
    /// Principal point (pixels, from the top-left corner).
    pub principal_point_px: [f64; 2],
    /// Nominal distance to the plate centre (mm), looking at it.
    pub distance_mm: f64,
    /// Sensor bits; values are stored as `DN << (16 − bits)` in 16-bit PNGs.
    pub bits: u32,
    /// Image axes of the frontal view.
    pub frontal_axes: String,
    /// Light model.
    pub light: String,
}

/// Plate part of `capture.toml`.
#[derive(Debug, Serialize)]
pub struct PlateDescription {
    /// Plate side (mm).
    pub size_mm: f64,
    /// Sample side (mm), centred.
    pub sample_mm: f64,
    /// Point markers `[x, y]` (mm); the last is the orientation marker.
    pub point_markers_mm: Vec<[f64; 2]>,
    /// Marker radius (mm).
    pub marker_radius_mm: f64,
    /// Border lines: squares' half-size to the line centre (mm) and line width (mm).
    pub border_offset_mm: f64,
    /// Border line width (mm).
    pub border_width_mm: f64,
}

/// Radiometry part of `capture.toml`: what a lab calibrates with a white reference tile and
/// a flat-field exposure.
#[derive(Debug, Serialize)]
pub struct RadiometryDescription {
    /// DN of a white (albedo 1) Lambertian reference at normal light and view incidence,
    /// for the lamp's reference irradiance: `BTF = DN / (reference_white_dn · π)`.
    pub reference_white_dn: f64,
    /// Flat field: pixel values fall off as `cos^k` of the ray angle to the optical axis.
    pub vignetting_cos_power: f64,
}

/// Parses a sampling name (`ubo81`, `ubo81-h1`, `dome151`) or a custom ring list
/// `rings:θxCOUNT,θxCOUNT,…` (degrees, e.g. `rings:0x1,45x4,75x6`), for small test captures.
pub fn parse_sampling(spec: &str) -> crate::Result<btf_core::Sampling> {
    let Some(list) = spec.strip_prefix("rings:") else {
        return Ok(btf_core::Sampling::by_name(spec)?);
    };
    let bad =
        || crate::Error::Invalid(format!("sampling '{spec}': expected rings:THETAxCOUNT,..."));
    let rings = list
        .split(',')
        .map(|r| {
            let (t, c) = r.split_once('x').ok_or_else(bad)?;
            Ok(btf_core::Ring {
                theta_deg: t.trim().parse().map_err(|_| bad())?,
                count: c.trim().parse().map_err(|_| bad())?,
                phi_offset_deg: 0.0,
            })
        })
        .collect::<crate::Result<Vec<_>>>()?;
    Ok(btf_core::Sampling::new("custom", rings)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn custom_sampling_parses() {
        let s = parse_sampling("rings:0x1,45x4,75x6").unwrap();
        assert_eq!(s.len(), 11);
        assert_eq!(s.direction(5).theta_deg, 75.0);
        assert_eq!(parse_sampling("ubo81").unwrap().len(), 81);
        assert!(parse_sampling("rings:0x2").is_err());
        assert!(parse_sampling("rings:abc").is_err());
    }
}
