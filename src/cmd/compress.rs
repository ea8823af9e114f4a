//! `btf compress`: per-view-slot PCA of a BTF store into an eigen store, or a sweep over the
//! number of components with a report of what accuracy costs.

use crate::guard::{self, outln};
use crate::progress;
use crate::report::compress_sweep as sweep;
use anyhow::{Context, Result, bail};
use btf_core::compress::CompressParams;
use btf_core::eigen::Quantization;
use btf_core::store::BtfStore;
use std::path::PathBuf;

/// Arguments of `btf compress`.
#[derive(clap::Args)]
pub struct CompressArgs {
    /// Input BTF store.
    input: PathBuf,
    /// Components per view slot.
    #[arg(short = 'c', long, default_value_t = 16)]
    components: usize,
    /// Output eigen store.
    #[arg(short = 'o', long = "out", alias = "output")]
    output: Option<PathBuf>,
    /// Storage of the eigentextures.
    #[arg(long, alias = "quantize", default_value = "f16")]
    quantization: crate::args::Quantization,
    /// Arithmetic of each slot's Gram matrix: f64, or f32 within chunks of 64 columns and
    /// f64 across them (for f16 data, 125 times below its precision; twice the lanes);
    /// auto: f32 for f16 stores, f64 for f32 ones.
    #[arg(long, default_value = "auto")]
    gram: crate::args::Gram,
    /// Chunk codec of the means and eigentextures: blosc (byte shuffle, zstd level 1), or
    /// none (no encoding: 7–20 % less wall time at 256² on 2 cores, about 40 % more disk).
    /// A resumed run, and every shard after the first, keeps the codec the store was begun
    /// with. Default: blosc.
    #[arg(long)]
    codec: Option<crate::args::Codec>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    /// Continue an interrupted run, keeping the slots it finished.
    #[arg(long)]
    resume: bool,
    /// Shard of a compression split over several processes or machines.
    #[command(flatten)]
    shard: crate::args::ShardArgs,
    /// Sweep these component counts (comma separated) instead of one compression.
    #[arg(long, value_delimiter = ',')]
    sweep: Option<Vec<usize>>,
    /// Folder for the sweep's tables and images.
    #[arg(long)]
    report: Option<PathBuf>,
}

/// Runs `btf compress`.
pub fn run(a: CompressArgs) -> Result<()> {
    let quantization: Quantization = a.quantization.quantization();
    let input =
        BtfStore::open(&a.input).with_context(|| format!("cannot open {}", a.input.display()))?;
    if let Some(cs) = a.sweep {
        let Some(dir) = a.report else { bail!("--sweep needs --report DIR") };
        if a.codec.is_some() {
            bail!("--codec is not available with --sweep (its stores are blosc)");
        }
        if cs.is_empty() || cs.contains(&0) {
            bail!("--sweep needs component counts ≥ 1, e.g. --sweep 1,2,4,8,16");
        }
        guard::refuse_overlap(&[("--report", &dir)], &[("input", &a.input)])?;
        return sweep::run(&input, &cs, quantization, &dir);
    }
    let Some(output) = a.output else { bail!("give -o OUT.eig (or --sweep LIST --report DIR)") };
    guard::refuse_overlap(&[("-o", &output)], &[("input", &a.input)])?;
    let params = CompressParams {
        components: a.components,
        quantization,
        resume: a.resume,
        gram: a.gram.precision(),
        codec: a.codec.unwrap_or(crate::args::Codec::Blosc).eigen(),
    };
    if let Some(shard) = a.shard.shard()? {
        return run_shard(&input, &output, params, shard, a.json);
    }
    let r =
        guard::resumable(&output, || progress::compress_with_progress(&input, &output, params))?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        outln!(
            "compressed {} slots × {} lights to {} components ({}) into {} in {:.2} s",
            r.slots.len(),
            input.meta().n_lights(),
            r.components,
            r.quantization.name(),
            output.display(),
            r.seconds
        );
        outln!(
            "  relative RMSE {:.3e} (exact PCA {:.3e}), PSNR {:.1} dB",
            r.rel_rmse,
            r.rel_rmse_exact,
            r.psnr_db
        );
        outln!(
            "  {:.1} MiB → {:.1} MiB (ratio {:.1}:1)",
            r.input_bytes as f64 / 1048576.0,
            r.output_bytes as f64 / 1048576.0,
            r.input_bytes as f64 / r.output_bytes.max(1) as f64
        );
        if r.resumed_slots > 0 {
            outln!("  resumed {} slots from an interrupted run", r.resumed_slots);
        }
    }
    Ok(())
}

/// One shard of a compression: its view slots into the shared `OUT.partial`.
fn run_shard(
    input: &BtfStore,
    output: &std::path::Path,
    params: CompressParams,
    shard: btf_core::shard::Shard,
    json: bool,
) -> Result<()> {
    let views = shard.range(input.meta().n_views());
    let pb = progress::bar(views.len() as u64, &format!("shard {}", shard.label()));
    let r = btf_core::compress::compress_shard(input, output, params, shard, &|| {
        pb.inc(1);
        progress::unit_delay();
    })
    .with_context(|| {
        format!(
            "compressing shard {} of {} into {}",
            shard.label(),
            input.path().display(),
            output.display()
        )
    })?;
    pb.finish_and_clear();
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        outln!(
            "shard {}: view slots {}..{} ({} computed, {} already done) into {} in {:.2} s",
            shard.label(),
            views.start,
            views.end,
            r.slots.len() - r.resumed_slots,
            r.resumed_slots,
            guard::partial_of(output).display(),
            r.seconds
        );
        outln!("  when every shard is done: btf finalize {}", output.display());
    }
    Ok(())
}
