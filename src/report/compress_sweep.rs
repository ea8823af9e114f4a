//! The component sweep of `btf compress --sweep`: what accuracy costs in time and size.
//! For each component count the whole BTF is compressed (timed), scored, and one texture is
//! reconstructed on the CPU (timed); the report holds a CSV and Markdown table, plots of
//! error, size and time against components, the eigenvalue decay of three view slots (as
//! Sattler et al. 2003, Fig. 7) and difference heat-maps (as their Fig. 6).

use crate::progress::compress_with_progress;
use anyhow::Result;
use btf_core::Direction;
use btf_core::compress::CompressParams;
use btf_core::eigen::{EigenStore, Quantization};
use btf_core::reconstruct::{ReconstructParams, reconstruct, reconstruct_sample};
use btf_core::store::BtfStore;
use btf_image::compose::{captioned_strip, side_by_side, stacked, upscale};
use btf_image::heatmap::{colour_bar, error_heatmap_image};
use btf_image::plot::{Plot, Series, render};
use btf_image::write::{to_srgb_image as to_srgb, write_png};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// One row of the sweep table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SweepRow {
    /// Components asked for.
    pub components: usize,
    /// Components stored (after clamping).
    pub stored_components: usize,
    /// Relative RMSE of the stored representation.
    pub rel_rmse: f64,
    /// PSNR in dB.
    pub psnr_db: f64,
    /// Relative RMSE of the exact (unquantised) PCA with the same components.
    pub rel_rmse_exact: f64,
    /// Seconds to compress the whole BTF.
    pub compress_s: f64,
    /// Milliseconds to reconstruct one texture on the CPU (four views × four lights).
    pub reconstruct_ms: f64,
    /// Bytes of the eigen store.
    pub output_bytes: u64,
    /// Input bytes / output bytes.
    pub ratio: f64,
}

fn slot_near(store: &BtfStore, theta: f64, phi: f64) -> usize {
    let w = store
        .meta()
        .view_sampling
        .view_weights(Direction::new(theta, phi), btf_core::InterpMode::Nearest);
    w.as_slice()[0].0
}

/// Runs the sweep, writes the report into `dir` and prints its tables.
pub fn run(input: &BtfStore, cs: &[usize], q: Quantization, dir: &Path) -> Result<()> {
    let tables = write_report(input, cs, q, dir)?;
    crate::guard::outln!("{tables}");
    crate::guard::outln!("report written to {}", dir.join("report.md").display());
    Ok(())
}

