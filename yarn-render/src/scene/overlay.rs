//! [`YarnOverlay`]: a scene's `[[yarns]]` drawn by the fiber renderer of [W19] (§5: fibers
//! generated from the control points every frame, LoD of [W19 eq. 4], the fiber BCSDF of
//! [W19 eq. 5–6]) — or, with `method = "strips"`, by the yarn strips of [H25] (textures
//! baked once per yarn and colour, cached with the fiber bakes), or, with
//! `method = "lumislice"`, by the lumislices of [C03 §5] (the table computed once per yarn
//! and colour, cached likewise; drawn after the fibers and strips and blended over them, in
//! 4× MSAA targets) — into btf-render's own colour and depth targets, after its BTF pass,
//! with its camera matrix and the scene's lights. The environment reaches fibers and strips
//! as its fit by 16 SRBFs with the `I_M` table ([H25 eq. 14–17], `yarn_precompute::srbf`),
//! fitted once per map and rotated about `+z` with the environment; each SRBF has a tube
//! (strip) shadow map. Lumislices take the point and directional lights only ([C03] has no
//! environment light).
//!
//! **How the two renderers meet — choice (a), drawing into shared targets.** btf-render
//! keeps its depth buffer when an overlay is present and hands the overlay its colour
//! target (multisampled under MSAA, with the resolve target), depth buffer and camera
//! ([`btf_render::renderer::Overlay`]); [`crate::FiberRenderer::encode_into`] loads both and
//! depth-tests its strips against the meshes with the very matrix the meshes were drawn
//! with ([`crate::FiberCamera::Matrix`]). Both use `Depth32Float`, `Less`, depth in
//! `[0, 1]`, the same colour format (`Rgba32Float`, `Rgba16Float` under MSAA) and sample
//! count, so hiding works both ways per sample, and MSAA edges between yarn and mesh
//! resolve together. The alternative (b) — two images with depth, composited per pixel —
//! would need a second colour and depth target, a resolve of depth (not defined for MSAA
//! depth in WebGPU) and would lose the per-sample hiding at edges; (a) costs one
//! `StoreOp::Store` of the depth buffer.
//!
//! **Radiometry.** Both write linear radiance; the exposure is applied once, when the frame
//! is written. Directional lights give perpendicular irradiance `E` and point lights
//! intensity `I` in both renderers (DESIGN §3). The environment light reaches the yarns
//! by its SRBF lobes (above), each shadowed by the other yarns through its tube shadow map
//! and by the yarn's own fibers through the self-shadow volume — [W19]'s constant ambient
//! term ([W19 eq. 7–8] with AO, the uniform radiance of the same power) measured 2.1× the
//! reference's mean radiance on a stockinette patch under a constant sky, the lobes 1.17×
//! (`tests/gpu/lights.rs`). The lobes have no visibility of the meshes: yarns and meshes
//! do not shadow each other (each casts shadows on itself only).

use super::SceneYarn;
use crate::{
    AoMode, FiberCamera, FiberEffects, FiberLight, FiberRenderer, FiberSettings, Result,
    StripRenderer, StripSettings,
};
use btf_render::Gpu;
use btf_render::camera::CameraSetup;
use btf_render::renderer::{Overlay, OverlayEnvironment, OverlayTargets, OverlayView};
use btf_render::scene::{Light, Scene, YarnAo, YarnMethod, YarnsDesc};
use std::path::Path;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn_precompute::StripBakeSettings;

/// The fiber renderer's camera for btf-render's: the same world → clip matrix.
pub fn fiber_camera(cam: &CameraSetup) -> FiberCamera {
    let m = &cam.view_proj;
    let view_proj = std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)] as f64));
    FiberCamera::Matrix {
        view_proj,
        eye: [cam.eye.x, cam.eye.y, cam.eye.z].map(f64::from),
        ortho_to_camera: cam.ortho_to_camera.map(|d| [d.x, d.y, d.z].map(f64::from)),
    }
}

/// The scene's point and directional lights (the environment goes by SRBFs).
pub fn fiber_lights(lights: &[Light]) -> Vec<FiberLight> {
    let f = |v: &[f32; 3]| v.map(f64::from);
    lights
        .iter()
        .filter_map(|l| match l {
            Light::Directional { direction, irradiance, .. } => {
                Some(FiberLight::Directional { to_light: f(direction), irradiance: f(irradiance) })
            }
            Light::Point { position, intensity, .. } => {
                Some(FiberLight::Point { position: f(position), intensity: f(intensity) })
            }
            Light::Environment(_) => None,
        })
        .collect()
}

/// The constant ambient radiance of the environment light's power ([W19 eq. 7–8]): what the
/// fibers fall back to if the SRBF environment is removed (see the module documentation).
pub fn ambient(env: Option<OverlayEnvironment>) -> [f32; 3] {
    env.map_or([0.0; 3], |e| e.mean_radiance().map(|x| x as f32))
}

