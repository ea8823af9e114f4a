//! What eigenweightsets cost in accuracy (Sattler et al. 2003, §5.4, [S03 eq. 13]; Fig. 12–13),
//! written by `btf relight` per environment into `OUTDIR/eigen/`:
//!
//! - `STEM-error.{csv,md,png}`: the relative error `‖U_e(δ) − U(δ)‖ / ‖U(δ)‖` (in the `U`
//!   metric of [`btf_light::eigenweights`]) of `e = 1…8` eigenweightsets against
//!   the exact gather, at the `A` rotations midway between the sampled ones (where the
//!   periodic interpolation of `o_k(δ)` is least exact), as mean and maximum, plus the
//!   relative RMS error of the rendered image at the first midpoint;
//! - `STEM-heat-eE.png`: green → red error heat maps of those renders against the render
//!   with exact weights (Fig. 13): per pixel the length of the RGB error, full scale = 20 %
//!   of the exact image's mean radiance over the garment (pixels that differ from the
//!   background; background pixels are black);
//! - `STEM-coefficients.{png,csv}`: `o_k(δ)` over `δ ∈ [0°, 360°)` (Fig. 12).
//!
//! The `.md` table is written last: its presence marks the report finished.

use anyhow::{Context, Result};
use btf_image::heatmap::error_heatmap_image;
use btf_image::plot::{Plot, Series};
use btf_image::write::{write_png, write_text};
use btf_light::eigenweights::relative_error;
use btf_light::environment::REPORT_COMPONENTS;
use btf_render::{Gpu, Renderer};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Error of `e` eigenweightsets.
#[derive(Debug, Clone, Serialize)]
pub struct EigenRow {
    /// Eigenweightsets used.
    pub e: usize,
    /// Mean relative error of `U` over the midway rotations.
    pub mean_rel_error: f64,
    /// Largest relative error of `U` over the midway rotations.
    pub max_rel_error: f64,
    /// Relative RMS error of the rendered image at the first midway rotation.
    pub image_rel_rmse: f64,
}

/// Measures `e = 1…8` against exact gathers, renders the heat maps and the `o_k(δ)` plot
/// of the renderer's current environment, and leaves the rotation where it was.
pub fn write(renderer: &mut Renderer, gpu: &Gpu, stem: &str, dir: &Path) -> Result<Vec<EigenRow>> {
    crate::guard::output_folder(dir, "relight", false, &|_| false)?;
    let env = renderer.environment().context("no environment light")?;
    let ews = env.eigenweightsets().context("eigenweightsets are off")?;
    let (a_n, kept) = (ews.rotations, ews.kept().min(REPORT_COMPONENTS));
    let metric = env.metric();
    let mids: Vec<f64> = (0..a_n).map(|t| (t as f64 + 0.5) * 360.0 / a_n as f64).collect();
    let exact: Vec<_> = mids.iter().map(|&d| env.gather(d)).collect();
    let mut rows: Vec<EigenRow> = (1..=kept)
        .map(|e| {
            let errs: Vec<f64> = mids
                .iter()
                .zip(&exact)
                .map(|(&d, u)| relative_error(&ews.reconstruct(d, e), u, &metric))
                .collect();
            EigenRow {
                e,
                mean_rel_error: errs.iter().sum::<f64>() / errs.len() as f64,
                max_rel_error: errs.iter().copied().fold(0.0, f64::max),
                image_rel_rmse: f64::NAN,
            }
        })
        .collect();
    let curves: Vec<Vec<f64>> = {
        let o: Vec<Vec<f64>> = (0..360).map(|d| ews.coefficients_at(d as f64, kept)).collect();
        (0..kept).map(|k| o.iter().map(|row| row[k]).collect()).collect()
    };
    let restore = env.rotation_deg();
    heat_maps(renderer, gpu, stem, dir, mids[0], &mut rows)?;
    renderer.set_environment_rotation(restore)?;
    write_coefficients(stem, dir, &curves)?;
    write_tables(stem, dir, a_n, &rows)?;
    Ok(rows)
}

