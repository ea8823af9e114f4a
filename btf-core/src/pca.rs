//! Principal component analysis of one view slot ([S03 eq. 1]).
//!
//! The `n` light images of slot `j` are the rows of `X` (`n × 3hw`). With so few rows the
//! snapshot method is the efficient one: accumulate the small Gram matrix `G = X̃X̃ᵀ` of the
//! images centred on their mean `μ` (in `f64`, or for `f16` data in `f32` lanes, see
//! [`GramPrecision`]), eigen-solve it in `f64`, and lift each
//! eigenvector `v_k` to an eigentexture `B_k = X̃ᵀv_k / √λ_k` of unit norm. The data is never
//! centred in memory: `G = C·YYᵀ·C` and `B = (C·V)ᵀY` for `Y = X − 1x_0ᵀ` (shifted by the
//! first image: exactly in `f64`, rounded to nearest in `f32` lanes) and `C = I − 11ᵀ/n`. Three streaming passes read the
//! slot, block by block of columns: the Gram matrix (with mean, energy and peak), the
//! eigentextures, and the correction terms of the stored basis. Signs are fixed so that
//! the largest-magnitude entry of every `B_k` is positive. The eigentextures are then
//! quantised for storage and the weights `p_ik` are the least-squares coefficients of each
//! centred image on the *stored* basis, so quantisation costs as little as it can. By
//! Eckart–Young, with the exact basis the squared error of the slot equals the sum of the
//! discarded eigenvalues; both are reported.

use crate::eigen::{Quantization, QuantizedSlot, dequantize, quantize};
use crate::gemm::{Mat, dgemm};
use crate::kernels::{
    Block, Block32, DotAcc, GramAcc32, LANES, LIFT_COMPONENTS, LoadTarget, Texel, lift_rows32_with,
    load_shifted_with, prefetch_rows,
};
use crate::simd::Isa;
use crate::store::SlotData;
use crate::{Error, Result};
use nalgebra::{DMatrix, SymmetricEigen};

mod fused;

/// Columns per block in the streaming passes: 81 rows of them fit the L2 cache in `f64`,
/// and each row's 4 KB of `f32` input are one long run for the hardware prefetcher.
const BLOCK: usize = 1024;
/// Bytes of each row checksummed at a time in the first pass (a multiple of a block's
/// piece of a row for `f32` and `f16`).
const CRC_SPAN_BYTES: usize = 8192;

/// The arithmetic of the first pass's Gram matrix `YYᵀ` (`Y = X − 1x₀ᵀ`).
///
/// - `F64`: `Y` exact in `f64` and every product and sum in `f64` ([`DotAcc`]): the
///   eigenvalues to `f64` rounding (within `10⁻⁹` of the largest in the tests).
/// - `F32`: `Y` rounded to `f32`, each entry's products summed in one `f32` lane over
///   chunks of 64 columns, the chunks' sums in `f64` ([`GramAcc32`]), at twice the lanes a
///   register and half the bytes a block. Every entry is then within `ε·Σ_t |y_it||y_jt|`
///   of the exact one with `ε = (CHUNK32 + 2)·2⁻²⁴ ≈ 3.9·10⁻⁶` (64 rounded steps a chunk,
///   the two roundings of `y`), so by Weyl's inequality every eigenvalue of the centred matrix
///   within `ε·tr(YYᵀ)`: for `f16` data, whose values carry 11 significant bits (a relative
///   precision of `2⁻¹¹ ≈ 4.9·10⁻⁴`), an error 125 times below the data's own. Components
///   whose eigenvalue is below that bound are not counted as effective.
/// - `Auto` (the default): `F32` for `f16` data, `F64` for `f32` data.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum GramPrecision {
    /// `F32` for `f16` data, `F64` for `f32` data.
    #[default]
    Auto,
    /// In `f64`.
    F64,
    /// In `f32` within chunks of 64 columns, `f64` across them.
    F32,
}

impl GramPrecision {
    /// What `self` means for data of `f16` (`half`) or `f32` values: `F64` or `F32`.
    pub fn resolve(self, half: bool) -> GramPrecision {
        match self {
            GramPrecision::Auto if half => GramPrecision::F32,
            GramPrecision::Auto => GramPrecision::F64,
            g => g,
        }
    }

