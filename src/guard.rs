//! The rules every command keeps about what it reads and writes, in one place so that a new
//! command keeps them by calling these (see `btf_core::fs` for the mechanics):
//!
//! - an output is never an input, never inside one and never holds one ([`refuse_overlap`]);
//! - an existing output is replaced only when the toolkit made it ([`check_file`],
//!   [`output_folder`], and `btf_core::store::StoreTxn` for stores);
//! - `--fresh` clears only what the command itself writes ([`output_folder`]);
//! - a store command without `--resume` leaves no partial behind when it fails
//!   ([`no_partial_on_error`]); one with `--resume` says where its partial is;
//! - standard output closed by the reader (`btf inspect | head`) ends the process quietly,
//!   as Unix tools do ([`outln!`]).

use anyhow::{Context, Result};
use btf_core::fs::OutputKind;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Prints a line on standard output; a closed pipe exits quietly (status 0, nothing on
/// stderr) and any other write error exits with status 1 and the error.
macro_rules! outln {
    () => { $crate::guard::out_line(format_args!("")) };
    ($($t:tt)*) => { $crate::guard::out_line(format_args!($($t)*)) };
}
pub(crate) use outln;

/// The body of [`outln!`].
pub fn out_line(args: std::fmt::Arguments) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.write_all(b"\n")) {
        exit_on_stdout_error(e);
    }
}

/// Flushes standard output, with [`outln!`]'s rules for a closed pipe.
pub fn flush_stdout() {
    if let Err(e) = std::io::stdout().lock().flush() {
        exit_on_stdout_error(e);
    }
}

fn exit_on_stdout_error(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    eprintln!("error: cannot write to standard output: {e}");
    std::process::exit(1);
}

/// Refuses outputs that are, contain or lie inside an input (and outputs that collide).
pub fn refuse_overlap(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    Ok(btf_core::fs::refuse_overlap(outputs, inputs)?)
}

/// [`refuse_overlap`] with the inputs of a scene (the scene file and every file it names).
pub fn refuse_scene_overlap(
    outputs: &[(&str, &Path)],
    scene_path: &Path,
    scene: &btf_render::Scene,
    more_inputs: &[(&str, &Path)],
) -> Result<()> {
    let named: Vec<(String, PathBuf)> = scene.input_paths();
    let mut inputs: Vec<(&str, &Path)> = vec![("scene", scene_path)];
    inputs.extend(named.iter().map(|(n, p)| (n.as_str(), p.as_path())));
    inputs.extend_from_slice(more_inputs);
    refuse_overlap(outputs, &inputs)
}

/// Refuses to replace an existing `path` that is not a file of `kind`.
pub fn check_file(path: &Path, kind: OutputKind) -> Result<()> {
    Ok(btf_core::fs::check_replaceable(path, kind)?)
}

/// The marker a command leaves in every output folder it fills: a folder is reused (and
/// cleared by `--fresh`) only when it is empty or holds this marker.
pub const FOLDER_MARKER: &str = ".btf-output.json";

/// Prepares an output folder: refuses a folder of somebody else's files, creates it, and
/// with `fresh` removes the entries `ours` recognises as this command's outputs (and
/// nothing else); then records the marker.
pub fn output_folder(
    dir: &Path,
    command: &str,
    fresh: bool,
    ours: &dyn Fn(&str) -> bool,
) -> Result<()> {
    btf_core::fs::check_replaceable(dir, OutputKind::Folder { marker: FOLDER_MARKER })?;
    if fresh {
        btf_core::fs::remove_listed(dir, &|p: &Path| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n != FOLDER_MARKER && ours(n))
        })?;
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let marker = serde_json::json!({ "written_by": format!("btf {command}") });
    btf_core::fs::write_atomic(&dir.join(FOLDER_MARKER), marker.to_string().as_bytes())?;
    Ok(())
}

/// [`output_folder`] for one of several writers of a folder (the shards of a job): the
/// marker is created once, by whoever comes first ([`btf_core::fs::write_new`]), and never
/// rewritten; nothing is cleared.
pub fn shared_output_folder(dir: &Path, command: &str) -> Result<()> {
    btf_core::fs::check_replaceable(dir, OutputKind::Folder { marker: FOLDER_MARKER })?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let marker = serde_json::json!({ "written_by": format!("btf {command}") });
    btf_core::fs::write_new(&dir.join(FOLDER_MARKER), marker.to_string().as_bytes())?;
    Ok(())
}

/// What the demos and reports write into their folders: files of the kinds they make and
/// the folders they fill. `--fresh` removes these and nothing else.
pub fn report_output(name: &str) -> bool {
    const EXT: [&str; 10] =
        ["png", "exr", "md", "json", "csv", "obj", "btf", "eig", "eigen", "partial"];
    const DIRS: [&str; 6] = ["sweep", "relight", "frames", "cache", "eigen", "render-sweep"];
    let ext = Path::new(name).extension().and_then(|e| e.to_str()).unwrap_or("");
    EXT.contains(&ext) || DIRS.contains(&name) || btf_core::fs::is_temp_name(name)
}

/// Runs `f`, which writes a store at `out` with no `--resume`; when it fails, the partial
/// store it began (`OUT.partial`) is removed, so a refusal leaves nothing behind.
pub fn no_partial_on_error<T>(out: &Path, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let r = f();
    if r.is_err() {
        let p = partial_of(out);
        if p.is_dir() && btf_core::fs::is_toolkit_store(&p) {
            let _ = std::fs::remove_dir_all(&p);
        }
    }
    r
}

/// Runs `f`, which writes a store at `out` with `--resume` available; when it fails and a
/// partial store with finished work is left, the error says so. A partial that holds no
/// chunk or side file yet (this run began it and was refused before its first slot) is
/// removed: there is nothing to resume, and a refusal leaves nothing behind. A partial that
/// was there before the run is another job's and stays as it was.
pub fn resumable<T>(out: &Path, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let existed = partial_of(out).exists();
    f().map_err(|e| {
        let p = partial_of(out);
        if !existed && p.is_dir() && btf_core::fs::is_toolkit_store(&p) && !holds_work(&p) {
            let _ = std::fs::remove_dir_all(&p);
        }
        if p.is_dir() {
            e.context(format!(
                "the work done so far is kept in {}; run the same command with --resume to \
                 continue, or without it to start over",
                p.display()
            ))
        } else {
            e
        }
    })
}

/// Whether a store folder holds finished work: any file but the metadata documents
/// (`zarr.json`) and temporaries, i.e. a chunk or a side file such as a registration.
fn holds_work(store: &Path) -> bool {
    let mut stack = vec![store.to_owned()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if e.path().is_dir() {
                stack.push(e.path());
            } else if name != "zarr.json" && !btf_core::fs::is_temp_name(&name) {
                return true;
            }
        }
    }
    false
}

/// `NAME.partial` beside a store path.
pub fn partial_of(out: &Path) -> PathBuf {
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    out.with_file_name(format!("{name}.partial"))
}
