//! `btf capture process`: a raw capture folder becomes a BTF store of tileable
//! normtextures (Sattler et al. 2003, §3.2): register each view slot (markers →
//! homography), rectify every light image of the slot onto the frontal plane, crop the
//! region of interest at the target size plus the blend width, blend the edges, and scale
//! the linear DN to BTF units with the lab's light reference:
//! `BTF = DN / (reference_white_dn · π · cos^k α)`, `α` the pixel's angle to the optical
//! axis (flat field), so that a white Lambertian under the reference light reads `1/π`.
//!
//! Work streams per view slot (a slot's images are decoded one at a time, so memory is a
//! few images per worker), slots run in parallel, and every finished image is a store
//! chunk: `resume` keeps them. Inputs are checked before anything is written, and on any
//! error the partial store is removed.

use super::blend;
use super::layout::CaptureLayout;
use super::raw::{self, RawImage};
use super::rectify::{Filter, Grid, Plan};
use super::register::{self, RegisterOptions, Registration};
use crate::{Error, Result};
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use rayon::prelude::*;
use serde_json::json;
use std::path::Path;

/// The region of interest, in pixels of the rectified frontal image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Roi {
    /// The whole sample square.
    Full,
    /// The largest centred square whose texels' bilinear taps stay on the sample in every
    /// view ([`auto_inset_mm`]).
    Auto,
    /// `x, y, w, h` in rectified pixels (`w = h`), `y` along sample `+y`.
    Rect([f64; 4]),
}

/// Options of [`process`].
#[derive(Debug, Clone)]
pub struct ProcessOptions {
    /// Output texels per side.
    pub size: usize,
    /// Pixels per side of the rectified frontal frame over the sample square, in which
    /// the ROI is given.
    pub rectified_size: usize,
    /// Region of interest.
    pub roi: Roi,
    /// Blend width in output texels.
    pub blend_width: usize,
    /// Resampling filter.
    pub filter: Filter,
    /// Register slots whose markers fail from the nominal pose (with a warning).
    pub fallback_nominal: bool,
    /// Keep the images of an interrupted run.
    pub resume: bool,
    /// Store element type.
    pub dtype: DType,
    /// Images (most frontal lights) averaged for registration.
    pub registration_lights: usize,
    /// Registration knobs.
    pub register: RegisterOptions,
    /// Scale each light's images by `cos θ_l / cos θ_l'` for the registered plate tilt
    /// ([`super::incidence`]).
    pub correct_light_incidence: bool,
    /// Process only this shard's view slots into the store every shard fills (issue #23);
    /// the store is committed by [`finalize_shards`] (`btf finalize`).
    pub shard: Option<btf_core::shard::Shard>,
}

