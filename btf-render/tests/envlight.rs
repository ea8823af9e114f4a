//! Environment lighting on the CPU (Sattler et al. 2003, §5): white furnace, analytic
//! visibility of a concave corner, a fully occluded vertex, a bright sun, eigenweightsets
//! (exact at e = A − 1, 360° identity) and the visibility cache.

mod common;

use btf_core::eigen::{EigenSlot, EigenStore, Quantization};
use btf_core::{Direction, InterpMode};
use btf_image::EnvMap;
use btf_light::mesh::Mesh;
use btf_light::tangent::compute_tangents;
use btf_light::{
    CoefficientMatrix, EigenWeightSets, EnvCube, GatherInput, Hemicube, HemicubeFrame, LightTable,
    Radiances, VisibilityMaps,
};
use common::Pattern;
use std::f64::consts::PI;

struct Setup {
    cube: Hemicube,
    table: LightTable,
    frames: Vec<HemicubeFrame>,
    vis: VisibilityMaps,
    slots: Vec<EigenSlot>,
    p: CoefficientMatrix,
    store: EigenStore,
}

fn setup(mesh: &Mesh, res: u32, pattern: Pattern, c: usize) -> (Setup, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let path = common::write_store(dir.path(), "m.eigen", pattern, 2, 2, c, Quantization::F16);
    let store = EigenStore::open(&path).unwrap();
    let slots: Vec<EigenSlot> =
        (0..store.view_sampling().len()).map(|j| store.read_slot(j).unwrap()).collect();
    let p = CoefficientMatrix::from_slots(&slots, store.light_sampling().len(), c);
    let cube = Hemicube::new(res).unwrap();
    let table = LightTable::new(&cube, store.light_sampling(), InterpMode::Four).unwrap();
    let tangents = compute_tangents(mesh);
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, false);
    let vis = VisibilityMaps::compute(&cube, &frames, &mesh.positions, &mesh.triangles);
    (Setup { cube, table, frames, vis, slots, p, store }, dir)
}

impl Setup {
    fn gather(&self, env: &EnvCube, delta: f64) -> Radiances {
        let input = GatherInput {
            table: &self.table,
            visibility: &self.vis,
            frames: &self.frames,
            dirs: &self.cube.dirs,
            lights: self.p.lights,
        };
        Radiances::gather(&input, env, delta)
    }

