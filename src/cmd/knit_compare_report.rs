//! The numbers and pictures of `btf knit compare` (DESIGN §4.2, the headline study): the
//! garment's silhouette rasterised on the CPU (one point-in-triangle test per pixel
//! centre), the interior mask and silhouette band, the relative RMSE `√(Σ(x−r)²/Σr²)` and
//! mean-radiance ratio on each, and the CSV, Markdown table, Pareto plot (error against
//! frame-time ratio) and contact sheets.

use btf_image::plot::{Plot, Series};
use image::RgbImage;
use std::fmt::Write as _;

/// Errors of one image against a reference.
#[derive(Debug, Clone, Copy)]
pub struct Scores {
    /// Relative RMSE on the interior mask.
    pub interior: f64,
    /// Relative RMSE on the silhouette band.
    pub band: f64,
    /// Mean radiance over the interior, as a ratio to the reference's.
    pub mean_ratio: f64,
    /// Relative RMSE on the interior after both images are box-filtered over one stitch
    /// (the appearance at the scale of the knit, without the fiber-level placement).
    pub stitch_scale: f64,
    /// Mean HDR-ꟻLIP on the interior (exposures from the reference's interior).
    pub flip_interior: f64,
    /// Mean HDR-ꟻLIP on the silhouette band (same exposures).
    pub flip_band: f64,
}

impl Default for Scores {
    fn default() -> Self {
        Scores {
            interior: f64::NAN,
            band: f64::NAN,
            mean_ratio: f64::NAN,
            stitch_scale: f64::NAN,
            flip_interior: f64::NAN,
            flip_band: f64::NAN,
        }
    }
}

/// One representation at one distance.
pub struct Cell {
    /// R0…R5 (DESIGN §4.2).
    pub repr: &'static str,
    /// What exactly is drawn.
    pub name: String,
    /// Index of the camera distance.
    pub distance: usize,
    /// The frame (linear RGB).
    pub rgb: Vec<f32>,
    /// Preprocessing seconds (renderer set-up, bakes, PCA).
    pub prep_s: f64,
    /// GPU memory of the representation (bytes).
    pub bytes: u64,
    /// Whether it follows a deformation of the garment.
    pub deforms: bool,
    /// Median frame ms.
    pub ms: f64,
    /// Median frame ms of the plain texture at the same distance.
    pub ms_plain: f64,
    /// Against the reference with every bounce.
    pub vs_full: Scores,
    /// Against the direct-only reference.
    pub vs_direct: Scores,
}

impl Cell {
    /// A cell before timing and scoring.
    pub fn new(
        repr: &'static str,
        name: &str,
        distance: usize,
        rgb: Vec<f32>,
        prep_s: f64,
        bytes: u64,
        deforms: bool,
    ) -> Self {
        Cell {
            repr,
            name: name.to_owned(),
            distance,
            rgb,
            prep_s,
            bytes,
            deforms,
            ms: f64::NAN,
            ms_plain: f64::NAN,
            vs_full: Scores::default(),
            vs_direct: Scores::default(),
        }
    }

    /// A file-name stem (`R1-fibers-LoD-1-px`).
    pub fn file_name(&self) -> String {
        let mut s = format!("{}-", self.repr);
        for ch in self.name.chars() {
            if ch.is_ascii_alphanumeric() || ch == '.' {
                s.push(ch);
            } else if !s.ends_with('-') {
                s.push('-');
            }
        }
        s.trim_end_matches('-').to_owned()
    }
}

/// One camera distance.
pub struct Distance {
    /// On-screen width of a stitch at the target (px).
    pub stitch_px: f64,
    /// Half-width of the silhouette band (px): the yarn reach beyond the surface.
    pub band_px: usize,
    /// Interior pixels.
    pub interior_px: usize,
    /// Band pixels.
    pub band_count: usize,
    /// Seconds of the reference render (every bounce).
    pub ref_s: f64,
    /// Seconds of the direct-only reference render.
    pub direct_s: f64,
    /// The direct-only reference against the full one: the multiple-scattering gap.
    pub ms_gap: Scores,
}

/// The study's set-up, for the report.
pub struct Info {
    pub btf: String,
    pub btf_size: usize,
    pub wales: usize,
    pub courses: usize,
    pub width_m: f64,
    pub size: (u32, u32),
    pub spp: u32,
    pub bounces: u32,
    pub view: String,
    pub light: String,
    pub r0_prep_s: f64,
    pub r0_bytes: u64,
    pub adapter: String,
    /// (c, PCA seconds, PCA rel. RMSE of the BTF itself).
    pub eig_errors: Vec<(usize, f64, f64)>,
    /// The BTF from fibers: (c, PCA seconds, PCA rel. RMSE, seconds to render it).
    pub from_fibers: Option<(usize, f64, f64, f64)>,
}

