//! The scene description: a plain, serialisable TOML document (meshes, materials, camera,
//! lights, effects, output) kept apart from the GPU objects built from it.
//!
//! Lights follow the radiometry of DESIGN.md §3: a directional light gives perpendicular
//! irradiance `E` (`L = BTF · E`), a point light has intensity `I` (`L = BTF · I / d²`).
//! Relative paths are resolved against the scene file's folder. Validation names the key.

mod effects;
mod light;
mod transmission;
mod yarns;

pub use crate::uniforms::MAX_LIGHTS;
pub use effects::{Effects, Evaluation, Shadows};
pub use light::{EigenSets, EnvironmentLight, Light};
pub use transmission::{Albedo, MAX_TAU, PhaseDesc, TauTexture, TransmissionDesc};
pub use yarns::{MAX_STITCHES, MAX_WALES, YarnAo, YarnMethod, YarnsDesc, names_file};

use crate::{Error, Result};
use btf_light::mesh::PlanarUv;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A whole scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Image size, exposure, background.
    #[serde(default)]
    pub output: Output,
    /// Meshes (all drawn; none in a scene of `[[yarns]]` alone).
    #[serde(default)]
    pub meshes: Vec<MeshDesc>,
    /// BTF materials, matched to mesh material names (none without meshes).
    #[serde(default)]
    pub materials: Vec<MaterialDesc>,
    /// The camera.
    pub camera: Camera,
    /// Point, directional and (at most one) environment lights, at most [`MAX_LIGHTS`].
    #[serde(default)]
    pub lights: Vec<Light>,
    /// What to compute and how.
    #[serde(default)]
    pub effects: Effects,
    /// Knit patches drawn as fiber-level yarns next to the meshes (data here; drawn by
    /// `yarn-render` through [`crate::renderer::Overlay`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub yarns: Vec<YarnsDesc>,
}

/// Image output parameters.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear scale applied before the sRGB PNG encoding (the EXR stays unscaled).
    pub exposure: f32,
    /// Linear background radiance.
    pub background: [f32; 3],
    /// Draw the environment light's map (rotated, times its exposure) behind the scene
    /// instead of `background` (needs an environment light).
    pub show_environment: bool,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            width: 512,
            height: 512,
            exposure: 1.0,
            background: [0.0; 3],
            show_environment: false,
        }
    }
}

/// One OBJ mesh.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// OBJ file.
    pub path: PathBuf,
    /// Planar UV projection for meshes without texture coordinates.
    #[serde(default)]
    pub planar_uv: Option<PlanarUv>,
}

/// A BTF material: an eigen store applied to faces whose OBJ material (`usemtl`) has the
/// given name, or to all remaining faces when `name` is absent.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// `usemtl` name to match; `None` = every face not matched by another material.
    #[serde(default)]
    pub name: Option<String>,
    /// Eigen store folder (`btf compress` output).
    pub store: PathBuf,
    /// Texture repetitions per unit of UV.
    #[serde(default = "one")]
    pub uv_scale: f32,
    /// Thin semi-transparent cloth (`transmission = { tau = …, albedo = …, phase = … }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<TransmissionDesc>,
}

fn one() -> f32 {
    1.0
}

/// Camera projection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Pinhole camera with vertical field of view `fov_y_deg`.
    #[default]
    Perspective,
    /// Parallel projection of a window `ortho_height` high.
    Orthographic,
}

/// The camera.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Projection kind.
    #[serde(default)]
    pub projection: Projection,
    /// Eye position (world).
    pub eye: [f32; 3],
    /// Point looked at (world).
    pub target: [f32; 3],
    /// Up direction (world).
    #[serde(default = "up_y")]
    pub up: [f32; 3],
    /// Vertical field of view for perspective cameras, degrees.
    #[serde(default = "fov_default")]
    pub fov_y_deg: f32,
    /// Height of the view window for orthographic cameras (world units).
    #[serde(default = "one")]
    pub ortho_height: f32,
}

