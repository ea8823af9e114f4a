//! The yarn BTF of DESIGN §4.2 rendered by the GPU fiber renderer (or the yarn strips of
//! [H25], `--method strips`, [`generate_strip_btf`]) instead of the CPU
//! reference (`btf synth material --kind yarn --method fibers`): the same periodic patch
//! (`yarn_ref::patch::KnitPatch`: chart, stitches, period, `z_ref`), the same oblique
//! orthographic camera through the texel centres of `z_ref`, the same directional light of
//! unit perpendicular irradiance, so a rendered frame *is* the normtexture; written through
//! the same resumable `BtfWriter`, so `btf compress`, `btf render` and `btf view` take it
//! unchanged and the representation R4′ of DESIGN §4.2 (a BTF from the fast renderer) can
//! be set against R4 (a BTF from the reference).
//!
//! Differences from the reference, by construction: the periodic wrap is the 3 × 3
//! neighbourhood of copies (`PackOptions::tiles`), the footprint average is MSAA 4
//! instead of jittered rays, the light transport is [W19]'s (self-shadow volume, tube
//! shadow maps, no multiple scattering), and the black backing is the black clear colour.
//! Hair flyaways are drawn when the spec asks for them, as the reference generates them
//! (the fibers from the same slots, the strips by their flyaway overlay).

use crate::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns, Result,
    StripRenderer, StripSettings,
};
use btf_core::store::{BtfMeta, BtfWriter};
use btf_render::Gpu;
use serde_json::json;
use std::path::Path;
use std::time::Instant;
use yarn::bcsdf::FiberBcsdf;
use yarn_precompute::StripBakeSettings;
use yarn_ref::btf::{YarnBtfOptions, YarnBtfSpec};
use yarn_ref::patch::{KnitPatch, PatchOptions};

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct FiberBtfReport {
    /// Images rendered in this run.
    pub images_written: usize,
    /// Images kept from an interrupted run.
    pub images_skipped: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Fiber instances drawn per image (the last one).
    pub instances: u32,
}

/// Renders the yarn BTF of `spec` with the fiber renderer (`settings`) into `out`.
pub fn generate_fiber_btf(
    gpu: &Gpu,
    spec: &YarnBtfSpec,
    settings: FiberSettings,
    out: &Path,
    opts: &YarnBtfOptions,
) -> Result<FiberBtfReport> {
    let t0 = Instant::now();
    let (bcsdf, sampling, patch, packed) = prepare(spec, "fiber")?;
    let settings = FiberSettings { hairs: settings.hairs && spec.hairs, ..settings };
    let renderer = FiberRenderer::new(gpu, &packed, &bcsdf, settings)?;
    let mut meta = BtfMeta::new(sampling.clone(), sampling.clone(), spec.size, spec.size);
    let s = &settings;
    meta.provenance = json!({
        "generator": "yarn-render",
        "version": env!("CARGO_PKG_VERSION"),
        "kind": "yarn",
        "method": "fibers",
        "chart": {"name": spec.chart.name, "source": spec.chart_source, "text": spec.chart.to_text()},
        "yarn": {"preset": spec.params.name},
        "stitches": patch.stitches,
        "size": spec.size,
        "seed": spec.seed,
        "shading": yarn_ref::Shading::Fiber { bcsdf: std::sync::Arc::new(bcsdf.clone()), tint: true }.name(),
        "color": spec.color,
        "period_m": patch.period.size,
        "z_ref_m": patch.z_ref,
        "settings": {
            "lod_px": s.lod_px, "n_sub": s.n_sub, "msaa": s.msaa, "core": s.effects.core,
            "self_shadow": s.effects.self_shadow, "yarn_shadows": s.effects.yarn_shadows,
            "hairs": s.hairs,
        },
        "model": "procedural fibers generated on the GPU [W19] (vertex pulling, fiber BCSDF, \
                  self-shadow volume, tube shadow maps), oblique orthographic camera through texel \
                  centres of z_ref, 3x3 periodic copies, black background, directional light of \
                  unit perpendicular irradiance, MSAA footprint",
    });
    let render = |cam: &FiberCamera, lights: &[FiberLight], size| {
        renderer.render(gpu, cam, lights, size, [0.0; 4]).map(|f| (f.pixels, f.stats.instances))
    };
    let (written, skipped, instances) =
        write_images(spec, &patch, &sampling, meta, out, opts, "fibers", render)?;
    Ok(FiberBtfReport {
        images_written: written,
        images_skipped: skipped,
        seconds: t0.elapsed().as_secs_f64(),
        instances,
    })
}

