//! `btf knit strips -o DIR`: the texture bake of [H25]'s yarn strips
//! (`yarn_precompute::strip_bake`, DESIGN §3.4) over a grid of bake settings — camera rays
//! per texel × light directions × texels × tangents per texel — with what each costs and
//! how well the factorised model (`Ψ_M Ψ_N`, `ξ_M ξ_N`, [H25 eq. 10–11]) reproduces the
//! path-traced reference at the bake directions: the coverage-weighted mean, median and
//! 90th percentile of the per-texel residual, and the Ψ fit's own residual. The residual
//! holds the reference's Monte-Carlo noise too, so the `--spp` axis separates noise (it
//! falls as 1/√spp) from the model's error (it stays). Writes `bake.csv`, `bake.md` and per
//! bake a picture `bake-TAG.png`: coverage, fiber tangent (|t_T|, |t_w|, |t_e| as RGB), AO
//! and the residual as a heat map (0 → green, ≥ 0.5 → red), stacked, 4× enlarged.

use super::knit::{ShadingChoice, load_yarn};
use super::knit_render::bcsdf as fiber_bcsdf;
use crate::guard::{self, outln};
use anyhow::{Result, bail};
use btf_image::color::heat_ramp;
use btf_image::write::{write_png_rgb8, write_text};
use clap::Args;
use std::fmt::Write as _;
use std::path::PathBuf;
use yarn_precompute::{StripBake, StripBakeSettings};

/// `btf knit strips`.
#[derive(Args)]
pub struct StripsArgs {
    /// Output folder (bake.csv, bake.md, bake-*.png).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Yarn preset name or yarn TOML file.
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Fiber scattering (simple, khungurn, huang).
    #[arg(long, default_value = "khungurn")]
    pub shading: ShadingChoice,
    /// Fiber colour R,G,B (linear).
    #[arg(long, default_value = "0.8,0.6,0.4")]
    pub albedo: String,
    /// Camera rays per texel, one bake per value.
    #[arg(long, value_delimiter = ',', default_value = "16")]
    pub spp: Vec<u32>,
    /// Light directions per angle (D × D), one bake per value.
    #[arg(long, value_delimiter = ',', default_value = "8")]
    pub directions: Vec<usize>,
    /// Texels WxH over one ply pitch × the strip width, one bake per value.
    #[arg(long, value_delimiter = ',', default_value = "64x32")]
    pub texels: Vec<String>,
    /// Fiber tangents per texel, one bake per value.
    #[arg(long, value_delimiter = ',', default_value = "4")]
    pub tangents: Vec<usize>,
    /// Seed of the fibers and paths.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Remove this command's earlier outputs from the folder first.
    #[arg(long)]
    pub fresh: bool,
}

fn texels(s: &str) -> Result<(usize, usize)> {
    let Some((w, h)) = s.split_once('x') else { bail!("--texels {s}: WxH, e.g. 64x32") };
    match (w.trim().parse(), h.trim().parse()) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => bail!("--texels {s}: WxH, e.g. 64x32"),
    }
}

/// A CSV cell: the value, or empty when nothing was measured (never `NaN`).
fn cell(x: f64) -> String {
    if x.is_finite() { format!("{x:.5}") } else { String::new() }
}

/// Coverage-weighted quantile `q` of the residual over texels with coverage.
fn quantile(b: &StripBake, q: f64) -> f64 {
    let mut v: Vec<(f64, f64)> = b
        .alpha
        .iter()
        .zip(&b.residual)
        .filter(|(a, _)| **a > 0.0)
        .map(|(&a, &r)| (r as f64, a as f64))
        .collect();
    v.sort_by(|x, y| x.0.total_cmp(&y.0));
    let total: f64 = v.iter().map(|x| x.1).sum();
    let mut acc = 0.0;
    for (r, w) in &v {
        acc += w;
        if acc >= q * total {
            return *r;
        }
    }
    v.last().map_or(f64::NAN, |x| x.0)
}

/// The bake's picture: four panels (coverage, tangent, AO, residual) stacked, 4× enlarged.
fn picture(b: &StripBake) -> (usize, usize, Vec<u8>) {
    let (w, h, k) = (b.settings.width, b.settings.height, b.settings.tangents);
    let z = 4;
    let (pw, ph) = (w * z, 4 * h * z + 3 * z);
    let mut px = vec![40u8; pw * ph * 3];
    for panel in 0..4 {
        for j in 0..h {
            for i in 0..w {
                let t = j * w + i;
                let c: [u8; 3] = match panel {
                    0 => [(255.0 * b.alpha[t]).round() as u8; 3],
                    1 => {
                        let mut m = [0.0f32; 3];
                        for tk in &b.tangent[t * k..(t + 1) * k] {
                            (0..3).for_each(|c| m[c] += tk[c].abs() / k as f32);
                        }
                        m.map(|x| (255.0 * x.clamp(0.0, 1.0)).round() as u8)
                    }
                    2 => [(255.0 * b.ao[t]).round() as u8; 3],
                    _ if b.alpha[t] > 0.0 => heat_ramp(2.0 * b.residual[t] as f64),
                    _ => [0; 3],
                };
                for y in 0..z {
                    for x in 0..z {
                        let row = panel * (h * z + z) + (h - 1 - j) * z + y;
                        let o = 3 * (row * pw + i * z + x);
                        px[o..o + 3].copy_from_slice(&c);
                    }
                }
            }
        }
    }
    (pw, ph, px)
}

