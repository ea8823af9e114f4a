//! `btf inspect FILE [--json]`: what a store holds (kind, sampling, sizes, dtype, bytes).

use anyhow::{Context, Result};
use btf_core::eigen::EigenStore;
use btf_core::store::{BtfStore, read_meta};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `btf inspect`.
#[derive(clap::Args)]
pub struct InspectArgs {
    /// A BTF store (`.btf`) or eigen store (`.eig`).
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// The inspection as JSON (keys are a contract: kind, sampling, n_views, n_lights, width,
/// height, components, dtype, bytes).
pub fn inspect_json(path: &std::path::Path) -> Result<serde_json::Value> {
    let meta = read_meta(path).with_context(|| format!("cannot open {}", path.display()))?;
    let mut v = json!({
        "kind": meta.kind,
        "sampling": meta.view_sampling.name,
        "light_sampling": meta.light_sampling.name,
        "n_views": meta.n_views(),
        "n_lights": meta.n_lights(),
        "width": meta.width,
        "height": meta.height,
        "color_space": meta.color_space,
        "units": meta.units,
        "provenance": meta.provenance,
    });
    if meta.kind == "eigen" {
        let s = EigenStore::open(path)?;
        v["components"] = json!(s.meta().components);
        v["dtype"] = json!(s.meta().quantization.name());
        v["bytes"] = json!(s.bytes());
    } else {
        let s = BtfStore::open(path)?;
        v["dtype"] = json!(s.dtype().zarr_name().replace("float", "f"));
        v["bytes"] = json!(s.bytes());
    }
    Ok(v)
}

/// Runs `btf inspect`.
pub fn run(a: InspectArgs) -> Result<()> {
    let v = inspect_json(&a.file)?;
    if a.json {
        crate::guard::outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    crate::guard::outln!("{}: {} store", a.file.display(), v["kind"].as_str().unwrap_or("?"));
    crate::guard::outln!(
        "  sampling     {} views × {} lights ({} / {})",
        v["n_views"],
        v["n_lights"],
        v["sampling"],
        v["light_sampling"]
    );
    crate::guard::outln!("  texture      {} × {} texels, {}", v["width"], v["height"], v["dtype"]);
    if let Some(c) = v.get("components") {
        crate::guard::outln!("  components   {c}");
    }
    crate::guard::outln!(
        "  bytes        {} ({:.1} MiB)",
        v["bytes"],
        v["bytes"].as_f64().unwrap_or(0.0) / 1048576.0
    );
    crate::guard::outln!("  colour space {}", v["color_space"].as_str().unwrap_or(""));
    crate::guard::outln!("  provenance   {}", v["provenance"]);
    Ok(())
}
