//! What accuracy costs in time (issue #5): renders one scene for every component count ×
//! evaluation mode (per pixel / the paper's per-vertex blending, §4.2) × blending (four
//! nearest views and lights, eq. 3 and 5, or the nearest one) and measures, per setting,
//! the error against the per-pixel, all-components, four/four reference frame, the texture
//! reads per pixel, and the BTF pass's time against two baselines timed back to back on the
//! same mesh, resolution and textures: plain texture mapping (`plain_texture.rs`) and the
//! read bound (`read_bound.rs`).
//!
//! Checks of the targets come with the rows: the BTF pass within 1.5× of its read
//! bound, cost linear in `c` (least-squares fit `ms = a + b·c` per mode, with R²), and
//! per-pixel evaluation no more reads than per-vertex blending. Shadows are turned off and
//! the background set to black for the sweep (the error is over the shaded pixels only).

use crate::frame::Frame;
use crate::passes::baselines::{Baseline, ReadForm};
use crate::renderer::{RenderOptions, Renderer};
use crate::scene::{Evaluation, Scene, Shadows};
use crate::{Error, Gpu, Result};
use btf_core::InterpMode;
use serde::Serialize;

/// Read-bound target of the issue: BTF pass time ≤ this × the read bound's.
pub const READ_BOUND_TARGET: f64 = 1.5;

/// What to sweep.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// Component counts (those above the store's are skipped).
    pub components: Vec<usize>,
    /// Timed repeats per setting (the median is reported), after one warm-up frame.
    pub repeats: usize,
}

/// One setting of the sweep.
#[derive(Debug, Clone, Serialize)]
pub struct CostRow {
    /// Components used.
    pub components: usize,
    /// `per-pixel` or `per-vertex`.
    pub evaluation: String,
    /// `four` or `nearest` (views and lights alike).
    pub blending: String,
    /// Relative RMSE against the reference frame.
    pub rel_rmse: f64,
    /// Texture reads per shaded pixel of the BTF pass.
    pub reads_per_pixel: f64,
    /// Median BTF pass time, ms.
    pub btf_ms: f64,
    /// Median whole-frame time (CPU work, read-back included), ms.
    pub frame_ms: f64,
    /// Median plain-texture pass time, ms.
    pub plain_ms: f64,
    /// Median read-bound pass time, ms.
    pub read_bound_ms: f64,
    /// `btf_ms / plain_ms`.
    pub ratio_plain: f64,
    /// Median over the timed frames of the BTF pass time over the read bound's time in the
    /// same iteration of the interleaved loop (pairing cancels the machine's slow phases),
    /// for the faster of the bound's two forms.
    pub ratio_read_bound: f64,
}

/// Least-squares line `ms = intercept + slope · c` of one mode.
#[derive(Debug, Clone, Serialize)]
pub struct LinearFit {
    /// `evaluation/blending`.
    pub mode: String,
    /// ms at `c = 0`.
    pub intercept: f64,
    /// ms per component.
    pub slope: f64,
    /// Coefficient of determination.
    pub r2: f64,
}

