//! ꟻLIP, the perceptual difference of two images as seen when flipping between them
//! (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images" `[A20]`),
//! and HDR-ꟻLIP for linear HDR images (Andersson et al. 2021, "Visualizing Errors in
//! Rendered High Dynamic Range Images" `[A21]`), following NVIDIA's reference
//! implementation (github.com/NVlabs/flip, `FLIP.h`, v1.7 — the `flip-evaluator` package)
//! in its constants, kernels, order of operations and `f32` arithmetic.
//!
//! Per pixel, a value in `[0, 1]` (0: no visible difference):
//!
//! 1. **Colour** `[A20, colour pipeline]`: linear sRGB → YCxCz; each channel filtered by its
//!    contrast sensitivity function at the viewing distance (`ppd` pixels per degree,
//!    [`filter`]); back to linear RGB, clamped to `[0, 1]`; CIE L*a*b* with the Hunt
//!    adjustment `(a*, b*)·L*/100`; the HyAB distance, raised to `q_c = 0.7` and
//!    redistributed so that `p_c = 0.4` of the largest distance (pure green against pure
//!    blue) maps to `p_t = 0.95`: `ΔE_c ∈ [0, 1]`.
//! 2. **Features** `[A20, feature pipeline]`: on the achromatic channel normalised to
//!    `[0, 1]`, edge strength `‖∇(G ⊗ Y)‖` and point strength from the second derivatives,
//!    Gaussian derivative kernels of `σ = ½·0.082°`; `ΔE_f = (max(|Δedge|, |Δpoint|)/√2)^0.5`.
//! 3. **Combination** `[A20, final difference]`: `ΔE = ΔE_c^(1 − ΔE_f)` — a feature
//!    difference raises a small colour difference towards 1.
//! 4. **HDR** `[A21]` ([`hdr`]): LDR-ꟻLIP of the ACES-tone-mapped pair at `N` exposures
//!    chosen from the reference's luminances, maximum per pixel.
//!
//! Conventions of this crate: inputs are **linear** RGB (`[y][x][rgb]`), as everywhere in
//! the toolkit; [`flip_ldr`] clamps them to `[0, 1]` (as the reference does), and
//! [`flip_ldr_srgb`] takes sRGB-encoded values (8-bit PNG codes / 255) and decodes them
//! first — what `flip_evaluator.evaluate(.., "LDR")` does with its default
//! `inputsRGB=True`. Borders are clamped (edge pixels repeat), as in the reference. The
//! default viewing condition is the reference's: a 0.7 m wide 3840-pixel display seen
//! from 0.7 m, [`DEFAULT_PPD`] ≈ 67.02 pixels per degree.
//!
//! Non-finite values, empty images, mismatched sizes and (for HDR) negative values are
//! refused with the pixel named; an HDR reference whose median luminance is 0 has no
//! exposure range and needs explicit exposures.

mod color;
pub mod filter;
pub mod hdr;
mod ldr;

use crate::{Error, Result};
pub use hdr::ExposureRange;
use std::path::Path;

/// The reference implementation's default pixels per degree: `0.7 m · (3840 px / 0.7 m)
/// · π/180` ≈ 67.0206 (the papers round it to 67).
pub const DEFAULT_PPD: f64 = 0.7 * (3840.0 / 0.7) * (std::f64::consts::PI / 180.0);

/// The largest pixels per degree accepted (kernels grow linearly with it; 10 000 ppd is a
/// 1 350-pixel CSF radius).
pub const MAX_PPD: f64 = 10_000.0;

/// A per-pixel ꟻLIP map (`[y][x]`, values in `[0, 1]`).
#[derive(Debug, Clone, PartialEq)]
pub struct FlipMap {
    /// ꟻLIP per pixel, row-major, top row first.
    pub values: Vec<f32>,
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// The exposures of an HDR-ꟻLIP map; `None` for LDR.
    pub exposures: Option<ExposureRange>,
}

impl FlipMap {
    /// Mean ꟻLIP over all pixels (the single number the authors recommend).
    pub fn mean(&self) -> f64 {
        self.values.iter().map(|&v| v as f64).sum::<f64>() / self.values.len() as f64
    }

    /// Mean ꟻLIP over the pixels where `mask` is true (e.g. the interior or the silhouette
    /// band of issue #19); refused when the mask has the wrong size or selects nothing.
    pub fn mean_over(&self, mask: &[bool]) -> Result<f64> {
        if mask.len() != self.values.len() {
            return Err(Error::Invalid(format!(
                "ꟻLIP mask of {} pixels for a {}×{} map",
                mask.len(),
                self.width,
                self.height
            )));
        }
        let (sum, n) = self
            .values
            .iter()
            .zip(mask)
            .filter(|(_, m)| **m)
            .fold((0f64, 0usize), |(s, n), (&v, _)| (s + v as f64, n + 1));
        if n == 0 {
            return Err(Error::Invalid("ꟻLIP mask selects no pixel: no mean".into()));
        }
        Ok(sum / n as f64)
    }

    /// Largest ꟻLIP of the map.
    pub fn max(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }

    /// The map through the toolkit's error ramp (0 green, ½ yellow, ≥ `full_scale` red);
    /// pixels outside `mask` black.
    pub fn heatmap_image(&self, full_scale: f32, mask: Option<&[bool]>) -> image::RgbImage {
        crate::heatmap::value_heatmap_image(self.width, self.height, &self.values, full_scale, mask)
    }

    /// Writes [`FlipMap::heatmap_image`] with full scale 1 as a PNG.
    pub fn write_heatmap(&self, path: &Path, mask: Option<&[bool]>) -> Result<()> {
        crate::write::write_png(path, &self.heatmap_image(1.0, mask))
    }
}