    /// `"auto"`, `"f64"` or `"f32"`.
    pub fn name(self) -> &'static str {
        match self {
            GramPrecision::Auto => "auto",
            GramPrecision::F64 => "f64",
            GramPrecision::F32 => "f32",
        }
    }
}

/// The `ε` of [`GramPrecision::F32`]: a bound on each entry's relative error.
pub const GRAM32_EPS: f64 = (crate::kernels::CHUNK32 + 2) as f64 / (1u64 << 24) as f64;

/// Result of the PCA of one slot.
#[derive(Debug, Clone)]
pub struct SlotPca {
    /// What goes into the eigen store.
    pub stored: QuantizedSlot,
    /// Components with a non-zero eigenvalue among those kept.
    pub effective_components: usize,
    /// Squared error of the exact (`f64`) `c`-component reconstruction, measured from the data.
    pub sse: f64,
    /// Squared error of the reconstruction from the stored (quantised) basis and weights.
    pub sse_stored: f64,
    /// Sum of the discarded eigenvalues (Eckart–Young: equals `sse`).
    pub discarded_eigen_sum: f64,
    /// `Σ_i ‖x_i‖²` of the uncentred images.
    pub energy: f64,
    /// Largest input value.
    pub peak: f32,
}

/// Largest number of components a slot of `n_lights` images supports (the centred data has
/// rank at most `n_lights − 1`), never less than one.
pub fn max_components(n_lights: usize) -> usize {
    n_lights.saturating_sub(1).max(1)
}

/// Computes the PCA of `slot` with `components` components (already clamped by the caller
/// to `1..=max_components`), quantising the basis with `quantization`.
pub fn pca_slot(slot: &SlotData, components: usize, quantization: Quantization) -> Result<SlotPca> {
    pca_slot_in(slot, components, quantization, &mut PcaScratch::default())
}

/// Reusable working memory of [`pca_slot_in`] (the `f64` eigentextures, 25 MB for 16
/// components at 256²): a caller that compresses slot after slot keeps one per thread, so
/// none of it is allocated, faulted in or cleared again.
#[derive(Debug, Default)]
pub struct PcaScratch {
    basis: Vec<f64>,
    /// Bytes for the next slot's stored eigentextures (see [`PcaScratch::recycle`]).
    raw: Vec<u8>,
    /// The passes' blocks, kept so that their pages stay mapped from slot to slot.
    blocks: fused::Blocks,
    /// The kernel path; `None`: the one `BTF_SIMD` asks for ([`Isa::from_env`]).
    isa: Option<Isa>,
    /// The Gram matrix's arithmetic.
    gram: GramPrecision,
}

impl PcaScratch {
    /// Working memory whose PCA runs on the kernel path `isa` (which this CPU must run),
    /// whatever `BTF_SIMD` says: how tests and benchmarks compare the paths in one process.
    pub fn for_isa(isa: Isa) -> Self {
        PcaScratch { isa: Some(isa), ..PcaScratch::default() }
    }

    /// The same, with the Gram matrix in `gram`'s arithmetic.
    pub fn with_gram(self, gram: GramPrecision) -> Self {
        PcaScratch { gram, ..self }
    }

    /// Hands back the eigentexture bytes of a slot already written, so that the next slot
    /// forms its own in them (6 MB at 256², c = 16: a fresh allocation would be faulted in
    /// page by page and its release would flush the other core's TLB).
    pub fn recycle(&mut self, eigentexture_bytes: Vec<u8>) {
        self.raw = eigentexture_bytes;
    }
}

/// The light images of one view slot as row slices of `f32` or `f16` values: of a
/// [`SlotData`] in memory, or of a store's mapped chunks ([`crate::mapped::MappedSlot`]).
#[derive(Debug, Clone)]
pub struct SlotRows<'a, T = f32> {
    /// View slot index.
    pub view: usize,
    /// One row of `texel_values` values per light.
    pub rows: Vec<&'a [T]>,
    /// Floats per row.
    pub texel_values: usize,
}

