//! The frame entry points: `Renderer::encode` into a caller's texture (what the viewer
//! presents, no read-back) renders what `Renderer::render` reads back, bit for bit, frame
//! after frame with the cached targets and persistent buffers; the same without GPU
//! timestamps (each pass submitted and timed on the CPU); a target of the wrong size or
//! format is refused.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::scene::{Evaluation, Light, Shadows};
use btf_render::{Frame, Gpu, RenderOptions, Renderer, Scene};
use std::path::Path;

/// The unit plane with a floating square over it under a coloured point light and a sun,
/// per vertex, shadow volumes, `msaa` samples.
fn scene(dir: &Path, msaa: u32) -> Scene {
    SceneBuilder::new(dir, 40)
        .size(40, 32)
        .mesh("plane.obj")
        .mesh("square.obj")
        .material("m.eigen")
        .perspective([0.5, -0.6, 1.2], [0.5, 0.5, 0.0], [0.0, 0.0, 1.0], 60.0)
        .light(Light::Point {
            position: [0.9, 0.1, 0.6],
            intensity: [0.3, 0.2, 0.1],
            shadows: true,
        })
        .light(directional([-0.3, 0.4, 0.8]))
        .effects(|e| {
            (e.evaluation, e.shadows, e.msaa) = (Evaluation::PerVertex, Shadows::Volume, msaa)
        })
        .build()
}

fn setup(dir: &Path) {
    write_store(dir, "m.eigen", Pattern::Checker, 16, 16, 8, Quantization::F16);
    unit_plane(dir, "plane.obj", 4);
    write(
        dir,
        "square.obj",
        "v 0.3 0.3 0.2\nv 0.6 0.3 0.2\nv 0.6 0.6 0.2\nv 0.3 0.6 0.2\nvt 0 0\nvt 1 0\nvt 1 1\n\
         vt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    );
}

/// A texture `renderer` can encode into, readable back.
fn target(gpu: &Gpu, renderer: &Renderer) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    gpu.target("caller's target", renderer.size(), 1, renderer.target_format(), usage)
}

/// Encodes a frame into `texture` in a caller's encoder, submits it and reads it back.
fn encode(gpu: &Gpu, r: &mut Renderer, texture: &wgpu::Texture) -> Frame {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    r.encode(gpu, &mut encoder, &texture.create_view(&Default::default())).unwrap();
    gpu.queue.submit([encoder.finish()]);
    let stats = r.last_stats(gpu).unwrap();
    Frame::read(gpu, texture, stats).unwrap()
}

fn identical(a: &Frame, b: &Frame) -> bool {
    a.rgb.iter().zip(&b.rgb).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn encoding_into_a_callers_texture_renders_the_read_back_frame() {
    let Some(gpu) = gpu("encoding_into_a_callers_texture_renders_the_read_back_frame") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    for msaa in [1, 4] {
        let mut r =
            Renderer::new(&gpu, &scene(dir.path(), msaa), RenderOptions::default()).unwrap();
        let texture = target(&gpu, &r);
        let read_back = r.render(&gpu).unwrap();
        assert!(read_back.rgb.iter().any(|&v| v > 0.0) && read_back.all_finite());
        let names = |f: &Frame| f.stats.passes.iter().map(|p| p.name.clone()).collect::<Vec<_>>();
        // Frame after frame (cached targets, buffers rewritten), and the light moved between.
        for k in 0..3 {
            let shown = encode(&gpu, &mut r, &texture);
            assert!(identical(&read_back, &shown), "msaa {msaa}, frame {k}: encode ≠ render");
            assert_eq!(names(&shown), names(&read_back), "msaa {msaa}: the same passes");
            assert!(shown.stats.passes.iter().all(|p| p.ms.is_finite() && p.ms >= 0.0));
            assert!(identical(&read_back, &r.render(&gpu).unwrap()), "render again");
        }
        let mut lights = r.scene().lights.clone();
        if let Light::Point { position, .. } = &mut lights[0] {
            position[0] = 0.1;
        }
        r.set_lights(&gpu, &lights).unwrap();
        let moved = r.render(&gpu).unwrap();
        assert!(!identical(&read_back, &moved), "msaa {msaa}: the light moved");
        assert!(identical(&moved, &encode(&gpu, &mut r, &texture)), "msaa {msaa}: after the move");
    }
}

#[test]
fn without_timestamps_each_pass_is_timed_on_the_cpu() {
    let Some(mut gpu) = gpu("without_timestamps_each_pass_is_timed_on_the_cpu") else { return };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let s = scene(dir.path(), 4);
    let timed = Renderer::new(&gpu, &s, RenderOptions::default()).unwrap().render(&gpu).unwrap();
    gpu.timestamps = false;
    let mut r = Renderer::new(&gpu, &s, RenderOptions::default()).unwrap();
    let f = r.render(&gpu).unwrap();
    assert!(identical(&timed, &f), "the frame does not depend on how it is timed");
    assert_eq!(f.stats.timing, "cpu");
    assert_eq!(f.stats.passes.len(), timed.stats.passes.len());
    assert!(f.stats.passes.iter().all(|p| p.ms.is_finite() && p.ms > 0.0), "{:?}", f.stats);
    // A caller's encoder is not submitted pass by pass: its GPU passes are not timed.
    let texture = target(&gpu, &r);
    let shown = encode(&gpu, &mut r, &texture);
    assert!(identical(&timed, &shown));
    let untimed: Vec<_> = shown.stats.passes.iter().filter(|p| p.ms.is_nan()).collect();
    assert!(untimed.iter().any(|p| p.name.starts_with("btf")), "{:?}", shown.stats.passes);
}

#[test]
fn a_target_of_another_size_or_format_is_refused() {
    let Some(gpu) = gpu("a_target_of_another_size_or_format_is_refused") else { return };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let mut r = Renderer::new(&gpu, &scene(dir.path(), 1), RenderOptions::default()).unwrap();
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    for (size, format) in [
        ((41, 32), r.target_format()),
        ((40, 32), wgpu::TextureFormat::Rgba16Float),
        ((40, 32), wgpu::TextureFormat::Rgba8Unorm),
    ] {
        let texture = gpu.target("wrong", size, 1, format, usage);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let view = texture.create_view(&Default::default());
        let e = r.encode(&gpu, &mut encoder, &view).unwrap_err().to_string();
        assert!(e.contains("encode") && e.contains("40×32"), "{e}");
    }
}
