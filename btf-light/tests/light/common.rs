//! Fixtures of the CPU light-transport tests: a synthetic eigen store (the same patterns
//! as btf-render's GPU tests), the meshes (a UV sphere, a concave corner, a crumpled sheet,
//! the low shirt), a sky with a bright sun, and the hemicube/visibility/coefficient set-up
//! most tests share, with the radiance of a texel under the gathered environment
//! (`[S03 eq. 11]`, `f = 1`).

use btf_core::eigen::{EigenMeta, EigenSlot, EigenStore, EigenWriter, Quantization};
use btf_core::eigen::{QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_core::{Direction, InterpMode, Sampling};
use btf_image::EnvMap;
use btf_light::mesh::Mesh;
use btf_light::tangent::compute_tangents;
use btf_light::{
    CoefficientMatrix, EnvCube, GatherInput, Hemicube, HemicubeFrame, LightTable, Radiances,
    VisibilityMaps,
};
use std::f32::consts::TAU;
use std::path::{Path, PathBuf};

/// Spatial pattern of the synthetic material.
#[derive(Clone, Copy, PartialEq)]
pub enum Pattern {
    /// Texture-varying in x and y, smooth in view and light.
    Checker,
    /// The same value at every texel (tests the direction dependence alone).
    Uniform,
    /// Exactly Lambertian, albedo 0.8: `BTF = ρ/π · cos θ_l` at every texel (component 0
    /// carries the light dependence, the others are zero).
    Lambert,
}

/// Writes an eigen store with `ubo81` samplings and `c` components. The images of slot `j`
/// under light `i` are `μ_j + Σ_k p_ikj B_kj` with smooth dependence on both directions.
pub fn write_store(
    dir: &Path,
    name: &str,
    pattern: Pattern,
    (w, h): (usize, usize),
    c: usize,
    q: Quantization,
) -> PathBuf {
    let views = Sampling::ubo81();
    let lights = Sampling::ubo81();
    let meta = EigenMeta {
        btf: BtfMeta::new(views.clone(), lights.clone(), w, h),
        components: c,
        quantization: q,
    };
    let path = dir.join(name);
    let writer = EigenWriter::create(&path, meta, false).unwrap();
    if pattern == Pattern::Lambert {
        return write_lambert(path, writer, &lights, w * h * 3, c, q);
    }
    for j in 0..views.len() {
        let vd = views.direction(j).to_vector();
        let mut mean = vec![0f32; w * h * 3];
        let mut basis = vec![0f32; c * w * h * 3];
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
                let s = match pattern {
                    Pattern::Checker => 0.5 + 0.3 * (TAU * fx * 2.0).sin() * (TAU * fy * 3.0).cos(),
                    Pattern::Uniform | Pattern::Lambert => 1.0,
                };
                let t = (y * w + x) * 3;
                for ch in 0..3 {
                    mean[t + ch] = 0.2 * s * (1.0 + 0.3 * vd[2] as f32) * [1.0, 0.8, 0.6][ch];
                    for k in 0..c {
                        let pk = match pattern {
                            Pattern::Uniform | Pattern::Lambert => 1.0,
                            Pattern::Checker => (TAU
                                * (fx * (k % 3 + 1) as f32
                                    + fy * (k / 3) as f32
                                    + 0.1 * ch as f32))
                                .cos(),
                        };
                        basis[k * w * h * 3 + t + ch] =
                            0.15 * pk * (1.0 + 0.5 * vd[0] as f32) / (1.0 + k as f32);
                    }
                }
            }
        }
        let mut weights = vec![0f32; lights.len() * c];
        for i in 0..lights.len() {
            let ld = lights.direction(i).to_vector();
            for k in 0..c {
                weights[i * c + k] = (ld[2] as f32 * 2.0 - 1.0) * (1.0 + k as f32 * 0.1)
                    + (ld[0] as f32 * (k + 1) as f32).sin()
                    + 0.5 * ld[1] as f32 * ((k % 2) as f32 - 0.5);
            }
        }
        let (eigentextures, scale_offset) = quantize(&basis, c, q);
        let slot = QuantizedSlot {
            mean,
            eigentextures,
            scale_offset,
            weights,
            eigenvalues: vec![1.0; lights.len()],
        };
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
    path
}