impl<'a> SlotRows<'a> {
    /// The rows of a slot held in memory.
    pub fn of(slot: &'a SlotData) -> Self {
        let m = slot.texel_values;
        let rows = (0..slot.n_lights).map(|i| &slot.data[i * m..(i + 1) * m]).collect();
        SlotRows { view: slot.view, rows, texel_values: m }
    }
}

/// Checks the CRC32C of every row (light `l` at index `l`) that the first pass computed.
pub type ChecksumCheck<'a> = &'a dyn Fn(&[u32]) -> Result<()>;

/// [`pca_slot`] with caller-owned working memory.
pub fn pca_slot_in(
    slot: &SlotData,
    components: usize,
    quantization: Quantization,
    scratch: &mut PcaScratch,
) -> Result<SlotPca> {
    let (n, m) = (slot.n_lights, slot.texel_values);
    if slot.data.len() != n * m {
        return Err(Error::Invalid(format!(
            "slot holds {} values, {n}×{m} expected",
            slot.data.len()
        )));
    }
    pca_rows_in(&SlotRows::of(slot), components, quantization, scratch, None)
}

/// [`pca_slot_in`] on row slices (of `f32` or `f16` values, widened to `f64` exactly as
/// they are loaded). With `checksums`, the first pass also computes the CRC32C of every
/// row's bytes on the way (the bytes it reads anyway) and hands them to `checksums` before
/// anything is derived from the data.
pub fn pca_rows_in<T: Texel>(
    slot: &SlotRows<'_, T>,
    components: usize,
    quantization: Quantization,
    scratch: &mut PcaScratch,
    checksums: Option<ChecksumCheck<'_>>,
) -> Result<SlotPca> {
    let (n, m) = (slot.rows.len(), slot.texel_values);
    let c = components;
    if c == 0 || c > n {
        return Err(Error::Invalid(format!("components {c} not in 1..={n}")));
    }
    if m == 0 {
        return Err(Error::Invalid(format!("view slot {}: images have no values", slot.view)));
    }
    if let Some(l) = slot.rows.iter().position(|r| r.len() != m) {
        return Err(Error::Invalid(format!(
            "view slot {}, light {l}: {} values, {m} expected",
            slot.view,
            slot.rows[l].len()
        )));
    }
    let isa = match scratch.isa {
        Some(isa) if !isa.supported() => {
            return Err(Error::Unsupported(format!("the {isa} kernels cannot run on this CPU")));
        }
        Some(isa) => isa,
        None => Isa::from_env()?,
    };
    // Pass 1: the centred Gram matrix, mean, energy and peak (and the checksums).
    let single = scratch.gram.resolve(T::HALF) == GramPrecision::F32;
    let first = if single {
        first_pass(slot, checksums.is_some(), &mut scratch.blocks.y32, isa)?
    } else {
        first_pass(slot, checksums.is_some(), &mut scratch.blocks.y, isa)?
    };
    if let Some(check) = checksums {
        check(&first.crcs)?;
    }
    let gram = &first.gram;
    let eig = SymmetricEigen::new(DMatrix::from_row_slice(n, n, gram));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let eigenvalues: Vec<f64> = order.iter().map(|&k| eig.eigenvalues[k].max(0.0)).collect();
    let trace: f64 = (0..n).map(|i| gram[i * n + i]).sum();
    // Eigenvalues below the Gram matrix's rounding are not components.
    let tol = (eigenvalues[0].max(0.0) * 1e-12 * n as f64).max(first.error_bound);
    let effective = eigenvalues[..c].iter().filter(|&&l| l > tol && l > 0.0).count();
    // Lifting matrix: column k = v_k / √λ_k (zero for rank-deficient components).
    let mut lift = vec![0f64; n * c];
    for k in 0..effective {
        let s = 1.0 / eigenvalues[k].sqrt();
        for i in 0..n {
            lift[i * c + k] = eig.eigenvectors[(i, order[k])] * s;
        }
    }

    // Passes 2 and 3: the eigentextures B = liftᵀX̃ with deterministic signs, their stored
    // (quantised) form S = B + E, and what the weights on S need from the data: X̃Eᵀ and
    // SSᵀ. For f16 both come from one sweep ([`fused`]); 8-bit scales need all of B first.
    let (raw, scale_offset, cross, bgram) = match quantization {
        Quantization::F16 => {
            let raw = std::mem::take(&mut scratch.raw);
            let blocks = &mut scratch.blocks;
            let f =
                fused::lift_store_f16(&slot.rows, m, (&mut lift, c), effective, raw, blocks, isa);
            (f.raw, f.scale_offset, f.cross, f.bgram)
        }
        Quantization::U8 => {
            let basis =
                lift_pass(slot, &mut lift, c, effective, std::mem::take(&mut scratch.basis), isa);
            let (raw, scale_offset) = quantize(&basis.rows_f32(), c, quantization);
            let stored_basis = dequantize(&raw, &scale_offset, quantization);
            let (cross, bgram) = stored_pass(slot, &basis, &stored_basis, c, isa);
            scratch.basis = basis.data;
            (raw, scale_offset, cross, bgram)
        }
    };

    // The exact basis is B = liftᵀX̃, so its projections X̃Bᵀ = G·lift and its Gram matrix
    // BBᵀ = liftᵀ·G·lift follow from the small Gram matrix alone, in f64; those of the
    // stored basis are X̃Sᵀ = G·lift + X̃Eᵀ.
    let mut proj_exact = vec![0f64; n * c];
    dgemm(1.0, Mat::new(gram, n, n), Mat::new(&lift, n, c), 0.0, &mut proj_exact, c);
    let mut bgram_exact = vec![0f64; c * c];
    dgemm(1.0, Mat::new(&lift, n, c).t(), Mat::new(&proj_exact, n, c), 0.0, &mut bgram_exact, c);
    let mut proj = proj_exact.clone();
    for k in 0..c {
        let row = &cross[k * n..(k + 1) * n];
        let mean = row.iter().sum::<f64>() / n as f64;
        for i in 0..n {
            proj[i * c + k] += row[i] - mean;
        }
    }
    let (sse, _) = least_squares(&proj_exact, &bgram_exact, gram, n, c);
    let (sse_stored, weights) = least_squares(&proj, &bgram, gram, n, c);
    let discarded_eigen_sum = (trace - eigenvalues[..effective].iter().sum::<f64>()).max(0.0);

    for (l, w) in weights.chunks(c).enumerate() {
        crate::store::check_finite(w, slot.view, l, 0)?;
    }
    Ok(SlotPca {
        stored: QuantizedSlot {
            mean: first.mean,
            eigentextures: raw,
            scale_offset,
            weights,
            eigenvalues,
        },
        effective_components: effective,
        sse,
        sse_stored,
        discarded_eigen_sum,
        energy: first.energy,
        peak: first.peak,
    })
}

