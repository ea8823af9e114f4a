//! Thin semi-transparent cloth (the transmission effect, `[TC eq. 7–9]`): the rendered
//! sheet against the slab formulas of `btf_core::thin_slab` (back-lit, front-lit, layers),
//! the limits τ₁ → 0 (what is behind shows through unchanged) and τ₁ → ∞ (the opaque BTF
//! render), and the paper's Fig. 2 contrast between a back-lit and a front-lit curtain.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_core::thin_slab::{direct_transmittance, reflection_share, transmission_factor};
use btf_render::scene::{Albedo, Evaluation, Light, PhaseDesc, TauTexture, TransmissionDesc};
use btf_render::{Frame, RenderOptions, Scene, render_scene};
use std::f64::consts::PI;
use std::path::Path;

/// A unit sheet `[0,1]²` at height `z`, normal `+z`, faces tagged `usemtl mtl`.
fn sheet_obj(n: usize, z: f32, mtl: &str) -> String {
    let mut s = format!("usemtl {mtl}\n");
    for line in plane_obj(n, false).lines() {
        match line.strip_prefix("v ") {
            Some(rest) => {
                let xy: Vec<&str> = rest.split(' ').take(2).collect();
                s += &format!("v {} {} {z}\n", xy[0], xy[1]);
            }
            None => s += &format!("{line}\n"),
        }
    }
    s
}

const TOP_CAMERA: Ortho = Ortho { eye: [0.5, 0.5, 2.0], target: [0.5, 0.5, 0.0], height: 0.8 };

const BG: [f32; 3] = [0.2, 0.3, 0.4];

/// A named material of the store `m.eigen`, thin (`Some`) or opaque.
type Mat = (&'static str, Option<TransmissionDesc>);

/// The sheets `meshes` seen from above under `lights`, with `materials`.
fn top_scene(
    dir: &Path,
    meshes: &[&str],
    materials: &[Mat],
    lights: &[Light],
    evaluation: Evaluation,
) -> Scene {
    let mut b = SceneBuilder::new(dir, 24).output(|o| o.background = BG).ortho(TOP_CAMERA);
    for m in meshes {
        b = b.mesh(m);
    }
    for (name, t) in materials {
        b = b.material_with(Some(name), "m.eigen", 1.0, t.clone());
    }
    for l in lights {
        b = b.light(l.clone());
    }
    b.effects(|e| e.evaluation = evaluation).build()
}

/// A thin material: optical thickness `tau`, albedo `albedo`, isotropic.
fn slab(tau: f64, albedo: f64) -> Option<TransmissionDesc> {
    Some(TransmissionDesc { albedo: Albedo::Grey(albedo as f32), ..thin(tau as f32) })
}

fn render(gpu: &btf_render::Gpu, scene: &Scene) -> Frame {
    let f = render_scene(gpu, scene, RenderOptions::default()).unwrap();
    assert!(f.all_finite());
    f
}

fn sun(direction: [f32; 3], e: f32) -> Light {
    Light::Directional { direction, irradiance: [e; 3], shadows: true }
}

fn assert_pixels(name: &str, f: &Frame, expected: impl Fn(usize) -> f64, tol: f64) {
    for (i, &v) in f.rgb.iter().enumerate() {
        let e = expected(i);
        assert!(
            ((v as f64) - e).abs() <= tol * e.abs().max(1e-3),
            "{name}: value {i} = {v}, expected {e}"
        );
    }
}

#[test]
fn back_lit_sheet_is_direct_transmission_plus_single_scattering() {
    let Some(gpu) = gpu("back_lit_sheet_is_direct_transmission_plus_single_scattering") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 8, 8, 4, Quantization::F16);
    write(dir.path(), "sheet.obj", &sheet_obj(2, 0.0, "voile"));
    let (tau, albedo, e) = (0.3, 0.8, 2.0);
    let mu0 = 1.0 / 1.09f64.sqrt();
    let light = [sun([0.3, 0.0, -1.0], e)];
    let pp = Evaluation::PerPixel;
    let f = render(
        &gpu,
        &top_scene(dir.path(), &["sheet.obj"], &[("voile", slab(tau, albedo))], &light, pp),
    );
    // μ = 1 (orthographic, straight down); light from below at μ₀ on the far face.
    let t = direct_transmittance(tau, 1.0);
    let sheet = albedo / (4.0 * PI) * transmission_factor(tau, 1.0, mu0) * mu0 * e as f64;
    assert_pixels("back-lit", &f, |i| BG[i % 3] as f64 * t + sheet, 1e-4);
    // Henyey–Greenstein: the same times p(cos Θ), cos Θ = −l·v = μ₀ (forward).
    let g = 0.4f64;
    let p = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * mu0).powf(1.5);
    let hg = Some(TransmissionDesc {
        phase: PhaseDesc::Hg { hg: g as f32 },
        ..slab(tau, albedo).unwrap()
    });
    let f =
        render(&gpu, &top_scene(dir.path(), &["sheet.obj"], &[("voile", hg.clone())], &light, pp));
    assert_pixels("back-lit HG", &f, |i| BG[i % 3] as f64 * t + sheet * p, 1e-4);
    // In a per-vertex scene the thin material is still evaluated per pixel, with an
    // opaque per-vertex material bound beside it.
    write(dir.path(), "floor.obj", &sheet_obj(2, -0.5, "floor"));
    let mats = [("voile", hg), ("floor", None)];
    let pv = Evaluation::PerVertex;
    let f = render(&gpu, &top_scene(dir.path(), &["floor.obj", "sheet.obj"], &mats, &light, pv));
    // The floor below is lit from below too: black, so only the sheet's own light shows.
    assert_pixels("per-vertex scene", &f, |_| sheet * p, 1e-4);
}