/// The sweep's rows and checks.
#[derive(Debug, Clone, Serialize)]
pub struct SweepResult {
    /// Components of the reference.
    pub reference_components: usize,
    /// Rendered size.
    pub width: u32,
    /// Rendered size.
    pub height: u32,
    /// One row per setting.
    pub rows: Vec<CostRow>,
    /// Time against `c` per mode.
    pub fits: Vec<LinearFit>,
    /// Largest `ratio_read_bound`.
    pub worst_read_bound_ratio: f64,
    /// Every (c, blending) has per-pixel reads ≤ per-vertex reads.
    pub per_pixel_reads_le_per_vertex: bool,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if !n.is_multiple_of(2) { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Fits `y = a + b·x` and returns `(a, b, R²)`.
pub fn linear_fit(points: &[(f64, f64)]) -> (f64, f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = points.iter().map(|p| (p.1 - my).powi(2)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let a = my - b * mx;
    let ss_res: f64 = points.iter().map(|p| (p.1 - a - b * p.0).powi(2)).sum();
    let r2 = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    (a, b, r2)
}

fn variant(base: &Scene, c: Option<usize>, eval: Evaluation, mode: InterpMode) -> Scene {
    let mut s = base.clone();
    s.effects.components = c;
    s.effects.evaluation = eval;
    s.effects.view_blend = mode;
    s.effects.light_interp = mode;
    s
}

fn mode_name(m: InterpMode) -> &'static str {
    match m {
        InterpMode::Four => "four",
        _ => "nearest",
    }
}

fn eval_name(e: Evaluation) -> &'static str {
    match e {
        Evaluation::PerPixel => "per-pixel",
        Evaluation::PerVertex => "per-vertex",
    }
}

/// Times of one setting: medians over the timed frames, and the paired read-bound ratio.
struct Timing {
    btf_ms: f64,
    frame_ms: f64,
    plain_ms: f64,
    read_bound_ms: f64,
    ratio_read_bound: f64,
}

/// Times the BTF pass and the baselines of `scene` (plain texture, the read bound in both
/// forms), interleaved frame by frame.
fn time_setting(gpu: &Gpu, scene: &Scene, reads: f64, repeats: usize) -> Result<Timing> {
    let with = |baseline| RenderOptions { baseline, ..Default::default() };
    let mut btf = Renderer::new(gpu, scene, with(None))?;
    let mut plain = Renderer::new(gpu, scene, with(Some(Baseline::Plain)))?;
    let bound = |form| {
        let read_bound = Baseline::ReadBound { reads_per_pixel: reads, form };
        Renderer::new(gpu, scene, with(Some(read_bound)))
    };
    let mut bounds = [bound(ReadForm::Loop)?, bound(ReadForm::Groups)?];
    let mut t: [Vec<f64>; 5] = Default::default();
    for r in 0..=repeats {
        let f = btf.render(gpu)?;
        let p = plain.render(gpu)?;
        let b: Vec<f64> = bounds
            .iter_mut()
            .map(|b| Ok(b.render(gpu)?.stats.ms_of("read bound")))
            .collect::<Result<_>>()?;
        if r > 0 {
            t[0].push(f.stats.ms_of("btf ("));
            t[1].push(f.stats.frame_ms);
            t[2].push(p.stats.ms_of("plain texture"));
            t[3].push(b[0]);
            t[4].push(b[1]);
        }
    }
    let [btf_ms, frame_ms, plain_ms, loop_ms, groups_ms] = t.clone().map(median);
    // the bound is the faster of the two ways to write the same reads
    let (k, read_bound_ms) = if groups_ms < loop_ms { (4, groups_ms) } else { (3, loop_ms) };
    let ratio_read_bound = median(t[0].iter().zip(&t[k]).map(|(f, b)| f / b).collect());
    Ok(Timing { btf_ms, frame_ms, plain_ms, read_bound_ms, ratio_read_bound })
}

/// Runs the sweep; `progress(done, total)` is called after every setting.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    config: &SweepConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<SweepResult> {
    let mut base = scene.clone();
    base.effects.shadows = Shadows::None;
    base.output.background = [0.0; 3];
    let mut reference = Renderer::new(
        gpu,
        &variant(&base, None, Evaluation::PerPixel, InterpMode::Four),
        RenderOptions::default(),
    )?;
    let stored = reference.components();
    let ref_frame = reference.render(gpu)?;
    drop(reference);
    let mut cs: Vec<usize> = config.components.iter().copied().filter(|&c| c <= stored).collect();
    cs.dedup();
    if cs.is_empty() {
        return Err(Error::Invalid(format!(
            "cost sweep: none of the component counts {:?} fits the store ({stored} components)",
            config.components
        )));
    }
    let settings: Vec<(usize, Evaluation, InterpMode)> = cs
        .iter()
        .flat_map(|&c| {
            [Evaluation::PerPixel, Evaluation::PerVertex].into_iter().flat_map(move |e| {
                [InterpMode::Four, InterpMode::Nearest].into_iter().map(move |m| (c, e, m))
            })
        })
        .collect();
    let mut rows = Vec::new();
    for (k, &(c, eval, mode)) in settings.iter().enumerate() {
        let s = variant(&base, Some(c), eval, mode);
        let counted =
            Renderer::new(gpu, &s, RenderOptions { count_reads: true, ..Default::default() })?
                .render(gpu)?;
        let reads = counted.stats.reads_per_pixel.unwrap_or(0.0);
        let timing = time_setting(gpu, &s, reads, config.repeats.max(1))?;
        let Timing { btf_ms, frame_ms, plain_ms, read_bound_ms, ratio_read_bound } = timing;
        rows.push(CostRow {
            components: c,
            evaluation: eval_name(eval).into(),
            blending: mode_name(mode).into(),
            rel_rmse: frame_error(&ref_frame, &counted),
            reads_per_pixel: reads,
            btf_ms,
            frame_ms,
            plain_ms,
            read_bound_ms,
            ratio_plain: btf_ms / plain_ms,
            ratio_read_bound,
        });
        progress(k + 1, settings.len());
    }
    Ok(summarise(rows, stored, scene.output.width, scene.output.height))
}

/// Relative RMSE of `actual` against `reference` (black background contributes nothing).
pub fn frame_error(reference: &Frame, actual: &Frame) -> f64 {
    btf_core::metrics::rel_rmse(&reference.rgb, &actual.rgb)
}

fn summarise(rows: Vec<CostRow>, stored: usize, width: u32, height: u32) -> SweepResult {
    let mut fits = Vec::new();
    for e in ["per-pixel", "per-vertex"] {
        for m in ["four", "nearest"] {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.evaluation == e && r.blending == m)
                .map(|r| (r.components as f64, r.btf_ms))
                .collect();
            if pts.len() >= 2 {
                let (intercept, slope, r2) = linear_fit(&pts);
                fits.push(LinearFit { mode: format!("{e}/{m}"), intercept, slope, r2 });
            }
        }
    }
    let worst = rows.iter().map(|r| r.ratio_read_bound).fold(0.0, f64::max);
    let le = rows.iter().filter(|r| r.evaluation == "per-pixel").all(|p| {
        rows.iter()
            .filter(|v| {
                v.evaluation == "per-vertex"
                    && v.components == p.components
                    && v.blending == p.blending
            })
            .all(|v| p.reads_per_pixel <= v.reads_per_pixel + 1e-9)
    });
    SweepResult {
        reference_components: stored,
        width,
        height,
        rows,
        fits,
        worst_read_bound_ratio: worst,
        per_pixel_reads_le_per_vertex: le,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_line_and_median_is_robust() {
        let (a, b, r2) = linear_fit(&[(4.0, 3.0), (8.0, 5.0), (16.0, 9.0), (32.0, 17.0)]);
        assert!((a - 1.0).abs() < 1e-12 && (b - 0.5).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
        let (_, _, r2) = linear_fit(&[(4.0, 3.0), (8.0, 9.0), (16.0, 4.0), (32.0, 17.0)]);
        assert!(r2 < 0.9);
        assert_eq!(median(vec![5.0, 1.0, 100.0]), 5.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 100.0]), 3.0);
    }
}