impl Default for ProcessOptions {
    fn default() -> Self {
        ProcessOptions {
            size: 256,
            rectified_size: 1024,
            roi: Roi::Auto,
            blend_width: 0,
            filter: Filter::Footprint,
            fallback_nominal: false,
            resume: false,
            dtype: DType::F32,
            registration_lights: 8,
            register: RegisterOptions::default(),
            correct_light_incidence: true,
            shard: None,
        }
    }
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct ProcessReport {
    /// Images rectified in this run.
    pub images_written: usize,
    /// Images kept from an interrupted run.
    pub images_kept: usize,
    /// Registration of every view slot.
    pub registrations: Vec<Registration>,
    /// The output grid (before blending: `size + blend_width` texels).
    pub grid: Grid,
}

impl ProcessReport {
    /// Per view slot, raw pixels per output texel along the worst- and best-resolved axis
    /// ([`super::rectify::pixels_per_texel`] on the registered homography).
    pub fn pixels_per_texel(&self) -> Vec<[f64; 2]> {
        self.registrations
            .iter()
            .map(|r| super::rectify::pixels_per_texel(&r.matrix(), &self.grid))
            .collect()
    }
}

/// The output grid on the plate for `opt` (size + blend width texels over the ROI).
pub fn output_grid(layout: &CaptureLayout, opt: &ProcessOptions) -> Result<Grid> {
    let file = layout.dir.join("capture.toml").display().to_string();
    let s = layout.plate.sample_mm;
    let r = opt.rectified_size as f64;
    let [x, y, w, h] = match opt.roi {
        Roi::Full => [0.0, 0.0, r, r],
        Roi::Auto => {
            let inset = (auto_inset_mm(layout) / (s / r)).ceil();
            [inset, inset, r - 2.0 * inset, r - 2.0 * inset]
        }
        Roi::Rect(v) => v,
    };
    if !(w > 0.0 && (w - h).abs() < 1e-9 && x >= 0.0 && y >= 0.0 && x + w <= r && y + h <= r) {
        return Err(Error::invalid(
            &file,
            "roi",
            format!("{x},{y},{w},{h} must be a square inside 0..{r}"),
        ));
    }
    if opt.size == 0 || opt.size > 8192 || opt.blend_width >= opt.size {
        return Err(Error::invalid(
            &file,
            "size",
            "size must be 1..=8192 and the blend width below it",
        ));
    }
    let mm = s / r;
    let n = opt.size + opt.blend_width;
    Ok(Grid { origin_mm: [-s / 2.0 + x * mm, -s / 2.0 + y * mm], texel_mm: w * mm / n as f64, n })
}

/// The inset (mm) of the automatic ROI: one raw pixel (the reach of a bilinear tap) at the
/// coarsest the sample's corners are seen in any view, `1 / σ_min(J)` for the Jacobian `J`
/// (pixels per mm) of the nominal homography, plus 1 mm for the robot's pose error.
pub fn auto_inset_mm(layout: &CaptureLayout) -> f64 {
    let h = layout.plate.sample_mm / 2.0;
    let mut worst = 0f64;
    for view in 0..layout.sampling.len() {
        let hm = layout.nominal_homography(view);
        for c in [[-h, -h], [h, -h], [h, h], [-h, h]] {
            let e = 1e-3;
            let p = super::homography::apply(&hm, c);
            let (px, py) = (
                super::homography::apply(&hm, [c[0] + e, c[1]]),
                super::homography::apply(&hm, [c[0], c[1] + e]),
            );
            let j =
                nalgebra::Matrix2::new(px[0] - p[0], py[0] - p[0], px[1] - p[1], py[1] - p[1]) / e;
            let smin = j.singular_values().min();
            if smin > 1e-9 {
                worst = worst.max(1.0 / smin);
            }
        }
    }
    worst + 1.0
}

/// Every image exists with the camera's size; the first failure names the file.
pub fn check_inputs(layout: &CaptureLayout) -> Result<()> {
    let n = layout.sampling.len();
    let (w, h) = (layout.camera.width, layout.camera.height);
    (0..n * n).into_par_iter().try_for_each(|k| {
        let path = layout.image_path(k / n, k % n);
        if !path.exists() {
            return Err(Error::invalid(
                &path.display().to_string(),
                "image",
                "missing from the capture",
            ));
        }
        let (iw, ih) = raw::dimensions(&path)?;
        if (iw, ih) != (w, h) {
            return Err(Error::invalid(
                &path.display().to_string(),
                "size",
                format!("{iw}x{ih}, but capture.toml says {w}x{h}"),
            ));
        }
        Ok(())
    })
}

/// Pixel value → BTF scale at image position `(u, v)`.
pub fn radiometric_gain(layout: &CaptureLayout) -> impl Fn(f64, f64) -> f64 + '_ {
    move |u, v| match layout.radiometry {
        Some(r) => {
            1.0 / (r.reference_white_dn
                * std::f64::consts::PI
                * layout.axis_cosine(u, v).powf(r.vignetting_cos_power))
        }
        None => 1.0 / ((1u64 << layout.camera.bits) - 1) as f64,
    }
}

/// The lights averaged to register a slot: the `k` most frontal ones with `θ ≤ 60°`
/// (grazing lights leave the markers dim).
pub fn registration_lights(layout: &CaptureLayout, k: usize) -> Vec<usize> {
    let s = &layout.sampling;
    let mut idx: Vec<usize> = (0..s.len()).collect();
    idx.sort_by(|&a, &b| s.direction(a).theta_deg.total_cmp(&s.direction(b).theta_deg));
    let usable = idx.iter().filter(|&&i| s.direction(i).theta_deg <= 60.0).count();
    idx.truncate(k.min(usable).max(1));
    idx
}

