//! What `btf view` shows and how a change reaches the screen, without any window: the scene
//! as loaded, the interactive camera, lights, effects, fabric and environment, and the
//! renderer built from them. Each interaction recomputes only what depends on it:
//!
//! | change | work before the frame |
//! |---|---|
//! | camera orbit / zoom / pan | none (a new frame uniform) |
//! | light drag | the shadow pass, when the scene has one |
//! | environment rotation | eigenweightset reconstruction (eq. 13) |
//! | environment swap | one gather (eq. 10) over the cached visibility |
//! | fabric, evaluation, blending, components, shadow technique | a new renderer |
//! | exposure | none (applied when the frame is shown) |
//!
//! A frame is encoded straight into the texture the window samples ([`Shown`],
//! `Renderer::encode`): nothing is read back to the CPU to show it; screenshots and the
//! turntable read that texture back when they save it. The window (`app.rs`), the
//! turntable export and the latency benchmark all drive this.

use super::camera::{self, Orbit};
use super::env::{self, Environments};
use anyhow::Result;
use btf_core::InterpMode;
use btf_core::eigen::EigenStore;
use btf_render::scene::{Effects, Evaluation, Light, Shadows};
use btf_render::{Frame, Gpu, RenderOptions, Renderer, Scene, Stats};
use std::path::{Path, PathBuf};

/// What a frame was rendered for (the latency figures are kept per kind).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Change {
    /// First frame.
    Start,
    /// Orbit, zoom, pan.
    Camera,
    /// A light moved.
    Light,
    /// The environment turned.
    EnvRotation,
    /// Another environment.
    EnvSwap,
    /// Fabric or effects: a new renderer.
    Rebuild,
}

impl Change {
    /// Name in the panel and the benchmark output.
    pub fn name(self) -> &'static str {
        match self {
            Change::Start => "start",
            Change::Camera => "camera move",
            Change::Light => "light move",
            Change::EnvRotation => "environment rotation",
            Change::EnvSwap => "environment swap",
            Change::Rebuild => "rebuild (fabric/effects)",
        }
    }
}

/// Cost of the last interaction, milliseconds.
#[derive(Debug, Clone, Copy)]
pub struct Latency {
    /// What changed.
    pub change: Change,
    /// Work before rendering (renderer updates, rebuilds, environment weights).
    pub update_ms: f64,
    /// Rendering the frame into the shown texture, until the GPU has finished it.
    pub render_ms: f64,
}

impl Latency {
    /// Change to frame ready.
    pub fn total_ms(&self) -> f64 {
        self.update_ms + self.render_ms
    }
}

/// The texture the renderer draws the shown frame into (linear HDR, the renderer's target
/// format), sampled by the window's present pass, and the frame's pass times.
pub struct Shown {
    /// `width × height`, `Renderer::target_format`.
    pub texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
    /// Passes and times of the frame in it.
    pub stats: Stats,
    /// Changes whenever the texture is made anew (the present pass rebinds then).
    pub generation: u64,
}

impl Shown {
    /// `slot`'s texture when it fits `renderer`'s frames, else a new one.
    fn ensure<'a>(slot: &'a mut Option<Shown>, gpu: &Gpu, renderer: &Renderer) -> &'a mut Shown {
        let (size, format) = (renderer.size(), renderer.target_format());
        let fits = slot.as_ref().is_some_and(|s| {
            (s.texture.width(), s.texture.height()) == size && s.texture.format() == format
        });
        if !fits {
            let generation = slot.as_ref().map_or(0, |s| s.generation + 1);
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("shown frame"),
                size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            *slot = Some(Shown { texture, view, stats: Stats::default(), generation });
        }
        slot.as_mut().expect("just made")
    }
}

/// Encodes a frame of `renderer` into the shown texture, submits it and reads its pass
/// times (which waits for the GPU); the frame itself stays on the GPU.
fn draw_frame(gpu: &Gpu, renderer: &mut Renderer, slot: &mut Option<Shown>) -> Result<()> {
    let t = std::time::Instant::now();
    let shown = Shown::ensure(slot, gpu, renderer);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    renderer.encode(gpu, &mut encoder, &shown.view)?;
    let commands = gpu.scoped("encoding the frame", || encoder.finish())?;
    gpu.queue.submit([commands]);
    shown.stats = renderer.last_stats(gpu)?;
    shown.stats.frame_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(())
}

