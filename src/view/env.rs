//! The environments `btf view` can switch between, their rotation, and the one place where
//! the viewer hands them to the renderer's environment light (Sattler et al. 2003 §5: a
//! rotation is `e` vector additions through the eigenweightsets of eq. 13, a new
//! environment is one gather of eq. 10 over the cached visibility; neither recomputes
//! visibility).
//!
//! A file that is missing or unreadable is an error shown in the panel, never a crash; the
//! viewer keeps drawing with the last environment that worked.

use btf_image::EnvMap;
use btf_render::{Gpu, Renderer};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The environment list and what happened to the last request.
#[derive(Debug, Default)]
pub struct Environments {
    /// Files offered in the panel (`--env`, in order).
    pub files: Vec<PathBuf>,
    /// Index of the environment in use.
    pub current: Option<usize>,
    /// Index of the last one asked for (in use, or failed).
    pub selected: Option<usize>,
    /// Rotation about the up axis, degrees.
    pub rotation_deg: f32,
    /// Last error (shown in the panel), if any.
    pub error: Option<String>,
    /// Whether the renderer lights the garment with the environment (false: the scene has
    /// no environment light, or this renderer has none yet).
    pub lighting: bool,
    /// Milliseconds of the last environment load (file → map).
    pub load_ms: f64,
}

impl Environments {
    /// The list from `--env` files; nothing is loaded yet.
    pub fn new(files: Vec<PathBuf>) -> Environments {
        Environments { files, ..Default::default() }
    }

    /// Display name of file `i`.
    pub fn name(&self, i: usize) -> String {
        self.files[i].file_name().map_or_else(
            || self.files[i].display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    }

    /// The index after the current one (wrapping), if there are files.
    pub fn next_index(&self) -> Option<usize> {
        if self.files.is_empty() {
            return None;
        }
        Some(self.selected.map_or(0, |c| (c + 1) % self.files.len()))
    }
}

/// Loads environment `path` (an error names the file) and hands it to the renderer. Returns
/// whether the renderer lights the garment with it.
pub fn swap(renderer: &mut Renderer, gpu: &Gpu, path: &Path) -> Result<bool, String> {
    let env = EnvMap::load(path).map_err(|e| e.to_string())?;
    apply_environment(renderer, gpu, path, &env)
}

/// Turns the renderer's environment to `rotation_deg`. Returns whether it is lit by one.
pub fn rotate(renderer: &mut Renderer, gpu: &Gpu, rotation_deg: f32) -> Result<bool, String> {
    apply_rotation(renderer, gpu, rotation_deg)
}

/// Times `f` in milliseconds.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, t.elapsed().as_secs_f64() * 1e3)
}

// The two hooks into the renderer's environment light: a scene without one is not lit by
// an environment (the file is still loaded and checked above, so a bad file is reported);
// with one, a swap is one gather over the cached visibility and a rotation goes through the
// eigenweightsets when the scene asks for them.
fn apply_environment(
    renderer: &mut Renderer,
    _gpu: &Gpu,
    path: &Path,
    env: &EnvMap,
) -> Result<bool, String> {
    if renderer.environment().is_none() {
        return Ok(false);
    }
    renderer.set_environment(env).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(true)
}

fn apply_rotation(renderer: &mut Renderer, _gpu: &Gpu, rotation_deg: f32) -> Result<bool, String> {
    if renderer.environment().is_none() {
        return Ok(false);
    }
    renderer.set_environment_rotation(rotation_deg as f64).map_err(|e| e.to_string())?;
    Ok(true)
}