fn read_image(layout: &CaptureLayout, view: usize, light: usize) -> Result<RawImage> {
    let path = layout.image_path(view, light);
    let img = raw::read(&path, layout.camera.bits)?;
    if (img.width, img.height) != (layout.camera.width, layout.camera.height) {
        return Err(Error::invalid(
            &path.display().to_string(),
            "size",
            "differs from capture.toml",
        ));
    }
    Ok(img)
}

/// Registers view slot `view` (or falls back to its nominal pose when allowed).
pub fn register_slot(
    layout: &CaptureLayout,
    view: usize,
    opt: &ProcessOptions,
) -> Result<Registration> {
    let lights = registration_lights(layout, opt.registration_lights);
    let (w, h) = (layout.camera.width, layout.camera.height);
    let mut sum = vec![0f32; w * h];
    for &l in &lights {
        let img = read_image(layout, view, l)?;
        for (s, p) in sum.iter_mut().zip(&img.rgb) {
            *s += (p[0] + p[1] + p[2]) / (3 * lights.len()) as f32;
        }
    }
    let gray = super::markers::Gray { width: w, height: h, data: sum };
    match register::register(layout, view, &gray, &opt.register) {
        Ok(r) => Ok(r),
        Err(why) if opt.fallback_nominal => Ok(register::nominal(layout, view, why)),
        Err(why) => {
            let files: Vec<String> =
                lights.iter().map(|&l| layout.image_path(view, l).display().to_string()).collect();
            Err(Error::Registration {
                file: files.join(", "),
                what: format!(
                    "view slot {view}: {why} (use --fallback nominal to register it from the nominal pose)"
                ),
            })
        }
    }
}

/// Rectifies, crops and blends one raw image with a slot's plan and scales it by `gain`
/// (the light-incidence correction): `size² · 3` values.
pub fn normtexture(plan: &Plan, img: &RawImage, size: usize, gain: f32) -> Vec<f32> {
    let crop = plan.apply(img);
    blend::fold(&crop, plan.n, size).into_iter().flatten().map(|v| v * gain).collect()
}

/// The per-light gains of a registered slot: the incidence correction, or all 1.
pub fn light_gains(layout: &CaptureLayout, reg: &Registration, correct: bool) -> Vec<f32> {
    if correct {
        let g = super::incidence::light_cosine_gains(layout, reg.view, &reg.matrix());
        g.into_iter().map(|x| x as f32).collect()
    } else {
        vec![1.0; layout.sampling.len()]
    }
}

/// The plan of a registered slot.
pub fn slot_plan(
    layout: &CaptureLayout,
    reg: &Registration,
    grid: &Grid,
    filter: Filter,
) -> Result<Plan> {
    let (w, h) = (layout.camera.width, layout.camera.height);
    Plan::new(&reg.matrix(), grid, w, h, filter, radiometric_gain(layout)).map_err(|[c, r]| {
        Error::invalid(
            &layout.image_path(reg.view, 0).display().to_string(),
            "roi",
            format!("texel ({c}, {r}) of view slot {} falls outside the image", reg.view),
        )
    })
}

/// The name of view `view`'s registration record: the Zarr group `registration/<name>`
/// inside the store being written ([`btf_core::zarr::write_record`]).
fn sidecar(view: usize) -> String {
    format!("view_{view:04}")
}

