//! `btf export`: data for other tools. `--format npy` writes one view slot as a
//! `lights × (h·w·3)` float32 array, so numpy users can check our numbers.

use anyhow::{Context, Result, bail};
use btf_core::store::BtfStore;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `btf export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// Input BTF store.
    input: PathBuf,
    /// View slot to export.
    #[arg(long)]
    slot: usize,
    /// Output format (npy).
    #[arg(long, default_value = "npy")]
    format: String,
    /// Output file.
    #[arg(short = 'o', long)]
    output: PathBuf,
}

/// Writes a 2-D little-endian float32 array in NumPy's `.npy` format (version 1.0).
pub fn write_npy(path: &Path, rows: usize, cols: usize, data: &[f32]) -> Result<()> {
    assert_eq!(data.len(), rows * cols);
    let mut header =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is padded to a multiple of 64.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.div_ceil(64) * 64 - total));
    header.push('\n');
    let tmp = path
        .with_file_name(format!(".{}.tmp", path.file_name().unwrap_or_default().to_string_lossy()));
    let mut f = std::io::BufWriter::new(
        std::fs::File::create(&tmp).with_context(|| format!("cannot write {}", tmp.display()))?,
    );
    f.write_all(b"\x93NUMPY\x01\x00")?;
    f.write_all(&(header.len() as u16).to_le_bytes())?;
    f.write_all(header.as_bytes())?;
    for v in data {
        f.write_all(&v.to_le_bytes())?;
    }
    f.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    std::fs::rename(&tmp, path)
        .with_context(|| format!("cannot move output into place at {}", path.display()))
}

/// Runs `btf export`.
pub fn run(a: ExportArgs) -> Result<()> {
    if a.format != "npy" {
        bail!("unsupported export format '{}' (this version writes: npy)", a.format);
    }
    let store =
        BtfStore::open(&a.input).with_context(|| format!("cannot open {}", a.input.display()))?;
    let n_views = store.meta().n_views();
    if a.slot >= n_views {
        bail!(
            "--slot {} is out of range: {} has view slots 0..{}",
            a.slot,
            a.input.display(),
            n_views - 1
        );
    }
    let slot = store.read_slot(a.slot)?;
    write_npy(&a.output, slot.n_lights, slot.texel_values, &slot.data)
}
