//! Accuracy of a processed capture against the virtual gonioreflectometer's ground truth
//! (`truth.toml`: the true plate pose of every view; the orthographic normtextures of the
//! material, supplied by the caller).
//!
//! **Reprojection error.** For every texel centre `p` (mm) of the output grid, the true
//! homography `H* = K M [r₁ r₂ t − c]` (eq. 8.1 of H&Z on the plane) takes it into the
//! image and the estimated one brings it back: `e = |H⁻¹ H* p − p| / texel_mm`, in texels
//! of the store (its pixels). Mean and max are over all texels of all views.
//!
//! **Relative RMSE** of the normtextures: `‖T − T*‖ / ‖T*‖` over all texels, channels,
//! lights and views, where `T*` is the truth on the same texel grid, folded by the same
//! edge blend (the blend is linear, so this is the truth of the blended image). A texel of
//! a normtexture stands for its square on the sample, so the truth is the material's BTF
//! *averaged over the texel's square* (not sampled at its centre: the material has detail
//! finer than a texel, which no rectification can put into one value). Two truths
//! ([`Truth`]): **measurable** — seen from the true camera position, so the view direction
//! of every point is the one the camera really had (it varies by ±3.8° across an 80 mm
//! sample at 600 mm and follows the plate's tilt; no processing can undo that without
//! knowing the BTF), under the nominal light; and **nominal** — the orthographic BTF at
//! the sampling's nominal directions, which also charges the set-up's perspective.
//!
//! **Filter comparison.** The same registrations are rectified again with each filter (and
//! with the true homography, which isolates the filter's own error), timing the resampling
//! per image and scoring the result against the truth.

