//! `btf render-sweep SCENE.toml -o DIR`: what accuracy costs in time on the GPU — the
//! sweep of `btf_render::cost_sweep` (components × evaluation × blending against plain
//! texture mapping and the read bound), written as CSV, Markdown and plots, plus the [S03 eq. 6]
//! on/off comparison of the scene's shadows side by side.

use anyhow::{Context, Result};
use btf_image::compose::side_by_side;
use btf_image::plot::{Plot, Series, render};
use btf_image::write::{to_srgb_image as to_srgb, write_png, write_text};
use btf_render::cost_sweep::{self, READ_BOUND_TARGET, SweepConfig, SweepResult};
use btf_render::scene::Shadows;
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `btf render-sweep`.
#[derive(clap::Args, Debug)]
pub struct RenderSweepArgs {
    /// The scene (TOML) and frame-size overrides.
    #[command(flatten)]
    pub scene: crate::args::SceneArgs,
    /// Output folder.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Component counts (default 4,8,16,32 up to what the scene's stores hold, with a note
    /// for those left out; a count given here that a store does not hold is an error).
    #[arg(short = 'c', long, value_delimiter = ',')]
    pub components: Option<Vec<usize>>,
    /// Timed repeats per setting (median reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub repeat: u32,
}

/// Runs `btf render-sweep`.
pub fn run(a: RenderSweepArgs) -> Result<()> {
    let scene = a.scene.load()?;
    crate::guard::refuse_scene_overlap(&[("-o", &a.output)], &a.scene.scene, &scene, &[])?;
    let components = components_to_sweep(&scene, a.components.as_deref())?;
    let gpu = Gpu::new().context("creating a headless GPU device")?;
    let md = sweep_into(&gpu, &scene, &components, a.repeat as usize, &a.output)?;
    crate::guard::outln!("{md}");
    crate::guard::outln!("written to {}", a.output.join("render-cost.md").display());
    Ok(())
}

/// The component counts of the sweep: those asked for, each of which every material's eigen
/// store must hold (an error naming the store otherwise: a count cannot be honoured by
/// rendering fewer), or by default 4, 8, 16, 32 up to the smallest store's count (that
/// count alone when it is below 4), with a note on standard error for those left out.
pub fn components_to_sweep(scene: &Scene, asked: Option<&[usize]>) -> Result<Vec<usize>> {
    let mut stored: Option<(usize, &Path)> = None;
    for m in &scene.materials {
        let eig = btf_core::eigen::EigenStore::open(&m.store)
            .with_context(|| format!("cannot open material store {}", m.store.display()))?;
        let c = eig.meta().components;
        if stored.is_none_or(|(s, _)| c < s) {
            stored = Some((c, &m.store));
        }
    }
    let Some((stored, store)) = stored else { anyhow::bail!("the scene has no [[materials]]") };
    match asked {
        Some(cs) => {
            anyhow::ensure!(!cs.is_empty() && !cs.contains(&0), "--components needs counts ≥ 1");
            if let Some(&c) = cs.iter().find(|&&c| c > stored) {
                anyhow::bail!(
                    "--components {c}: {} holds only {stored} components per view slot; give \
                     counts ≤ {stored} (or compress the material with -c {c})",
                    store.display()
                );
            }
            Ok(cs.to_vec())
        }
        None => {
            let (mut kept, left): (Vec<usize>, Vec<usize>) =
                [4, 8, 16, 32].into_iter().partition(|&c| c <= stored);
            if kept.is_empty() {
                kept.push(stored);
            }
            if !left.is_empty() {
                eprintln!(
                    "note: components {left:?} left out of the default sweep: {} holds {stored}",
                    store.display()
                );
            }
            Ok(kept)
        }
    }
}

