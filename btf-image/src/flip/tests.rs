//! Unit tests of ꟻLIP: zeros for identical images, the range `[0, 1]`, the symmetries that
//! hold (LDR swap, HDR with fixed exposures, HDR under a common exposure change) and the
//! one that does not (HDR's automatic range comes from the reference), locality (pixels
//! beyond the kernel radii of a change are exactly 0), a closed form for a flat colour
//! change computed independently in `f64`, and the refusals.

use super::*;

/// A deterministic pseudo-random sequence in `[0, 1)` (xorshift64*).
fn noise(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect()
}

fn flat(w: usize, h: usize, rgb: [f32; 3]) -> Vec<f32> {
    rgb.repeat(w * h)
}

#[test]
fn identical_images_give_zero_everywhere() {
    let (w, h) = (23, 17);
    let img = noise(w * h * 3, 1);
    let m = flip_ldr(&img, &img, w, h, DEFAULT_PPD).unwrap();
    assert!(m.values.iter().all(|&v| v == 0.0));
    let hdr: Vec<f32> = img.iter().map(|v| v * 20.0).collect();
    let m = flip_hdr(&hdr, &hdr, w, h, DEFAULT_PPD, None).unwrap();
    assert!(m.values.iter().all(|&v| v == 0.0) && m.mean() == 0.0);
    assert!(m.exposures.is_some_and(|r| r.count >= 2));
}

#[test]
fn values_lie_in_the_unit_interval_and_ldr_is_symmetric() {
    let (w, h) = (32, 24);
    let (a, b) = (noise(w * h * 3, 2), noise(w * h * 3, 3));
    let ab = flip_ldr(&a, &b, w, h, DEFAULT_PPD).unwrap();
    assert!(ab.values.iter().all(|v| (0.0..=1.0).contains(v)));
    assert!(ab.mean() > 0.3, "independent noise is very different: {}", ab.mean());
    // HyAB and |Δedge|, |Δpoint| are symmetric, so swapping the images changes nothing.
    assert_eq!(flip_ldr(&b, &a, w, h, DEFAULT_PPD).unwrap().values, ab.values);
    // Extreme inputs: black against white, out-of-range values (clamped).
    let black = flat(w, h, [0.0; 3]);
    let over: Vec<f32> = a.iter().map(|v| v * 5.0 - 2.0).collect();
    for (r, t) in [(&black, &flat(w, h, [1.0; 3])), (&over, &black)] {
        let m = flip_ldr(r, t, w, h, 10.0).unwrap();
        assert!(m.values.iter().all(|v| (0.0..=1.0).contains(v)), "{}", m.max());
    }
}

#[test]
fn hdr_is_asymmetric_with_its_own_range_and_symmetric_with_a_fixed_one() {
    let (w, h) = (24, 24);
    let a: Vec<f32> = noise(w * h * 3, 4).iter().map(|v| 20.0 * v * v).collect();
    let b: Vec<f32> = noise(w * h * 3, 5).iter().map(|v| 2.0 * v).collect();
    let ab = flip_hdr(&a, &b, w, h, DEFAULT_PPD, None).unwrap();
    let ba = flip_hdr(&b, &a, w, h, DEFAULT_PPD, None).unwrap();
    assert!(ab.values.iter().chain(&ba.values).all(|v| (0.0..=1.0).contains(v)));
    // The exposure range is the reference's: swapping the images moves it.
    let (ra, rb) = (ab.exposures.unwrap(), ba.exposures.unwrap());
    assert!((ra.start - rb.start).abs() > 1.0, "{ra:?} {rb:?}");
    assert_ne!(ab.values, ba.values);
    let fixed = Some((ra.start as f64, ra.stop as f64));
    let ab_fixed = flip_hdr(&a, &b, w, h, DEFAULT_PPD, fixed).unwrap();
    assert_eq!(ab_fixed.values, ab.values);
    assert_eq!(flip_hdr(&b, &a, w, h, DEFAULT_PPD, fixed).unwrap().values, ab.values);
}

#[test]
fn hdr_ignores_a_common_exposure_change() {
    // Scaling both images by 2^k shifts the automatic range by −k stops exactly (powers of
    // two), so the exposed, tone-mapped pairs — and the map — are the same up to the
    // rounding of log₂ and 2^c (a few ulps of the exposure, ~1e-6 of the values).
    let (w, h) = (20, 20);
    let a: Vec<f32> = noise(w * h * 3, 6).iter().map(|v| 8.0 * v).collect();
    let b: Vec<f32> = a.iter().zip(noise(w * h * 3, 7)).map(|(v, n)| v * (0.8 + 0.4 * n)).collect();
    let base = flip_hdr(&a, &b, w, h, DEFAULT_PPD, None).unwrap();
    for k in [-6i32, 3, 10] {
        let s = 2f32.powi(k);
        let (sa, sb): (Vec<f32>, Vec<f32>) = a.iter().zip(&b).map(|(x, y)| (x * s, y * s)).unzip();
        let m = flip_hdr(&sa, &sb, w, h, DEFAULT_PPD, None).unwrap();
        let (r0, r) = (base.exposures.unwrap(), m.exposures.unwrap());
        assert_eq!(r.count, r0.count);
        assert!((r.start - (r0.start - k as f32)).abs() < 1e-5, "{r:?} {r0:?}");
        let worst =
            m.values.iter().zip(&base.values).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-4, "k = {k}: {worst}");
    }
}

