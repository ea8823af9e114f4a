//! `btf relight SCENE.toml --env a.exr --env b.hdr … [--rotations N] [--eigen E] -o OUTDIR`:
//! catalogue relighting. Renders the scene under every environment × rotation
//! (`δ_r = δ_scene + r · 360°/N`), building the mesh's visibility maps once (cached in
//! `OUTDIR/cache`), gathering the weights `g` once per environment (Sattler et al. 2003,
//! [S03 eq. 10]) and, with eigenweightsets, turning the environment by `e` vector additions
//! ([S03 eq. 13]). Frames are written atomically and skipped when already present, so an
//! interrupted job resumes; `job.json` pins the parameters a folder was rendered with.
//! `summary.json` holds `visibility_s`, `weights_s_per_env` and `frame_ms` with per-env
//! detail; with eigenweightsets, `OUTDIR/eigen/` gets the error table for `e = 1…8`,
//! heat maps and the `o_k(δ)` plot ([`crate::report::relight`]).

use crate::report::relight::EigenRow;
use anyhow::{Context, Result, bail, ensure};
use btf_image::EnvMap;
use btf_render::scene::{EigenSets, EnvironmentLight, Light, MAX_LIGHTS};
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `btf relight`.
#[derive(clap::Args, Debug)]
pub struct RelightArgs {
    /// The scene (TOML) and frame-size overrides.
    #[command(flatten)]
    pub scene: crate::args::SceneArgs,
    /// Environment maps (`.hdr`/`.exr`, equirectangular, `+z` up); repeat for several.
    #[arg(long = "env", required = true)]
    pub envs: Vec<PathBuf>,
    /// Rotations per environment, in equal steps of 360°/N from the scene's rotation.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=3600))]
    pub rotations: u32,
    /// Eigenweightset components `e` (0 = off; default: the scene's setting).
    #[arg(long)]
    pub eigen: Option<usize>,
    /// Output folder.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Also write linear EXR frames.
    #[arg(long)]
    pub exr: bool,
    /// Delete the output folder's frames and start again.
    #[arg(long)]
    pub fresh: bool,
    /// Shard of the job (its frames only) when several processes or machines share it.
    #[command(flatten)]
    pub shard: crate::args::ShardArgs,
}

/// One environment of the job.
struct EnvJob {
    path: PathBuf,
    stem: String,
    frames: Vec<(f64, PathBuf)>,
    report_done: bool,
}

#[derive(Serialize, Default)]
struct EnvSummary {
    path: String,
    /// Weights gathered in this run (false when all its outputs already existed).
    prepared: bool,
    frames_rendered: usize,
    frames_skipped: usize,
    gather_s: f64,
    eigen_s: f64,
    frame_ms_mean: f64,
    rotation_ms_mean: f64,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    eigen_error: Vec<EigenRow>,
}

#[derive(Serialize)]
struct Summary {
    visibility_s: f64,
    visibility_cached: bool,
    visibility_frames: usize,
    /// Frames whose visibility was computed: the vertex sides the camera shows.
    visibility_frames_computed: usize,
    /// Finding those sides (the corner-id pass), seconds; included in `visibility_s`.
    camera_sides_s: f64,
    weights_s_per_env: f64,
    frame_ms: f64,
    frames_rendered: usize,
    frames_skipped: usize,
    width: u32,
    height: u32,
    rotations: u32,
    eigenweightsets: Option<(usize, usize)>,
    setup: Vec<btf_render::PassStat>,
    envs: Vec<EnvSummary>,
}

