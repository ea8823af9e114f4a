//! `btf capture`: raw captures → BTF store (`process`) and its accuracy against a synthetic
//! capture's ground truth (`score`). Arguments are validated here; the work is in
//! `btf_capture::capture`.

use anyhow::{Context, Result};
use btf_capture::capture::rectify::Grid;
use btf_capture::capture::{self as cap, CaptureLayout, Filter, ProcessOptions, Roi, score};
use btf_core::store::BtfStore;
use std::path::PathBuf;

/// `btf capture` subcommands.
#[derive(clap::Subcommand)]
pub enum CaptureCmd {
    /// Register, rectify, crop and blend raw captures into a BTF store.
    Process(ProcessArgs),
    /// Score a processed store against the capture's ground truth (synthetic captures).
    Score(ScoreArgs),
    /// How far past the robot's tolerance registration holds: virtual captures registered
    /// by camera resolution × pose error × view angle, a table and a plot.
    RegistrationSweep(crate::cmd::registration_sweep::SweepArgs),
}

crate::args::choices! {
    /// `btf capture process --filter`: how a texel is resampled from a raw image.
    FilterChoice {
        /// A box over the texel's footprint in the raw image.
        Footprint = "footprint",
        /// Bilinear at the texel's centre.
        Bilinear = "bilinear",
    }
}

crate::args::choices! {
    /// `btf capture process --fallback`.
    FallbackChoice {
        /// Register from the nominal pose.
        Nominal = "nominal",
    }
}

crate::args::choices! {
    /// `btf capture process --registration`.
    RegistrationChoice {
        /// Point markers.
        Markers = "markers",
        /// Point markers plus border-line samples (experimental: biased in some views, see
        /// btf-capture/README.md).
        MarkersLines = "markers+lines",
    }
}

crate::args::choices! {
    /// `btf capture process --light-correction`.
    LightCorrection {
        /// Scale by cos θ_l / cos θ_l' for the registered plate tilt.
        Cosine = "cosine",
        /// No correction.
        None = "none",
    }
}

/// Arguments of `btf capture process`.
#[derive(clap::Args)]
pub struct ProcessArgs {
    /// Folder with capture.toml and the raw images.
    raw_dir: PathBuf,
    /// Output BTF store.
    #[arg(short = 'o', long = "out", alias = "output")]
    output: PathBuf,
    /// Texels per side of the normtextures.
    #[arg(long, default_value_t = 256)]
    size: usize,
    /// Pixels per side of the rectified frontal frame of the sample (the ROI's units).
    #[arg(long, default_value_t = 1024)]
    rectified_size: usize,
    /// Region of interest x,y,w,h in rectified pixels (square), `auto` (inset so that no
    /// texel reads past the sample's edge in any view) or `full` (the whole sample).
    #[arg(long, default_value = "auto")]
    roi: String,
    /// Edge-blend width in output texels (default: size/16).
    #[arg(long)]
    blend_width: Option<usize>,
    /// Resampling filter.
    #[arg(long, default_value = "footprint")]
    filter: FilterChoice,
    /// Register slots whose markers fail from the nominal pose, with a warning.
    #[arg(long)]
    fallback: Option<FallbackChoice>,
    /// Keep the images of an interrupted run.
    #[arg(long)]
    resume: bool,
    /// Shard of the processing (its view slots) when several processes share it.
    #[command(flatten)]
    shard: crate::args::ShardArgs,
    /// Registration features.
    #[arg(long, default_value = "markers")]
    registration: RegistrationChoice,
    /// Store element type.
    #[arg(long, default_value = "f32")]
    dtype: crate::args::Dtype,
    /// Light-incidence correction for the registered plate tilt.
    #[arg(long, default_value = "cosine")]
    light_correction: LightCorrection,
    /// Print a JSON summary on standard output.
    #[arg(long)]
    json: bool,
}

/// Arguments of `btf capture score`.
#[derive(clap::Args)]
pub struct ScoreArgs {
    /// The processed BTF store.
    store: PathBuf,
    /// The raw capture folder with truth.toml.
    #[arg(long)]
    truth: PathBuf,
    /// Also rectify again with every filter and compare error and time.
    #[arg(long)]
    compare_filters: bool,
    /// Write score.json and filters.md into this folder.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print one JSON object (the keys of score.json) instead of the table.
    #[arg(long)]
    json: bool,
    /// Also score against the nominal-direction (orthographic) truth, which charges the
    /// set-up's perspective (doubles the truth's cost).
    #[arg(long)]
    nominal: bool,
}

