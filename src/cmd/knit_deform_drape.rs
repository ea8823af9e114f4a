//! `btf knit deform --drape N`: the knot solver ([H25 §5.2], [`yarn::knit::knot`]) driven by
//! an animated stitch mesh — `datasets`' drape simulation (a square cloth falling over a
//! sphere, [C03 §4]) recorded at `N + 1` evenly spaced times from the flat start. The chart
//! is laid on the cloth through its UVs (`--wales` across, whole courses at the yarn's
//! natural gauge, the cloth scaled so that the flat start is the rest state), every frame's
//! stitch mesh is found by inverse UV lookup on that frame, and the yarns follow by three
//! Gauss–Newton iterations per face.
//!
//! Per frame: the solve time, the energy before and after, the guard count, the RMS length
//! strain of the yarn and of the cloth's stitch faces (how far the drape stretches the
//! knit), the clearance between yarns / 2r, and the deviation from the converged reference
//! (block Gauss–Seidel). Writes `drape/frame-K.bcc`, `drape.csv`, `drape.md`,
//! `drape-strain.png` and with `--render W,H` the GPU fibers of every frame
//! (`drape/frame-K.png`) and a contact sheet `drape.png`. With `--relaxed-rest` the
//! solved and the converged frames carry the contact-relaxed template
//! ([`yarn::knit::knot::detail`]) and the solve time includes adding it.

use super::knit_deform::DeformArgs;
use crate::guard::outln;
use anyhow::{Context, Result, bail};
use btf_image::plot::{Plot, Series};
use btf_image::write::{write_png, write_text};
use datasets::mesh::cloth::{DrapeParams, drape_frames};
use std::time::Instant;
use yarn::knit::knot::{KnotFrame, min_clearance};
use yarn::knit::{Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh, UvLayout};
use yarn::params::YarnParams;

struct FrameRow {
    t: f64,
    solve_ms: f64,
    e_init: f64,
    e_solved: f64,
    guard: usize,
    yarn_strain: f64,
    face_strain: f64,
    clearance: f64,
    clearance_naive: f64,
    rms_vs_ref: f64,
}