fn up_y() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn fov_default() -> f32 {
    40.0
}

impl Scene {
    /// Reads and validates a scene file; relative paths become relative to its folder.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Scene::from_toml(&text, path)
    }

    /// Parses and validates scene text as [`Scene::load`] does for the file at `path`
    /// (which names it in errors and anchors its relative paths; nothing is read from disk).
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| {
            Error::Invalid(format!("{}: {}", path.display(), e.to_string().trim_end()))
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for m in &mut scene.meshes {
            m.path = dir.join(&m.path);
        }
        for m in &mut scene.materials {
            m.store = dir.join(&m.store);
            if let Some(t) = &mut m.transmission {
                t.resolve(dir);
            }
        }
        for y in &mut scene.yarns {
            y.resolve(dir);
        }
        for l in &mut scene.lights {
            if let Light::Environment(e) = l {
                e.path = dir.join(&e.path);
                e.cache_dir = e.cache_dir.as_ref().map(|c| dir.join(c));
            }
        }
        scene.validate(path)?;
        Ok(scene)
    }

    /// Every file the scene reads, each with the name a user knows it by
    /// (`[[meshes]] 0 path`), for commands that must never write over an input.
    pub fn input_paths(&self) -> Vec<(String, PathBuf)> {
        let mut out = Vec::new();
        for (i, m) in self.meshes.iter().enumerate() {
            out.push((format!("[[meshes]] {i} path"), m.path.clone()));
        }
        for (i, m) in self.materials.iter().enumerate() {
            out.push((format!("[[materials]] {i} store"), m.store.clone()));
            if let Some(t) = &m.transmission
                && let Some(TauTexture::Image(p)) = &t.tau_texture
            {
                out.push((format!("[[materials]] {i} transmission.tau_texture"), p.clone()));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            if let Light::Environment(e) = l {
                out.push((format!("[[lights]] {i} path"), e.path.clone()));
            }
        }
        for (i, y) in self.yarns.iter().enumerate() {
            y.input_paths(i, &mut out);
        }
        out
    }

    /// Checks ranges and counts; `path` names the file in errors.
    pub fn validate(&self, path: &Path) -> Result<()> {
        let bad = |key: String, what: &str| {
            Err(Error::Scene { path: path.into(), key, what: what.into() })
        };
        let finite = |v: &[f32]| v.iter().all(|c| c.is_finite());
        let o = &self.output;
        if !(1..=16384).contains(&o.width) || !(1..=16384).contains(&o.height) {
            return bad("output.width/height".into(), "must be in 1..=16384");
        }
        if !(o.exposure.is_finite() && o.exposure > 0.0 && o.exposure <= btf_core::MAX_RADIANCE) {
            return bad("output.exposure".into(), "must be a positive number ≤ 1e12");
        }
        if self.meshes.is_empty() && self.yarns.is_empty() {
            return bad("meshes".into(), "at least one [[meshes]] (or [[yarns]]) entry is needed");
        }
        if self.materials.is_empty() && !self.meshes.is_empty() {
            return bad("materials".into(), "at least one [[materials]] entry is needed");
        }
        if let (true, Some((i, _))) = (self.meshes.is_empty(), self.environment()) {
            return bad(
                format!("lights[{i}]"),
                "an environment light needs a [[meshes]] entry (its visibility maps and \
                 eigenweightsets are the BTF meshes'); [[yarns]] alone take point and \
                 directional lights",
            );
        }
        for (i, m) in self.materials.iter().enumerate() {
            if !(m.uv_scale.is_finite() && m.uv_scale > 0.0) {
                return bad(format!("materials[{i}].uv_scale"), "must be a positive number");
            }
            if let Some(t) = &m.transmission {
                t.validate(path, &format!("materials[{i}].transmission"))?;
            }
        }
        let c = &self.camera;
        if !finite(&c.eye) || !finite(&c.target) || !finite(&c.up) {
            return bad("camera".into(), "eye, target and up must be finite");
        }
        if (0..3).all(|a| c.eye[a] == c.target[a]) {
            return bad("camera.target".into(), "must differ from camera.eye");
        }
        if !(c.fov_y_deg > 0.5 && c.fov_y_deg < 179.0) {
            return bad("camera.fov_y_deg".into(), "must be in (0.5, 179)");
        }
        if !(c.ortho_height.is_finite() && c.ortho_height > 0.0) {
            return bad("camera.ortho_height".into(), "must be a positive number");
        }
        if self.lights.len() > MAX_LIGHTS {
            return bad("lights".into(), &format!("at most {MAX_LIGHTS} lights"));
        }
        if self.lights.iter().filter(|l| matches!(l, Light::Environment(_))).count() > 1 {
            return bad("lights".into(), "at most one environment light");
        }
        for (i, l) in self.lights.iter().enumerate() {
            let (v, power, key) = match l {
                Light::Directional { direction, irradiance, .. } => {
                    (direction, irradiance, "irradiance")
                }
                Light::Point { position, intensity, .. } => (position, intensity, "intensity"),
                Light::Environment(e) => {
                    if let Err((key, what)) = e.validate(&format!("lights[{i}]")) {
                        return bad(key, &what);
                    }
                    continue;
                }
            };
            if !finite(v) || !finite(power) || power.iter().any(|p| *p < 0.0) {
                return bad(
                    format!("lights[{i}]"),
                    &format!("position/direction must be finite and {key} ≥ 0"),
                );
            }
            if power.iter().any(|p| *p > btf_core::MAX_RADIANCE) || v.iter().any(|c| c.abs() > 1e12)
            {
                return bad(
                    format!("lights[{i}].{key}"),
                    "must be at most 1e12 (btf_core::MAX_RADIANCE), and positions within 1e12",
                );
            }
            if let Light::Directional { direction, .. } = l
                && direction.iter().all(|c| *c == 0.0)
            {
                return bad(format!("lights[{i}].direction"), "must not be zero");
            }
        }
        let e = &self.effects;
        if e.components == Some(0) {
            return bad("effects.components".into(), "must be at least 1");
        }
        if !(e.terminator_deg.is_finite() && (0.0..90.0).contains(&e.terminator_deg)) {
            return bad("effects.terminator_deg".into(), "must be in [0, 90)");
        }
        if e.terminator_blur > 256 {
            return bad("effects.terminator_blur".into(), "must be in 0..=256 texels");
        }
        if !(16..=8192).contains(&e.shadow_map_size) {
            return bad("effects.shadow_map_size".into(), "must be in 16..=8192");
        }
        if !(1..=16).contains(&e.anisotropy) {
            return bad("effects.anisotropy".into(), "must be in 1..=16");
        }
        if e.msaa != 1 && e.msaa != 4 {
            return bad("effects.msaa".into(), "must be 1 or 4");
        }
        if o.show_environment && self.environment().is_none() {
            return bad("output.show_environment".into(), "needs an environment light");
        }
        for (i, y) in self.yarns.iter().enumerate() {
            if let Err((key, what)) = y.validate(&format!("yarns[{i}]")) {
                return bad(key, &what);
            }
            if y.method == yarns::YarnMethod::Lumislice && e.msaa != 4 {
                return bad(
                    format!("yarns[{i}].method = \"lumislice\""),
                    &format!(
                        "blends into 4× MSAA targets; the scene has effects.msaa = {}",
                        e.msaa
                    ),
                );
            }
        }
        if !self.yarns.is_empty()
            && let Some(i) = self.materials.iter().position(|m| m.transmission.is_some())
        {
            return bad(
                format!("materials[{i}].transmission"),
                "thin cloth in a scene with [[yarns]] is not supported yet (the yarns would be \
                 drawn over the blended cloth)",
            );
        }
        Ok(())
    }

    /// The environment light and its index in `lights`, if the scene has one.
    pub fn environment(&self) -> Option<(usize, &EnvironmentLight)> {
        self.lights.iter().enumerate().find_map(|(i, l)| match l {
            Light::Environment(e) => Some((i, e)),
            _ => None,
        })
    }

    /// True when some light casts shadows and the scene asks for a shadow technique.
    pub fn wants_shadow_pass(&self) -> bool {
        self.effects.shadows != Shadows::None && self.lights.iter().any(Light::casts_shadows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
        [[meshes]]
        path = "plane.obj"
        [[materials]]
        store = "m.eigen"
        [camera]
        eye = [0, 0, 3]
        target = [0, 0, 0]
        [[lights]]
        kind = "directional"
        direction = [0, 0, 1]
        irradiance = [1, 1, 1]
    "#;

    fn load(text: &str) -> Result<Scene> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.toml");
        std::fs::write(&p, text).unwrap();
        Scene::load(&p)
    }

    #[test]
    fn minimal_scene_gets_defaults_and_resolved_paths() {
        let s = load(MINIMAL).unwrap();
        assert_eq!(s.effects.terminator_deg, 15.0);
        assert_eq!(s.effects.evaluation, Evaluation::PerPixel);
        assert!(s.meshes[0].path.is_absolute());
        assert!(!s.wants_shadow_pass());
    }

    #[test]
    fn bad_keys_are_named() {
        let e = load(&MINIMAL.replace("[camera]", "[camera]\nfov_y_deg = 500"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera.fov_y_deg"), "{e}");
        let e = load(&MINIMAL.replace("[camera]", "[effects]\nshadows = \"maybe\"\n[camera]"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("shadows") && e.contains("maybe"), "{e}");
        let e = load(&MINIMAL.replace("[camera]", "[camera]\nfocus = 1")).unwrap_err().to_string();
        assert!(e.contains("focus"), "{e}");
        let e = load(&MINIMAL.replace("direction = [0, 0, 1]", "direction = [0, 0, 0]"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("lights[0].direction"), "{e}");
    }

    const ENV: &str = "[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\n";

    #[test]
    fn environment_lights_get_defaults_and_resolved_paths() {
        let s = load(&format!("{MINIMAL}{ENV}rotation_deg = 400\ncache_dir = \"c\"\neigenweightsets = {{ components = 3 }}\n")).unwrap();
        let (i, e) = s.environment().unwrap();
        assert_eq!(i, 1);
        assert!(e.path.is_absolute() && e.path.ends_with("sky.exr"));
        assert!(e.cache_dir.as_ref().unwrap().is_absolute());
        assert_eq!((e.exposure, e.visibility_res, e.two_sided), (1.0, 16, true));
        assert_eq!(e.params().eigen, Some((30, 3)));
        assert_eq!(e.rotation_deg, 400.0);
        assert!(!s.wants_shadow_pass());
        assert!(load(MINIMAL).unwrap().environment().is_none());
    }

    #[test]
    fn bad_environment_keys_are_named() {
        let e = load(&format!("{MINIMAL}{ENV}visibility_res = 1\n")).unwrap_err().to_string();
        assert!(e.contains("lights[1].visibility_res"), "{e}");
        let e =
            load(&format!("{MINIMAL}{ENV}eigenweightsets = {{ rotations = 4, components = 4 }}\n"))
                .unwrap_err()
                .to_string();
        assert!(e.contains("lights[1].eigenweightsets.components"), "{e}");
        let e = load(&format!("{MINIMAL}{ENV}exposure = -1\n")).unwrap_err().to_string();
        assert!(e.contains("lights[1].exposure"), "{e}");
        let e = load(&format!("{MINIMAL}{ENV}sharpness = 1\n")).unwrap_err().to_string();
        assert!(e.contains("sharpness"), "{e}");
        let e = load(&format!("{MINIMAL}{ENV}{ENV}")).unwrap_err().to_string();
        assert!(e.contains("at most one environment light"), "{e}");
    }

    const YARNS: &str =
        "[[yarns]]\nchart = \"stockinette\"\nmesh = \"plane.obj\"\nwales = 4\ncourses = 4\n";

    #[test]
    fn yarns_entries_get_defaults_and_resolved_paths() {
        let s = load(
            &format!("{MINIMAL}{YARNS}chart = \"charts/rib.chart\"\n")
                .replace("chart = \"stockinette\"\n", ""),
        )
        .unwrap();
        let y = &s.yarns[0];
        assert!(y.mesh.is_absolute() && y.mesh.ends_with("plane.obj"));
        assert!(Path::new(&y.chart).is_absolute(), "{}", y.chart);
        assert_eq!(
            (y.yarn.as_str(), y.lod_px, y.seed, y.method),
            ("cotton-2ply", 1.0, 1, YarnMethod::Fibers)
        );
        assert!(s.input_paths().iter().any(|(k, _)| k == "[[yarns]] 0 chart"));
        let s = load(&format!("{MINIMAL}{YARNS}")).unwrap();
        assert_eq!(s.yarns[0].chart, "stockinette");
        assert!(load(MINIMAL).unwrap().yarns.is_empty());
    }

    #[test]
    fn bad_yarns_keys_are_named() {
        let cases = [
            ("wales = 4", "wales = 0", "yarns[0].wales"),
            ("courses = 4", "courses = 5000", "yarns[0].courses"),
            ("wales = 4\ncourses = 4", "wales = 4096\ncourses = 4096", "yarns[0].wales"),
            ("wales = 4", "wales = 4\nstitch_uv = [0.0, 0.1]", "yarns[0].stitch_uv"),
            ("wales = 4", "wales = 4\nstitch_uv = [0.1, -0.1]", "yarns[0].stitch_uv"),
            ("wales = 4", "wales = 4\nlod_px = -1", "yarns[0].lod_px"),
            ("wales = 4", "wales = 4\nalbedo = [2, 0, 0]", "yarns[0].albedo"),
        ];
        for (from, to, key) in cases {
            let e = load(&format!("{MINIMAL}{YARNS}").replace(from, to)).unwrap_err().to_string();
            assert!(e.contains(key), "{to}: {e}");
        }
        // Lumislices blend into 4× MSAA targets: accepted by default, refused without MSAA.
        let ls =
            format!("{MINIMAL}{YARNS}").replace("wales = 4", "wales = 4\nmethod = \"lumislice\"");
        assert_eq!(load(&ls).unwrap().yarns[0].method, YarnMethod::Lumislice);
        let e = load(&format!("{ls}[effects]\nmsaa = 1\n")).unwrap_err().to_string();
        assert!(e.contains("yarns[0].method") && e.contains("msaa = 1"), "{e}");
        let e = load(
            &format!("{MINIMAL}{YARNS}").replace("wales = 4", "wales = 4\nmethod = \"splines\""),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("method") && e.contains("splines"), "{e}");
        let e = load(&format!("{MINIMAL}{YARNS}").replace("wales = 4", "wales = 10000000000"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("wales"), "{e}");
        let e = load(&format!("{MINIMAL}{YARNS}colour = 1\n")).unwrap_err().to_string();
        assert!(e.contains("colour"), "{e}");
        let thin = MINIMAL
            .replace("store = \"m.eigen\"", "store = \"m.eigen\"\ntransmission = { tau = 0.1 }");
        load(&thin).unwrap();
        let e = load(&format!("{thin}{YARNS}")).unwrap_err().to_string();
        assert!(e.contains("materials[0].transmission") && e.contains("[[yarns]]"), "{e}");
    }
}