/// Runs `btf capture`.
pub fn run(cmd: CaptureCmd) -> Result<()> {
    match cmd {
        CaptureCmd::Process(a) => process(a),
        CaptureCmd::Score(a) => score_cmd(a),
        CaptureCmd::RegistrationSweep(a) => crate::cmd::registration_sweep::run(a),
    }
}

fn parse_roi(s: &str) -> Result<Roi> {
    match s {
        "full" => return Ok(Roi::Full),
        "auto" => return Ok(Roi::Auto),
        _ => {}
    }
    let r =
        crate::args::numbers::<f64, 4>(s, "--roi").context("--roi takes x,y,w,h, auto or full")?;
    Ok(Roi::Rect(r))
}

fn process(a: ProcessArgs) -> Result<()> {
    let filter = Filter::from_name(a.filter.as_str())
        .with_context(|| format!("--filter '{}' is not footprint or bilinear", a.filter))?;
    let fallback_nominal = a.fallback == Some(FallbackChoice::Nominal);
    let dtype = a.dtype.dtype();
    let use_lines = a.registration == RegistrationChoice::MarkersLines;
    let correct_light_incidence = a.light_correction == LightCorrection::Cosine;
    let mut opt = ProcessOptions {
        size: a.size,
        rectified_size: a.rectified_size,
        roi: parse_roi(&a.roi)?,
        blend_width: a.blend_width.unwrap_or(a.size / 16),
        filter,
        fallback_nominal,
        resume: a.resume,
        dtype,
        correct_light_incidence,
        shard: a.shard.shard()?,
        ..ProcessOptions::default()
    };
    opt.register.use_lines = use_lines;
    crate::guard::refuse_overlap(&[("-o", &a.output)], &[("raw folder", &a.raw_dir)])?;
    if let Some(shard) = opt.shard {
        let layout = CaptureLayout::read(&a.raw_dir)?;
        let n = layout.sampling.len();
        let views = shard.range(n);
        let bar =
            crate::progress::bar((views.len() * n) as u64, &format!("shard {}", shard.label()));
        let rep = cap::process(&a.raw_dir, &a.output, &opt, &|| bar.inc(1))
            .with_context(|| format!("cannot process {}", a.raw_dir.display()))?;
        bar.finish_and_clear();
        for r in rep.registrations.iter().filter(|r| r.fallback_nominal) {
            eprintln!("warning: view slot {} registered from the nominal pose", r.view);
        }
        crate::guard::outln!(
            "shard {}: view slots {}..{}: {} images processed ({} kept) into {}",
            shard.label(),
            views.start,
            views.end,
            rep.images_written,
            rep.images_kept,
            crate::guard::partial_of(&a.output).display()
        );
        crate::guard::outln!("  when every shard is done: btf finalize {}", a.output.display());
        return Ok(());
    }
    let layout = CaptureLayout::read(&a.raw_dir)?;
    let n = layout.sampling.len() as u64;
    let bar = crate::progress::bar(n * n, "rectify");
    let t0 = std::time::Instant::now();
    let rep = crate::guard::resumable(&a.output, || {
        cap::process(&a.raw_dir, &a.output, &opt, &|| bar.inc(1))
            .with_context(|| format!("cannot process {}", a.raw_dir.display()))
    })?;
    bar.finish_and_clear();
    let seconds = t0.elapsed().as_secs_f64();
    for r in rep.registrations.iter().filter(|r| r.fallback_nominal) {
        eprintln!(
            "warning: view slot {} registered from the nominal pose: {}",
            r.view,
            r.missed.join("; ")
        );
    }
    let worst = rep.registrations.iter().map(|r| r.marker_rms_px).fold(0.0, f64::max);
    // How well the camera resolves the store: below ~1 px per texel along an axis, the
    // store is finer than the raw images and the camera, not the processing, bounds its error.
    let resolution = rep.pixels_per_texel();
    let (least, least_view) = resolution
        .iter()
        .enumerate()
        .map(|(v, r)| (r[0], v))
        .fold((f64::INFINITY, 0), |m, x| if x.0 < m.0 { x } else { m });
    let frontal = resolution.iter().map(|r| r[1]).fold(0.0, f64::max);
    if least < 1.0 {
        let d = layout.sampling.direction(least_view);
        eprintln!(
            "warning: the camera gives {least:.2} px per texel along the most foreshortened axis \
             (view slot {least_view}, θ {:.0}°; up to {frontal:.2} px elsewhere): texel detail finer \
             than a pixel is lost there, so the store's error is bounded by the camera — a smaller \
             --size or a finer camera resolves it (BENCHMARKS.md, capture processing)",
            d.theta_deg
        );
    }
    if a.json {
        let j = serde_json::json!({
            "images_written": rep.images_written, "images_kept": rep.images_kept, "seconds": seconds,
            "views": rep.registrations.len(), "fallback_views": rep.registrations.iter().filter(|r| r.fallback_nominal).map(|r| r.view).collect::<Vec<_>>(),
            "worst_marker_rms_px": worst, "texel_mm": rep.grid.texel_mm,
            "pixels_per_texel": resolution,
        });
        crate::guard::outln!("{j}");
    } else {
        crate::guard::outln!(
            "processed {} images ({} kept) of {} view slots into {} ({}², {} filter) in {:.1} s; worst marker RMS {:.3} px",
            rep.images_written,
            rep.images_kept,
            rep.registrations.len(),
            a.output.display(),
            a.size,
            filter.name(),
            seconds,
            worst
        );
    }
    Ok(())
}