    /// Radiance of texel 0 of frame `f` seen from tangent-space `view` (eq. 11, f = 1).
    fn radiance(&self, w: &Radiances, f: usize, view: Direction) -> [f32; 3] {
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

fn sphere(seg: usize) -> Mesh {
    Mesh::parse_obj(&common::sphere_obj(0.5, [0.0; 3], seg), "sphere.obj", None).unwrap()
}

fn furnace_error(hemicube_res: u32, cube_res: usize) -> f64 {
    let mesh = sphere(16);
    let (s, _d) = setup(&mesh, hemicube_res, Pattern::Lambert, 1);
    for f in 0..s.frames.len() {
        assert!(s.vis.visible_fraction(&s.cube, f) > 0.999_999, "vertex {f} occluded on a sphere");
    }
    let env = EnvCube::new(&EnvMap::constant(64, [1.0; 3]).unwrap(), cube_res);
    let w = s.gather(&env, 0.0);
    let mut worst = 0f64;
    for f in (0..s.frames.len()).step_by(7) {
        for view in
            [Direction::new(0.0, 0.0), Direction::new(40.0, 100.0), Direction::new(80.0, 250.0)]
        {
            let l = s.radiance(&w, f, view);
            for ch in l {
                worst = worst.max((ch as f64 / 0.8 - 1.0).abs());
            }
        }
    }
    eprintln!(
        "white furnace: hemicube {hemicube_res}, cube {cube_res}: worst relative error {worst:.5}"
    );
    worst
}

#[test]
fn white_furnace_gives_the_albedo() {
    // Hemicube quadrature and the bilinear interpolation of the concave cos θ across 15°
    // rings (≈ 0.4 % low) stay within 1 % at the default (cube texels = hemicube pixels).
    assert!(furnace_error(32, 32) < 0.01);
    assert!(furnace_error(16, 16) < 0.01);
}

/// A floor grid with a vertex at the origin and a wall rectangle at `x = d`.
fn corner_mesh(d: f32, half_width: f32, height: f32) -> Mesh {
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

fn rect_solid_angle(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let f = |a: f64, b: f64| (a * b / (1.0 + a * a + b * b).sqrt()).atan();
    f(a1, b1) - f(a0, b1) - f(a1, b0) + f(a0, b0)
}

#[test]
fn concave_corner_matches_the_analytic_visible_fraction() {
    let (d, hw, h) = (0.1f32, 0.5f32, 0.3f32);
    let mesh = corner_mesh(d, hw, h);
    let centre = 12; // the grid vertex at the origin
    assert_eq!(mesh.positions[centre], [0.0, 0.0, 0.0]);
    let wall = rect_solid_angle(-(hw / d) as f64, (hw / d) as f64, 0.0, (h / d) as f64);
    let expect = 1.0 - wall / (2.0 * PI);
    for res in [16, 32, 64] {
        let (s, _d) = setup(&mesh, res, Pattern::Uniform, 1);
        let got = s.vis.visible_fraction(&s.cube, centre);
        eprintln!("corner: res {res}: visible {got:.5}, analytic {expect:.5}");
        // Pixels straddling the wall's outline are counted whole: the error is bounded by
        // the outline's pixels, O(1/res).
        assert!((got - expect).abs() < 1.0 / res as f64, "res {res}: {got} vs {expect}");
    }
}

#[test]
fn fully_occluded_vertex_is_black_not_nan() {
    // A small plane inside a closed box: its vertices see nothing of the environment.
    let mut mesh = corner_mesh(10.0, 0.1, 0.1);
    let b = mesh.positions.len() as u32;
    for z in [-1.0f32, 1.0] {
        for y in [-1.0f32, 1.0] {
            for x in [-1.0f32, 1.0] {
                mesh.positions.push([x, y, z]);
                mesh.normals.push([0.0, 0.0, 1.0]);
                mesh.uvs.push([x, y]);
            }
        }
    }
    let q = |a: u32, c: u32, e: u32, g: u32| [[b + a, b + c, b + e], [b + a, b + e, b + g]];
    for f in
        [q(0, 1, 3, 2), q(4, 5, 7, 6), q(0, 1, 5, 4), q(2, 3, 7, 6), q(0, 2, 6, 4), q(1, 3, 7, 5)]
    {
        mesh.triangles.extend(f);
    }
    mesh.triangle_material = vec![0; mesh.triangles.len()];
    let (s, _d) = setup(&mesh, 8, Pattern::Checker, 4);
    let env = EnvCube::new(&EnvMap::constant(32, [5.0; 3]).unwrap(), 4);
    let w = s.gather(&env, 0.0);
    assert_eq!(s.vis.visible_fraction(&s.cube, 12), 0.0);
    let l = s.radiance(&w, 12, Direction::new(30.0, 10.0));
    assert_eq!(l, [0.0; 3], "occluded vertex must be black");
}

/// Sky of radiance 1 and a sun of angular radius 0.5° that is 1e5 times brighter.
fn sun_env(width: usize, sun: [f64; 3]) -> (EnvMap, f64) {
    let cos_r = 0.5f64.to_radians().cos();
    let env = EnvMap::from_fn(width, |d| {
        let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
        [if c >= cos_r { 1e5 } else { 1.0 }; 3]
    })
    .unwrap();
    let sky = 4.0 * PI;
    let sun_power = env.integral()[0] - sky; // Σ (L − 1) dω over the sun's pixels
    (env, sun_power)
}

#[test]
fn bright_sun_is_finite_without_speckle() {
    let mesh = sphere(24);
    let (s, _d) = setup(&mesh, 16, Pattern::Lambert, 1);
    let sun = [0.6, 0.0, 0.8];
    let (env, sun_power) = sun_env(1024, sun);
    let w = s.gather(&EnvCube::new(&env, 16), 0.0);
    assert!(w.g.iter().all(|g| g.is_finite()));
    let (mut worst, mut sq) = (0f64, 0f64);
    for f in 0..s.frames.len() {
        let l = s.radiance(&w, f, Direction::new(0.0, 0.0))[0] as f64 * PI / 0.8; // irradiance
        let n = s.frames[f].axes[2];
        let cos = (n[0] as f64 * sun[0] + n[1] as f64 * sun[1] + n[2] as f64 * sun[2]).max(0.0);
        let expect = PI + sun_power * cos;
        let err = (l - expect).abs() / sun_power;
        worst = worst.max(err);
        sq += err * err;
    }
    let rms = (sq / s.frames.len() as f64).sqrt();
    eprintln!("sun 1e5: worst error {worst:.4} of the sun's irradiance, rms {rms:.4}");
    // The sun keeps its power and direction; what is left is the hemicube's quantisation of
    // directions (half a pixel, ≤ 3.6° at res 16, i.e. ≤ 0.063 of cos θ) — the sampling's
    // own expectation. Point-sampling the map at pixel centres would miss it or count it ×50.
    assert!(worst < 0.063 && rms < 0.025, "worst {worst}, rms {rms}");
}

#[test]
fn eigenweightsets_reproduce_every_rotation_and_360_is_identity() {
    // A sphere standing on a floor: rotations change the lighting and the occlusion.
    let mut mesh = sphere(12);
    let floor = corner_mesh(10.0, 0.1, 0.1);
    let b = mesh.positions.len() as u32;
    for p in &floor.positions[..25] {
        mesh.positions.push([p[0] * 5.0, p[1] * 5.0, -0.5]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.uvs.push([p[0], p[1]]);
    }
    mesh.triangles.extend(floor.triangles[..32].iter().map(|t| t.map(|i| i + b)));
    mesh.triangle_material = vec![0; mesh.triangles.len()];
    let (s, _d) = setup(&mesh, 8, Pattern::Checker, 4);
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let cube = EnvCube::new(&env, 8);
    let a_n = 30;
    let sets: Vec<Radiances> = (0..a_n).map(|a| s.gather(&cube, a as f64 * 12.0)).collect();
    let metric = s.p.metric();
    let full = s.gather(&cube, 360.0);
    assert!(btf_light::eigenweights::relative_error(&full, &sets[0], &metric) < 1e-6);
    let ews = EigenWeightSets::build(&sets, &metric, a_n - 1).unwrap();
    for (a, set) in sets.iter().enumerate() {
        let r = ews.reconstruct(a as f64 * 12.0, a_n - 1);
        let e = btf_light::eigenweights::relative_error(&r, set, &metric);
        assert!(e < 1e-6, "U_{a}: relative error {e}");
    }
    // The metric form equals the plain error of U = G·P.
    let (u0, ur) = (sets[3].full_u(&s.p), ews.reconstruct(36.0, 3).full_u(&s.p));
    let num: f64 = u0.iter().zip(&ur).map(|(a, b)| ((a - b) as f64).powi(2)).sum();
    let den: f64 = u0.iter().map(|a| (*a as f64).powi(2)).sum();
    let via_metric =
        btf_light::eigenweights::relative_error(&ews.reconstruct(36.0, 3), &sets[3], &metric);
    assert!(
        ((num / den).sqrt() - via_metric).abs() < 1e-4 * via_metric.max(1e-3),
        "{} vs {via_metric}",
        (num / den).sqrt()
    );
    let r1 = ews.reconstruct(100.0, 5);
    assert_eq!(r1.g, ews.reconstruct(460.0, 5).g);
}

#[test]
fn visibility_cache_round_trips_and_survives_corruption() {
    let mesh = corner_mesh(0.1, 0.5, 0.3);
    let cube = Hemicube::new(8).unwrap();
    let tangents = compute_tangents(&mesh);
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
    let dir = tempfile::tempdir().unwrap();
    let (a, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(!hit);
    let (b, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(hit && a == b);
    let file = std::fs::read_dir(dir.path()).unwrap().next().unwrap().unwrap().path();
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[30] ^= 0xff;
    std::fs::write(&file, bytes).unwrap();
    let (c, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(!hit && c == a);
    // A different resolution is a different key.
    let (_, hit) = VisibilityMaps::cached(
        dir.path(),
        &Hemicube::new(4).unwrap(),
        &frames,
        &mesh.positions,
        &mesh.triangles,
    )
    .unwrap();
    assert!(!hit);
    // Back sides (two-sided cloth) of the floor see the lower hemisphere: unoccluded.
    assert!((a.visible_fraction(&cube, frames.len() / 2 + 12) - 1.0).abs() < 1e-12);
    // A subset of the frames: served by the maps of all frames when those are cached, else
    // computed and cached under a key of its own.
    let (pos, tris) = (&mesh.positions, &mesh.triangles);
    let wanted: Vec<bool> = (0..frames.len()).map(|f| f % 3 == 0).collect();
    let (d, hit, all) =
        VisibilityMaps::cached_some(dir.path(), &cube, &frames, Some(&wanted), pos, tris).unwrap();
    assert!(hit && all && d == a, "the full maps serve a subset");
    let fresh = tempfile::tempdir().unwrap();
    let run =
        || VisibilityMaps::cached_some(fresh.path(), &cube, &frames, Some(&wanted), pos, tris);
    let ((e, hit_e, all_e), (f, hit_f, all_f)) = (run().unwrap(), run().unwrap());
    assert!(!hit_e && hit_f && e == f && !all_e && !all_f);
    for k in 0..frames.len() {
        let expect = if wanted[k] { a.frame_bits(k).to_vec() } else { vec![0; a.words] };
        assert_eq!(e.frame_bits(k), &expect[..], "frame {k}");
    }
    let (g, hit) = VisibilityMaps::cached(fresh.path(), &cube, &frames, pos, tris).unwrap();
    assert!(!hit && g == a, "a subset never stands in for all frames");
}

#[test]
fn non_finite_environment_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.exr");
    exr::prelude::write_rgb_file(&p, 16, 8, |x, y| {
        if (x, y) == (3, 2) { (f32::INFINITY, 0.0, 0.0) } else { (1.0, 1.0, 1.0) }
    })
    .unwrap();
    let e = EnvMap::load(&p).unwrap_err().to_string();
    assert!(e.contains("bad.exr") && e.contains("x=3, y=2") && e.contains("non-finite"), "{e}");
    let ok = dir.path().join("ok.exr");
    exr::prelude::write_rgb_file(&ok, 16, 8, |_, _| (0.5, 1.0, 2.0)).unwrap();
    let m = EnvMap::load(&ok).unwrap();
    assert_eq!((m.width, m.height, m.pixels[5]), (16, 8, [0.5, 1.0, 2.0]));
    assert!(EnvMap::load(&dir.path().join("x.png")).is_err());
}

/// A 12×12 sheet crumpled by pseudo-random heights about one grid step high: every kind of
/// near and far occluder at once.
fn crumpled_sheet() -> Mesh {
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

fn shirt_low() -> Mesh {
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

#[test]
fn fast_visibility_equals_the_ray_cast() {
    let meshes = [
        ("sphere", sphere(16), 16),
        ("corner", corner_mesh(0.1, 0.5, 0.3), 32),
        // Rows of two mask words (96 = 64 + 32) and the smallest cube.
        ("corner", corner_mesh(0.1, 0.5, 0.3), 96),
        ("sphere", sphere(8), 2),
        ("crumpled sheet", crumpled_sheet(), 16),
        ("shirt low", shirt_low(), 8),
    ];
    for (name, mesh, res) in meshes {
        let cube = Hemicube::new(res).unwrap();
        let tangents = compute_tangents(&mesh);
        let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
        let (pos, tris) = (&mesh.positions, &mesh.triangles);
        let fast = VisibilityMaps::compute(&cube, &frames, pos, tris);
        let reference = VisibilityMaps::compute_ray_cast(&cube, &frames, pos, tris);
        let differ: u32 =
            fast.bits.iter().zip(&reference.bits).map(|(a, b)| (a ^ b).count_ones()).sum();
        let visible: u32 = reference.bits.iter().map(|w| w.count_ones()).sum();
        let share = visible as f64 / (frames.len() * cube.len()) as f64;
        eprintln!(
            "{name}: {} frames, {differ} differing pixels, visible share {share:.3}",
            frames.len()
        );
        assert_eq!(differ, 0, "{name}: fast visibility differs from the ray cast");
        // Not a trivial case: both occluded and visible pixels occur.
        assert!(share > 0.05 && share < 0.95, "{name}: visible share {share}");
    }
}

#[test]
fn fast_gather_reproduces_the_frame_by_frame_sums_bit_for_bit() {
    let mesh = crumpled_sheet();
    let (env, _) = sun_env(256, [0.5, 0.3, 0.812]);
    let cube_env = EnvCube::new(&env, 16);
    // Every frame, and a subset as a camera leaves it (a third of the vertices with neither
    // side, whose frames the gather skips; one side for the others).
    for (two_sided, subset) in [(false, false), (true, false), (false, true), (true, true)] {
        let (mut s, _d) = setup(&mesh, 16, Pattern::Checker, 4);
        let tangents = compute_tangents(&mesh);
        s.frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, two_sided);
        let (pos, tris) = (&mesh.positions, &mesh.triangles);
        s.vis = VisibilityMaps::compute(&s.cube, &s.frames, pos, tris);
        if subset {
            let n = mesh.positions.len();
            let wanted: Vec<bool> = (0..s.frames.len())
                .map(|f| !(f % n).is_multiple_of(3) && (f < n) == f.is_multiple_of(2))
                .collect();
            let some = VisibilityMaps::compute_some(&s.cube, &s.frames, &wanted, pos, tris);
            for f in 0..s.frames.len() {
                let expect: Vec<u64> =
                    if wanted[f] { s.vis.frame_bits(f).to_vec() } else { vec![0; s.vis.words] };
                assert_eq!(some.frame_bits(f), &expect[..], "frame {f}");
            }
            s.vis = some;
        }
        let input = GatherInput {
            table: &s.table,
            visibility: &s.vis,
            frames: &s.frames,
            dirs: &s.cube.dirs,
            lights: s.p.lights,
        };
        for delta in [0.0, 37.0] {
            let fast = Radiances::gather(&input, &cube_env, delta);
            let reference = Radiances::gather_reference(&input, &cube_env, delta);
            assert!(fast.g.iter().any(|&g| g > 0.0));
            assert_eq!(fast, reference, "two-sided {two_sided}, subset {subset}, δ = {delta}");
        }
    }
}

#[test]
fn gamma_basis_equals_gamma_star_of_the_reconstruction() {
    let mesh = crumpled_sheet();
    let (s, _d) = setup(&mesh, 8, Pattern::Checker, 4);
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let cube = EnvCube::new(&env, 8);
    let sets: Vec<Radiances> = (0..12).map(|a| s.gather(&cube, a as f64 * 30.0)).collect();
    let ews = EigenWeightSets::build(&sets, &s.p.metric(), 5).unwrap();
    let picks: Vec<(usize, usize)> = (0..s.frames.len()).map(|f| (f, f % s.p.slots)).collect();
    let basis = ews.gamma_basis(&s.p, &picks, 5).unwrap();
    let k3 = 3 * s.p.per_slot();
    let mut fast = vec![0f32; picks.len() * k3];
    let mut slow = vec![0f32; k3];
    for delta in [0.0, 47.0, 200.0] {
        basis.at(&ews.coefficients_at(delta, 5), &mut fast);
        let g = ews.reconstruct(delta, 5);
        for (n, &(f, j)) in picks.iter().enumerate() {
            g.gamma_star(&s.p, f, j, &mut slow);
            let scale = slow.iter().fold(1e-6f32, |m, x| m.max(x.abs()));
            for (a, b) in fast[n * k3..(n + 1) * k3].iter().zip(&slow) {
                // Same sums in another order: f32 rounding of ~100 terms.
                assert!((a - b).abs() <= 1e-4 * scale, "δ {delta}, pick {n}: {a} vs {b}");
            }
        }
    }
    assert!(ews.gamma_basis(&s.p, &[(s.frames.len(), 0)], 5).is_err());
}

#[test]
fn renderer_rotation_through_the_camera_basis_equals_the_direct_path() {
    use btf_light::env_coefficients::fill_direct;
    use btf_light::{EnvCoefficients, EnvironmentParams, SceneEnvironment, Slots};
    use btf_light::{EnvMesh, ViewInput};
    use btf_render::material::MaterialData;
    use btf_render::math::Vec3;
    use btf_render::per_vertex::{self, VertexCoefficients};
    let mesh = crumpled_sheet();
    let dir = tempfile::tempdir().unwrap();
    let store =
        common::write_store(dir.path(), "m.eigen", Pattern::Checker, 2, 2, 4, Quantization::F16);
    let mat = MaterialData::load(&store, None).unwrap();
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let tangents = compute_tangents(&mesh);
    let em = EnvMesh {
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        triangles: &mesh.triangles,
    };
    let params = EnvironmentParams {
        rotation_deg: 10.0,
        exposure: 0.7,
        visibility_res: 8,
        two_sided: true,
        eigen: Some((12, 5)),
        cache_dir: None,
    };
    let mut s = SceneEnvironment::new(
        params,
        &env,
        &em,
        &mat.light_sampling,
        vec![mat.coefficient_matrix()],
    )
    .unwrap();
    let n = mesh.positions.len();
    let stride = per_vertex::stride(mat.groups);
    let (material_of, mats) = (vec![0usize; n], [&mat.view_sampling]);
    let view_from = |eye: Vec3| ViewInput {
        eye,
        ortho_to_camera: None,
        view_mode: InterpMode::Four,
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        material_of: &material_of,
        view_samplings: &mats,
    };
    let blank = || VertexCoefficients {
        slots: vec![[0; 4]; n],
        coef: vec![[0.0; 4]; n * 4 * stride],
        irradiance: Vec::new(),
    };
    // The sheet is seen from both sides (the camera below it sees back sides).
    let view = view_from(Vec3::new(0.3, -2.0, -0.4));
    let at = Slots { l: 0, n_lights: 1, stride };
    let mut ec = EnvCoefficients::default();
    ec.fill(&s, &mut blank().coef, &view, at);
    assert!(!ec.used_basis(), "first fill at a camera: the direct path");
    for delta in [47.0, 200.0, 370.0] {
        s.set_rotation(delta);
        let (mut fast, mut slow) = (blank(), blank());
        ec.fill(&s, &mut fast.coef, &view, at);
        assert!(ec.used_basis(), "δ {delta}: a rotation under the same camera streams the basis");
        fill_direct(&s, &mut slow.coef, &view, at);
        let scale = slow.coef.iter().flatten().fold(0f32, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (a, b) in fast.coef.iter().flatten().zip(slow.coef.iter().flatten()) {
            // Same sums in another order: f32 rounding of ~100 terms.
            assert!((a - b).abs() <= 1e-4 * scale, "δ {delta}: {a} vs {b} (scale {scale})");
        }
    }
    // A camera move and an exact rotation take the direct path again.
    ec.fill(&s, &mut blank().coef, &view_from(Vec3::new(2.0, 0.5, 1.0)), at);
    assert!(!ec.used_basis());
    s.set_rotation_exact(30.0);
    ec.fill(&s, &mut blank().coef, &view, at);
    assert!(!ec.used_basis());
}