/// What the first pass over a slot yields.
struct FirstPass {
    /// `X̃X̃ᵀ` (`n × n`, row-major) of the centred images.
    gram: Vec<f64>,
    /// The mean image `μ`.
    mean: Vec<f32>,
    /// `Σ_i ‖x_i‖²`.
    energy: f64,
    /// Largest value.
    peak: f32,
    /// CRC32C of every row's bytes, when asked for.
    crcs: Vec<u32>,
    /// A bound on the error of every eigenvalue of `gram` from the rounding of its entries
    /// beyond `f64`'s ([`GramPrecision::F32`]; zero in `f64`).
    error_bound: f64,
}

/// The Gram matrix accumulators of the first pass, over its block type.
trait FirstGram: LoadTarget {
    /// The accumulator for `n` rows.
    type Acc;
    fn acc(n: usize) -> Self::Acc;
    fn add(acc: &mut Self::Acc, blk: &Self, isa: Isa);
    /// `out[i·n + j] = Σ y_i·y_j` for `j ≥ i`, and the bound on its eigenvalues' error.
    fn finish(acc: &Self::Acc, out: &mut [f64], n: usize) -> f64;
}

impl FirstGram for Block {
    type Acc = DotAcc;
    fn acc(n: usize) -> DotAcc {
        DotAcc::new(n, n, true)
    }
    fn add(acc: &mut DotAcc, blk: &Block, isa: Isa) {
        acc.add_with(blk, blk, isa);
    }
    fn finish(acc: &DotAcc, out: &mut [f64], n: usize) -> f64 {
        acc.finish(out, n);
        0.0
    }
}