/// The viewer's state.
pub struct Viewer {
    base: Scene,
    /// The interactive camera.
    pub orbit: Orbit,
    /// Current lights.
    pub lights: Vec<Light>,
    /// Current effects.
    pub effects: Effects,
    /// Linear exposure applied when showing and saving frames.
    pub exposure: f32,
    /// 0: materials as the scene assigns them; `k ≥ 1`: scene material `k − 1` everywhere.
    pub fabric: usize,
    /// Environments and their rotation.
    pub env: Environments,
    renderer: Option<Renderer>,
    /// The last frame rendered, on the GPU.
    pub shown: Option<Shown>,
    /// Problems to show in the panel (bad files, refused settings).
    pub errors: Vec<String>,
    /// The last interaction's cost.
    pub last: Option<Latency>,
    /// Frames rendered so far.
    pub frames: u64,
    /// Fewest PCA components any of the scene's stores holds (`None`: unreadable).
    pub stored_components: Option<usize>,
    pending: Option<Change>,
    pending_env: Option<usize>,
    needs_rebuild: bool,
    applied: (Effects, usize),
    /// The scene's `[[yarns]]`, built once and drawn by every renderer made.
    yarns: crate::scene_yarns::SceneYarns,
}

impl Viewer {
    /// Builds the renderer for `scene`; a failure is kept as a panel error, not returned.
    pub fn new(
        gpu: &Gpu,
        scene: Scene,
        scene_path: &std::path::Path,
        env_files: Vec<PathBuf>,
        auto_exposure: bool,
    ) -> Viewer {
        let mut errors = Vec::new();
        let yarns = crate::scene_yarns::SceneYarns::build(
            &scene,
            scene_path,
            Some(crate::scene_yarns::default_cache()),
        )
        .unwrap_or_else(|e| {
            errors.push(format!("{e:#}"));
            crate::scene_yarns::SceneYarns::none()
        });
        let mut v = Viewer {
            orbit: Orbit::new(&scene.camera),
            lights: scene.lights.clone(),
            effects: scene.effects.clone(),
            exposure: scene.output.exposure,
            fabric: 0,
            env: Environments::new(env_files, &scene, auto_exposure),
            renderer: None,
            shown: None,
            errors,
            last: None,
            frames: 0,
            stored_components: scene
                .materials
                .iter()
                .map(|m| EigenStore::open(&m.store).ok().map(|s| s.meta().components))
                .min()
                .flatten(),
            pending: Some(Change::Start),
            pending_env: None,
            needs_rebuild: false,
            applied: (scene.effects.clone(), 0),
            base: scene,
            yarns,
        };
        v.rebuild(gpu);
        v.pending_env = v.env.next_index();
        v
    }

    /// The scene as it would be written now (camera, lights, effects, fabric applied).
    pub fn scene_now(&self) -> Scene {
        let mut s = self.base.clone();
        s.camera = self.orbit.camera.clone();
        s.lights = self.lights.clone();
        s.effects = self.effects.clone();
        if self.fabric > 0 {
            let mut m = s.materials[self.fabric - 1].clone();
            m.name = None;
            s.materials = vec![m];
        }
        s
    }

    /// Names of the fabrics to choose from (index 0 = as in the scene).
    pub fn fabric_names(&self) -> Vec<String> {
        let mut out = vec!["as in the scene".to_string()];
        out.extend(self.base.materials.iter().map(|m| {
            let file = m.store.file_name().map(|n| n.to_string_lossy().into_owned());
            match (&m.name, file) {
                (Some(n), Some(f)) => format!("{n} ({f})"),
                (None, Some(f)) => f,
                (n, None) => n.clone().unwrap_or_default(),
            }
        }));
        out
    }

    /// Image size of the frames.
    pub fn size(&self) -> (u32, u32) {
        (self.base.output.width, self.base.output.height)
    }

    /// Renders the next frames at `width × height` (the window's frame area): the camera's
    /// aspect follows; nothing else is recomputed. A size the device refuses keeps the old
    /// one and goes to the panel's errors.
    pub fn set_size(&mut self, gpu: &Gpu, width: u32, height: u32) {
        let (width, height) = (width.max(1), height.max(1));
        if (width, height) == self.size() {
            return;
        }
        if let Some(r) = self.renderer.as_mut()
            && let Err(e) = r.set_size(gpu, width, height)
        {
            self.errors.push(format!("frame size {width} × {height}: {e}"));
            return;
        }
        (self.base.output.width, self.base.output.height) = (width, height);
        self.mark(Change::Camera);
    }

    /// True when a frame is waiting to be rendered.
    pub fn needs_frame(&self) -> bool {
        self.pending.is_some()
    }

