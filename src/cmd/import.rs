//! `btf import`: Bonn database BTFs into our stores. `ubo2003` reads per-view folders (or a
//! zip) of per-(view, light) images; `ubo2014` reads the binary `.btf` files (FMF, DFMF, PVF,
//! BDI) into a BTF store, or a PVF file straight into an eigen store with `--eigen`.

use anyhow::{Context, Result};
use btf_capture::bonn::{ubo2003, ubo2014};
use btf_core::eigen::Quantization;
use std::path::PathBuf;
use std::time::Instant;

/// Formats `btf import` reads.
#[derive(clap::Subcommand)]
pub enum ImportCmd {
    /// A UBO2003/ATRIUM folder or zip of images named with tl/pl/tv/pv angle tags.
    Ubo2003(Ubo2003Args),
    /// A UBO2014 binary `.btf` file (FMF, DFMF, PVF or BDI).
    Ubo2014(Ubo2014Args),
}

/// Arguments of `btf import ubo2003`.
#[derive(clap::Args)]
pub struct Ubo2003Args {
    /// Folder (searched recursively) or zip of JPEG/PNG/BMP/HDR/EXR images.
    input: PathBuf,
    /// Output BTF store.
    #[arg(short = 'o', long = "out", alias = "output")]
    output: PathBuf,
    /// Element type of the store.
    #[arg(long, default_value = "f32")]
    dtype: crate::args::Dtype,
}

/// Arguments of `btf import ubo2014`.
#[derive(clap::Args)]
pub struct Ubo2014Args {
    /// The `.btf` file.
    input: PathBuf,
    /// Output store (a BTF store, or an eigen store with `--eigen`).
    #[arg(short = 'o', long = "out", alias = "output")]
    output: PathBuf,
    /// Write a PVF file's per-view eigentextures straight into an eigen store.
    #[arg(long)]
    eigen: bool,
    /// Eigentexture storage for `--eigen`.
    #[arg(long, alias = "quantize", default_value = "f16")]
    quantization: crate::args::Quantization,
    /// Element type of a BTF store.
    #[arg(long, default_value = "f32")]
    dtype: crate::args::Dtype,
    /// Memory for BDI view buffers, MiB (BDI is read once per group of views that fits).
    #[arg(long, default_value_t = 1024)]
    memory_mib: u64,
}

/// Runs `btf import`.
pub fn run(cmd: ImportCmd) -> Result<()> {
    let start = Instant::now();
    match cmd {
        ImportCmd::Ubo2003(a) => {
            crate::guard::refuse_overlap(&[("-o", &a.output)], &[("input", &a.input)])?;
            let dtype = a.dtype.dtype();
            let rep = crate::guard::no_partial_on_error(&a.output, || {
                crate::progress::counted("import", |p| {
                    ubo2003::import_with_progress(&a.input, &a.output, dtype, p)
                })
                .with_context(|| format!("cannot import {}", a.input.display()))
            })?;
            crate::guard::outln!(
                "imported {} images ({} views x {} lights, {}x{} texels, scale {}) into {} in {:.2} s",
                rep.images,
                rep.samplings.0,
                rep.samplings.1,
                rep.size.0,
                rep.size.1,
                rep.scale,
                a.output.display(),
                start.elapsed().as_secs_f64()
            );
        }
        ImportCmd::Ubo2014(a) => {
            crate::guard::refuse_overlap(&[("-o", &a.output)], &[("input", &a.input)])?;
            let rep = crate::guard::no_partial_on_error(&a.output, || {
                if a.eigen {
                    let q: Quantization = a.quantization.quantization();
                    ubo2014::import_pvf_to_eigen(&a.input, &a.output, q)
                } else {
                    ubo2014::import_to_store(
                        &a.input,
                        &a.output,
                        a.dtype.dtype(),
                        a.memory_mib << 20,
                    )
                }
                .with_context(|| format!("cannot import {}", a.input.display()))
            })?;
            crate::guard::outln!(
                "imported {} ({} {}, {} views x {} lights, {}x{} texels) into {} in {:.2} s",
                a.input.display(),
                rep.signature,
                if a.eigen { "eigen slots" } else { "images" },
                rep.samplings.0,
                rep.samplings.1,
                rep.size.0,
                rep.size.1,
                a.output.display(),
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}
