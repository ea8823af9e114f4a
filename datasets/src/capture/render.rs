//! Rendering of the raw images of a virtual capture (see the parent module for the set-up)
//! and writing of `capture.toml` / `truth.toml`. Images are independent, rendered in
//! parallel, each written atomically, and skipped when already present (resumable).

use super::*;
use crate::material::Material;
use crate::noise::{Rng, hash01};
use crate::vec3::{V3, add, cross, dot, normalize_or, scale, sub};
use crate::{Error, Result};
use indicatif::ProgressBar;
use rayon::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};

/// What a capture run did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureReport {
    /// Images rendered in this run.
    pub images_written: usize,
    /// Images already present (resumed).
    pub images_skipped: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// True placement of the plate for one view: `p_lab = R · p_sample + t` (mm).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Pose {
    /// Rotation matrix, rows.
    pub rotation: [[f64; 3]; 3],
    /// Translation (mm).
    pub translation_mm: [f64; 3],
}

impl Pose {
    fn random(rng: &mut Rng, deg: f64, mm: f64) -> Self {
        let axis = normalize_or([rng.normal(), rng.normal(), rng.normal()], [0.0, 0.0, 1.0]);
        let angle = (deg * rng.normal()).to_radians();
        let (s, c) = angle.sin_cos();
        let k = axis;
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let kron = if i == j { 1.0 } else { 0.0 };
                let cross_ij = match (i, j) {
                    (0, 1) => -k[2],
                    (0, 2) => k[1],
                    (1, 0) => k[2],
                    (1, 2) => -k[0],
                    (2, 0) => -k[1],
                    (2, 1) => k[0],
                    _ => 0.0,
                };
                r[i][j] = c * kron + s * cross_ij + (1.0 - c) * k[i] * k[j];
            }
        }
        Pose {
            rotation: r,
            translation_mm: [mm * rng.normal(), mm * rng.normal(), mm * rng.normal()],
        }
    }
    /// Lab vector → sample frame (`Rᵀ v`).
    fn to_sample(self, v: V3) -> V3 {
        let r = &self.rotation;
        std::array::from_fn(|j| r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2])
    }
    /// Sample point → lab (`R p + t`).
    pub fn to_lab(self, p: V3) -> V3 {
        let r = &self.rotation;
        std::array::from_fn(|i| {
            r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + self.translation_mm[i]
        })
    }
}

/// The nominal pinhole camera of a view: position (mm), axes and focal length.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    /// Centre of projection (lab, mm).
    pub centre: V3,
    right: V3,
    up: V3,
    forward: V3,
    focal_px: f64,
    cx: f64,
    cy: f64,
}

impl Camera {
    /// Camera looking at the plate centre from unit direction `view` at the nominal
    /// distance. Its image up is the plate normal's projection (the tilt axis is
    /// horizontal), and sample `+y` for the frontal view.
    pub fn new(view: V3, width: usize, height: usize) -> Self {
        let forward = scale(view, -1.0);
        let up_hint = if view[2] > 0.9999 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
        let right = normalize_or(cross(forward, up_hint), [1.0, 0.0, 0.0]);
        let up = cross(right, forward);
        // The plate's circumcircle (radius ~100 mm) spans 80 % of the image height in the
        // frontal view, so the markers stay in the frame at any roll and tilt.
        let focal_px = 0.8 * (height.min(width) as f64 / 2.0) * CAMERA_DISTANCE_MM / 100.0;
        let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
        Camera { centre: scale(view, CAMERA_DISTANCE_MM), right, up, forward, focal_px, cx, cy }
    }
    /// Unit ray direction (lab) through pixel position `(u, v)` (pixels, from top-left).
    pub fn ray(&self, u: f64, v: f64) -> V3 {
        let d = add(
            add(scale(self.forward, self.focal_px), scale(self.right, u - self.cx)),
            scale(self.up, self.cy - v),
        );
        normalize_or(d, self.forward)
    }
    /// Pixel position of a lab point (`None` behind the camera).
    pub fn project(&self, p: V3) -> Option<[f64; 2]> {
        let d = sub(p, self.centre);
        let z = dot(d, self.forward);
        (z > 0.0).then(|| {
            [
                self.cx + self.focal_px * dot(d, self.right) / z,
                self.cy - self.focal_px * dot(d, self.up) / z,
            ]
        })
    }
}

/// Folder and file name of image (view, light) from their directions, e.g.
/// `tv030_pv060/tl045_pl120_tv030_pv060.png` (rounded integer degrees).
pub fn image_path(view: btf_core::Direction, light: btf_core::Direction) -> PathBuf {
    let f = |x: f64| format!("{:03}", x.round() as i64 % 360);
    let dir = format!("tv{}_pv{}", f(view.theta_deg), f(view.phi_deg));
    PathBuf::from(&dir).join(format!("tl{}_pl{}_{dir}.png", f(light.theta_deg), f(light.phi_deg)))
}

