//! An eigen store's view slots packed for few texture reads (`[S03 eq. 2–5]`), on the CPU:
//! the layers and weights [`super::gpu`] uploads.
//!
//! Layout. The `c` eigentextures of a slot hold `3c` values per texel (component `k`,
//! channel `ch` at flat position `f = 3k + ch`). They are packed four values to a texel in
//! `3 · ⌈c/4⌉` RGBA layers (layer `q` holds `f = 4q … 4q+3`), so one group of four
//! components costs three reads instead of four; slot `j` owns layers `j·3G … j·3G+3G−1`
//! (`G = ⌈c/4⌉`). The stored `f16` (or `u8`, read as `Rgba8Unorm`) values are uploaded as
//! they are: the per-component scale is folded into the weights, `p'_ikj = p_ikj · s_kj`
//! (`·255` for `u8`), and the offsets into a per-(slot, light) constant
//! `b_ij = Σ_k p_ikj · o_kj`, so dequantisation costs the shader nothing. The mean `μ_j` is
//! one `Rgba16Float` layer per slot. Weights sit in a storage buffer, `G + 1` vec4 per
//! (slot, light): the scaled weights, then `(b_ij, 0, 0, 0)`. Or, packed (when the pass has
//! a constant group count and every value fits `f16`), as `f16` halves: the `4G` scaled
//! weights then `b_ij`, two halves per `u32`, `⌈(4G + 1)/8⌉` `vec4<u32>` per (slot, light),
//! so one load brings a light sample's bias and first eight weights (llvmpipe pays per
//! load, lane by lane, not per byte). Its error: ≤ 2⁻¹¹ relative per weight.
//!
//! Error of the layout: `f16` keeps 11 significant bits of each eigentexture value scaled
//! to `[−1, 1]` (≤ 2⁻¹¹ of the component's largest magnitude), `u8` ≤ half a step of
//! `(max − min)/255`; the mean in `f16` is within 2⁻¹¹ relative.

use crate::{Error, Result};
use btf_core::Sampling;
use btf_core::eigen::{EigenStore, Quantization};
use half::f16;
use std::path::Path;

/// Most rings a sampling may have on the GPU.
pub const MAX_RINGS: usize = 16;

/// A material's data, packed for upload (CPU side).
#[derive(Debug, Clone)]
pub struct MaterialData {
    /// View-slot sampling.
    pub view_sampling: Sampling,
    /// Light sampling.
    pub light_sampling: Sampling,
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Components used (`≤` stored).
    pub components: usize,
    /// Groups of four components, `G = ⌈c/4⌉`.
    pub groups: usize,
    /// Storage of the eigentextures.
    pub quantization: Quantization,
    /// Eigentexture layers (`n_views · 3G` layers of `w·h` RGBA texels, raw f16 or u8).
    pub eigen_layers: Vec<u8>,
    /// Mean layers (`n_views` layers of `w·h` RGBA f16 texels).
    pub mean_layers: Vec<f16>,
    /// Scaled weights and biases, `(n_views · n_lights) · (G + 1)` vec4.
    pub weights: Vec<[f32; 4]>,
}

impl MaterialData {
    /// Reads and packs an eigen store for `components` components (`None` = all stored).
    pub fn load(path: &Path, components: Option<usize>) -> Result<MaterialData> {
        let store = EigenStore::open(path)?;
        let meta = store.meta().clone();
        let stored = meta.components;
        let c = components.unwrap_or(stored);
        if c == 0 || c > stored {
            return Err(Error::Invalid(format!(
                "{}: {c} components asked, the store holds {stored}",
                path.display()
            )));
        }
        for (s, what) in [(&meta.btf.view_sampling, "view"), (&meta.btf.light_sampling, "light")] {
            if s.rings.len() > MAX_RINGS {
                return Err(Error::Unsupported(format!(
                    "{}: {what} sampling has more than {MAX_RINGS} rings",
                    path.display()
                )));
            }
        }
        let (w, h) = (meta.btf.width, meta.btf.height);
        let (n_v, n_l) = (meta.btf.n_views(), meta.btf.n_lights());
        let g = c.div_ceil(4);
        let q = meta.quantization;
        let elem = match q {
            Quantization::F16 => 2,
            Quantization::U8 => 1,
        };
        let texels = w * h;
        // Everything below is allocated for the whole store at once: refuse metadata that
        // claims more than the chunk files hold, or more than memory, before allocating.
        store.check_chunks()?;
        let prod = |f: &[usize]| f.iter().try_fold(1u64, |a, &b| a.checked_mul(b as u64));
        let bytes = [
            prod(&[n_v, 3 * g, texels, 4, elem]),
            prod(&[n_v, texels, 4, 2]),
            prod(&[n_v, n_l, g + 1, 16]),
        ]
        .iter()
        .try_fold(0u64, |a, b| a.checked_add((*b)?));
        btf_core::memory::check_alloc(
            bytes,
            &format!(
                "{}: the store's GPU layers ({w} x {h} texels, {n_v} view slots)",
                path.display()
            ),
        )?;
        let mut data = MaterialData {
            view_sampling: meta.btf.view_sampling.clone(),
            light_sampling: meta.btf.light_sampling.clone(),
            width: w as u32,
            height: h as u32,
            components: c,
            groups: g,
            quantization: q,
            eigen_layers: vec![0u8; n_v * 3 * g * texels * 4 * elem],
            mean_layers: vec![f16::ZERO; n_v * texels * 4],
            weights: vec![[0.0; 4]; n_v * n_l * (g + 1)],
        };
        for j in 0..n_v {
            let slot = store.read_quantized(j)?;
            data.pack_slot(j, &slot, stored, elem);
        }
        Ok(data)
    }

