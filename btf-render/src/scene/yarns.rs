//! `[[yarns]]` of a scene: knit patches drawn next to the BTF meshes, in the same colour and
//! depth targets, by the method each entry names ([`YarnMethod`]): fiber-level yarns (Wu &
//! Yuksel 2019, [W19 §3–5]; the default), fiber-textured yarn strips (Huang et al. 2025,
//! [H25]) or lumislices (Chen et al. 2003, [C03 §5]; blended over the opaque scene, so the
//! scene needs MSAA 4). This module is data only: btf-render parses the entries, resolves
//! their paths and checks their ranges (naming the key), and draws nothing for them —
//! `yarn-render::scene` builds the yarns (chart → stitch mesh on the carrier mesh's UVs →
//! Chen skeleton → packed yarn curves) and draws them through
//! [`crate::renderer::Overlay`], because btf-render cannot depend on yarn-render. No
//! equation of the papers lives here.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Most wales (or courses) of one `[[yarns]]` entry.
pub const MAX_WALES: u32 = 4096;
/// Most stitches (wales × courses) of one entry: about 12 control points a stitch, so
/// 2¹⁸ stitches are ≈ 3·10⁶ control points (≈ 0.4 GB packed) — refused beyond, before
/// anything is allocated.
pub const MAX_STITCHES: u64 = 1 << 18;

/// How the yarns are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum YarnMethod {
    /// Procedural fibers generated on the GPU every frame ([W19]).
    #[default]
    Fibers,
    /// Fiber-textured yarn strips (Huang et al. 2025) with baked textures.
    Strips,
    /// Lumislices (Chen et al. 2003): ray-marched yarn volumes with a precomputed
    /// scattering table, blended over the opaque scene (needs MSAA 4).
    Lumislice,
}

/// Ambient occlusion inside the yarns ([W19 §4.2]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum YarnAo {
    /// None.
    Off,
    /// [W19]'s distance cubic.
    #[default]
    Cubic,
    /// The stratified 2-D texture.
    Texture,
}

/// One knit patch: a chart mapped onto a mesh through its UVs, knitted from one yarn.
///
/// The chart's corner `(course c, wale w)` sits at `uv_origin + (w·stitch_uv[0],
/// c·stitch_uv[1])` of the mesh's UVs (OBJ convention, `v` up); `wales × courses` stitches
/// are laid out. Without `stitch_uv`, one stitch is the yarn's own gauge (9 × 8 yarn radii,
/// `yarn::knit::SkeletonParams::default_spacing`) converted to UV units by the mesh's mean
/// UV scale (metres of surface per unit of u and of v), so the yarn keeps its size whatever
/// the UV layout. Scene units are metres (the yarn presets are in metres).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YarnsDesc {
    /// Built-in chart name (`stockinette`, `garter`, `rib1x1`, …) or a chart file; a value
    /// with a `/` or a `.` is a file, relative to the scene file.
    pub chart: String,
    /// The carrier mesh whose UVs carry the chart: a `[[meshes]]` path (drawn with its BTF
    /// and reusing its `planar_uv`) or another OBJ (not drawn), relative to the scene file.
    pub mesh: PathBuf,
    /// Yarn preset (`cotton-2ply`, `fleece-3ply`, `fine-2ply`) or a yarn TOML file (same
    /// rule as `chart`).
    #[serde(default = "default_yarn")]
    pub yarn: String,
    /// UV of the chart's corner (course 0, wale 0).
    #[serde(default)]
    pub uv_origin: [f64; 2],
    /// Stitches along u (wales).
    pub wales: u32,
    /// Stitches along v (courses).
    pub courses: u32,
    /// UV size of one stitch `[Δu, Δv]` (default: the yarn's gauge on this mesh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stitch_uv: Option<[f64; 2]>,
    /// Level-of-detail threshold ω^LoD in pixels ([W19 eq. 4]; 0: every fiber); read by
    /// `method = "fibers"` only.
    #[serde(default = "default_lod_px")]
    pub lod_px: f32,
    /// How the yarns are drawn: `fibers` (the default), `strips` or `lumislice` (the last
    /// needs `effects.msaa = 4`).
    #[serde(default)]
    pub method: YarnMethod,
    /// Yarn colour (linear RGB in [0, 1]); default: the skeleton's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f32; 3]>,
    /// Seed of the fibers.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Self-shadows inside the yarns and shadows of other yarns (directional lights).
    #[serde(default = "yes")]
    pub shadows: bool,
    /// Ambient occlusion inside the yarns ([W19 §4.2]); read by `method = "fibers"` only.
    #[serde(default)]
    pub ao: YarnAo,
    /// Hair flyaways: the yarn's hairs on the fibers, the flyaway overlay on the strips.
    #[serde(default = "yes")]
    pub hairs: bool,
    /// Shadows of every fiber (`method = "fibers"` with `shadows`): each light's map drawn
    /// from the fibers instead of tubes and the self-shadow volume (one more fiber pass
    /// per light).
    #[serde(default)]
    pub fiber_shadows: bool,
}