fn gaussian(seed: u64, a: i64, b: i64, c: i64) -> f64 {
    let u1 = hash01(seed, a, b, 2 * c).max(1e-300);
    let u2 = hash01(seed, a, b, 2 * c + 1);
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Radiance along the sample-frame ray from `origin` in direction `d`: the material on the
/// sample square, the Lambertian plate around it, nothing off the plate.
fn ray_radiance(material: &Material, n: f64, origin: V3, d: V3, light: V3) -> [f64; 3] {
    if d[2] >= 0.0 {
        return [0.0; 3];
    }
    let t = -origin[2] / d[2];
    let (x, y) = (origin[0] + t * d[0], origin[1] + t * d[1]);
    let h = SAMPLE_MM / 2.0;
    if x.abs() < h && y.abs() < h {
        let view = scale(d, -1.0);
        material.eval_at((x + h) / SAMPLE_MM * n, (y + h) / SAMPLE_MM * n, view, light)
    } else if light[2] > 0.0 {
        [plate_albedo(x, y) * light[2] / std::f64::consts::PI; 3]
    } else {
        [0.0; 3]
    }
}

/// Renders image (view `j`, light `i`) as 12-bit DN values, RGB, row-major.
pub fn render_image(
    spec: &CaptureSpec,
    material: &Material,
    pose: &Pose,
    j: usize,
    i: usize,
) -> Vec<[u16; 3]> {
    let s = &spec.material.sampling;
    let cam = Camera::new(s.direction(j).to_vector(), spec.width, spec.height);
    let light = pose.to_sample(s.direction(i).to_vector());
    let n = spec.material.size as f64;
    let gain = 0.9 * 4095.0 * std::f64::consts::PI; // keep in step with `radiometry`
    let origin = pose.to_sample(sub(cam.centre, pose.translation_mm));
    let mut out = Vec::with_capacity(spec.width * spec.height);
    let k = spec.supersample.max(1);
    for r in 0..spec.height {
        for c in 0..spec.width {
            let (mut radiance, mut vig) = ([0.0; 3], 0.0);
            for sub in 0..k * k {
                let (du, dv) =
                    (((sub % k) as f64 + 0.5) / k as f64, ((sub / k) as f64 + 0.5) / k as f64);
                let d_lab = cam.ray(c as f64 + du, r as f64 + dv);
                let l = ray_radiance(material, n, origin, pose.to_sample(d_lab), light);
                for ch in 0..3 {
                    radiance[ch] += l[ch] / (k * k) as f64;
                }
                vig += dot(d_lab, cam.forward).powf(4.0 * spec.vignetting) / (k * k) as f64;
            }
            let px: [u16; 3] = std::array::from_fn(|ch| {
                let dn = gain * radiance[ch] * vig;
                let sigma = (spec.read_noise_dn.powi(2) + spec.shot_noise_per_dn * dn).sqrt();
                let pix = ((j * s.len() + i) * spec.height + r) as i64;
                let noisy = dn + sigma * gaussian(spec.seed, pix, c as i64, ch as i64);
                noisy.round().clamp(0.0, 4095.0) as u16
            });
            out.push(px);
        }
    }
    out
}

fn write_png(path: &Path, w: usize, h: usize, px: &[[u16; 3]]) -> Result<()> {
    let data: Vec<u16> = px.iter().flat_map(|p| p.map(|v| v << 4)).collect();
    let img = image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(w as u32, h as u32, data)
        .ok_or_else(|| Error::Invalid("image buffer size".into()))?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| Error::Image { path: path.to_owned(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic_unsynced(path, &bytes)?)
}

/// Writes a file that describes the job (`capture.toml`, `truth.toml`). When the folder
/// already holds one from an interrupted run, it must describe the same job — otherwise
/// the images kept from that run would belong to another capture — and the error names
/// the first field that differs.
fn write_job_toml(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    if let Ok(old) = std::fs::read_to_string(path) {
        let now = serde_json::to_value(value)
            .map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
        let was: serde_json::Value = toml::from_str(&old).unwrap_or(serde_json::Value::Null);
        let now_rt: serde_json::Value =
            toml::to_string(value).ok().and_then(|t| toml::from_str(&t).ok()).unwrap_or(now);
        if was != now_rt {
            return Err(Error::Invalid(format!(
                "{} describes a different capture ({}); the images beside it belong to that \
                 job: choose another folder or remove this one",
                path.display(),
                btf_core::store::first_difference(&was, &now_rt, "")
            )));
        }
        return Ok(());
    }
    write_toml(path, value)
}

fn write_toml(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text =
        toml::to_string(value).map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
    Ok(btf_core::fs::write_atomic(path, text.as_bytes())?)
}

/// The true pose of every view (deterministic in the seed).
pub fn true_poses(spec: &CaptureSpec) -> Vec<Pose> {
    let mut rng = Rng::new(spec.seed ^ 0x9051);
    (0..spec.material.sampling.len())
        .map(|_| Pose::random(&mut rng, spec.pose_noise_deg, spec.pose_noise_mm))
        .collect()
}

/// `capture.toml` of `spec`: what the lab knows of the capture.
pub fn description(spec: &CaptureSpec) -> CaptureDescription {
    let cam = Camera::new([0.0, 0.0, 1.0], spec.width, spec.height);
    CaptureDescription {
        version: 1,
        sampling: spec.material.sampling.name.clone(),
        rings: spec.material.sampling.rings.clone(),
        directions_deg: spec.material.sampling.directions().iter().map(|d| [d.theta_deg, d.phi_deg]).collect(),
        naming: "tvTTT_pvPPP/tlTTT_plPPP_tvTTT_pvPPP.png (rounded integer degrees)".into(),
        camera: CameraDescription {
            width: spec.width,
            height: spec.height,
            focal_px: cam.focal_px,
            principal_point_px: [cam.cx, cam.cy],
            distance_mm: CAMERA_DISTANCE_MM,
            bits: 12,
            frontal_axes: "image right = sample +x, image up = sample +y (rows run along -y)".into(),
            light: "distant lamp; irradiance 1 maps a white Lambertian at normal incidence to 0.9 of full scale".into(),
        },
        plate: PlateDescription {
            size_mm: PLATE_MM,
            sample_mm: SAMPLE_MM,
            point_markers_mm: point_markers(),
            marker_radius_mm: MARKER_RADIUS_MM,
            border_offset_mm: BORDER_OFFSET_MM,
            border_width_mm: BORDER_WIDTH_MM,
        },
        radiometry: RadiometryDescription {
            reference_white_dn: 0.9 * 4095.0,
            vignetting_cos_power: 4.0 * spec.vignetting,
        },
        material: {
            let mut m = json!({"kind": spec.material.kind.name(), "size": spec.material.size, "seed": spec.material.seed});
            if let Some(a) = spec.material.albedo {
                m["albedo"] = json!(a);
            }
            m
        },
    }
}

/// The `capture.toml` text of `spec` (for tools that render a capture's images themselves,
/// such as the registration sweep).
pub fn description_toml(spec: &CaptureSpec) -> Result<String> {
    toml::to_string(&description(spec)).map_err(|e| Error::Invalid(format!("capture.toml: {e}")))
}

/// Renders every raw image of `spec` into `out`, with `capture.toml` and `truth.toml`.
pub fn capture(spec: &CaptureSpec, out: &Path, progress: bool) -> Result<CaptureReport> {
    let t0 = std::time::Instant::now();
    if !(16..=8192).contains(&spec.width) || !(16..=8192).contains(&spec.height) {
        return Err(Error::Invalid(format!(
            "capture resolution {}x{} is outside 16..=8192",
            spec.width, spec.height
        )));
    }
    let noise = [
        spec.pose_noise_deg,
        spec.pose_noise_mm,
        spec.read_noise_dn,
        spec.shot_noise_per_dn,
        spec.vignetting,
    ];
    if !(1..=16).contains(&spec.supersample) {
        return Err(Error::Invalid(format!("supersample {} is outside 1..=16", spec.supersample)));
    }
    if noise.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
        return Err(Error::Invalid(
            "pose noise, sensor noise and vignetting must be finite and ≥ 0".into(),
        ));
    }
    let material = Material::build(&spec.material)?;
    let s = &spec.material.sampling;
    let poses = true_poses(spec);
    // A folder of somebody's files is refused; an earlier capture is resumed only when it
    // is the same job (see `write_job_toml`).
    btf_core::fs::check_replaceable(
        out,
        btf_core::fs::OutputKind::Folder { marker: "capture.toml" },
    )?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let desc = description(spec);
    write_job_toml(&out.join("capture.toml"), &desc)?;
    let truth = json!({
        "warning": "ground truth for evaluation only; capture processing must not read this file",
        "seed": spec.seed,
        "pose_noise_deg": spec.pose_noise_deg, "pose_noise_mm": spec.pose_noise_mm,
        "supersample": spec.supersample,
        "read_noise_dn": spec.read_noise_dn, "shot_noise_per_dn": spec.shot_noise_per_dn, "vignetting": spec.vignetting,
        "view_poses": poses.iter().enumerate().map(|(j, p)| json!({"view": j, "rotation": p.rotation, "translation_mm": p.translation_mm})).collect::<Vec<_>>(),
    });
    write_job_toml(&out.join("truth.toml"), &truth)?;
    let pairs: Vec<(usize, usize)> =
        (0..s.len()).flat_map(|j| (0..s.len()).map(move |i| (j, i))).collect();
    let bar = if progress { ProgressBar::new(pairs.len() as u64) } else { ProgressBar::hidden() };
    let written = pairs
        .par_iter()
        .map(|&(j, i)| -> Result<usize> {
            let path = out.join(image_path(s.direction(j), s.direction(i)));
            bar.inc(1);
            if path.exists() {
                return Ok(0);
            }
            let dir = path.parent().unwrap_or(out);
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
            let px = render_image(spec, &material, &poses[j], j, i);
            write_png(&path, spec.width, spec.height, &px)?;
            Ok(1)
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .sum::<usize>();
    bar.finish_and_clear();
    Ok(CaptureReport {
        images_written: written,
        images_skipped: pairs.len() - written,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
