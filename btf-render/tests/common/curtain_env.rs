//! The folded curtain under a rotated sky with a sun, and the f64 reference of the
//! thin-cloth environment tables (`transmission/env.rs`): a direct quadrature over every
//! source of the binned environment with `btf_core::thin_slab::Slab::f_t`. Included by
//! `tests/thin_env.rs` and `tests/thin_env_tau.rs`.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_core::thin_slab::{Phase, Slab};
use btf_image::EnvMap;
use btf_light::EnvMesh;
use btf_light::hemicube::pixel_of as hemicube_pixel;
use btf_light::mesh::Mesh;
use btf_light::tangent::compute_tangents;
use btf_light::{EnvCube, EnvironmentParams, HemicubeFrame, SceneEnvironment};
use btf_render::material::MaterialData;
use std::path::Path;

pub fn curtain_mesh(dir: &Path) -> Mesh {
    let mesh =
        datasets::synth_mesh(datasets::MeshKind::Curtain, datasets::Resolution::Low).unwrap();
    let path = dir.join("curtain.obj");
    datasets::write_obj(&mesh, &path, "curtain").unwrap();
    Mesh::load_obj(&path, None).unwrap()
}

/// A sky with a small bright sun, not symmetric under the rotation.
pub fn sky(d: [f64; 3]) -> [f32; 3] {
    let sun = [0.6f64, 0.2, 0.775];
    let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    let s = if c > 0.995 { 40.0 } else { 0.0 };
    let base = 0.3 + 0.6 * d[2].max(0.0) + 0.1 * (d[0] + 1.0);
    [(base + s) as f32, (0.9 * base + s) as f32, (0.7 * base + 0.8 * s) as f32]
}

/// The curtain under the rotated sky (rotation 30°, exposure 0.7, visibility 8²) and
/// the f64 reference over every source of the binned environment.
pub struct CurtainEnv {
    pub mesh: Mesh,
    pub env: SceneEnvironment,
    pub frames: Vec<HemicubeFrame>,
    pub cube: EnvCube,
}

pub const ROT_DEG: f64 = 30.0;
pub const EXPOSURE: f32 = 0.7;
pub const VIS_RES: u32 = 8;

pub fn curtain_env(dir: &Path) -> CurtainEnv {
    let mesh = curtain_mesh(dir);
    let tangents = compute_tangents(&mesh);
    let store = write_store(dir, "m.eigen", Pattern::Lambert, 2, 2, 2, Quantization::F16);
    let mat = MaterialData::load(&store, None).unwrap();
    let map = EnvMap::from_fn(64, |d| sky(d).map(f64::from)).unwrap();
    let params = EnvironmentParams {
        rotation_deg: ROT_DEG,
        exposure: EXPOSURE,
        visibility_res: VIS_RES,
        two_sided: true,
        eigen: None,
        cache_dir: None,
    };
    let env_mesh = EnvMesh {
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        triangles: &mesh.triangles,
    };
    let env = SceneEnvironment::new(
        params,
        &map,
        &env_mesh,
        &mat.light_sampling,
        vec![mat.coefficient_matrix()],
    )
    .unwrap();
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
    let cube = EnvCube::new(&map, SceneEnvironment::cube_res(VIS_RES));
    CurtainEnv { mesh, env, frames, cube }
}

/// Reference terms of hemicube frame `f`: every source of the binned environment,
/// rotated, dropped into its hemicube pixel, kept if visible, weighted by `f_t · μ₀` of
/// the slab (f64). Returns `(A, T(μ) for each μ, visible / all irradiance)`.
pub fn reference(
    c: &CurtainEnv,
    f: usize,
    tau: f64,
    albedo: [f64; 3],
    mus: &[f64],
) -> ([f64; 3], Vec<[f64; 3]>, f64) {
    let (sin, cos) = ROT_DEG.to_radians().sin_cos();
    let rot = |a: [f32; 3]| {
        [cos as f32 * a[0] + sin as f32 * a[1], -sin as f32 * a[0] + cos as f32 * a[1], a[2]]
    };
    let [t, b, nn] = c.frames[f].axes.map(rot);
    let dot = |d: &[f32; 3], a: [f32; 3]| d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    let (mut irr, mut num, mut all) = ([0f64; 3], [0f64; 3], 0f64);
    let mut tk = vec![[0f64; 3]; mus.len()];
    for (d, pw) in c.cube.dirs.iter().zip(&c.cube.power) {
        let z = dot(d, nn);
        if z <= 0.0 {
            continue;
        }
        all += pw[0] as f64 * z as f64;
        let p = hemicube_pixel(VIS_RES as usize, dot(d, t), dot(d, b), z);
        if !c.env.visibility().visible(f, p) {
            continue;
        }
        let mu0 = z as f64;
        for ch in 0..3 {
            let s = Slab { tau, albedo: albedo[ch], phase: Phase::Isotropic };
            irr[ch] += pw[ch] as f64 * mu0;
            num[ch] += pw[ch] as f64 * mu0 * (-tau / mu0).exp();
            for (row, &mu) in tk.iter_mut().zip(mus) {
                row[ch] += EXPOSURE as f64 * s.f_t(mu, mu0, 0.0) * mu0 * pw[ch] as f64;
            }
        }
    }
    let a = [0, 1, 2].map(|ch| if irr[ch] > 0.0 { num[ch] / irr[ch] } else { 0.0 });
    (a, tk, irr[0] / all)
}