/// Median (NaN for none).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Which pixel centres of a `w × h` perspective frame (row 0 at the top, vertical field of
/// view `fov_deg`, the conventions of `yarn_ref::Camera::perspective` and `btf-render`)
/// the mesh covers.
pub fn raster_mask(
    mesh: &datasets::mesh::Mesh,
    eye: [f64; 3],
    target: [f64; 3],
    up: [f64; 3],
    fov_deg: f64,
    (w, h): (u32, u32),
) -> Vec<bool> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let norm = |a: [f64; 3]| {
        let l = dot(a, a).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let f = norm(sub(target, eye));
    let s = norm(cross(f, up));
    let u = cross(s, f);
    let ty = (0.5 * fov_deg.to_radians()).tan();
    let tx = ty * w as f64 / h as f64;
    let (wf, hf) = (w as f64, h as f64);
    let project = |p: [f64; 3]| -> Option<[f64; 2]> {
        let d = sub(p, eye);
        let z = dot(d, f);
        (z > 1e-9)
            .then(|| [(dot(d, s) / z / tx + 1.0) * 0.5 * wf, (1.0 - dot(d, u) / z / ty) * 0.5 * hf])
    };
    let mut mask = vec![false; (w * h) as usize];
    for t in &mesh.triangles {
        let Some(q) = t
            .iter()
            .map(|&i| project(mesh.positions[i as usize]))
            .collect::<Option<Vec<[f64; 2]>>>()
        else {
            continue;
        };
        let area =
            (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]);
        if area.abs() < 1e-18 {
            continue;
        }
        let x0 = q.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min).floor().max(0.0) as u32;
        let x1 = (q.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max).ceil().max(0.0) as u32)
            .min(w);
        let y0 = q.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min).floor().max(0.0) as u32;
        let y1 = (q.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max).ceil().max(0.0) as u32)
            .min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = [x as f64 + 0.5, y as f64 + 0.5];
                let e = |a: [f64; 2], b: [f64; 2]| {
                    ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) * area.signum()
                };
                if e(q[0], q[1]) >= 0.0 && e(q[1], q[2]) >= 0.0 && e(q[2], q[0]) >= 0.0 {
                    mask[(y * w + x) as usize] = true;
                }
            }
        }
    }
    mask
}

/// `(interior, band)`: the mask eroded by `r` pixels (Chebyshev distance), and the mask
/// dilated by `r` minus the interior.
pub fn interior_and_band(
    mask: &[bool],
    (w, h): (usize, usize),
    r: usize,
) -> (Vec<bool>, Vec<bool>) {
    let filter = |m: &[bool], keep_all: bool| -> Vec<bool> {
        // Separable min (erode, keep_all) or max (dilate) over a (2r+1)² square; outside
        // the frame counts as empty.
        let pass = |src: &[bool], horizontal: bool| -> Vec<bool> {
            let mut out = vec![false; w * h];
            for y in 0..h {
                for x in 0..w {
                    let mut acc = keep_all;
                    for d in -(r as i64)..=(r as i64) {
                        let (xx, yy) = if horizontal {
                            (x as i64 + d, y as i64)
                        } else {
                            (x as i64, y as i64 + d)
                        };
                        let v = xx >= 0
                            && yy >= 0
                            && (xx as usize) < w
                            && (yy as usize) < h
                            && src[yy as usize * w + xx as usize];
                        acc = if keep_all { acc && v } else { acc || v };
                    }
                    out[y * w + x] = acc;
                }
            }
            out
        };
        pass(&pass(m, true), false)
    };
    let interior = filter(mask, true);
    let dilated = filter(mask, false);
    let band = dilated.iter().zip(&interior).map(|(d, i)| *d && !*i).collect();
    (interior, band)
}

/// Box filter of `rgb` (`w × h`) over a `(2k+1)²` window, averaging only pixels inside
/// `mask` (the background does not bleed into the garment's edge).
pub fn box_filter(rgb: &[f32], mask: &[bool], (w, h): (usize, usize), k: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; rgb.len()];
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0f64; 3];
            let mut n = 0usize;
            for yy in y.saturating_sub(k)..(y + k + 1).min(h) {
                for xx in x.saturating_sub(k)..(x + k + 1).min(w) {
                    let i = yy * w + xx;
                    if mask[i] {
                        for c in 0..3 {
                            acc[c] += rgb[3 * i + c] as f64;
                        }
                        n += 1;
                    }
                }
            }
            for c in 0..3 {
                out[3 * (y * w + x) + c] = if n > 0 { (acc[c] / n as f64) as f32 } else { 0.0 };
            }
        }
    }
    out
}