    fn mark(&mut self, change: Change) {
        // A rebuild or an environment change dominates a camera move in the same frame.
        self.pending = Some(match self.pending {
            Some(Change::Start) => Change::Start,
            Some(p) if p != Change::Camera => p,
            _ => change,
        });
    }

    /// Rebuilds the renderer from [`Viewer::scene_now`]; on failure keeps the old one and
    /// the settings it was built with.
    fn rebuild(&mut self, gpu: &Gpu) {
        // The camera orbits: every vertex side's visibility, once, instead of recomputing
        // the sides a new camera shows after each move.
        let options = RenderOptions { all_env_sides: true, ..Default::default() };
        match self.yarns.renderer(gpu, &self.scene_now(), options) {
            Ok(r) => {
                self.renderer = Some(r);
                self.applied = (self.effects.clone(), self.fabric);
            }
            Err(e) => {
                self.errors.push(format!("{e:#}"));
                (self.effects, self.fabric) = self.applied.clone();
            }
        }
    }

    /// Orbit by a drag of `(dx, dy)` pixels.
    pub fn drag_camera(&mut self, dx: f32, dy: f32) {
        self.orbit.drag(dx, dy);
        self.mark(Change::Camera);
    }

    /// Zoom by `lines` wheel lines (positive: closer).
    pub fn zoom(&mut self, lines: f32) {
        self.orbit.zoom(lines);
        self.mark(Change::Camera);
    }

