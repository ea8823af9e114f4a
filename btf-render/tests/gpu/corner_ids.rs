//! An environment light computes visibility (`[S03 §5.2]`) and radiances
//! (`[S03 eq. 10]`) only for the vertex sides the camera shows (the corner-id pass,
//! `passes/corner_ids`): the frame is the same as with every side computed,
//! bit for bit, with and without MSAA, for a camera that sees the inside of the shirt
//! through its neck; a camera move computes the rest and again equals the full renderer.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::scene::{EnvironmentLight, Light};
use btf_render::{Frame, RenderOptions, Renderer, Scene};
use std::path::Path;

/// Writes the low shirt, a checker store and a sky with a sun.
fn setup(dir: &Path) {
    synth_mesh(dir, "shirt.obj", datasets::MeshKind::Shirt);
    write_store(dir, "m.eigen", Pattern::Checker, 4, 4, 8, Quantization::F16);
    let (w, h) = (64usize, 32usize);
    exr::prelude::write_rgb_file(dir.join("sky.exr"), w, h, |x, y| {
        let theta = std::f32::consts::PI * (y as f32 + 0.5) / h as f32;
        let phi = std::f32::consts::TAU * (x as f32 + 0.5) / w as f32;
        let sun = if (10..12).contains(&y) && (20..22).contains(&x) { 200.0 } else { 0.0 };
        let l = 0.6 + 0.3 * phi.cos() + 0.4 * theta.cos().max(0.0) + sun;
        (l, 0.9 * l, 0.8 * l)
    })
    .unwrap();
}

/// The shirt under the sky from a perspective camera at `eye` with `msaa` samples.
fn scene(dir: &Path, eye: [f32; 3], msaa: u32) -> Scene {
    scene_with(dir, eye, msaa, |_| {})
}

/// The scene with its environment light changed by `env`.
fn scene_with(
    dir: &Path,
    eye: [f32; 3],
    msaa: u32,
    env: impl FnOnce(&mut EnvironmentLight),
) -> Scene {
    let mut light = EnvironmentLight { visibility_res: 8, ..environment(dir, "sky.exr") };
    env(&mut light);
    SceneBuilder::new(dir, 40)
        .mesh("shirt.obj")
        .material("m.eigen")
        .perspective(eye, [0.0, 0.0, 0.1], [0.0, 1.0, 0.0], 40.0)
        .light(Light::Environment(light))
        .effects(|e| e.msaa = msaa)
        .build()
}

fn build(gpu: &btf_render::Gpu, scene: &Scene, all: bool) -> Renderer {
    Renderer::new(gpu, scene, RenderOptions { all_env_sides: all, ..Default::default() }).unwrap()
}

fn identical(a: &Frame, b: &Frame) -> usize {
    a.rgb.iter().zip(&b.rgb).filter(|(x, y)| x.to_bits() != y.to_bits()).count()
}

/// From the front and a little above: the front's outside and, through the neck, the
/// inside of the back.
const FRONT: [f32; 3] = [0.0, -2.2, 1.0];

#[test]
fn camera_sides_render_the_frame_of_all_sides_bit_for_bit() {
    let Some(gpu) = gpu("camera_sides_render_the_frame_of_all_sides_bit_for_bit") else { return };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    for msaa in [1, 4] {
        let s = scene(dir.path(), FRONT, msaa);
        let (mut some, mut all) = (build(&gpu, &s, false), build(&gpu, &s, true));
        let (a, b) = (some.render(&gpu).unwrap(), all.render(&gpu).unwrap());
        let (e_some, e_all) = (some.environment().unwrap(), all.environment().unwrap());
        let (computed, frames) = (e_some.computed_frames(), e_some.frames());
        let backs = (frames / 2..frames).filter(|&f| e_some.has_frame(f)).count();
        eprintln!("msaa {msaa}: {computed} of {frames} frames computed, {backs} back sides");
        assert_eq!(e_all.computed_frames(), frames);
        // At most one side per vertex, and far fewer than all: the back of the shirt is
        // hidden behind its front.
        assert!(computed * 10 <= frames * 4, "{computed} of {frames}");
        assert!(backs > 0, "the camera sees some inside through the neck");
        let lit = a.rgb.iter().filter(|&&v| v > 0.0).count();
        assert!(lit > a.rgb.len() / 10, "the shirt fills part of the frame ({lit} values lit)");
        assert_eq!(identical(&a, &b), 0, "msaa {msaa}: frames differ");
        // Computed frames carry the same bits as the full computation.
        let (va, vb) = (e_some.visibility(), e_all.visibility());
        for f in (0..frames).filter(|&f| e_some.has_frame(f)) {
            assert_eq!(va.frame_bits(f), vb.frame_bits(f), "frame {f}");
        }
    }
}

#[test]
fn a_camera_move_computes_the_other_sides() {
    let Some(gpu) = gpu("a_camera_move_computes_the_other_sides") else { return };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let (s, back) = (scene(dir.path(), FRONT, 1), scene(dir.path(), [0.4, 2.4, 0.6], 1));
    let mut moved = build(&gpu, &s, false);
    let before = moved.environment().unwrap().computed_frames();
    moved.set_camera(&back.camera).unwrap();
    let env = moved.environment().unwrap();
    assert_eq!(env.computed_frames(), env.frames(), "{before} frames before the move");
    let mut fresh = build(&gpu, &back, true);
    let (a, b) = (moved.render(&gpu).unwrap(), fresh.render(&gpu).unwrap());
    assert_eq!(identical(&a, &b), 0, "the moved renderer differs from a fresh one");
}

#[test]
fn cached_maps_of_every_side_serve_a_camera() {
    let Some(gpu) = gpu("cached_maps_of_every_side_serve_a_camera") else { return };
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let s = scene_with(dir.path(), FRONT, 1, |e| e.cache_dir = Some(dir.path().join("cache")));
    // A camera's subset first: cached under its own key, and again from there.
    let mut some = build(&gpu, &s, false);
    let e = some.environment().unwrap();
    assert!(!e.timings.visibility_cached && e.computed_frames() < e.frames());
    let again = build(&gpu, &s, false);
    let e = again.environment().unwrap();
    assert!(e.timings.visibility_cached && e.computed_frames() < e.frames());
    assert!(e.timings.sides_ms > 0.0, "the subset's key needs the corner-id pass");
    // Once every side is cached, a camera takes all of them (nothing left to complete),
    // without a corner-id pass.
    let all = build(&gpu, &s, true);
    assert!(!all.environment().unwrap().timings.visibility_cached);
    let mut served = build(&gpu, &s, false);
    let e = served.environment().unwrap();
    assert!(e.timings.visibility_cached && e.computed_frames() == e.frames());
    assert_eq!(e.timings.sides_ms, 0.0);
    let (a, b) = (some.render(&gpu).unwrap(), served.render(&gpu).unwrap());
    assert_eq!(identical(&a, &b), 0, "the subset and the full maps render alike");
}