/// Relative RMSE of `x` against `r` on the interior and on the band, the interior
/// mean-radiance ratio, and the interior error at the stitch scale: both images box-filtered
/// over `(2k+1)²` pixels of the dilated garment mask `support` first.
#[allow(clippy::too_many_arguments)]
pub fn scores(
    x: &[f32],
    r: &[f32],
    interior: &[bool],
    band: &[bool],
    support: &[bool],
    size: (usize, usize),
    k: usize,
) -> Scores {
    let mut s = scores_raw(x, r, interior, band);
    let (xs, rs) = (box_filter(x, support, size, k), box_filter(r, support, size, k));
    s.stitch_scale = scores_raw(&xs, &rs, interior, band).interior;
    s
}

fn scores_raw(x: &[f32], r: &[f32], interior: &[bool], band: &[bool]) -> Scores {
    let rel = |m: &[bool]| {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (i, _) in m.iter().enumerate().filter(|(_, v)| **v) {
            for c in 0..3 {
                let (a, b) = (x[3 * i + c] as f64, r[3 * i + c] as f64);
                num += (a - b).powi(2);
                den += b * b;
            }
        }
        if den > 0.0 { (num / den).sqrt() } else { f64::NAN }
    };
    let sum = |v: &[f32]| -> f64 {
        interior
            .iter()
            .enumerate()
            .filter(|(_, m)| **m)
            .map(|(i, _)| (0..3).map(|c| v[3 * i + c] as f64).sum::<f64>())
            .sum()
    };
    Scores {
        interior: rel(interior),
        band: rel(band),
        mean_ratio: sum(x) / sum(r),
        ..Scores::default()
    }
}

fn to_image(rgb: &[f32], (w, h): (u32, u32), exposure: f32) -> RgbImage {
    RgbImage::from_raw(w, h, btf_image::write::to_srgb8(rgb, exposure)).expect("w × h RGB")
}

/// One distance: the references, each representation and its error heat map (full scale
/// = the reference's mean interior radiance).
pub fn contact_sheet(
    cells: &[Cell],
    distance: usize,
    full: &[f32],
    direct: &[f32],
    size: (u32, u32),
    mask: &[bool],
) -> RgbImage {
    let n = mask.iter().filter(|m| **m).count().max(1);
    let mean: f64 = mask
        .iter()
        .enumerate()
        .filter(|(_, m)| **m)
        .map(|(i, _)| (0..3).map(|c| full[3 * i + c] as f64).sum::<f64>() / 3.0)
        .sum::<f64>()
        / n as f64;
    // Exposure: the reference's interior mean at 18 % grey.
    let exposure = if mean > 0.0 { (0.18 / mean) as f32 } else { 1.0 };
    let scale = mean.max(1e-9) as f32;
    let mut top: Vec<(RgbImage, String)> = vec![
        (to_image(full, size, exposure), "R0".into()),
        (to_image(direct, size, exposure), "R0 1 bounce".into()),
    ];
    let mut bottom: Vec<(RgbImage, String)> = vec![
        (RgbImage::from_pixel(size.0, size.1, image::Rgb([255, 255, 255])), String::new()),
        (
            btf_image::heatmap::error_heatmap_image(
                size.0 as usize,
                size.1 as usize,
                full,
                direct,
                scale,
                None,
            ),
            "error".into(),
        ),
    ];
    for c in cells.iter().filter(|c| c.distance == distance) {
        top.push((to_image(&c.rgb, size, exposure), short(c)));
        bottom.push((
            btf_image::heatmap::error_heatmap_image(
                size.0 as usize,
                size.1 as usize,
                full,
                &c.rgb,
                scale,
                None,
            ),
            "error".into(),
        ));
    }
    let strip = |v: &[(RgbImage, String)]| {
        let refs: Vec<(&RgbImage, &str)> = v.iter().map(|(i, s)| (i, s.as_str())).collect();
        btf_image::compose::captioned_strip(&refs, 4)
    };
    btf_image::compose::stacked(&[&strip(&top), &strip(&bottom)], 4)
}