#[test]
fn front_lit_sheet_reflects_its_share_of_the_btf() {
    let Some(gpu) = gpu("front_lit_sheet_reflects_its_share_of_the_btf") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 8, 8, 4, Quantization::F16);
    write(dir.path(), "sheet.obj", &sheet_obj(2, 0.0, "voile"));
    let (light, pp) = ([sun([0.3, 0.0, 1.0], 2.0)], Evaluation::PerPixel);
    let opaque =
        render(&gpu, &top_scene(dir.path(), &["sheet.obj"], &[("voile", None)], &light, pp));
    let tau = 0.25;
    let mat = [("voile", slab(tau, 0.7))];
    let thin = render(&gpu, &top_scene(dir.path(), &["sheet.obj"], &mat, &light, pp));
    let mu0 = 1.0 / 1.09f64.sqrt();
    let (t, share) = (direct_transmittance(tau, 1.0), reflection_share(tau, 1.0, mu0));
    let expected: Vec<f32> = opaque
        .rgb
        .iter()
        .enumerate()
        .map(|(i, &r)| (BG[i % 3] as f64 * t + share * r as f64) as f32)
        .collect();
    assert_close("front-lit", 24, 24, &expected, &thin.rgb, 1e-4);
    assert!(opaque.rgb.iter().sum::<f32>() > 0.0);
}

