//! LDR-ꟻLIP on linear sRGB in `[0, 1]` `[A20]`: the colour pipeline (YCxCz, CSF filter,
//! clamp to the displayable gamut, Hunt-adjusted L*a*b*, HyAB, `ΔE_c = HyAB^q_c`
//! redistributed to `[0, 1]`), the feature pipeline (edge and point responses of the
//! normalised achromatic channel, `ΔE_f = (max(|Δedge|, |Δpoint|)/√2)^q_f`) and their
//! combination `ΔE = ΔE_c^(1 − ΔE_f)`.
//!
//! The passes: one conversion to YCxCz planes per image, the horizontal passes of all
//! seven kernels (four CSF, three feature) per image, then one row-parallel pass that runs
//! every vertical kernel for its row and combines colour and features there, so no
//! filtered image is ever stored whole.

use super::color::{hyab, linear_rgb_to_hunt_lab, max_distance, xyz_to_linear_rgb, ycxcz_to_xyz};
use super::color::{linear_rgb_to_xyz, xyz_to_ycxcz};
use super::filter::vertical_row;
use super::filter::{CsfKernels, FeatureKernels, csf_kernels, feature_kernels, horizontal};
use rayon::prelude::*;

/// Exponent of the colour difference (`q_c`).
pub(crate) const QC: f32 = 0.7;
/// Fraction of `c_max` below which differences are stretched (`p_c`).
pub(crate) const PC: f32 = 0.4;
/// The value that `p_c·c_max` maps to (`p_t`).
pub(crate) const PT: f32 = 0.95;
/// Exponent of the feature difference (`q_f`).
pub(crate) const QF: f32 = 0.5;

/// One image after the horizontal passes: the CSF channels (Y, Cx, Cz twice) and the
/// feature responses of the normalised achromatic channel `(Y + 16)/116`.
struct Horizontal {
    y: Vec<f32>,
    cx: Vec<f32>,
    cz1: Vec<f32>,
    cz2: Vec<f32>,
    g: Vec<f32>,
    dg: Vec<f32>,
    ddg: Vec<f32>,
}

impl Horizontal {
    fn new(linear_rgb: &[f32], w: usize, csf: &CsfKernels, feat: &FeatureKernels) -> Self {
        let n = linear_rgb.len() / 3;
        let (mut y, mut cx, mut cz) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
        let mut y_norm = vec![0f32; n];
        y.par_iter_mut()
            .zip(cx.par_iter_mut())
            .zip(cz.par_iter_mut().zip(y_norm.par_iter_mut()))
            .zip(linear_rgb.par_chunks_exact(3))
            .for_each(|(((y, cx), (cz, yn)), rgb)| {
                let c = xyz_to_ycxcz(linear_rgb_to_xyz([rgb[0], rgb[1], rgb[2]]));
                (*y, *cx, *cz) = (c[0], c[1], c[2]);
                *yn = c[0] * (1.0 / 116.0) + 16.0 / 116.0;
            });
        Horizontal {
            y: horizontal(&y, w, &csf.y),
            cx: horizontal(&cx, w, &csf.cx),
            cz1: horizontal(&cz, w, &csf.cz1),
            cz2: horizontal(&cz, w, &csf.cz2),
            g: horizontal(&y_norm, w, &feat.g),
            dg: horizontal(&y_norm, w, &feat.dg),
            ddg: horizontal(&y_norm, w, &feat.ddg),
        }
    }
}

/// One row of one image after the vertical passes.
struct Row {
    /// CSF-filtered Y, Cx and the two Cz halves.
    csf: [Vec<f32>; 4],
    /// `∂x, ∂²x, ∂y, ∂²y` of the Gaussian-smoothed normalised Y.
    feat: [Vec<f32>; 4],
}

impl Row {
    fn new(w: usize) -> Self {
        Row {
            csf: std::array::from_fn(|_| vec![0f32; w]),
            feat: std::array::from_fn(|_| vec![0f32; w]),
        }
    }