/// Renders the yarn BTF of `spec` with the yarn strips of [H25] (`settings`, textures baked
/// with `bake` and cached in `cache_dir`) into `out` (`--method strips`): the same patch,
/// camera, light and store as the reference and the fibers.
pub fn generate_strip_btf(
    gpu: &Gpu,
    spec: &YarnBtfSpec,
    settings: StripSettings,
    bake: &StripBakeSettings,
    cache_dir: Option<&Path>,
    out: &Path,
    opts: &YarnBtfOptions,
) -> Result<FiberBtfReport> {
    let t0 = Instant::now();
    let (bcsdf, sampling, patch, packed) = prepare(spec, "strip")?;
    let bake = StripBakeSettings { seed: spec.seed, ..*bake };
    let bakes = crate::strips::bakes_for(
        &patch.yarns,
        std::slice::from_ref(&spec.params),
        &bcsdf,
        &bake,
        cache_dir,
        &|_| {},
    )?;
    let mut renderer = StripRenderer::new(gpu, &packed, &bakes, &bcsdf, settings)?;
    // The reference's patch has hair flyaways when the spec asks: the overlay draws them.
    if spec.hairs {
        let fly = crate::strips::flyaways_for(std::slice::from_ref(&spec.params), spec.seed)?;
        renderer.set_flyaways(gpu, &fly)?;
    }
    let mut meta = BtfMeta::new(sampling.clone(), sampling.clone(), spec.size, spec.size);
    let s = &settings;
    meta.provenance = json!({
        "generator": "yarn-render",
        "version": env!("CARGO_PKG_VERSION"),
        "kind": "yarn",
        "method": "strips",
        "chart": {"name": spec.chart.name, "source": spec.chart_source, "text": spec.chart.to_text()},
        "yarn": {"preset": spec.params.name},
        "stitches": patch.stitches,
        "size": spec.size,
        "seed": spec.seed,
        "shading": yarn_ref::Shading::Fiber { bcsdf: std::sync::Arc::new(bcsdf.clone()), tint: true }.name(),
        "color": spec.color,
        "period_m": patch.period.size,
        "z_ref_m": patch.z_ref,
        "settings": {
            "msaa": s.msaa, "textures": s.textures, "xi": s.xi, "psi": s.psi,
            "shadows": s.shadows, "light_angle_deg": s.light_angle_deg,
            "flyaways": spec.hairs && s.flyaways,
        },
        "bake": {
            "texels": [bake.width, bake.height], "directions": bake.directions, "spp": bake.spp,
            "tangents": bake.tangents, "bounces": bake.bounces,
            "mean_residual": bakes[0].mean_residual(), "seconds": bakes[0].seconds,
        },
        "model": "yarn strips [H25] (camera-facing strips textured with a bake of a straight \
                  yarn of explicit fibers: coverage, fiber tangents, AO, rank-1 fiber shadowing \
                  and multiple-scattering factors; strip shadow maps with PCSS), oblique \
                  orthographic camera through texel centres of z_ref, 3x3 periodic copies, \
                  black background, directional light of unit perpendicular irradiance, MSAA",
    });
    let render = |cam: &FiberCamera, lights: &[FiberLight], size| {
        renderer.render(gpu, cam, lights, size, [0.0; 4]).map(|f| (f.pixels, f.stats.instances))
    };
    let (written, skipped, instances) =
        write_images(spec, &patch, &sampling, meta, out, opts, "strips", render)?;
    Ok(FiberBtfReport {
        images_written: written,
        images_skipped: skipped,
        seconds: t0.elapsed().as_secs_f64(),
        instances,
    })
}

