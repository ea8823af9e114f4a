//! `btf status OUT` and `btf finalize OUT` (issue #23): which frames (a `btf relight`
//! folder) or view slots (a `btf compress` eigen store, a `btf synth material` BTF store)
//! of a job are done, missing or corrupt — overall and per shard, as a table or `--json` —
//! and the one step that needs every part: for a store, committing `OUT.partial` to `OUT`
//! (with the error report over all slots for a compression); for a relight job, merging
//! the shards' summaries into `summary.json`.
//!
//! A frame is done when its PNG (and EXR, when the job writes them) decodes — the PNG
//! chunks' CRCs and the EXR's structure are checked by decoding — and, for an
//! environment's first frame in a job with eigenweightsets, when its error report is
//! there. A view slot is done when its five chunks are present with valid crc32c and its
//! statistics are recorded ([`btf_core::eigen::EigenWriter::slot_state`]). Finalising is
//! idempotent: a second run finds the work done and only reports.

use crate::guard::outln;
use anyhow::{Context, Result, bail};
use btf_core::shard::Shard;
use serde::Serialize;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Arguments of `btf status`.
#[derive(clap::Args)]
pub struct StatusArgs {
    /// A `btf relight` output folder or a `btf compress` output store (`OUT.eig`; its
    /// `OUT.eig.partial` while shards are writing it).
    output: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Arguments of `btf finalize`.
#[derive(clap::Args)]
pub struct FinalizeArgs {
    /// The output every shard wrote into (as for `btf status`).
    output: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// The state of one unit of work.
#[derive(Debug, Clone, PartialEq)]
enum State {
    Done,
    Missing,
    Corrupt(String),
}

/// What `btf status` reports (the `--json` keys).
#[derive(Serialize)]
struct Status {
    /// `"relight"`, `"compress"` or `"synth"` (a BTF store that `btf synth material` shards
    /// fill).
    kind: &'static str,
    output: String,
    /// `"frames"` or `"view slots"`.
    units: &'static str,
    total: usize,
    done: usize,
    missing: usize,
    corrupt: usize,
    /// Every unit done.
    complete: bool,
    /// Finalised: the store committed, or the shards' summaries merged.
    finalised: bool,
    shards: Vec<ShardRow>,
    /// Names of the missing units (frames, `slot N`).
    missing_units: Vec<String>,
    /// Corrupt units with what is wrong.
    corrupt_units: Vec<Value>,
}

#[derive(Serialize)]
struct ShardRow {
    shard: String,
    units: usize,
    done: usize,
    missing: usize,
    corrupt: usize,
    /// `"done"`, `"incomplete"` (missing units) or `"corrupt"`.
    state: &'static str,
}

fn status_of(
    kind: &'static str,
    output: &Path,
    units: &'static str,
    list: &[(String, State)],
    shards: usize,
    finalised: bool,
) -> Status {
    let count = |f: &dyn Fn(&State) -> bool| list.iter().filter(|(_, s)| f(s)).count();
    let rows = (0..shards.max(1))
        .map(|i| {
            let r = Shard { index: i, count: shards.max(1) }.range(list.len());
            let part = &list[r.clone()];
            let n = |f: &dyn Fn(&State) -> bool| part.iter().filter(|(_, s)| f(s)).count();
            let (done, missing) = (n(&|s| *s == State::Done), n(&|s| *s == State::Missing));
            let corrupt = part.len() - done - missing;
            ShardRow {
                shard: format!("{i}/{}", shards.max(1)),
                units: part.len(),
                done,
                missing,
                corrupt,
                state: if corrupt > 0 {
                    "corrupt"
                } else if missing > 0 {
                    "incomplete"
                } else {
                    "done"
                },
            }
        })
        .collect();
    let done = count(&|s| *s == State::Done);
    Status {
        kind,
        output: output.display().to_string(),
        units,
        total: list.len(),
        done,
        missing: count(&|s| *s == State::Missing),
        corrupt: count(&|s| matches!(s, State::Corrupt(_))),
        complete: done == list.len(),
        finalised,
        shards: rows,
        missing_units: list
            .iter()
            .filter(|(_, s)| *s == State::Missing)
            .map(|(n, _)| n.clone())
            .collect(),
        corrupt_units: list
            .iter()
            .filter_map(|(n, s)| match s {
                State::Corrupt(why) => Some(json!({"unit": n, "why": why})),
                _ => None,
            })
            .collect(),
    }
}

/// Runs `btf status`.
pub fn run_status(a: StatusArgs) -> Result<()> {
    let st = status(&a.output)?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&st)?);
        return Ok(());
    }
    outln!(
        "{} job {}: {} of {} {} done, {} missing, {} corrupt{}",
        st.kind,
        st.output,
        st.done,
        st.total,
        st.units,
        st.missing,
        st.corrupt,
        if st.finalised { "; finalised" } else { "" }
    );
    outln!(
        "{:>9} {:>7} {:>7} {:>8} {:>8}  state",
        "shard",
        st.units.split(' ').next_back().unwrap_or(""),
        "done",
        "missing",
        "corrupt"
    );
    for r in &st.shards {
        outln!(
            "{:>9} {:>7} {:>7} {:>8} {:>8}  {}",
            r.shard,
            r.units,
            r.done,
            r.missing,
            r.corrupt,
            r.state
        );
    }
    for c in &st.corrupt_units {
        outln!(
            "  corrupt {}: {}",
            c["unit"].as_str().unwrap_or(""),
            c["why"].as_str().unwrap_or("")
        );
    }
    if st.complete && !st.finalised {
        outln!("every part is done: run `btf finalize {}`", a.output.display());
    }
    Ok(())
}