impl FirstGram for Block32 {
    type Acc = GramAcc32;
    fn acc(n: usize) -> GramAcc32 {
        GramAcc32::new(n)
    }
    fn add(acc: &mut GramAcc32, blk: &Block32, isa: Isa) {
        acc.add_with(blk, isa);
    }
    fn finish(acc: &GramAcc32, out: &mut [f64], n: usize) -> f64 {
        acc.finish(out, n);
        // ‖δG‖₂ ≤ ε·‖|Y||Y|ᵀ‖₂ ≤ ε·tr(YYᵀ); the centring C·δG·C is no larger.
        GRAM32_EPS * (0..n).map(|i| out[i * n + i]).sum::<f64>()
    }
}

/// The Gram matrix of the centred images, without centring them: any shift `s` gives
/// `X̃ = C·(X − 1sᵀ)` with `C = I − 11ᵀ/n`, so `X̃X̃ᵀ = C·YYᵀ·C` for `Y = X − 1sᵀ`. With
/// `s = x_0` (the first light image) `Y` is exact in `f64` and of the data's spread, not its
/// mean, so no precision is lost to a large mean.
fn first_pass<T: Texel, B: FirstGram>(
    slot: &SlotRows<'_, T>,
    with_crc: bool,
    blk: &mut B,
    isa: Isa,
) -> Result<FirstPass> {
    let (n, m, x) = (slot.rows.len(), slot.texel_values, &slot.rows[..]);
    let shift = x[0];
    let mut crcs = vec![0u32; if with_crc { n } else { 0 }];
    let mut gram = B::acc(n);
    let mut mean = vec![0f32; m];
    let (mut energy, mut peak) = (0f64, f32::MIN);
    let mut colsum = vec![0f64; BLOCK];
    for c0 in (0..m).step_by(BLOCK) {
        let w = BLOCK.min(m - c0);
        colsum[..w].fill(0.0);
        // The checksum reads the next 8 KB of every row (one to four blocks' worth) into
        // the cache just before the loads do: longer runs than a block's piece of a row
        // amortise the three-stream CRC32C's cost per call.
        let span = CRC_SPAN_BYTES / size_of::<T>();
        if c0 % span == 0 {
            for (crc, row) in crcs.iter_mut().zip(x) {
                let piece = &row[c0..(c0 + span).min(m)];
                *crc = crc32c::crc32c_append(*crc, bytemuck::cast_slice(piece));
            }
        }
        let st = load_shifted_with(x, c0, w, Some(shift), blk, Some(&mut colsum), isa)
            .expect("statistics were asked for");
        if !st.finite {
            for (i, row) in x.iter().enumerate() {
                let row: Vec<f32> = row.iter().map(|v| v.widen()).collect();
                crate::store::check_finite(&row, slot.view, i, 0)?;
            }
        }
        energy += st.energy;
        peak = peak.max(st.peak);
        prefetch_rows(x, c0 + w, BLOCK);
        B::add(&mut gram, blk, isa);
        for t in 0..w {
            mean[c0 + t] = (shift[c0 + t].widen() as f64 + colsum[t] / n as f64) as f32;
        }
    }
    let mut g = vec![0f64; n * n];
    let error_bound = B::finish(&gram, &mut g, n);
    for i in 0..n {
        for j in 0..i {
            g[i * n + j] = g[j * n + i];
        }
    }
    // C·G·C: subtract row and column means, add back the overall mean.
    let row_mean: Vec<f64> = g.chunks(n).map(|r| r.iter().sum::<f64>() / n as f64).collect();
    let all_mean = row_mean.iter().sum::<f64>() / n as f64;
    for i in 0..n {
        for j in 0..n {
            g[i * n + j] += all_mean - row_mean[i] - row_mean[j];
        }
    }
    Ok(FirstPass { gram: g, mean, energy, peak, crcs, error_bound })
}

/// Eigentextures in `f64`, `cp` rows (a multiple of the lift tile) of `mp` columns (a
/// multiple of the SIMD width), zero past the `c` rows and `m` columns in use.
struct Basis {
    data: Vec<f64>,
    c: usize,
    m: usize,
    mp: usize,
}

