//! `btf render SCENE.toml -o out.png [--exr out.exr] [--width W --height H] [--stats]
//! [--stats-json] [--baseline plain|read-bound|read-bound-groups]`: renders a scene (TOML, see `examples/scenes/`) headless on the GPU
//! (lavapipe without one) and writes an sRGB PNG (exposure from the scene) and optionally a
//! linear EXR.

use anyhow::{Context, Result, bail};
use btf_render::{Baseline, Gpu, ReadForm, RenderOptions, Stats};
use std::path::PathBuf;

/// Arguments of `btf render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: crate::args::SceneArgs,
    /// Output PNG (sRGB, exposure applied).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Also write the linear HDR image as EXR.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Print which passes ran and what each cost.
    #[arg(long)]
    pub stats: bool,
    /// Print the statistics as JSON (`{"passes":[{"name","ms"}],"frame_ms",…}`).
    #[arg(long)]
    pub stats_json: bool,
    /// Render this many frames and report the last (warm caches, for timing).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: u32,
    /// Count texture reads per pixel in the BTF pass (adds atomics; for measurements).
    #[arg(long)]
    pub count_reads: bool,
    /// Draw a cost baseline instead of the BTF: `plain` (mean texture of slot 0) or
    /// `read-bound` (the BTF pass's reads per pixel, counted first, merely summed; one read
    /// per loop iteration) or `read-bound-groups` (the same reads, three per iteration of a
    /// constant-length loop).
    #[arg(long, value_parser = ["plain", "read-bound", "read-bound-groups"])]
    pub baseline: Option<String>,
}

/// Runs `btf render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let scene = args.scene.load()?;
    if args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref()
        != Some("png")
    {
        bail!(
            "{}: the output must be a .png file (use --exr for linear HDR)",
            args.output.display()
        );
    }
    let mut outputs: Vec<(&str, &std::path::Path)> = vec![("-o", &args.output)];
    if let Some(exr) = &args.exr {
        outputs.push(("--exr", exr));
    }
    crate::guard::refuse_scene_overlap(&outputs, &args.scene.scene, &scene, &[])?;
    if let Some(exr) = &args.exr {
        crate::guard::check_file(exr, btf_core::fs::EXR)?;
    }
    crate::guard::check_file(&args.output, btf_core::fs::PNG)?;
    let yarns = crate::scene_yarns::SceneYarns::build(
        &scene,
        &args.scene.scene,
        Some(crate::scene_yarns::default_cache()),
    )?;
    let gpu = Gpu::new().context("creating a headless GPU device")?;
    let baseline = match args.baseline.as_deref() {
        None => None,
        Some("plain") => Some(Baseline::Plain),
        Some(name) => {
            let form = if name == "read-bound" { ReadForm::Loop } else { ReadForm::Groups };
            let counting = RenderOptions { count_reads: true, ..Default::default() };
            let counted = yarns
                .renderer(&gpu, &scene, counting)
                .with_context(|| format!("preparing {}", args.scene.scene.display()))?
                .render(&gpu)?;
            let reads_per_pixel = counted.stats.reads_per_pixel.unwrap_or(0.0);
            Some(Baseline::ReadBound { reads_per_pixel, form })
        }
    };
    let options = RenderOptions { count_reads: args.count_reads, baseline, ..Default::default() };
    let mut renderer = yarns
        .renderer(&gpu, &scene, options)
        .with_context(|| format!("preparing {}", args.scene.scene.display()))?;
    let mut frame = renderer.render(&gpu)?;
    for _ in 1..args.repeat {
        frame = renderer.render(&gpu)?;
    }
    if !frame.all_finite() {
        bail!("the rendered image contains non-finite values (please report this scene)");
    }
    frame.write_png(&args.output, scene.output.exposure)?;
    if let Some(exr) = &args.exr {
        frame.write_exr(exr)?;
    }
    if args.stats {
        print_stats(&frame.stats, &gpu);
    }
    if args.stats_json {
        crate::guard::outln!("{}", serde_json::to_string(&frame.stats)?);
    }
    Ok(())
}

fn print_stats(s: &Stats, gpu: &Gpu) {
    crate::guard::outln!(
        "adapter: {} ({:?}); timing: {}",
        gpu.info.name,
        gpu.info.backend,
        s.timing
    );
    if !s.setup.is_empty() {
        crate::guard::outln!("setup (once per scene):");
        for p in &s.setup {
            crate::guard::outln!("  {:<40} {:>10.3} ms", p.name, p.ms);
        }
        crate::guard::outln!("per frame:");
    }
    for p in &s.passes {
        crate::guard::outln!("  {:<40} {:>10.3} ms", p.name, p.ms);
    }
    crate::guard::outln!("  {:<40} {:>10.3} ms", "frame", s.frame_ms);
    if let (Some(r), Some(n)) = (s.reads_per_pixel, s.shaded_pixels) {
        crate::guard::outln!("  texture reads per shaded pixel: {r:.2} ({n} pixels)");
    }
}