    fn fill(
        &mut self,
        hz: &Horizontal,
        w: usize,
        h: usize,
        y: usize,
        k: (&CsfKernels, &FeatureKernels),
    ) {
        let (csf, feat) = k;
        let sources =
            [(&hz.y, &csf.y), (&hz.cx, &csf.cx), (&hz.cz1, &csf.cz1), (&hz.cz2, &csf.cz2)];
        for (out, (src, kernel)) in self.csf.iter_mut().zip(sources) {
            vertical_row(src, w, h, kernel, y, out);
        }
        // ∂x and ∂²x: derivative across the row, Gaussian down the column; ∂y and ∂²y the
        // other way round.
        let sources =
            [(&hz.dg, &feat.g), (&hz.ddg, &feat.g), (&hz.g, &feat.dg), (&hz.g, &feat.ddg)];
        for (out, (src, kernel)) in self.feat.iter_mut().zip(sources) {
            vertical_row(src, w, h, kernel, y, out);
        }
    }

    /// Hunt-adjusted L*a*b* of pixel `x` after the CSF, clamped to the displayable gamut.
    fn lab(&self, x: usize) -> [f32; 3] {
        let ycxcz = [self.csf[0][x], self.csf[1][x], self.csf[2][x] + self.csf[3][x]];
        let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(ycxcz)).map(|c| c.clamp(0.0, 1.0));
        linear_rgb_to_hunt_lab(rgb)
    }

    /// Edge and point strengths of pixel `x`.
    fn features(&self, x: usize) -> (f32, f32) {
        let [dx, ddx, dy, ddy] = self.feat.each_ref().map(|v| v[x]);
        ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt())
    }
}

/// The colour difference `ΔE_c ∈ [0, 1]` of two Hunt-adjusted L*a*b* colours: `HyAB^q_c`,
/// then `[0, p_c·c_max)` → `[0, p_t)` and `[p_c·c_max, c_max]` → `[p_t, 1]` linearly.
pub(crate) fn colour_difference(lab_ref: [f32; 3], lab_test: [f32; 3], c_max: f32) -> f32 {
    let pc_cmax = PC * c_max;
    let d = hyab(lab_ref, lab_test).powf(QC);
    if d < pc_cmax {
        d * (PT / pc_cmax)
    } else {
        PT + ((d - pc_cmax) / (c_max - pc_cmax)) * (1.0 - PT)
    }
}

/// The feature difference `ΔE_f ∈ [0, 1]` from the edge and point strengths of both images.
pub(crate) fn feature_difference(edge: (f32, f32), point: (f32, f32)) -> f32 {
    let de = (edge.0 - edge.1).abs();
    let dp = (point.0 - point.1).abs();
    ((1.0 / 2f32.sqrt()) * if de > dp { de } else { dp }).powf(QF)
}

/// LDR-ꟻLIP of two validated linear sRGB images (values clamped to `[0, 1]` here).
pub(crate) fn flip_linear(
    reference: &[f32],
    test: &[f32],
    w: usize,
    h: usize,
    ppd: f32,
) -> Vec<f32> {
    let csf = csf_kernels(ppd);
    let feat = feature_kernels(ppd);
    let clamp = |v: &[f32]| v.iter().map(|c| c.clamp(0.0, 1.0)).collect::<Vec<f32>>();
    let (hz_ref, hz_test) = rayon::join(
        || Horizontal::new(&clamp(reference), w, &csf, &feat),
        || Horizontal::new(&clamp(test), w, &csf, &feat),
    );
    let c_max = max_distance(QC);
    let mut out = vec![0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each_init(
        || (Row::new(w), Row::new(w)),
        |(row_ref, row_test), (y, out)| {
            row_ref.fill(&hz_ref, w, h, y, (&csf, &feat));
            row_test.fill(&hz_test, w, h, y, (&csf, &feat));
            for (x, o) in out.iter_mut().enumerate() {
                let colour = colour_difference(row_ref.lab(x), row_test.lab(x), c_max);
                let (e_ref, p_ref) = row_ref.features(x);
                let (e_test, p_test) = row_test.features(x);
                let features = feature_difference((e_ref, e_test), (p_ref, p_test));
                *o = colour.powf(1.0 - features);
            }
        },
    );
    out
}
