//! The rendering half of `btf demo`: a garment mesh and an HDR sky are synthesised, scene
//! files are written beside them (so a user can edit and re-render them with `btf render`),
//! and the garment is rendered with the demo's eigen store under a point light with shadows,
//! without shadows, and under the sky as an environment light (per-vertex visibility maps
//! and weights, Sattler et al. 2003 §5; exposure `f` chosen so that the sky's horizontal
//! irradiance is 1).

use anyhow::{Context, Result};
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use datasets::{EnvKind, EnvParams, MeshKind, Resolution};
use std::fmt::Write as _;
use std::path::Path;

/// A demo stage runner: `(name, already done, work)`.
pub type StageFn<'a> =
    dyn FnMut(&'static str, bool, Box<dyn FnOnce() -> Result<()> + '_>) -> Result<()> + 'a;

/// Bounding box of a mesh: `(min, max)`.
fn bounds(mesh: &datasets::Mesh) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// What lights a demo scene.
#[derive(Clone, Copy)]
enum Lighting {
    /// Point light (shadows "volume" or "none") plus a dim directional fill.
    Point(&'static str),
    /// The sky as an environment light of exposure `f`.
    Environment(f64),
}

fn scene_toml(width: u32, (lo, hi): ([f64; 3], [f64; 3]), lighting: Lighting) -> String {
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0f64, f64::max);
    // The garments are z-up with their front facing −y.
    let eye = [c[0] + 0.35 * size, c[1] - 1.9 * size, c[2] + 0.2 * size];
    let light = [c[0] - 0.8 * size, c[1] - 1.4 * size, c[2] + 1.0 * size];
    let d2 = (0..3).map(|k| (light[k] - c[k]).powi(2)).sum::<f64>();
    // Intensity chosen so the irradiance at the garment's centre is 3 (a bright room).
    let i = 3.0 * d2;
    let (lights, shadows) = match lighting {
        Lighting::Point(shadows) => (point_lights(light, i), shadows),
        Lighting::Environment(f) => (environment_light(f), "none"),
    };
    format!(
        r#"# Written by `btf demo`: the demo garment in the demo material.
# Re-render with: btf render {{this file}} -o out.png --stats
[output]
width = {width}
height = {height}
exposure = 1.6
background = [0.03, 0.03, 0.04]

[[meshes]]
path = "garment.obj"

[[materials]]
store = "material.eig"
uv_scale = 6.0

[camera]
eye = [{:.3}, {:.3}, {:.3}]
target = [{:.3}, {:.3}, {:.3}]
up = [0.0, 0.0, 1.0]
fov_y_deg = 38.0

{lights}
[effects]
evaluation = "per-pixel"
light_interp = "four"
view_blend = "four"
shadows = "{shadows}"
terminator_deg = 15.0
msaa = 4
"#,
        eye[0],
        eye[1],
        eye[2],
        c[0],
        c[1],
        c[2],
        height = width * 3 / 4,
    )
}

fn point_lights(light: [f64; 3], i: f64) -> String {
    format!(
        r#"[[lights]]
kind = "point"
position = [{:.3}, {:.3}, {:.3}]
intensity = [{i:.3}, {:.3}, {:.3}]

[[lights]]
kind = "directional"
direction = [0.6, -1.0, 0.3]
irradiance = [0.25, 0.28, 0.35]
shadows = false
"#,
        light[0],
        light[1],
        light[2],
        i * 0.97,
        i * 0.9,
    )
}

fn environment_light(exposure: f64) -> String {
    format!(
        r#"[[lights]]
kind = "environment"
path = "sky.exr"          # equirectangular, +z up
rotation_deg = 240.0      # turns the sun (azimuth 30°) round to the garment's front
exposure = {exposure:.6e}  # horizontal irradiance of the sky → 1
visibility_res = 16       # hemicube pixels across the top face, per vertex
two_sided = true
cache_dir = "cache"       # visibility maps are kept here
"#
    )
}

/// Runs the mesh, environment and render stages; returns the report section.
pub fn run(out: &Path, width: u32, stage: &mut StageFn<'_>) -> Result<String> {
    let mesh_path = out.join("garment.obj");
    let env_path = out.join("sky.exr");
    let mesh = datasets::synth_mesh(MeshKind::Shirt, Resolution::Low)?;
    stage(
        "garment mesh",
        mesh_path.exists(),
        Box::new(|| Ok(datasets::write_obj(&mesh, &mesh_path, "btf demo: shirt, low resolution")?)),
    )?;
    stage(
        "HDR sky",
        env_path.exists(),
        Box::new(|| {
            Ok(datasets::synth_env(EnvKind::Sky, &EnvParams::default(), 512)?
                .write_exr(&env_path)?)
        }),
    )?;
    let env_exposure = btf_image::EnvMap::load(&env_path)?.unit_irradiance_exposure();
    let mut md = String::from("## Renders\n\n");
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) if std::env::var("BTF_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            return Err(e).context("BTF_REQUIRE_GPU=1 but no GPU adapter");
        }
        Err(e) => {
            let msg = "no GPU adapter (install `mesa-vulkan-drivers` for the CPU one)";
            eprintln!("warning: {msg}: {e}; renders skipped");
            writeln!(md, "Renders skipped: {msg}: {e}.")?;
            return Ok(md);
        }
    };
    let b = bounds(&mesh);
    let renders = [
        ("point", "render point light", Lighting::Point("volume")),
        ("point-noshadow", "render without shadows", Lighting::Point("none")),
        ("environment", "render environment", Lighting::Environment(env_exposure)),
    ];
    for (name, stage_name, lighting) in renders {
        let scene_path = out.join(format!("scene-{name}.toml"));
        let png = out.join(format!("render-{name}.png"));
        btf_image::write::write_text(&scene_path, &scene_toml(width, b, lighting))?;
        let mut stats = None;
        stage(
            stage_name,
            false,
            Box::new(|| {
                let scene = Scene::load(&scene_path)
                    .with_context(|| format!("loading {}", scene_path.display()))?;
                let mut renderer = Renderer::new(&gpu, &scene, RenderOptions::default())?;
                let frame = renderer.render(&gpu)?;
                anyhow::ensure!(frame.all_finite(), "the render has non-finite pixels");
                frame.write_png(&png, scene.output.exposure)?;
                frame.write_exr(&png.with_extension("exr"))?;
                stats = Some(frame.stats.clone());
                Ok(())
            }),
        )?;
        writeln!(
            md,
            "### {name} (`{}`)\n\n![{name}](render-{name}.png)\n",
            scene_path.file_name().unwrap().to_string_lossy()
        )?;
        if let Some(s) = stats {
            writeln!(md, "| pass | ms (lavapipe) |\n|---|---:|")?;
            for p in &s.setup {
                writeln!(md, "| {} (setup, once) | {:.2} |", p.name, p.ms)?;
            }
            for p in &s.passes {
                writeln!(md, "| {} | {:.2} |", p.name, p.ms)?;
            }
            writeln!(md, "| frame | {:.2} |\n", s.frame_ms)?;
        }
    }
    writeln!(
        md,
        "The environment render lights the garment by `sky.exr` with per-vertex visibility maps (cached in `cache/`); `btf relight scene-environment.toml --env sky.exr --rotations 12 --eigen 5 -o relight` turns it.\n"
    )?;
    Ok(md)
}
