//! The environments `btf view` can switch between, their rotation, and the one place where
//! the viewer hands them to the renderer's environment light (Sattler et al. 2003 §5: a
//! rotation is `e` vector additions through the eigenweightsets of eq. 13, a new
//! environment is one gather of eq. 10 over the cached visibility; neither recomputes
//! visibility).
//!
//! The rotation is absolute, the scene's `rotation_deg` at the start (the turntable adds its
//! turn to it). Each environment is lit at an exposure of its own (auto-exposure, on unless
//! `--env-exposure fixed`): the factor `f` of `[S03 eq. 11]` that gives a horizontal surface
//! the same irradiance `E_h = ∫ L max(0, ω_z) dω` as the scene's own environment at the
//! scene's `f`, so that a studio map a thousand times dimmer than the sky does not turn the
//! garment black; with none in the scene, `E_h = 1`.
//!
//! A file that is missing or unreadable is an error shown in the panel, never a crash; the
//! viewer keeps drawing with the last environment that worked.

use btf_image::EnvMap;
use btf_render::{Gpu, Renderer, Scene};
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
    /// Exposure `f` per environment (auto-exposure); `None` keeps the scene's `f`.
    pub auto_exposure: bool,
    /// The horizontal irradiance every environment is scaled to (auto-exposure).
    pub target_irradiance: Option<f64>,
    /// The environment light's exposure `f` in use.
    pub light_exposure: f32,
}

impl Environments {
    /// The list from `--env` files, starting at the rotation and exposure of `scene`'s
    /// environment light; nothing is loaded yet.
    pub fn new(files: Vec<PathBuf>, scene: &Scene, auto_exposure: bool) -> Environments {
        let (rotation_deg, light_exposure) = scene
            .environment()
            .map_or((0.0, 1.0), |(_, e)| (e.rotation_deg.rem_euclid(360.0) as f32, e.exposure));
        Environments {
            files,
            rotation_deg,
            light_exposure,
            auto_exposure,
            lighting: scene.environment().is_some(),
            ..Default::default()
        }
    }

    /// The exposure `f` that gives `map` the target horizontal irradiance (the scene
    /// environment's `E_h · f`, loaded once from its file; 1 without one), or `None` when
    /// auto-exposure is off or the map is black above the horizon.
    pub fn exposure_for(&mut self, scene: &Scene, map: &EnvMap) -> Option<f32> {
        if !self.auto_exposure {
            return None;
        }
        let target = *self.target_irradiance.get_or_insert_with(|| {
            scene
                .environment()
                .and_then(|(_, e)| {
                    let own = EnvMap::load(&e.path).ok()?;
                    Some(e.exposure as f64 / own.unit_irradiance_exposure())
                })
                .unwrap_or(1.0)
        });
        exposure_giving(target, map)
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

/// The exposure `f` that gives a horizontal surface under `map` the irradiance `target`
/// (`None` for a map black above the horizon).
pub fn exposure_giving(target: f64, map: &EnvMap) -> Option<f32> {
    let e_h = horizontal_irradiance(map);
    (e_h > 0.0 && target > 0.0).then(|| (target / e_h) as f32)
}

/// `E_h`, the mean over channels of the irradiance of a horizontal surface (normal `+z`).
pub fn horizontal_irradiance(map: &EnvMap) -> f64 {
    let e = map.irradiance([0.0, 0.0, 1.0]);
    (e[0] + e[1] + e[2]) / 3.0
}

/// Loads environment `path` (an error names the file), hands it to the renderer and, when
/// `exposure` gives one for it, sets its exposure `f`. Returns whether the renderer lights
/// the garment with it and the `f` in use.
pub fn swap(
    renderer: &mut Renderer,
    gpu: &Gpu,
    path: &Path,
    exposure: impl FnOnce(&EnvMap) -> Option<f32>,
) -> Result<(bool, Option<f32>), String> {
    let env = EnvMap::load(path).map_err(|e| e.to_string())?;
    let lit = apply_environment(renderer, gpu, path, &env)?;
    let f = exposure(&env);
    if let Some(f) = f.filter(|_| lit) {
        renderer.set_environment_exposure(f).map_err(|e| e.to_string())?;
    }
    Ok((lit, f))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant sky of radiance `L` gives a horizontal surface `E_h = π L`, so the
    /// exposure that matches a sky of `L₀` at `f₀` is `f₀ L₀ / L₁` — a map 1000× dimmer is
    /// lit 1000× brighter — up to the map's pixel quadrature (≤ 1e-3 at 256 × 128).
    #[test]
    fn auto_exposure_matches_horizontal_irradiance() {
        let sky = EnvMap::constant(256, [2.0, 2.0, 2.0]).unwrap();
        let studio = EnvMap::constant(256, [0.002, 0.002, 0.002]).unwrap();
        let e_sky = horizontal_irradiance(&sky);
        assert!((e_sky / (2.0 * std::f64::consts::PI) - 1.0).abs() < 1e-3, "{e_sky}");
        let f0 = 0.5;
        let f = exposure_giving(f0 * e_sky, &studio).unwrap() as f64;
        assert!((f / (f0 * 1000.0) - 1.0).abs() < 1e-6, "{f}");
        let black = EnvMap::constant(256, [0.0; 3]).unwrap();
        assert_eq!(exposure_giving(1.0, &black), None);
    }
}
