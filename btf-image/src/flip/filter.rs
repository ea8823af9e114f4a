//! ꟻLIP's one-dimensional kernels and the separable passes that apply them.
//!
//! - **Contrast sensitivity** `[A20, colour pipeline]`: each opponent channel is low-passed
//!   by a CSF modelled in the spatial domain as `a·√(π/b)·exp(−π²x²/b)` (`x` in degrees
//!   of visual angle, a pixel being `1/ppd` degrees) with `(a, b) = (1, 0.0047)` for the
//!   achromatic channel, `(1, 0.0053)` for red–green and the sum of two Gaussians
//!   `(34.1, 0.04) + (13.5, 0.025)` for blue–yellow. The kernel radius is three standard
//!   deviations of the widest Gaussian, `⌈3·√(b_max/(2π²))·ppd⌉`. A 2-D Gaussian is the
//!   product of two 1-D ones; the blue–yellow *sum* of two Gaussians is separated into two
//!   separable halves that are filtered apart and added (NVlabs/flip,
//!   `misc/separatedConvolutions.pdf`), each 1-D half `√(a·√(π/b))·exp(−π²x²/b)`, both
//!   divided by `√(S₁² + S₂²)` (`S` the 1-D sums) so that the 2-D kernel sums to one.
//! - **Features** `[A20, feature pipeline]`: a Gaussian of standard deviation
//!   `σ = ½·w·ppd` pixels (`w = 0.082°`) and its first and second derivatives on
//!   `[−⌈3σ⌉, ⌈3σ⌉]`; the Gaussian sums to one, the positive and the negative lobes of each
//!   derivative sum to `+1` and `−1`. Edges are `‖(G′ₓ ⊗ G_y, G_x ⊗ G′_y)‖`, points the same
//!   with `G″`.
//!
//! All in `f32` and in the reference implementation's order of operations; borders are
//! clamped to the edge pixel. A pass correlates (kernel index `k` weighs the pixel at
//! offset `k − r`), as the reference does; only magnitudes of the derivative responses are
//! used, so the sign convention does not matter.

use rayon::prelude::*;

/// π as the reference rounds it to `f32`.
const PI: f32 = std::f32::consts::PI;

/// The CSF Gaussians `(a, b)`: achromatic, red–green, and the two blue–yellow terms.
const CSF_Y: (f32, f32) = (1.0, 0.0047);
const CSF_CX: (f32, f32) = (1.0, 0.0053);
const CSF_CZ1: (f32, f32) = (34.1, 0.04);
const CSF_CZ2: (f32, f32) = (13.5, 0.025);

/// Width of the feature detectors in degrees (`w` of `[A20]`, 0.082°).
pub(crate) const FEATURE_WIDTH_DEG: f32 = 0.082;

/// The CSF kernels of one ppd, each `2r + 1` taps.
#[derive(Debug, Clone)]
pub(crate) struct CsfKernels {
    /// Achromatic (Y).
    pub y: Vec<f32>,
    /// Red–green (Cx).
    pub cx: Vec<f32>,
    /// First separable half of blue–yellow (Cz).
    pub cz1: Vec<f32>,
    /// Second separable half of blue–yellow (Cz).
    pub cz2: Vec<f32>,
}

/// The feature kernels of one ppd: Gaussian, first and second derivative.
#[derive(Debug, Clone)]
pub(crate) struct FeatureKernels {
    /// Gaussian, sums to 1.
    pub g: Vec<f32>,
    /// First derivative (`−x·g`), lobes normalised to ±1.
    pub dg: Vec<f32>,
    /// Second derivative (`(x²/σ² − 1)·g`), lobes normalised to ±1.
    pub ddg: Vec<f32>,
}

