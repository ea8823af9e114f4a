//! `btf demo`: the README's main job on embedded defaults — synthesise a material, compress
//! it, sweep the number of components, make an environment and a garment, render the
//! garment, and write a report for a non-developer (`report.html`, `report.md`) with the
//! developer tables in `details.{html,md}`; the terminal gets a summary of a few lines. Every stage keeps its output and is skipped when that
//! output is already complete, so an interrupted demo resumes where it stopped.

use crate::progress::compress_with_progress;
use crate::report::demo::StageTime;
use anyhow::{Context, Result};
use btf_core::compress::CompressParams;
use btf_core::eigen::{EigenStore, Quantization};
use btf_core::store::BtfStore;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `btf demo`.
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(short = 'o', long, alias = "output", default_value = "demo-out")]
    out: PathBuf,
    /// Material kind.
    #[arg(long, default_value = "corduroy")]
    kind: crate::args::Material,
    /// Texels per side of the material.
    #[arg(long, default_value_t = 64)]
    size: usize,
    /// Components per view slot.
    #[arg(short = 'c', long, default_value_t = 16)]
    components: usize,
    /// Rendered image width (height = 3/4 of it).
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// Component counts of the sweep report.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16")]
    sweep: Vec<usize>,
    /// Start from scratch instead of reusing finished stages.
    #[arg(long)]
    fresh: bool,
}

fn stage(
    stages: &mut Vec<StageTime>,
    name: &'static str,
    done: bool,
    f: impl FnOnce() -> Result<()>,
) -> Result<()> {
    let t0 = Instant::now();
    if done {
        eprintln!("[demo] {name}: reusing finished output");
    } else {
        eprintln!("[demo] {name} …");
        f().with_context(|| format!("demo stage '{name}'"))?;
    }
    stages.push(StageTime { name, seconds: t0.elapsed().as_secs_f64(), reused: done });
    Ok(())
}

/// Runs `btf demo`.
pub fn run(a: DemoArgs) -> Result<()> {
    crate::guard::output_folder(&a.out, "demo", a.fresh, &crate::guard::report_output)?;
    let kind = datasets::MaterialKind::from_name(a.kind.as_str())?;
    let (btf_path, eig_path) = (a.out.join("material.btf"), a.out.join("material.eig"));
    let mut stages = Vec::new();

    stage(&mut stages, "synthesise material", BtfStore::open(&btf_path).is_ok(), || {
        let spec = datasets::MaterialSpec::new(kind, a.size);
        let opts = datasets::GenerateOptions {
            resume: true,
            progress: crate::progress::enabled(),
            ..Default::default()
        };
        datasets::generate(&spec, &btf_path, &opts)?;
        Ok(())
    })?;
    let btf = BtfStore::open(&btf_path)?;
    stage(&mut stages, "compress", EigenStore::open(&eig_path).is_ok(), || {
        let params = CompressParams {
            components: a.components,
            quantization: Quantization::F16,
            resume: true,
            ..Default::default()
        };
        compress_with_progress(&btf, &eig_path, params)?;
        Ok(())
    })?;
    let sweep_dir = a.out.join("sweep");
    stage(&mut stages, "component sweep", sweep_dir.join("report.md").exists(), || {
        anyhow::ensure!(!a.sweep.is_empty() && !a.sweep.contains(&0), "--sweep needs counts ≥ 1");
        crate::report::compress_sweep::write_report(&btf, &a.sweep, Quantization::F16, &sweep_dir)?;
        Ok(())
    })?;
    let renders = crate::demo::scene::run(&a.out, a.width, a.components, &mut |name, done, f| {
        stage(&mut stages, name, done, f)
    })?;
    // The GPU cost sweep writes render-cost/; the details page reads its CSV.
    crate::cmd::render_sweep::demo_section(&a.out, a.components, &mut |name, done, f| {
        stage(&mut stages, name, done, f)
    })?;
    stage(&mut stages, "knit: fibers on the GPU", a.out.join("knit/knit.json").exists(), || {
        crate::demo::knit::run(&a.out, a.width)
    })?;
    let eig = EigenStore::open(&eig_path)?;
    let summary =
        crate::report::demo::write(&a.out, a.kind.as_str(), &btf, &eig, &renders, &stages)?;
    for line in summary {
        crate::guard::outln!("{line}");
    }
    Ok(())
}