use super::blend;
use super::homography::apply;
use super::incidence::light_cosine_gains;
use super::layout::CaptureLayout;
use super::process::{normtexture, radiometric_gain};
use super::raw;
use super::rectify::{Filter, Grid, Plan};
use super::register::Registration;
use crate::{Error, Result};
use btf_core::store::BtfStore;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Which ground truth a store is compared with (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Truth {
    /// Texel-averaged BTF from the true camera position, nominal light.
    Measurable,
    /// Texel-averaged BTF at the nominal view and light directions (orthographic).
    Nominal,
}

/// The truth normtexture of (view, light) on a grid: `grid.n²` RGB texels, row-major.
pub type TruthFn<'a> = dyn Fn(usize, usize, &Grid, Truth) -> Vec<[f32; 3]> + Sync + 'a;

/// `truth.toml` as the virtual gonioreflectometer writes it: the poses and, for the
/// record, the noise parameters they were drawn with.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct TruthToml {
    warning: Option<String>,
    seed: Option<u64>,
    pose_noise_deg: Option<f64>,
    pose_noise_mm: Option<f64>,
    supersample: Option<u64>,
    read_noise_dn: Option<f64>,
    shot_noise_per_dn: Option<f64>,
    vignetting: Option<f64>,
    view_poses: Vec<PoseToml>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseToml {
    view: usize,
    rotation: [[f64; 3]; 3],
    translation_mm: [f64; 3],
}

/// The true placement of the plate for one view: `p_lab = R · p_sample + t` (mm).
#[derive(Debug, Clone, Copy)]
pub struct TruePose {
    /// Rotation `R`.
    pub rotation: Matrix3<f64>,
    /// Translation `t` (mm).
    pub translation_mm: Vector3<f64>,
}

impl TruePose {
    /// A lab direction in the sample frame (`Rᵀ d`).
    pub fn to_sample(&self, d_lab: [f64; 3]) -> [f64; 3] {
        let v = self.rotation.transpose() * Vector3::from(d_lab);
        [v.x, v.y, v.z]
    }
    /// Unit vector from sample point `p_mm` (on the plane `z = 0`) towards the camera of
    /// `view`, in the sample frame.
    pub fn view_dir_sample(&self, layout: &CaptureLayout, view: usize, p_mm: [f64; 2]) -> [f64; 3] {
        let d = layout.sampling.direction(view).to_vector();
        let cam_lab = Vector3::from(d) * layout.camera.distance_mm;
        let cam = self.rotation.transpose() * (cam_lab - self.translation_mm);
        let v = (cam - Vector3::new(p_mm[0], p_mm[1], 0.0)).normalize();
        [v.x, v.y, v.z]
    }
}

/// The true pose of every view from `RAW_DIR/truth.toml`.
pub fn true_poses(layout: &CaptureLayout) -> Result<Vec<TruePose>> {
    let path = layout.dir.join("truth.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let file = path.display().to_string();
    let t: TruthToml = super::config::parse(&file, &text)?;
    let n = layout.sampling.len();
    let c = super::config::Checker { file: &file };
    if t.view_poses.len() != n || t.view_poses.iter().enumerate().any(|(j, p)| p.view != j) {
        return Err(c.wrong("[[view_poses]]", format!("expected views 0..{n} in order")));
    }
    for (j, p) in t.view_poses.iter().enumerate() {
        let r = Matrix3::from_fn(|a, b| p.rotation[a][b]);
        let key = format!("[[view_poses]] (view {j}) rotation");
        if !r.iter().all(|v| v.is_finite()) {
            return Err(c.bad(&key, format!("{:?}", p.rotation), "must be finite"));
        }
        let off = (r.transpose() * r - Matrix3::identity()).amax();
        if off > 1e-6 || r.determinant() <= 0.0 {
            return Err(c.bad(
                &key,
                format!("{:?}", p.rotation),
                format!("not a rotation (|RᵀR − I| = {off:.2e}, det {:.3})", r.determinant()),
            ));
        }
        let key = format!("[[view_poses]] (view {j}) translation_mm");
        for v in p.translation_mm {
            c.within(&key, v, -layout.plate.size_mm, layout.plate.size_mm)?;
        }
    }
    Ok(t.view_poses
        .iter()
        .map(|p| TruePose {
            rotation: Matrix3::from_fn(|i, j| p.rotation[i][j]),
            translation_mm: Vector3::from(p.translation_mm),
        })
        .collect())
}

/// The true homography of every view from `RAW_DIR/truth.toml`.
pub fn true_homographies(layout: &CaptureLayout) -> Result<Vec<Matrix3<f64>>> {
    Ok(true_poses(layout)?
        .iter()
        .enumerate()
        .map(|(j, p)| layout.homography(j, &p.rotation, &p.translation_mm))
        .collect())
}

/// One row of the filter table.
#[derive(Debug, Clone, Serialize)]
pub struct FilterRow {
    /// Filter name.
    pub filter: String,
    /// `estimated` (the store's registration) or `true` (the truth's poses).
    pub homography: String,
    /// Relative RMSE against the truth.
    pub rel_rmse: f64,
    /// Resampling time per image (ms), plan building included.
    pub ms_per_image: f64,
    /// Mean taps per texel.
    pub taps_per_texel: f64,
}

/// The score of a processed store.
#[derive(Debug, Clone, Serialize)]
pub struct Score {
    /// Mean reprojection error, in texels of the store.
    pub mean_reprojection_texels: f64,
    /// Maximum reprojection error, in texels of the store.
    pub max_reprojection_texels: f64,
    /// Relative RMSE of the normtextures against the measurable truth.
    pub rel_rmse: f64,
    /// Relative RMSE against the nominal-direction truth (only when asked for).
    pub rel_rmse_nominal: Option<f64>,
    /// Texel side (mm) of the store.
    pub texel_mm: f64,
    /// Per view: `[θ, φ, mean, max]` reprojection (texels).
    pub per_view: Vec<[f64; 4]>,
    /// Relative RMSE per view ring: `[θ, rel_rmse]`.
    pub rel_rmse_by_theta: Vec<[f64; 2]>,
    /// Relative RMSE against the nominal truth per view ring (only when asked for).
    pub rel_rmse_nominal_by_theta: Vec<[f64; 2]>,
    /// Whether the store was processed with the light-incidence correction.
    pub light_incidence_correction: bool,
    /// Views registered from the nominal pose.
    pub fallback_views: Vec<usize>,
    /// Filter comparison (empty unless asked for).
    pub filters: Vec<FilterRow>,
}

/// What `btf capture process` recorded in a store's provenance.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// The output grid before blending.
    pub grid: Grid,
    /// Texels per side of the store.
    pub size: usize,
    /// Every view slot's registration.
    pub registrations: Vec<Registration>,
    /// Whether the light-incidence correction was applied (absent in older stores: no).
    pub light_incidence_correction: bool,
}

/// What `btf capture process` recorded: the grid and the registrations.
pub fn recorded(store: &BtfStore) -> Result<Recorded> {
    let p = &store.meta().provenance;
    let file = store.path().display().to_string();
    let bad = || Error::invalid(&file, "provenance", "not written by `btf capture process`");
    let g = &p["grid"];
    let origin: [f64; 2] = serde_json::from_value(g["origin_mm"].clone()).map_err(|_| bad())?;
    let grid = Grid {
        origin_mm: origin,
        texel_mm: g["texel_mm"].as_f64().ok_or_else(bad)?,
        n: g["n"].as_u64().ok_or_else(bad)? as usize,
    };
    let registrations: Vec<Registration> =
        serde_json::from_value(p["registration"].clone()).map_err(|_| bad())?;
    let size = store.meta().width;
    let c = super::config::Checker { file: &file };
    c.finite("provenance grid.origin_mm[0]", grid.origin_mm[0])?;
    c.finite("provenance grid.origin_mm[1]", grid.origin_mm[1])?;
    c.positive("provenance grid.texel_mm", grid.texel_mm, 1e6)?;
    c.count("provenance grid.n", grid.n as u64, size as u64, 2 * size as u64)?;
    for (j, r) in registrations.iter().enumerate() {
        let key = format!("provenance registration[{j}]");
        if r.view != j {
            return Err(c.bad(&format!("{key}.view"), r.view, format!("must be {j}")));
        }
        let h = r.matrix();
        if !h.iter().all(|v| v.is_finite()) || h.try_inverse().is_none() {
            return Err(c.bad(
                &format!("{key}.homography"),
                format!("{:?}", r.homography),
                "must be finite and invertible",
            ));
        }
    }
    Ok(Recorded {
        grid,
        size,
        registrations,
        light_incidence_correction: p["light_incidence_correction"].as_bool().unwrap_or(false),
    })
}

/// Scores `store` against the capture in `layout`'s folder; `filters` lists the filters to
/// compare (none for the plain score); `nominal` adds the nominal-direction truth.
pub fn score(
    store: &BtfStore,
    layout: &CaptureLayout,
    truth: &TruthFn,
    filters: &[Filter],
    nominal: bool,
) -> Result<Score> {
    let rec = recorded(store)?;
    let (grid, size, regs) = (rec.grid, rec.size, &rec.registrations);
    let n = layout.sampling.len();
    if store.meta().n_views() != n || regs.len() != n {
        return Err(Error::invalid(
            &store.path().display().to_string(),
            "sampling",
            "differs from the capture's",
        ));
    }
    let truths = true_homographies(layout)?;
    let mut per_view = Vec::with_capacity(n);
    let (mut sum, mut count, mut max) = (0.0, 0usize, 0f64);
    for (j, reg) in regs.iter().enumerate() {
        let errs = reprojection_texels(&reg.matrix(), &truths[j], &grid);
        let m = errs.iter().sum::<f64>() / errs.len() as f64;
        let mx = errs.iter().copied().fold(0.0, f64::max);
        let d = layout.sampling.direction(j);
        per_view.push([d.theta_deg, d.phi_deg, m, mx]);
        (sum, count, max) = (sum + errs.iter().sum::<f64>(), count + errs.len(), max.max(mx));
    }
    let stored = |j: usize, i: usize| store.read_image(j, i).map_err(Error::from);
    let set = Setting { layout, grid, size, truth };
    let (rel_rmse, by_theta) = set.rel_rmse(Truth::Measurable, &stored)?;
    let (rel_nominal, nominal_by_theta) = match nominal {
        true => set.rel_rmse(Truth::Nominal, &stored).map(|(r, t)| (Some(r), t))?,
        false => (None, Vec::new()),
    };
    let mut rows = Vec::new();
    // The filter rows compare four rectifications with one truth: evaluate it once when
    // it fits in memory (1 GiB), else again per row.
    let bytes = n * n * grid.n * grid.n * 12;
    let cache: Vec<Vec<[f32; 3]>> = if !filters.is_empty() && bytes <= 1 << 30 {
        use rayon::prelude::*;
        (0..n * n).into_par_iter().map(|k| truth(k / n, k % n, &grid, Truth::Measurable)).collect()
    } else {
        Vec::new()
    };
    let cached = |j: usize, i: usize, g: &Grid, w: Truth| match cache.get(j * n + i) {
        Some(t) if w == Truth::Measurable => t.clone(),
        _ => truth(j, i, g, w),
    };
    let set = Setting { truth: &cached, ..set };
    for &f in filters {
        for (which, hs) in [
            ("estimated", regs.iter().map(|r| r.matrix()).collect::<Vec<_>>()),
            ("true", truths.clone()),
        ] {
            rows.push(set.filter_row(f, which, &hs, rec.light_incidence_correction)?);
        }
    }
    Ok(Score {
        mean_reprojection_texels: sum / count.max(1) as f64,
        max_reprojection_texels: max,
        rel_rmse,
        rel_rmse_nominal: rel_nominal,
        texel_mm: grid.texel_mm,
        per_view,
        rel_rmse_by_theta: by_theta,
        rel_rmse_nominal_by_theta: nominal_by_theta,
        light_incidence_correction: rec.light_incidence_correction,
        fallback_views: regs.iter().filter(|r| r.fallback_nominal).map(|r| r.view).collect(),
        filters: rows,
    })
}

/// Reprojection errors (texels) of `h_est` against `h_true` at the texel centres of `grid`.
pub fn reprojection_texels(h_est: &Matrix3<f64>, h_true: &Matrix3<f64>, grid: &Grid) -> Vec<f64> {
    let Some(back) = h_est.try_inverse() else { return vec![f64::INFINITY] };
    let map = back * h_true;
    let stride = (grid.n / 128).max(1);
    let mut out = Vec::new();
    for row in (0..grid.n).step_by(stride) {
        for col in (0..grid.n).step_by(stride) {
            let p = grid.centre_mm(col, row);
            let q = apply(&map, p);
            out.push(((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt() / grid.texel_mm);
        }
    }
    out
}

type ImageFn<'a> = dyn Fn(usize, usize) -> Result<Vec<f32>> + Sync + 'a;

/// What every error figure is computed over.
struct Setting<'a> {
    layout: &'a CaptureLayout,
    grid: Grid,
    size: usize,
    truth: &'a TruthFn<'a>,
}

impl Setting<'_> {
    /// Relative RMSE of `image` against `which` truth, overall and per view ring.
    fn rel_rmse(&self, which: Truth, image: &ImageFn) -> Result<(f64, Vec<[f64; 2]>)> {
        use rayon::prelude::*;
        let (layout, grid, size) = (self.layout, &self.grid, self.size);
        let n = layout.sampling.len();
        let per_view: Vec<(f64, f64)> = (0..n)
            .into_par_iter()
            .map(|j| -> Result<(f64, f64)> {
                let (mut se, mut st) = (0.0, 0.0);
                for i in 0..n {
                    let t = blend::fold(&(self.truth)(j, i, grid, which), grid.n, size);
                    let v = image(j, i)?;
                    for (a, b) in v.iter().zip(t.iter().flatten()) {
                        se += ((a - b) as f64).powi(2);
                        st += (*b as f64).powi(2);
                    }
                }
                Ok((se, st))
            })
            .collect::<Result<_>>()?;
        let mut rings: Vec<[f64; 3]> = Vec::new();
        for (j, (se, st)) in per_view.iter().enumerate() {
            let th = layout.sampling.direction(j).theta_deg;
            match rings.iter_mut().find(|r| r[0] == th) {
                Some(r) => (r[1], r[2]) = (r[1] + se, r[2] + st),
                None => rings.push([th, *se, *st]),
            }
        }
        let (se, st) = per_view.iter().fold((0.0, 0.0), |a, v| (a.0 + v.0, a.1 + v.1));
        let ratio = |e: f64, t: f64| if t > 0.0 { (e / t).sqrt() } else { 0.0 };
        Ok((ratio(se, st), rings.iter().map(|r| [r[0], ratio(r[1], r[2])]).collect()))
    }

    /// Rectifies every image again with `filter` under homographies `hs` (with the
    /// light-incidence correction when `correct`), timed, and scores it.
    fn filter_row(
        &self,
        filter: Filter,
        which: &str,
        hs: &[Matrix3<f64>],
        correct: bool,
    ) -> Result<FilterRow> {
        let layout = self.layout;
        let n = layout.sampling.len();
        let (w, h) = (layout.camera.width, layout.camera.height);
        let seconds = std::sync::Mutex::new((0.0f64, 0.0f64));
        // One plan per view slot, built when its first light is read and dropped after its
        // last, as `process` does; its cost is part of the timing.
        let plans: Vec<std::sync::Mutex<Option<Plan>>> =
            (0..n).map(|_| std::sync::Mutex::new(None)).collect();
        let gains: Vec<Vec<f64>> = (0..n)
            .map(|j| match correct {
                true => light_cosine_gains(layout, j, &hs[j]),
                false => vec![1.0; n],
            })
            .collect();
        let image = |j: usize, i: usize| -> Result<Vec<f32>> {
            let path = layout.image_path(j, i);
            let img = raw::read(&path, layout.camera.bits)?;
            let t0 = Instant::now();
            let mut slot = plans[j].lock().expect("plan lock");
            if slot.is_none() {
                let plan = Plan::new(&hs[j], &self.grid, w, h, filter, radiometric_gain(layout))
                    .map_err(|_| {
                        Error::invalid(&path.display().to_string(), "roi", "outside the image")
                    })?;
                seconds.lock().expect("timer lock").1 += plan.taps_per_texel() * n as f64;
                *slot = Some(plan);
            }
            let plan = slot.as_ref().expect("plan built");
            let out = normtexture(plan, &img, self.size, gains[j][i] as f32);
            if i + 1 == n {
                *slot = None;
            }
            seconds.lock().expect("timer lock").0 += t0.elapsed().as_secs_f64();
            Ok(out)
        };
        let (rel, _) = self.rel_rmse(Truth::Measurable, &image)?;
        let (secs, taps) = *seconds.lock().expect("timer lock");
        let images = (n * n) as f64;
        Ok(FilterRow {
            filter: filter.name().into(),
            homography: which.into(),
            rel_rmse: rel,
            ms_per_image: 1e3 * secs / images,
            taps_per_texel: taps / images,
        })
    }
}

/// The filter table as Markdown.
pub fn filter_table_markdown(rows: &[FilterRow]) -> String {
    let mut s = String::from(
        "| filter | homography | rel. RMSE | ms / image | taps / texel |\n|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {:.5} | {:.2} | {:.1} |\n",
            r.filter, r.homography, r.rel_rmse, r.ms_per_image, r.taps_per_texel
        );
    }
    s
}