fn write_lambert(
    path: PathBuf,
    writer: EigenWriter,
    lights: &Sampling,
    n: usize,
    c: usize,
    q: Quantization,
) -> PathBuf {
    let rho_pi = 0.8 / std::f32::consts::PI;
    let cos: Vec<f32> = (0..lights.len()).map(|i| lights.direction(i).cos_theta() as f32).collect();
    let mean_cos = cos.iter().sum::<f32>() / cos.len() as f32;
    let unit = 1.0 / (n as f32).sqrt();
    let mut basis = vec![0f32; c * n];
    basis[..n].fill(unit);
    let mut weights = vec![0f32; lights.len() * c];
    for i in 0..lights.len() {
        weights[i * c] = rho_pi * (cos[i] - mean_cos) / unit;
    }
    let (eigentextures, scale_offset) = quantize(&basis, c, q);
    let slot = QuantizedSlot {
        mean: vec![rho_pi * mean_cos; n],
        eigentextures,
        scale_offset,
        weights,
        eigenvalues: vec![1.0; lights.len()],
    };
    for j in 0..Sampling::ubo81().len() {
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
    path
}

/// The coefficient matrix `P` of `[S03 eq. 10–12]` of an eigen store (plain weights, no
/// bias), its dequantised slots and the store.
pub fn coefficients(path: &Path, c: usize) -> (CoefficientMatrix, Vec<EigenSlot>, EigenStore) {
    let store = EigenStore::open(path).unwrap();
    let slots: Vec<EigenSlot> =
        (0..store.view_sampling().len()).map(|j| store.read_slot(j).unwrap()).collect();
    let p = CoefficientMatrix::from_slots(&slots, store.light_sampling().len(), c);
    (p, slots, store)
}

/// A UV sphere of radius `r` centred at `c` with `seg` segments and `seg/2` rings, as OBJ.
fn sphere_obj(r: f32, c: [f32; 3], seg: usize) -> String {
    let rings = seg / 2;
    let mut s = String::new();
    for j in 0..=rings {
        let th = std::f32::consts::PI * j as f32 / rings as f32;
        for i in 0..=seg {
            let ph = TAU * i as f32 / seg as f32;
            let n = [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()];
            s += &format!(
                "v {} {} {}\nvn {} {} {}\nvt {} {}\n",
                c[0] + r * n[0],
                c[1] + r * n[1],
                c[2] + r * n[2],
                n[0],
                n[1],
                n[2],
                i as f32 / seg as f32,
                1.0 - j as f32 / rings as f32
            );
        }
    }
    let id = |i: usize, j: usize| j * (seg + 1) + i + 1;
    for j in 0..rings {
        for i in 0..seg {
            let (a, b, cc, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!(
                "f {a}/{a}/{a} {d}/{d}/{d} {cc}/{cc}/{cc}\nf {a}/{a}/{a} {cc}/{cc}/{cc} {b}/{b}/{b}\n"
            );
        }
    }
    s
}

/// The unit-diameter sphere at the origin, `seg` segments.
pub fn sphere(seg: usize) -> Mesh {
    Mesh::parse_obj(&sphere_obj(0.5, [0.0; 3], seg), "sphere.obj", None).unwrap()
}

/// A mesh's hemicubes, light table, one-sided frames and visibility, and a store's `P`.
pub struct Setup {
    pub cube: Hemicube,
    pub table: LightTable,
    pub frames: Vec<HemicubeFrame>,
    pub vis: VisibilityMaps,
    pub slots: Vec<EigenSlot>,
    pub p: CoefficientMatrix,
    pub store: EigenStore,
}

/// [`Setup`] for `mesh` at hemicube resolution `res` and a 2×2 store of `pattern`, `c`
/// components (kept in the returned folder).
pub fn setup(mesh: &Mesh, res: u32, pattern: Pattern, c: usize) -> (Setup, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let path = write_store(dir.path(), "m.eigen", pattern, (2, 2), c, Quantization::F16);
    let (p, slots, store) = coefficients(&path, c);
    let cube = Hemicube::new(res).unwrap();
    let table = LightTable::new(&cube, store.light_sampling(), InterpMode::Four).unwrap();
    let tangents = compute_tangents(mesh);
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, false);
    let vis = VisibilityMaps::compute(&cube, &frames, &mesh.positions, &mesh.triangles);
    (Setup { cube, table, frames, vis, slots, p, store }, dir)
}

impl Setup {
    /// The radiances `g` of `[S03 eq. 10]` of every frame, the environment turned by `delta`.
    pub fn gather(&self, env: &EnvCube, delta: f64) -> Radiances {
        let input = GatherInput {
            table: &self.table,
            visibility: &self.vis,
            frames: &self.frames,
            dirs: &self.cube.dirs,
            lights: self.p.lights,
        };
        Radiances::gather(&input, env, delta)
    }

    /// Radiance of texel 0 of frame `f` seen from tangent-space `view` (`[S03 eq. 11]`,
    /// `f = 1`).
    pub fn radiance(&self, w: &Radiances, f: usize, view: Direction) -> [f32; 3] {
        let k = self.p.per_slot();
        let mut gs = vec![0f32; 3 * k];
        let mut out = [0f32; 3];
        for &(j, omega) in
            self.store.view_sampling().view_weights(view, InterpMode::Four).as_slice()
        {
            w.gamma_star(&self.p, f, j, &mut gs);
            let s = &self.slots[j];
            for ch in 0..3 {
                let mut v = gs[ch * k] * s.mean[ch] + gs[ch * k + 1];
                for c in 0..self.p.components {
                    v += gs[ch * k + 2 + c] * s.basis_row(c)[ch];
                }
                out[ch] += omega as f32 * v;
            }
        }
        out
    }
}

/// A floor grid with a vertex at the origin and a wall rectangle at `x = d`.
pub fn corner_mesh(d: f32, half_width: f32, height: f32) -> Mesh {
    let mut m = Mesh::default();
    let n = 4;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (-0.2 + 0.4 * i as f32 / n as f32, -0.2 + 0.4 * j as f32 / n as f32);
            m.positions.push([x, y, 0.0]);
            m.normals.push([0.0, 0.0, 1.0]);
            m.uvs.push([x, y]);
        }
    }
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * (n as u32 + 1) + i;
            m.triangles.push([a, a + 1, a + n as u32 + 2]);
            m.triangles.push([a, a + n as u32 + 2, a + n as u32 + 1]);
        }
    }
    let b = m.positions.len() as u32;
    for (y, z) in
        [(-half_width, 0.0), (half_width, 0.0), (half_width, height), (-half_width, height)]
    {
        m.positions.push([d, y, z]);
        m.normals.push([-1.0, 0.0, 0.0]);
        m.uvs.push([y, z]);
    }
    m.triangles.extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
    m.triangle_material = vec![0; m.triangles.len()];
    m.material_names = vec![String::new()];
    m
}