    fn pack_slot(
        &mut self,
        j: usize,
        slot: &btf_core::eigen::QuantizedSlot,
        stored: usize,
        elem: usize,
    ) {
        let (c, g) = (self.components, self.groups);
        let texels = (self.width * self.height) as usize;
        let n_l = self.light_sampling.len();
        let layer_bytes = texels * 4 * elem;
        for layer in 0..3 * g {
            let base = (j * 3 * g + layer) * layer_bytes;
            for lane in 0..4 {
                let f = 4 * layer + lane;
                let (k, ch) = (f / 3, f % 3);
                if k >= c {
                    continue;
                }
                for t in 0..texels {
                    let src = ((k * texels + t) * 3 + ch) * elem;
                    let dst = base + (t * 4 + lane) * elem;
                    self.eigen_layers[dst..dst + elem]
                        .copy_from_slice(&slot.eigentextures[src..src + elem]);
                }
            }
        }
        let mean = &mut self.mean_layers[j * texels * 4..(j + 1) * texels * 4];
        for t in 0..texels {
            for ch in 0..3 {
                mean[t * 4 + ch] = f16::from_f32(slot.mean[t * 3 + ch]);
            }
            mean[t * 4 + 3] = f16::ONE;
        }
        let unorm = if self.quantization == Quantization::U8 { 255.0 } else { 1.0 };
        for i in 0..n_l {
            let row = &slot.weights[i * stored..(i + 1) * stored];
            let out = &mut self.weights[(j * n_l + i) * (g + 1)..(j * n_l + i + 1) * (g + 1)];
            let mut bias = 0.0f64;
            for k in 0..c {
                let [s, o] = slot.scale_offset[k];
                out[k / 4][k % 4] = row[k] * s * unorm;
                bias += row[k] as f64 * o as f64;
            }
            out[g] = [bias as f32, 0.0, 0.0, 0.0];
        }
    }

    /// Scaled weights of (slot `j`, light `i`), group `g` (vec4), as the shader reads them.
    pub fn weight_group(&self, j: usize, i: usize, g: usize) -> [f32; 4] {
        self.weights[(j * self.light_sampling.len() + i) * (self.groups + 1) + g]
    }

    /// Bias `b_ij` (the folded dequantisation offsets).
    pub fn bias(&self, j: usize, i: usize) -> f32 {
        self.weight_group(j, i, self.groups)[0]
    }

    /// The coefficient matrix `P` of `[S03 eq. 10–12]` in this layout's units: per (slot,
    /// light) the folded bias `b_ij` and the scaled weights, so the environment's `γ*`
    /// multiplies the layers exactly as the shader reads them.
    pub fn coefficient_matrix(&self) -> btf_light::CoefficientMatrix {
        let (n_l, n_v) = (self.light_sampling.len(), self.view_sampling.len());
        btf_light::CoefficientMatrix::from_rows(n_l, n_v, self.components, |j, i, w| {
            for (k, wk) in w.iter_mut().enumerate() {
                *wk = self.weight_group(j, i, k / 4)[k % 4];
            }
            self.bias(j, i)
        })
    }

    /// The weights in the packed `f16` layout (see the module notes), or `None` when a value
    /// is beyond the `f16` range (an HDR store), which keeps the `f32` rows.
    pub fn packed_weights(&self) -> Option<Vec<[u32; 4]>> {
        let g = self.groups;
        let stride = packed_stride(g);
        let entries = self.weights.len() / (g + 1);
        let mut out = vec![[0u32; 4]; entries * stride];
        let mut halves = vec![0u16; stride * 8];
        for (e, rows) in self.weights.chunks_exact(g + 1).enumerate() {
            halves.fill(0);
            let values = rows[..g].iter().flatten().chain(std::iter::once(&rows[g][0]));
            for (h, &v) in halves.iter_mut().zip(values) {
                let x = f16::from_f32(v);
                if !x.is_finite() {
                    return None;
                }
                *h = x.to_bits();
            }
            for (k, pair) in halves.chunks_exact(2).enumerate() {
                out[e * stride + k / 4][k % 4] = u32::from(pair[0]) | (u32::from(pair[1]) << 16);
            }
        }
        Some(out)
    }

    /// Texture reads one slot costs per pixel: the mean plus three per group.
    pub fn reads_per_slot(&self) -> usize {
        1 + 3 * self.groups
    }
}

/// `vec4<u32>` per (slot, light) in the packed weight layout: `4G + 1` halves, eight per vec4.
pub fn packed_stride(groups: usize) -> usize {
    (4 * groups + 8) / 8
}
