//! The `[[yarns]]` of a scene for the commands that render scenes (`btf render`,
//! `btf relight`, `btf view`): built once on the CPU by `yarn_render::scene` (chart on the
//! carrier mesh's UVs, Chen skeleton, packed fibers), then drawn by a
//! `yarn_render::scene::YarnOverlay` in every `btf_render::Renderer` made for the scene —
//! same colour and depth targets, same camera, same lights (the module documentation of
//! `yarn_render::scene::overlay` gives the composition and its radiometry). Glue only.

use anyhow::{Context, Result};
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use std::path::{Path, PathBuf};
use yarn_render::scene::{SceneYarn, YarnOverlay, bounds_f32};

/// Where `btf render` and `btf view` cache the yarns' bakes (fiber effects, strip textures):
/// `$BTF_YARN_CACHE`, else `btf-yarn-cache` in the system's temporary folder. The files are
/// named by a hash of everything they depend on and checked on load, so the folder can be
/// shared and deleted at any time.
pub fn default_cache() -> PathBuf {
    match std::env::var_os("BTF_YARN_CACHE") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => std::env::temp_dir().join("btf-yarn-cache"),
    }
}

/// A scene's yarns, built.
pub struct SceneYarns {
    yarns: Vec<SceneYarn>,
    cache: Option<PathBuf>,
}

impl SceneYarns {
    /// Builds the `[[yarns]]` of `scene` (loaded from `path`); the effects' bakes go to
    /// `cache` when given. Refusals name the key (`yarns[0].chart`, …).
    pub fn build(scene: &Scene, path: &Path, cache: Option<PathBuf>) -> Result<SceneYarns> {
        let yarns = yarn_render::scene::build(scene, path)?;
        Ok(SceneYarns { yarns, cache })
    }

    /// `options` with the yarns' bounds, so the camera's depth range covers them.
    pub fn options(&self, options: RenderOptions) -> RenderOptions {
        RenderOptions { extra_bounds: bounds_f32(&self.yarns), ..options }
    }

    /// An empty set (a scene without `[[yarns]]`, or one whose yarns failed to build).
    pub fn none() -> SceneYarns {
        SceneYarns { yarns: Vec::new(), cache: None }
    }

    /// A renderer of `scene` with the yarns drawn after its BTF pass.
    pub fn renderer(&self, gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Renderer> {
        let mut r = Renderer::new(gpu, scene, self.options(options))?;
        if !self.yarns.is_empty() {
            let overlay = YarnOverlay::new(gpu, scene, &self.yarns, self.cache.as_deref())
                .context("preparing the [[yarns]] fiber renderer")?;
            r.add_overlay(Box::new(overlay));
        }
        Ok(r)
    }
}