/// A score as CSV text, empty where it was not measured (ꟻLIP without exposures): no NaN
/// is written.
fn measured(x: f64, decimals: usize) -> String {
    if x.is_finite() { format!("{x:.decimals$}") } else { String::new() }
}

/// A score as Markdown text: `n/m` where it was not measured (no NaN in a report).
fn shown(x: f64, decimals: usize) -> String {
    if x.is_finite() { format!("{x:.decimals$}") } else { "n/m".into() }
}

/// `compare.csv`.
pub fn csv(cells: &[Cell], dists: &[Distance]) -> String {
    let mut s = String::from(
        "stitch_px,repr,name,rel_rmse_interior,rel_rmse_band,rel_rmse_stitch_scale,mean_ratio,\
         flip_interior,flip_band,rel_rmse_interior_direct,rel_rmse_band_direct,mean_ratio_direct,frame_ms,\
         ms_ratio_plain,prep_s,gpu_bytes,deforms\n",
    );
    for c in cells {
        let d = &dists[c.distance];
        let _ = writeln!(
            s,
            "{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{:.3},{},{}",
            d.stitch_px,
            c.repr,
            c.name,
            measured(c.vs_full.interior, 5),
            measured(c.vs_full.band, 5),
            measured(c.vs_full.stitch_scale, 5),
            measured(c.vs_full.mean_ratio, 4),
            measured(c.vs_full.flip_interior, 4),
            measured(c.vs_full.flip_band, 4),
            measured(c.vs_direct.interior, 5),
            measured(c.vs_direct.band, 5),
            measured(c.vs_direct.mean_ratio, 4),
            measured(c.ms, 3),
            measured(c.ms / c.ms_plain, 3),
            c.prep_s,
            c.bytes,
            c.deforms
        );
    }
    s
}

/// `report.md`.
pub fn markdown(info: &Info, cells: &[Cell], dists: &[Distance]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Knit garment: every representation against the path-traced fibers\n");
    let _ = writeln!(
        s,
        "{} × {} stitches of the yarn BTF's chart and yarn on the drape ({:.3} m wide), \
         {} × {} px, view {}, light {}; reference {} spp, {} bounces (R0) and 1 (R0 direct); \
         yarn BTF `{}` ({}² texels per period); adapter {}.\n",
        info.wales,
        info.courses,
        info.width_m,
        info.size.0,
        info.size.1,
        info.view,
        info.light,
        info.spp,
        info.bounces,
        info.btf,
        info.btf_size,
        info.adapter
    );
    let _ = writeln!(
        s,
        "Errors are relative RMSE against R0 on the interior (the garment's silhouette eroded \
         by the yarn reach) and on the silhouette band, and mean HDR-ꟻLIP on each (at {:.0} \
         pixels per degree, exposures from R0's interior pixels: the black background would \
         make the frame's median 0); time is the median GPU frame as a ratio \
         to the plain texture drawn in the same run. R0 itself: fibers and BVH built in {:.1} s, \
         {:.0} MiB.\n",
        btf_image::flip::DEFAULT_PPD,
        info.r0_prep_s,
        info.r0_bytes as f64 / 1048576.0
    );
    for (k, d) in dists.iter().enumerate() {
        let _ = writeln!(
            s,
            "## A stitch covers {} px\n\nInterior {} px, band {} px (±{} px). Reference {:.1} s \
             (direct only {:.1} s). Multiple-scattering gap (R0 direct against R0): interior \
             {}, band {}, stitch scale {}, mean ratio {}, ꟻLIP interior {}, band {}.\n",
            d.stitch_px,
            d.interior_px,
            d.band_count,
            d.band_px,
            d.ref_s,
            d.direct_s,
            shown(d.ms_gap.interior, 3),
            shown(d.ms_gap.band, 3),
            shown(d.ms_gap.stitch_scale, 3),
            shown(d.ms_gap.mean_ratio, 3),
            shown(d.ms_gap.flip_interior, 3),
            shown(d.ms_gap.flip_band, 3)
        );
        let _ = writeln!(
            s,
            "| repr | what | interior | band | stitch scale | mean ratio | ꟻLIP interior | \
             ꟻLIP band | interior vs direct | frame / plain | prep s | GPU MiB | deforms |\n\
             |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|"
        );
        for c in cells.iter().filter(|c| c.distance == k) {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.1} | {} |",
                c.repr,
                c.name,
                shown(c.vs_full.interior, 3),
                shown(c.vs_full.band, 3),
                shown(c.vs_full.stitch_scale, 3),
                shown(c.vs_full.mean_ratio, 3),
                shown(c.vs_full.flip_interior, 3),
                shown(c.vs_full.flip_band, 3),
                shown(c.vs_direct.interior, 3),
                shown(c.ms / c.ms_plain, 2),
                c.prep_s,
                c.bytes as f64 / 1048576.0,
                if c.deforms { "yes" } else { "no" }
            );
        }
        let _ = writeln!(s, "\n![contact sheet](sheet-{}px.png)\n", d.stitch_px);
    }
    let _ = writeln!(
        s,
        "## The BTF itself\n\n| c | PCA s | PCA rel. RMSE of the BTF |\n|---:|---:|---:|"
    );
    for (c, sec, e) in &info.eig_errors {
        let _ = writeln!(s, "| {c} | {sec:.2} | {e:.3} |");
    }
    if let Some((c, sec, e, made)) = info.from_fibers {
        let _ = writeln!(
            s,
            "\nThe BTF from fibers (the same patch and sampling rendered by the GPU fibers in \
             {made:.1} s; resumed runs count only the images rendered): c = {c}, PCA {sec:.2} s, \
             PCA rel. RMSE {e:.3}."
        );
    }
    let _ = writeln!(s, "\n![error against time](pareto.png)");
    s
}

