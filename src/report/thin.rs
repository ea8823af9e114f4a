//! The report of `btf thin demo` (`report.json`, `report.md`): per frame the frame time of
//! the transmission scene against the same scene with the curtain opaque, and the
//! curtain's brightness front-lit vs back-lit (the contrast of the thin-cloth paper's
//! Fig. 2: reflection front-lit, [TC eq. 7]; the light shining through back-lit, [TC eq. 8]), plus
//! the alpha of [TC eq. 9] measured through the curtain.

use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// Numbers of one frame of the orbit.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameReport {
    /// Frame index.
    pub index: usize,
    /// Angle of the light on its orbit, degrees (0 = in front of the curtain).
    pub light_deg: f64,
    /// Light position (world).
    pub light_position: [f32; 3],
    /// `"front"` (light on the camera's side of the curtain, `y < −0.25`), `"back"`
    /// (`y > 0.25`) or `"edge"` (beside it).
    pub side: String,
    /// Frame time with the curtain opaque, ms.
    pub opaque_ms: f64,
    /// Frame time with `transmission`, ms.
    pub thin_ms: f64,
    /// Mean sheet radiance of the thin curtain (its own light, without what lies behind).
    pub curtain_mean: f64,
    /// Of it, the point light's part (the rest is the environment's).
    pub curtain_point_thin: f64,
    /// The point light's part on the opaque curtain.
    pub curtain_point_opaque: f64,
}

/// The alpha check over the curtain pixels.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AlphaReport {
    /// Curtain pixels (values) measured.
    pub values: usize,
    /// Mean measured alpha at τ₁.
    pub mean_alpha: f64,
    /// Largest measured alpha (the model: ≤ e^{−τ₁}, reached at μ = 1).
    pub max_alpha: f64,
    /// e^{−τ₁}.
    pub bound: f64,
    /// Largest `|α(2τ₁) − α(τ₁)²|`.
    pub max_square_error: f64,
}

/// Means over the frames of one side.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SideMeans {
    /// Frames on this side.
    pub frames: usize,
    /// Mean sheet radiance of the thin curtain.
    pub curtain_mean: f64,
    /// Mean point-light part on the thin curtain.
    pub point_thin: f64,
    /// Mean point-light part on the opaque curtain.
    pub point_opaque: f64,
}

fn side_means(frames: &[FrameReport], side: &str) -> SideMeans {
    let f: Vec<&FrameReport> = frames.iter().filter(|f| f.side == side).collect();
    let n = f.len().max(1) as f64;
    let mean = |g: fn(&FrameReport) -> f64| f.iter().map(|x| g(x)).sum::<f64>() / n;
    SideMeans {
        frames: f.len(),
        curtain_mean: mean(|x| x.curtain_mean),
        point_thin: mean(|x| x.curtain_point_thin),
        point_opaque: mean(|x| x.curtain_point_opaque),
    }
}

/// Writes `report.json` and `report.md` into `out` (atomically) and prints the Markdown.
pub fn write(
    out: &Path,
    frames: &[FrameReport],
    alpha: &AlphaReport,
    tau: f64,
    albedo: f64,
    load: &str,
) -> Result<()> {
    let (front, back) = (side_means(frames, "front"), side_means(frames, "back"));
    let total = |g: fn(&FrameReport) -> f64| frames.iter().map(g).sum::<f64>();
    let ratio = total(|f| f.thin_ms) / total(|f| f.opaque_ms);
    let json = serde_json::json!({
        "tau": tau, "albedo": albedo, "load_average": load,
        "frame_time_ratio": ratio, "front": front, "back": back, "alpha": alpha,
        "frames": frames,
    });
    btf_image::write::write_text(&out.join("report.json"), &serde_json::to_string_pretty(&json)?)?;
    let mut md = String::from("# btf thin demo\n\n");
    writeln!(
        md,
        "The datasets curtain (woven, τ₁ = {tau}, ϖ₀ = {albedo}, isotropic) in front of the synthetic sky that lights it, a point light circling it ({} frames). Load average {load} (lavapipe: ratios mean more than milliseconds).\n",
        frames.len()
    )?;
    writeln!(md, "![orbit](contact.png)\n")?;
    writeln!(
        md,
        "| frame | light ° | side | opaque ms | transmission ms | ratio | curtain | point light (thin) | point light (opaque) |\n|---:|---:|---|---:|---:|---:|---:|---:|---:|"
    )?;
    for f in frames {
        writeln!(
            md,
            "| {} | {:.0} | {} | {:.1} | {:.1} | {:.3} | {:.4} | {:.4} | {:.4} |",
            f.index,
            f.light_deg,
            f.side,
            f.opaque_ms,
            f.thin_ms,
            f.thin_ms / f.opaque_ms,
            f.curtain_mean,
            f.curtain_point_thin,
            f.curtain_point_opaque
        )?;
    }
    writeln!(md, "\nFrame time, transmission / opaque over the orbit: **{ratio:.3}**.\n")?;
    writeln!(
        md,
        "| side | frames | curtain | point light (thin) | point light (opaque) |\n|---|---:|---:|---:|---:|"
    )?;
    for (name, s) in [("front-lit", front), ("back-lit", back)] {
        writeln!(
            md,
            "| {name} | {} | {:.4} | {:.4} | {:.4} |",
            s.frames, s.curtain_mean, s.point_thin, s.point_opaque
        )?;
    }
    writeln!(
        md,
        "\nFront-lit the thin curtain reflects its share `1 − e^{{−τ₁(1/μ + 1/μ₀)}}` of the opaque one's light; back-lit the opaque curtain gets almost nothing from the point light while the thin one lets it through (`f_t μ₀ E`).\n"
    )?;
    writeln!(
        md,
        "Alpha through the curtain (point light off, `(R − R_no background)/background` over {} values): mean {:.4}, largest {:.4} (model: ≤ e^{{−τ₁}} = {:.4}); `|α(2τ₁) − α(τ₁)²|` ≤ {:.2e}.",
        alpha.values, alpha.mean_alpha, alpha.max_alpha, alpha.bound, alpha.max_square_error
    )?;
    btf_image::write::write_text(&out.join("report.md"), &md)?;
    crate::guard::outln!("{md}");
    Ok(())
}