/// Runs `btf relight`.
pub fn run(args: RelightArgs) -> Result<()> {
    let mut scene = args.scene.load_unvalidated()?;
    if scene.meshes.is_empty() {
        bail!(
            "{}: relight lights a scene by environment maps, whose visibility and \
             eigenweightsets belong to BTF meshes; this scene has [[yarns]] alone (render it \
             with btf render under point and directional lights)",
            args.scene.scene.display()
        );
    }
    let env_index = attach_environment(&mut scene, &args)?;
    scene.validate(&args.scene.scene)?;
    let mut jobs = plan(&args, &scene, env_index)?;
    let shard = args.shard.shard()?;
    if let Some(shard) = shard {
        keep_shard(&mut jobs, shard, args.rotations as usize);
        // A frame of this shard that does not decode (`btf status` calls it corrupt) is
        // rendered again: it is this shard's own file.
        for (_, png) in jobs.iter().flat_map(|j| &j.frames) {
            if crate::cmd::shards::frame_is_corrupt(png, args.exr) {
                eprintln!("warning: {} is corrupt; rendering it again", png.display());
                std::fs::remove_file(png).with_context(|| format!("removing {}", png.display()))?;
            }
        }
    }
    let envs: Vec<(&str, &Path)> = args.envs.iter().map(|p| ("--env", p.as_path())).collect();
    crate::guard::refuse_scene_overlap(&[("-o", &args.output)], &args.scene.scene, &scene, &envs)?;
    let pending: usize =
        jobs.iter().map(|j| j.frames.iter().filter(|(_, p)| !p.exists()).count()).sum();
    let all: usize = jobs.iter().map(|j| j.frames.len()).sum();
    let finished = pending == 0 && jobs.iter().all(|j| j.report_done);
    if finished && shard.is_some() && args.output.join("job.json").is_file() {
        // A shard retried after its work (or the whole job) was done: check it is the same
        // job and leave the folder as it is (a finalised job keeps no shard records).
        btf_core::shard::check_agrees(&args.output.join("job.json"), &job_record(&args, &scene))?;
    } else {
        prepare_output(&args, &scene, shard)?;
    }
    let (pending, finished) = if args.fresh {
        // `--fresh` (never with --shard) removed the frames: plan again.
        jobs = plan(&args, &scene, env_index)?;
        let pending: usize = jobs.iter().map(|j| j.frames.len()).sum();
        (pending, false)
    } else {
        (pending, finished)
    };
    if finished {
        let whose = shard.map_or(String::new(), |s| format!("shard {}: ", s.label()));
        crate::guard::outln!(
            "{whose}all {all} frames of {} already rendered",
            args.output.display()
        );
        return Ok(());
    }
    let first = jobs.iter().position(|j| !j.is_done()).unwrap_or(0);
    set_env_path(&mut scene, env_index, &jobs[first].path);
    let yarns = crate::scene_yarns::SceneYarns::build(
        &scene,
        &args.scene.scene,
        Some(args.output.join("cache").join("yarns")),
    )?;
    let gpu = Gpu::new().context("creating a headless GPU device")?;
    // With eigenweightsets, the PCA of `U` over rotations takes every vertex side, so the
    // frames would depend on which sides' visibility happens to be cached (the report
    // computes all of them): compute all from the start, so that a resumed job or a
    // shard started at any time renders the very same frames.
    let eigen = scene.environment().and_then(|(_, e)| e.eigenweightsets).is_some();
    let options = RenderOptions { all_env_sides: eigen, ..RenderOptions::default() };
    let mut renderer = yarns.renderer(&gpu, &scene, options).with_context(|| {
        format!("preparing {} with {}", args.scene.scene.display(), jobs[first].path.display())
    })?;
    let bar = crate::progress::bar(pending as u64, "relight");
    let mut summaries = Vec::new();
    for (i, job) in jobs.iter_mut().enumerate() {
        let mut s = EnvSummary { path: job.path.display().to_string(), ..Default::default() };
        s.frames_skipped = job.frames.iter().filter(|(_, p)| p.exists()).count();
        if !job.is_done() {
            bar.set_message(job.stem.clone());
            if i != first {
                let map = EnvMap::load(&job.path)
                    .with_context(|| format!("environment {}", job.path.display()))?;
                renderer.set_environment(&map)?;
            }
            let t = &renderer.environment().context("no environment light")?.timings;
            (s.gather_s, s.eigen_s) = (t.weights_ms / 1e3, t.eigen_ms / 1e3);
            s.prepared = true;
            render_frames(&mut renderer, &gpu, &scene, job, &args, &mut s, &bar)?;
            if scene.environment().and_then(|(_, e)| e.eigenweightsets).is_some() {
                let dir = args.output.join("eigen");
                s.eigen_error =
                    crate::report::relight::write(&mut renderer, &gpu, &job.stem, &dir)?;
                job.report_done = true;
            }
        }
        summaries.push(s);
    }
    bar.finish_and_clear();
    let summary = summarise(&renderer, &scene, &args, summaries)?;
    let text = serde_json::to_string_pretty(&summary)?;
    // A shard's summary covers its own frames: it goes beside the others', for
    // `btf finalize` to merge into summary.json.
    let path = match shard {
        Some(s) => crate::cmd::shards::relight_shard_summary(&args.output, s),
        None => args.output.join("summary.json"),
    };
    btf_image::write::write_text(&path, &text)?;
    crate::guard::outln!(
        "{}{} frames rendered, {} reused; visibility {:.2} s, weights {:.3} s per environment, {:.1} ms per frame → {}",
        shard.map_or(String::new(), |s| format!("shard {}: ", s.label())),
        summary.frames_rendered,
        summary.frames_skipped,
        summary.visibility_s,
        summary.weights_s_per_env,
        summary.frame_ms,
        path.display()
    );
    if shard.is_some() {
        crate::guard::outln!("  when every shard is done: btf finalize {}", args.output.display());
    }
    Ok(())
}

