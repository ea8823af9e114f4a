//! Rewrites a BTF store with another element type, e.g. the `f32` benchmark store as `f16`
//! (half the bytes; the natural type of HDR normtextures): `cargo run --release -p btf-core
//! --example convert_store -- IN.btf OUT.btf f16 [blosc|bloscN|zstd|none]`. Values are
//! rounded to nearest; one beyond the `f16` range is refused with its image named (the
//! writer's check). The optional last argument chooses the chunks' codec: `blosc` (the
//! default, as every writer: byte shuffle + zstd, `Compression::DEFAULT`), `blosc0`‥`blosc9`
//! (the same at another c-blosc level), `zstd` (zstd level 3 alone, the stores of issue #25
//! before blosc), `none` (the uncompressed layout the PCA maps in place; BENCHMARKS.md,
//! issue #24/#25).

use btf_core::store::{BtfStore, BtfWriter};
use btf_core::zarr::{Compression, DType};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if !(4..=5).contains(&args.len()) {
        return Err("usage: convert_store IN.btf OUT.btf f16|f32 [blosc|bloscN|zstd|none]".into());
    }
    let compression = match args.get(4).map(String::as_str) {
        None | Some("blosc") => Compression::DEFAULT,
        Some("zstd") => Compression::ZSTD,
        Some("none") => Compression::None,
        Some(o) => match o.strip_prefix("blosc").and_then(|l| l.parse::<u8>().ok()) {
            Some(clevel @ 0..=9) => Compression::Blosc { clevel, shuffle: true },
            _ => {
                return Err(format!("codec '{o}' is not blosc, blosc0‥blosc9, zstd or none").into());
            }
        },
    };
    let dtype = match args[3].as_str() {
        "f16" => DType::F16,
        "f32" => DType::F32,
        o => return Err(format!("dtype '{o}' is not f16 or f32").into()),
    };
    let input = BtfStore::open(Path::new(&args[1]))?;
    let meta = input.meta().clone();
    let (out, job) = (Path::new(&args[2]), serde_json::Value::Null);
    let mut writer =
        BtfWriter::create_compressed(out, meta.clone(), dtype, true, job, compression)?;
    let mut provenance = meta.provenance.clone();
    provenance["converted_from"] =
        serde_json::json!({"path": args[1], "dtype": format!("{:?}", input.dtype())});
    writer.set_provenance(provenance);
    let done = AtomicUsize::new(0);
    (0..meta.n_views()).into_par_iter().try_for_each(|v| -> btf_core::Result<()> {
        let mut img = vec![0f32; meta.texel_values()];
        for l in 0..meta.n_lights() {
            if !writer.has_image(v, l) {
                input.read_image_into(v, l, &mut img)?;
                writer.write_image(v, l, &img)?;
            }
        }
        let k = done.fetch_add(1, Ordering::Relaxed) + 1;
        eprintln!("view slot {v} done ({k}/{})", meta.n_views());
        Ok(())
    })?;
    writer.finish()?;
    Ok(())
}