/// LDR-ꟻLIP of two linear RGB images (`[y][x][rgb]`, `width × height`), values clamped to
/// `[0, 1]`, at `ppd` pixels per degree.
pub fn flip_ldr(
    reference: &[f32],
    test: &[f32],
    width: usize,
    height: usize,
    ppd: f64,
) -> Result<FlipMap> {
    let ppd = check(reference, test, width, height, ppd, false)?;
    let values = ldr::flip_linear(reference, test, width, height, ppd);
    Ok(FlipMap { values, width, height, exposures: None })
}

/// LDR-ꟻLIP of two sRGB-encoded images (values in `[0, 1]`, e.g. 8-bit codes / 255):
/// decoded with the sRGB transfer function, then [`flip_ldr`].
pub fn flip_ldr_srgb(
    reference: &[f32],
    test: &[f32],
    width: usize,
    height: usize,
    ppd: f64,
) -> Result<FlipMap> {
    check(reference, test, width, height, ppd, false)?;
    let decode = |v: &[f32]| v.iter().map(|&c| crate::color::srgb_decode(c)).collect::<Vec<f32>>();
    flip_ldr(&decode(reference), &decode(test), width, height, ppd)
}

/// HDR-ꟻLIP of two linear HDR RGB images (finite, non-negative) at `ppd` pixels per
/// degree. `exposures`: `(start, stop)` in stops, or `None` for the range of `[A21]` taken
/// from the reference; the number of exposures is `max(2, ⌈stop − start⌉)`.
pub fn flip_hdr(
    reference: &[f32],
    test: &[f32],
    width: usize,
    height: usize,
    ppd: f64,
    exposures: Option<(f64, f64)>,
) -> Result<FlipMap> {
    let ppd = check(reference, test, width, height, ppd, true)?;
    let (start, stop) = match exposures {
        Some((start, stop)) => {
            if !(start.is_finite() && stop.is_finite() && start <= stop) {
                return Err(Error::Invalid(format!(
                    "HDR-ꟻLIP exposures must be finite with start ≤ stop, got {start} … {stop}"
                )));
            }
            (start as f32, stop as f32)
        }
        None => ExposureRange::from_reference(reference).ok_or_else(|| {
            Error::Invalid(
                "HDR-ꟻLIP: the reference's median (or largest) luminance is 0, so the \
                 exposure range of [A21] is undefined; give the exposures explicitly"
                    .into(),
            )
        })?,
    };
    let range = ExposureRange::with_default_count(start, stop);
    let values = hdr::flip_hdr_linear(reference, test, width, height, ppd, &range);
    Ok(FlipMap { values, width, height, exposures: Some(range) })
}

/// The exposure range of `[A21]` taken from the reference's pixels where `mask` is true
/// (linear RGB, `mask.len()` pixels): for a subject on a black background, whose median
/// over the whole frame is 0 and whose range is then undefined. Refused when the mask has
/// the wrong size or its pixels have no positive median luminance.
pub fn hdr_exposures_over(reference: &[f32], mask: &[bool]) -> Result<(f64, f64)> {
    if mask.len() * 3 != reference.len() {
        return Err(Error::Invalid(format!(
            "HDR-ꟻLIP exposures: a mask of {} pixels for an image of {} values",
            mask.len(),
            reference.len()
        )));
    }
    let picked: Vec<f32> = reference
        .chunks_exact(3)
        .zip(mask)
        .filter(|(_, m)| **m)
        .flat_map(|(p, _)| [p[0], p[1], p[2]])
        .collect();
    if picked.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Error::Invalid(
            "HDR-ꟻLIP exposures: the reference has a negative or non-finite value".into(),
        ));
    }
    let (start, stop) = ExposureRange::from_reference(&picked).ok_or_else(|| {
        Error::Invalid(
            "HDR-ꟻLIP exposures: the masked reference pixels have no positive median luminance"
                .into(),
        )
    })?;
    Ok((start as f64, stop as f64))
}

/// Refuses empty or mismatched images, non-finite values (and negative ones for HDR) and
/// a ppd that is not a positive number up to [`MAX_PPD`]; returns the ppd as `f32`.
fn check(reference: &[f32], test: &[f32], w: usize, h: usize, ppd: f64, hdr: bool) -> Result<f32> {
    if w == 0 || h == 0 {
        return Err(Error::Invalid(format!("ꟻLIP of an empty image ({w}×{h})")));
    }
    let n = w.checked_mul(h).and_then(|n| n.checked_mul(3));
    for (name, img) in [("reference", reference), ("test", test)] {
        if n != Some(img.len()) {
            return Err(Error::Invalid(format!(
                "ꟻLIP: the {name} image has {} values, a {w}×{h} RGB image has {}",
                img.len(),
                w.saturating_mul(h).saturating_mul(3)
            )));
        }
        let bad = |v: &f32| !v.is_finite() || (hdr && *v < 0.0);
        if let Some(i) = img.iter().position(bad) {
            return Err(Error::Invalid(format!(
                "ꟻLIP: the {name} image has {} {} at pixel x={}, y={} ({}){}",
                if img[i].is_finite() { "the negative value" } else { "the non-finite value" },
                img[i],
                i / 3 % w,
                i / 3 / w,
                ["R", "G", "B"][i % 3],
                if hdr { "; HDR-ꟻLIP takes finite, non-negative linear RGB" } else { "" }
            )));
        }
    }
    if !(ppd.is_finite() && ppd > 0.0 && ppd <= MAX_PPD) {
        return Err(Error::Invalid(format!(
            "ꟻLIP: pixels per degree must be in (0, {MAX_PPD}], got {ppd}"
        )));
    }
    Ok(ppd as f32)
}

#[cfg(test)]
mod tests;
