//! Issue #24 like for like: the per-slot PCA of `btf compress` ([S03 eq. 1]) on the very
//! view slots `benches/isa_sklearn.py` hands scikit-learn, timed as scikit-learn's fits are:
//! the data already in memory, nothing read or written, so the store's codec and the eigen
//! store's encoding are not in the figure (they are in `btf compress`'s wall time).
//!
//! `fit_slots PATHS SLOT.npy…` reads each 2-D `float32` `.npy` file (one slot's light
//! images as rows, as `btf export --format npy` writes them), checks that every value is an
//! `f16` widened (so the slot holds the same numbers as the `f16` store it came from) and
//! keeps it as `f16` rows, as a mapped store's slot is held. Then for each kernel path of
//! the comma-separated `PATHS` (`scalar`, `avx2`, `avx512`, `neon`): one untimed fit, then
//! two threads (as `btf compress` runs one slot per core) each fit every slot once, c = 16,
//! `f16` eigentextures. One JSON object per path is printed: the wall seconds of those
//! `2K` fits, the seconds per slot on two cores (`wall / 2K`: all `V` slots of a store take
//! `V` times that), and the relative RMSE of
//! the stored representation over the `K` slots.
//!
//! `cargo build --release -p btf-core --example fit_slots`

use btf_core::eigen::Quantization;
use btf_core::pca::{PcaScratch, SlotRows, pca_rows_in};
use btf_core::simd::Isa;
use half::f16;
use std::error::Error;
use std::path::Path;
use std::time::Instant;

type Res<T> = Result<T, Box<dyn Error>>;

/// The light images of one slot as `f16` rows.
struct Slot {
    view: usize,
    rows: usize,
    cols: usize,
    data: Vec<f16>,
}

/// Reads a version 1 `.npy` file of a little-endian `float32` C-order 2-D array whose values
/// are all `f16` widened.
fn read_slot(path: &Path, view: usize) -> Res<Slot> {
    let bytes = std::fs::read(path)?;
    let name = path.display();
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" || bytes[6] != 1 {
        return Err(format!("{name}: not a version 1 .npy file").into());
    }
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(bytes.get(10..10 + hlen).ok_or("header past the end")?)?;
    if !header.contains("'descr': '<f4'") || !header.contains("'fortran_order': False") {
        return Err(format!("{name}: not a C-order little-endian float32 array: {header}").into());
    }
    let shape = header.split("'shape': (").nth(1).and_then(|s| s.split(')').next());
    let dims: Vec<usize> = shape
        .ok_or_else(|| format!("{name}: no shape in {header}"))?
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let [rows, cols] = dims[..] else {
        return Err(format!("{name}: shape {dims:?} is not 2-D").into());
    };
    let body = &bytes[10 + hlen..];
    // A header's shape is checked against the bytes there are before anything is sized by it.
    if rows.checked_mul(cols).and_then(|v| v.checked_mul(4)) != Some(body.len()) {
        return Err(
            format!("{name}: {} data bytes, {rows} × {cols} × 4 expected", body.len()).into()
        );
    }
    let mut data = Vec::with_capacity(rows * cols);
    for (i, v) in body.chunks_exact(4).enumerate() {
        let v = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        let h = f16::from_f32(v);
        if h.to_f32().to_bits() != v.to_bits() {
            return Err(format!("{name}: value {i} ({v}) is not an f16 widened").into());
        }
        data.push(h);
    }
    Ok(Slot { view, rows, cols, data })
}

fn rows(s: &Slot) -> SlotRows<'_, f16> {
    SlotRows { view: s.view, rows: s.data.chunks_exact(s.cols).collect(), texel_values: s.cols }
}

/// Fits every slot once on the scratch's path; returns `(Σ sse_stored, Σ energy)`.
fn fit_all(slots: &[Slot], scratch: &mut PcaScratch) -> Res<(f64, f64)> {
    let (mut sse, mut energy) = (0.0, 0.0);
    for s in slots {
        let p = pca_rows_in(&rows(s), 16, Quantization::F16, scratch, None)?;
        sse += p.sse_stored;
        energy += p.energy;
        // Hand the eigentexture bytes back as `btf compress`'s writer does.
        scratch.recycle(p.stored.eigentextures);
    }
    Ok((sse, energy))
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        return Err("usage: fit_slots PATH[,PATH…] SLOT.npy…".into());
    }
    let mut slots = Vec::new();
    for (k, f) in args[1..].iter().enumerate() {
        slots.push(read_slot(Path::new(f), k)?);
    }
    let n = slots[0].rows;
    if slots.iter().any(|s| s.rows != n || s.rows < 17) {
        return Err("every slot needs the same number of lights, at least 17".into());
    }
    for name in args[0].split(',') {
        let isa = Isa::choose(Some(name))?;
        let mut a = PcaScratch::for_isa(isa);
        fit_all(&slots[..1], &mut a)?; // untimed: first-touch of the scratch
        let mut b = PcaScratch::for_isa(isa);
        fit_all(&slots[..1], &mut b)?;
        let t = Instant::now();
        let (ra, rb) = std::thread::scope(|sc| {
            let ha = sc.spawn(|| fit_all(&slots, &mut a).map_err(|e| e.to_string()));
            let hb = sc.spawn(|| fit_all(&slots, &mut b).map_err(|e| e.to_string()));
            (ha.join(), hb.join())
        });
        let wall = t.elapsed().as_secs_f64();
        let (sse, energy) = ra.map_err(|_| "fit thread panicked")??;
        let (sse_b, _) = rb.map_err(|_| "fit thread panicked")??;
        if sse_b.to_bits() != sse.to_bits() {
            return Err(format!("{name}: the two threads' fits differ").into());
        }
        let k = slots.len();
        println!(
            "{{\"path\": \"{name}\", \"slots\": {k}, \"fits\": {}, \"wall_s\": {wall:.6}, \
             \"per_slot_two_cores_s\": {:.6}, \"rel_rmse\": {:.15e}}}",
            2 * k,
            wall / (2 * k) as f64,
            (sse / energy).sqrt()
        );
    }
    Ok(())
}