#[test]
fn a_change_is_invisible_beyond_the_kernel_radii() {
    // A vertical edge moved by one pixel: columns farther than the CSF radius (10 at 67
    // ppd, which exceeds the feature radius 9) from both edge positions see identical
    // neighbourhoods, so their colour difference — and ꟻLIP — is exactly 0.
    let (w, h) = (64, 8);
    let edge = |x0: usize| -> Vec<f32> {
        (0..w * h)
            .flat_map(|i| if i % w < x0 { [0.1, 0.1, 0.1] } else { [0.8, 0.6, 0.3] })
            .collect()
    };
    let m = flip_ldr(&edge(30), &edge(31), w, h, 67.0).unwrap();
    let r = filter::csf_radius(67.0);
    for y in 0..h {
        for x in 0..w {
            let v = m.values[y * w + x];
            if x + r < 30 || x > 30 + r {
                assert_eq!(v, 0.0, "x = {x}");
            }
        }
        assert!(m.values[y * w + 30] > 0.3, "{}", m.values[y * w + 30]);
    }
}

/// sRGB (linear) → CIE L*a*b* in `f64` with the textbook sRGB matrix (IEC 61966-2-1,
/// four decimals) and D65 white — independent of the `f32` code under test.
fn lab64(rgb: [f64; 3]) -> [f64; 3] {
    let m = [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]];
    let white = [0.95047, 1.0, 1.08883];
    let f = |t: f64| {
        if t > (6.0f64 / 29.0).powi(3) {
            t.cbrt()
        } else {
            t / (3.0 * (6.0f64 / 29.0).powi(2)) + 4.0 / 29.0
        }
    };
    let xyz: Vec<f64> =
        (0..3).map(|i| f((0..3).map(|j| m[i][j] * rgb[j]).sum::<f64>() / white[i])).collect();
    [116.0 * xyz[1] - 16.0, 500.0 * (xyz[0] - xyz[1]), 200.0 * (xyz[1] - xyz[2])]
}

/// ꟻLIP's colour term for two flat colours, in `f64`: Hunt, HyAB, `^0.7`, redistribution.
fn flat_colour_term(a: [f64; 3], b: [f64; 3]) -> f64 {
    let hunt = |l: [f64; 3]| [l[0], l[0] * l[1] / 100.0, l[0] * l[2] / 100.0];
    let hyab = |p: [f64; 3], q: [f64; 3]| (p[0] - q[0]).abs() + (p[1] - q[1]).hypot(p[2] - q[2]);
    let c_max = hyab(hunt(lab64([0.0, 1.0, 0.0])), hunt(lab64([0.0, 0.0, 1.0]))).powf(0.7);
    let d = hyab(hunt(lab64(a)), hunt(lab64(b))).powf(0.7);
    let (pc, pt) = (0.4 * c_max, 0.95);
    if d < pc { d * pt / pc } else { pt + (d - pc) / (c_max - pc) * (1.0 - pt) }
}

#[test]
fn a_flat_colour_change_is_the_normalised_hyab_term() {
    // On flat images every filter returns the colour itself (kernels sum to 1) and the
    // derivative kernels return ~0, so ꟻLIP is the colour term. Residuals: the f32
    // pipeline and the reference's 9-digit matrix against the 4-digit textbook one here
    // (≤ 2e-4 in L*a*b* → ≤ 1e-4 in the term), and the f32 sums of the derivative
    // kernels (|Σ| ~ 1e-8) seen through ΔE_f = (…)^0.5 ~ 1e-4, which moves ΔE_c^(1−ΔE_f)
    // by at most ΔE_f·max(x·|ln x|) = ΔE_f/e.
    let (w, h) = (16, 12);
    let cases = [
        ([0.2, 0.2, 0.2], [0.3, 0.3, 0.3]),
        ([0.5, 0.1, 0.1], [0.5, 0.3, 0.1]),
        ([0.05, 0.2, 0.6], [0.05, 0.2, 0.65]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.9, 0.8, 0.7], [0.9, 0.8, 0.69]),
    ];
    for (a, b) in cases {
        let expect = flat_colour_term(a, b);
        let m = flip_ldr(
            &flat(w, h, a.map(|v| v as f32)),
            &flat(w, h, b.map(|v| v as f32)),
            w,
            h,
            DEFAULT_PPD,
        )
        .unwrap();
        for &v in &m.values {
            assert!((v as f64 - expect).abs() < 3e-4, "{a:?} vs {b:?}: {v} expected {expect}");
        }
    }
    // Green against blue is the largest difference: exactly 1 up to rounding.
    assert!((flat_colour_term([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]) - 1.0).abs() < 1e-12);
}