/// Runs the sweep on `scene` and writes `render-cost.{csv,md,png}`, `cost-vs-components.png`
/// and (with a shadowing light) `eq6-on-off.png` into `out`; returns the Markdown.
pub fn sweep_into(
    gpu: &Gpu,
    scene: &Scene,
    components: &[usize],
    repeats: usize,
    out: &Path,
) -> Result<String> {
    crate::guard::output_folder(out, "render-sweep", false, &|_| false)?;
    let config = SweepConfig { components: components.to_vec(), repeats };
    let n = (components.len() * 4) as u64;
    let bar = crate::progress::bar(n, "render sweep");
    let result =
        cost_sweep::run(gpu, scene, &config, &mut |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    write_text(&out.join("render-cost.csv"), &csv(&result))?;
    write_plots(&result, out)?;
    let mut md = markdown(&result);
    if let Some(line) = eq6_comparison(gpu, scene, out)? {
        md.push_str(&line);
    }
    write_text(&out.join("render-cost.md"), &md)?;
    Ok(md)
}

fn csv(r: &SweepResult) -> String {
    let mut s = String::from(
        "components,evaluation,blending,rel_rmse,reads_per_pixel,btf_ms,frame_ms,plain_ms,read_bound_ms,ratio_plain,ratio_read_bound\n",
    );
    for x in &r.rows {
        let _ = writeln!(s, "{}", row_cells(x, false).join(","));
    }
    s
}

/// One row's cells: full precision for the CSV, rounded for reading in the Markdown table.
fn row_cells(x: &cost_sweep::CostRow, rounded: bool) -> [String; 11] {
    let f =
        |v: f64, short: usize, long: usize| format!("{v:.*}", if rounded { short } else { long });
    let e = if rounded { format!("{:.2e}", x.rel_rmse) } else { format!("{:.6e}", x.rel_rmse) };
    [
        x.components.to_string(),
        x.evaluation.clone(),
        x.blending.clone(),
        e,
        f(x.reads_per_pixel, 1, 3),
        f(x.btf_ms, 2, 4),
        f(x.frame_ms, 2, 4),
        f(x.plain_ms, 2, 4),
        f(x.read_bound_ms, 2, 4),
        f(x.ratio_plain, 1, 4),
        f(x.ratio_read_bound, 2, 4),
    ]
}

/// The sweep as Markdown: the table, the linear fits and the target checks.
pub fn markdown(r: &SweepResult) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## What accuracy costs in time ({}×{}, reference: per-pixel, c = {}, four/four)\n",
        r.width, r.height, r.reference_components
    );
    s.push_str("| c | evaluation | blending | rel. RMSE | reads/px | BTF pass ms | frame ms | plain ms | read bound ms | × plain | × read bound |\n");
    s.push_str("|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for x in &r.rows {
        let _ = writeln!(s, "| {} |", row_cells(x, true).join(" | "));
    }
    s.push_str("\nBTF pass time against components (least squares `ms = a + b·c`):\n\n");
    s.push_str("| mode | a (ms) | b (ms per component) | R² |\n|---|---:|---:|---:|\n");
    for f in &r.fits {
        let _ = writeln!(s, "| {} | {:.3} | {:.4} | {:.4} |", f.mode, f.intercept, f.slope, f.r2);
    }
    let yes = |b: bool| if b { "met" } else { "NOT met" };
    let _ = writeln!(
        s,
        "\nTargets: BTF pass ≤ {READ_BOUND_TARGET}× its read bound — worst {:.2}× ({}); per-pixel reads ≤ per-vertex reads — {}.\n",
        r.worst_read_bound_ratio,
        yes(r.worst_read_bound_ratio <= READ_BOUND_TARGET),
        yes(r.per_pixel_reads_le_per_vertex)
    );
    s.push_str(
        "![accuracy vs time](render-cost.png) ![time vs components](cost-vs-components.png)\n\n",
    );
    s
}