/// The status of the job at `output`, whichever kind it is.
fn status(output: &Path) -> Result<Status> {
    let output = strip_partial(output);
    if output.join("job.json").is_file() {
        return relight_status(&output);
    }
    if let Some(kind) = btf_core::store::store_kind(&output) {
        let st = if kind == "btf" {
            btf_core::store::sharded_status(&output)
        } else {
            btf_core::compress::status(&output)
        }
        .with_context(|| format!("reading the state of {}", output.display()))?;
        let kind = if kind == "btf" { "synth" } else { "compress" };
        let list: Vec<(String, State)> = st
            .slots
            .iter()
            .enumerate()
            .map(|(v, s)| {
                let state = match s.as_str() {
                    "done" => State::Done,
                    "missing" => State::Missing,
                    other => State::Corrupt(other.trim_start_matches("corrupt: ").to_string()),
                };
                (format!("slot {v}"), state)
            })
            .collect();
        return Ok(status_of(kind, &output, "view slots", &list, st.shards, st.finalised));
    }
    bail!(
        "{}: neither a `btf relight` folder (no job.json) nor a `btf compress` store or its \
         partial",
        output.display()
    )
}

/// `OUT` for `OUT.partial`.
fn strip_partial(p: &Path) -> PathBuf {
    let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match name.strip_suffix(".partial") {
        Some(base) if !base.is_empty() => p.with_file_name(base),
        _ => p.to_owned(),
    }
}

