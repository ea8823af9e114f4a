//! Mipmapped eigentextures and means (`mips.rs`) against a supersampled reference: a plane
//! far enough away that every pixel covers 4×4 texels of a noise material. The PCA
//! reconstruction is linear in the textures, so the mip render must match the 4×4 box
//! average of a 4×-resolution render (the reference) up to f16 rounding, while sampling the
//! base level alone aliases.

use crate::common::*;
use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_render::{Frame, RenderOptions, Scene, render_scene};
use std::path::Path;

fn noise(t: usize, salt: u32) -> f32 {
    let mut h = (t as u32).wrapping_mul(0x9e37_79b9) ^ salt.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    (h & 0xffff) as f32 / 65535.0
}

/// A `w × w` store whose mean and two eigentextures are per-texel noise (all view slots).
fn write_noise_store(dir: &Path, w: usize, q: Quantization) {
    let (views, lights) = (Sampling::ubo81(), Sampling::ubo81());
    let c = 2;
    let meta = EigenMeta {
        btf: BtfMeta::new(views.clone(), lights.clone(), w, w),
        components: c,
        quantization: q,
    };
    let writer = EigenWriter::create(&dir.join("n.eigen"), meta, false).unwrap();
    let n = w * w * 3;
    let mean: Vec<f32> = (0..n).map(|i| 0.1 + 0.3 * noise(i, 1)).collect();
    let basis: Vec<f32> = (0..c * n).map(|i| 0.05 * (noise(i, 2) - 0.5)).collect();
    let (eigentextures, scale_offset) = quantize(&basis, c, q);
    let slot = QuantizedSlot {
        mean,
        eigentextures,
        scale_offset,
        weights: (0..lights.len() * c).map(|i| 1.0 + 0.1 * (i % 3) as f32).collect(),
        eigenvalues: vec![1.0; lights.len()],
    };
    for j in 0..views.len() {
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
}

fn plane_scene(dir: &Path, size: u32, mipmaps: bool) -> Scene {
    SceneBuilder::new(dir, size)
        .mesh("plane.obj")
        .material_with(None, "n.eigen", 4.0, None)
        .ortho(Ortho { eye: [0.5, 0.5, 3.0], ..OVER_PLANE })
        .light(directional([0.0, 0.0, 1.0]))
        .effects(|e| e.mipmaps = mipmaps)
        .build()
}

/// `k × k` box average of a frame.
fn downsample(f: &Frame, k: u32) -> Vec<f32> {
    let (w, h) = (f.width / k, f.height / k);
    let mut out = vec![0f32; (w * h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            for dy in 0..k {
                for dx in 0..k {
                    let p = f.pixel(x * k + dx, y * k + dy);
                    for ch in 0..3 {
                        out[((y * w + x) * 3) as usize + ch] += p[ch] / (k * k) as f32;
                    }
                }
            }
        }
    }
    out
}

#[test]
fn mipmaps_match_a_supersampled_reference_far_better() {
    let Some(gpu) = gpu("mipmaps_match_a_supersampled_reference_far_better") else { return };
    for q in [Quantization::F16, Quantization::U8] {
        let dir = tempfile::tempdir().unwrap();
        write_noise_store(dir.path(), 32, q);
        unit_plane(dir.path(), "plane.obj", 2);
        // 128 texels across the plane: 1 texel per pixel at 128², 4×4 at 32².
        let fine =
            render_scene(&gpu, &plane_scene(dir.path(), 128, false), RenderOptions::default())
                .unwrap();
        let reference = downsample(&fine, 4);
        let with = render_scene(&gpu, &plane_scene(dir.path(), 32, true), RenderOptions::default())
            .unwrap();
        let without =
            render_scene(&gpu, &plane_scene(dir.path(), 32, false), RenderOptions::default())
                .unwrap();
        let e_with = rel_rmse(&reference, &with.rgb);
        let e_without = rel_rmse(&reference, &without.rgb);
        eprintln!(
            "{q:?}: rel. RMSE against the 4×4-supersampled reference: mipmapped {e_with:.2e}, base level only {e_without:.2e}"
        );
        if e_with > 5e-3 {
            save_comparison("mipmaps", 32, 32, &reference, &with.rgb);
        }
        // f16 levels: ≤ 2⁻¹¹ relative per value; u8 levels: half a step of 255 in each of
        // the mean (f16) and the two eigentextures' contributions.
        assert!(e_with < 5e-3, "{q:?}: mipmapped render off the reference by {e_with}");
        assert!(e_without > 10.0 * e_with, "{q:?}: no-mip render should alias ({e_without})");
    }
}
