//! `btf synth garment`: a garment sewn from pattern panels and draped on a parametric
//! mannequin by cloth simulation (`datasets::garment`), or the mannequin itself
//! (`--kind body`), written as OBJ through the atomic writer.

use crate::args::choices;
use anyhow::{Context, Result, bail};
use clap::Args;
use datasets::garment::checkpoint::{Checkpointing, Snapshot};
use datasets::garment::{Body, GarmentKind, GarmentOptions, Size, check};
use std::path::PathBuf;

choices! {
    /// `btf synth garment --kind`.
    GarmentChoice {
        /// Short-sleeved T-shirt: front, back, two sleeves.
        Tshirt = "tshirt",
        /// Long-sleeved shirt.
        Shirt = "shirt",
        /// Trousers: front and back of each leg.
        Trousers = "trousers",
        /// A-line skirt: front and back.
        Skirt = "skirt",
        /// Scarf laid round the neck.
        Scarf = "scarf",
        /// Curtain panel gathered in six pleats on a rod behind the mannequin (not draped on it).
        Curtain = "curtain",
        /// The mannequin alone (closed mesh).
        Body = "body",
    }
}

choices! {
    /// `btf synth garment --size`.
    SizeChoice {
        /// Small (1.68 m, chest 0.90 m).
        S = "S",
        /// Medium (1.76 m, chest 0.98 m).
        M = "M",
        /// Large (1.84 m, chest 1.07 m).
        L = "L",
    }
}

/// `btf synth garment`.
#[derive(Args)]
pub struct GarmentArgs {
    /// The garment, or `body` for the mannequin alone.
    #[arg(long)]
    pub kind: GarmentChoice,
    /// Body size.
    #[arg(long, default_value = "M")]
    pub size: SizeChoice,
    /// Body height (m), overriding the size's.
    #[arg(long)]
    pub height: Option<f64>,
    /// Chest girth (m), overriding the size's.
    #[arg(long)]
    pub chest: Option<f64>,
    /// Waist girth (m), overriding the size's.
    #[arg(long)]
    pub waist: Option<f64>,
    /// Hip girth (m), overriding the size's.
    #[arg(long)]
    pub hip: Option<f64>,
    /// Drape on this closed OBJ body instead of the mannequin (the pattern is still drafted
    /// for the size's measurements).
    #[arg(long, value_name = "FILE")]
    pub body: Option<PathBuf>,
    /// Target vertex count of the garment [default: 10 000; the scarf 3 000].
    #[arg(long)]
    pub vertices: Option<usize>,
    /// Sleeve length from the shoulder point (m).
    #[arg(long)]
    pub sleeve_length: Option<f64>,
    /// Garment length (m).
    #[arg(long)]
    pub length: Option<f64>,
    /// Sew and drape without cloth–cloth contact: faster (at 10 000 vertices 12–19 s
    /// instead of 15–27 s), but layers pass through each other — the T-shirt, the shirt and
    /// the trousers come out with 139–385 crossing triangle pairs (BENCHMARKS.md,
    /// "Cloth–cloth contact").
    #[arg(long)]
    pub no_cloth_contact: bool,
    /// Go on from the snapshot an interrupted run of the same command left in `OUT.partial`
    /// (written every 10 s of sewing and draping; the result is bit for bit that of an
    /// uninterrupted run). Without it a run starts over.
    #[arg(long)]
    pub resume: bool,
    /// Seconds of wall time between snapshots (tests: 0 snapshots at every chance).
    #[arg(long, default_value_t = 10.0, hide = true)]
    pub snapshot_every: f64,
    /// Stop with an error after this many snapshots, as an interruption would (tests).
    #[arg(long, hide = true)]
    pub stop_after_snapshots: Option<usize>,
    /// Also write the body the garment was draped on (OBJ, material `body`).
    #[arg(long, value_name = "FILE")]
    pub body_out: Option<PathBuf>,
    /// Output OBJ file.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
}

