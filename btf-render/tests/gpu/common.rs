//! Shared fixtures of the GPU tests: tiny synthetic eigen stores and meshes written into
//! a temporary folder, [`SceneBuilder`] for `Scene` values (what a scene file would hold,
//! built in code), the GPU guard, and image comparison with `-actual`/`-difference` PNGs
//! written on failure.

use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_render::scene::{
    Albedo, Camera, Effects, EnvironmentLight, Light, MaterialDesc, MeshDesc, Output, PhaseDesc,
    Projection, TransmissionDesc,
};
use btf_render::{Frame, Gpu, Scene};
use std::f32::consts::TAU;
use std::path::{Path, PathBuf};

/// Spatial pattern of the synthetic material.
#[derive(Clone, Copy, PartialEq)]
pub enum Pattern {
    /// Ribs: varies along texture x (columns) only, constant along rows — anisotropic.
    Ribs,
    /// Texture-varying in x and y, smooth in view and light.
    Checker,
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
    w: usize,
    h: usize,
    c: usize,
    q: Quantization,
) -> PathBuf {
    write_store_scaled(dir, name, pattern, w, h, c, q, 1.0)
}

/// [`write_store`] with every per-light weight times `weight_scale` (an HDR store whose
/// weights leave `f16`'s range at 1e6).
#[allow(clippy::too_many_arguments)]
pub fn write_store_scaled(
    dir: &Path,
    name: &str,
    pattern: Pattern,
    w: usize,
    h: usize,
    c: usize,
    q: Quantization,
    weight_scale: f32,
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
                    Pattern::Ribs => 0.5 + 0.4 * (TAU * fx * 4.0).cos(),
                    Pattern::Checker => 0.5 + 0.3 * (TAU * fx * 2.0).sin() * (TAU * fy * 3.0).cos(),
                    Pattern::Lambert => 1.0,
                };
                let t = (y * w + x) * 3;
                for ch in 0..3 {
                    mean[t + ch] = 0.2 * s * (1.0 + 0.3 * vd[2] as f32) * [1.0, 0.8, 0.6][ch];
                    for k in 0..c {
                        let pk = match pattern {
                            Pattern::Lambert => 1.0,
                            Pattern::Ribs => {
                                (TAU * (fx * (k % 3 + 1) as f32 + 0.1 * ch as f32)).cos()
                            }
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
                weights[i * c + k] = weight_scale
                    * ((ld[2] as f32 * 2.0 - 1.0) * (1.0 + k as f32 * 0.1)
                        + (ld[0] as f32 * (k + 1) as f32).sin()
                        + 0.5 * ld[1] as f32 * ((k % 2) as f32 - 0.5));
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

/// A unit plane `[0,1]²` at z = 0 split into `n × n` quads, UV = (x, y) (or rotated 90°:
/// UV = (y, 1 − x)).
pub fn plane_obj(n: usize, rotate_uv: bool) -> String {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            s += &format!("v {x} {y} 0\n");
            let (u, v) = if rotate_uv { (y, 1.0 - x) } else { (x, y) };
            s += &format!("vt {u} {v}\nvn 0 0 1\n");
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!(
                "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\nf {a}/{a}/{a} {c}/{c}/{c} {d}/{d}/{d}\n"
            );
        }
    }
    s
}

/// A UV sphere of radius `r` centred at `c` with `seg` segments and `seg/2` rings.
pub fn sphere_obj(r: f32, c: [f32; 3], seg: usize) -> String {
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

/// A GPU for this test, or `None` (skip) — a failure when `BTF_REQUIRE_GPU=1`.
pub fn gpu(test: &str) -> Option<Gpu> {
    Gpu::for_tests(test)
}

/// Relative RMSE `‖a − b‖ / ‖a‖` over all values.
pub fn rel_rmse(reference: &[f32], actual: &[f32]) -> f64 {
    btf_core::metrics::rel_rmse(reference, actual)
}

/// Where failing comparisons leave their images.
pub fn artifact_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render-artifacts");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes `NAME-actual.png`, `NAME-expected.png` and `NAME-difference.png` (×10).
pub fn save_comparison(name: &str, w: u32, h: u32, expected: &[f32], actual: &[f32]) -> PathBuf {
    let d = artifact_dir();
    let scale = expected.iter().fold(0f32, |a, &b| a.max(b)).max(1e-6);
    let save = |suffix: &str, data: Vec<f32>| {
        let f = Frame { width: w, height: h, rgb: data, stats: Default::default() };
        f.write_png(&d.join(format!("{name}-{suffix}.png")), 1.0 / scale).unwrap();
    };
    save("actual", actual.to_vec());
    save("expected", expected.to_vec());
    save("difference", expected.iter().zip(actual).map(|(a, b)| (a - b).abs() * 10.0).collect());
    d
}

/// Asserts `rel_rmse(expected, actual) ≤ tol`, leaving comparison images on failure.
pub fn assert_close(name: &str, w: u32, h: u32, expected: &[f32], actual: &[f32], tol: f64) -> f64 {
    let e = rel_rmse(expected, actual);
    if e.is_nan() || e > tol {
        let d = save_comparison(name, w, h, expected, actual);
        panic!("{name}: relative RMSE {e:.4} > {tol} (images in {})", d.display());
    }
    e
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

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The unit plane `[0, 1]²` at `z = 0` with `(n + 1)²` vertices, UV = (x, y): the datasets
/// plane (`datasets::mesh::shapes::plane`, centred at the origin) moved by `(½, ½)`, written
/// as `dir/name`.
pub fn unit_plane(dir: &Path, name: &str, n: usize) -> PathBuf {
    let mut m = datasets::mesh::shapes::plane(n + 1);
    for p in &mut m.positions {
        (p[0], p[1]) = (p[0] + 0.5, p[1] + 0.5);
    }
    let path = dir.join(name);
    datasets::write_obj(&m, &path, "unit plane").unwrap();
    path
}

/// A datasets mesh (`kind`, low resolution) written as `dir/name`.
pub fn synth_mesh(dir: &Path, name: &str, kind: datasets::MeshKind) -> PathBuf {
    let m = datasets::synth_mesh(kind, datasets::Resolution::Low).unwrap();
    let path = dir.join(name);
    datasets::write_obj(&m, &path, name).unwrap();
    path
}

/// An orthographic camera for the small test scenes.
#[derive(Debug, Clone, Copy)]
pub struct Ortho {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    /// World height of the view.
    pub height: f32,
}

/// Looking at the unit plane `[0, 1]²` from above.
pub const OVER_PLANE: Ortho = Ortho { eye: [0.5, 0.5, 4.0], target: [0.5, 0.5, 0.0], height: 1.0 };

/// Looking at a sphere around the origin from `+z`, view height 2.
pub const OVER_SPHERE: Ortho = Ortho { eye: [0.0, 0.0, 5.0], target: [0.0, 0.0, 0.0], height: 2.0 };

impl Ortho {
    /// The same camera with view height `height`.
    pub fn with_height(self, height: f32) -> Ortho {
        Ortho { height, ..self }
    }
}

/// A white directional light shining from `direction` (irradiance 1).
pub fn directional(direction: [f32; 3]) -> Light {
    Light::Directional { direction, irradiance: [1.0; 3], shadows: true }
}

/// A grey point light of `intensity` at `position`.
pub fn point(position: [f32; 3], intensity: f32) -> Light {
    Light::Point { position, intensity: [intensity; 3], shadows: true }
}

/// An environment light of the map `dir/file` with a scene file's defaults (no rotation,
/// exposure 1, visibility 16², two-sided, no eigenweightsets, no cache).
pub fn environment(dir: &Path, file: &str) -> EnvironmentLight {
    EnvironmentLight {
        path: dir.join(file),
        rotation_deg: 0.0,
        exposure: 1.0,
        visibility_res: 16,
        two_sided: true,
        eigenweightsets: None,
        cache_dir: None,
    }
}

/// A `transmission` table with a scene file's defaults (albedo 0.8, isotropic, no τ
/// texture) and optical thickness `tau`.
pub fn thin(tau: f32) -> TransmissionDesc {
    TransmissionDesc {
        tau,
        tau_texture: None,
        albedo: Albedo::Grey(0.8),
        phase: PhaseDesc::Isotropic,
    }
}

/// Builds a [`Scene`] value as a scene file in `dir` would describe it: file names are
/// taken relative to `dir`; [`SceneBuilder::build`] validates it as `Scene::load` does.
pub struct SceneBuilder {
    dir: PathBuf,
    scene: Scene,
}

impl SceneBuilder {
    /// A `size × size` scene in `dir` with an orthographic camera over the unit plane and
    /// no meshes, materials or lights yet.
    pub fn new(dir: &Path, size: u32) -> SceneBuilder {
        let mut b = SceneBuilder {
            dir: dir.to_path_buf(),
            scene: Scene {
                output: Output { width: size, height: size, ..Default::default() },
                meshes: Vec::new(),
                materials: Vec::new(),
                camera: Camera {
                    projection: Projection::Perspective,
                    eye: [0.0, 0.0, 1.0],
                    target: [0.0; 3],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: 40.0,
                    ortho_height: 1.0,
                },
                lights: Vec::new(),
                // One sample per pixel: the references are per-pixel CPU evaluations at
                // pixel centres (the scene default, 4 samples, averages silhouettes); the
                // tests that are about MSAA ask for it.
                effects: Effects { msaa: 1, ..Effects::default() },
                yarns: Vec::new(),
            },
        };
        b = b.ortho(OVER_PLANE);
        b
    }

    /// Frame size.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        (self.scene.output.width, self.scene.output.height) = (width, height);
        self
    }

    /// The mesh `dir/file`.
    pub fn mesh(mut self, file: &str) -> Self {
        self.scene.meshes.push(MeshDesc { path: self.dir.join(file), planar_uv: None });
        self
    }

    /// The default material: the eigen store `dir/store` on every face no other takes.
    pub fn material(self, store: &str) -> Self {
        self.material_with(None, store, 1.0, None)
    }

    /// A material: `name` (`usemtl`; `None`: the default), `dir/store`, `uv_scale`,
    /// `transmission` (a τ texture's file taken relative to `dir`).
    pub fn material_with(
        mut self,
        name: Option<&str>,
        store: &str,
        uv_scale: f32,
        mut transmission: Option<TransmissionDesc>,
    ) -> Self {
        if let Some(t) = &mut transmission {
            t.resolve(&self.dir);
        }
        self.scene.materials.push(MaterialDesc {
            name: name.map(str::to_string),
            store: self.dir.join(store),
            uv_scale,
            transmission,
        });
        self
    }

    /// An orthographic camera (up `+y`).
    pub fn ortho(mut self, cam: Ortho) -> Self {
        let c = &mut self.scene.camera;
        (c.projection, c.eye, c.target, c.up) =
            (Projection::Orthographic, cam.eye, cam.target, [0.0, 1.0, 0.0]);
        c.ortho_height = cam.height;
        self
    }

    /// A perspective camera.
    pub fn perspective(
        mut self,
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fov_y_deg: f32,
    ) -> Self {
        let c = &mut self.scene.camera;
        (c.projection, c.eye, c.target, c.up, c.fov_y_deg) =
            (Projection::Perspective, eye, target, up, fov_y_deg);
        self
    }

    /// One more light.
    pub fn light(mut self, light: Light) -> Self {
        self.scene.lights.push(light);
        self
    }

    /// Changes the effects.
    pub fn effects(mut self, f: impl FnOnce(&mut Effects)) -> Self {
        f(&mut self.scene.effects);
        self
    }

    /// Changes the output (background, environment shown).
    pub fn output(mut self, f: impl FnOnce(&mut Output)) -> Self {
        f(&mut self.scene.output);
        self
    }

    /// The scene, validated.
    pub fn build(self) -> Scene {
        self.scene.validate(&self.dir.join("scene (built in code)")).unwrap();
        self.scene
    }
}