#[test]
fn layers_composite_back_to_front_whatever_the_mesh_order() {
    let Some(gpu) = gpu("layers_composite_back_to_front_whatever_the_mesh_order") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 8, 8, 4, Quantization::F16);
    write(dir.path(), "low.obj", &sheet_obj(2, 0.0, "shirt"));
    write(dir.path(), "high.obj", &sheet_obj(2, 0.3, "scarf"));
    let (tau_a, alb_a, tau_b, alb_b, e) = (0.5, 0.9, 0.15, 0.4, 3.0);
    let mats = [("shirt", slab(tau_a, alb_a)), ("scarf", slab(tau_b, alb_b))];
    let light = [sun([0.0, 0.4, -1.0], e)];
    let mu0 = 1.0 / 1.16f64.sqrt();
    let sheet =
        |tau: f64, alb: f64| alb / (4.0 * PI) * transmission_factor(tau, 1.0, mu0) * mu0 * e as f64;
    let (ta, tb) = (direct_transmittance(tau_a, 1.0), direct_transmittance(tau_b, 1.0));
    // The eye is above: the lower sheet first, then the upper one over it (eq. 9 twice).
    let expected =
        |i: usize| (BG[i % 3] as f64 * ta + sheet(tau_a, alb_a)) * tb + sheet(tau_b, alb_b);
    for order in [["low.obj", "high.obj"], ["high.obj", "low.obj"]] {
        let f = render(&gpu, &top_scene(dir.path(), &order, &mats, &light, Evaluation::PerPixel));
        assert_pixels(&format!("layers {order:?}"), &f, expected, 1e-4);
    }
    // The wrong order would differ by far more than the tolerance.
    let wrong = (BG[0] as f64 * tb + sheet(tau_b, alb_b)) * ta + sheet(tau_a, alb_a);
    assert!((wrong - expected(0)).abs() > 1e-2 * expected(0));
}

#[test]
fn thickness_texture_from_an_image_and_from_the_btf_mean() {
    let Some(gpu) = gpu("thickness_texture_from_an_image_and_from_the_btf_mean") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 8, 8, 4, Quantization::F16);
    write(dir.path(), "sheet.obj", &sheet_obj(2, 0.0, "voile"));
    image::GrayImage::from_pixel(4, 4, image::Luma([128u8]))
        .save(dir.path().join("tau.png"))
        .unwrap();
    let (no_light, pp) = (&[], Evaluation::PerPixel);
    let textured = |tau: f32, texture: TauTexture| {
        [("voile", Some(TransmissionDesc { tau_texture: Some(texture), ..thin(tau) }))]
    };
    let mat = textured(1.0, TauTexture::Image("tau.png".into()));
    let f = render(&gpu, &top_scene(dir.path(), &["sheet.obj"], &mat, no_light, pp));
    let t = direct_transmittance(128.0 / 255.0, 1.0);
    assert_pixels("tau.png", &f, |i| BG[i % 3] as f64 * t, 2e-3);
    // A uniform BTF mean normalises to 1: the same as the scalar thickness.
    let mat = textured(0.6, TauTexture::BtfMean);
    let f = render(&gpu, &top_scene(dir.path(), &["sheet.obj"], &mat, no_light, pp));
    assert_pixels("btf-mean", &f, |i| BG[i % 3] as f64 * direct_transmittance(0.6, 1.0), 2e-3);
    // A bad texture is refused with the file named.
    let mat = textured(1.0, TauTexture::Image("missing.png".into()));
    let scene = top_scene(dir.path(), &["sheet.obj"], &mat, no_light, pp);
    let err = render_scene(&gpu, &scene, RenderOptions::default()).err().unwrap().to_string();
    assert!(err.contains("missing.png"), "{err}");
}

#[test]
fn scene_keys_are_validated() {
    let dir = tempfile::tempdir().unwrap();
    let base = |t: &str| {
        let text = format!(
            "[[meshes]]\npath = \"a.obj\"\n[[materials]]\nstore = \"m.eigen\"\ntransmission = {t}\n\
         [camera]\neye = [0.5, 0.5, 2.0]\ntarget = [0.5, 0.5, 0.0]\n"
        );
        Scene::load(&write(dir.path(), "s.toml", &text)).map(|_| ()).map_err(|e| e.to_string())
    };
    assert!(base("{ tau = 0.2, albedo = [0.9, 0.8, 0.7], phase = { hg = 0.3 } }").is_ok());
    assert!(base("{ tau = -1 }").unwrap_err().contains("materials[0].transmission.tau"));
    assert!(base("{ tau = 0.2, albedo = 1.5 }").unwrap_err().contains("transmission.albedo"));
    assert!(base("{ tau = 0.2, phase = { hg = 1.0 } }").unwrap_err().contains("phase.hg"));
    assert!(base("{ tau = 0.2, phase = \"rayleigh\" }").unwrap_err().contains("rayleigh"));
    assert!(base("{ tau = 0.2, thickness = 3 }").unwrap_err().contains("thickness"));
}