/// Runs `btf synth garment`.
pub fn run(a: GarmentArgs) -> Result<()> {
    let size = Size::from_name(a.size.as_str())?;
    let mut o = GarmentOptions::new(size);
    let m = &mut o.body.measurements;
    for (v, slot) in [
        (a.height, &mut m.height_m),
        (a.chest, &mut m.chest_m),
        (a.waist, &mut m.waist_m),
        (a.hip, &mut m.hip_m),
    ] {
        if let Some(v) = v {
            *slot = v;
        }
    }
    m.validate()?;
    o.drape.cloth_contact = !a.no_cloth_contact;
    o.pattern.sleeve_length_m = a.sleeve_length;
    o.pattern.length_m = a.length;
    let mut outputs: Vec<(&str, &std::path::Path)> = vec![("--out", a.output.as_path())];
    if let Some(p) = &a.body_out {
        outputs.push(("--body-out", p.as_path()));
    }
    let inputs: Vec<(&str, &std::path::Path)> =
        a.body.iter().map(|p| ("--body", p.as_path())).collect();
    crate::guard::refuse_overlap(&outputs, &inputs)?;
    for (_, p) in &outputs {
        crate::guard::check_file(p, btf_core::fs::TEXT)?;
    }
    let t0 = std::time::Instant::now();
    let body_file = match &a.body {
        Some(p) => {
            let mesh =
                datasets::read_obj(p).with_context(|| format!("reading --body {}", p.display()))?;
            Some(
                Body::from_mesh(mesh, o.body.sdf_step_m)
                    .with_context(|| format!("--body {}", p.display()))?,
            )
        }
        None => None,
    };
    let comment = format!("btf synth garment --kind {} --size {}", a.kind, a.size);
    if a.kind == GarmentChoice::Body {
        if a.body.is_some() {
            bail!(
                "--kind body makes the mannequin; --body is for draping a garment on another body"
            );
        }
        let body = Body::new(&o.body)?;
        datasets::write_obj_material(&body.mesh, &a.output, &comment, Some("body"))?;
        eprintln!(
            "body ({}): {} vertices, {} triangles, {:.2} s -> {}",
            a.size,
            body.mesh.positions.len(),
            body.mesh.triangles.len(),
            t0.elapsed().as_secs_f64(),
            a.output.display()
        );
        return Ok(());
    }
    let kind = GarmentKind::from_name(a.kind.as_str())?;
    if a.sleeve_length.is_some() && !matches!(kind, GarmentKind::TShirt | GarmentKind::Shirt) {
        bail!("--sleeve-length is for --kind tshirt or shirt, not {}", a.kind);
    }
    o.vertices = a.vertices.unwrap_or_else(|| datasets::garment::sew::default_vertices(kind));
    let bar = crate::progress::bar(1000, "garment");
    if !crate::progress::enabled() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    // Snapshots go to OUT.partial, keyed by everything that shapes the garment (the body
    // file by its bytes), and are removed once the garment is written.
    let partial = crate::guard::partial_of(&a.output);
    let mut fingerprint = format!("{kind:?}\n{o:?}\n").into_bytes();
    if let Some(p) = &a.body {
        fingerprint
            .extend(std::fs::read(p).with_context(|| format!("reading --body {}", p.display()))?);
    }
    let key = datasets::garment::checkpoint::fingerprint(&fingerprint);
    let from = if a.resume && partial.is_file() {
        let bytes = std::fs::read(&partial)
            .with_context(|| format!("reading the snapshot {}", partial.display()))?;
        let s = Snapshot::from_bytes(&bytes).with_context(|| format!("{}", partial.display()))?;
        eprintln!("resuming from {} (phase {})", partial.display(), s.phase);
        Some(s)
    } else {
        if a.resume {
            eprintln!("no snapshot at {}: starting from the beginning", partial.display());
        }
        None
    };
    if !(a.snapshot_every >= 0.0 && a.snapshot_every < 1e9) {
        bail!("--snapshot-every = {}: give seconds, 0 or more", a.snapshot_every);
    }
    // This run's work is in OUT.partial once it has resumed or saved one; a snapshot another
    // run left there is not this run's to point at.
    let resumed = from.is_some();
    let saved = std::cell::Cell::new(0usize);
    let mut save = |s: &Snapshot| {
        let saved_so_far = saved.get();
        if a.stop_after_snapshots.is_some_and(|n| saved_so_far >= n) {
            return Err(datasets::Error::Invalid(format!(
                "stopped after {saved_so_far} snapshots (--stop-after-snapshots)"
            )));
        }
        btf_core::fs::write_atomic(&partial, &s.to_bytes())
            .map_err(|e| datasets::Error::Invalid(format!("{}: {e}", partial.display())))?;
        saved.set(saved_so_far + 1);
        Ok(())
    };
    let every = std::time::Duration::from_secs_f64(a.snapshot_every);
    let mut checkpoints = Checkpointing::new(key, from, every, &mut save).with_context(|| {
        format!(
            "{} is another run's (run that command with --resume, or this one without it to \
             start over)",
            partial.display()
        )
    })?;
    let (g, body) = datasets::garment::make_resumable(
        kind,
        &o,
        body_file,
        &mut |stage, f| {
            bar.set_message(stage.to_owned());
            bar.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64);
        },
        Some(&mut checkpoints),
    )
    .map_err(|e| {
        let e = anyhow::Error::from(e);
        if partial.is_file() && (resumed || saved.get() > 0) {
            e.context(format!(
                "the work done so far is kept in {}; run the same command with --resume to \
                 continue",
                partial.display()
            ))
        } else {
            e
        }
    })?;
    drop(checkpoints);
    bar.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    datasets::write_obj(&g.mesh, &a.output, &comment)?;
    if let Some(p) = &a.body_out {
        datasets::write_obj_material(
            &body.mesh,
            p,
            &format!("{comment} (its body)"),
            Some("body"),
        )?;
    }
    if partial.is_file() {
        std::fs::remove_file(&partial).with_context(|| {
            format!("removing the finished run's snapshot {}", partial.display())
        })?;
    }
    let topo = check::topology(g.mesh.positions.len(), &g.mesh.triangles);
    eprintln!(
        "{} ({}): {} vertices, {} triangles, {} openings, seams closed to {:.1} mm, rest {} after {:.2} s simulated ({} steps, kinetic energy {:.1e} J/kg), min body distance {:.1} mm, {} crossing triangle pairs ({} smoothing rounds{}), {:.1} s -> {}",
        a.kind,
        a.size,
        g.mesh.positions.len(),
        g.mesh.triangles.len(),
        topo.boundary_loops.len(),
        1e3 * g.seam_gap_at_weld_m,
        if g.drape.settled { "reached" } else { "NOT reached" },
        g.drape.settle_time_s,
        g.sewing.steps + g.drape.steps,
        g.drape.kinetic_energy_per_kg,
        1e3 * check::min_body_distance(&g.mesh, &body.sdf),
        check::self_intersections(&g.mesh).len(),
        g.untangle_rounds,
        if g.final_smoothing_m > 0.0 {
            format!(
                ", the last after the drape moving vertices up to {:.1} mm",
                1e3 * g.final_smoothing_m
            )
        } else {
            String::new()
        },
        secs,
        a.output.display()
    );
    Ok(())
}
