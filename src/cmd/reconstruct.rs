//! `btf reconstruct IN.eig --view θ,φ --light θ,φ`: the CPU reference texture for one view and
//! one light direction ([S03 eq. 2–5]), written as linear EXR (and optionally an sRGB PNG).

use anyhow::{Context, Result, bail};
use btf_core::Direction;
use btf_core::eigen::EigenStore;
use btf_core::reconstruct::{ReconstructParams, reconstruct};
use std::path::PathBuf;

/// Arguments of `btf reconstruct`.
#[derive(clap::Args)]
pub struct ReconstructArgs {
    /// Eigen store.
    input: PathBuf,
    /// View direction θ,φ in degrees (tangent space).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, required = true)]
    view: Vec<f64>,
    /// Light direction θ,φ in degrees (tangent space).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, required = true)]
    light: Vec<f64>,
    /// View blending: nearest or four.
    #[arg(long, default_value = "four")]
    blend: String,
    /// Light interpolation: nearest or four.
    #[arg(long, default_value = "four")]
    light_interp: String,
    /// Components to use (default: all stored).
    #[arg(short = 'c', long)]
    components: Option<usize>,
    /// Output EXR (linear BTF values).
    #[arg(short = 'o', long)]
    output: PathBuf,
    /// Also write an sRGB PNG preview here.
    #[arg(long)]
    png: Option<PathBuf>,
}

fn direction(v: &[f64], what: &str) -> Result<Direction> {
    if v.len() != 2 || !v.iter().all(|x| x.is_finite()) {
        bail!("--{what} takes θ,φ in degrees, e.g. --{what} 30,45");
    }
    if !(0.0..=180.0).contains(&v[0]) {
        bail!("--{what}: θ = {} is outside [0, 180] degrees", v[0]);
    }
    Ok(Direction::new(v[0], v[1]))
}

/// Runs `btf reconstruct`.
pub fn run(a: ReconstructArgs) -> Result<()> {
    let view = direction(&a.view, "view")?;
    let light = direction(&a.light, "light")?;
    let store =
        EigenStore::open(&a.input).with_context(|| format!("cannot open {}", a.input.display()))?;
    let params = ReconstructParams {
        view_mode: a.blend.parse()?,
        light_mode: a.light_interp.parse()?,
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
    let m = &store.meta().btf;
    btf_image::write::write_exr_rgb(&a.output, m.width, m.height, &tex)?;
    if let Some(png) = a.png {
        let peak = tex.iter().copied().fold(0f32, f32::max);
        btf_image::write::write_png_linear(
            &png,
            m.width,
            m.height,
            &tex,
            if peak > 0.0 { 0.8 / peak } else { 1.0 },
        )?;
    }
    Ok(())
}