fn default_yarn() -> String {
    "cotton-2ply".into()
}
fn default_lod_px() -> f32 {
    1.0
}
fn default_seed() -> u64 {
    1
}
fn yes() -> bool {
    true
}

/// A chart or yarn value names a file when it holds a `/` or a `.`.
pub fn names_file(value: &str) -> bool {
    value.contains('/') || value.contains('.') || value.contains('\\')
}

impl YarnsDesc {
    /// Makes relative paths relative to the scene folder `dir`.
    pub(crate) fn resolve(&mut self, dir: &Path) {
        self.mesh = dir.join(&self.mesh);
        for v in [&mut self.chart, &mut self.yarn] {
            if names_file(v) {
                *v = dir.join(&*v).display().to_string();
            }
        }
    }

    /// The files this entry reads, named as `[[yarns]] i key`.
    pub(crate) fn input_paths(&self, i: usize, out: &mut Vec<(String, PathBuf)>) {
        out.push((format!("[[yarns]] {i} mesh"), self.mesh.clone()));
        for (key, v) in [("chart", &self.chart), ("yarn", &self.yarn)] {
            if names_file(v) {
                out.push((format!("[[yarns]] {i} {key}"), PathBuf::from(v)));
            }
        }
    }

    /// Checks ranges; `Err((key, what))` names the key as `{key}.field` (`key` is
    /// `yarns[i]`).
    pub fn validate(&self, key: &str) -> std::result::Result<(), (String, String)> {
        let bad = |k: &str, what: String| Err((format!("{key}.{k}"), what));
        for (k, n) in [("wales", self.wales), ("courses", self.courses)] {
            if !(1..=MAX_WALES).contains(&n) {
                return bad(k, format!("{n} must be in 1..={MAX_WALES}"));
            }
        }
        let stitches = self.wales as u64 * self.courses as u64;
        if stitches > MAX_STITCHES {
            return bad(
                "wales",
                format!(
                    "{} × {} = {stitches} stitches; at most {MAX_STITCHES} per entry",
                    self.wales, self.courses
                ),
            );
        }
        if !self.uv_origin.iter().all(|x| x.is_finite()) {
            return bad("uv_origin", "must be finite".into());
        }
        if let Some(s) = self.stitch_uv
            && !s.iter().all(|x| x.is_finite() && *x > 0.0)
        {
            return bad("stitch_uv", format!("{s:?}: both sizes must be positive and finite"));
        }
        if !(self.lod_px.is_finite() && (0.0..=1e4).contains(&self.lod_px)) {
            return bad("lod_px", format!("{} must be in [0, 1e4] pixels", self.lod_px));
        }
        if let Some(a) = self.albedo
            && !a.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x))
        {
            return bad("albedo", format!("{a:?}: each channel must be in [0, 1]"));
        }
        if self.chart.trim().is_empty() {
            return bad("chart", "must name a chart".into());
        }
        if self.yarn.trim().is_empty() {
            return bad("yarn", "must name a yarn preset or file".into());
        }
        if self.fiber_shadows && self.method != YarnMethod::Fibers {
            return bad("fiber_shadows", "shadows of every fiber need method = \"fibers\"".into());
        }
        if self.fiber_shadows && !self.shadows {
            return bad("fiber_shadows", "needs shadows = true".into());
        }
        Ok(())
    }
}