/// A wall `x ∈ [−1, 1]`, `z ∈ [−0.3, 1.8]` at `y = 0.8` facing `−y`, `usemtl wall`.
fn wall_obj() -> String {
    let mut s = String::from("usemtl wall\n");
    for (x, z) in [(-1.0, -0.3), (1.0, -0.3), (1.0, 1.8), (-1.0, 1.8)] {
        s += &format!("v {x} 0.8 {z}\nvt {} {}\nvn 0 -1 0\n", (x + 1.0) / 2.0, (z + 0.3) / 2.1);
    }
    s + "f 1/1/1 2/2/2 3/3/3\nf 1/1/1 3/3/3 4/4/4\n"
}

struct CurtainSet {
    dir: tempfile::TempDir,
}

const FRONT_LIGHT: ([f32; 3], f32) = ([0.3, -1.0, 1.0], 1.0);
const BACK_LIGHT: ([f32; 3], f32) = ([0.3, 0.45, 1.0], 0.25);

impl CurtainSet {
    fn new() -> CurtainSet {
        let dir = tempfile::tempdir().unwrap();
        write_store(dir.path(), "voile.eigen", Pattern::Checker, 16, 16, 4, Quantization::F16);
        write_store(dir.path(), "wall.eigen", Pattern::Ribs, 16, 16, 4, Quantization::F16);
        synth_mesh(dir.path(), "curtain.obj", datasets::MeshKind::Curtain);
        write(dir.path(), "wall.obj", &wall_obj());
        CurtainSet { dir }
    }

    /// The curtain (when `curtain` is `Some`: thin with `Some(transmission)`, else opaque)
    /// in front of the wall (when `wall`), lit by the point light `(position, intensity)`.
    fn scene(
        &self,
        curtain: Option<Option<TransmissionDesc>>,
        wall: bool,
        (position, intensity): ([f32; 3], f32),
    ) -> Scene {
        let mut b = SceneBuilder::new(self.dir.path(), 48);
        if curtain.is_some() {
            b = b.mesh("curtain.obj");
        }
        if wall {
            b = b.mesh("wall.obj");
        }
        b.material_with(Some("wall"), "wall.eigen", 3.0, None)
            .material_with(None, "voile.eigen", 4.0, curtain.flatten())
            .perspective([0.0, -2.6, 0.75], [0.0, 0.0, 0.75], [0.0, 0.0, 1.0], 40.0)
            .light(point(position, intensity))
            .build()
    }
}

#[test]
fn curtain_limits_transparent_and_opaque() {
    let Some(gpu) = gpu("curtain_limits_transparent_and_opaque") else { return };
    let set = CurtainSet::new();
    for (side, light) in [("front", FRONT_LIGHT), ("back", BACK_LIGHT)] {
        // τ₁ → ∞: alpha 0, full share of the BTF, no transmitted light: the opaque render.
        let opaque = render(&gpu, &set.scene(Some(None), true, light));
        let thick = render(&gpu, &set.scene(Some(slab(1e4, 1.0)), true, light));
        assert_close(&format!("thick-{side}"), 48, 48, &opaque.rgb, &thick.rgb, 1e-5);
        // τ₁ → 0: the wall behind shows through unchanged (with a per-texel thickness too).
        let wall = render(&gpu, &set.scene(None, true, light));
        let clear =
            TransmissionDesc { tau_texture: Some(TauTexture::BtfMean), ..slab(1e-6, 1.0).unwrap() };
        let clear = render(&gpu, &set.scene(Some(Some(clear)), true, light));
        assert_close(&format!("clear-{side}"), 48, 48, &wall.rgb, &clear.rgb, 1e-5);
        assert!(rel_rmse(&wall.rgb, &opaque.rgb) > 0.05, "the curtain must be visible when opaque");
    }
}