/// Runs `btf finalize`.
pub fn run_finalize(a: FinalizeArgs) -> Result<()> {
    let output = strip_partial(&a.output);
    if output.join("job.json").is_file() {
        return finalize_relight(&output, a.json);
    }
    if btf_core::store::store_kind(&output).as_deref() == Some("btf") {
        let record = btf_core::store::StoreTxn::recorded_job(&output);
        let capture = record.is_some_and(|r| r["job"]["kind"] == "capture process");
        let already = if capture {
            btf_capture::capture::finalize_shards(&output).map_err(anyhow::Error::from)
        } else {
            btf_core::store::finalize_sharded(&output).map_err(anyhow::Error::from)
        }
        .with_context(|| format!("finalising {}", output.display()))?;
        let st = status(&output)?;
        if a.json {
            outln!("{}", serde_json::to_string_pretty(&st)?);
        } else {
            let what = if already { "already finalised" } else { "finalised" };
            outln!("{what} {}: {} view slots", output.display(), st.total);
        }
        return Ok(());
    }
    let (r, already) = btf_core::compress::finalize(&output)
        .with_context(|| format!("finalising {}", output.display()))?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        outln!(
            "{} {}: {} slots, {} components ({}); relative RMSE {:.3e} (exact PCA {:.3e}), PSNR {:.1} dB",
            if already { "already finalised" } else { "finalised" },
            output.display(),
            r.slots.len(),
            r.components,
            r.quantization.name(),
            r.rel_rmse,
            r.rel_rmse_exact,
            r.psnr_db
        );
    }
    Ok(())
}

/// `OUT/shards/plan.json`: how a sharded relight job is split.
pub fn plan_path(out: &Path) -> PathBuf {
    out.join("shards").join("plan.json")
}

/// The plan every shard of a relight job agrees on.
pub fn relight_plan(shards: usize, envs: usize, rotations: u32) -> Value {
    json!({ "shards": shards, "frames": envs * rotations as usize })
}

/// Where shard `s` of a relight job leaves its summary.
pub fn relight_shard_summary(out: &Path, s: Shard) -> PathBuf {
    out.join("shards").join(format!("summary-{}-of-{}.json", s.index, s.count))
}

/// The frames of the relight job recorded in `out/job.json`, in shard order, with their
/// state.
fn relight_frames(out: &Path) -> Result<Vec<(String, State)>> {
    let path = out.join("job.json");
    let job: Value = serde_json::from_slice(
        &std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("{}: not JSON", path.display()))?;
    let envs =
        job["envs"].as_array().with_context(|| format!("{}: no envs list", path.display()))?;
    let rotations =
        job["rotations"].as_u64().with_context(|| format!("{}: no rotations", path.display()))?;
    let exr = job["exr"].as_bool().unwrap_or(false);
    let eigen = job["scene"]["lights"].as_array().is_some_and(|ls| {
        ls.iter().any(|l| !l["eigenweightsets"].is_null() && l.get("eigenweightsets").is_some())
    });
    let mut list = Vec::new();
    for env in envs {
        let env = Path::new(env.as_str().unwrap_or_default());
        let stem = env.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        for r in 0..rotations {
            let name = format!("{stem}_r{r:03}.png");
            let mut state = frame_state(&out.join(&name), exr);
            if r == 0
                && eigen
                && state == State::Done
                && !out.join("eigen").join(format!("{stem}-error.md")).is_file()
            {
                state = State::Missing;
            }
            list.push((name, state));
        }
    }
    Ok(list)
}

/// Whether frame `png` (and its EXR, with `exr`) is there but does not decode.
pub fn frame_is_corrupt(png: &Path, exr: bool) -> bool {
    png.is_file() && matches!(frame_state(png, exr), State::Corrupt(_))
}

fn frame_state(png: &Path, exr: bool) -> State {
    if !png.is_file() || exr && !png.with_extension("exr").is_file() {
        return State::Missing;
    }
    if let Err(e) = image::open(png) {
        return State::Corrupt(format!("{}: {e}", png.display()));
    }
    if exr {
        let p = png.with_extension("exr");
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &p,
            |_, _| (),
            |_: &mut (), _, _: (f32, f32, f32, f32)| {},
        );
        if let Err(e) = read {
            return State::Corrupt(format!("{}: {e}", p.display()));
        }
    }
    State::Done
}