/// Runs `btf knit strips`.
pub fn run(a: StripsArgs) -> Result<()> {
    let inputs = super::knit::chart_inputs_of("", &a.yarn);
    guard::refuse_overlap(&[("-o", &a.output)], &inputs)?;
    let params = load_yarn(&a.yarn)?;
    let bcsdf = fiber_bcsdf(a.shading.as_str())?;
    let [r, g, b] = crate::args::numbers::<f32, 3>(&a.albedo, "--albedo")?;
    if ![r, g, b].iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)) {
        bail!("--albedo {}: each channel in [0, 1]", a.albedo);
    }
    let mut grid = Vec::new();
    for &spp in &a.spp {
        for &d in &a.directions {
            for t in &a.texels {
                let (w, h) = texels(t)?;
                for &k in &a.tangents {
                    let s = StripBakeSettings {
                        width: w,
                        height: h,
                        directions: d,
                        spp,
                        tangents: k,
                        seed: a.seed,
                        ..StripBakeSettings::default()
                    };
                    s.validate()?;
                    grid.push(s);
                }
            }
        }
    }
    guard::output_folder(&a.output, "knit strips", a.fresh, &guard::report_output)?;
    let mut csv = String::from(
        "spp,directions,width,height,tangents,seconds,mean_residual,median_residual,p90_residual,mean_residual_psi,gpu_bytes,half_width_m,ply_pitch_m\n",
    );
    let mut md = format!(
        "## Yarn-strip bakes of {} ({} shading)\n\n| spp | directions | texels | tangents | bake s | mean residual | median | 90 % | Ψ residual | GPU KiB |\n|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n",
        params.name,
        a.shading.as_str()
    );
    let total: u64 = grid.iter().map(|s| (s.width * s.height) as u64).sum();
    let bar = crate::progress::bar(total, "strip bakes");
    for s in &grid {
        let b = StripBake::bake(&params, &bcsdf, [r, g, b], s, &|_| bar.inc(1))?;
        let n = b.alpha.len();
        let cover: f64 = b.alpha.iter().map(|&x| x as f64).sum();
        let psi =
            b.alpha.iter().zip(&b.residual_psi).map(|(&a, &r)| a as f64 * r as f64).sum::<f64>()
                / cover.max(1e-12);
        let (med, p90) = (quantile(&b, 0.5), quantile(&b, 0.9));
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.3},{:.5},{},{},{:.5},{},{:.6e},{:.6e}",
            s.spp,
            s.directions,
            s.width,
            s.height,
            s.tangents,
            b.seconds,
            b.mean_residual(),
            cell(med),
            cell(p90),
            psi,
            b.gpu_bytes(),
            b.half_width,
            b.ply_pitch
        );
        let _ = writeln!(
            md,
            "| {} | {}×{} | {}×{} | {} | {:.1} | {:.3} | {:.3} | {:.3} | {:.3} | {:.0} |",
            s.spp,
            s.directions,
            s.directions,
            s.width,
            s.height,
            s.tangents,
            b.seconds,
            b.mean_residual(),
            med,
            p90,
            psi,
            b.gpu_bytes() as f64 / 1024.0
        );
        let tag =
            format!("spp{}-d{}-{}x{}-k{}", s.spp, s.directions, s.width, s.height, s.tangents);
        let (pw, ph, px) = picture(&b);
        write_png_rgb8(&a.output.join(format!("bake-{tag}.png")), pw, ph, px)?;
        debug_assert_eq!(n, s.width * s.height);
    }
    bar.finish_and_clear();
    md.push_str("\nResidual: per texel, the relative RMS (luminance, over the bake directions) of the baked model `L_m·Ψ̂·ξ̂` against the path-traced reference of that texel; coverage-weighted over the texels. It holds the reference's Monte-Carlo noise: what stays as spp grows is the model's error. Pictures `bake-*.png`: coverage, tangent (|t_T|, |t_w|, |t_e|), AO, residual (green 0 → red ≥ 0.5), u to the right, v up.\n");
    write_text(&a.output.join("bake.csv"), &csv)?;
    write_text(&a.output.join("bake.md"), &md)?;
    outln!("{md}");
    outln!("written to {}", a.output.join("bake.md").display());
    Ok(())
}