impl Basis {
    fn rows_f32(&self) -> Vec<f32> {
        let mut out = vec![0f32; self.c * self.m];
        for (k, o) in out.chunks_exact_mut(self.m.max(1)).enumerate() {
            let src = &self.data[k * self.mp..k * self.mp + self.m];
            o.iter_mut().zip(src).for_each(|(o, &v)| *o = v as f32);
        }
        out
    }
}

/// Largest and smallest value of `row` (zero if it is empty or has none above/below zero),
/// in a form that vectorises.
fn max_min(row: &[f64], hi: &mut f64, lo: &mut f64) {
    let (mut h, mut l) = ([*hi; LANES], [*lo; LANES]);
    let chunks = row.chunks_exact(LANES);
    for &v in chunks.remainder() {
        h[0] = if v > h[0] { v } else { h[0] };
        l[0] = if v < l[0] { v } else { l[0] };
    }
    for ch in chunks {
        for k in 0..LANES {
            h[k] = if ch[k] > h[k] { ch[k] } else { h[k] };
            l[k] = if ch[k] < l[k] { ch[k] } else { l[k] };
        }
    }
    *hi = h.iter().copied().fold(*hi, f64::max);
    *lo = l.iter().copied().fold(*lo, f64::min);
}

/// `B = liftᵀX̃ = (C·lift)ᵀY` (`C·lift` has zero column sums, so the shift cancels), then
/// the sign of each eigentexture (and its lift column) fixed so that its largest-magnitude
/// entry is positive.
fn lift_pass<T: Texel>(
    slot: &SlotRows<'_, T>,
    lift: &mut [f64],
    c: usize,
    effective: usize,
    mut data: Vec<f64>,
    isa: Isa,
) -> Basis {
    let (n, m, x) = (slot.rows.len(), slot.texel_values, &slot.rows[..]);
    let cp = c.div_ceil(LIFT_COMPONENTS) * LIFT_COMPONENTS;
    let mp = m.div_ceil(LANES) * LANES;
    let coef = centred_coef(lift, n, c, cp);
    // Every value is written by the lift below: no need to clear a reused buffer.
    data.resize(cp * mp, 0.0);
    let mut blk = Block32::default();
    let (mut hi, mut lo) = (vec![0f64; c], vec![0f64; c]);
    // The lift writes whole rows of the block's pitch: into `tmp`, then `w` columns on.
    let mut tmp = Vec::new();
    for c0 in (0..m).step_by(BLOCK) {
        let w = BLOCK.min(m - c0);
        // The images widened exactly; the centred coefficients give coefᵀX = coefᵀY.
        blk.widen_from_with(x, c0, w, isa);
        tmp.resize(cp * blk.stride, 0.0);
        lift_rows32_with(&blk, &coef, cp, &mut tmp, blk.stride, 0, isa);
        for k in 0..cp {
            let from = &tmp[k * blk.stride..k * blk.stride + w];
            data[k * mp + c0..k * mp + c0 + w].copy_from_slice(from);
        }
        for k in 0..effective {
            max_min(&data[k * mp + c0..k * mp + c0 + w], &mut hi[k], &mut lo[k]);
        }
    }
    for k in 0..effective {
        let row = &mut data[k * mp..k * mp + m];
        // The entry of largest magnitude; on a tie of ±, the first one of them.
        let big = if hi[k] != -lo[k] {
            if hi[k] > -lo[k] { hi[k] } else { lo[k] }
        } else {
            row.iter().copied().fold(0f64, |a, v| if v.abs() > a.abs() { v } else { a })
        };
        if big < 0.0 {
            row.iter_mut().for_each(|v| *v = -*v);
            for i in 0..n {
                lift[i * c + k] = -lift[i * c + k];
            }
        }
    }
    Basis { data, c, m, mp }
}

