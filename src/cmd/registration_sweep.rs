//! `btf capture registration-sweep`: how far past the robot's tolerance capture registration
//! holds, by camera resolution, pose error and view angle.
//!
//! For every resolution × pose-error σ (degrees and millimetres alike, per axis, as the
//! virtual gonioreflectometer draws them) × seed, the registration images of a virtual
//! capture are rendered — the most frontal lights of every view slot, as `capture process`
//! averages them — and every slot is registered exactly as `capture process` registers it
//! (`btf_capture::capture::register`). Its homography is compared with the true pose's: the
//! largest image distance over a 5 × 5 grid on the sample square. A slot is *registered*
//! when that distance is below `--max-error-px`, *wrong* when the registration succeeded but
//! is further off, and *refused* when registration failed (the message is kept in the CSV).
//! Writes `registration.md` (the table), `registration.csv` (one row per slot) and
//! `registration.png` (registered fraction against σ, one curve per view angle, one panel per
//! resolution).

use crate::guard::outln;
use anyhow::{Context, Result, bail};
use btf_capture::capture::{CaptureLayout, ProcessOptions, markers::Gray, process, register};
use datasets::capture::{CaptureSpec, render};
use datasets::{MaterialKind, MaterialSpec};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `btf capture registration-sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Output folder for registration.md, .csv and .png.
    #[arg(short = 'o', long, alias = "output")]
    out: PathBuf,
    /// Camera resolutions `WxH,WxH,…`.
    #[arg(long, default_value = "320x240,480x360,1280x960")]
    resolutions: String,
    /// Pose-error standard deviations σ (applied as σ° and σ mm).
    #[arg(long, default_value = "0.5,1,1.5,2,3")]
    sigmas: String,
    /// View zenith angles (degrees); 0 is one slot, every other ring has `--azimuths`.
    #[arg(long, default_value = "0,30,45,60,75")]
    angles: String,
    /// View slots per ring above the pole.
    #[arg(long, default_value_t = 4)]
    azimuths: usize,
    /// Captures (seeds) per resolution and σ.
    #[arg(long, default_value_t = 4)]
    seeds: u64,
    /// Largest grid error (pixels) that counts as registered.
    #[arg(long, default_value_t = 0.5)]
    max_error_px: f64,
    /// Rays per pixel side of the rendered images.
    #[arg(long, default_value_t = 2)]
    supersample: usize,
    /// Register without the pose search (to measure what it adds).
    #[arg(long)]
    no_pose_search: bool,
    /// Clear the table and pictures of an earlier sweep in `--out` first.
    #[arg(long)]
    fresh: bool,
    /// Print a JSON summary on standard output.
    #[arg(long)]
    json: bool,
}

/// One registered view slot.
struct Outcome {
    resolution: (usize, usize),
    sigma: f64,
    seed: u64,
    view: usize,
    theta_deg: f64,
    /// Grid error (pixels) of a registration that succeeded.
    error_px: Option<f64>,
    /// Markers used, of a registration that succeeded.
    markers: usize,
    /// The true plate pose away from nominal: rotation angle (degrees), shift (mm).
    true_pose: (f64, f64),
    /// The pose behind the registered homography, the same way (`None` if refused).
    registered_pose: Option<(f64, f64)>,
    /// Why registration failed.
    refused: Option<String>,
}

fn list<T: std::str::FromStr>(s: &str, what: &str) -> Result<Vec<T>> {
    s.split(',')
        .map(|x| x.trim().parse().map_err(|_| anyhow::anyhow!("{what} '{s}': cannot read '{x}'")))
        .collect()
}

fn resolutions(s: &str) -> Result<Vec<(usize, usize)>> {
    s.split(',')
        .map(|r| {
            let (w, h) = r.trim().split_once('x').context("expected WxH")?;
            Ok((w.parse()?, h.parse()?))
        })
        .collect::<Result<_>>()
        .with_context(|| format!("--resolutions '{s}': expected WxH,WxH,…"))
}

fn what_it_writes(name: &str) -> bool {
    name.starts_with("registration.") || btf_core::fs::is_temp_name(name)
}

/// Runs `btf capture registration-sweep`.
pub fn run(a: SweepArgs) -> Result<()> {
    let res = resolutions(&a.resolutions)?;
    let sigmas: Vec<f64> = list(&a.sigmas, "--sigmas")?;
    let angles: Vec<f64> = list(&a.angles, "--angles")?;
    if sigmas.iter().any(|s| !(s.is_finite() && (0.0..=20.0).contains(s))) {
        bail!("--sigmas '{}': every σ must lie in 0..=20", a.sigmas);
    }
    if angles.iter().any(|t| !(t.is_finite() && (0.0..=85.0).contains(t))) {
        bail!("--angles '{}': every angle must lie in 0..=85 degrees", a.angles);
    }
    if !(1..=64).contains(&a.azimuths) || !(1..=1000).contains(&a.seeds) {
        bail!("--azimuths must lie in 1..=64 and --seeds in 1..=1000");
    }
    if !(a.max_error_px.is_finite() && a.max_error_px > 0.0) {
        bail!("--max-error-px must be a positive number");
    }
    let rings: Vec<String> =
        angles.iter().map(|&t| format!("{t}x{}", if t == 0.0 { 1 } else { a.azimuths })).collect();
    let sampling = datasets::capture::parse_sampling(&format!("rings:{}", rings.join(",")))?;
    crate::guard::output_folder(&a.out, "capture registration-sweep", a.fresh, &what_it_writes)?;

    let cases: Vec<((usize, usize), f64, u64)> = res
        .iter()
        .flat_map(|&r| sigmas.iter().flat_map(move |&s| (1..=a.seeds).map(move |k| (r, s, k))))
        .collect();
    let bar = crate::progress::bar(cases.len() as u64, "captures registered");
    let outcomes: Vec<Outcome> = cases
        .par_iter()
        .map(|&(r, sigma, seed)| {
            let mut material = MaterialSpec::new(MaterialKind::Knit, 16);
            material.sampling = sampling.clone();
            let mut spec = CaptureSpec::new(material);
            (spec.width, spec.height) = r;
            (spec.pose_noise_deg, spec.pose_noise_mm) = (sigma, sigma);
            spec.seed = seed;
            spec.supersample = a.supersample;
            let out = register_capture(&spec, !a.no_pose_search);
            bar.inc(1);
            out
        })
        .collect::<Result<Vec<Vec<Outcome>>>>()?
        .into_iter()
        .flatten()
        .collect();
    bar.finish_and_clear();

    let table = table(&outcomes, &res, &sigmas, &angles, a.max_error_px);
    let header = format!(
        "# Capture registration past the robot's tolerance\n\n`btf capture registration-sweep \
         --resolutions {} --sigmas {} --angles {} --azimuths {} --seeds {} --max-error-px {}{}`: \
         {} view slots. A cell is registered/slots (largest grid error of those, px); *wrong* \
         counts registrations further off than {} px, *refused* failed ones.\n\n",
        a.resolutions,
        a.sigmas,
        a.angles,
        a.azimuths,
        a.seeds,
        a.max_error_px,
        if a.no_pose_search { " --no-pose-search" } else { "" },
        outcomes.len(),
        a.max_error_px
    );
    btf_image::write::write_text(&a.out.join("registration.md"), &(header + &table))?;
    btf_image::write::write_text(&a.out.join("registration.csv"), &csv(&outcomes))?;
    let panels: Vec<image::RgbImage> = res
        .iter()
        .map(|&r| {
            btf_image::plot::render(&fraction_plot(&outcomes, r, &sigmas, &angles, a.max_error_px))
        })
        .collect();
    let refs: Vec<&image::RgbImage> = panels.iter().collect();
    btf_image::write::write_png(
        &a.out.join("registration.png"),
        &btf_image::compose::side_by_side(&refs, 8),
    )?;

    let ok = outcomes.iter().filter(|o| o.error_px.is_some_and(|e| e <= a.max_error_px)).count();
    let wrong = outcomes.iter().filter(|o| o.error_px.is_some_and(|e| e > a.max_error_px)).count();
    let refused = outcomes.iter().filter(|o| o.refused.is_some()).count();
    if a.json {
        let cells: Vec<serde_json::Value> =
            summary(&outcomes, &res, &sigmas, &angles, a.max_error_px);
        outln!(
            "{}",
            serde_json::json!({
                "slots": outcomes.len(), "registered": ok, "wrong": wrong, "refused": refused,
                "cells": cells, "out": a.out.display().to_string(),
            })
        );
    } else {
        outln!("{table}");
        outln!(
            "{ok} of {} slots registered, {wrong} wrong, {refused} refused -> {}",
            outcomes.len(),
            a.out.display()
        );
    }
    Ok(())
}

/// Renders the registration images of every view of `spec` and registers each slot.
fn register_capture(spec: &CaptureSpec, pose_search: bool) -> Result<Vec<Outcome>> {
    let text = render::description_toml(spec)?;
    let layout = CaptureLayout::from_text(Path::new("."), "capture.toml", &text)?;
    let material = datasets::material::Material::build(&spec.material)?;
    let poses = render::true_poses(spec);
    let mut opt = ProcessOptions::default();
    opt.register.pose_search = pose_search;
    let lights = process::registration_lights(&layout, opt.registration_lights);
    let s = &spec.material.sampling;
    let (w, h) = (spec.width, spec.height);
    Ok((0..s.len())
        .map(|view| {
            let mut sum = vec![0f32; w * h];
            for &l in &lights {
                let px = render::render_image(spec, &material, &poses[view], view, l);
                // Left-aligned 12-bit DN, as `capture process` reads them.
                for (v, p) in sum.iter_mut().zip(&px) {
                    *v += (p[0] + p[1] + p[2]) as f32 / 16.0 / (3 * lights.len()) as f32;
                }
            }
            let gray = Gray { width: w, height: h, data: sum };
            let truth = {
                let p = &poses[view];
                let r = Matrix3::from_fn(|i, j| p.rotation[i][j]);
                layout.homography(view, &r, &Vector3::from(p.translation_mm))
            };
            let p = &poses[view];
            let true_pose =
                pose_size(&Matrix3::from_fn(|i, j| p.rotation[i][j]), &p.translation_mm);
            let (error_px, markers, refused, registered_pose) =
                match register::register(&layout, view, &gray, &opt.register) {
                    Ok(reg) => {
                        let m = reg.matrix();
                        let pose = layout
                            .pose_from_homography(view, &m)
                            .map(|(r, t)| pose_size(&r, &[t.x, t.y, t.z]));
                        (Some(grid_error(&m, &truth, 40.0)), reg.markers_used, None, pose)
                    }
                    Err(why) => (None, 0, Some(why), None),
                };
            Outcome {
                resolution: (w, h),
                sigma: spec.pose_noise_deg,
                seed: spec.seed,
                view,
                theta_deg: s.direction(view).theta_deg,
                error_px,
                markers,
                true_pose,
                registered_pose,
                refused,
            }
        })
        .collect())
}

/// A plate pose's distance from nominal: rotation angle (degrees) and shift length (mm).
fn pose_size(r: &Matrix3<f64>, t: &[f64; 3]) -> (f64, f64) {
    let angle = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    (angle, Vector3::from(*t).norm())
}

/// Largest image distance between `a` and `b` over a 5 × 5 grid on the square `±half` mm.
fn grid_error(a: &Matrix3<f64>, b: &Matrix3<f64>, half: f64) -> f64 {
    let apply = btf_capture::capture::homography::apply;
    let mut worst = 0.0f64;
    for i in 0..5 {
        for j in 0..5 {
            let p = [half * (i as f64 / 2.0 - 1.0), half * (j as f64 / 2.0 - 1.0)];
            let (u, v) = (apply(a, p), apply(b, p));
            let d = (u[0] - v[0]).hypot(u[1] - v[1]);
            worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
        }
    }
    worst
}

fn cell(
    o: &[Outcome],
    r: (usize, usize),
    sigma: f64,
    theta: f64,
) -> impl Iterator<Item = &Outcome> {
    o.iter().filter(move |x| x.resolution == r && x.sigma == sigma && x.theta_deg == theta)
}

fn table(
    o: &[Outcome],
    res: &[(usize, usize)],
    sigmas: &[f64],
    angles: &[f64],
    tol: f64,
) -> String {
    let mut t = String::from("| camera | σ (° / mm) |");
    for a in angles {
        let _ = write!(t, " θ_v = {a}° |");
    }
    t.push_str(" wrong | refused |\n|---|---:|");
    t.push_str(&"---:|".repeat(angles.len() + 2));
    t.push('\n');
    for &r in res {
        for &s in sigmas {
            let _ = write!(t, "| {}×{} | {s} |", r.0, r.1);
            let (mut wrong, mut refused) = (0, 0);
            for &a in angles {
                let c: Vec<&Outcome> = cell(o, r, s, a).collect();
                let ok: Vec<f64> =
                    c.iter().filter_map(|x| x.error_px).filter(|e| *e <= tol).collect();
                wrong += c.iter().filter(|x| x.error_px.is_some_and(|e| e > tol)).count();
                refused += c.iter().filter(|x| x.refused.is_some()).count();
                let worst = ok.iter().copied().fold(0.0, f64::max);
                let mark = if ok.len() == c.len() { "" } else { "**" };
                let _ = write!(t, " {mark}{}/{}{mark} ({worst:.2}) |", ok.len(), c.len());
            }
            let _ = writeln!(t, " {wrong} | {refused} |");
        }
    }
    t
}

fn summary(
    o: &[Outcome],
    res: &[(usize, usize)],
    sigmas: &[f64],
    angles: &[f64],
    tol: f64,
) -> Vec<serde_json::Value> {
    let mut v = Vec::new();
    for &r in res {
        for &s in sigmas {
            for &a in angles {
                let c: Vec<&Outcome> = cell(o, r, s, a).collect();
                let ok: Vec<f64> =
                    c.iter().filter_map(|x| x.error_px).filter(|e| *e <= tol).collect();
                v.push(serde_json::json!({
                    "width": r.0, "height": r.1, "sigma": s, "theta_deg": a,
                    "slots": c.len(), "registered": ok.len(),
                    "wrong": c.iter().filter(|x| x.error_px.is_some_and(|e| e > tol)).count(),
                    "refused": c.iter().filter(|x| x.refused.is_some()).count(),
                    "max_error_px": ok.iter().copied().fold(0.0, f64::max),
                }));
            }
        }
    }
    v
}

fn csv(o: &[Outcome]) -> String {
    let mut t = String::from(
        "width,height,sigma,seed,view,theta_deg,error_px,markers,true_rotation_deg,\
         true_shift_mm,registered_rotation_deg,registered_shift_mm,refused\n",
    );
    for x in o {
        let (rr, rs) = match x.registered_pose {
            Some((r, s)) => (format!("{r:.3}"), format!("{s:.3}")),
            None => (String::new(), String::new()),
        };
        let _ = writeln!(
            t,
            "{},{},{},{},{},{},{},{},{:.3},{:.3},{},{},\"{}\"",
            x.resolution.0,
            x.resolution.1,
            x.sigma,
            x.seed,
            x.view,
            x.theta_deg,
            x.error_px.map(|e| format!("{e:.4}")).unwrap_or_default(),
            x.markers,
            x.true_pose.0,
            x.true_pose.1,
            rr,
            rs,
            x.refused.as_deref().unwrap_or("").replace('"', "'")
        );
    }
    t
}

fn fraction_plot(
    o: &[Outcome],
    r: (usize, usize),
    sigmas: &[f64],
    angles: &[f64],
    tol: f64,
) -> btf_image::plot::Plot {
    btf_image::plot::Plot {
        title: format!("registered fraction, {}x{}", r.0, r.1),
        x_label: "pose error sigma (deg and mm)".into(),
        y_label: "fraction registered".into(),
        log_y: false,
        log_x: false,
        series: angles
            .iter()
            .map(|&a| btf_image::plot::Series {
                name: format!("view {a} deg"),
                points: sigmas
                    .iter()
                    .map(|&s| {
                        let c: Vec<&Outcome> = cell(o, r, s, a).collect();
                        let ok = c.iter().filter(|x| x.error_px.is_some_and(|e| e <= tol)).count();
                        (s, ok as f64 / c.len().max(1) as f64)
                    })
                    .collect(),
            })
            .collect(),
    }
}