/// Keeps the frames `shard` owns: frames are numbered environment by environment, rotation
/// by rotation, and split into contiguous blocks ([`btf_core::shard::Shard::range`]). An
/// environment's eigenweightset report goes with its first frame's shard.
fn keep_shard(jobs: &mut [EnvJob], shard: btf_core::shard::Shard, rotations: usize) {
    let mine = shard.range(jobs.len() * rotations);
    for (e, job) in jobs.iter_mut().enumerate() {
        let first = e * rotations;
        if !mine.contains(&first) {
            job.report_done = true;
        }
        let frames = std::mem::take(&mut job.frames);
        job.frames = frames
            .into_iter()
            .enumerate()
            .filter(|(r, _)| mine.contains(&(first + r)))
            .map(|(_, f)| f)
            .collect();
    }
}

impl EnvJob {
    fn is_done(&self) -> bool {
        self.report_done && self.frames.iter().all(|(_, p)| p.exists())
    }
}

/// Makes sure the scene has an environment light (appending a default one) and applies
/// `--eigen`; returns its index in `scene.lights`.
fn attach_environment(scene: &mut Scene, args: &RelightArgs) -> Result<usize> {
    let index = match scene.environment() {
        Some((i, _)) => i,
        None => {
            ensure!(
                scene.lights.len() < MAX_LIGHTS,
                "{}: the scene has {MAX_LIGHTS} lights; no room for the environment light",
                args.scene.scene.display()
            );
            scene.lights.push(Light::Environment(EnvironmentLight {
                path: args.envs[0].clone(),
                rotation_deg: 0.0,
                exposure: 1.0,
                visibility_res: 16,
                two_sided: true,
                eigenweightsets: None,
                cache_dir: None,
            }));
            scene.lights.len() - 1
        }
    };
    let Light::Environment(env) = &mut scene.lights[index] else { unreachable!() };
    match args.eigen {
        Some(0) => env.eigenweightsets = None,
        Some(e) => {
            let rotations = env.eigenweightsets.map_or(30, |s| s.rotations);
            env.eigenweightsets = Some(EigenSets { rotations, components: e });
        }
        None => {}
    }
    if env.cache_dir.is_none() {
        env.cache_dir = Some(args.output.join("cache"));
    }
    Ok(index)
}

fn set_env_path(scene: &mut Scene, index: usize, path: &Path) {
    if let Light::Environment(env) = &mut scene.lights[index] {
        env.path = path.to_owned();
    }
}