/// The truth normtextures of a synthetic capture: its material's BTF averaged over each
/// texel's square (`k × k` stratified points, `k` giving ≥ 3 points per material texel,
/// as the material has sub-texel detail), seen from the true camera position
/// ([`score::Truth::Measurable`]) or orthographically at the nominal view
/// ([`score::Truth::Nominal`]); always under the nominal light.
fn truth_fn(
    layout: &CaptureLayout,
) -> Result<impl Fn(usize, usize, &Grid, score::Truth) -> Vec<[f32; 3]> + Sync + '_> {
    let m = &layout.material;
    let kind = m["kind"]
        .as_str()
        .context("capture.toml has no [material] kind: not a synthetic capture")?;
    let mut spec = datasets::MaterialSpec::new(
        datasets::MaterialKind::from_name(kind)?,
        m["size"].as_u64().context("material size")? as usize,
    );
    spec.seed = m["seed"].as_u64().unwrap_or(1);
    if let Some(a) =
        m.get("albedo").and_then(|a| serde_json::from_value::<[f64; 3]>(a.clone()).ok())
    {
        spec.albedo = Some(a);
    }
    let material = datasets::Material::build(&spec)?;
    let (s_mm, n_mat) = (layout.plate.sample_mm, spec.size as f64);
    let poses = score::true_poses(layout)?;
    Ok(move |view: usize, light: usize, g: &Grid, which: score::Truth| {
        let k = ((3.0 * g.texel_mm / (s_mm / n_mat)).ceil() as usize).clamp(2, 16);
        let view_nominal = layout.sampling.direction(view).to_vector();
        let light_dir = layout.sampling.direction(light).to_vector();
        let weight = 1.0 / (k * k) as f64;
        (0..g.n * g.n)
            .map(|t| {
                let centre = g.centre_mm(t % g.n, t / g.n);
                let mut sum = [0f64; 3];
                for s in 0..k * k {
                    let offset = |i: usize| ((i as f64 + 0.5) / k as f64 - 0.5) * g.texel_mm;
                    let p = [centre[0] + offset(s % k), centre[1] + offset(s / k)];
                    let v = match which {
                        score::Truth::Measurable => poses[view].view_dir_sample(layout, view, p),
                        score::Truth::Nominal => view_nominal,
                    };
                    let texel = |x: f64| (x + s_mm / 2.0) / s_mm * n_mat;
                    let e = material.eval_at(texel(p[0]), texel(p[1]), v, light_dir);
                    (0..3).for_each(|c| sum[c] += e[c] * weight);
                }
                sum.map(|x| x as f32)
            })
            .collect()
    })
}