    /// Pan by a drag of `(dx, dy)` pixels.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        self.orbit.pan(dx, dy, self.base.output.height as f32);
        self.mark(Change::Camera);
    }

    /// Any camera change made directly on [`Viewer::orbit`].
    pub fn camera_changed(&mut self) {
        self.mark(Change::Camera);
    }

    /// Turns every light about the target by a drag of `(dx, dy)` pixels.
    pub fn drag_lights(&mut self, dx: f32, dy: f32) {
        let (pivot, up) = (self.orbit.camera.target, self.orbit.camera.up);
        for l in &mut self.lights {
            camera::drag_light(l, pivot, up, dx, dy);
        }
        self.mark(Change::Light);
    }

    /// Turns the environment by `d_deg` about the up axis.
    pub fn rotate_env(&mut self, d_deg: f32) {
        self.env.rotation_deg = (self.env.rotation_deg + d_deg).rem_euclid(360.0);
        self.mark(Change::EnvRotation);
    }

    /// Switches to environment `i` before the next frame; errors go to the panel.
    pub fn select_env(&mut self, i: usize) {
        if i < self.env.files.len() {
            self.pending_env = Some(i);
            self.mark(Change::EnvSwap);
        }
    }

    /// Loads environment `i` and hands it to the renderer.
    fn swap_env(&mut self, gpu: &Gpu, i: usize) {
        let Some(path) = self.env.files.get(i).cloned() else { return };
        let Some(r) = self.renderer.as_mut() else { return };
        self.env.selected = Some(i);
        let (environments, base) = (&mut self.env, &self.base);
        let (res, ms) =
            env::timed(|| env::swap(r, gpu, &path, |map| environments.exposure_for(base, map)));
        self.env.load_ms = ms;
        match res {
            Ok((lit, f)) => {
                self.env.current = Some(i);
                self.env.lighting = lit;
                self.env.error = None;
                if let (true, Some(f)) = (lit, f) {
                    self.env.light_exposure = f;
                }
            }
            Err(e) => self.env.error = Some(e),
        }
    }

    /// Changes effects or fabric; the renderer is rebuilt before the next frame.
    pub fn set_effects(&mut self, effects: Effects, fabric: usize) {
        self.effects = effects;
        self.fabric = fabric.min(self.base.materials.len());
        self.needs_rebuild = true;
        self.mark(Change::Rebuild);
    }

    /// Cycles shadows none → volume → map.
    pub fn cycle_shadows(&mut self) {
        let mut fx = self.effects.clone();
        fx.shadows = match fx.shadows {
            Shadows::None => Shadows::Volume,
            Shadows::Volume => Shadows::Map,
            Shadows::Map => Shadows::None,
        };
        self.set_effects(fx, self.fabric);
    }

    /// Toggles per-pixel ↔ per-vertex evaluation.
    pub fn toggle_evaluation(&mut self) {
        let mut fx = self.effects.clone();
        fx.evaluation = match fx.evaluation {
            Evaluation::PerPixel => Evaluation::PerVertex,
            Evaluation::PerVertex => Evaluation::PerPixel,
        };
        self.set_effects(fx, self.fabric);
    }

    /// Toggles four-nearest ↔ nearest for both view blending and light interpolation.
    pub fn toggle_blending(&mut self) {
        let mut fx = self.effects.clone();
        let four = fx.view_blend == InterpMode::Four;
        let mode = if four { InterpMode::Nearest } else { InterpMode::Four };
        (fx.view_blend, fx.light_interp) = (mode, mode);
        self.set_effects(fx, self.fabric);
    }

    /// Adds `delta` PCA components (at least one; the store's count bounds it).
    pub fn step_components(&mut self, delta: i64) {
        let mut fx = self.effects.clone();
        let now = fx.components.or(self.stored_components).unwrap_or(1) as i64;
        let top = self.stored_components.unwrap_or(usize::MAX) as i64;
        fx.components = Some((now + delta).clamp(1, top) as usize);
        self.set_effects(fx, self.fabric);
    }

    /// Toggles the offset α of the smooth shadow boundary between the scene's and 0°.
    pub fn toggle_terminator(&mut self) {
        let scene_alpha = self.base.effects.terminator_deg;
        let on = self.effects.terminator_deg == 0.0;
        self.set_terminator(if on { scene_alpha.max(1.0) } else { 0.0 });
    }

    /// Sets the offset α of the smooth shadow boundary (eq. 6), degrees; a uniform only.
    pub fn set_terminator(&mut self, alpha_deg: f32) {
        let Some(r) = self.renderer.as_mut() else { return };
        match r.set_terminator_deg(alpha_deg) {
            Ok(()) => self.effects.terminator_deg = alpha_deg,
            Err(e) => self.errors.push(e.to_string()),
        }
        self.mark(Change::Light);
    }

    /// Back to the scene's camera.
    pub fn reset_camera(&mut self) {
        self.orbit.reset();
        self.mark(Change::Camera);
    }

    /// Applies what changed and renders a frame if something did; returns its cost.
    pub fn update(&mut self, gpu: &Gpu) -> Option<Latency> {
        let change = self.pending.take()?;
        let (_, update_ms) = env::timed(|| self.apply(gpu, change));
        let r = self.renderer.as_mut()?;
        let (drawn, render_ms) = env::timed(|| draw_frame(gpu, r, &mut self.shown));
        match drawn {
            Ok(()) => self.frames += 1,
            Err(e) => self.errors.push(format!("render: {e}")),
        }
        let lat = Latency { change, update_ms, render_ms };
        self.last = Some(lat);
        Some(lat)
    }

    /// Applies what changed without rendering a frame (the benchmark renders it the former
    /// way, read back, to compare).
    pub fn update_state_only(&mut self, gpu: &Gpu) {
        if let Some(change) = self.pending.take() {
            self.apply(gpu, change);
        }
    }

    fn apply(&mut self, gpu: &Gpu, change: Change) {
        if std::mem::take(&mut self.needs_rebuild) {
            self.rebuild(gpu);
        }
        if let Some(i) = self.pending_env.take() {
            self.swap_env(gpu, i);
        }
        let Some(r) = self.renderer.as_mut() else { return };
        if let Err(e) = r.set_camera(&self.orbit.camera) {
            self.errors.push(e.to_string());
        }
        if let Err(e) = r.set_lights(gpu, &self.lights) {
            self.errors.push(e.to_string());
        }
        if matches!(change, Change::EnvRotation | Change::Rebuild) {
            match env::rotate(r, gpu, self.env.rotation_deg) {
                Ok(lit) => self.env.lighting = lit,
                Err(e) => self.env.error = Some(e),
            }
        }
    }

    /// The last frame, read back from the shown texture.
    pub fn read_frame(&self, gpu: &Gpu) -> Result<Frame> {
        let Some(s) = &self.shown else { anyhow::bail!("no frame rendered yet") };
        Ok(Frame::read(gpu, &s.texture, s.stats.clone())?)
    }

    /// Writes the last frame as an sRGB PNG (exposure applied, written atomically).
    pub fn save_frame(&self, gpu: &Gpu, path: &Path) -> Result<()> {
        let f = self.read_frame(gpu)?;
        let (w, h) = (f.width as usize, f.height as usize);
        Ok(btf_image::write::write_png_linear(path, w, h, &f.rgb, self.exposure)?)
    }

    /// Renders the current state the way the viewer did before it presented the GPU
    /// texture: into the renderer's own target, read back as a [`Frame`] (for the
    /// benchmark's comparison).
    pub fn render_read_back(&mut self, gpu: &Gpu) -> Result<Frame> {
        let Some(r) = self.renderer.as_mut() else { anyhow::bail!("no renderer") };
        Ok(r.render(gpu)?)
    }
}