fn relight_status(out: &Path) -> Result<Status> {
    let list = relight_frames(out)?;
    let plan: Option<Value> =
        std::fs::read(plan_path(out)).ok().and_then(|b| serde_json::from_slice(&b).ok());
    let shards = plan.as_ref().and_then(|p| p["shards"].as_u64()).unwrap_or(1) as usize;
    let finalised = out.join("summary.json").is_file() && !out.join("shards").exists();
    let done = list.iter().all(|(_, s)| *s == State::Done);
    Ok(status_of("relight", out, "frames", &list, shards, finalised && done))
}

/// Checks every frame and merges the shards' summaries into `summary.json`.
fn finalize_relight(out: &Path, as_json: bool) -> Result<()> {
    let st = relight_status(out)?;
    if !st.complete {
        let mut names = st.missing_units.clone();
        names.extend(st.corrupt_units.iter().map(|c| c["unit"].as_str().unwrap_or("").to_string()));
        let more =
            if names.len() > 8 { format!(" and {} more", names.len() - 8) } else { String::new() };
        names.truncate(8);
        bail!(
            "{}: cannot finalise: {} of {} frames missing, {} corrupt ({}{more}); run the \
             shards that own them again (`btf status {}` lists them)",
            out.display(),
            st.missing,
            st.total,
            st.corrupt,
            names.join(", "),
            out.display()
        );
    }
    // Every frame is in, so no shard of this job is writing: what a killed one left under
    // a temporary name goes.
    btf_core::fs::sweep_temps(out)?;
    let shards_dir = out.join("shards");
    if !shards_dir.exists() {
        if as_json {
            outln!("{}", serde_json::to_string_pretty(&st)?);
        } else {
            outln!("{}: already finalised ({} frames)", out.display(), st.total);
        }
        return Ok(());
    }
    let mut records = Vec::new();
    for i in 0..st.shards.len() {
        let p = relight_shard_summary(out, Shard { index: i, count: st.shards.len() });
        if let Some(v) =
            std::fs::read(&p).ok().and_then(|b| serde_json::from_slice::<Value>(&b).ok())
        {
            records.push(json!({ "shard": format!("{i}/{}", st.shards.len()), "summary": v }));
        }
    }
    let summary = merge_summaries(&records, st.total);
    let text = serde_json::to_string_pretty(&summary)?;
    btf_image::write::write_text(&out.join("summary.json"), &text)?;
    std::fs::remove_dir_all(&shards_dir)
        .with_context(|| format!("removing {}", shards_dir.display()))?;
    if as_json {
        outln!("{text}");
    } else {
        outln!(
            "finalised {}: {} frames from {} shards, {:.1} ms per frame → {}",
            out.display(),
            st.total,
            st.shards.len(),
            summary["frame_ms"].as_f64().unwrap_or(0.0),
            out.join("summary.json").display()
        );
    }
    Ok(())
}

/// `summary.json` of a sharded job: the single-process keys (`visibility_s`,
/// `weights_s_per_env`, `frame_ms`: means over the shards, frame-weighted for `frame_ms`)
/// and every shard's own summary (its last run).
fn merge_summaries(records: &[Value], frames: usize) -> Value {
    let s = |r: &Value, k: &str| r["summary"][k].as_f64().unwrap_or(0.0);
    let n = records.len().max(1) as f64;
    let rendered: f64 = records.iter().map(|r| s(r, "frames_rendered")).sum();
    let frame_ms = records.iter().map(|r| s(r, "frame_ms") * s(r, "frames_rendered")).sum::<f64>()
        / rendered.max(1.0);
    let first = records.first().map(|r| r["summary"].clone()).unwrap_or_default();
    json!({
        "frames": frames,
        "visibility_s": records.iter().map(|r| s(r, "visibility_s")).sum::<f64>() / n,
        "weights_s_per_env": records.iter().map(|r| s(r, "weights_s_per_env")).sum::<f64>() / n,
        "frame_ms": frame_ms,
        "frames_rendered": rendered as u64,
        "width": first["width"],
        "height": first["height"],
        "rotations": first["rotations"],
        "eigenweightsets": first["eigenweightsets"],
        "shards": records,
    })
}