/// Runs the sweep and writes the report into `dir`; returns its tables (Markdown).
pub fn write_report(input: &BtfStore, cs: &[usize], q: Quantization, dir: &Path) -> Result<String> {
    crate::guard::output_folder(dir, "compress --sweep", false, &|_| false)?;
    let meta = input.meta();
    let (w, h) = (meta.width, meta.height);
    let work = dir.join(".sweep-stores");
    let slot_j = slot_near(input, 45.0, 300.0);
    let light_i = meta.light_sampling.len() / 2;
    let original = input.read_image(slot_j, light_i)?;
    let peak = original.iter().copied().fold(0f32, f32::max).max(1e-12);
    let mut rows = Vec::new();
    let mut panels = vec![upscale(&to_srgb(w, h, &original, 0.8 / peak), 128)];
    let mut heat =
        vec![upscale(&error_heatmap_image(w, h, &original, &original, 0.1 * peak, None), 128)];
    let mut decay: Vec<Series> = Vec::new();
    for &c in cs {
        let out = work.join(format!("c{c}.eig"));
        let r = compress_with_progress(
            input,
            &out,
            CompressParams { components: c, quantization: q, resume: false, ..Default::default() },
        )?;
        let store = EigenStore::open(&out)?;
        let t0 = Instant::now();
        let reps = 3;
        for k in 0..reps {
            let v = Direction::new(37.0 + k as f64, 101.0);
            let l = Direction::new(22.0, 250.0 + k as f64);
            std::hint::black_box(reconstruct(&store, v, l, ReconstructParams::default())?);
        }
        let reconstruct_ms = t0.elapsed().as_secs_f64() * 1e3 / reps as f64;
        let slot = store.read_slot(slot_j)?;
        let rec = reconstruct_sample(&slot, light_i, r.components);
        panels.push(upscale(&to_srgb(w, h, &rec, 0.8 / peak), 128));
        heat.push(upscale(&error_heatmap_image(w, h, &original, &rec, 0.1 * peak, None), 128));
        if c == *cs.iter().max().unwrap() {
            for (name, th, ph) in [
                ("view theta 0", 0.0, 0.0),
                ("view theta 45, phi 300", 45.0, 300.0),
                ("view theta 75, phi 45", 75.0, 45.0),
            ] {
                let j = slot_near(input, th, ph);
                let ev = store.read_slot(j)?.eigenvalues;
                let points = ev.iter().enumerate().map(|(k, &l)| ((k + 1) as f64, l)).collect();
                decay.push(Series::new(name, points));
            }
        }
        rows.push(SweepRow {
            components: c,
            stored_components: r.components,
            rel_rmse: r.rel_rmse,
            psnr_db: r.psnr_db,
            rel_rmse_exact: r.rel_rmse_exact,
            compress_s: r.seconds,
            reconstruct_ms,
            output_bytes: r.output_bytes,
            ratio: r.input_bytes as f64 / r.output_bytes.max(1) as f64,
        });
        std::fs::remove_dir_all(&out).ok();
    }
    // What the storage precision costs: the largest c once more with the other quantisation.
    let c_max = *cs.iter().max().unwrap();
    let other = if q == Quantization::F16 { Quantization::U8 } else { Quantization::F16 };
    let out = work.join("other.eig");
    let r_other = compress_with_progress(
        input,
        &out,
        CompressParams {
            components: c_max,
            quantization: other,
            resume: false,
            ..Default::default()
        },
    )?;
    std::fs::remove_dir_all(&work).ok();
    let last = rows.iter().find(|r| r.components == c_max).unwrap();
    let quant_md = format!(
        "\n## What storage precision costs (c = {})\n\n| eigentextures | rel. RMSE | store MiB |\n|---|---:|---:|\n| exact (f64, not stored) | {:.3e} | — |\n| {} | {:.3e} | {:.2} |\n| {} | {:.3e} | {:.2} |\n",
        last.stored_components,
        last.rel_rmse_exact,
        q.name(),
        last.rel_rmse,
        last.output_bytes as f64 / 1048576.0,
        other.name(),
        r_other.rel_rmse,
        r_other.output_bytes as f64 / 1048576.0
    );
    write_tables(dir, &rows, input)?;
    write_strips(dir, cs, &panels, &heat)?;
    write_plots(dir, &rows, decay)?;
    let mut md = String::new();
    writeln!(
        md,
        "# Compression sweep\n\nInput: `{}` ({}), {}×{} texels, {} view slots × {} lights, eigentextures {}.\n",
        input.path().display(),
        meta.view_sampling.name,
        w,
        h,
        meta.n_views(),
        meta.n_lights(),
        q.name()
    )?;
    md.push_str(&std::fs::read_to_string(dir.join("sweep.md"))?);
    md.push_str(&quant_md);
    writeln!(
        md,
        "\n![error](error.png) ![accuracy vs time](accuracy_vs_time.png)\n\nEach point of the accuracy-vs-time plot is labelled with its c; the points are joined only when the time grows with c (timings are noisy).\n\n![size and time](size_time.png) ![eigenvalues](eigenvalues.png)\n"
    )?;
    writeln!(
        md,
        "Reconstructions of view slot {slot_j}, light {light_i} (original, then c = {cs:?}):\n\n![reconstructions](reconstructions.png)\n"
    )?;
    writeln!(
        md,
        "Difference heat-maps against the original (length of the RGB error vector; green = 0, red ≥ 10 % of the image's peak; colour bar below):\n\n![heat-maps](heatmaps.png)"
    )?;
    btf_image::write::write_text(&dir.join("report.md"), &md)?;
    Ok(format!("{}{quant_md}", std::fs::read_to_string(dir.join("sweep.md"))?))
}

