//! Headless companions of the viewer, driving the same [`Viewer`] state as the window:
//!
//! - the turntable export (`--turntable N -o DIR`): `N` frames of a full turn as a product
//!   page shows them. A garment on a turntable turns under a fixed studio; seen from the
//!   garment, camera, lights and environment turn together by `i · 360°/N`, which is what
//!   frame `i` renders. PNGs are written atomically; `--resume` keeps finished frames.
//! - the interaction-latency benchmark (`--bench N`): `N` camera moves, light moves,
//!   environment rotations and environment swaps, interleaved in one run, each timed from
//!   the change to the frame finished on the GPU; medians and ratios to the camera move.
//!   Then the cost of presenting a frame, with and without a read-back, interleaved: the
//!   window's path (encode into the texture the present pass samples) against the former
//!   one (render → `Frame` on the CPU → upload → present), each into an offscreen surface.

use super::ViewArgs;
use super::camera::turn_light;
use super::present::{Present, Rect};
use super::state::{Change, Latency, Viewer};
use crate::progress;
use anyhow::{Context, Result, bail};
use btf_render::{Gpu, Scene};
use std::path::Path;

fn start(args: &ViewArgs, scene: Scene) -> Result<(Gpu, Viewer)> {
    let gpu = Gpu::new().context("creating a headless GPU device")?;
    let mut v = Viewer::new(
        &gpu,
        scene,
        &args.scene,
        args.env.clone(),
        args.env_exposure == super::EnvExposure::Auto,
    );
    v.update(&gpu);
    if let Some(e) = v.errors.first() {
        bail!("{}: {e}", args.scene.display());
    }
    if let Some(e) = &v.env.error {
        bail!("{e}");
    }
    Ok((gpu, v))
}

/// Writes `n` turntable frames to `out/turntable-NNNN.png`.
pub fn export(args: &ViewArgs, scene: Scene, n: u32, out: &Path) -> Result<()> {
    crate::guard::refuse_scene_overlap(&[("-o", out)], &args.scene, &scene, &[])?;
    crate::guard::output_folder(out, "view --turntable", false, &|_| false)?;
    let (gpu, mut v) = start(args, scene)?;
    let (home_camera, home_lights) = (v.orbit.home.clone(), v.lights.clone());
    let (pivot, up) = (home_camera.target, home_camera.up);
    let env0 = v.env.rotation_deg;
    let bar = progress::bar(n as u64, "turntable");
    for i in 0..n {
        let path = out.join(format!("turntable-{i:04}.png"));
        if args.resume && path.exists() {
            bar.inc(1);
            continue;
        }
        let angle_deg = i as f32 * 360.0 / n as f32;
        v.orbit.camera = home_camera.clone();
        v.orbit.orbit(angle_deg, 0.0);
        v.camera_changed();
        v.lights = home_lights.clone();
        for l in &mut v.lights {
            turn_light(l, pivot, up, angle_deg, 0.0);
        }
        v.rotate_env(env0 + angle_deg - v.env.rotation_deg);
        v.update(&gpu);
        if let Some(e) = v.errors.last() {
            bail!("turntable frame {i} ({angle_deg}°): {e}");
        }
        v.save_frame(&gpu, &path)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    crate::guard::outln!("{n} turntable frames in {}", out.display());
    Ok(())
}

fn median(mut xs: Vec<f64>) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(f64::total_cmp);
    let m = xs.len() / 2;
    if xs.len() % 2 == 1 { xs[m] } else { 0.5 * (xs[m - 1] + xs[m]) }
}

