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

use super::config::{self, Checker};
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
#[serde(deny_unknown_fields)]
struct CaptureToml {
    version: u32,
    sampling: String,
    directions_deg: Vec<[f64; 2]>,
    rings: Option<Vec<RingToml>>,
    naming: Option<String>,
    camera: CameraToml,
    plate: PlateToml,
    radiometry: Option<RadiometryToml>,
    material: Option<MaterialToml>,
}

/// `[[rings]]` of `capture.toml` (a [`Ring`], read strictly).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RingToml {
    theta_deg: f64,
    count: usize,
    phi_offset_deg: f64,
}

/// `[material]` of `capture.toml`: the recipe of a synthetic capture's sample.
#[derive(Debug, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct MaterialToml {
    kind: String,
    size: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    albedo: Option<[f64; 3]>,
}

/// `[camera]` of `capture.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
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
    /// Description of the frontal view's image axes (informative).
    #[serde(default)]
    pub frontal_axes: Option<String>,
    /// Description of the light (informative).
    #[serde(default)]
    pub light: Option<String>,
}

/// `[plate]` of `capture.toml` (all in sample millimetres, origin at the sample centre).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
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
#[serde(deny_unknown_fields)]
pub struct RadiometryToml {
    /// DN of a white Lambertian reference at normal incidence under the reference light.
    pub reference_white_dn: f64,
    /// Flat field `cos^k` of the angle to the optical axis.
    pub vignetting_cos_power: f64,
}

/// Largest image side `capture.toml` may claim (pixels).
pub const MAX_IMAGE_SIDE: usize = 16384;
/// Largest plate side, focal length (pixels) and camera distance accepted (mm, px).
pub const MAX_LENGTH: f64 = 1e6;
/// Most point markers a layout may have: the consensus tries every 4-subset (O(n⁴)).
pub const MAX_POINT_MARKERS: usize = 32;
/// The image naming this reader supports (`naming` must start with it).
pub const NAMING: &str = "tvTTT_pvPPP/tlTTT_plPPP_tvTTT_pvPPP";