/// Interior error against frame-time ratio, one series per distance, each point labelled
/// by its representation; the Pareto front is what no other cell beats on both axes.
pub fn pareto(cells: &[Cell], dists: &[Distance]) -> Plot {
    let mut series = Vec::new();
    for (k, d) in dists.iter().enumerate() {
        let pts: Vec<(f64, f64)> = cells
            .iter()
            .filter(|c| c.distance == k)
            .map(|c| (c.ms / c.ms_plain, c.vs_full.interior))
            .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
            .collect();
        let mut sr = Series::new(format!("{} px per stitch", d.stitch_px), pts);
        sr.points_only = true;
        sr.labels = cells
            .iter()
            .filter(|c| c.distance == k)
            .filter(|c| {
                let (x, y) = (c.ms / c.ms_plain, c.vs_full.interior);
                x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0
            })
            .map(short)
            .collect();
        series.push(sr);
    }
    Plot {
        title: "Knit garment: error against frame time".into(),
        x_label: "frame time / plain texture (same run, log)".into(),
        y_label: "rel. RMSE against R0, interior (log)".into(),
        log_x: true,
        log_y: true,
        series,
    }
}

fn short(c: &Cell) -> String {
    match c.repr {
        "R1" if c.name.contains("full") => "R1 full".into(),
        "R1" => format!("R1 {}", c.name.trim_start_matches("fibers LoD ").replace(' ', "")),
        "R4" if c.name.starts_with("BTF from fibers") => {
            format!("R4f {}", c.name.trim_start_matches("BTF from fibers ").replace(' ', ""))
        }
        "R4" => format!("R4 {}", c.name.trim_start_matches("BTF ").replace(' ', "")),
        "R2" => "R2 strips".into(),
        "R3" => "R3 lumislices".into(),
        _ if c.name.contains("tubes") => "tubes".into(),
        _ => "plain".into(),
    }
}

/// One strain of the stretch study: the strain, its cells and distances, and the minimum
/// clearance between the knot yarns' courses / 2r.
pub type StretchRun = (f64, Vec<Cell>, Vec<Distance>, f64);

/// The representations the stretch summary follows: the BTF at its largest component
/// count, the GPU fibers at full detail, the yarn strips, the lumislices and the plain
/// texture.
fn stretch_followed(cells: &[Cell]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    let best_btf = cells
        .iter()
        .filter(|c| c.repr == "R4" && c.name.starts_with("BTF c = "))
        .max_by_key(|c| c.name.trim_start_matches("BTF c = ").parse::<usize>().unwrap_or(0))
        .map(|c| c.name.clone());
    names.extend(best_btf);
    names.extend(
        cells.iter().find(|c| c.name.starts_with("BTF from fibers")).map(|c| c.name.clone()),
    );
    names.push("fibers full detail".into());
    if cells.iter().any(|c| c.name == "yarn strips") {
        names.push("yarn strips".into());
    }
    if cells.iter().any(|c| c.name == "lumislices") {
        names.push("lumislices".into());
    }
    names.push("plain texture (BTF mean)".into());
    names
}