/// Per-pixel direct transmittance and sheet radiance of the curtain, from renders with
/// and without the wall behind it: `R_wall = W · T + S`, `R_nowall = S`.
fn separate(
    gpu: &btf_render::Gpu,
    set: &CurtainSet,
    t: &TransmissionDesc,
    light: ([f32; 3], f32),
) -> (Vec<f32>, Vec<f32>, Frame) {
    let with = render(gpu, &set.scene(Some(Some(t.clone())), true, light));
    let without = render(gpu, &set.scene(Some(Some(t.clone())), false, light));
    let wall = render(gpu, &set.scene(None, true, light));
    let alpha = (0..with.rgb.len())
        .map(|i| {
            if wall.rgb[i] > 1e-3 { (with.rgb[i] - without.rgb[i]) / wall.rgb[i] } else { f32::NAN }
        })
        .collect();
    (alpha, without.rgb, with)
}

#[test]
fn back_lit_and_front_lit_curtain_differ_as_in_fig_2() {
    let Some(gpu) = gpu("back_lit_and_front_lit_curtain_differ_as_in_fig_2") else { return };
    let set = CurtainSet::new();
    // The paper's Fig. 2 values: ϖ₀ = 1, τ₁ = 2 (here per texel from the BTF mean).
    let t = TransmissionDesc { tau_texture: Some(TauTexture::BtfMean), ..slab(2.0, 1.0).unwrap() };
    let (alpha_f, sheet_f, with_f) = separate(&gpu, &set, &t, FRONT_LIGHT);
    let (alpha_b, sheet_b, with_b) = separate(&gpu, &set, &t, BACK_LIGHT);
    let d = artifact_dir();
    with_b.write_png(&d.join("fig2-back-lit.png"), 3.0).unwrap();
    with_f.write_png(&d.join("fig2-front-lit.png"), 3.0).unwrap();
    // Curtain pixels: where something blocks the wall.
    let mask: Vec<usize> = (0..alpha_f.len()).filter(|&i| alpha_f[i] < 0.999).collect();
    assert!(mask.len() > alpha_f.len() / 4, "curtain covers {} values", mask.len());
    // The direct transmission (the alpha) is the same front- and back-lit (paper §4).
    let worst = mask.iter().map(|&i| (alpha_f[i] - alpha_b[i]).abs()).fold(0f32, f32::max);
    assert!(worst < 2e-3, "alpha differs by {worst}");
    // Front-lit the sheet is brighter; back-lit it is darker, so more of what lies behind
    // makes up the pixel: it looks more transparent.
    let mean = |v: &[f32]| mask.iter().map(|&i| v[i] as f64).sum::<f64>() / mask.len() as f64;
    let (bright_f, bright_b) = (mean(&sheet_f), mean(&sheet_b));
    let behind = |with: &Frame, sheet: &[f32]| {
        mask.iter().map(|&i| (with.rgb[i] - sheet[i]) as f64).sum::<f64>()
            / mask.iter().map(|&i| with.rgb[i] as f64).sum::<f64>()
    };
    let (share_f, share_b) = (behind(&with_f, &sheet_f), behind(&with_b, &sheet_b));
    eprintln!(
        "sheet radiance front {bright_f:.4} back {bright_b:.4}; background share front {share_f:.3} back {share_b:.3}"
    );
    assert!(bright_f > 2.0 * bright_b, "front {bright_f} vs back {bright_b}");
    assert!(share_b > share_f + 0.1, "background share back {share_b} vs front {share_f}");
    assert!(bright_b > 0.0, "back-lit light must come through");
}