/// Renders the yarn BTF of `spec` with the lumislice renderer of [C03 §5] (`settings`; its
/// table computed with `table` in the spec's colour and cached in `cache_dir`) into `out`
/// (`--method lumislice`): the same patch, camera, light and store as the other methods.
/// The yarn is the table's Kajiya–Kay medium, not the spec's fiber BCSDF.
pub fn generate_lumislice_btf(
    gpu: &Gpu,
    spec: &YarnBtfSpec,
    settings: crate::LumisliceRenderSettings,
    table: &yarn_precompute::LumisliceSettings,
    cache_dir: Option<&Path>,
    out: &Path,
    opts: &YarnBtfOptions,
) -> Result<FiberBtfReport> {
    let t0 = Instant::now();
    let (sampling, patch, packed) = prepare_patch(spec)?;
    let table = yarn_precompute::LumisliceSettings { seed: spec.seed, ..*table };
    let color = spec.color.map(|c| c.clamp(0.0, 1.0));
    let slice =
        yarn_precompute::Lumislice::for_params(&spec.params, color, &table, cache_dir, &|_| {})
            .map_err(|e| crate::Error::Invalid(format!("lumislice table: {e}")))?;
    let renderer =
        crate::LumisliceRenderer::new(gpu, &packed, std::slice::from_ref(&slice), settings)?;
    let mut meta = BtfMeta::new(sampling.clone(), sampling.clone(), spec.size, spec.size);
    let s = &settings;
    meta.provenance = json!({
        "generator": "yarn-render",
        "version": env!("CARGO_PKG_VERSION"),
        "kind": "yarn",
        "method": "lumislice",
        "chart": {"name": spec.chart.name, "source": spec.chart_source, "text": spec.chart.to_text()},
        "yarn": {"preset": spec.params.name},
        "stitches": patch.stitches,
        "size": spec.size,
        "seed": spec.seed,
        "color": spec.color,
        "period_m": patch.period.size,
        "z_ref_m": patch.z_ref,
        "settings": {
            "n_sub": s.n_sub, "step_cells": s.step_cells, "max_steps": s.max_steps,
            "level_bias": s.level_bias, "shadows": s.shadows,
            "shadow_variant": format!("{:?}", s.shadow_variant),
        },
        "table": {
            "res": table.res, "levels": slice.levels.len(), "multiple": table.multiple,
            "extinction": format!("{:?}", table.extinction), "lod": format!("{:?}", table.lod),
            "seconds": slice.seconds,
        },
        "model": "lumislices [C03 §5] (a 32x21-direction scattering table per voxel of the \
                  yarn cross-section, ray-marched along straight pieces of the yarn, shadows of \
                  other yarns by eq. 10 from centre-line maps), oblique orthographic camera \
                  through texel centres of z_ref, 3x3 periodic copies, black background, \
                  directional light of unit perpendicular irradiance",
    });
    let render = |cam: &FiberCamera, lights: &[FiberLight], size| {
        renderer.render(gpu, cam, lights, size, [0.0; 4]).map(|f| (f.pixels, f.stats.instances))
    };
    let (written, skipped, instances) =
        write_images(spec, &patch, &sampling, meta, out, opts, "lumislice", render)?;
    Ok(FiberBtfReport {
        images_written: written,
        images_skipped: skipped,
        seconds: t0.elapsed().as_secs_f64(),
        instances,
    })
}