/// Processes `raw_dir` into the BTF store `out`; `tick` is called once per image.
pub fn process(
    raw_dir: &Path,
    out: &Path,
    opt: &ProcessOptions,
    tick: &(dyn Fn() + Sync),
) -> Result<ProcessReport> {
    let layout = CaptureLayout::read(raw_dir)?;
    let grid = output_grid(&layout, opt)?;
    check_inputs(&layout)?;
    let s = layout.sampling.clone();
    let mut meta = BtfMeta::new(s.clone(), s, opt.size, opt.size);
    if layout.radiometry.is_none() {
        meta.units = "DN / sensor full scale (capture.toml has no light reference)".into();
    }
    // The job a resume must match: which raw capture (its folder and its capture.toml) and
    // every option that shapes the result.
    let options = format!("{:?}", ProcessOptions { resume: false, shard: None, ..opt.clone() });
    if let Some(shard) = opt.shard {
        // Shards identify the capture by content (their paths may differ) and record what
        // the finaliser needs for the provenance.
        let job = serde_json::json!({
            "kind": "capture process",
            "raw": { "fingerprint": btf_core::shard::fingerprint(raw_dir)? },
            "options": options,
            "shards": shard.count,
            "provenance": provenance_base(&layout, &grid, opt),
        });
        let writer = BtfWriter::join_for_job(out, meta, opt.dtype, job)?;
        btf_core::zarr::ensure_record_group(writer.dir(), "registration")?;
        btf_core::zarr::ensure_record_group(writer.dir(), TILT)?;
        let views = shard.range(layout.sampling.len());
        let (regs, written, kept) = run_slots(&layout, &writer, &grid, opt, views, tick)?;
        return Ok(ProcessReport {
            images_written: written,
            images_kept: kept,
            registrations: regs,
            grid,
        });
    }
    let job = serde_json::json!({
        "raw_dir": btf_core::fs::input_identity(raw_dir),
        "capture_toml": btf_core::fs::input_identity(&raw_dir.join("capture.toml")),
        "options": options,
    });
    let mut writer = BtfWriter::create_for_job(out, meta, opt.dtype, opt.resume, job)?;
    let partial = writer.dir().to_owned();
    btf_core::zarr::ensure_record_group(&partial, "registration")?;
    btf_core::zarr::ensure_record_group(&partial, TILT)?;
    let views = 0..layout.sampling.len();
    let result = run_slots(&layout, &writer, &grid, opt, views, tick);
    let outcome = result.and_then(|(regs, written, kept)| {
        // From the records, as the finaliser of a sharded job reads them: the provenance
        // is then the same to the last digit whichever way the store was made.
        let base = provenance_base(&layout, &grid, opt);
        assemble_provenance(&mut writer, out, base)?;
        writer.finish()?;
        Ok(ProcessReport { images_written: written, images_kept: kept, registrations: regs, grid })
    });
    if outcome.is_err() {
        let _ = std::fs::remove_dir_all(&partial);
    }
    outcome
}

/// The record group where shards keep each view slot's plate tilt for the finaliser
/// (removed when the store is committed).
const TILT: &str = "capture_tilt";

/// Commits the store that the shards of a `btf capture process` job filled at `out`: every
/// image must be in and sound and every slot's registration recorded; the provenance is
/// assembled from the job's record and the slots' records as one process would have
/// written it. `Ok(true)` when it was committed already (safe to run twice).
pub fn finalize_shards(out: &Path) -> Result<bool> {
    let Some((writer, record)) = BtfWriter::reopen_for_commit(out)? else {
        btf_core::store::BtfStore::open(out)?;
        return Ok(true);
    };
    writer.check_complete(out)?;
    let mut writer = writer;
    assemble_provenance(&mut writer, out, record["job"]["provenance"].clone())?;
    writer.finish()?;
    Ok(false)
}

/// Sets the store's provenance from `base` and every slot's registration and plate-tilt
/// records, then removes the tilt records (they were only for this).
fn assemble_provenance(writer: &mut BtfWriter, out: &Path, base: serde_json::Value) -> Result<()> {
    let n = writer.meta().n_views();
    let mut regs = Vec::with_capacity(n);
    let mut tilts = Vec::with_capacity(n);
    for view in 0..n {
        let side = sidecar(view);
        let missing = |what: &str| {
            crate::Error::invalid(
                &out.join(what).display().to_string(),
                &side,
                format!("view slot {view} has no {what} record; run its shard again"),
            )
        };
        regs.push(
            btf_core::zarr::read_record(writer.dir(), "registration", &side)
                .ok_or_else(|| missing("registration"))?,
        );
        let tilt = btf_core::zarr::read_record(writer.dir(), TILT, &side)
            .map(|t| t["tilt_deg"].clone())
            .ok_or_else(|| missing(TILT))?;
        tilts.push(tilt);
    }
    writer.set_provenance(provenance_with(base, regs, tilts));
    let tilt_dir = writer.dir().join(TILT);
    std::fs::remove_dir_all(&tilt_dir).map_err(|e| btf_core::Error::io(&tilt_dir, e))?;
    Ok(())
}