/// RMS relative change of the stitch faces' edge lengths against the rest mesh.
fn face_strain(rest: &StitchMesh, m: &StitchMesh) -> f64 {
    let (w1, mut sum, mut n) = (m.wales + 1, 0.0, 0usize);
    let d = |p: [f64; 3], q: [f64; 3]| {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    for c in 0..=m.courses {
        for w in 0..=m.wales {
            let i = c * w1 + w;
            for j in [(w < m.wales).then_some(i + 1), (c < m.courses).then_some(i + w1)]
                .into_iter()
                .flatten()
            {
                let l0 = d(rest.corners[i], rest.corners[j]);
                let e = d(m.corners[i], m.corners[j]) / l0 - 1.0;
                sum += e * e;
                n += 1;
            }
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

pub fn run(a: &DeformArgs, chart: &Chart, params: &YarnParams, p: &KnotParams) -> Result<()> {
    if !(4..=200).contains(&a.cloth_res) || a.drape > 500 {
        bail!("--cloth-res {} in 4..=200 and --drape {} ≤ 500", a.cloth_res, a.drape);
    }
    if a.wales == 0 || !a.wales.is_multiple_of(chart.width) || a.wales > 1024 {
        bail!("--wales {}: a multiple of the chart's width {} up to 1024", a.wales, chart.width);
    }
    let r = params.yarn_radius();
    let sk = SkeletonParams::new(r);
    let (ws, cs) = sk.default_spacing();
    let dp = DrapeParams::new(a.cloth_res);
    let t0 = Instant::now();
    let (_, mut frames) = drape_frames(&dp, a.drape).context("the drape simulation")?;
    let sim_s = t0.elapsed().as_secs_f64();
    // Scale the cloth so that `wales` stitches span it at the yarn's gauge.
    let s = a.wales as f64 * ws / dp.size_m;
    for f in &mut frames {
        for q in &mut f.positions {
            *q = q.map(|x| x * s);
        }
    }
    let courses =
        (((dp.size_m * s / cs) / chart.height as f64).floor() as usize).max(1) * chart.height;
    let layout = UvLayout {
        origin: [0.0, 0.0],
        wale_du: dp.size_m / a.wales as f64,
        course_dv: dp.size_m / courses as f64,
        wales: a.wales,
        courses,
    };
    let meshes: Vec<StitchMesh> = frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            StitchMesh::on_surface(&super::knit_compare::surface_of(f), chart, &layout)
                .with_context(|| format!("drape frame {k}: laying the chart through the UVs"))
        })
        .collect::<Result<_>>()?;
    // The flat start is the rest: its gauge (whole courses over the cloth change the course
    // spacing by less than chart.height / courses) is the templates'.
    let model = KnotModel::new(&meshes[0], &sk, (ws, layout.course_dv * s))?;
    // With --relaxed-rest the solved and the converged frames both carry the rest detail.
    let detail = if a.relaxed_rest {
        Some(yarn::knit::knot::RestDetail::relax(
            &model,
            &meshes[0],
            p,
            &yarn::knit::knot::ContactParams::default(),
        )?)
    } else {
        None
    };
    let with_detail = |mesh: &StitchMesh, f: KnotFrame| -> Result<KnotFrame> {
        Ok(match &detail {
            Some(d) => d.apply(&model, mesh, &f)?,
            None => f,
        })
    };
    let dir = a.output.join("drape");
    std::fs::create_dir_all(&dir)?;
    outln!(
        "knit deform --drape: {} {} × {courses} stitches on a {:.3} m cloth, {} knot faces, {} \
         frames ({:.1} s of simulation)",
        chart.name,
        a.wales,
        dp.size_m * s,
        model.knot_faces(),
        frames.len(),
        sim_s
    );
    let render =
        a.render.as_deref().map(|v| crate::args::numbers::<u32, 2>(v, "--render")).transpose()?;
    if let Some([w, h]) = render
        && (w == 0 || h == 0 || w > 2048 || h > 2048)
    {
        bail!("--render {w},{h}: each side 1..=2048");
    }
    let gpu = match render {
        Some(_) => Some(btf_render::Gpu::new().context("creating a headless GPU device")?),
        None => None,
    };
    let bar = crate::progress::bar(frames.len() as u64, "drape frames");
    let mut rows = Vec::new();
    let mut shots = Vec::new();
    let dt = dp.duration_s / a.drape as f64;
    for (k, mesh) in meshes.iter().enumerate() {
        let t = Instant::now();
        let frame = with_detail(mesh, model.solve(mesh, p)?)?;
        let solve_ms = t.elapsed().as_secs_f64() * 1e3;
        let set = model.yarn_set(&frame, a.upsample)?;
        yarn::io::bcc::write_bcc(
            &dir.join(format!("frame-{k:03}.bcc")),
            &set,
            &format!("btf knit deform --drape, frame {k}"),
        )?;
        let reference = with_detail(mesh, model.reference(mesh, p, a.max_sweeps)?.0)?;
        let knots = model.knot_cps();
        let rms_vs_ref = (knots
            .iter()
            .map(|&i| {
                let (x, y) = (frame.points[i], reference.points[i]);
                (0..3).map(|j| (x[j] - y[j]).powi(2)).sum::<f64>()
            })
            .sum::<f64>()
            / knots.len().max(1) as f64)
            .sqrt()
            / r;
        rows.push(FrameRow {
            t: k as f64 * dt,
            solve_ms,
            e_init: model.energy(&model.initial(mesh, p.beta)?, p),
            e_solved: model.energy(&frame, p),
            guard: frame.stats.guard_triggers,
            yarn_strain: model.length_strain(&frame),
            face_strain: face_strain(&meshes[0], mesh),
            clearance: min_clearance(&model.yarn_set(&frame, 1)?, None, r, 8).ratio,
            clearance_naive: min_clearance(&model.yarn_set(&model.naive(mesh)?, 1)?, None, r, 8)
                .ratio,
            rms_vs_ref,
        });
        if let (Some(gpu), Some([w, h])) = (&gpu, render) {
            let img = render_frame(gpu, &set, params, &frames[0], (w, h))?;
            write_png(&dir.join(format!("frame-{k:03}.png")), &img)?;
            shots.push(img);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut csv = String::from(
        "frame,time_s,solve_ms,energy_initial,energy_solved,guard_triggers,rms_yarn_length_strain,\
         rms_face_strain,clearance,clearance_naive,rms_vs_reference_r\n",
    );
    let mut md = format!(
        "# Knot-based deformation driven by the drape: {}, {} × {courses} stitches\n\n\
         {} knot faces; solve = 3 Gauss–Newton iterations, all faces in parallel.\n\n\
         | frame | t (s) | solve ms | E₀ | E₃ | guard | RMS yarn strain | RMS face strain | clearance / 2r (naive) | RMS dev. from converged (r) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        chart.name,
        a.wales,
        model.knot_faces()
    );
    for (k, x) in rows.iter().enumerate() {
        csv.push_str(&format!(
            "{k},{:.4},{:.4},{:.6e},{:.6e},{},{:.5},{:.5},{:.4},{:.4},{:.5}\n",
            x.t,
            x.solve_ms,
            x.e_init,
            x.e_solved,
            x.guard,
            x.yarn_strain,
            x.face_strain,
            x.clearance,
            x.clearance_naive,
            x.rms_vs_ref
        ));
        md.push_str(&format!(
            "| {k} | {:.2} | {:.2} | {:.3e} | {:.3e} | {} | {:.4} | {:.4} | {:.3} ({:.3}) | {:.3} |\n",
            x.t,
            x.solve_ms,
            x.e_init,
            x.e_solved,
            x.guard,
            x.yarn_strain,
            x.face_strain,
            x.clearance,
            x.clearance_naive,
            x.rms_vs_ref
        ));
    }
    md.push_str("\n![strain and clearance over the drape](drape-strain.png)\n");
    if !shots.is_empty() {
        md.push_str("\n![the GPU fibers of every frame](drape.png)\n");
    }
    write_text(&a.output.join("drape.csv"), &csv)?;
    write_text(&a.output.join("drape.md"), &md)?;
    let series = |name: &str, f: &dyn Fn(&FrameRow) -> f64| {
        Series::new(name, rows.iter().map(|x| (x.t, f(x))).collect())
    };
    let plot = Plot {
        title: format!("{}: the knit over the drape", chart.name),
        x_label: "time (s)".into(),
        y_label: "strain (RMS) / clearance over 2r".into(),
        series: vec![
            series("face strain", &|x| x.face_strain),
            series("yarn length strain", &|x| x.yarn_strain),
            series("clearance / 2r", &|x| x.clearance),
            series("dev. from converged / r", &|x| x.rms_vs_ref),
        ],
        ..Plot::default()
    };
    write_png(&a.output.join("drape-strain.png"), &btf_image::plot::render(&plot))?;
    if !shots.is_empty() {
        let labels: Vec<String> = rows.iter().map(|x| format!("t={:.2}s", x.t)).collect();
        let pairs: Vec<(&image::RgbImage, &str)> =
            shots.iter().zip(&labels).map(|(i, l)| (i, l.as_str())).collect();
        write_png(&a.output.join("drape.png"), &btf_image::compose::captioned_strip(&pairs, 4))?;
    }
    outln!("{md}");
    Ok(())
}

/// The GPU fibers ([W19], `yarn-render`) of one frame: the camera above the sphere,
/// looking down at 50° from the side, a directional light.
fn render_frame(
    gpu: &btf_render::Gpu,
    set: &yarn::YarnSet,
    params: &YarnParams,
    mesh: &datasets::mesh::Mesh,
    (w, h): (u32, u32),
) -> Result<image::RgbImage> {
    use yarn_render::{
        FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
    };
    let packed = PackedYarns::new(
        set,
        std::slice::from_ref(params),
        &PackOptions { seed: 1, frame_samples_per_segment: 8, tiles: [1, 1] },
    )?;
    let bcsdf = super::knit_render::bcsdf("khungurn")?;
    let settings = FiberSettings { lod_px: 1.0, msaa: 4, ..FiberSettings::default() };
    let r = FiberRenderer::new(gpu, &packed, &bcsdf, settings)?;
    // Frame the cloth's bounding box (all frames share the sphere; the start is the widest).
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for q in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let target = [0.0, 0.0, 0.5 * (lo[2] + hi[2])];
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(hi[2] - lo[2]);
    let dist = 1.1 * extent / (2.0 * (15f64).to_radians().tan());
    let dir = btf_core::Direction::new(50.0, 240.0).to_vector();
    let eye = [0, 1, 2].map(|k| target[k] + dist * dir[k]);
    let cam = FiberCamera::perspective(eye, target, [0.0, 0.0, 1.0], 30.0);
    let light = FiberLight::Directional {
        to_light: btf_core::Direction::new(35.0, 300.0).to_vector(),
        irradiance: [8.0; 3],
    };
    let img = r.render(gpu, &cam, &[light], (w, h), [0.05, 0.05, 0.06, 1.0])?;
    let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    Ok(btf_image::write::to_srgb_image(w as usize, h as usize, &rgb, 1.0))
}
