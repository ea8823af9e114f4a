//! The yarn BTF of DESIGN §4.2, written as an ordinary BTF store through
//! `btf_core::store::BtfWriter` (resumable, checksummed), so `btf compress`, `btf render`,
//! `btf view` and `btf inspect` take it unchanged.
//!
//! **Definition** (DESIGN §4.2, exactly):
//! - the sample is a P×Q-stitch periodic patch of a periodic chart ([`KnitPatch`]); the
//!   texel grid `S × S` spans exactly one period (texels are `P_x/S × P_y/S`);
//! - the reference plane is `z_ref` = the top of the yarn tubes (highest centre line + yarn
//!   radius); flyaways may rise above it and rays start above them;
//! - texel `(x, y)` of view `v` is the oblique orthographic ray through the texel centre of
//!   the reference plane ([`Camera::Oblique`]), `spp` jittered sub-texel samples average
//!   its footprint; rows run along `+y`;
//! - below the fabric lies an opaque backing plane of albedo 0;
//! - the light is directional with perpendicular irradiance 1, so the rendered radiance is
//!   the BTF value itself: radiance per unit perpendicular irradiance, with `cos θ_l` and
//!   self-shadowing inside (DESIGN §3);
//! - the ray coordinates wrap modulo the period (infinite tiling).
//!
//! **Thin-cloth link.** Per view, the fraction of camera rays that reach the backing is
//! the patch's direct transmittance `T(μ)`; it is recorded in the provenance with the
//! `τ₁` of the slab law `e^{−τ₁/μ}` fitted to it by least squares in `ln T` (views with
//! `T = 0` left out) and the worst residual. It is computed before any image, from camera
//! rays alone, so a resumed run records the same provenance.
//!
//! **Work.** Parallel over view slots (each slot's lights in turn, each image's rows in
//! parallel), as `datasets::material::generate` does; image `(view, light)` is seeded by
//! `hash(seed, view, light)`, so the store has the same bits for any thread count and any
//! interruption.

use crate::camera::Camera;
use crate::geometry::{FiberScene, SceneOptions};
use crate::integrator::{Background, PathSettings, Scene};
use crate::light::Light;
use crate::material::Shading;
use crate::patch::{KnitPatch, PatchOptions};
use crate::render::{PixelSampler, RenderSettings, render};
use crate::{Error, Result};
use btf_core::sampling::Sampling;
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde_json::json;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::Chart;
use yarn::params::YarnParams;

/// What to generate.
#[derive(Debug, Clone)]
pub struct YarnBtfSpec {
    /// The chart.
    pub chart: Chart,
    /// Where the chart came from (a built-in name or a file), for the provenance.
    pub chart_source: String,
    /// The yarn.
    pub params: YarnParams,
    /// Stitches `(wales, courses)`; `None`: one chart repeat.
    pub stitches: Option<[usize; 2]>,
    /// Texels per side.
    pub size: usize,
    /// View and light sampling.
    pub sampling: Sampling,
    /// Jittered sub-texel samples.
    pub spp: u32,
    /// Seed of the fibers and of every image.
    pub seed: u64,
    /// Lit vertices per path (multiple scattering).
    pub bounces: u32,
    /// Fiber scattering.
    pub shading: Shading,
    /// Yarn colour (linear RGB).
    pub color: [f32; 3],
    /// Generate hair flyaways.
    pub hairs: bool,
    /// Method name (only `"reference"`).
    pub method: String,
}

impl YarnBtfSpec {
    /// Defaults: one chart repeat, 16 spp, 8 bounces, Khungurn R+TT+D tinted by a 0.8 grey
    /// yarn, hairs on, `ubo81`.
    pub fn new(chart: Chart, chart_source: &str, params: YarnParams, size: usize) -> Self {
        let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default())
            .expect("the default Khungurn parameters are valid");
        YarnBtfSpec {
            chart,
            chart_source: chart_source.to_owned(),
            params,
            stitches: None,
            size,
            sampling: Sampling::ubo81(),
            spp: 16,
            seed: 1,
            bounces: 8,
            shading: Shading::Fiber { bcsdf: Arc::new(bcsdf), tint: true },
            color: yarn::curve::DEFAULT_COLOR,
            hairs: true,
            method: "reference".into(),
        }
    }
}