#[test]
fn srgb_inputs_are_decoded_first_and_masks_select_pixels() {
    let (w, h) = (12, 10);
    let (a, b) = (noise(w * h * 3, 8), noise(w * h * 3, 9));
    let dec = |v: &[f32]| v.iter().map(|&c| crate::color::srgb_decode(c)).collect::<Vec<f32>>();
    let s = flip_ldr_srgb(&a, &b, w, h, 30.0).unwrap();
    assert_eq!(s.values, flip_ldr(&dec(&a), &dec(&b), w, h, 30.0).unwrap().values);
    let mask: Vec<bool> = (0..w * h).map(|i| i % w < 4).collect();
    let direct = (0..w * h).filter(|i| mask[*i]).map(|i| s.values[i] as f64).sum::<f64>() / 40.0;
    assert!((s.mean_over(&mask).unwrap() - direct).abs() < 1e-12);
    assert!(s.mean_over(&mask[1..]).unwrap_err().to_string().contains("mask of 119 pixels"));
    assert!(s.mean_over(&vec![false; w * h]).unwrap_err().to_string().contains("no pixel"));
    let img = s.heatmap_image(1.0, Some(&mask));
    assert_eq!(img.dimensions(), (12, 10));
    assert_eq!(img.get_pixel(5, 0).0, [0, 0, 0]);
}

#[test]
fn bad_inputs_are_refused_with_a_clear_message() {
    let (w, h) = (4, 3);
    let a = noise(w * h * 3, 10);
    let err = |r: Result<FlipMap>| r.unwrap_err().to_string();
    assert!(
        err(flip_ldr(&a, &a[3..], w, h, 67.0))
            .contains("test image has 33 values, a 4×3 RGB image has 36")
    );
    assert!(err(flip_ldr(&[], &[], 0, 3, 67.0)).contains("empty image (0×3)"));
    let mut nan = a.clone();
    nan[3 * 6 + 2] = f32::NAN;
    let e = err(flip_ldr(&a, &nan, w, h, 67.0));
    assert!(
        e.contains("test image") && e.contains("x=2, y=1 (B)") && e.contains("non-finite"),
        "{e}"
    );
    let mut neg = a.clone();
    neg[0] = -0.5;
    let e = err(flip_hdr(&neg, &a, w, h, 67.0, None));
    assert!(e.contains("reference image has the negative value -0.5 at pixel x=0, y=0 (R)"), "{e}");
    assert!(flip_ldr(&neg, &a, w, h, 67.0).is_ok(), "LDR clamps, as the reference does");
    for ppd in [0.0, -3.0, f64::NAN, 1e9] {
        assert!(err(flip_ldr(&a, &a, w, h, ppd)).contains("pixels per degree"));
    }
    let black = vec![0.0; w * h * 3];
    assert!(
        err(flip_hdr(&black, &a, w, h, 67.0, None)).contains("median (or largest) luminance is 0")
    );
    let m = flip_hdr(&black, &a, w, h, 67.0, Some((-2.0, 1.5))).unwrap();
    assert_eq!(m.exposures.map(|r| (r.start, r.stop, r.count)), Some((-2.0, 1.5, 4)));
    assert!(err(flip_hdr(&a, &a, w, h, 67.0, Some((1.0, 0.0)))).contains("start ≤ stop"));
}

#[test]
fn exposures_over_a_mask_are_those_of_the_masked_pixels_alone() {
    // A bright subject on a black background covering under half the frame: the median
    // over the frame is 0, so the automatic range is refused; over the subject's mask it
    // is the range of the subject's pixels as an image of their own.
    let (w, h) = (20, 20);
    let subject: Vec<f32> = noise(8 * 10 * 3, 9).iter().map(|v| 0.1 + 4.0 * v).collect();
    let mut frame = flat(w, h, [0.0; 3]);
    let mut mask = vec![false; w * h];
    for y in 0..10 {
        for x in 0..8 {
            let (i, j) = (y * w + x + 3, y * 8 + x);
            frame[3 * i..3 * i + 3].copy_from_slice(&subject[3 * j..3 * j + 3]);
            mask[i] = true;
        }
    }
    assert!(flip_hdr(&frame, &frame, w, h, DEFAULT_PPD, None).is_err());
    let over = hdr_exposures_over(&frame, &mask).unwrap();
    let own = flip_hdr(&subject, &subject, 8, 10, DEFAULT_PPD, None).unwrap().exposures.unwrap();
    assert_eq!(over, (own.start as f64, own.stop as f64));
    let m = flip_hdr(&frame, &frame, w, h, DEFAULT_PPD, Some(over)).unwrap();
    assert_eq!(m.mean_over(&mask).unwrap(), 0.0);
    // Refusals: a mask of the wrong size, a mask over black pixels only.
    assert!(hdr_exposures_over(&frame, &mask[1..]).is_err());
    let black: Vec<bool> = mask.iter().map(|m| !m).collect();
    let e = hdr_exposures_over(&frame, &black).unwrap_err().to_string();
    assert!(e.contains("median"), "{e}");
}