/// Sky of radiance 1 and a sun of angular radius 0.5° that is 1e5 times brighter.
pub fn sun_env(width: usize, sun: [f64; 3]) -> (EnvMap, f64) {
    let cos_r = 0.5f64.to_radians().cos();
    let env = EnvMap::from_fn(width, |d| {
        let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
        [if c >= cos_r { 1e5 } else { 1.0 }; 3]
    })
    .unwrap();
    let sky = 4.0 * std::f64::consts::PI;
    let sun_power = env.integral()[0] - sky; // Σ (L − 1) dω over the sun's pixels
    (env, sun_power)
}

/// A 12×12 sheet crumpled by pseudo-random heights about one grid step high: every kind of
/// near and far occluder at once.
pub fn crumpled_sheet() -> Mesh {
    let n = 12u32;
    let mut m = Mesh::default();
    let mut seed = 7u32;
    for j in 0..=n {
        for i in 0..=n {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let z = ((seed >> 8) as f32 / (1 << 24) as f32 - 0.5) * 0.15;
            m.positions.push([i as f32 / n as f32, j as f32 / n as f32, z]);
            m.uvs.push([i as f32, j as f32]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            m.triangles.push([a, a + 1, a + n + 2]);
            m.triangles.push([a, a + n + 2, a + n + 1]);
        }
    }
    m.triangle_material = vec![0; m.triangles.len()];
    m.material_names = vec![String::new()];
    m.normals = vec![[0.0; 3]; m.positions.len()];
    m.repair_normals(true);
    m
}

pub fn shirt_low() -> Mesh {
    let dir = tempfile::tempdir().unwrap();
    let m = datasets::mesh::synth_mesh(
        datasets::mesh::MeshKind::Shirt,
        datasets::mesh::Resolution::Low,
    )
    .unwrap();
    let p = dir.path().join("shirt.obj");
    datasets::mesh::write_obj(&m, &p, "shirt").unwrap();
    Mesh::load_obj(&p, None).unwrap()
}