/// The stretch study's summary (DESIGN §4.2, issue #20): per distance and followed
/// representation the interior rel. RMSE and ꟻLIP against the reference at each strain
/// (the GPU fibers also against the direct-only reference, which isolates the geometry
/// from the multiple-scattering gap), the first strain at which the BTF is worse than the
/// fibers, `stretch.csv`, `stretch.md` and one plot per distance.
pub fn write_stretch(
    out: &std::path::Path,
    runs: &[StretchRun],
    header: &str,
) -> anyhow::Result<()> {
    let Some((_, cells0, dists0, _)) = runs.first() else { return Ok(()) };
    let names = stretch_followed(cells0);
    fn find<'a>(cells: &'a [Cell], d: usize, name: &str) -> Option<&'a Cell> {
        cells.iter().find(|c| c.distance == d && c.name == name)
    }
    let mut csv = String::from(
        "strain,stitch_px,repr,name,rel_rmse_interior,flip_interior,stitch_scale,mean_ratio,rel_rmse_vs_direct\n",
    );
    let mut md = String::from(
        "# The stretch study: when must a preview leave the BTF?\n\n\
         The garment stretched along the wales by each strain; the yarns follow by the knot \
         solver (3 Gauss–Newton iterations); the BTF is the rest sample's, stretched with the \
         UVs. Errors against the path-traced fibers of the stretched garment (R0, every \
         bounce); the GPU fibers also against the direct-only R0 (their own light transport), \
         which isolates the geometry from the multiple-scattering gap.\n\n",
    );
    let _ = write!(
        md,
        "Minimum clearance between the knot yarns' courses / 2r (below 1 they interpenetrate; the model has no contact):"
    );
    for (s, _, _, c) in runs {
        let _ = write!(md, " {:.0} %: {c:.3};", s * 100.0);
    }
    let _ = writeln!(md, "\n");
    for (d, dist) in dists0.iter().enumerate() {
        let _ = writeln!(md, "## {} px per stitch\n", dist.stitch_px);
        let _ = write!(md, "| representation | measure |");
        for (s, _, _, _) in runs {
            let _ = write!(md, " {:.0} % |", s * 100.0);
        }
        let _ = writeln!(md);
        let _ = writeln!(md, "|---|---|{}", "---:|".repeat(runs.len()));
        let mut series = Vec::new();
        for name in &names {
            let per: Vec<(f64, Option<&Cell>)> =
                runs.iter().map(|(s, cells, _, _)| (*s, find(cells, d, name))).collect();
            for (s, c) in &per {
                if let Some(c) = c {
                    let _ = writeln!(
                        csv,
                        "{s},{},{},{},{},{},{},{},{}",
                        dist.stitch_px,
                        c.repr,
                        c.name,
                        measured(c.vs_full.interior, 5),
                        measured(c.vs_full.flip_interior, 5),
                        measured(c.vs_full.stitch_scale, 5),
                        measured(c.vs_full.mean_ratio, 5),
                        measured(c.vs_direct.interior, 5)
                    );
                }
            }
            let row = |label: &str, f: &dyn Fn(&Cell) -> f64| {
                let mut line = format!("| {name} | {label} |");
                for (_, c) in &per {
                    match c {
                        Some(c) if f(c).is_finite() => line.push_str(&format!(" {:.3} |", f(c))),
                        Some(_) => line.push_str(" n/m |"),
                        None => line.push_str(" — |"),
                    }
                }
                line
            };
            let _ = writeln!(md, "{}", row("rel. RMSE", &|c| c.vs_full.interior));
            let _ = writeln!(md, "{}", row("ꟻLIP", &|c| c.vs_full.flip_interior));
            let _ = writeln!(md, "{}", row("stitch-scale rel. RMSE", &|c| c.vs_full.stitch_scale));
            if name.starts_with("fibers") {
                let _ =
                    writeln!(md, "{}", row("rel. RMSE vs direct R0", &|c| c.vs_direct.interior));
            }
            series.push(Series::new(
                format!("{name}: rel. RMSE"),
                per.iter()
                    .filter_map(|(s, c)| c.map(|c| (s * 100.0, c.vs_full.interior)))
                    .collect(),
            ));
            series.push(Series::new(
                format!("{name}: FLIP"),
                per.iter()
                    .filter_map(|(s, c)| c.map(|c| (s * 100.0, c.vs_full.flip_interior)))
                    .collect(),
            ));
        }
        // The first strain at which the BTF is worse than the fibers (by each measure).
        let btf = &names[0];
        let cross_with = |other: &str, f: &dyn Fn(&Cell) -> f64| {
            runs.iter()
                .find(|(_, cells, _, _)| match (find(cells, d, btf), find(cells, d, other)) {
                    (Some(b), Some(r)) => f(b) > f(r),
                    _ => false,
                })
                .map(|(s, _, _, _)| format!("{:.0} %", s * 100.0))
                .unwrap_or_else(|| "none of the strains measured".into())
        };
        let strips_line: String = ["yarn strips", "lumislices"]
            .iter()
            .filter(|m| names.iter().any(|n| n == *m))
            .map(|m| {
                format!(
                    " Than the {m}: {} by rel. RMSE, {} by ꟻLIP.",
                    cross_with(m, &|c| c.vs_full.interior),
                    cross_with(m, &|c| c.vs_full.flip_interior)
                )
            })
            .collect();
        let cross = |f: &dyn Fn(&Cell) -> f64| {
            runs.iter()
                .find(|(_, cells, _, _)| {
                    match (find(cells, d, btf), find(cells, d, "fibers full detail")) {
                        (Some(b), Some(r)) => f(b) > f(r),
                        _ => false,
                    }
                })
                .map(|(s, _, _, _)| format!("{:.0} %", s * 100.0))
                .unwrap_or_else(|| "none of the strains measured".into())
        };
        let _ = writeln!(
            md,
            "\nFirst strain at which {btf} is worse than the GPU fibers: {} by rel. RMSE, {} by \
             ꟻLIP.{strips_line}\n\n![errors against strain](stretch-{}px.png)\n",
            cross(&|c| c.vs_full.interior),
            cross(&|c| c.vs_full.flip_interior),
            dist.stitch_px
        );
        let plot = Plot {
            title: format!("stretch study, {} px per stitch", dist.stitch_px),
            x_label: "stretch along the wales (%)".into(),
            y_label: "error against R0 (interior)".into(),
            series,
            ..Plot::default()
        };
        btf_image::write::write_png(
            &out.join(format!("stretch-{}px.png", dist.stitch_px)),
            &btf_image::plot::render(&plot),
        )?;
    }
    btf_image::write::write_text(&out.join("stretch.csv"), &csv)?;
    btf_image::write::write_text(&out.join("stretch.md"), &md)?;
    eprintln!("{md}");
    write_final(out, runs, header)
}