/// `a·√(π/b)·exp(−π²x²/b)`.
fn csf_gaussian(x2: f32, (a, b): (f32, f32)) -> f32 {
    a * (PI / b).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// The separable half of [`csf_gaussian`]: `√(a·√(π/b))·exp(−π²x²/b)`.
fn csf_gaussian_half(x2: f32, (a, b): (f32, f32)) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// Radius in pixels of the CSF kernels: three standard deviations of the widest Gaussian.
pub(crate) fn csf_radius(ppd: f32) -> usize {
    let b_max = [CSF_Y.1, CSF_CX.1, CSF_CZ1.1, CSF_CZ2.1].into_iter().fold(0f32, f32::max);
    (3.0 * (b_max / (2.0 * (PI * PI))).sqrt() * ppd).ceil() as usize
}

/// The CSF kernels for `ppd` pixels per degree.
pub(crate) fn csf_kernels(ppd: f32) -> CsfKernels {
    let r = csf_radius(ppd) as i64;
    let dx_deg = 1.0 / ppd;
    let x2s: Vec<f32> = (-r..=r).map(|i| (i as f32 * dx_deg) * (i as f32 * dx_deg)).collect();
    let taps = |f: &dyn Fn(f32) -> f32| -> (Vec<f32>, f32) {
        let v: Vec<f32> = x2s.iter().map(|&x2| f(x2)).collect();
        let sum = v.iter().fold(0f32, |s, &t| s + t);
        (v, sum)
    };
    let (y, sum_y) = taps(&|x2| csf_gaussian(x2, CSF_Y));
    let (cx, sum_cx) = taps(&|x2| csf_gaussian(x2, CSF_CX));
    let (cz1, s1) = taps(&|x2| csf_gaussian_half(x2, CSF_CZ1));
    let (cz2, s2) = taps(&|x2| csf_gaussian_half(x2, CSF_CZ2));
    let scale = |v: Vec<f32>, k: f32| v.into_iter().map(|t| t * k).collect::<Vec<f32>>();
    let k_cz = 1.0 / (s1 * s1 + s2 * s2).sqrt();
    CsfKernels {
        y: scale(y, 1.0 / sum_y),
        cx: scale(cx, 1.0 / sum_cx),
        cz1: scale(cz1, k_cz),
        cz2: scale(cz2, k_cz),
    }
}

/// The feature kernels for `ppd` pixels per degree.
pub(crate) fn feature_kernels(ppd: f32) -> FeatureKernels {
    let sigma = 0.5 * FEATURE_WIDTH_DEG * ppd;
    let r = (3.0 * sigma).ceil() as i64;
    let (mut g, mut dg, mut ddg) = (Vec::new(), Vec::new(), Vec::new());
    for i in -r..=r {
        let x = i as f32;
        let gi = (-(x * x) / (2.0 * sigma * sigma)).exp();
        g.push(gi);
        dg.push(-x * gi);
        ddg.push((x * x / (sigma * sigma) - 1.0) * gi);
    }
    let sum = |v: &[f32], positive: bool| {
        v.iter().fold(0f32, |s, &t| if (t > 0.0) == positive { s + t.abs() } else { s })
    };
    let g_sum = sum(&g, true);
    let lobes = |v: Vec<f32>| {
        let (pos, neg) = (sum(&v, true), sum(&v, false));
        v.into_iter().map(|t| t / if t > 0.0 { pos } else { neg }).collect::<Vec<f32>>()
    };
    FeatureKernels { g: g.into_iter().map(|t| t / g_sum).collect(), dg: lobes(dg), ddg: lobes(ddg) }
}

/// Correlates every row of `src` (`w × h`, row-major) with `kernel`, borders clamped. Each
/// row is copied into a buffer padded with its edge values so that the tap loop is outer
/// and the pixel loop inner (vectorised); every pixel still sums its taps in kernel order.
pub(crate) fn horizontal(src: &[f32], w: usize, kernel: &[f32]) -> Vec<f32> {
    let r = kernel.len() / 2;
    let mut dst = vec![0f32; src.len()];
    dst.par_chunks_mut(w).zip(src.par_chunks(w)).for_each_init(
        || vec![0f32; w + 2 * r],
        |padded, (out, row)| {
            padded[..r].fill(row[0]);
            padded[r..r + w].copy_from_slice(row);
            padded[r + w..].fill(row[w - 1]);
            for (k, &wk) in kernel.iter().enumerate() {
                for (o, &v) in out.iter_mut().zip(&padded[k..k + w]) {
                    *o += wk * v;
                }
            }
        },
    );
    dst
}

/// Row `y` of the column-wise correlation of `src` (`w × h`) with `kernel`, borders
/// clamped, written into `out` (`w` values).
pub(crate) fn vertical_row(
    src: &[f32],
    w: usize,
    h: usize,
    kernel: &[f32],
    y: usize,
    out: &mut [f32],
) {
    let r = kernel.len() / 2;
    out.fill(0.0);
    for (k, &wk) in kernel.iter().enumerate() {
        let yy = (y + k).saturating_sub(r).min(h - 1);
        for (o, &v) in out.iter_mut().zip(&src[yy * w..(yy + 1) * w]) {
            *o += wk * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(v: &[f32]) -> f64 {
        v.iter().map(|&t| t as f64).sum()
    }

    #[test]
    fn kernels_at_67_ppd_have_the_published_radii_and_sums() {
        let ppd = 67.0;
        // ⌈3·√(0.04/(2π²))·67⌉ = ⌈9.05⌉ = 10; σ = 0.041·67 = 2.747, ⌈3σ⌉ = 9.
        assert_eq!(csf_radius(ppd), 10);
        let k = csf_kernels(ppd);
        assert_eq!((k.y.len(), k.cz2.len()), (21, 21));
        assert!((sum(&k.y) - 1.0).abs() < 1e-6 && (sum(&k.cx) - 1.0).abs() < 1e-6);
        // The blue–yellow 2-D kernel is cz1⊗cz1 + cz2⊗cz2; it sums to one.
        let s2 = sum(&k.cz1).powi(2) + sum(&k.cz2).powi(2);
        assert!((s2 - 1.0).abs() < 1e-6, "{s2}");
        let f = feature_kernels(ppd);
        assert_eq!(f.g.len(), 19);
        assert!((sum(&f.g) - 1.0).abs() < 1e-6);
        for d in [&f.dg, &f.ddg] {
            let pos: f64 = d.iter().filter(|&&t| t > 0.0).map(|&t| t as f64).sum();
            assert!((pos - 1.0).abs() < 1e-6 && sum(d).abs() < 1e-6, "{pos}");
        }
        // Symmetric Gaussians, antisymmetric first derivative.
        for i in 0..19 {
            assert_eq!(f.g[i], f.g[18 - i]);
            assert_eq!(f.dg[i], -f.dg[18 - i]);
        }
    }

    #[test]
    fn passes_keep_constants_and_clamp_the_border() {
        let (w, h) = (5, 4);
        let k = [0.25f32, 0.5, 0.25];
        let flat = vec![3.0f32; w * h];
        assert!(horizontal(&flat, w, &k).iter().all(|&v| v == 3.0));
        // A ramp along x: interior unchanged (symmetric kernel), ends pulled inwards by a
        // quarter step (the clamped neighbour repeats the edge value).
        let ramp: Vec<f32> = (0..w * h).map(|i| (i % w) as f32).collect();
        let hz = horizontal(&ramp, w, &k);
        assert_eq!(&hz[..w], &[0.25, 1.0, 2.0, 3.0, 3.75]);
        let col: Vec<f32> = (0..w * h).map(|i| (i / w) as f32).collect();
        let mut out = vec![0f32; w];
        vertical_row(&col, w, h, &k, 0, &mut out);
        assert_eq!(out, vec![0.25; w]);
        vertical_row(&col, w, h, &k, 3, &mut out);
        assert_eq!(out, vec![2.75; w]);
    }
}