/// The frames of every environment; refuses missing files and clashing names up front.
fn plan(args: &RelightArgs, scene: &Scene, index: usize) -> Result<Vec<EnvJob>> {
    let Light::Environment(env) = &scene.lights[index] else { unreachable!() };
    let eigen = env.eigenweightsets.is_some();
    let mut jobs: Vec<EnvJob> = Vec::new();
    for path in &args.envs {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("hdr" | "exr")) {
            bail!("{}: environment maps must be .hdr or .exr", path.display());
        }
        ensure!(path.is_file(), "environment {}: no such file", path.display());
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        if let Some(other) = jobs.iter().find(|j| j.stem == stem) {
            bail!(
                "environments {} and {} would write frames of the same name '{stem}'; rename one",
                other.path.display(),
                path.display()
            );
        }
        let frames = (0..args.rotations)
            .map(|r| {
                let delta = env.rotation_deg + r as f64 * 360.0 / args.rotations as f64;
                (delta, args.output.join(format!("{stem}_r{r:03}.png")))
            })
            .collect();
        let report_done =
            !eigen || args.output.join("eigen").join(format!("{stem}-error.md")).exists();
        jobs.push(EnvJob { path: path.clone(), stem, frames, report_done });
    }
    Ok(jobs)
}

/// What `btf relight` writes into its folder (and `--fresh` removes): frames
/// `STEM_rNNN.{png,exr}`, `summary.json`, `job.json` and the `eigen/` report.
fn relight_output(name: &str) -> bool {
    let frame = name
        .rsplit_once('.')
        .filter(|(_, ext)| matches!(*ext, "png" | "exr"))
        .and_then(|(stem, _)| stem.rsplit_once("_r"))
        .is_some_and(|(_, r)| r.len() == 3 && r.bytes().all(|b| b.is_ascii_digit()));
    frame
        || matches!(name, "summary.json" | "job.json" | "eigen" | "shards")
        || btf_core::fs::is_temp_name(name)
}

/// Creates the folder and checks (or writes) `job.json`, so that frames of a different job
/// are never mistaken for finished ones. A shard checks the job (and the shard plan)
/// before it writes anything; the first shard creates them ([`btf_core::shard`]).
fn prepare_output(
    args: &RelightArgs,
    scene: &Scene,
    shard: Option<btf_core::shard::Shard>,
) -> Result<()> {
    let out = &args.output;
    let job = job_record(args, scene);
    if let Some(shard) = shard {
        ensure!(
            !args.fresh,
            "--fresh cannot be combined with --shard: one shard would delete the others' frames"
        );
        btf_core::fs::check_replaceable(
            out,
            btf_core::fs::OutputKind::Folder { marker: crate::guard::FOLDER_MARKER },
        )?;
        let mut plan =
            crate::cmd::shards::relight_plan(shard.count, args.envs.len(), args.rotations);
        plan["inputs"] = input_identities(args, scene)?;
        for (path, record) in
            [(out.join("job.json"), &job), (crate::cmd::shards::plan_path(out), &plan)]
        {
            if path.exists() {
                btf_core::shard::check_agrees(&path, record)
                    .context("this shard is not part of the relight job in that folder")?;
            }
        }
        crate::guard::shared_output_folder(out, "relight")?;
        btf_core::shard::agree_or_create(&out.join("job.json"), &job)?;
        btf_core::shard::agree_or_create(&crate::cmd::shards::plan_path(out), &plan)?;
        return Ok(());
    }
    let path = out.join("job.json");
    let text = serde_json::to_string_pretty(&job)?;
    let old = if args.fresh { None } else { std::fs::read_to_string(&path).ok() };
    if let Some(old) = old.filter(|old| *old != text) {
        let was: serde_json::Value = serde_json::from_str(&old).unwrap_or_default();
        bail!(
            "{} holds frames of a different relight job ({}); use --fresh or another folder",
            out.display(),
            btf_core::store::first_difference(&was, &job, "")
        );
    }
    crate::guard::output_folder(out, "relight", args.fresh, &relight_output)?;
    if path.exists() {
        return Ok(());
    }
    Ok(btf_image::write::write_text(&path, &text)?)
}