/// The fiber settings of one `[[yarns]]` entry in `scene` (MSAA of the scene, the entry's
/// LoD threshold, shadows and AO).
pub fn settings(scene: &Scene, d: &YarnsDesc) -> FiberSettings {
    let effects = FiberEffects {
        self_shadow: d.shadows,
        yarn_shadows: d.shadows,
        fiber_shadows: d.fiber_shadows,
        ao: match d.ao {
            YarnAo::Off => AoMode::Off,
            YarnAo::Cubic => AoMode::Cubic,
            YarnAo::Texture => AoMode::Texture,
        },
        ..FiberEffects::default()
    };
    FiberSettings {
        lod_px: d.lod_px,
        msaa: scene.effects.msaa,
        hairs: d.hairs,
        effects,
        ..FiberSettings::default()
    }
}

/// The fiber BCSDF of scene yarns: Khungurn's R + TT lobes with a diffuse part ([W19 eq. 6]).
pub fn scene_bcsdf() -> Result<FiberBcsdf> {
    Ok(FiberBcsdf::khungurn(&KhungurnParams::default())?)
}

/// How one `[[yarns]]` entry is drawn (`method`).
pub enum YarnDrawer {
    /// Procedural fibers [W19].
    Fibers(FiberRenderer),
    /// Fiber-textured strips [H25] (`method = "strips"`).
    Strips(StripRenderer),
    /// Lumislices [C03 §5] (`method = "lumislice"`), drawn after every opaque drawer.
    Lumislice(crate::LumisliceRenderer),
}

/// The yarn renderers of a scene's `[[yarns]]`, drawn after its BTF pass.
pub struct YarnOverlay {
    renderers: Vec<YarnDrawer>,
    bcsdf: FiberBcsdf,
    /// The yarns' environment (fibers and strips): the map it was fitted to (path,
    /// revision), its SRBF fit and I_M table, refitted when the map changes.
    srbf: Option<(std::path::PathBuf, u64, yarn_precompute::SrbfFit, yarn_precompute::ImTable)>,
    /// The environment state (revision, rotation and exposure bits) the renderers were last
    /// given; `None` before the first frame. The lobes are uploaded only when it changes.
    env_key: Option<Option<(u64, u64, u32)>>,
}

/// SRBFs of the yarns' environment fit in scenes ([H25 §6]: 16).
pub const SCENE_SRBFS: usize = 16;

impl YarnOverlay {
    /// Uploads `yarns` (built by [`super::build`] from `scene`) and compiles their passes;
    /// the effects' bakes are cached in `cache_dir` when given.
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        yarns: &[SceneYarn],
        cache_dir: Option<&Path>,
    ) -> Result<Self> {
        let bcsdf = scene_bcsdf()?;
        let renderers = yarns
            .iter()
            .map(|y| {
                let d = &scene.yarns[y.index];
                if d.method == YarnMethod::Lumislice {
                    if scene.effects.msaa != crate::lumislice::SAMPLES {
                        return Err(crate::Error::Invalid(format!(
                            "yarns[{}].method = \"lumislice\" blends into 4× MSAA targets; the \
                             scene has effects.msaa = {}",
                            y.index, scene.effects.msaa
                        )));
                    }
                    let color = crate::lumislice::table_albedo(&y.set);
                    let table = yarn_precompute::Lumislice::for_params(
                        &y.params,
                        color,
                        &yarn_precompute::LumisliceSettings { seed: d.seed, ..Default::default() },
                        cache_dir,
                        &|_| {},
                    )
                    .map_err(|e| {
                        crate::Error::Invalid(format!("yarns[{}]: lumislice: {e}", y.index))
                    })?;
                    let s =
                        crate::LumisliceRenderSettings { shadows: d.shadows, ..Default::default() };
                    let r = crate::LumisliceRenderer::new(gpu, &y.packed, &[table], s)?;
                    return Ok(YarnDrawer::Lumislice(r));
                }
                if d.method == YarnMethod::Strips {
                    let bake = StripBakeSettings { seed: d.seed, ..Default::default() };
                    let bakes = crate::strips::bakes_for(
                        &y.set,
                        std::slice::from_ref(&y.params),
                        &bcsdf,
                        &bake,
                        cache_dir,
                        &|_| {},
                    )?;
                    let s = StripSettings {
                        msaa: scene.effects.msaa,
                        shadows: d.shadows,
                        ..StripSettings::default()
                    };
                    let mut r = StripRenderer::new(gpu, &y.packed, &bakes, &bcsdf, s)?;
                    if d.hairs {
                        let fly =
                            crate::strips::flyaways_for(std::slice::from_ref(&y.params), d.seed)?;
                        r.set_flyaways(gpu, &fly)?;
                    }
                    return Ok(YarnDrawer::Strips(r));
                }
                let bake = yarn_precompute::BakeSettings { seed: d.seed, ..Default::default() };
                Ok(YarnDrawer::Fibers(FiberRenderer::with_bake(
                    gpu,
                    &y.packed,
                    &bcsdf,
                    settings(scene, d),
                    &bake,
                    cache_dir,
                )?))
            })
            .collect::<Result<_>>()?;
        Ok(YarnOverlay { renderers, bcsdf, srbf: None, env_key: None })
    }

    /// The yarns' SRBF environment for this frame: fitted once per map (path and
    /// revision), rotated about `+z` and scaled by the exposure per frame.
    fn environment(&mut self, view: &OverlayView<'_>) -> Result<Option<yarn_precompute::SrbfFit>> {
        let (Some(oe), Some(desc)) = (
            view.environment,
            view.scene.lights.iter().find_map(|l| match l {
                Light::Environment(e) => Some(e),
                _ => None,
            }),
        ) else {
            return Ok(None);
        };
        let fresh =
            !matches!(&self.srbf, Some((p, r, _, _)) if *p == desc.path && *r == oe.revision);
        if fresh {
            let map = btf_image::EnvMap::load(&desc.path).map_err(|e| {
                crate::Error::Invalid(format!(
                    "[[yarns]]: environment {}: {e}",
                    desc.path.display()
                ))
            })?;
            let fit = yarn_precompute::SrbfFit::fit(&map, SCENE_SRBFS)
                .map_err(|e| crate::Error::Invalid(format!("[[yarns]]: SRBF fit: {e}")))?;
            let table = yarn_precompute::ImTable::build(&self.bcsdf, fit.lambda)
                .map_err(|e| crate::Error::Invalid(format!("[[yarns]]: I_M table: {e}")))?;
            self.srbf = Some((desc.path.clone(), oe.revision, fit, table));
        }
        let Some((_, _, fit, _)) = &self.srbf else { return Ok(None) };
        let mut f = fit.rotated_z(oe.rotation_deg);
        let x = oe.exposure as f64;
        f.weights.iter_mut().for_each(|w| *w = w.map(|v| v * x));
        Ok(Some(f))
    }

    /// The renderers, in `[[yarns]]` order.
    pub fn renderers(&self) -> &[YarnDrawer] {
        &self.renderers
    }
}