/// What both GPU methods start from: the spec's fiber BCSDF (`what` names the renderer
/// refusing Lambert), its validated sampling, the periodic patch (hair flyaways not
/// generated: the renderers draw from the curves) and the curves packed with 3 × 3 periodic
/// copies.
fn prepare(
    spec: &YarnBtfSpec,
    what: &str,
) -> Result<(FiberBcsdf, btf_core::sampling::Sampling, KnitPatch, PackedYarns)> {
    let bcsdf = match &spec.shading {
        yarn_ref::Shading::Fiber { bcsdf, .. } => (**bcsdf).clone(),
        yarn_ref::Shading::Lambert { .. } => {
            return Err(crate::Error::Invalid(format!(
                "the {what} renderer shades with a fiber BCSDF, not Lambert"
            )));
        }
    };
    let (sampling, patch, packed) = prepare_patch(spec)?;
    Ok((bcsdf, sampling, patch, packed))
}

/// The validated sampling, the periodic patch (hair flyaways not generated: the renderers
/// draw from the curves) and the curves packed with 3 × 3 periodic copies.
fn prepare_patch(
    spec: &YarnBtfSpec,
) -> Result<(btf_core::sampling::Sampling, KnitPatch, PackedYarns)> {
    if spec.size == 0 || spec.size > 4096 {
        return Err(crate::Error::Invalid(format!("yarn BTF size {} (1..=4096)", spec.size)));
    }
    let sampling = spec.sampling.clone().validated().map_err(btf_render::Error::from)?;
    let mut popts =
        PatchOptions { stitches: spec.stitches, color: spec.color, ..PatchOptions::default() };
    popts.generation.seed = spec.seed;
    popts.generation.hairs = false;
    let patch = KnitPatch::new(&spec.chart, &spec.params, &popts)
        .map_err(|e| crate::Error::Invalid(e.to_string()))?;
    let packed = PackedYarns::new(
        &patch.yarns,
        std::slice::from_ref(&spec.params),
        &PackOptions { seed: spec.seed, frame_samples_per_segment: 16, tiles: [3, 3] },
    )?;
    Ok((sampling, patch, packed))
}

/// The image loop both methods share: every (view, light) of `sampling` rendered by
/// `render` through the oblique camera of the patch and written (resumable) into `out`.
/// Returns (written, kept, instances of the last image).
#[allow(clippy::too_many_arguments)]
fn write_images(
    spec: &YarnBtfSpec,
    patch: &KnitPatch,
    sampling: &btf_core::sampling::Sampling,
    meta: BtfMeta,
    out: &Path,
    opts: &YarnBtfOptions,
    method: &str,
    mut render: impl FnMut(&FiberCamera, &[FiberLight], (u32, u32)) -> Result<(Vec<[f32; 4]>, u32)>,
) -> Result<(usize, usize, u32)> {
    let n = sampling.len();
    let dirs: Vec<[f64; 3]> = (0..n).map(|i| sampling.direction(i).to_vector()).collect();
    let writer = BtfWriter::create(out, meta, opts.dtype, opts.resume)?;
    let bar = if opts.progress {
        indicatif::ProgressBar::new((n * n) as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_message(format!("yarn {method} {} {}²", spec.chart.name, spec.size));
    let (mut written, mut skipped, mut instances) = (0, 0, 0);
    let size = (spec.size as u32, spec.size as u32);
    for view in 0..n {
        let cam =
            FiberCamera::oblique(dirs[view], patch.z_ref, patch.period.origin, patch.period.size);
        for light in 0..n {
            if writer.has_image(view, light) {
                skipped += 1;
                bar.inc(1);
                continue;
            }
            let l = dirs[light];
            let img = if l[2] <= 0.0 {
                vec![0.0f32; spec.size * spec.size * 3]
            } else {
                let lights = [FiberLight::Directional { to_light: l, irradiance: [1.0; 3] }];
                let (pixels, count) = render(&cam, &lights, size)?;
                instances = count;
                pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
            };
            writer.write_image(view, light, &img)?;
            written += 1;
            bar.inc(1);
        }
    }
    writer.finish()?;
    bar.finish_and_clear();
    Ok((written, skipped, instances))
}