impl CaptureLayout {
    /// Reads and checks `DIR/capture.toml`: unknown keys and tables are errors, and every
    /// number is range-checked; each message names the file and the key.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("capture.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        Self::from_text(dir, &path.display().to_string(), &text)
    }

    /// [`CaptureLayout::read`] on `text`, the `capture.toml` of the images in `dir`
    /// (messages name `file`).
    pub fn from_text(dir: &Path, file: &str, text: &str) -> Result<Self> {
        let file = file.to_owned();
        let t: CaptureToml = config::parse(&file, text)?;
        let c = Checker { file: &file };
        if t.version != 1 {
            return Err(c.bad("version", t.version, "unsupported (this toolkit reads version 1)"));
        }
        if let Some(n) = &t.naming
            && !n.starts_with(NAMING)
        {
            return Err(c.bad(
                "naming",
                format!("{n:?}"),
                format!("unsupported: expected {NAMING}"),
            ));
        }
        let sampling = match &t.rings {
            Some(rings) => Sampling::new(
                t.sampling.clone(),
                rings
                    .iter()
                    .map(|r| Ring {
                        theta_deg: r.theta_deg,
                        count: r.count,
                        phi_offset_deg: r.phi_offset_deg,
                    })
                    .collect(),
            )
            .map_err(|e| c.wrong("[[rings]]", e.to_string())),
            None => Sampling::by_name(&t.sampling)
                .map_err(|e| c.bad("sampling", format!("{:?}", t.sampling), e.to_string())),
        }?;
        check_directions(&c, &sampling, &t.directions_deg)?;
        check_camera(&c, &t.camera)?;
        check_plate(&c, &t.plate, &t.camera)?;
        if let Some(r) = &t.radiometry {
            c.positive("[radiometry] reference_white_dn", r.reference_white_dn, 1e12)?;
            c.within("[radiometry] vignetting_cos_power", r.vignetting_cos_power, 0.0, 16.0)?;
        }
        let material = match t.material {
            Some(m) => {
                if m.kind.trim().is_empty() {
                    return Err(c.bad("[material] kind", "\"\"", "must name a material kind"));
                }
                c.count("[material] size", m.size, 1, 8192)?;
                for (k, a) in m.albedo.iter().flatten().enumerate() {
                    c.within(&format!("[material] albedo[{k}]"), *a, 0.0, 1.0)?;
                }
                serde_json::to_value(m).unwrap_or_default()
            }
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

fn check_directions(c: &Checker, s: &Sampling, dirs: &[[f64; 2]]) -> Result<()> {
    if dirs.len() != s.len() {
        return Err(c.wrong(
            "directions_deg",
            format!("{} directions, but sampling {} has {}", dirs.len(), s.describe(), s.len()),
        ));
    }
    for (i, d) in dirs.iter().enumerate() {
        let key = format!("directions_deg[{i}]");
        c.within(&key, d[0], 0.0, 90.0)?;
        c.finite(&key, d[1])?;
        let e = s.direction(i);
        let dphi = ((d[1] - e.phi_deg + 540.0).rem_euclid(360.0) - 180.0).abs();
        if (d[0] - e.theta_deg).abs() > 1e-6 || (e.theta_deg > 0.0 && dphi > 1e-6) {
            return Err(c.bad(
                &key,
                format!("{d:?}"),
                format!("the sampling says [{}, {}]", e.theta_deg, e.phi_deg),
            ));
        }
    }
    Ok(())
}

fn check_camera(c: &Checker, cam: &CameraToml) -> Result<()> {
    let side = MAX_IMAGE_SIDE as u64;
    c.count("[camera] width", cam.width as u64, 1, side)?;
    c.count("[camera] height", cam.height as u64, 1, side)?;
    c.positive("[camera] focal_px", cam.focal_px, MAX_LENGTH)?;
    let [cx, cy] = cam.principal_point_px;
    c.within("[camera] principal_point_px[0]", cx, 0.0, cam.width as f64)?;
    c.within("[camera] principal_point_px[1]", cy, 0.0, cam.height as f64)?;
    c.positive("[camera] distance_mm", cam.distance_mm, MAX_LENGTH)?;
    c.count("[camera] bits", cam.bits as u64, 1, 16)?;
    Ok(())
}

/// Whether the disc of radius `r` at `p` meets the axis-aligned rectangle `[lo, hi]`.
fn disc_meets_rect(p: [f64; 2], r: f64, lo: [f64; 2], hi: [f64; 2]) -> bool {
    let q = [p[0].clamp(lo[0], hi[0]), p[1].clamp(lo[1], hi[1])];
    (p[0] - q[0]).hypot(p[1] - q[1]) < r
}

fn check_plate(c: &Checker, p: &PlateToml, cam: &CameraToml) -> Result<()> {
    let size = c.positive("[plate] size_mm", p.size_mm, MAX_LENGTH)?;
    let sample = c.positive("[plate] sample_mm", p.sample_mm, size)?;
    let radius = c.positive("[plate] marker_radius_mm", p.marker_radius_mm, size / 4.0)?;
    let offset = c.positive("[plate] border_offset_mm", p.border_offset_mm, size / 2.0)?;
    let width = c.positive("[plate] border_width_mm", p.border_width_mm, size / 2.0)?;
    let (inner, outer) = (offset - width / 2.0, offset + width / 2.0);
    if inner < sample / 2.0 || outer > size / 2.0 {
        return Err(c.bad(
            "[plate] border_offset_mm",
            offset,
            format!(
                "with border_width_mm = {width} the border lines span {inner}..{outer} mm from \
                 the centre: they must lie between the sample's edge ({}) and the plate's ({})",
                sample / 2.0,
                size / 2.0
            ),
        ));
    }
    let half_diagonal = size / std::f64::consts::SQRT_2;
    if cam.distance_mm <= half_diagonal {
        return Err(c.bad(
            "[camera] distance_mm",
            cam.distance_mm,
            format!("must exceed the plate's half-diagonal ({half_diagonal:.1} mm)"),
        ));
    }
    let m = &p.point_markers_mm;
    let n = m.len() as u64;
    c.count("[plate] point_markers_mm (count)", n, 4, MAX_POINT_MARKERS as u64)?;
    // The border lines as four rectangles (mm).
    let lines = [
        ([inner, -outer], [outer, outer]),
        ([-outer, -outer], [-inner, outer]),
        ([-outer, inner], [outer, outer]),
        ([-outer, -outer], [outer, -inner]),
    ];
    for (k, &q) in m.iter().enumerate() {
        let key = format!("[plate] point_markers_mm[{k}]");
        c.finite(&key, q[0])
            .and_then(|_| c.finite(&key, q[1]))
            .map_err(|_| c.bad(&key, format!("{q:?}"), "must be finite"))?;
        let fail = |what: String| c.bad(&key, format!("{q:?}"), what);
        if q[0].abs() + radius > size / 2.0 || q[1].abs() + radius > size / 2.0 {
            return Err(fail(format!(
                "the marker (radius {radius}) must lie on the plate (±{})",
                size / 2.0
            )));
        }
        let h = sample / 2.0;
        if disc_meets_rect(q, radius, [-h, -h], [h, h]) {
            return Err(fail(format!("the marker (radius {radius}) overlaps the sample (±{h})")));
        }
        if lines.iter().any(|&(lo, hi)| disc_meets_rect(q, radius, lo, hi)) {
            return Err(fail(format!("the marker (radius {radius}) overlaps a border line")));
        }
        if let Some(j) = m[..k].iter().position(|o| (o[0] - q[0]).hypot(o[1] - q[1]) < 2.0 * radius)
        {
            return Err(fail(format!("the marker overlaps marker {j} at {:?}", m[j])));
        }
    }
    if !super::homography::general_position(m) {
        return Err(c.wrong(
            "[plate] point_markers_mm",
            "no four markers are in general position (no three on a line): they cannot fix a homography",
        ));
    }
    Ok(())
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
                frontal_axes: None,
                light: None,
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

    /// `capture.toml` as `datasets` writes it (pole + four views at 75°, 480×360).
    pub(crate) const GOOD: &str = r#"version = 1
sampling = "custom"
directions_deg = [[0.0, 0.0], [75.0, 0.0], [75.0, 90.0], [75.0, 180.0], [75.0, 270.0]]
naming = "tvTTT_pvPPP/tlTTT_plPPP_tvTTT_pvPPP.png (rounded integer degrees)"

[[rings]]
theta_deg = 0.0
count = 1
phi_offset_deg = 0.0

[[rings]]
theta_deg = 75.0
count = 4
phi_offset_deg = 0.0

[camera]
width = 480
height = 360
focal_px = 864.0
principal_point_px = [240.0, 180.0]
distance_mm = 600.0
bits = 12
frontal_axes = "image right = sample +x, image up = sample +y (rows run along -y)"
light = "distant lamp"

[plate]
size_mm = 140.0
sample_mm = 80.0
point_markers_mm = [[-60.0, -60.0], [0.0, -60.0], [60.0, -60.0], [60.0, 0.0], [60.0, 60.0], [0.0, 60.0], [-60.0, 60.0], [-60.0, 0.0], [30.0, 60.0]]
marker_radius_mm = 4.0
border_offset_mm = 46.0
border_width_mm = 3.0

[radiometry]
reference_white_dn = 3685.5
vignetting_cos_power = 4.0

[material]
kind = "knit"
seed = 1
size = 64
"#;

    /// Reads `text` as a `capture.toml`.
    fn read_text(text: &str) -> Result<CaptureLayout> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("capture.toml"), text).unwrap();
        CaptureLayout::read(dir.path())
    }

    /// The message of reading `GOOD` with `from` replaced by `to` (which must occur).
    fn refused(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        let e = read_text(&GOOD.replacen(from, to, 1)).expect_err(to).to_string();
        assert!(e.contains("capture.toml: "), "the file must be named: {e}");
        e
    }

    #[test]
    fn the_file_datasets_writes_is_read() {
        let l = read_text(GOOD).unwrap();
        assert_eq!((l.camera.width, l.sampling.len(), l.plate.point_markers_mm.len()), (480, 5, 9));
        assert!((l.radiometry.unwrap().reference_white_dn - 3685.5).abs() < 1e-12);
        assert_eq!(l.material["kind"], "knit");
        assert_eq!(l.material["size"], 64);
        // Optional parts may be left out.
        let minimal = GOOD.replace("naming = ", "# naming = ").replace("[radiometry]", "[xx]");
        let minimal = minimal.split("[xx]").next().unwrap();
        assert!(read_text(minimal).unwrap().radiometry.is_none());
    }

    #[test]
    fn unknown_tables_and_keys_are_refused_by_name() {
        let e = refused("[radiometry]", "[radiometri]");
        assert!(e.contains("[radiometri]") && e.contains("unknown field `radiometri`"), "{e}");
        let e = refused("bits = 12", "bits = 12\nfocal = 3.0");
        assert!(e.contains("[camera] focal: unknown field `focal`"), "{e}");
        let e = refused("border_width_mm = 3.0", "border_width_mm = 3.0\nborder_colour = 1");
        assert!(e.contains("[plate] border_colour"), "{e}");
        let e = refused("vignetting_cos_power = 4.0", "vignetting_cos_power = 4.0\nwhite = 1.0");
        assert!(e.contains("[radiometry] white"), "{e}");
        let e = refused("size = 64", "size = 64\nsise = 32");
        assert!(e.contains("[material] sise"), "{e}");
        let e = refused("phi_offset_deg = 0.0", "phi_offset_deg = 0.0\nphi_ofset_deg = 0.0");
        assert!(e.contains("[[rings]] phi_ofset_deg"), "{e}");
        let e = refused("version = 1", "version = 1\nversoin = 1");
        assert!(e.contains("versoin: unknown field"), "{e}");
        let e = refused("focal_px = 864.0\n", "");
        assert!(e.contains("[camera]") && e.contains("missing field `focal_px`"), "{e}");
        let e = refused("width = 480", "width = -480");
        assert!(e.contains("[camera] width"), "{e}");
    }

    #[test]
    fn numbers_out_of_range_are_refused_naming_key_and_value() {
        let cases = [
            ("size_mm = 140.0", "size_mm = -140.0", "[plate] size_mm = -140: must be > 0"),
            ("border_width_mm = 3.0", "border_width_mm = inf", "[plate] border_width_mm = inf"),
            ("border_width_mm = 3.0", "border_width_mm = 0.0", "[plate] border_width_mm = 0"),
            ("border_offset_mm = 46.0", "border_offset_mm = 30.0", "[plate] border_offset_mm = 30"),
            ("border_offset_mm = 46.0", "border_offset_mm = 69.0", "[plate] border_offset_mm = 69"),
            ("sample_mm = 80.0", "sample_mm = 200.0", "[plate] sample_mm = 200: must be ≤ 140"),
            ("sample_mm = 80.0", "sample_mm = nan", "[plate] sample_mm = NaN"),
            ("marker_radius_mm = 4.0", "marker_radius_mm = -4.0", "[plate] marker_radius_mm = -4"),
            (
                "[[-60.0, -60.0],",
                "[[-68.0, -60.0],",
                "[plate] point_markers_mm[0] = [-68.0, -60.0]",
            ),
            ("[[-60.0, -60.0],", "[[-30.0, -30.0],", "overlaps the sample"),
            ("[[-60.0, -60.0],", "[[0.0, -57.0],", "overlaps marker"),
            ("[[-60.0, -60.0],", "[[-46.0, -50.0],", "overlaps a border line"),
            ("[[-60.0, -60.0],", "[[nan, -60.0],", "[plate] point_markers_mm[0] = [NaN, -60.0]"),
            (
                "principal_point_px = [240.0, 180.0]",
                "principal_point_px = [nan, 180.0]",
                "[camera] principal_point_px[0] = NaN: must be a finite number",
            ),
            (
                "principal_point_px = [240.0, 180.0]",
                "principal_point_px = [240.0, 400.0]",
                "[camera] principal_point_px[1] = 400: must be in [0, 360]",
            ),
            ("width = 480", "width = 0", "[camera] width = 0: must be in 1..=16384"),
            ("height = 360", "height = 100000", "[camera] height = 100000: must be in 1..=16384"),
            ("focal_px = 864.0", "focal_px = -864.0", "[camera] focal_px = -864: must be > 0"),
            ("focal_px = 864.0", "focal_px = inf", "[camera] focal_px = inf"),
            ("distance_mm = 600.0", "distance_mm = 50.0", "[camera] distance_mm = 50: must exceed"),
            ("bits = 12", "bits = 17", "[camera] bits = 17: must be in 1..=16"),
            ("bits = 12", "bits = 0", "[camera] bits = 0"),
            (
                "reference_white_dn = 3685.5",
                "reference_white_dn = 0.0",
                "[radiometry] reference_white_dn = 0: must be > 0",
            ),
            (
                "vignetting_cos_power = 4.0",
                "vignetting_cos_power = -1.0",
                "[radiometry] vignetting_cos_power = -1: must be in [0, 16]",
            ),
            ("size = 64", "size = 0", "[material] size = 0"),
            ("seed = 1", "seed = 1\nalbedo = [0.5, 2.0, 0.5]", "[material] albedo[1] = 2"),
            ("version = 1", "version = 2", "version = 2: unsupported"),
            (
                "naming = \"tvTTT",
                "naming = \"img_%04d.png\" # \"tvTTT",
                "naming = \"img_%04d.png\"",
            ),
            ("[75.0, 0.0], [75.0, 90.0]", "[nan, 0.0], [75.0, 90.0]", "directions_deg[1] = NaN"),
            (
                "[75.0, 0.0], [75.0, 90.0]",
                "[75.0, 10.0], [75.0, 90.0]",
                "directions_deg[1] = [75.0, 10.0]",
            ),
            (
                "theta_deg = 75.0",
                "theta_deg = 95.0",
                "[[rings]]: invalid input: ring 1: theta 95 deg",
            ),
            ("count = 4", "count = 0", "[[rings]]: invalid input: ring 1: count 0"),
        ];
        for (from, to, expected) in cases {
            let e = refused(from, to);
            assert!(e.contains(expected), "{to}: expected '{expected}' in: {e}");
        }
        // Three markers, or every marker on one line, cannot fix a homography.
        let e = refused(
            "[[-60.0, -60.0], [0.0, -60.0], [60.0, -60.0], [60.0, 0.0], [60.0, 60.0], [0.0, 60.0], [-60.0, 60.0], [-60.0, 0.0], [30.0, 60.0]]",
            "[[-60.0, -60.0], [0.0, -60.0], [60.0, -60.0]]",
        );
        assert!(e.contains("[plate] point_markers_mm (count) = 3: must be in 4..=32"), "{e}");
        let e = refused(
            "[[-60.0, -60.0], [0.0, -60.0], [60.0, -60.0], [60.0, 0.0], [60.0, 60.0], [0.0, 60.0], [-60.0, 60.0], [-60.0, 0.0], [30.0, 60.0]]",
            "[[-60.0, -60.0], [-30.0, -60.0], [0.0, -60.0], [30.0, -60.0], [60.0, -60.0]]",
        );
        assert!(
            e.contains("[plate] point_markers_mm: no four markers are in general position"),
            "{e}"
        );
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