fn write_tables(dir: &Path, rows: &[SweepRow], input: &BtfStore) -> Result<()> {
    let mut csv = String::from(
        "components,stored_components,rel_rmse,psnr_db,compress_s,reconstruct_ms,output_bytes,ratio\n",
    );
    let mut md = String::from(
        "| c | rel. RMSE | PSNR dB | compress s | CPU reconstruct ms | store MiB | ratio |\n|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        writeln!(
            csv,
            "{},{},{:.6e},{:.3},{:.4},{:.3},{},{:.2}",
            r.components,
            r.stored_components,
            r.rel_rmse,
            r.psnr_db,
            r.compress_s,
            r.reconstruct_ms,
            r.output_bytes,
            r.ratio
        )?;
        writeln!(
            md,
            "| {} | {:.3e} | {:.2} | {:.3} | {:.2} | {:.2} | {:.1}:1 |",
            r.stored_components,
            r.rel_rmse,
            r.psnr_db,
            r.compress_s,
            r.reconstruct_ms,
            r.output_bytes as f64 / 1048576.0,
            r.ratio
        )?;
    }
    writeln!(md, "\nInput store: {:.1} MiB.", input.bytes() as f64 / 1048576.0)?;
    btf_image::write::write_text(&dir.join("sweep.csv"), &csv)?;
    btf_image::write::write_text(&dir.join("sweep.md"), &md)?;
    Ok(())
}

/// `reconstructions.png` and `heatmaps.png`: the original and each `c`, captioned; the
/// heat-maps with their colour bar below.
fn write_strips(
    dir: &Path,
    cs: &[usize],
    panels: &[image::RgbImage],
    heat: &[image::RgbImage],
) -> Result<()> {
    let mut captions = vec!["original".to_string()];
    captions.extend(cs.iter().map(|c| format!("c = {c}")));
    let strip = |imgs: &[image::RgbImage]| {
        let pairs: Vec<(&image::RgbImage, &str)> =
            imgs.iter().zip(&captions).map(|(i, c)| (i, c.as_str())).collect();
        captioned_strip(&pairs, 6)
    };
    write_png(&dir.join("reconstructions.png"), &strip(panels))?;
    let heat_strip = strip(heat);
    let bar = colour_bar(
        heat_strip.width().clamp(260, 520),
        &[(0.0, "0"), (0.5, "5 % of peak"), (1.0, ">= 10 % of peak")],
    );
    write_png(&dir.join("heatmaps.png"), &stacked(&[&heat_strip, &bar], 4))?;
    Ok(())
}

/// The sweep's plots, one unit per axis: error, accuracy against compression time (points
/// labelled with c), size and CPU reconstruction time (two panels), eigenvalue decay.
fn write_plots(dir: &Path, rows: &[SweepRow], decay: Vec<Series>) -> Result<()> {
    let pts = |f: &dyn Fn(&SweepRow) -> (f64, f64)| rows.iter().map(f).collect::<Vec<_>>();
    let c_label = |c: f64| format!("c={c}");
    let line = |title: &str, x: &str, y: &str, log_y: bool, series: Vec<Series>| Plot {
        title: title.into(),
        x_label: x.into(),
        y_label: y.into(),
        log_y,
        log_x: false,
        series,
    };
    let error = line(
        "Error against components",
        "components c",
        "relative RMSE (log)",
        true,
        vec![Series::new("whole BTF", pts(&|r| (r.components as f64, r.rel_rmse)))],
    );
    let accuracy = line(
        "Accuracy against compression time",
        "time to compress the whole BTF (s)",
        "relative RMSE (log)",
        true,
        vec![Series::parametric(
            "compress (label: c)",
            rows.iter().map(|r| (r.components as f64, r.compress_s, r.rel_rmse)).collect(),
            c_label,
        )],
    );
    let size = line(
        "Store size against components",
        "components c",
        "eigen store (MiB)",
        false,
        vec![Series::new(
            "eigen store",
            pts(&|r| (r.components as f64, r.output_bytes as f64 / 1048576.0)),
        )],
    );
    let time = line(
        "CPU reconstruction time against components",
        "components c",
        "one texture (ms)",
        false,
        vec![Series::new("CPU reconstruct", pts(&|r| (r.components as f64, r.reconstruct_ms)))],
    );
    let eigen = line(
        "Eigenvalue decay of three view slots",
        "eigenvalue index",
        "eigenvalue (log)",
        true,
        decay,
    );
    write_png(&dir.join("error.png"), &render(&error))?;
    write_png(&dir.join("accuracy_vs_time.png"), &render(&accuracy))?;
    write_png(&dir.join("size_time.png"), &side_by_side(&[&render(&size), &render(&time)], 16))?;
    write_png(&dir.join("eigenvalues.png"), &render(&eigen))?;
    Ok(())
}
