//! `btf export`: data for other tools. `npy` writes one view slot of a BTF store as a
//! `lights × (h·w·3)` float32 array; `ubo2003` writes a BTF store as a Bonn image folder;
//! `pvf` writes an eigen store as a Bonn PVF file; `exr` writes one slot of an eigen store
//! (mean and eigentextures) as a multi-layer OpenEXR for any image tool.

use crate::guard::outln;
use anyhow::{Context, Result, bail};
use btf_capture::bonn::export::{ImageEncoding, export_pvf, export_ubo2003_with_progress};
use btf_core::eigen::EigenStore;
use btf_core::store::BtfStore;
use std::path::{Path, PathBuf};

crate::args::choices! {
    /// `btf export --format`.
    ExportFormat {
        /// One view slot of a BTF store as a `lights × (h·w·3)` float32 NumPy array (`--slot`).
        Npy = "npy",
        /// A BTF store as a Bonn UBO2003 image folder (`--image`, `--name`).
        Ubo2003 = "ubo2003",
        /// An eigen store as a Bonn PVF file.
        Pvf = "pvf",
        /// One view slot of an eigen store (mean, eigentextures) as multi-layer EXR (`--slot`).
        Exr = "exr",
    }
}

crate::args::choices! {
    /// `btf export --image`: image encoding of a ubo2003 folder.
    ImageChoice {
        /// 8-bit PNG (values scaled to the peak).
        Png = "png",
        /// 16-bit PNG (values scaled to the peak).
        Png16 = "png16",
        /// JPEG, quality 95.
        Jpg = "jpg",
        /// Linear float EXR (no scaling).
        Exr = "exr",
    }
}

/// Arguments of `btf export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// Input store (a BTF store for npy/ubo2003, an eigen store for pvf/exr).
    input: PathBuf,
    /// View slot to export (required by npy and exr).
    #[arg(long, required_if_eq_any([("format", "npy"), ("format", "exr")]))]
    slot: Option<usize>,
    /// Output format.
    #[arg(long, default_value = "npy")]
    format: ExportFormat,
    /// Image encoding of a ubo2003 folder.
    #[arg(long, default_value = "png16")]
    image: ImageChoice,
    /// Material name at the start of ubo2003 file names.
    #[arg(long, default_value = "material")]
    name: String,
    /// Output file (or folder for ubo2003).
    #[arg(short = 'o', long = "out", alias = "output")]
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
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        bail!("{}: refusing to write a non-finite value (element {i})", path.display());
    }
    btf_core::fs::write_atomic_with(path, |f| {
        f.write_all(b"\x93NUMPY\x01\x00")?;
        f.write_all(&(header.len() as u16).to_le_bytes())?;
        f.write_all(header.as_bytes())?;
        for v in data {
            f.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Writes `layers` (name, `h·w·3` linear RGB) as one multi-layer float32 EXR, atomically.
pub fn write_layers_exr(
    path: &Path,
    w: usize,
    h: usize,
    layers: &[(String, Vec<f32>)],
) -> Result<()> {
    use exr::prelude::*;
    let list: Vec<Layer<AnyChannels<FlatSamples>>> = layers
        .iter()
        .map(|(name, px)| {
            let ch = |c: usize, n: &str| {
                AnyChannel::new(
                    n,
                    FlatSamples::F32(px.iter().skip(c).step_by(3).copied().collect()),
                )
            };
            Layer::new(
                (w, h),
                LayerAttributes::named(name.as_str()),
                Encoding::FAST_LOSSLESS,
                AnyChannels::sort(vec![ch(0, "R"), ch(1, "G"), ch(2, "B")].into()),
            )
        })
        .collect();
    let image =
        Image::from_layers(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))), list);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .with_context(|| format!("cannot encode {}", path.display()))?;
    btf_core::fs::write_atomic(path, bytes.get_ref())?;
    Ok(())
}

fn slot_arg(a: &ExportArgs, n_views: usize) -> Result<usize> {
    let Some(slot) = a.slot else { bail!("--format {} needs --slot J", a.format) };
    if slot >= n_views {
        bail!(
            "--slot {} is out of range: {} has view slots 0..{}",
            slot,
            a.input.display(),
            n_views - 1
        );
    }
    Ok(slot)
}

fn open_eigen(path: &Path) -> Result<EigenStore> {
    EigenStore::open(path)
        .with_context(|| format!("cannot open {} as an eigen store", path.display()))
}

fn open_btf(path: &Path) -> Result<BtfStore> {
    BtfStore::open(path).with_context(|| format!("cannot open {}", path.display()))
}

/// Runs `btf export`.
pub fn run(a: ExportArgs) -> Result<()> {
    crate::guard::refuse_overlap(&[("-o", &a.output)], &[("input", &a.input)])?;
    let kind = match a.format.as_str() {
        "npy" => Some(btf_core::fs::NPY),
        "exr" => Some(btf_core::fs::EXR),
        "pvf" => Some(btf_core::fs::OutputKind::File { magic: b"!PVF", format: "PVF" }),
        _ => None,
    };
    if let Some(kind) = kind {
        crate::guard::check_file(&a.output, kind)?;
    }
    match a.format.as_str() {
        "npy" => {
            let store = open_btf(&a.input)?;
            let j = slot_arg(&a, store.meta().n_views())?;
            let slot = store.read_slot(j)?;
            write_npy(&a.output, slot.n_lights, slot.texel_values, &slot.data)?;
            outln!(
                "wrote view slot {j} of {} ({} lights × {} values, float32) to {}",
                a.input.display(),
                slot.n_lights,
                slot.texel_values,
                a.output.display()
            );
            Ok(())
        }
        "ubo2003" => {
            let enc = match a.image.as_str() {
                "png" => ImageEncoding::Png8,
                "png16" => ImageEncoding::Png16,
                "jpg" => ImageEncoding::Jpeg(95),
                "exr" => ImageEncoding::Exr,
                o => bail!("--image '{o}' is not png, png16, jpg or exr"),
            };
            let store = open_btf(&a.input)?;
            let scale = crate::progress::counted("export", |p| {
                export_ubo2003_with_progress(&store, &a.output, &a.name, enc, p)
            })
            .with_context(|| format!("cannot export to {}", a.output.display()))?;
            let m = store.meta();
            crate::guard::outln!(
                "wrote {} images to {} (scale {scale}, in btf-export.json)",
                m.n_views() * m.n_lights(),
                a.output.display()
            );
            Ok(())
        }
        "pvf" => {
            let store = open_eigen(&a.input)?;
            export_pvf(&store, &a.output)
                .with_context(|| format!("cannot write {}", a.output.display()))?;
            let m = store.meta();
            outln!(
                "wrote {} ({} view slots × {} components) as PVF to {}",
                a.input.display(),
                m.btf.n_views(),
                m.components,
                a.output.display()
            );
            Ok(())
        }
        "exr" => {
            let store = open_eigen(&a.input)?;
            let m = &store.meta().btf;
            let j = slot_arg(&a, m.n_views())?;
            let s = store.read_slot(j)?;
            let mut layers = vec![("mean".to_string(), s.mean.clone())];
            for k in 0..s.components {
                layers.push((format!("eigen{k:02}"), s.basis_row(k).to_vec()));
            }
            write_layers_exr(&a.output, m.width, m.height, &layers)?;
            outln!(
                "wrote view slot {j} of {} (mean + {} eigentextures, {}×{}) to {}",
                a.input.display(),
                s.components,
                m.width,
                m.height,
                a.output.display()
            );
            Ok(())
        }
        o => bail!("unsupported export format '{o}' (npy, ubo2003, pvf, exr)"),
    }
}
