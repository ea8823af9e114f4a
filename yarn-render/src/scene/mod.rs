//! The `[[yarns]]` of a btf-render scene built on the CPU: the chart laid out on the
//! carrier mesh through its UVs (`yarn::knit::StitchMesh::on_surface`, [C03 §3]), the
//! Chen skeleton of that stitch mesh ([C03 §3.1], `chen_skeleton`) knitted from the
//! entry's yarn, packed for the fiber renderer ([W19 §3.1, §5]); [`overlay`] draws them in
//! the scene's frame. Every refusal names the scene key (`yarns[i].chart`, …) through
//! [`btf_render::Error::Scene`].
//!
//! Stitch size: `stitch_uv` when given, else the yarn's gauge (9 × 8 yarn radii,
//! `SkeletonParams::default_spacing`) divided by the carrier mesh's mean UV scale — the
//! UV-area-weighted mean of `|∂p/∂u|` and `|∂p/∂v|` over its triangles (metres of surface
//! per unit of u and of v), so that a stitch keeps its physical size on any UV layout.

pub mod overlay;

use crate::{Error, PackOptions, PackedYarns, Result};
use btf_light::mesh::Mesh;
use btf_render::Scene;
use btf_render::scene::YarnsDesc;
use std::path::Path;
use yarn::YarnParams;
use yarn::knit::{Chart, SkeletonParams, StitchMesh, SurfaceMesh, UvLayout, chen_skeleton};

pub use overlay::{YarnDrawer, YarnOverlay, fiber_camera, fiber_lights};

/// One `[[yarns]]` entry built: its yarn, curves and packed data.
#[derive(Debug, Clone)]
pub struct SceneYarn {
    /// Index in the scene's `yarns`.
    pub index: usize,
    /// The yarn.
    pub params: YarnParams,
    /// The yarn curves.
    pub set: yarn::YarnSet,
    /// Packed for the GPU.
    pub packed: PackedYarns,
    /// UV size of one stitch `[Δu, Δv]` used.
    pub stitch_uv: [f64; 2],
}

impl SceneYarn {
    /// World bounds of every fiber: the control points' box grown by twice the largest
    /// fiber reach (Catmull–Rom segments bulge a little beyond their control points).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let (lo, hi) = self.packed.bounds;
        let m = 2.0 * self.packed.max_reach;
        (lo.map(|x| x - m), hi.map(|x| x + m))
    }
}

/// The union of `yarns`' bounds in f32, for `RenderOptions::extra_bounds`.
pub fn bounds_f32(yarns: &[SceneYarn]) -> Option<([f32; 3], [f32; 3])> {
    let mut it = yarns.iter().map(SceneYarn::bounds);
    let (mut lo, mut hi) = it.next()?;
    for (a, b) in it {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    }
    Some((lo.map(|x| x as f32), hi.map(|x| x as f32)))
}

/// A refusal naming `yarns[i].key` in `scene_path`.
fn bad(scene_path: &Path, i: usize, key: &str, what: impl Into<String>) -> Error {
    Error::Render(btf_render::Error::Scene {
        path: scene_path.into(),
        key: format!("yarns[{i}].{key}"),
        what: what.into(),
    })
}

/// Builds every `[[yarns]]` entry of `scene` (loaded from `scene_path`, which names it in
/// errors).
pub fn build(scene: &Scene, scene_path: &Path) -> Result<Vec<SceneYarn>> {
    scene.yarns.iter().enumerate().map(|(i, d)| build_one(scene, scene_path, i, d)).collect()
}

fn load_chart(value: &str) -> std::result::Result<Chart, String> {
    if btf_render::scene::names_file(value) {
        let text =
            std::fs::read_to_string(value).map_err(|e| format!("chart file {value}: {e}"))?;
        Chart::parse(&text, value).map_err(|e| e.to_string())
    } else {
        Chart::builtin(value).map_err(|e| e.to_string())
    }
}

fn load_yarn(value: &str) -> std::result::Result<YarnParams, String> {
    if btf_render::scene::names_file(value) {
        let text = std::fs::read_to_string(value).map_err(|e| format!("yarn file {value}: {e}"))?;
        YarnParams::from_toml(&text, value).map_err(|e| e.to_string())
    } else {
        YarnParams::preset(value).map_err(|e| e.to_string())
    }
}

