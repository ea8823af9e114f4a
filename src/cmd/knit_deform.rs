//! `btf knit deform -o DIR`: knot-based yarn deformation ([H25 §3, §5.2],
//! [`yarn::knit::knot`]) of a flat periodic patch under the analytic test maps of DESIGN
//! §3.6 — stretch along the wales (`+y`, the loops' height), along the courses (`+x`) and
//! shear `[[1, γ], [0, 1]]` — each scored against the converged reference (block
//! Gauss–Seidel on the same energy) and against naive interpolation of the rest CPs.
//!
//! Per case: the energy of [H25 eq. 3] before and after the iterations and at the
//! reference; the RMS and maximum distance of the knot CPs from the reference / r for
//! naive interpolation, interpolated knots and knots + Gauss–Newton ([H25 Fig. 9]); the
//! RMS length strain; the minimum clearance between different yarns / 2r (DESIGN §3.3
//! item 9: the model has no contact) for naive, solved and reference yarns; the solve time
//! (median of `--repeat`, all faces in parallel) and how often the step guard fired.
//! Writes `deform.csv`, `report.md`, `clearance.png` and `deviation.png` (plots against
//! the strain), `yarns.png` (the centre lines seen from above: reference, solved, naive)
//! and per case the solved and reference yarns as BCC in `yarns/`. With `--contact` each
//! reference is also relaxed with the yarn–yarn contact penalty of DESIGN §3.3 item 1
//! ([`yarn::knit::knot::relax`]): the contact reference's clearance and the solve's
//! deviation from it over every CP (the geometry the model's missing contact costs).
//! With `--relaxed-rest` the chart's template is relaxed with that penalty once (on a flat
//! periodic patch) and carried on top of every solve as the rest detail
//! ([`yarn::knit::knot::detail`], DESIGN §3.3 item 1): the solve + detail's clearance, its
//! cost per frame and, with `--contact`, its deviation from the contact reference;
//! `yarns/CASE-detail.bcc`.

use super::knit::{chart_inputs_of, load_chart, load_yarn};
use crate::guard::{self, outln};
use anyhow::{Result, bail};
use btf_image::plot::{Plot, Series};
use btf_image::write::{write_png, write_text};
use clap::Args;
use image::RgbImage;
use std::path::PathBuf;
use std::time::Instant;
use yarn::knit::knot::{ContactParams, KnotFrame, RestDetail, min_clearance};
use yarn::knit::{KnotModel, KnotParams, SkeletonParams, StitchMesh};

/// `btf knit deform`.
#[derive(Args)]
pub struct DeformArgs {
    /// Built-in chart name or chart file (cables are refused).
    #[arg(long, default_value = "rib1x1")]
    pub chart: String,
    /// Yarn preset name or yarn TOML file (its radius sets r).
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Stitches W,C of the periodic patch (multiples of the chart's size).
    #[arg(long, default_value = "8,8")]
    pub stitches: String,
    /// Stretch along the wales (loop height, +y), as engineering strains (negative:
    /// compression).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0.1,0.2,0.3,0.5"
    )]
    pub stretch: Vec<f64>,
    /// Stretch along the courses (+x), as engineering strains (negative: compression).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, default_value = "-0.1,0.1,0.3")]
    pub stretch_course: Vec<f64>,
    /// Engineering shear γ of `[[1, γ], [0, 1]]`.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.2,0.3")]
    pub shear: Vec<f64>,
    /// Gauss–Newton iterations per frame.
    #[arg(long, default_value_t = 3)]
    pub iterations: usize,
    /// Weight of the relative length residuals.
    #[arg(long, default_value_t = 1e2)]
    pub w_length: f64,
    /// Knot spacing blend β (1 uniform, 0 rest spacing).
    #[arg(long, default_value_t = 1.0)]
    pub beta: f64,
    /// Catmull–Rom samples per CP segment in the written yarns.
    #[arg(long, default_value_t = 4)]
    pub upsample: usize,
    /// Timed solves per case (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// Gauss–Seidel sweeps allowed for the converged reference.
    #[arg(long, default_value_t = 500)]
    pub max_sweeps: usize,
    /// Also relax every case's converged reference with the yarn–yarn contact penalty
    /// (`yarn::knit::knot::relax`, DESIGN §3.3 item 1): the contact reference's clearance
    /// and the knot solve's deviation from it (slow: seconds to minutes per case).
    #[arg(long)]
    pub contact: bool,
    /// Carry the contact-relaxed template on top of every solve (the rest detail of
    /// `yarn::knit::knot::detail`, DESIGN §3.3 item 1): relaxed once on a flat periodic
    /// patch of the chart, reported beside the plain solve.
    #[arg(long)]
    pub relaxed_rest: bool,
    /// Levenberg–Marquardt steps allowed for the contact relaxation (`--contact`).
    #[arg(long, default_value_t = 250)]
    pub contact_iterations: usize,
    /// Drive the yarns by the drape simulation instead (a cloth falling over a sphere,
    /// `datasets`' drape): this many frames after the flat start, written as
    /// `drape/frame-K.bcc` with a per-frame table (0: the analytic maps).
    #[arg(long, default_value_t = 0)]
    pub drape: usize,
    /// Wales across the draped cloth (`--drape`; the 1 m cloth of the simulation is
    /// scaled to them, so few wales make its folds sharper than a stitch).
    #[arg(long, default_value_t = 64)]
    pub wales: usize,
    /// Cloth vertices per side of the drape simulation (`--drape`).
    #[arg(long, default_value_t = 40)]
    pub cloth_res: usize,
    /// Render every drape frame with the GPU fibers at W,H (`--drape`; `drape.png`).
    #[arg(long)]
    pub render: Option<String>,
    /// Output folder.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Remove this command's earlier outputs from the folder first.
    #[arg(long)]
    pub fresh: bool,
}