/// How to write.
#[derive(Debug, Clone, Copy)]
pub struct YarnBtfOptions {
    /// Keep the images of an interrupted run.
    pub resume: bool,
    /// Progress bar on stderr.
    pub progress: bool,
    /// `F32` or `F16`.
    pub dtype: DType,
}

impl Default for YarnBtfOptions {
    fn default() -> Self {
        YarnBtfOptions { resume: false, progress: false, dtype: DType::F32 }
    }
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct YarnBtfReport {
    /// Images rendered in this run.
    pub images_written: usize,
    /// Images kept from an interrupted run.
    pub images_skipped: usize,
    /// Rays traced in this run.
    pub rays: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Direct transmittance per view slot.
    pub transmittance: Vec<f64>,
    /// Fitted slab optical thickness.
    pub tau1: Option<f64>,
    /// Fibers in the patch.
    pub fibers: usize,
}

/// A patch ready for rendering.
pub struct PreparedPatch {
    /// The patch.
    pub patch: KnitPatch,
    /// Its scene (wrapped, backed).
    pub scene: FiberScene,
}

/// Builds the patch and its scene.
pub fn prepare(spec: &YarnBtfSpec) -> Result<PreparedPatch> {
    let mut opts =
        PatchOptions { stitches: spec.stitches, color: spec.color, ..PatchOptions::default() };
    opts.generation.seed = spec.seed;
    opts.generation.hairs = spec.hairs;
    let patch = KnitPatch::new(&spec.chart, &spec.params, &opts)?;
    let scene = FiberScene::new(
        &patch.fibers,
        &SceneOptions { period: Some(patch.period), backing_z: Some(patch.backing_z()) },
    )?;
    Ok(PreparedPatch { patch, scene })
}

impl PreparedPatch {
    /// The camera of view `view` (unit, towards the viewer).
    pub fn camera(&self, view: [f64; 3]) -> Result<Camera> {
        Camera::oblique(view, self.patch.z_ref, self.patch.period.origin, self.patch.period.size)
    }

    /// The normtexture for one (view, light): `S·S·3` values, and the rays traced.
    pub fn normtexture(
        &self,
        spec: &YarnBtfSpec,
        view: [f64; 3],
        light: [f64; 3],
        seed: u64,
    ) -> Result<(Vec<f32>, u64)> {
        if light[2] <= 0.0 {
            // A light at or below the horizon contributes nothing (DESIGN §3).
            return Ok((vec![0.0; spec.size * spec.size * 3], 0));
        }
        let lights = [Light::directional(light, [1.0; 3])];
        let sc = Scene { fibers: &self.scene, lights: &lights, shading: &spec.shading };
        let mut s = RenderSettings::new(spec.size, spec.size, spec.spp);
        s.seed = seed;
        s.sampler = PixelSampler::Stratified;
        s.path =
            PathSettings { max_bounces: spec.bounces, rr_start: 3, background: Background::Black };
        let (img, stats) = render(&sc, &self.camera(view)?, &s)?;
        Ok((img.rgb, stats.rays))
    }