/// The study's `report.md` over every strain (DESIGN §4.2's final table): per distance one
/// row per representation with its interior ꟻLIP and rel. RMSE against the reference of
/// each strain, and its frame time over the plain texture's, preprocessing, memory and
/// whether it follows deformation (from the first strain's run); and per distance a Pareto
/// plot, ꟻLIP against frame-time ratio, one series per strain.
fn write_final(out: &std::path::Path, runs: &[StretchRun], header: &str) -> anyhow::Result<()> {
    let Some((_, cells0, dists0, _)) = runs.first() else { return Ok(()) };
    let pct = |s: f64| format!("{:.0} %", s * 100.0);
    let mut md = format!(
        "# Every representation of a knit garment against the path-traced fibers\n\n{header}\n\n\
         Per strain the garment is stretched along the wales and its yarns follow by the knot \
         solver; the BTFs are the rest sample's, stretched with the UVs. ꟻLIP and rel. RMSE \
         are on the interior against R0 (every bounce) of that strain; frame time, \
         preprocessing and memory are the first strain's ({}). Each strain's full report is \
         in `stretch-S/report.md`, the errors against strain in [stretch.md](stretch.md).\n\n",
        pct(runs[0].0)
    );
    for (d, dist) in dists0.iter().enumerate() {
        let _ = writeln!(md, "## {} px per stitch\n", dist.stitch_px);
        let _ = write!(md, "| repr | what |");
        for (s, ..) in runs {
            let _ = write!(md, " ꟻLIP {} |", pct(*s));
        }
        for (s, ..) in runs {
            let _ = write!(md, " rel. RMSE {} |", pct(*s));
        }
        let _ = writeln!(md, " frame / plain | prep s | GPU MiB | follows deformation |");
        let _ = writeln!(md, "|---|---|{}---:|---:|---:|:-:|", "---:|".repeat(2 * runs.len()));
        let value = |x: Option<f64>| match x {
            Some(v) if v.is_finite() => format!(" {v:.3} |"),
            Some(_) => " n/m |".to_string(),
            None => " — |".to_string(),
        };
        // R0 with one bounce: the multiple-scattering gap the one-bounce methods inherit.
        let mut line = "| R0 | one bounce (the multiple-scattering gap) |".to_string();
        for (_, _, dists, _) in runs {
            line.push_str(&value(dists.get(d).map(|x| x.ms_gap.flip_interior)));
        }
        for (_, _, dists, _) in runs {
            line.push_str(&value(dists.get(d).map(|x| x.ms_gap.interior)));
        }
        let _ = writeln!(md, "{line} — | — | — | yes |");
        let mut series = Vec::new();
        for c0 in cells0.iter().filter(|c| c.distance == d) {
            let per: Vec<Option<&Cell>> = runs
                .iter()
                .map(|(_, cells, ..)| cells.iter().find(|c| c.distance == d && c.name == c0.name))
                .collect();
            let mut line = format!("| {} | {} |", c0.repr, c0.name);
            for c in &per {
                line.push_str(&value(c.map(|c| c.vs_full.flip_interior)));
            }
            for c in &per {
                line.push_str(&value(c.map(|c| c.vs_full.interior)));
            }
            let _ = writeln!(
                md,
                "{line} {} | {:.2} | {:.1} | {} |",
                shown(c0.ms / c0.ms_plain, 2),
                c0.prep_s,
                c0.bytes as f64 / 1048576.0,
                if c0.deforms { "yes" } else { "no" }
            );
        }
        for (k, (s, cells, ..)) in runs.iter().enumerate() {
            // x: the first strain's frame ratio of the same representation.
            let pts: Vec<((f64, f64), String)> = cells
                .iter()
                .filter(|c| c.distance == d)
                .filter_map(|c| {
                    let c0 = cells0.iter().find(|k| k.distance == d && k.name == c.name)?;
                    let (x, y) = (c0.ms / c0.ms_plain, c.vs_full.flip_interior);
                    (x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0)
                        .then(|| ((x, y), short(c)))
                })
                .collect();
            let mut sr =
                Series::new(format!("strain {}", pct(*s)), pts.iter().map(|p| p.0).collect());
            sr.points_only = true;
            // Labels on the first strain's points only (the others sit beside them).
            if k == 0 {
                sr.labels = pts.into_iter().map(|p| p.1).collect();
            }
            series.push(sr);
        }
        let plot = Plot {
            title: format!("{} px per stitch: error against frame time", dist.stitch_px),
            x_label: "frame time / plain texture (same run, log)".into(),
            y_label: "HDR-FLIP against R0, interior (log)".into(),
            log_x: true,
            log_y: true,
            series,
        };
        let name = format!("pareto-{}px.png", dist.stitch_px);
        btf_image::write::write_png(&out.join(&name), &btf_image::plot::render(&plot))?;
        let _ = writeln!(
            md,
            "\n![error against time]({name})\n\n![errors against strain](stretch-{}px.png)\n",
            dist.stitch_px
        );
    }
    btf_image::write::write_text(&out.join("report.md"), &md)?;
    crate::guard::outln!("{md}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erosion_and_dilation_of_a_square() {
        let (w, h) = (20, 20);
        let mask: Vec<bool> =
            (0..w * h).map(|i| (5..15).contains(&(i % w)) && (5..15).contains(&(i / w))).collect();
        let (interior, band) = interior_and_band(&mask, (w, h), 2);
        // 10 × 10 eroded by 2 → 6 × 6; dilated by 2 → 14 × 14; band = 196 − 36.
        assert_eq!(interior.iter().filter(|m| **m).count(), 36);
        assert_eq!(band.iter().filter(|m| **m).count(), 196 - 36);
    }

    #[test]
    fn scores_of_a_uniform_scaling() {
        let r = vec![1.0f32; 12];
        let x = vec![1.1f32; 12];
        let m = vec![true; 4];
        let s = scores(&x, &r, &m, &m, &m, (2, 2), 1);
        assert!((s.interior - 0.1).abs() < 1e-6 && (s.mean_ratio - 1.1).abs() < 1e-6);
        assert!((s.stitch_scale - 0.1).abs() < 1e-6);
    }

    #[test]
    fn a_square_facing_the_camera_covers_its_projected_pixels() {
        // A 2 × 2 m square at z = 0 seen from z = 2 (fov 90°): it spans ±0.5 of the frame.
        let mesh = datasets::mesh::Mesh {
            positions: vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            uvs: vec![[0.0, 0.0]; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            triangle_uvs: vec![[0, 0, 0], [0, 0, 0]],
            ..Default::default()
        };
        let m = raster_mask(&mesh, [0.0, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0], 90.0, (40, 40));
        assert_eq!(m.iter().filter(|v| **v).count(), 20 * 20);
        assert!(m[20 * 40 + 20] && !m[0]);
    }
}
