//! HDR-ꟻLIP `[A21]`: an HDR pair is seen as the LDR pairs a viewer would see over a range
//! of exposures, and the error of a pixel is the largest LDR-ꟻLIP over those exposures.
//!
//! - **Tone mapping** `[A21, tone mapping]`: the reference implementation's default, the
//!   ACES filmic fit `t(x) = (a·x² + b·x + c)/(d·x² + e·x + f)` per channel with
//!   `(a, b, c, d, e, f) = (0.6²·2.51, 0.6·0.03, 0, 0.6²·2.43, 0.6·0.59, 0.14)` (Narkowicz's
//!   fit with its 0.6 pre-exposure cancelled), then clamped to `[0, 1]`.
//! - **Exposure range** `[A21, exposure range]`: exposure `c` scales linear values by
//!   `2^c`. The start exposure maps the reference's largest luminance `Y_max`, and the stop
//!   exposure its median luminance `Y_median` (the element at index `⌊n/2⌋` in sorted
//!   order), to the value `x_max` that the tone mapper takes to 0.85:
//!   `c_start = log₂(x_max/Y_max)`, `c_stop = log₂(x_max/Y_median)`, `x_max` the larger
//!   root of `(a − 0.85d)x² + (b − 0.85e)x + (c − 0.85f) = 0`.
//! - **Exposures** `N = max(2, ⌈c_stop − c_start⌉)`, evenly spaced from `c_start` to
//!   `c_stop` inclusive; HDR-ꟻLIP is the per-pixel maximum of the `N` LDR-ꟻLIP maps.

use super::color::luminance;
use super::ldr::flip_linear;

/// The ACES fit's coefficients `(a, b, c, d, e, f)`, evaluated in `f32` as the reference
/// does.
const ACES: [f32; 6] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// The tone-mapped value that the exposure range aims the reference's luminances at.
const TARGET: f32 = 0.85;

/// The exposures HDR-ꟻLIP ran (returned so that reports can state them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExposureRange {
    /// First exposure, stops (`2^start` scales the linear values).
    pub start: f32,
    /// Last exposure, stops.
    pub stop: f32,
    /// Number of exposures, evenly spaced, both ends included (≥ 2).
    pub count: usize,
}

impl ExposureRange {
    /// The range of `[A21]` for a reference image (linear RGB, validated finite and
    /// non-negative): `None` when its median or largest luminance is 0 — the range is then
    /// undefined (`log₂(x/0)`) and must be given explicitly.
    pub(crate) fn from_reference(reference: &[f32]) -> Option<(f32, f32)> {
        let [a, b, c, d, e, f] = ACES;
        let (qa, qb, qc) = (a - TARGET * d, b - TARGET * e, c - TARGET * f);
        let x_max = larger_root(qa, qb, qc);
        let mut lum: Vec<f32> =
            reference.chunks_exact(3).map(|p| luminance([p[0], p[1], p[2]])).collect();
        let y_max = lum.iter().copied().fold(0f32, f32::max);
        let mid = lum.len() / 2;
        let y_median = *lum.select_nth_unstable_by(mid, f32::total_cmp).1;
        (y_median > 0.0 && y_max > 0.0).then(|| ((x_max / y_max).log2(), (x_max / y_median).log2()))
    }

    /// `N = max(2, ⌈stop − start⌉)` exposures over `[start, stop]`.
    pub(crate) fn with_default_count(start: f32, stop: f32) -> Self {
        ExposureRange { start, stop, count: ((stop - start).ceil().max(2.0)) as usize }
    }

    /// The `i`-th exposure in stops.
    pub fn exposure(&self, i: usize) -> f32 {
        let step = (self.stop - self.start) / (self.count - 1) as f32;
        self.start + i as f32 * step
    }
}

/// The larger root of `a·x² + b·x + c = 0` (`a ≠ 0`, real roots), or `−c/b` when `a = 0`.
fn larger_root(a: f32, b: f32, c: f32) -> f32 {
    if a == 0.0 {
        return -c / b;
    }
    let half = -0.5 * (b / a);
    half + (half * half - c / a).sqrt()
}

/// The ACES fit applied to one linear value after exposure, clamped to `[0, 1]`.
pub(crate) fn tone_map(x: f32) -> f32 {
    let [a, b, c, d, e, f] = ACES;
    (((x * x) * a + x * b + c) / (x * x * d + x * e + f)).clamp(0.0, 1.0)
}

/// HDR-ꟻLIP of two validated linear HDR images over `range`.
pub(crate) fn flip_hdr_linear(
    reference: &[f32],
    test: &[f32],
    w: usize,
    h: usize,
    ppd: f32,
    range: &ExposureRange,
) -> Vec<f32> {
    let mut worst = vec![0f32; w * h];
    for i in 0..range.count {
        let scale = 2f32.powf(range.exposure(i));
        let ldr = |img: &[f32]| img.iter().map(|&v| tone_map(v * scale)).collect::<Vec<f32>>();
        let err = flip_linear(&ldr(reference), &ldr(test), w, h, ppd);
        for (m, e) in worst.iter_mut().zip(err) {
            *m = m.max(e);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aces_fit_is_monotone_and_the_exposure_rule_aims_at_085() {
        assert_eq!(tone_map(0.0), 0.0);
        let mut prev = 0.0;
        for i in 1..2000 {
            let t = tone_map(i as f32 * 0.01);
            assert!(t >= prev && t <= 1.0);
            prev = t;
        }
        // A reference whose luminances are 1 (median) and 16 (max), grey pixels.
        let mut img = vec![1.0f32; 3 * 5];
        img[12..15].copy_from_slice(&[16.0; 3]);
        let (start, stop) = ExposureRange::from_reference(&img).unwrap();
        assert!((stop - start - 4.0).abs() < 1e-5, "{start} {stop}");
        // After exposure by 2^stop the median maps to 0.85, the maximum after 2^start too.
        assert!((tone_map(2f32.powf(stop)) - TARGET).abs() < 1e-5);
        assert!((tone_map(16.0 * 2f32.powf(start)) - TARGET).abs() < 1e-5);
        let r = ExposureRange::with_default_count(start, stop);
        assert_eq!(r.count, 4);
        assert!((r.exposure(3) - stop).abs() < 1e-6 && r.exposure(0) == start);
        // Narrow ranges still take two exposures; black references have no range.
        assert_eq!(ExposureRange::with_default_count(0.0, 0.3).count, 2);
        assert_eq!(ExposureRange::from_reference(&[0.0; 9]), None);
    }
}