    /// Fraction of the camera rays of view `view` that reach the backing.
    pub fn transmittance(&self, spec: &YarnBtfSpec, view: [f64; 3]) -> Result<f64> {
        let sc = Scene { fibers: &self.scene, lights: &[], shading: &spec.shading };
        let mut s = RenderSettings::new(spec.size, spec.size, spec.spp);
        s.seed = spec.seed;
        s.path = PathSettings { max_bounces: 1, rr_start: 1, background: Background::Black };
        let (img, _) = render(&sc, &self.camera(view)?, &s)?;
        Ok(img.mean_backing())
    }
}

/// `τ₁` minimising `Σ (ln T_j + τ₁/μ_j)²` over views with `T_j > 0`, and the largest
/// `|T_j − e^{−τ₁/μ_j}|` over all views.
pub fn fit_tau1(mu: &[f64], t: &[f64]) -> Option<(f64, f64)> {
    let (mut num, mut den) = (0.0, 0.0);
    for (m, tr) in mu.iter().zip(t) {
        if *tr > 0.0 && *m > 0.0 {
            num -= tr.ln() / m;
            den += 1.0 / (m * m);
        }
    }
    if den == 0.0 {
        return None;
    }
    let tau = num / den;
    let resid = mu.iter().zip(t).map(|(m, tr)| (tr - (-tau / m).exp()).abs()).fold(0.0, f64::max);
    Some((tau, resid))
}

/// Renders the yarn BTF of `spec` into a BTF store at `out`.
pub fn generate_yarn_btf(
    spec: &YarnBtfSpec,
    out: &Path,
    opts: &YarnBtfOptions,
) -> Result<YarnBtfReport> {
    let t0 = Instant::now();
    if spec.method != "reference" {
        return Err(Error::Unsupported(format!(
            "yarn BTF method '{}' (this build has 'reference'; fibers, strips and lumislice come with their renderers)",
            spec.method
        )));
    }
    if spec.size == 0 || spec.size > 4096 || spec.spp == 0 || spec.bounces == 0 {
        return Err(Error::Invalid(format!(
            "yarn BTF: size {} (1..=4096), spp {} and bounces {} (≥ 1)",
            spec.size, spec.spp, spec.bounces
        )));
    }
    let sampling = spec.sampling.clone().validated()?;
    let prep = prepare(spec)?;
    let n = sampling.len();
    let views: Vec<[f64; 3]> = (0..n).map(|i| sampling.direction(i).to_vector()).collect();
    let transmittance =
        views.par_iter().map(|v| prep.transmittance(spec, *v)).collect::<Result<Vec<f64>>>()?;
    let mu: Vec<f64> = views.iter().map(|v| v[2]).collect();
    let fit = fit_tau1(&mu, &transmittance);
    let p = &prep.patch;
    let mut meta = BtfMeta::new(sampling.clone(), sampling.clone(), spec.size, spec.size);
    meta.provenance = json!({
        "generator": "yarn-ref",
        "version": env!("CARGO_PKG_VERSION"),
        "kind": "yarn",
        "method": spec.method,
        "chart": {"name": spec.chart.name, "source": spec.chart_source, "text": spec.chart.to_text()},
        "yarn": {"preset": spec.params.name, "params": spec.params.to_toml()?},
        "stitches": p.stitches,
        "size": spec.size,
        "spp": spec.spp,
        "seed": spec.seed,
        "bounces": spec.bounces,
        "shading": spec.shading.name(),
        "color": spec.color,
        "hairs": spec.hairs,
        "period_m": p.period.size,
        "z_ref_m": p.z_ref,
        "backing_z_m": p.backing_z(),
        "fibers": p.fibers.fiber_count(),
        "fiber_points": p.fibers.points.len(),
        "transmittance": {
            "per_view": transmittance,
            "definition": "fraction of camera rays reaching the black backing (DESIGN §4.2 thin-cloth link)",
            "tau1_fit": fit.map(|f| f.0),
            "tau1_max_residual": fit.map(|f| f.1),
        },
        "model": "explicit fibers (capsule chains, BVH), path traced: NEE + BCSDF sampling with MIS, \
                  Russian roulette after 3 vertices; oblique orthographic camera through texel centres \
                  of z_ref, periodic wrap, black backing, directional light of unit perpendicular irradiance",
    });
    let writer = BtfWriter::create(out, meta, opts.dtype, opts.resume)?;
    let bar = if opts.progress { ProgressBar::new((n * n) as u64) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} images, {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("yarn {} {}²", spec.chart.name, spec.size));
    let counts = (0..n)
        .into_par_iter()
        .map(|view| -> Result<(usize, usize, u64)> {
            let missing: Vec<usize> = (0..n).filter(|&l| !writer.has_image(view, l)).collect();
            bar.inc((n - missing.len()) as u64);
            let mut rays = 0;
            for &light in &missing {
                let seed = yarn::hash::hash_keys(&[spec.seed, view as u64, light as u64]);
                let (img, r) = prep.normtexture(spec, views[view], views[light], seed)?;
                rays += r;
                writer.write_image(view, light, &img)?;
                bar.inc(1);
            }
            Ok((missing.len(), n - missing.len(), rays))
        })
        .collect::<Result<Vec<_>>>()?;
    writer.finish()?;
    bar.finish_and_clear();
    let (written, skipped, rays) =
        counts.iter().fold((0, 0, 0), |a, c| (a.0 + c.0, a.1 + c.1, a.2 + c.2));
    Ok(YarnBtfReport {
        images_written: written,
        images_skipped: skipped,
        rays,
        seconds: t0.elapsed().as_secs_f64(),
        transmittance,
        tau1: fit.map(|f| f.0),
        fibers: p.fibers.fiber_count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tau1_fit_recovers_a_slab() {
        let mu = [1.0, 0.8, 0.5, 0.3];
        let t: Vec<f64> = mu.iter().map(|m| (-0.7f64 / m).exp()).collect();
        let (tau, resid) = fit_tau1(&mu, &t).unwrap();
        assert!((tau - 0.7).abs() < 1e-12 && resid < 1e-12);
        assert!(fit_tau1(&mu, &[0.0; 4]).is_none());
    }

    #[test]
    fn a_small_yarn_btf_is_a_deterministic_store() {
        let chart = Chart::builtin("stockinette").unwrap();
        let params = YarnParams::preset("fine-2ply").unwrap();
        let mut spec = YarnBtfSpec::new(chart, "stockinette", params, 8);
        spec.sampling = btf_core::sampling::Sampling::new(
            "custom",
            vec![
                btf_core::Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 },
                btf_core::Ring { theta_deg: 45.0, count: 2, phi_offset_deg: 0.0 },
            ],
        )
        .unwrap();
        spec.spp = 2;
        spec.bounces = 2;
        spec.hairs = false;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("y.btf");
        let r = generate_yarn_btf(&spec, &out, &YarnBtfOptions::default()).unwrap();
        assert_eq!((r.images_written, r.images_skipped), (9, 0));
        let store = btf_core::store::BtfStore::open(&out).unwrap();
        assert_eq!(store.meta().width, 8);
        assert_eq!(store.meta().provenance["kind"], "yarn");
        assert_eq!(store.meta().provenance["spp"], 2);
        // The same image rendered directly has the same bits (deterministic seeds).
        let prep = prepare(&spec).unwrap();
        let seed = yarn::hash::hash_keys(&[spec.seed, 1, 2]);
        let v = spec.sampling.direction(1).to_vector();
        let l = spec.sampling.direction(2).to_vector();
        let (img, _) = prep.normtexture(&spec, v, l, seed).unwrap();
        assert_eq!(store.read_image(1, 2).unwrap(), img);
        // Finite, non-negative, not black.
        assert!(img.iter().all(|x| x.is_finite() && *x >= 0.0) && img.iter().any(|x| *x > 0.0));
        // Transmittance: the top view sees the backing through the gaps; the 45° views less.
        assert!(r.transmittance[0] > 0.0 && r.transmittance[0] < 0.5, "{:?}", r.transmittance);
    }
}