/// Renders exact and eigenweightset frames at `delta` and writes the heat maps.
fn heat_maps(
    renderer: &mut Renderer,
    gpu: &Gpu,
    stem: &str,
    dir: &Path,
    delta: f64,
    rows: &mut [EigenRow],
) -> Result<()> {
    let env = renderer.environment_mut().context("no environment light")?;
    env.set_rotation_exact(delta);
    let reference = renderer.render(gpu)?;
    let bg = renderer.scene().output.background;
    let garment: Vec<bool> = reference.rgb.chunks_exact(3).map(|p| p != bg).collect();
    let (sum, n) = reference
        .rgb
        .chunks_exact(3)
        .zip(&garment)
        .filter(|(_, g)| **g)
        .fold((0f32, 0usize), |(s, n), (p, _)| (s + (p[0] + p[1] + p[2]) / 3.0, n + 1));
    let full_scale = (0.2 * sum / n.max(1) as f32).max(f32::MIN_POSITIVE);
    let ref_norm = reference.rgb.iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
    for row in rows.iter_mut() {
        renderer
            .environment_mut()
            .context("no environment light")?
            .set_rotation_eigen(delta, row.e)?;
        let frame = renderer.render(gpu)?;
        let diff = reference.rgb.iter().zip(&frame.rgb).map(|(a, b)| ((a - b) as f64).powi(2));
        row.image_rel_rmse = diff.sum::<f64>().sqrt() / ref_norm.max(f64::MIN_POSITIVE);
        let shown: Vec<bool> =
            frame.rgb.chunks_exact(3).zip(&garment).map(|(a, &g)| g || a != bg).collect();
        let (w, h) = (frame.width as usize, frame.height as usize);
        let img = error_heatmap_image(w, h, &reference.rgb, &frame.rgb, full_scale, Some(&shown));
        write_png(&dir.join(format!("{stem}-heat-e{}.png", row.e)), &img)?;
    }
    Ok(())
}

fn write_coefficients(stem: &str, dir: &Path, curves: &[Vec<f64>]) -> Result<()> {
    let mut csv = String::from("delta_deg");
    (0..curves.len()).for_each(|k| csv += &format!(",o{}", k + 1));
    csv.push('\n');
    for d in 0..360 {
        csv += &d.to_string();
        curves.iter().for_each(|c| csv += &format!(",{:.6e}", c[d]));
        csv.push('\n');
    }
    write_text(&dir.join(format!("{stem}-coefficients.csv")), &csv)?;
    let plot = Plot {
        title: format!("{stem}: eigenweightset coefficients o_k(delta)"),
        x_label: "rotation delta (deg)".into(),
        y_label: "o_k".into(),
        log_y: false,
        log_x: false,
        series: curves
            .iter()
            .enumerate()
            .map(|(k, c)| Series {
                name: format!("o_{}", k + 1),
                points: c.iter().enumerate().map(|(d, v)| (d as f64, *v)).collect(),
                ..Default::default()
            })
            .collect(),
    };
    write_png(&dir.join(format!("{stem}-coefficients.png")), &btf_image::plot::render(&plot))?;
    Ok(())
}

fn write_tables(stem: &str, dir: &Path, a_n: usize, rows: &[EigenRow]) -> Result<()> {
    let mut csv = String::from("e,mean_rel_error,max_rel_error,image_rel_rmse\n");
    let mut md = format!(
        "# Eigenweightset error, {stem}\n\nA = {a_n} rotations; error of U(δ) against the exact gather at the {a_n} rotations midway between the samples; image error at δ = {:.1}°.\n\n| e | mean ‖ΔU‖/‖U‖ | max ‖ΔU‖/‖U‖ | image rel. RMSE | heat map |\n|---:|---:|---:|---:|---|\n",
        180.0 / a_n as f64
    );
    for r in rows {
        writeln!(
            csv,
            "{},{:.6e},{:.6e},{:.6e}",
            r.e, r.mean_rel_error, r.max_rel_error, r.image_rel_rmse
        )?;
        writeln!(
            md,
            "| {} | {:.3e} | {:.3e} | {:.3e} | ![e={}]({stem}-heat-e{}.png) |",
            r.e, r.mean_rel_error, r.max_rel_error, r.image_rel_rmse, r.e, r.e
        )?;
    }
    md += &format!("\n![o_k(δ)]({stem}-coefficients.png)\n");
    write_text(&dir.join(format!("{stem}-error.csv")), &csv)?;
    let plot = Plot {
        title: format!("{stem}: eigenweightset error"),
        x_label: "eigenweightsets e".into(),
        y_label: "relative error of U".into(),
        log_y: true,
        log_x: false,
        series: vec![
            Series {
                name: "mean".into(),
                points: rows.iter().map(|r| (r.e as f64, r.mean_rel_error)).collect(),
                ..Default::default()
            },
            Series {
                name: "max".into(),
                points: rows.iter().map(|r| (r.e as f64, r.max_rel_error)).collect(),
                ..Default::default()
            },
        ],
    };
    write_png(&dir.join(format!("{stem}-error.png")), &btf_image::plot::render(&plot))?;
    Ok(write_text(&dir.join(format!("{stem}-error.md")), &md)?)
}