/// One measured case.
struct Row {
    name: String,
    kind: &'static str,
    strain: f64,
    e_init: f64,
    e_solved: f64,
    e_ref: f64,
    rms: [f64; 3],
    max: [f64; 3],
    length_strain: f64,
    clearance: [f64; 3],
    solve_ms: f64,
    guard: usize,
    sweeps: usize,
    frames: [KnotFrame; 3],
    /// With `--contact`: the contact reference's clearance, the GN solve's RMS and maximum
    /// deviation from it over every CP (r), LM steps and seconds.
    contact: Option<ContactRow>,
    /// With `--relaxed-rest`: the solve + rest detail.
    detail: Option<DetailRow>,
}

/// The solve with the rest detail of one case.
struct DetailRow {
    clearance: f64,
    /// Median milliseconds to add the detail to a solved frame.
    apply_ms: f64,
    /// With `--contact`: RMS and maximum deviation from the contact reference over every
    /// CP (r).
    contact_dev: Option<(f64, f64)>,
}

/// The contact reference of one case.
struct ContactRow {
    clearance: f64,
    rms_gn: f64,
    max_gn: f64,
    steps: usize,
    seconds: f64,
}

fn deviations(a: &KnotFrame, b: &KnotFrame, idx: &[usize], r: f64) -> (f64, f64) {
    let d: Vec<f64> = idx
        .iter()
        .map(|&i| {
            let (p, q) = (a.points[i], b.points[i]);
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .collect();
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
    (rms / r, d.iter().copied().fold(0.0, f64::max) / r)
}

pub fn run(a: DeformArgs) -> Result<()> {
    guard::refuse_overlap(&[("-o", &a.output)], &chart_inputs_of(&a.chart, &a.yarn))?;
    let [w, c] = crate::args::numbers::<usize, 2>(&a.stitches, "--stitches")?;
    if w * c > 1 << 16 {
        bail!("--stitches {w},{c}: at most 65 536 faces here (the reference is serial)");
    }
    let bad =
        |v: &[f64], lo: f64, hi: f64| v.iter().any(|x| !(x.is_finite() && *x >= lo && *x <= hi));
    if bad(&a.stretch, -0.5, 2.0) || bad(&a.stretch_course, -0.5, 2.0) {
        bail!("--stretch / --stretch-course: strains in [-0.5, 2]");
    }
    if bad(&a.shear, -1.0, 1.0) {
        bail!("--shear {:?}: γ in [-1, 1]", a.shear);
    }
    if a.repeat == 0 || a.repeat > 1000 || a.upsample == 0 || a.upsample > 16 {
        bail!("--repeat 1..=1000 and --upsample 1..=16");
    }
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let r = params.yarn_radius();
    let sk = SkeletonParams::new(r);
    let spacing = sk.default_spacing();
    let rest = StitchMesh::flat(&chart, w, c, spacing.0, spacing.1)?;
    let model = KnotModel::new(&rest, &sk, spacing)?;
    let p = KnotParams {
        iterations: a.iterations,
        w_length: a.w_length,
        beta: a.beta,
        ..KnotParams::default()
    };
    guard::output_folder(&a.output, "knit deform", a.fresh, &|n| {
        guard::report_output(n) || n == "yarns" || n == "drape"
    })?;
    if a.drape > 0 {
        return super::knit_deform_drape::run(&a, &chart, &params, &p);
    }
    let yarn_dir = a.output.join("yarns");
    std::fs::create_dir_all(&yarn_dir)?;
    outln!(
        "knit deform: {} {w} × {c} stitches, {} knot faces, {} CPs, r = {:.3} mm",
        chart.name,
        model.knot_faces(),
        model.cp_count(),
        r * 1e3
    );
    let mut cases: Vec<(String, &'static str, f64, [[f64; 2]; 2])> = Vec::new();
    for &s in &a.stretch {
        let name = if s == 0.0 { "rest".to_string() } else { format!("stretch-wale-{s}") };
        cases.push((name, "stretch along the wales", s, [[1.0, 0.0], [0.0, 1.0 + s]]));
    }
    for &s in &a.stretch_course {
        cases.push((
            format!("stretch-course-{s}"),
            "stretch along the courses",
            s,
            [[1.0 + s, 0.0], [0.0, 1.0]],
        ));
    }
    for &g in &a.shear {
        cases.push((format!("shear-{g}"), "shear", g, [[1.0, g], [0.0, 1.0]]));
    }
    let detail = if a.relaxed_rest {
        let c = ContactParams::default();
        let d = RestDetail::relax(&model, &rest, &p, &c)?;
        outln!(
            "  rest detail: {} × {} patch relaxed in {} LM steps ({:.1} s), clearance {:.3} → \
             {:.3} × 2r, largest offset {:.3} r",
            d.patch.0,
            d.patch.1,
            d.stats.iterations,
            d.stats.seconds,
            d.stats.clearance_before,
            d.stats.clearance_after,
            d.max_offset_over_r()
        );
        Some(d)
    } else {
        None
    };
    let knots = model.knot_cps();
    let bar = crate::progress::bar(cases.len() as u64, "cases");
    let mut rows = Vec::new();
    for (name, kind, strain, map) in cases {
        bar.set_message(name.clone());
        let mesh = rest.map_affine(map)?;
        let naive = model.naive(&mesh)?;
        let init = model.initial(&mesh, p.beta)?;
        let mut times = Vec::with_capacity(a.repeat);
        let mut solved = model.solve(&mesh, &p)?;
        for _ in 0..a.repeat {
            let t = Instant::now();
            solved = model.solve(&mesh, &p)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        let (reference, sweeps) = model.reference(&mesh, &p, a.max_sweeps)?;
        let dev = |f: &KnotFrame| deviations(f, &reference, &knots, r);
        let (dn, di, ds) = (dev(&naive), dev(&init), dev(&solved));
        let clear = |f: &KnotFrame| -> Result<f64> {
            Ok(min_clearance(&model.yarn_set(f, 1)?, mesh.lattice, r, 12).ratio)
        };
        let clearance = [clear(&naive)?, clear(&solved)?, clear(&reference)?];
        let detailed = match &detail {
            Some(d) => {
                let mut times = Vec::with_capacity(a.repeat);
                let mut f = d.apply(&model, &mesh, &solved)?;
                for _ in 0..a.repeat {
                    let t = Instant::now();
                    f = d.apply(&model, &mesh, &solved)?;
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                }
                times.sort_by(f64::total_cmp);
                yarn::io::bcc::write_bcc(
                    &yarn_dir.join(format!("{name}-detail.bcc")),
                    &model.yarn_set(&f, a.upsample)?,
                    &format!("btf knit deform {name}, chart {}, solve + rest detail", chart.name),
                )?;
                Some((f, times[times.len() / 2]))
            }
            None => None,
        };
        let mut detail_contact = None;
        let contact = if a.contact {
            let c = ContactParams { max_iterations: a.contact_iterations, ..Default::default() };
            let (relaxed, st) = model.relax_contact(&reference, &p, &c)?;
            if let Some((f, _)) = &detailed {
                let all: Vec<usize> = (0..model.cp_count()).collect();
                detail_contact = Some(deviations(f, &relaxed, &all, r));
            }
            let all: Vec<usize> = (0..model.cp_count()).collect();
            let (rms_gn, max_gn) = deviations(&solved, &relaxed, &all, r);
            yarn::io::bcc::write_bcc(
                &yarn_dir.join(format!("{name}-contact.bcc")),
                &model.yarn_set(&relaxed, a.upsample)?,
                &format!("btf knit deform {name}, chart {}, contact reference", chart.name),
            )?;
            Some(ContactRow {
                clearance: clear(&relaxed)?,
                rms_gn,
                max_gn,
                steps: st.iterations,
                seconds: st.seconds,
            })
        } else {
            None
        };
        let info = format!("btf knit deform {name}, chart {}, {w} x {c}", chart.name);
        yarn::io::bcc::write_bcc(
            &yarn_dir.join(format!("{name}.bcc")),
            &model.yarn_set(&solved, a.upsample)?,
            &info,
        )?;
        yarn::io::bcc::write_bcc(
            &yarn_dir.join(format!("{name}-reference.bcc")),
            &model.yarn_set(&reference, a.upsample)?,
            &format!("{info}, converged reference"),
        )?;
        let detail = match &detailed {
            Some((f, ms)) => {
                Some(DetailRow { clearance: clear(f)?, apply_ms: *ms, contact_dev: detail_contact })
            }
            None => None,
        };
        rows.push(Row {
            name,
            kind,
            strain,
            e_init: model.energy(&init, &p),
            e_solved: model.energy(&solved, &p),
            e_ref: model.energy(&reference, &p),
            rms: [dn.0, di.0, ds.0],
            max: [dn.1, di.1, ds.1],
            length_strain: model.length_strain(&solved),
            clearance,
            solve_ms: times[times.len() / 2],
            guard: solved.stats.guard_triggers,
            sweeps,
            frames: [naive, solved, reference],
            contact,
            detail,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    write_outputs(&a, &model, &rows, w, c, &chart.name, r)?;
    Ok(())
}

fn write_outputs(
    a: &DeformArgs,
    model: &KnotModel,
    rows: &[Row],
    w: usize,
    c: usize,
    chart: &str,
    r: f64,
) -> Result<()> {
    let mut csv = String::from(
        "case,kind,strain,energy_initial,energy_solved,energy_reference,rms_naive_r,rms_knots_r,\
         rms_gn_r,max_naive_r,max_knots_r,max_gn_r,rms_length_strain,clearance_naive,\
         clearance_gn,clearance_reference,solve_ms,guard_triggers,reference_sweeps,\
         clearance_contact,rms_gn_contact_r,max_gn_contact_r,contact_steps,contact_s,\
         clearance_gn_detail,detail_ms,rms_gn_detail_contact_r,max_gn_detail_contact_r\n",
    );
    for x in rows {
        csv.push_str(&format!(
            "{},{},{},{:.6e},{:.6e},{:.6e},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.4},{:.4},{:.4},{:.4},{},{}\n",
            x.name,
            x.kind,
            x.strain,
            x.e_init,
            x.e_solved,
            x.e_ref,
            x.rms[0],
            x.rms[1],
            x.rms[2],
            x.max[0],
            x.max[1],
            x.max[2],
            x.length_strain,
            x.clearance[0],
            x.clearance[1],
            x.clearance[2],
            x.solve_ms,
            x.guard,
            x.sweeps
        ));
        // The contact columns: empty without --contact (no NaN is written).
        let contact = x.contact.as_ref().map_or(",,,,".to_string(), |k| {
            format!(
                "{:.4},{:.5},{:.5},{},{:.2}",
                k.clearance, k.rms_gn, k.max_gn, k.steps, k.seconds
            )
        });
        csv.insert_str(csv.len() - 1, &format!(",{contact}"));
        // The rest-detail columns: empty without --relaxed-rest (and the deviation without
        // --contact).
        let detail = x.detail.as_ref().map_or(",,,".to_string(), |d| {
            let dev = d.contact_dev.map_or(",".to_string(), |(a, b)| format!("{a:.5},{b:.5}"));
            format!("{:.4},{:.4},{dev}", d.clearance, d.apply_ms)
        });
        csv.insert_str(csv.len() - 1, &format!(",{detail}"));
    }
    write_text(&a.output.join("deform.csv"), &csv)?;
    let mut md = format!(
        "# Knot-based deformation: {chart}, {w} × {c} stitches\n\n\
         {} knot faces, {} CPs, r = {:.3} mm; {} Gauss–Newton iterations, w_length = {}, β = {}; \
         solve time = median of {} (all faces, rayon).\n\n\
         Deviations are of the knot CPs from the converged reference, in yarn radii; clearance is \
         the minimum centre-line distance between different courses / 2r (below 1: the yarns \
         interpenetrate; the model has no contact term).\n\n\
         | case | E₀ | E₃ | E_∞ | E₃/E_∞ | RMS dev. naive / knots / GN (r) | max dev. GN (r) | RMS length strain | clearance naive / GN / ref. | solve ms | guard |\n\
         |---|---:|---:|---:|---:|---|---:|---:|---|---:|---:|\n",
        model.knot_faces(),
        model.cp_count(),
        r * 1e3,
        a.iterations,
        a.w_length,
        a.beta,
        a.repeat
    );
    for x in rows {
        let ratio =
            if x.e_ref > 0.0 { format!("{:.3}", x.e_solved / x.e_ref) } else { "—".into() };
        md.push_str(&format!(
            "| {} | {:.3e} | {:.3e} | {:.3e} | {ratio} | {:.3} / {:.3} / {:.3} | {:.3} | {:.4} | {:.3} / {:.3} / {:.3} | {:.3} | {} |\n",
            x.name,
            x.e_init,
            x.e_solved,
            x.e_ref,
            x.rms[0],
            x.rms[1],
            x.rms[2],
            x.max[2],
            x.length_strain,
            x.clearance[0],
            x.clearance[1],
            x.clearance[2],
            x.solve_ms,
            x.guard
        ));
    }
    if rows.iter().any(|x| x.contact.is_some()) {
        md.push_str(
            "\n**The contact reference** (DESIGN §3.3 item 1): each converged reference relaxed \
             with the yarn–yarn contact penalty (`yarn::knit::knot::relax`, Levenberg–Marquardt, \
             every CP free): its clearance, and how far the Gauss–Newton knot solve is from it \
             over every CP — what the model's missing contact costs in geometry.\n\n\
             | case | clearance ref. → contact ref. | RMS / max dev. GN from contact ref. (r) | LM steps | s |\n\
             |---|---|---|---:|---:|\n",
        );
        for x in rows {
            if let Some(k) = &x.contact {
                md.push_str(&format!(
                    "| {} | {:.3} → {:.3} | {:.3} / {:.3} | {} | {:.1} |\n",
                    x.name, x.clearance[2], k.clearance, k.rms_gn, k.max_gn, k.steps, k.seconds
                ));
            }
        }
    }
    if rows.iter().any(|x| x.detail.is_some()) {
        md.push_str(
            "\n**The relaxed rest** (DESIGN §3.3 item 1, `yarn::knit::knot::detail`): the \
             chart's template relaxed once with the contact penalty on a flat periodic patch and \
             carried on top of every solve in each CP's frame — its clearance against the plain \
             solve's, what adding it costs per frame and, with `--contact`, how far the solve + \
             detail is from the contact reference.\n\n\
             | case | clearance GN → GN + detail | detail ms | RMS / max dev. GN + detail from contact ref. (r) |\n\
             |---|---|---:|---|\n",
        );
        for x in rows {
            if let Some(d) = &x.detail {
                let dev =
                    d.contact_dev.map_or("—".to_string(), |(a, b)| format!("{a:.3} / {b:.3}"));
                md.push_str(&format!(
                    "| {} | {:.3} → {:.3} | {:.3} | {dev} |\n",
                    x.name, x.clearance[1], d.clearance, d.apply_ms
                ));
            }
        }
    }
    md.push_str(
        "\n![clearance against strain](clearance.png)\n\n![deviation against strain](deviation.png)\n\n\
         ![centre lines from above: reference (orange), solved (blue), naive (grey)](yarns.png)\n",
    );
    write_text(&a.output.join("report.md"), &md)?;
    // Plots against the strain, one series per kind of map and method.
    let kinds = ["stretch along the wales", "stretch along the courses", "shear"];
    // (The rest case joins every series at strain 0.)
    let series = |f: &dyn Fn(&Row) -> f64, label: &str| -> Vec<Series> {
        kinds
            .iter()
            .map(|k| {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|x| x.kind == *k || (x.strain == 0.0 && x.kind == kinds[0]))
                    .map(|x| (x.strain, f(x)))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series::new(format!("{label}, {k}"), pts)
            })
            .filter(|s| s.points.len() > 1)
            .collect()
    };
    let mut clear = series(&|x| x.clearance[1], "solved");
    clear.extend(series(&|x| x.clearance[2], "reference"));
    clear.extend(series(&|x| x.clearance[0], "naive"));
    if rows.iter().all(|x| x.detail.is_some()) {
        clear.extend(series(
            &|x| x.detail.as_ref().map_or(f64::NAN, |d| d.clearance),
            "solved + rest detail",
        ));
    }
    if rows.iter().all(|x| x.contact.is_some()) {
        clear.extend(series(
            &|x| x.contact.as_ref().map_or(f64::NAN, |k| k.clearance),
            "contact reference",
        ));
    }
    let plot = Plot {
        title: format!("{chart}: minimum clearance between yarns"),
        x_label: "strain (engineering)".into(),
        y_label: "clearance / 2r".into(),
        series: clear,
        ..Plot::default()
    };
    write_png(&a.output.join("clearance.png"), &btf_image::plot::render(&plot))?;
    let mut dev = series(&|x| x.rms[0], "naive");
    dev.extend(series(&|x| x.rms[1], "knots"));
    dev.extend(series(&|x| x.rms[2], "knots + GN"));
    let plot = Plot {
        title: format!("{chart}: knot CPs against the converged reference"),
        x_label: "strain (engineering)".into(),
        y_label: "RMS deviation / r".into(),
        series: dev,
        ..Plot::default()
    };
    write_png(&a.output.join("deviation.png"), &btf_image::plot::render(&plot))?;
    // Centre lines from above.
    // Three rest stitches wide, at one scale for all panels.
    let window = 3.0 * SkeletonParams::new(r).default_spacing().0;
    let panels: Vec<RgbImage> =
        rows.iter().map(|x| top_view(model, &x.frames, window, 240)).collect();
    let captioned: Vec<(&RgbImage, &str)> =
        panels.iter().zip(rows).map(|(p, x)| (p, x.name.as_str())).collect();
    let sheet = btf_image::compose::captioned_strip(&captioned, 6);
    write_png(&a.output.join("yarns.png"), &sheet)?;
    outln!("knit deform: {} cases -> {}", rows.len(), a.output.display());
    for x in rows {
        outln!(
            "  {:<22} E₃/E_∞ {:>6.3}  RMS dev naive/knots/GN {:.3}/{:.3}/{:.3} r  clearance naive/GN/ref {:.3}/{:.3}/{:.3}  {:.2} ms",
            x.name,
            if x.e_ref > 0.0 { x.e_solved / x.e_ref } else { 1.0 },
            x.rms[0],
            x.rms[1],
            x.rms[2],
            x.clearance[0],
            x.clearance[1],
            x.clearance[2],
            x.solve_ms
        );
    }
    Ok(())
}

/// The CPs' Catmull–Rom centre lines of the three frames drawn from above (`xy`), a
/// square window of side `window` metres around the patch centre at `size` pixels (the
/// same scale in every panel, so stretch shows): naive grey, reference orange, solved blue.
fn top_view(model: &KnotModel, frames: &[KnotFrame; 3], window: f64, size: u32) -> RgbImage {
    let mut img = RgbImage::from_pixel(size, size, image::Rgb([255, 255, 255]));
    let n = frames[2].points.len().max(1) as f64;
    let centre = [0, 1].map(|k| frames[2].points.iter().map(|p| p[k]).sum::<f64>() / n);
    let scale = size as f64 / window;
    let colours = [[170, 170, 170], [0, 114, 178], [213, 94, 0]];
    for k in [0usize, 2, 1] {
        let Ok(set) = model.yarn_set(&frames[k], 1) else { continue };
        for curve in &set.curves {
            let line = curve.sample_polyline(8);
            for s in line.windows(2) {
                let px = |p: [f64; 3]| {
                    (
                        0.5 * size as f64 + (p[0] - centre[0]) * scale,
                        0.5 * size as f64 - (p[1] - centre[1]) * scale,
                    )
                };
                let (a, b) = (px(s[0]), px(s[1]));
                let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
                for i in 0..=steps {
                    let t = i as f64 / steps as f64;
                    let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        btf_image::text::put(
                            &mut img,
                            x.round() as i64 + dx,
                            y.round() as i64 + dy,
                            colours[k],
                        );
                    }
                }
            }
        }
    }
    img
}