/// For the stored basis `S` (`c × m`) and the exact one `B`: `E·Yᵀ` (`c × n`, with
/// `E = S − B`; centring it gives `X̃Eᵀ`, transposed) and `SSᵀ` (`c × c`), in `f64`.
fn stored_pass<T: Texel>(
    slot: &SlotRows<'_, T>,
    basis: &Basis,
    stored: &[f32],
    c: usize,
    isa: Isa,
) -> (Vec<f64>, Vec<f64>) {
    let (n, m, x) = (slot.rows.len(), slot.texel_values, &slot.rows[..]);
    let stored: Vec<&[f32]> = stored.chunks_exact(m).collect();
    let mp = basis.mp;
    let (mut cross_acc, mut bgram_acc) = (DotAcc::new(c, n, false), DotAcc::new(c, c, true));
    let (mut yb, mut sb, mut eb) = (Block::default(), Block::default(), Block::default());
    for c0 in (0..m).step_by(BLOCK) {
        let w = BLOCK.min(m - c0);
        load_shifted_with(x, c0, w, Some(x[0]), &mut yb, None, isa);
        load_shifted_with(&stored, c0, w, None, &mut sb, None, isa);
        eb.shape(c, w);
        for k in 0..c {
            let b = &basis.data[k * mp + c0..k * mp + c0 + w];
            let s = &sb.data[k * sb.stride..k * sb.stride + w];
            for ((e, &s), &b) in eb.row_mut(k).iter_mut().zip(s).zip(b) {
                *e = s - b;
            }
        }
        cross_acc.add_with(&eb, &yb, isa);
        bgram_acc.add_with(&sb, &sb, isa);
    }
    finish_correction(&cross_acc, &bgram_acc, c, n)
}

/// `E·Yᵀ` (`c × n`) and the full, symmetric `SSᵀ` (`c × c`) from their accumulators.
fn finish_correction(cross: &DotAcc, bgram: &DotAcc, c: usize, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut cross_out = vec![0f64; c * n];
    cross.finish(&mut cross_out, n);
    (cross_out, finish_symmetric(bgram, c))
}

/// The full `c × c` matrix of a symmetric product accumulated as its upper triangle.
fn finish_symmetric(upper: &DotAcc, c: usize) -> Vec<f64> {
    let mut out = vec![0f64; c * c];
    upper.finish(&mut out, c);
    for i in 0..c {
        for j in 0..i {
            out[i * c + j] = out[j * c + i];
        }
    }
    out
}

/// The lift's columns centred (`C·lift`, zero column sums, so the images' shift cancels),
/// `cp` columns wide (zero past `c`).
fn centred_coef(lift: &[f64], n: usize, c: usize, cp: usize) -> Vec<f64> {
    let mut coef = vec![0f64; n * cp];
    for k in 0..c {
        let mean = (0..n).map(|i| lift[i * c + k]).sum::<f64>() / n as f64;
        for i in 0..n {
            coef[i * cp + k] = lift[i * c + k] - mean;
        }
    }
    coef
}

/// Least-squares weights of each centred image on a basis, given the projections `q_i`
/// (`n × c`) and the basis's Gram matrix `M` (`c × c`), and the resulting total squared
/// error `Σ_i ‖x̃_i‖² − q_iᵀ M⁻¹ q_i`.
fn least_squares(proj: &[f64], bgram: &[f64], gram: &[f64], n: usize, c: usize) -> (f64, Vec<f32>) {
    let m = DMatrix::from_fn(c, c, |a, b| bgram[a * c + b]);
    // Zero components (rank deficiency) make M singular: solve on the non-zero ones.
    let active: Vec<usize> = (0..c).filter(|&k| m[(k, k)] > 0.0).collect();
    let ma = DMatrix::from_fn(active.len(), active.len(), |a, b| m[(active[a], active[b])]);
    let chol = ma.cholesky();
    let mut sse = 0f64;
    let mut weights = vec![0f32; n * c];
    for i in 0..n {
        let q = nalgebra::DVector::from_fn(active.len(), |a, _| proj[i * c + active[a]]);
        let p = match &chol {
            Some(ch) => ch.solve(&q),
            None => q.clone(),
        };
        sse += (gram[i * n + i] - q.dot(&p)).max(0.0);
        for (a, &k) in active.iter().enumerate() {
            weights[i * c + k] = p[a] as f32;
        }
    }
    (sse, weights)
}

#[cfg(test)]
mod tests;
