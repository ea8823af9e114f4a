//! The quick material of `btf thin demo --material weave-lambert` (`[S03 eq. 1–2]` in
//! closed form): a Lambertian fabric with
//! a basket-weave albedo texture, written straight into an eigen store. Its BTF is exactly
//! `ρ(x)/π · cos θ_l` (DESIGN.md §3) for every view slot, which one component represents
//! (the PCA of [S03 eq. 1–2] with mean `ρ/π · mean cos θ_l` and eigentexture `ρ/‖ρ‖`) — no
//! 81 × 81 images are rendered or stored, so it takes milliseconds.

use crate::Result;
use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use std::path::Path;

/// Albedo of texel `(x, y)` of a `size²` basket weave (4 threads per side, two over two
/// under), linear RGB.
fn weave_albedo(x: usize, y: usize, size: usize) -> [f32; 3] {
    let cell = (size / 8).max(1);
    let (cx, cy) = (x / cell, y / cell);
    let warp_on_top = (cx / 2 + cy / 2) % 2 == 0;
    // A thread is brightest along its middle and darker at its edges.
    let across = if warp_on_top { x % cell } else { y % cell } as f32 + 0.5;
    let bulge = (std::f32::consts::PI * across / cell as f32).sin();
    let base = if warp_on_top { [0.80, 0.78, 0.72] } else { [0.62, 0.66, 0.80] };
    base.map(|c| c * (0.55 + 0.45 * bulge))
}

/// Writes the store (`ubo81` samplings, `components ≥ 1`, f16) to `path`.
pub fn write_weave_lambert(path: &Path, size: usize, components: usize) -> Result<()> {
    let (views, lights) = (Sampling::ubo81(), Sampling::ubo81());
    let c = components.clamp(1, lights.len());
    let meta = EigenMeta {
        btf: BtfMeta::new(views.clone(), lights.clone(), size, size),
        components: c,
        quantization: Quantization::F16,
    };
    let n = size * size * 3;
    let rho: Vec<f32> =
        (0..size * size).flat_map(|t| weave_albedo(t % size, t / size, size)).collect();
    let norm = rho.iter().map(|&r| (r * r) as f64).sum::<f64>().sqrt() as f32;
    let cos: Vec<f32> = (0..lights.len()).map(|i| lights.direction(i).cos_theta() as f32).collect();
    let mean_cos = cos.iter().sum::<f32>() / cos.len() as f32;
    let inv_pi = 1.0 / std::f32::consts::PI;
    let mut basis = vec![0f32; c * n];
    for (b, r) in basis[..n].iter_mut().zip(&rho) {
        *b = r / norm;
    }
    let mut weights = vec![0f32; lights.len() * c];
    for i in 0..lights.len() {
        weights[i * c] = inv_pi * (cos[i] - mean_cos) * norm;
    }
    let (eigentextures, scale_offset) = quantize(&basis, c, Quantization::F16);
    let slot = QuantizedSlot {
        mean: rho.iter().map(|r| r * inv_pi * mean_cos).collect(),
        eigentextures,
        scale_offset,
        weights,
        eigenvalues: vec![1.0; lights.len()],
    };
    let writer = EigenWriter::create(path, meta, false)?;
    for j in 0..views.len() {
        writer.write_slot(j, &slot)?;
    }
    writer.finish()?;
    Ok(())
}
