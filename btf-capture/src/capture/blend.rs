//! Linear edge blending, which makes a cropped normtexture tileable (Sattler et al. 2003,
//! §3.2: the rectified images are cropped and their edges blended linearly).
//!
//! A crop of `m = n + b` texels per side is folded to `n`: along each axis, the first `b`
//! texels are cross-faded with the `b` texels that follow the last kept one,
//! `out[k] = w_k · in[k] + (1 − w_k) · in[k + n]` with `w_k = k / b` for `k < b` and
//! `out[k] = in[k]` otherwise. The wrap-around neighbour of `out[n − 1] = in[n − 1]` is
//! then `out[0] = in[n]`, its real neighbour on the sample, so the seam is exactly as
//! smooth as the interior; the ramp's last step (`k = b − 1 → b`) carries a `1/b` share of
//! the difference between the two ends instead. The fold is linear, so applying it to the ground truth sampled on the
//! same grid gives the matching truth ([`fold`] is used for both).

/// Folds an `m × m` RGB image (row-major) with blend width `b = m − n` to `n × n`.
pub fn fold(img: &[[f32; 3]], m: usize, n: usize) -> Vec<[f32; 3]> {
    assert!(n <= m && img.len() == m * m, "fold: {m}² image to {n}²");
    let b = m - n;
    let weight = |k: usize| if k < b { k as f32 / b as f32 } else { 1.0 };
    let mix =
        |a: [f32; 3], c: [f32; 3], w: f32| std::array::from_fn(|i| w * a[i] + (1.0 - w) * c[i]);
    // Rows first (along x), then columns (along y).
    let mut tmp = vec![[0f32; 3]; m * n];
    for y in 0..m {
        for x in 0..n {
            let a = img[y * m + x];
            tmp[y * n + x] = if x < b { mix(a, img[y * m + x + n], weight(x)) } else { a };
        }
    }
    let mut out = vec![[0f32; 3]; n * n];
    for y in 0..n {
        for x in 0..n {
            let a = tmp[y * n + x];
            out[y * n + x] = if y < b { mix(a, tmp[(y + n) * n + x], weight(y)) } else { a };
        }
    }
    out
}

/// Neighbour differences of an `n × n` image (mean absolute difference over channels).
#[derive(Debug, Clone, Copy)]
pub struct Jumps {
    /// Mean over interior neighbour pairs.
    pub interior_mean: f64,
    /// Largest mean over one interior column pair `(x, x+1)` or row pair `(y, y+1)`.
    pub interior_max_line: f64,
    /// Mean over the wrap-around pairs (last column with the first, last row with the first).
    pub seam: f64,
}

/// Neighbour differences of an `n × n` RGB image; interior pairs are only counted where
/// both texels lie at `x, y ≥ skip` (pass the blend width to leave out the cross-faded band,
/// which is smoother than the sample because it averages two places).
pub fn neighbour_jumps(img: &[[f32; 3]], n: usize, skip: usize) -> Jumps {
    let d =
        |a: [f32; 3], b: [f32; 3]| (0..3).map(|i| (a[i] - b[i]).abs() as f64).sum::<f64>() / 3.0;
    // Per line index k: sums and counts for column pairs (axis 0) and row pairs (axis 1).
    let mut lines = vec![[(0.0, 0usize); 2]; n];
    for y in 0..n {
        for x in 0..n {
            let h = d(img[y * n + x], img[y * n + (x + 1) % n]);
            let v = d(img[y * n + x], img[((y + 1) % n) * n + x]);
            for (axis, k, jump) in [(0, x, h), (1, y, v)] {
                if k + 1 == n || (x >= skip && y >= skip) {
                    lines[k][axis].0 += jump;
                    lines[k][axis].1 += 1;
                }
            }
        }
    }
    let mean = |l: (f64, usize)| l.0 / l.1.max(1) as f64;
    let seam = (mean(lines[n - 1][0]) + mean(lines[n - 1][1])) / 2.0;
    let interior: Vec<(f64, usize)> =
        lines[..n - 1].iter().flatten().copied().filter(|l| l.1 > 0).collect();
    let (sum, count) = interior.iter().fold((0.0, 0), |a, l| (a.0 + l.0, a.1 + l.1));
    Jumps {
        interior_mean: sum / count.max(1) as f64,
        interior_max_line: interior.iter().map(|l| mean(*l)).fold(0.0, f64::max),
        seam,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-periodic texture: a tilted wave whose period does not divide the size, a ramp
    /// and hash noise — its own wrap-around seam is a jump.
    fn texture(m: usize) -> Vec<[f32; 3]> {
        (0..m * m)
            .map(|k| {
                let (x, y) = ((k % m) as f32, (k / m) as f32);
                let noise = ((k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32
                    / (1u64 << 24) as f32;
                let v = 0.5 + 0.3 * (0.37 * x + 0.21 * y).sin() + 0.01 * x + 0.1 * noise;
                [v, 0.8 * v, 0.5 * v]
            })
            .collect()
    }

    #[test]
    fn blended_seam_is_no_rougher_than_the_interior() {
        let (n, b) = (48, 8);
        let raw = texture(n + b);
        let crop: Vec<[f32; 3]> = (0..n * n).map(|k| raw[(k / n) * (n + b) + k % n]).collect();
        let before = neighbour_jumps(&crop, n, 0);
        assert!(
            before.seam > 3.0 * before.interior_max_line,
            "the crop must have a seam: {before:?}"
        );
        let after = neighbour_jumps(&fold(&raw, n + b, n), n, b);
        assert!(after.seam <= after.interior_mean, "{after:?}");
    }

    #[test]
    fn zero_width_is_the_identity_and_constants_stay_constant() {
        let raw = texture(16);
        assert_eq!(fold(&raw, 16, 16), raw);
        let flat = vec![[0.25f32, 0.5, 1.0]; 20 * 20];
        assert!(
            fold(&flat, 20, 14)
                .iter()
                .all(|p| (p[0] - 0.25).abs() < 1e-6 && (p[2] - 1.0).abs() < 1e-6)
        );
    }
}