/// A yarn-render error as btf-render reports it.
fn to_render(e: crate::Error) -> btf_render::Error {
    match e {
        crate::Error::Render(e) => e,
        crate::Error::Gpu(m) => btf_render::Error::Gpu(m),
        crate::Error::Limit(m) => btf_render::Error::Limit(m),
        other => btf_render::Error::Invalid(format!("[[yarns]]: {other}")),
    }
}

impl Overlay for YarnOverlay {
    fn name(&self) -> &str {
        "yarns"
    }

    fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        targets: &OverlayTargets<'_>,
        view: &OverlayView<'_>,
    ) -> btf_render::Result<()> {
        let cam = fiber_camera(view.camera);
        let lights = fiber_lights(&view.scene.lights);
        let ambient = ambient(view.environment);
        // The lobes (fitted once per map, rotated and exposed per change) go to the
        // renderers only when the environment changed since the last frame.
        let key =
            view.environment.map(|e| (e.revision, e.rotation_deg.to_bits(), e.exposure.to_bits()));
        let lobed = self.renderers.iter().any(|r| !matches!(r, YarnDrawer::Lumislice(_)));
        let fresh = lobed && self.env_key != Some(key);
        let env = if fresh { self.environment(view).map_err(to_render)? } else { None };
        // The table stays where it was built (it changes only with the map).
        let table = self.srbf.as_ref().map(|s| &s.3);
        // Opaque drawers first, then the blended lumislices over them.
        let (opaque, blended): (Vec<_>, Vec<_>) =
            self.renderers.iter_mut().partition(|r| !matches!(r, YarnDrawer::Lumislice(_)));
        for r in opaque.into_iter().chain(blended) {
            let t = (targets.color, targets.resolve, targets.depth);
            match r {
                // The environment through SRBFs with the lobes' tube shadow maps; the ambient
                // term stays for when there is none.
                YarnDrawer::Fibers(r) => {
                    r.set_ambient(ambient);
                    let set = if fresh {
                        r.set_environment(gpu, env.as_ref().zip(table))
                    } else {
                        Ok(())
                    };
                    set.and_then(|_| r.encode_into(gpu, encoder, t, targets.size, &cam, &lights))
                }
                YarnDrawer::Strips(r) => {
                    // The environment through SRBFs ([H25 eq. 17]), not the ambient term.
                    let set = if fresh {
                        r.set_environment(gpu, env.as_ref().zip(table))
                    } else {
                        Ok(())
                    };
                    set.and_then(|_| r.encode_into(gpu, encoder, t, targets.size, &cam, &lights))
                }
                // Point and directional lights only: [C03] has no environment light.
                YarnDrawer::Lumislice(r) => {
                    r.encode_into(gpu, encoder, t, targets.size, &cam, &lights)
                }
            }
            .map_err(to_render)?;
        }
        // Kept only once every renderer took it (a failed upload is retried next frame).
        if fresh {
            self.env_key = Some(key);
        }
        Ok(())
    }
}