/// What identifies the job's input files for its shards, by the name the job knows them
/// by (not their path, which may differ between machines): a store by its content
/// fingerprint ([`btf_core::shard::fingerprint`]), any other file by its size and
/// modification time (reading every environment map in every shard would cost more than
/// the shard's frames).
fn input_identities(args: &RelightArgs, scene: &Scene) -> Result<serde_json::Value> {
    let mut named: Vec<(String, std::path::PathBuf)> = scene
        .input_paths()
        .into_iter()
        .filter(|(name, _)| !name.starts_with("[[lights]]"))
        .collect();
    named.extend(args.envs.iter().enumerate().map(|(i, p)| (format!("--env {i}"), p.clone())));
    let mut out = serde_json::Map::new();
    for (name, path) in named {
        let id = if path.is_dir() {
            serde_json::json!({ "fingerprint": btf_core::shard::fingerprint(&path)? })
        } else {
            let m =
                std::fs::metadata(&path).with_context(|| format!("{name} {}", path.display()))?;
            let mtime = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            serde_json::json!({ "bytes": m.len(), "mtime_ns": mtime.to_string() })
        };
        out.insert(name, id);
    }
    Ok(serde_json::Value::Object(out))
}

/// What `job.json` pins: the scene (without the environment path, which varies), the
/// environments, rotations and whether EXR frames are written.
fn job_record(args: &RelightArgs, scene: &Scene) -> serde_json::Value {
    let mut scene_for_key = scene.clone();
    if let Some((i, _)) = scene.environment() {
        set_env_path(&mut scene_for_key, i, Path::new(""));
    }
    serde_json::json!({
        "scene": scene_for_key,
        "envs": args.envs,
        "rotations": args.rotations,
        "exr": args.exr,
    })
}

fn render_frames(
    renderer: &mut Renderer,
    gpu: &Gpu,
    scene: &Scene,
    job: &EnvJob,
    args: &RelightArgs,
    s: &mut EnvSummary,
    bar: &indicatif::ProgressBar,
) -> Result<()> {
    let (w, h) = (scene.output.width as usize, scene.output.height as usize);
    let (mut frame_ms, mut rotation_ms) = (0.0, 0.0);
    for (delta, png) in &job.frames {
        if png.exists() {
            continue;
        }
        let t = Instant::now();
        renderer.set_environment_rotation(*delta)?;
        let rot = t.elapsed().as_secs_f64() * 1e3;
        let frame = renderer.render(gpu)?;
        ensure!(frame.all_finite(), "{}: the render has non-finite pixels", png.display());
        frame_ms += t.elapsed().as_secs_f64() * 1e3;
        rotation_ms += rot;
        if args.exr {
            btf_image::write::write_exr_rgb(&png.with_extension("exr"), w, h, &frame.rgb)?;
        }
        btf_image::write::write_png_linear(png, w, h, &frame.rgb, scene.output.exposure)?;
        s.frames_rendered += 1;
        bar.inc(1);
        crate::progress::unit_delay();
    }
    let n = s.frames_rendered.max(1) as f64;
    (s.frame_ms_mean, s.rotation_ms_mean) = (frame_ms / n, rotation_ms / n);
    Ok(())
}

fn summarise(
    renderer: &Renderer,
    scene: &Scene,
    args: &RelightArgs,
    envs: Vec<EnvSummary>,
) -> Result<Summary> {
    let env = renderer.environment().context("no environment light")?;
    let prepared: Vec<&EnvSummary> = envs.iter().filter(|e| e.prepared).collect();
    let frames: usize = envs.iter().map(|e| e.frames_rendered).sum();
    let frame_ms = envs.iter().map(|e| e.frame_ms_mean * e.frames_rendered as f64).sum::<f64>()
        / frames.max(1) as f64;
    Ok(Summary {
        visibility_s: (env.timings.visibility_ms + env.timings.sides_ms) / 1e3,
        visibility_cached: env.timings.visibility_cached,
        visibility_frames: env.visibility().frames,
        visibility_frames_computed: env.computed_frames(),
        camera_sides_s: env.timings.sides_ms / 1e3,
        weights_s_per_env: prepared.iter().map(|e| e.gather_s + e.eigen_s).sum::<f64>()
            / prepared.len().max(1) as f64,
        frame_ms,
        frames_rendered: frames,
        frames_skipped: envs.iter().map(|e| e.frames_skipped).sum(),
        width: scene.output.width,
        height: scene.output.height,
        rotations: args.rotations,
        eigenweightsets: env.eigen_params(),
        setup: renderer.setup_stats(),
        envs,
    })
}