fn write_plots(r: &SweepResult, out: &Path) -> Result<()> {
    let modes = ["per-pixel/four", "per-pixel/nearest", "per-vertex/four", "per-vertex/nearest"];
    let series = |f: &dyn Fn(&cost_sweep::CostRow) -> (f64, f64)| {
        modes
            .iter()
            .map(|m| Series {
                name: (*m).into(),
                points: r
                    .rows
                    .iter()
                    .filter(|x| format!("{}/{}", x.evaluation, x.blending) == *m)
                    .map(f)
                    .collect(),
            })
            .collect::<Vec<_>>()
    };
    let mut cs: Vec<usize> = r.rows.iter().map(|x| x.components).collect();
    cs.dedup();
    let counts = cs.iter().map(|c| c.to_string()).collect::<Vec<_>>().join(", ");
    let accuracy = Plot {
        title: format!("Accuracy vs BTF pass time (points: c = {counts})"),
        x_label: "BTF pass ms".into(),
        y_label: "rel. RMSE".into(),
        log_y: true,
        log_x: false,
        series: series(&|x| (x.btf_ms, x.rel_rmse)),
    };
    write_png(&out.join("render-cost.png"), &render(&accuracy))?;
    let mut by_c = series(&|x| (x.components as f64, x.btf_ms));
    by_c.push(Series {
        name: "read bound, per-pixel/four".into(),
        points: r
            .rows
            .iter()
            .filter(|x| x.evaluation == "per-pixel" && x.blending == "four")
            .map(|x| (x.components as f64, x.read_bound_ms))
            .collect(),
    });
    let cost = Plot {
        title: "BTF pass time vs components".into(),
        x_label: "components c".into(),
        y_label: "ms".into(),
        log_y: false,
        log_x: false,
        series: by_c,
    };
    Ok(write_png(&out.join("cost-vs-components.png"), &render(&cost))?)
}

/// Renders the scene's shadows with and without the smooth boundary of [S03 eq. 6] and writes them
/// side by side; `None` when no light casts shadows.
fn eq6_comparison(gpu: &Gpu, scene: &Scene, out: &Path) -> Result<Option<String>> {
    if !scene.lights.iter().any(|l| l.casts_shadows()) {
        return Ok(None);
    }
    let mut s = scene.clone();
    if s.effects.shadows == Shadows::None {
        s.effects.shadows = Shadows::Volume;
    }
    let mut images = Vec::new();
    for on in [true, false] {
        s.effects.smooth_boundary = on;
        let f = Renderer::new(gpu, &s, RenderOptions::default())?.render(gpu)?;
        images.push(to_srgb(f.width as usize, f.height as usize, &f.rgb, s.output.exposure));
    }
    write_png(&out.join("eq6-on-off.png"), &side_by_side(&[&images[0], &images[1]], 8))?;
    Ok(Some(format!(
        "Shadows ({:?}) with the smooth boundary of eq. 6 (left) and without it (right):\n\n![eq. 6 on/off](eq6-on-off.png)\n\n",
        s.effects.shadows
    )))
}

/// The `btf demo` stage: the sweep on the demo's point-light scene at a small size
/// (`96 × 72`, components 4/8/16 up to what the store holds, 3 repeats) into `out/render-cost`;
/// returns the report section (reused when already written).
pub fn demo_section(
    out: &Path,
    stored_components: usize,
    stage: &mut crate::demo::scene::StageFn<'_>,
) -> Result<String> {
    let dir = out.join("render-cost");
    let md_path = dir.join("render-cost.md");
    let scene_path = out.join("scene-point.toml");
    let components: Vec<usize> =
        [4, 8, 16].into_iter().filter(|&c| c <= stored_components).collect();
    if components.is_empty() || !scene_path.exists() {
        return Ok(String::new());
    }
    let done = md_path.exists();
    let mut skipped = None;
    stage(
        "render cost sweep",
        done,
        Box::new(|| {
            let gpu = match Gpu::new() {
                Ok(g) => g,
                Err(e) if std::env::var("BTF_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
                    return Err(e).context("BTF_REQUIRE_GPU=1 but no GPU adapter");
                }
                Err(e) => {
                    skipped = Some(format!("Render cost sweep skipped: no GPU adapter ({e}).\n"));
                    return Ok(());
                }
            };
            let mut scene = Scene::load(&scene_path)?;
            scene.output.width = 96;
            scene.output.height = 72;
            scene.effects.msaa = 1;
            sweep_into(&gpu, &scene, &components, 3, &dir)?;
            Ok(())
        }),
    )?;
    if let Some(s) = skipped {
        return Ok(s);
    }
    let md = std::fs::read_to_string(&md_path)
        .with_context(|| format!("cannot read {}", md_path.display()))?;
    // Links in the section are relative to its folder.
    Ok(md.replace("](", "](render-cost/"))
}
