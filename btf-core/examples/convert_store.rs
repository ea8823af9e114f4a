//! Rewrites a BTF store with another element type, e.g. the `f32` benchmark store as `f16`
//! (half the bytes; the natural type of HDR normtextures): `cargo run --release -p btf-core
//! --example convert_store -- IN.btf OUT.btf f16`. Values are rounded to nearest; one beyond
//! the `f16` range is refused with its image named (the writer's check).

use btf_core::store::{BtfStore, BtfWriter};
use btf_core::zarr::DType;
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        return Err("usage: convert_store IN.btf OUT.btf f16|f32".into());
    }
    let dtype = match args[3].as_str() {
        "f16" => DType::F16,
        "f32" => DType::F32,
        o => return Err(format!("dtype '{o}' is not f16 or f32").into()),
    };
    let input = BtfStore::open(Path::new(&args[1]))?;
    let meta = input.meta().clone();
    let mut writer = BtfWriter::create(Path::new(&args[2]), meta.clone(), dtype, true)?;
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