fn run_slots(
    layout: &CaptureLayout,
    writer: &BtfWriter,
    grid: &Grid,
    opt: &ProcessOptions,
    views: std::ops::Range<usize>,
    tick: &(dyn Fn() + Sync),
) -> Result<(Vec<Registration>, usize, usize)> {
    let n = layout.sampling.len();
    let results: Vec<(Registration, usize)> = views
        .clone()
        .into_par_iter()
        .map(|view| -> Result<(Registration, usize)> {
            let side = sidecar(view);
            let done = (0..n).all(|l| writer.has_image(view, l))
                && btf_core::zarr::read_record(writer.dir(), TILT, &side).is_some();
            if done
                && let Some(record) =
                    btf_core::zarr::read_record(writer.dir(), "registration", &side)
                && let Ok(reg) = serde_json::from_value::<Registration>(record)
                && sidecar_is_sound(&reg, view)
            {
                (0..n).for_each(|_| tick());
                return Ok((reg, 0));
            }
            let reg = register_slot(layout, view, opt)?;
            let plan = slot_plan(layout, &reg, grid, opt.filter)?;
            let gains = light_gains(layout, &reg, opt.correct_light_incidence);
            let mut written = 0;
            for light in 0..n {
                if !writer.has_image(view, light) {
                    let img = read_image(layout, view, light)?;
                    writer.write_image(
                        view,
                        light,
                        &normtexture(&plan, &img, opt.size, gains[light]),
                    )?;
                    written += 1;
                }
                tick();
            }
            write_sidecar(writer.dir(), &side, &reg)?;
            let tilt = super::incidence::tilt_deg(layout, view, &reg.matrix());
            btf_core::zarr::write_record(writer.dir(), TILT, &side, &json!({ "tilt_deg": tilt }))?;
            Ok((reg, written))
        })
        .collect::<Result<_>>()?;
    let written: usize = results.iter().map(|r| r.1).sum();
    Ok((results.into_iter().map(|r| r.0).collect(), written, views.len() * n - written))
}

/// Whether a registration sidecar left by an interrupted run can be kept: it is the view's
/// and its homography is finite and invertible (anything else is registered again).
fn sidecar_is_sound(reg: &Registration, view: usize) -> bool {
    let h = reg.matrix();
    reg.view == view && h.iter().all(|v| v.is_finite()) && h.try_inverse().is_some()
}

fn write_sidecar(dir: &Path, name: &str, reg: &Registration) -> Result<()> {
    let record = serde_json::to_value(reg).expect("registration serialises");
    Ok(btf_core::zarr::write_record(dir, "registration", name, &record)?)
}

/// What the provenance says of the job, before any slot is registered.
fn provenance_base(layout: &CaptureLayout, grid: &Grid, opt: &ProcessOptions) -> serde_json::Value {
    json!({
        "generator": "btf capture process",
        "raw_dir": layout.dir.display().to_string(),
        "material": layout.material,
        "filter": opt.filter.name(),
        "size": opt.size,
        "blend_width": opt.blend_width,
        "rectified_size": opt.rectified_size,
        "light_incidence_correction": opt.correct_light_incidence,
        "grid": {"origin_mm": grid.origin_mm, "texel_mm": grid.texel_mm, "n": grid.n},
        "radiometry": match layout.radiometry {
            Some(r) => json!({"reference_white_dn": r.reference_white_dn, "vignetting_cos_power": r.vignetting_cos_power}),
            None => json!("none in capture.toml: values are DN / full scale"),
        },
    })
}

/// The provenance: [`provenance_base`] with every slot's registration record (in view
/// order), plate tilt and the slots registered from the nominal pose — the same for one
/// process and for the finaliser of a sharded job.
fn provenance_with(
    mut base: serde_json::Value,
    registrations: Vec<serde_json::Value>,
    tilts: Vec<serde_json::Value>,
) -> serde_json::Value {
    let fallback: Vec<u64> = registrations
        .iter()
        .filter(|r| r["fallback_nominal"] == json!(true))
        .filter_map(|r| r["view"].as_u64())
        .collect();
    base["plate_tilt_deg"] = json!(tilts);
    base["fallback_views"] = json!(fallback);
    base["registration"] = json!(registrations);
    base
}
