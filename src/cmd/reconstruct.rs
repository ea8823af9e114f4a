//! `btf reconstruct IN.eig --view θ,φ --light θ,φ`: the CPU reference texture for one view and
//! one light direction ([S03 eq. 2–5]), written as linear EXR (and optionally an sRGB PNG).
//!
//! Directions are checked against what the store measured: below the horizon (θ > 90°) is
//! refused, and so is a θ beyond the store's largest sampled θ (for the view or the light)
//! unless `--clamp` asks for the texture at that largest θ (with a warning naming both).

use crate::args::Blend;
use crate::guard::outln;
use anyhow::{Context, Result, bail};
use btf_core::eigen::EigenStore;
use btf_core::reconstruct::{ReconstructParams, reconstruct};
use btf_core::{Direction, Sampling};
use std::path::PathBuf;

/// Arguments of `btf reconstruct`.
#[derive(clap::Args)]
#[command(after_help = "Angles: θ in [0, 90] degrees from the normal, φ any azimuth. A θ \
above 90 (below the horizon) is refused. A θ beyond the largest θ the store sampled is refused \
too (the store holds no measurement there), unless --clamp: then the texture at the largest \
sampled θ (same φ) is written and a warning names both angles.")]
pub struct ReconstructArgs {
    /// Eigen store.
    input: PathBuf,
    /// View direction θ,φ in degrees (tangent space).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, required = true)]
    view: Vec<f64>,
    /// Light direction θ,φ in degrees (tangent space).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, required = true)]
    light: Vec<f64>,
    /// View blending.
    #[arg(long, default_value = "four")]
    blend: Blend,
    /// Light interpolation.
    #[arg(long, default_value = "four")]
    light_interp: Blend,
    /// Beyond the sampled θ range, use the largest sampled θ (with a warning) instead of
    /// refusing.
    #[arg(long)]
    clamp: bool,
    /// Components to use (default: all stored).
    #[arg(short = 'c', long)]
    components: Option<usize>,
    /// Output EXR (linear BTF values).
    #[arg(short = 'o', long = "out", alias = "output")]
    output: PathBuf,
    /// Also write an sRGB PNG preview here.
    #[arg(long)]
    png: Option<PathBuf>,
}

fn direction(v: &[f64], what: &str) -> Result<Direction> {
    if v.len() != 2 || !v.iter().all(|x| x.is_finite()) {
        bail!("--{what} takes θ,φ in degrees, e.g. --{what} 30,45");
    }
    if v[0] > 90.0 {
        bail!(
            "--{what} θ = {}° is below the horizon (θ > 90°): a BTF holds directions above the \
             surface only",
            v[0]
        );
    }
    if v[0] < 0.0 {
        bail!("--{what} θ = {}° is negative: θ is measured from the normal, in [0, 90]", v[0]);
    }
    Ok(Direction::new(v[0], v[1]))
}

/// `d` within the sampled θ range of `sampling`, or clamped to its largest θ with a warning
/// when `clamp`, or an error naming the angle, the store and the range.
fn within_sampled(
    d: Direction,
    sampling: &Sampling,
    what: &str,
    store: &std::path::Path,
    clamp: bool,
) -> Result<Direction> {
    let theta_max = sampling.rings.last().map_or(0.0, |r| r.theta_deg);
    if d.theta_deg <= theta_max + 1e-9 {
        return Ok(d);
    }
    if !clamp {
        bail!(
            "--{what} θ = {}° is beyond the sampled range of {} ({what} directions up to θ = \
             {theta_max}°): the store holds no measurement there; give θ ≤ {theta_max} or add \
             --clamp to use θ = {theta_max}°",
            d.theta_deg,
            store.display()
        );
    }
    eprintln!(
        "warning: --{what} θ = {}° is beyond the sampled range of {}; clamped to θ = {theta_max}° \
         (φ = {}°)",
        d.theta_deg,
        store.display(),
        d.phi_deg
    );
    Ok(Direction::new(theta_max, d.phi_deg))
}

/// Runs `btf reconstruct`.
pub fn run(a: ReconstructArgs) -> Result<()> {
    let view = direction(&a.view, "view")?;
    let light = direction(&a.light, "light")?;
    let store =
        EigenStore::open(&a.input).with_context(|| format!("cannot open {}", a.input.display()))?;
    let m = &store.meta().btf;
    let view = within_sampled(view, &m.view_sampling, "view", &a.input, a.clamp)?;
    let light = within_sampled(light, &m.light_sampling, "light", &a.input, a.clamp)?;
    let params = ReconstructParams {
        view_mode: a.blend.mode(),
        light_mode: a.light_interp.mode(),
        components: a.components,
    };
    let mut outputs: Vec<(&str, &std::path::Path)> = vec![("-o", &a.output)];
    if let Some(png) = &a.png {
        outputs.push(("--png", png));
    }
    crate::guard::refuse_overlap(&outputs, &[("input", &a.input)])?;
    if let Some(png) = &a.png {
        crate::guard::check_file(png, btf_core::fs::PNG)?;
    }
    crate::guard::check_file(&a.output, btf_core::fs::EXR)?;
    let tex = reconstruct(&store, view, light, params)?;
    btf_image::write::write_exr_rgb(&a.output, m.width, m.height, &tex)?;
    let png_note = a.png.as_ref().map_or(String::new(), |p| format!(" and {}", p.display()));
    if let Some(png) = &a.png {
        let peak = tex.iter().copied().fold(0f32, f32::max);
        btf_image::write::write_png_linear(
            png,
            m.width,
            m.height,
            &tex,
            if peak > 0.0 { 0.8 / peak } else { 1.0 },
        )?;
    }
    outln!(
        "wrote the {}×{} texture for view θ {}° φ {}°, light θ {}° φ {}° ({} components, {} \
         view blending, {} light interpolation) to {}{}",
        m.width,
        m.height,
        view.theta_deg,
        view.phi_deg,
        light.theta_deg,
        light.phi_deg,
        a.components.unwrap_or(store.meta().components),
        a.blend,
        a.light_interp,
        a.output.display(),
        png_note
    );
    Ok(())
}