/// Times `n` interactions of each kind and prints a table and one JSON line.
pub fn bench(args: &ViewArgs, scene: Scene, n: u32) -> Result<()> {
    let (gpu, mut v) = start(args, scene)?;
    let envs = v.env.files.len();
    type Step = fn(&mut Viewer, u32, usize);
    let kinds: [(Change, Step); 4] = [
        (Change::Camera, |v, _, _| v.drag_camera(10.0, 0.0)),
        (Change::Light, |v, _, _| v.drag_lights(10.0, 0.0)),
        (Change::EnvRotation, |v, _, _| v.rotate_env(15.0)),
        (Change::EnvSwap, |v, i, envs| v.select_env(i as usize % envs.max(1))),
    ];
    let kinds: Vec<(Change, Step)> =
        kinds.into_iter().filter(|(k, _)| *k != Change::EnvSwap || envs > 0).collect();
    // Round robin, so that a change of machine load affects every kind alike; the first
    // round warms caches and is not counted.
    let mut rows: Vec<(Change, Vec<Latency>)> = kinds.iter().map(|(k, _)| (*k, vec![])).collect();
    for i in 0..n + 1 {
        for (r, (_, step)) in kinds.iter().enumerate() {
            step(&mut v, i, envs);
            let lat = v.update(&gpu).context("no frame rendered")?;
            if i > 0 {
                rows[r].1.push(lat);
            }
        }
    }
    if let Some(e) = v.errors.last() {
        bail!("{e}");
    }
    let camera = median(rows[0].1.iter().map(Latency::total_ms).collect());
    crate::guard::outln!(
        "adapter: {} ({:?}); {n} interactions each, medians",
        gpu.info.name,
        gpu.info.backend
    );
    crate::guard::outln!(
        "{:<24} {:>10} {:>10} {:>10} {:>8}",
        "change",
        "total ms",
        "update",
        "render",
        "ratio"
    );
    let mut json = Vec::new();
    for (kind, lats) in &rows {
        let total = median(lats.iter().map(Latency::total_ms).collect());
        let update = median(lats.iter().map(|l| l.update_ms).collect());
        let render = median(lats.iter().map(|l| l.render_ms).collect());
        let ratio = total / camera;
        crate::guard::outln!(
            "{:<24} {total:>10.2} {update:>10.2} {render:>10.2} {ratio:>8.2}",
            kind.name()
        );
        json.push(format!(
            r#"{{"change":"{}","total_ms":{total:.3},"update_ms":{update:.3},"render_ms":{render:.3},"ratio_to_camera":{ratio:.3}}}"#,
            kind.name()
        ));
    }
    crate::guard::outln!(
        "environment lighting of the garment: {}",
        if v.env.lighting { "on" } else { "off (no environment light in this renderer/scene)" }
    );
    let (shown, read_back) = present_costs(&gpu, &mut v, n.max(5))?;
    let (w, h) = v.size();
    crate::guard::outln!(
        "presented frame ({w} × {h}, camera moves, median of {}): {shown:.2} ms without a \
         read-back, {read_back:.2} ms with one (render → Frame → upload), ratio {:.2}",
        n.max(5),
        read_back / shown
    );
    crate::guard::outln!("[{}]", json.join(","));
    Ok(())
}

/// Median milliseconds from a camera move to a frame presented into an offscreen surface
/// and finished, over `n` frames each way, interleaved: `(without, with)` a read-back.
fn present_costs(gpu: &Gpu, v: &mut Viewer, n: u32) -> Result<(f64, f64)> {
    let (w, h) = v.size();
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let surface =
        gpu.target("offscreen surface", (w, h), 1, format, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let surface = surface.create_view(&Default::default());
    let (mut direct, mut uploaded) = (Present::new(gpu, format), Present::new(gpu, format));
    let viewport = Rect { x: 0.0, y: 0.0, w: w as f32, h: h as f32 };
    let exposure = v.exposure;
    let present = |p: &Present| -> Result<()> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present (bench)"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &surface,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            p.draw(gpu, &mut pass, exposure, viewport);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(gpu.wait()?)
    };
    let (mut without, mut with) = (Vec::new(), Vec::new());
    for i in 0..=n {
        v.drag_camera(10.0, 0.0);
        let t = std::time::Instant::now();
        v.update(gpu).context("no frame rendered")?;
        let shown = v.shown.as_ref().context("no frame shown")?;
        direct.show(gpu, shown);
        present(&direct)?;
        let ms_without = t.elapsed().as_secs_f64() * 1e3;
        v.drag_camera(10.0, 0.0);
        let t = std::time::Instant::now();
        v.update_state_only(gpu);
        let frame = v.render_read_back(gpu)?;
        uploaded.upload(gpu, &frame);
        present(&uploaded)?;
        let ms_with = t.elapsed().as_secs_f64() * 1e3;
        if i > 0 {
            without.push(ms_without);
            with.push(ms_with);
        }
    }
    if let Some(e) = v.errors.last() {
        bail!("{e}");
    }
    Ok((median(without), median(with)))
}