fn score_cmd(a: ScoreArgs) -> Result<()> {
    let store =
        BtfStore::open(&a.store).with_context(|| format!("cannot open {}", a.store.display()))?;
    let layout = CaptureLayout::read(&a.truth)?;
    let truth = truth_fn(&layout)?;
    let filters: &[Filter] =
        if a.compare_filters { &[Filter::Bilinear, Filter::Footprint] } else { &[] };
    let s = score::score(&store, &layout, &truth, filters, a.nominal).with_context(|| {
        format!("cannot score {} against {}", a.store.display(), a.truth.display())
    })?;
    let json = serde_json::to_string_pretty(&s)?;
    if let Some(dir) = &a.report {
        crate::guard::refuse_overlap(
            &[("--report", dir)],
            &[("store", &a.store), ("--truth", &a.truth)],
        )?;
        crate::guard::output_folder(dir, "capture score", false, &|_| false)?;
        btf_core::fs::write_atomic(&dir.join("score.json"), json.as_bytes())?;
        let md = format!(
            "# Capture score: {}\n\nmean reprojection {:.4} texel, max {:.4} texel (texel = {:.4} mm); rel. RMSE {:.5}\n\n{}",
            a.store.display(),
            s.mean_reprojection_texels,
            s.max_reprojection_texels,
            s.texel_mm,
            s.rel_rmse,
            score::filter_table_markdown(&s.filters)
        );
        btf_core::fs::write_atomic(&dir.join("filters.md"), md.as_bytes())?;
    }
    if a.json {
        crate::guard::outln!("{json}");
    } else {
        crate::guard::outln!("{}", score_table(&s, &a));
    }
    Ok(())
}

/// The score as a human-readable table (all lengths in texels of the store).
fn score_table(s: &score::Score, a: &ScoreArgs) -> String {
    let mut t = format!(
        "capture score of {} against {}\n  texel              {:.4} mm, light-incidence correction {}\n  \
         reprojection       mean {:.4} texel, max {:.4} texel\n  rel. RMSE          {:.5}",
        a.store.display(),
        a.truth.display(),
        s.texel_mm,
        if s.light_incidence_correction { "on" } else { "off" },
        s.mean_reprojection_texels,
        s.max_reprojection_texels,
        s.rel_rmse
    );
    if let Some(n) = s.rel_rmse_nominal {
        t += &format!(" (nominal-direction truth: {n:.5})");
    }
    let fallback = if s.fallback_views.is_empty() {
        "none".to_string()
    } else {
        s.fallback_views.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ")
    };
    t += &format!("\n  fallback views     {fallback}\n\n  view θ   rel. RMSE");
    if !s.rel_rmse_nominal_by_theta.is_empty() {
        t += "   nominal";
    }
    for (i, [theta, rel]) in s.rel_rmse_by_theta.iter().enumerate() {
        t += &format!("\n  {theta:5.1}°   {rel:9.5}");
        if let Some([_, n]) = s.rel_rmse_nominal_by_theta.get(i) {
            t += &format!("   {n:7.5}");
        }
    }
    if !s.filters.is_empty() {
        t += &format!("\n\n{}", score::filter_table_markdown(&s.filters).trim_end());
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_score_table_names_one_unit_and_every_ring() {
        let s = score::Score {
            mean_reprojection_texels: 0.0123,
            max_reprojection_texels: 0.0456,
            rel_rmse: 0.019,
            rel_rmse_nominal: Some(0.048),
            texel_mm: 4.6,
            per_view: vec![],
            rel_rmse_by_theta: vec![[0.0, 0.01], [45.0, 0.02]],
            rel_rmse_nominal_by_theta: vec![[0.0, 0.03], [45.0, 0.05]],
            light_incidence_correction: true,
            fallback_views: vec![3],
            filters: vec![],
        };
        let a = ScoreArgs {
            store: "m.btf".into(),
            truth: "raw".into(),
            compare_filters: false,
            report: None,
            json: false,
            nominal: true,
        };
        let t = score_table(&s, &a);
        assert!(t.contains("mean 0.0123 texel, max 0.0456 texel"), "{t}");
        assert!(!t.contains("px"), "one unit, texels: {t}");
        assert!(t.contains(" 45.0°     0.02000   0.05000"), "{t}");
        assert!(
            t.contains("fallback views     3") && t.contains("nominal-direction truth: 0.04800")
        );
    }
}
