//! The window of `btf view`: a winit event loop (X11), a wgpu surface on an adapter that
//! can present to it, the frame — rendered into a texture on the same device, never read
//! back — drawn by [`Present`] beside the egui panel, and mouse and key input turned into
//! [`Viewer`] changes. Frames are rendered only when something
//! changed, at the size of the area the panel leaves free (in physical pixels, so a
//! 1280 × 800 window shows a frame rendered for it, not a scaled-up scene-size one); the
//! panel is repainted on input.
//!
//! A drag (orbit, light, pan) lives from a button press over the frame to the release of
//! that button. The release ends it wherever it happens — over the panel (where egui takes
//! the event), outside the window, or never seen because the window lost focus or the
//! cursor left it — so motion without a button held can never keep orbiting ([`DragState`],
//! tested).

use super::ViewArgs;
use super::actions::{self, Action};
use super::panel::{self, LatencyLog};
use super::present::{Present, Rect, letterbox};
use super::state::Viewer;
use anyhow::{Context, Result, anyhow};
use btf_render::{Gpu, Scene};
use std::path::PathBuf;
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::dpi::{LogicalSize, PhysicalPosition};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::ModifiersState;
use winit::window::{Window, WindowId};

/// Opens the window and runs until it is closed.
pub fn run(args: ViewArgs, scene: Scene) -> Result<()> {
    let event_loop = EventLoop::new()
        .context("cannot open a window (is DISPLAY set? `--turntable` works without one)")?;
    event_loop.set_control_flow(ControlFlow::Wait);
    let mut app = App { args, scene: Some(scene), running: None, error: None };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

struct App {
    args: ViewArgs,
    scene: Option<Scene>,
    running: Option<Running>,
    error: Option<anyhow::Error>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Drag {
    Orbit,
    Light,
    Pan,
}

/// The drag in progress: which kind, started by which button, and the last cursor position.
#[derive(Debug, Default)]
struct DragState {
    active: Option<(Drag, MouseButton, PhysicalPosition<f64>)>,
}

impl DragState {
    /// A button went down (`over_frame`: not on the panel) or up.
    fn button(
        &mut self,
        pressed: bool,
        button: MouseButton,
        shift: bool,
        at: PhysicalPosition<f64>,
        over_frame: bool,
    ) {
        if !pressed {
            // Any release ends the drag: a second button released while the first is held
            // ends it too, which is harmless, and a release is never missed.
            self.active = None;
            return;
        }
        let kind = match button {
            MouseButton::Left if shift => Some(Drag::Pan),
            MouseButton::Left => Some(Drag::Orbit),
            MouseButton::Right => Some(Drag::Light),
            MouseButton::Middle => Some(Drag::Pan),
            _ => None,
        };
        if let (Some(k), true, None) = (kind, over_frame, self.active) {
            self.active = Some((k, button, at));
        }
    }

    /// The cursor moved: the drag's kind and motion in pixels, when a drag is on.
    fn moved(&mut self, to: PhysicalPosition<f64>) -> Option<(Drag, f32, f32)> {
        let (kind, button, from) = self.active?;
        self.active = Some((kind, button, to));
        Some((kind, (to.x - from.x) as f32, (to.y - from.y) as f32))
    }

    /// Focus lost or cursor gone: the release may never arrive.
    fn cancel(&mut self) {
        self.active = None;
    }
}

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    adapter: String,
    viewer: Viewer,
    present: Present,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    log: LatencyLog,
    drag: DragState,
    cursor: PhysicalPosition<f64>,
    modifiers: ModifiersState,
    show_panel: bool,
    frame_rect: Rect,
    frame_area: Rect,
    shots: u32,
    shot_dir: PathBuf,
    print_log: bool,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(scene) = self.scene.take() else { return };
        match Running::new(event_loop, &self.args, scene) {
            Ok(r) => {
                r.window.request_redraw();
                self.running = Some(r);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else { return };
        match &event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => {
                crate::guard::outln!("closing");
                event_loop.exit();
                return;
            }
            WindowEvent::Resized(size) => {
                if size.width > 0 && size.height > 0 {
                    r.config.width = size.width;
                    r.config.height = size.height;
                    r.surface.configure(&r.gpu.device, &r.config);
                }
                r.window.request_redraw();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = r.redraw(event_loop) {
                    self.error = Some(e);
                    event_loop.exit();
                }
                return;
            }
            // Seen before egui, which may consume them: a drag must end whoever takes the
            // release (see `DragState`).
            WindowEvent::MouseInput { state: ElementState::Released, button, .. } => {
                r.drag.button(false, *button, false, r.cursor, false);
            }
            WindowEvent::Focused(false) | WindowEvent::CursorLeft { .. } => r.drag.cancel(),
            WindowEvent::CursorMoved { position, .. } => r.cursor = *position,
            _ => {}
        }
        let response = r.egui_state.on_window_event(&r.window, &event);
        if response.repaint {
            r.window.request_redraw();
        }
        if !response.consumed {
            r.input(event_loop, &event);
        }
    }
}

/// The first surface format without sRGB encoding (egui paints in gamma space; the frame
/// is encoded in `present.wgsl`), else the first offered.
fn surface_format(caps: &wgpu::SurfaceCapabilities) -> Result<wgpu::TextureFormat> {
    caps.formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or_else(|| caps.formats.first().copied())
        .ok_or_else(|| anyhow!("the window surface offers no format"))
}

/// The frame area the window opens with, in points: `--width`/`--height` as given, else the
/// scene's frame scaled up (aspect kept) to fill about 960 × 720 — the scene's size is the
/// size of its still renders, often small, and the frame follows the window from then on.
fn initial_area(width: u32, height: u32, explicit: bool) -> (f64, f64) {
    let (w, h) = (width.max(1) as f64, height.max(1) as f64);
    let s = if explicit { 1.0 } else { (960.0 / w).min(720.0 / h).max(1.0) };
    ((w * s).round(), (h * s).round())
}

impl Running {
    fn new(event_loop: &ActiveEventLoop, args: &ViewArgs, scene: Scene) -> Result<Running> {
        let explicit = args.width.is_some() || args.height.is_some();
        let (fw, fh) = initial_area(scene.output.width, scene.output.height, explicit);
        let title = format!("btf view — {}", args.scene.display());
        let attrs = Window::default_attributes()
            .with_title(title)
            .with_inner_size(LogicalSize::new(fw + panel::WIDTH_PT as f64, fh));
        let window = Arc::new(event_loop.create_window(attrs).context("creating the window")?);
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(desc.with_env());
        let surface =
            instance.create_surface(window.clone()).context("creating the window surface")?;
        let (gpu, adapter) = Gpu::with_surface(&instance, &surface)
            .context("no GPU adapter can present to this window")?;
        let size = window.inner_size();
        let format = surface_format(&surface.get_capabilities(&adapter))?;
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| anyhow!("the adapter cannot present to this window"))?;
        config.format = format;
        surface.configure(&gpu.device, &config);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        let present = Present::new(&gpu, format);
        let info = &gpu.info;
        let adapter_name = format!("{} ({:?}), {format:?}", info.name, info.backend);
        let viewer = Viewer::new(
            &gpu,
            scene,
            &args.scene,
            args.env.clone(),
            args.env_exposure == super::EnvExposure::Auto,
        );
        crate::guard::outln!("window {} adapter {adapter_name}", u64::from(window.id()));
        Ok(Running {
            window,
            surface,
            config,
            gpu,
            adapter: adapter_name,
            viewer,
            present,
            egui_ctx,
            egui_state,
            egui_renderer,
            log: LatencyLog::default(),
            drag: DragState::default(),
            cursor: PhysicalPosition::new(0.0, 0.0),
            modifiers: ModifiersState::empty(),
            show_panel: !args.no_panel,
            frame_rect: Rect { x: 0.0, y: 0.0, w: 0.0, h: 0.0 },
            frame_area: Rect { x: 0.0, y: 0.0, w: 0.0, h: 0.0 },
            shots: 0,
            shot_dir: args.shots.clone(),
            print_log: args.log,
        })
    }

    /// Renders at the size of the frame area of the last layout (the whole window before
    /// the first); a layout that changes it asks for another frame.
    fn sync_size(&mut self) {
        let area = if self.frame_area.w > 0.0 {
            self.frame_area
        } else {
            Rect { x: 0.0, y: 0.0, w: self.config.width as f32, h: self.config.height as f32 }
        };
        self.viewer.set_size(&self.gpu, area.w.round() as u32, area.h.round() as u32);
    }

    /// Renders a frame into the shown texture when the state changed (no read-back).
    fn render_pending(&mut self) {
        if let Some(lat) = self.viewer.update(&self.gpu) {
            self.log.record(lat);
            if let Some(s) = &self.viewer.shown {
                self.present.show(&self.gpu, s);
            }
            if self.print_log {
                let env = &self.viewer.env;
                crate::guard::outln!(
                    "frame {} size={}x{} change={:?} update_ms={:.2} render_ms={:.2} env={:?} \
                     env_rotation_deg={} env_lighting={} env_f={} env_error={:?} errors={} \
                     read_back_bytes={}",
                    self.viewer.frames,
                    self.viewer.size().0,
                    self.viewer.size().1,
                    lat.change,
                    lat.update_ms,
                    lat.render_ms,
                    env.current,
                    env.rotation_deg,
                    env.lighting,
                    env.light_exposure,
                    env.error,
                    self.viewer.errors.len(),
                    self.gpu.read_back_bytes()
                );
            }
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        self.sync_size();
        self.render_pending();
        let raw = self.egui_state.take_egui_input(&self.window);
        let mut actions = Vec::new();
        let mut area = egui::Rect::NOTHING;
        let full = self.egui_ctx.run_ui(raw, |ui| {
            if self.show_panel {
                actions = panel::show(ui, &self.viewer, &self.log, &self.adapter);
            }
            area = ui.available_rect_before_wrap();
        });
        let egui::FullOutput {
            platform_output, mut textures_delta, shapes, pixels_per_point, ..
        } = full;
        self.egui_state.handle_platform_output(&self.window, platform_output);
        let ppp = pixels_per_point;
        // Whole pixels, so the frame rendered at the area's size is shown texel for pixel.
        let (x0, y0) = ((area.min.x * ppp).ceil(), (area.min.y * ppp).ceil());
        let (x1, y1) = ((area.max.x * ppp).floor(), (area.max.y * ppp).floor());
        let area_px = Rect { x: x0, y: y0, w: (x1 - x0).max(1.0), h: (y1 - y0).max(1.0) };
        let resized = area_px != self.frame_area;
        self.frame_area = area_px;
        let (fw, fh) = self.viewer.size();
        let rect = letterbox(area_px, fw, fh);
        if rect != self.frame_rect && self.print_log {
            crate::guard::outln!("layout {} {} {} {}", rect.x, rect.y, rect.w, rect.h);
        }
        self.frame_rect = rect;
        let jobs = self.egui_ctx.tessellate(shapes, ppp);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: ppp,
        };
        for (id, deltas) in textures_delta.set.drain() {
            for delta in &deltas {
                self.egui_renderer.update_texture(&self.gpu.device, &self.gpu.queue, id, delta);
            }
        }
        let freed: Vec<egui::TextureId> = textures_delta.free.drain().collect();
        let retry = self.paint(&jobs, &screen);
        for id in &freed {
            self.egui_renderer.free_texture(id);
        }
        for a in actions {
            self.act(event_loop, a);
        }
        if self.viewer.needs_frame() || retry || resized {
            self.window.request_redraw();
        }
        Ok(())
    }

    /// Draws the frame and the panel on the surface; true when the surface had to be
    /// reconfigured and the frame should be drawn again.
    fn paint(
        &mut self,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) -> bool {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return true;
            }
            _ => return false,
        };
        let target = texture.texture.create_view(&Default::default());
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        let extra = self.egui_renderer.update_buffers(
            &self.gpu.device,
            &self.gpu.queue,
            &mut enc,
            jobs,
            screen,
        );
        {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("window"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.02,
                                g: 0.02,
                                b: 0.02,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.present.draw(&self.gpu, &mut pass, self.viewer.exposure, self.frame_rect);
            let (w, h) = (self.config.width as f32, self.config.height as f32);
            pass.set_viewport(0.0, 0.0, w, h, 0.0, 1.0);
            self.egui_renderer.render(&mut pass, jobs, screen);
        }
        self.gpu.queue.submit(extra.into_iter().chain([enc.finish()]));
        self.gpu.queue.present(texture);
        false
    }

    fn act(&mut self, event_loop: &ActiveEventLoop, action: Action) {
        match action {
            Action::Quit => {
                crate::guard::outln!("closing");
                event_loop.exit();
            }
            Action::TogglePanel => self.show_panel = !self.show_panel,
            Action::Screenshot => self.screenshot(),
            a => actions::apply(&mut self.viewer, a),
        }
        self.window.request_redraw();
    }

    /// Writes the frame of the current state (pending changes rendered first).
    fn screenshot(&mut self) {
        self.sync_size();
        self.render_pending();
        // The next free number: a screenshot never replaces an earlier session's.
        let mut path;
        loop {
            self.shots += 1;
            path = self.shot_dir.join(format!("shot-{:04}.png", self.shots));
            if !path.exists() {
                break;
            }
        }
        match self.viewer.save_frame(&self.gpu, &path) {
            Ok(()) => crate::guard::outln!("screenshot {}", path.display()),
            Err(e) => self.viewer.errors.push(format!("{e:#}")),
        }
    }

    fn input(&mut self, event_loop: &ActiveEventLoop, event: &WindowEvent) {
        match event {
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            // A key held while the window gains focus comes again as a synthetic press (winit):
            // not a key stroke, so no action (it took a second screenshot when focus arrived
            // while `p` was down).
            WindowEvent::KeyboardInput { event, is_synthetic: false, .. }
                if event.state == ElementState::Pressed =>
            {
                if let Some(a) = actions::for_key(&event.logical_key) {
                    self.act(event_loop, a);
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let (x, y) = (self.cursor.x as f32, self.cursor.y as f32);
                let r = self.frame_rect;
                let over_frame = x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h;
                let shift = self.modifiers.shift_key();
                let pressed = *state == ElementState::Pressed;
                self.drag.button(pressed, *button, shift, self.cursor, over_frame);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = *position;
                if let Some((kind, dx, dy)) = self.drag.moved(*position) {
                    self.dragged(kind, dx, dy);
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.viewer.zoom(lines);
                self.window.request_redraw();
            }
            _ => {}
        }
    }

    fn dragged(&mut self, kind: Drag, dx: f32, dy: f32) {
        match kind {
            Drag::Orbit => self.viewer.drag_camera(dx, dy),
            Drag::Light => self.viewer.drag_lights(dx, dy),
            Drag::Pan => {
                // Frame pixels per window pixel (1 once the frame has the area's size), so
                // the garment follows the cursor.
                let s = self.viewer.size().1 as f32 / self.frame_rect.h.max(1.0);
                self.viewer.pan(dx * s, dy * s);
            }
        }
        self.window.request_redraw();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64) -> PhysicalPosition<f64> {
        PhysicalPosition::new(x, y)
    }

    #[test]
    fn the_window_opens_at_a_useful_size() {
        assert_eq!(initial_area(320, 240, false), (960.0, 720.0));
        assert_eq!(initial_area(96, 72, false), (960.0, 720.0));
        assert_eq!(initial_area(1920, 1080, false), (1920.0, 1080.0)); // never shrunk
        assert_eq!(initial_area(320, 240, true), (320.0, 240.0));
    }

    #[test]
    fn motion_without_a_button_never_orbits() {
        let mut d = DragState::default();
        // a press over the frame starts an orbit; motion turns by the cursor's motion
        d.button(true, MouseButton::Left, false, at(10.0, 10.0), true);
        assert_eq!(d.moved(at(13.0, 14.0)), Some((Drag::Orbit, 3.0, 4.0)));
        // the release, taken by egui over the panel, still reaches the drag first
        d.button(false, MouseButton::Left, false, at(300.0, 14.0), false);
        assert_eq!(d.moved(at(320.0, 20.0)), None);
        // a press on the panel starts nothing
        d.button(true, MouseButton::Left, false, at(5.0, 5.0), false);
        assert_eq!(d.moved(at(6.0, 6.0)), None);
        // focus lost mid-drag (the release goes to another window)
        d.button(true, MouseButton::Right, false, at(50.0, 50.0), true);
        assert_eq!(d.moved(at(52.0, 50.0)), Some((Drag::Light, 2.0, 0.0)));
        d.cancel();
        assert_eq!(d.moved(at(60.0, 50.0)), None);
        // a second button pressed during a drag does not switch its kind; shift+left pans
        d.button(true, MouseButton::Left, true, at(0.0, 0.0), true);
        d.button(true, MouseButton::Right, false, at(0.0, 0.0), true);
        assert_eq!(d.moved(at(1.0, 0.0)), Some((Drag::Pan, 1.0, 0.0)));
    }
}
