//! `btf thin validate`: the first-order thin-slab terms against a Monte-Carlo solution
//! of the same slab, as a table of relative errors per optical thickness (the check of
//! `btf_core::thin_slab`, [TC eq. 4–5]); `btf thin demo`: the curtain scene
//! of `crate::thin_demo`.

use anyhow::{Result, bail};
use btf_core::thin_slab::monte_carlo::{
    ErrorRow, McParams, TABLE_MU, TABLE_MU0, first_order_error_table,
};
use std::path::PathBuf;

/// `btf thin …` subcommands.
#[derive(clap::Subcommand)]
pub enum ThinCmd {
    /// First-order reflection/transmission vs Monte Carlo for a range of thicknesses.
    Validate(ValidateArgs),
    /// A curtain in front of a sky with a point light circling it: frames, contact sheet,
    /// frame-time and front-/back-lit report.
    Demo(crate::demo::thin::DemoArgs),
}

/// Arguments of `btf thin validate`.
#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Optical thicknesses τ₁, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.1,0.2,0.5,1,2")]
    tau: Vec<f64>,
    /// Single-scattering albedo ϖ₀.
    #[arg(long, default_value_t = 1.0)]
    albedo: f64,
    /// Photons per (τ₁, μ₀).
    #[arg(long, default_value_t = 400_000)]
    photons: u64,
    /// Seed of the Monte-Carlo generator.
    #[arg(long, default_value_t = 0x5eed)]
    seed: u64,
    /// Print JSON instead of a Markdown table.
    #[arg(long)]
    json: bool,
    /// Also write `thin-validate.md` and `thin-validate.json` into this folder.
    #[arg(long)]
    report: Option<PathBuf>,
}

/// Runs `btf thin …`.
pub fn run(c: ThinCmd) -> Result<()> {
    match c {
        ThinCmd::Validate(a) => validate(a),
        ThinCmd::Demo(a) => crate::demo::thin::run(a),
    }
}

fn validate(a: ValidateArgs) -> Result<()> {
    if a.tau.iter().any(|t| !(t.is_finite() && *t > 0.0 && *t <= 50.0)) {
        bail!("--tau: every thickness must be in (0, 50], got {:?}", a.tau);
    }
    if !(0.0..=1.0).contains(&a.albedo) || a.albedo == 0.0 {
        bail!("--albedo must be in (0, 1], got {}", a.albedo);
    }
    if !(1000..=100_000_000).contains(&a.photons) {
        bail!("--photons must be in 1000..=100000000, got {}", a.photons);
    }
    let params = McParams { photons: a.photons, seed: a.seed, ..Default::default() };
    let rows = first_order_error_table(&a.tau, a.albedo, &params);
    let md = markdown(&rows, a.albedo, a.photons);
    let json = serde_json::to_string_pretty(&serde_json::json!({
        "albedo": a.albedo, "photons": a.photons, "seed": a.seed,
        "mu0": TABLE_MU0, "mu": TABLE_MU, "rows": rows,
    }))?;
    if let Some(dir) = &a.report {
        crate::guard::output_folder(dir, "thin validate", false, &|_| false)?;
        for (name, text) in [("thin-validate.md", &md), ("thin-validate.json", &json)] {
            btf_core::fs::write_atomic(&dir.join(name), text.as_bytes())?;
        }
    }
    crate::guard::outln!("{}", if a.json { &json } else { &md });
    Ok(())
}

fn markdown(rows: &[ErrorRow], albedo: f64, photons: u64) -> String {
    let mut s = format!(
        "First-order thin-slab terms vs Monte Carlo (ϖ₀ = {albedo}, isotropic, {photons} photons per μ₀; \
         max over μ₀ ∈ {TABLE_MU0:?}, μ ∈ {TABLE_MU:?})\n\n\
         | τ₁ | formula vs MC 1st order | f_r vs MC all orders | f_t vs MC all orders | MC rel. std. error |\n\
         |---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        s += &format!(
            "| {} | {:.2} % | {:.2} % | {:.2} % | {:.2} % |\n",
            r.tau,
            100.0 * r.single_rel_err,
            100.0 * r.reflect_rel_err,
            100.0 * r.transmit_rel_err,
            100.0 * r.mc_rel_std_err
        );
    }
    s
}
