//! Mip chains for the eigentextures and means (trilinear / anisotropic minification).
//!
//! The reconstruction of Sattler et al. 2003 (eq. 2–5) is linear in the textures,
//! `T = Σ_m ω_m [c_m μ_{j_m} + Σ_k γ_k B_{k,j_m}]` with coefficients that do not depend on
//! the texel, so filtering the mean and each eigentexture separately and then
//! reconstructing equals filtering the reconstructed texture: mipmapping the PCA data is
//! exact for the reconstruction (up to the storage rounding of each level). The folded
//! dequantisation (`p' = p·s`, offsets in a per-slot constant, `material.rs`) is affine per
//! component, so averaging the stored `u8`/`f16` values is averaging the dequantised ones.
//!
//! Each level halves the size (floor, at least 1) by a 2×2 box average; an odd last row or
//! column is folded into the last texel's average so no texel is dropped.

use half::f16;

/// Mip levels of a `w × h` texture down to 1×1.
pub fn level_count(w: u32, h: u32) -> u32 {
    32 - w.max(h).max(1).leading_zeros()
}

#[cfg(test)]
/// Sizes of every level, base first.
pub fn level_sizes(w: u32, h: u32) -> Vec<(u32, u32)> {
    (0..level_count(w, h)).map(|l| ((w >> l).max(1), (h >> l).max(1))).collect()
}

/// Source texels `[lo, hi)` averaged into destination texel `i` when a dimension of `n`
/// texels shrinks to `m` (`m = max(1, n/2)`): pairs, the last one taking an odd remainder.
fn source_span(i: usize, n: usize, m: usize) -> (usize, usize) {
    if m == n {
        return (i, i + 1);
    }
    let lo = 2 * i;
    let hi = if i + 1 == m { n } else { lo + 2 };
    (lo, hi)
}

/// One RGBA level `w × h` (values as `f32`) reduced to the next.
fn reduce(src: &[f32], w: usize, h: usize) -> (Vec<f32>, usize, usize) {
    let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
    let mut out = vec![0f32; w2 * h2 * 4];
    for y in 0..h2 {
        let (y0, y1) = source_span(y, h, h2);
        for x in 0..w2 {
            let (x0, x1) = source_span(x, w, w2);
            let n = ((y1 - y0) * (x1 - x0)) as f32;
            for ch in 0..4 {
                let mut sum = 0f32;
                for sy in y0..y1 {
                    for sx in x0..x1 {
                        sum += src[(sy * w + sx) * 4 + ch];
                    }
                }
                out[(y * w2 + x) * 4 + ch] = sum / n;
            }
        }
    }
    (out, w2, h2)
}

/// Appends every level of one layer (base included) to `out`, converting with `decode` /
/// `encode` (4 values a texel).
fn chain_of_layer<T: Copy>(
    base: &[T],
    w: usize,
    h: usize,
    decode: impl Fn(T) -> f32,
    encode: impl Fn(f32) -> T,
    out: &mut Vec<T>,
) {
    out.extend_from_slice(base);
    let mut level: Vec<f32> = base.iter().map(|&v| decode(v)).collect();
    let (mut lw, mut lh) = (w, h);
    while lw > 1 || lh > 1 {
        let (next, nw, nh) = reduce(&level, lw, lh);
        out.extend(next.iter().map(|&v| encode(v)));
        (level, lw, lh) = (next, nw, nh);
    }
}

/// Full mip chains of `layers` RGBA `f16` layers of `w × h`, layer-major (layer 0's levels,
/// then layer 1's, …) as `wgpu::util::TextureDataOrder::LayerMajor` expects.
pub fn chain_f16(data: &[f16], w: usize, h: usize, layers: usize) -> Vec<f16> {
    let per = w * h * 4;
    let mut out = Vec::with_capacity(data.len() * 4 / 3 + layers * 16);
    for l in 0..layers {
        chain_of_layer(&data[l * per..(l + 1) * per], w, h, f16::to_f32, f16::from_f32, &mut out);
    }
    out
}

/// Full mip chains of `u8` (unorm) RGBA layers, rounded to the nearest step.
pub fn chain_u8(data: &[u8], w: usize, h: usize, layers: usize) -> Vec<u8> {
    let per = w * h * 4;
    let mut out = Vec::with_capacity(data.len() * 4 / 3 + layers * 16);
    for l in 0..layers {
        chain_of_layer(
            &data[l * per..(l + 1) * per],
            w,
            h,
            |v| v as f32,
            |v| v.round().clamp(0.0, 255.0) as u8,
            &mut out,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_counts_and_sizes() {
        assert_eq!(level_count(1, 1), 1);
        assert_eq!(level_count(32, 32), 6);
        assert_eq!(level_count(33, 8), 6);
        assert_eq!(level_sizes(5, 3), vec![(5, 3), (2, 1), (1, 1)]);
    }

    #[test]
    fn levels_keep_the_mean_and_average_blocks() {
        // 4×2 layer with distinct values: level 1 is 2×1 (2×2 boxes), level 2 is 1×1.
        let base: Vec<f16> = (0..32).map(|i| f16::from_f32(i as f32)).collect();
        let chain = chain_f16(&base, 4, 2, 1);
        assert_eq!(chain.len(), 32 + 8 + 4);
        // texel (0,0) of level 1, channel 0: mean of texels (0,0),(1,0),(0,1),(1,1) = 0,4,16,20.
        assert_eq!(chain[32].to_f32(), 10.0);
        let mean_base: f32 = (0..8).map(|t| t as f32 * 4.0).sum::<f32>() / 8.0;
        assert_eq!(chain[40].to_f32(), mean_base);
    }

    #[test]
    fn odd_sizes_fold_the_remainder() {
        // 3×1: level 1 is 1×1, the mean of all three texels.
        let base: Vec<u8> = [0u8, 0, 0, 0, 30, 30, 30, 30, 90, 90, 90, 90].to_vec();
        let chain = chain_u8(&base, 3, 1, 1);
        assert_eq!(&chain[12..16], &[40, 40, 40, 40]);
    }
}