/// Checks that `raw_dir` holds a synthetic capture's ground truth.
pub fn has_truth(raw_dir: &Path) -> bool {
    raw_dir.join("truth.toml").is_file()
}

#[cfg(test)]
mod tests {
    use super::*;

    const POSE: &str = "[[view_poses]]\nrotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\ntranslation_mm = [0.5, -0.25, 1.0]\nview = V\n\n";

    /// `true_poses` of the five-view layout with `truth` as `truth.toml`.
    fn read(truth: &str) -> Result<Vec<TruePose>> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("capture.toml"), super::super::layout::tests::GOOD).unwrap();
        std::fs::write(dir.path().join("truth.toml"), truth).unwrap();
        true_poses(&CaptureLayout::read(dir.path())?)
    }

    fn truth(head: &str) -> String {
        let poses: String = (0..5).map(|v| POSE.replace('V', &v.to_string())).collect();
        format!("warning = \"ground truth\"\nseed = 1\npose_noise_deg = 1.0\n{head}\n{poses}")
    }

    #[test]
    fn truth_toml_is_read_strictly() {
        let p = read(&truth("")).unwrap();
        assert_eq!(p.len(), 5);
        assert!((p[4].translation_mm - Vector3::new(0.5, -0.25, 1.0)).amax() < 1e-12);
        let e = read(&truth("pose_noise_dg = 1.0")).unwrap_err().to_string();
        assert!(e.contains("truth.toml: pose_noise_dg: unknown field"), "{e}");
        let t = truth("").replacen("translation_mm = [0.5", "translation_mm = [nan", 1);
        let e = read(&t).unwrap_err().to_string();
        assert!(e.contains("[[view_poses]] (view 0) translation_mm = NaN"), "{e}");
        let t = truth("").replacen("[1.0, 0.0, 0.0]", "[2.0, 0.0, 0.0]", 1);
        let e = read(&t).unwrap_err().to_string();
        assert!(
            e.contains("[[view_poses]] (view 0) rotation = ") && e.contains("not a rotation"),
            "{e}"
        );
        let t = truth("").replacen("view = 3", "view = 7", 1);
        let e = read(&t).unwrap_err().to_string();
        assert!(e.contains("truth.toml: [[view_poses]]: expected views 0..5 in order"), "{e}");
        let t = truth("").replacen("view = 0\n", "view = 0\nscale = 2\n", 1);
        let e = read(&t).unwrap_err().to_string();
        assert!(e.contains("[[view_poses]] scale: unknown field"), "{e}");
    }
}
