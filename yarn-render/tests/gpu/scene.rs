//! A btf-render scene's `[[yarns]]` drawn into its frame (`yarn_render::scene`): the
//! composite against the standalone `FiberRenderer` image of the same yarns, camera and
//! lights (bit-identical wherever no mesh is in front), depth both ways against an opaque
//! BTF quad (pixel counts against its projection, a 1-pixel band excluded), and refusals
//! naming the key. A 10 mm carrier plane at z = 0 (UV = position / 10 mm) with a 2 × 2
//! stockinette patch, seen by an orthographic camera from +z over a 10 mm window at 48²
//! (0.21 mm a pixel; the cotton yarn is 1 mm across).

use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_render::{Frame, Gpu, RenderOptions, Renderer, Scene};
use std::path::{Path, PathBuf};
use yarn_render::scene::overlay::{scene_bcsdf, settings};
use yarn_render::scene::{YarnOverlay, bounds_f32, fiber_camera, fiber_lights};
use yarn_render::{FiberImage, FiberRenderer};

const SIZE: u32 = 48;

/// An 8×8 eigen store of 2 components: mean 0.25, small texture-varying eigentextures.
fn tiny_store(dir: &Path) {
    let (w, h, c) = (8, 8, 2);
    let s = Sampling::ubo81();
    let meta = EigenMeta {
        btf: BtfMeta::new(s.clone(), s.clone(), w, h),
        components: c,
        quantization: Quantization::F16,
    };
    let writer = EigenWriter::create(&dir.join("m.eigen"), meta, false).unwrap();
    for j in 0..s.len() {
        let basis: Vec<f32> =
            (0..c * w * h * 3).map(|i| 0.01 * ((i * 7 + j) % 13) as f32).collect();
        let (eigentextures, scale_offset) = quantize(&basis, c, Quantization::F16);
        let slot = QuantizedSlot {
            mean: vec![0.25; w * h * 3],
            eigentextures,
            scale_offset,
            weights: (0..s.len() * c).map(|i| (i % 5) as f32 * 0.1).collect(),
            eigenvalues: vec![1.0; s.len()],
        };
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
}

/// A quad `x0..x1 × y0..y1` at height `z`, normal +z, UVs of its corners.
fn quad(x0: f64, x1: f64, y0: f64, y1: f64, z: f64) -> String {
    format!(
        "v {x0} {y0} {z}\nv {x1} {y0} {z}\nv {x1} {y1} {z}\nv {x0} {y1} {z}\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n\
         f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
    )
}

/// The scene text: `occluder` is the BTF mesh, `extra` appended to the `[[yarns]]` entry.
fn scene_text(msaa: u32, extra: &str) -> String {
    format!(
        r#"
[output]
width = {SIZE}
height = {SIZE}
background = [0.05, 0.1, 0.2]
[[meshes]]
path = "occluder.obj"
[[materials]]
store = "m.eigen"
[[yarns]]
chart = "stockinette"
mesh = "carrier.obj"
uv_origin = [0.05, 0.1]
wales = 2
courses = 2
lod_px = 1.0
{extra}
[camera]
projection = "orthographic"
eye = [0.005, 0.005, 0.05]
target = [0.005, 0.005, 0.0]
up = [0.0, 1.0, 0.0]
ortho_height = 0.01
[[lights]]
kind = "directional"
direction = [0.3, 0.4, 1.0]
irradiance = [2.0, 2.0, 2.0]
[effects]
msaa = {msaa}
"#
    )
}

struct Setup {
    _dir: tempfile::TempDir,
    path: PathBuf,
}

/// A folder with the store, the carrier and the BTF mesh `occluder`, and the scene.
fn setup(occluder: &str, scene: &str) -> Setup {
    let dir = tempfile::tempdir().unwrap();
    tiny_store(dir.path());
    std::fs::write(dir.path().join("carrier.obj"), quad(0.0, 0.01, 0.0, 0.01, 0.0)).unwrap();
    std::fs::write(dir.path().join("occluder.obj"), occluder).unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    Setup { _dir: dir, path }
}

/// The composite (BTF pass + yarns), the meshes alone with the same camera, and the
/// standalone fiber image of the same yarns, camera and lights over the background.
fn render_three(gpu: &Gpu, path: &Path) -> (Frame, Frame, FiberImage) {
    let scene = Scene::load(path).unwrap();
    let yarns = yarn_render::scene::build(&scene, path).unwrap();
    let options = RenderOptions { extra_bounds: bounds_f32(&yarns), ..Default::default() };
    let mut meshes = Renderer::new(gpu, &scene, options).unwrap();
    let alone = meshes.render(gpu).unwrap();
    let mut both = Renderer::new(gpu, &scene, options).unwrap();
    both.add_overlay(Box::new(YarnOverlay::new(gpu, &scene, &yarns, None).unwrap()));
    let composite = both.render(gpu).unwrap();
    let d = &scene.yarns[0];
    let bake = yarn_precompute::BakeSettings { seed: d.seed, ..Default::default() };
    let fibers = FiberRenderer::with_bake(
        gpu,
        &yarns[0].packed,
        &scene_bcsdf().unwrap(),
        settings(&scene, d),
        &bake,
        None,
    )
    .unwrap();
    let cam = fiber_camera(both.camera());
    let [r, g, b] = scene.output.background.map(f64::from);
    let img = fibers
        .render(gpu, &cam, &fiber_lights(&scene.lights), (SIZE, SIZE), [r, g, b, 0.0])
        .unwrap();
    (composite, alone, img)
}

fn rgb_of(f: &Frame, i: usize) -> [f32; 3] {
    [f.rgb[3 * i], f.rgb[3 * i + 1], f.rgb[3 * i + 2]]
}

fn fiber_rgb(img: &FiberImage, i: usize) -> [f32; 3] {
    let p = img.pixels[i];
    [p[0], p[1], p[2]]
}

#[test]
fn yarns_through_the_scene_path_equal_the_standalone_fiber_renderer() {
    let Some(gpu) = Gpu::for_tests("yarns_through_the_scene_path") else { return };
    // The scene's one BTF mesh lies outside the frustum: only the yarns are seen.
    let far_away = quad(0.5, 0.51, 0.5, 0.51, 0.0);
    for msaa in [1, 4] {
        let s = setup(&far_away, &scene_text(msaa, ""));
        let (composite, alone, img) = render_three(&gpu, &s.path);
        let n = (SIZE * SIZE) as usize;
        let covered = (0..n).filter(|&i| img.pixels[i][3] > 0.0).count();
        let differ = (0..n).filter(|&i| rgb_of(&composite, i) != fiber_rgb(&img, i)).count();
        let worst = (0..n)
            .flat_map(|i| {
                let (a, b) = (rgb_of(&composite, i), fiber_rgb(&img, i));
                (0..3).map(move |c| (a[c] - b[c]).abs())
            })
            .fold(0.0f32, f32::max);
        // (f16 under MSAA: the background within its rounding)
        let is_bg = |p: [f32; 3]| p.iter().zip([0.05, 0.1, 0.2]).all(|(a, b)| (a - b).abs() < 1e-3);
        let background = (0..n).filter(|&i| is_bg(rgb_of(&alone, i))).count();
        eprintln!(
            "msaa {msaa}: {covered} of {n} pixels with yarn, {differ} differ from the \
             standalone image (worst {worst:e}); meshes alone: {background} background pixels"
        );
        assert!(covered > n / 5, "the patch must fill a good part of the frame: {covered}");
        assert_eq!(background, n, "the BTF mesh must be outside the frame");
        assert_eq!(differ, 0, "bit-identical expected; worst difference {worst:e}");
    }
}

/// The occluder covers `x < 5 mm`, i.e. columns `< SIZE/2` exactly (0.01 m over SIZE px).
fn column(i: usize) -> usize {
    i % SIZE as usize
}

#[test]
fn an_opaque_mesh_hides_the_yarns_behind_it_and_yarns_hide_the_mesh_behind_them() {
    let Some(gpu) = Gpu::for_tests("an_opaque_mesh_hides_the_yarns") else { return };
    let n = (SIZE * SIZE) as usize;
    let half = SIZE as usize / 2;
    // In front: the yarns reach 1 mm above the carrier, the quad is at 3 mm.
    let front = setup(&quad(-0.01, 0.005, -0.01, 0.02, 0.003), &scene_text(1, ""));
    let (c, o, y) = render_three(&gpu, &front.path);
    let yarn = |i: usize| y.pixels[i][3] > 0.0;
    let hidden_yarn = (0..n).filter(|&i| column(i) + 1 < half && yarn(i)).count();
    let left_wrong =
        (0..n).filter(|&i| column(i) + 1 < half && rgb_of(&c, i) != rgb_of(&o, i)).count();
    let right_wrong =
        (0..n).filter(|&i| column(i) > half && rgb_of(&c, i) != fiber_rgb(&y, i)).count();
    let occluder = (0..n).filter(|&i| rgb_of(&o, i) != [0.05, 0.1, 0.2]).count();
    eprintln!(
        "front quad: {occluder} quad pixels (expected {}), {hidden_yarn} yarn pixels behind \
         it; {left_wrong} pixels left of the band differ from the quad alone, {right_wrong} \
         right of it from the yarns alone",
        n / 2
    );
    assert!(hidden_yarn > n / 10, "the quad must cover yarns: {hidden_yarn}");
    assert!(occluder.abs_diff(n / 2) <= SIZE as usize, "quad projection: {occluder}");
    assert_eq!(left_wrong, 0);
    assert_eq!(right_wrong, 0);
    // Behind: a quad over the whole frame 3 mm below the carrier.
    let back = setup(&quad(-0.01, 0.02, -0.01, 0.02, -0.003), &scene_text(1, ""));
    let (c, o, y) = render_three(&gpu, &back.path);
    let yarn = |i: usize| y.pixels[i][3] > 0.0;
    let shown = (0..n).filter(|&i| yarn(i)).count();
    let yarn_wrong = (0..n).filter(|&i| yarn(i) && rgb_of(&c, i) != fiber_rgb(&y, i)).count();
    let mesh_wrong = (0..n).filter(|&i| !yarn(i) && rgb_of(&c, i) != rgb_of(&o, i)).count();
    let mesh_everywhere = (0..n).filter(|&i| rgb_of(&o, i) != [0.05, 0.1, 0.2]).count();
    eprintln!(
        "back quad: {mesh_everywhere} of {n} quad pixels; {shown} yarn pixels, \
         {yarn_wrong} of them not the yarn's radiance, {mesh_wrong} others not the quad's"
    );
    assert_eq!(mesh_everywhere, n);
    assert!(shown > n / 5);
    assert_eq!(yarn_wrong, 0);
    assert_eq!(mesh_wrong, 0);
}