/// The carrier mesh as the yarn crate takes it, with its `planar_uv` when it is one of the
/// scene's meshes.
fn carrier(scene: &Scene, d: &YarnsDesc) -> std::result::Result<SurfaceMesh, String> {
    let same = |p: &Path| {
        p == d.mesh || matches!((p.canonicalize(), d.mesh.canonicalize()), (Ok(a), Ok(b)) if a == b)
    };
    let planar = match scene.meshes.iter().find(|m| same(&m.path)) {
        Some(m) => m.planar_uv,
        None if d.mesh.is_file() => None,
        None => {
            return Err(format!(
                "'{}' is neither a [[meshes]] path of the scene nor an OBJ file",
                d.mesh.display()
            ));
        }
    };
    let m = Mesh::load_obj(&d.mesh, planar).map_err(|e| e.to_string())?;
    let f = |v: &[f32; 3]| v.map(f64::from);
    Ok(SurfaceMesh {
        positions: m.positions.iter().map(f).collect(),
        normals: m.normals.iter().map(f).collect(),
        uvs: m.uvs.iter().map(|t| t.map(f64::from)).collect(),
        triangles: m.triangles.clone(),
        triangle_uvs: m.triangles,
    })
}

/// Metres of surface per unit of u and of v, averaged over the triangles weighted by their
/// UV area (`None` when no triangle has UV area).
pub fn mean_uv_scale(s: &SurfaceMesh) -> Option<[f64; 2]> {
    let (mut su, mut sv, mut area) = (0.0, 0.0, 0.0);
    for (t, tu) in s.triangles.iter().zip(&s.triangle_uvs) {
        let p = t.map(|i| s.positions[i as usize]);
        let q = tu.map(|i| s.uvs[i as usize]);
        let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
        let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
        let (du1, dv1) = (q[1][0] - q[0][0], q[1][1] - q[0][1]);
        let (du2, dv2) = (q[2][0] - q[0][0], q[2][1] - q[0][1]);
        let det = du1 * dv2 - du2 * dv1;
        if det.abs() <= 1e-300 || !det.is_finite() {
            continue;
        }
        let dpu = [0, 1, 2].map(|k| (e1[k] * dv2 - e2[k] * dv1) / det);
        let dpv = [0, 1, 2].map(|k| (e2[k] * du1 - e1[k] * du2) / det);
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let w = 0.5 * det.abs();
        su += w * norm(dpu);
        sv += w * norm(dpv);
        area += w;
    }
    (area > 0.0 && su > 0.0 && sv > 0.0).then(|| [su / area, sv / area])
}

fn build_one(scene: &Scene, path: &Path, i: usize, d: &YarnsDesc) -> Result<SceneYarn> {
    if let Err((key, what)) = d.validate(&format!("yarns[{i}]")) {
        return Err(Error::Render(btf_render::Error::Scene { path: path.into(), key, what }));
    }
    let chart = load_chart(&d.chart).map_err(|e| bad(path, i, "chart", e))?;
    let params = load_yarn(&d.yarn).map_err(|e| bad(path, i, "yarn", e))?;
    let radius = params.yarn_radius();
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(bad(path, i, "yarn", format!("yarn radius {radius} m must be positive")));
    }
    let surface = carrier(scene, d).map_err(|e| bad(path, i, "mesh", e))?;
    let mut sk = SkeletonParams::new(radius);
    if let Some(a) = d.albedo {
        sk.color = a;
    }
    sk.seed = d.seed;
    let stitch_uv = match d.stitch_uv {
        Some(s) => s,
        None => {
            let scale = mean_uv_scale(&surface)
                .ok_or_else(|| bad(path, i, "mesh", "no triangle has UV area"))?;
            let (ws, cs) = sk.default_spacing();
            [ws / scale[0], cs / scale[1]]
        }
    };
    let layout = UvLayout {
        origin: d.uv_origin,
        wale_du: stitch_uv[0],
        course_dv: stitch_uv[1],
        wales: d.wales as usize,
        courses: d.courses as usize,
    };
    let stitches = StitchMesh::on_surface(&surface, &chart, &layout).map_err(|e| {
        let what = format!(
            "{e} — mesh {}, uv_origin {:?}, stitch_uv {stitch_uv:?}, {} wales × {} courses",
            d.mesh.display(),
            d.uv_origin,
            d.wales,
            d.courses
        );
        bad(path, i, "uv_origin", what)
    })?;
    let set = chen_skeleton(&stitches, &sk).map_err(|e| bad(path, i, "yarn", e.to_string()))?;
    let opts = PackOptions { seed: d.seed, frame_samples_per_segment: 16, tiles: [1, 1] };
    let packed = PackedYarns::new(&set, std::slice::from_ref(&params), &opts)?;
    Ok(SceneYarn { index: i, params, set, packed, stitch_uv })
}

#[cfg(test)]
mod tests;
