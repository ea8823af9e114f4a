//! The knot solver's WGSL pass (`yarn_render::knot`) against the CPU solve of
//! `yarn::knit::knot` on the same frames: the f32 pass takes the f64 solve's steps to the
//! rounding of f32, so the knot points agree to a small fraction of the yarn radius and the
//! [H25 eq. 3] energy of the result is the CPU's within its f32 rounding.

use btf_render::Gpu;
use yarn::knit::{Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh};
use yarn_render::knot::KnotGpuSolver;

const R: f64 = 0.428e-3;

fn worst(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_gpu_knot_solve_matches_the_cpu_solve() {
    let Some(gpu) = Gpu::for_tests("the_gpu_knot_solve_matches_the_cpu_solve") else { return };
    let sk = SkeletonParams::new(R);
    let (sw, sc) = sk.default_spacing();
    let chart = Chart::builtin("rib1x1").unwrap();
    let rest = StitchMesh::flat(&chart, 8, 8, sw, sc).unwrap();
    let model = KnotModel::new(&rest, &sk, (sw, sc)).unwrap();
    let solver = KnotGpuSolver::new(&gpu, &model).unwrap();
    let p = KnotParams::default();
    // Far from the origin too: positions go to the GPU relative to the first corner.
    let mut far = rest.shear(0.3).unwrap();
    far.corners.iter_mut().for_each(|q| q[0] += 2.0);
    for (name, mesh) in [
        ("rest", rest.clone()),
        ("50 % wale stretch", rest.stretch(0.0, 0.5).unwrap()),
        ("30 % shear", rest.shear(0.3).unwrap()),
        ("30 % shear, 2 m off", far),
    ] {
        let cpu = model.solve(&mesh, &p).unwrap();
        let (gpu_frame, t) = solver.solve(&gpu, &model, &mesh, &p).unwrap();
        let dev = worst(&cpu.points, &gpu_frame.points) / R;
        let (ec, eg) = (model.energy(&cpu, &p), model.energy(&gpu_frame, &p));
        let e0 = model.energy(&model.initial(&mesh, p.beta).unwrap(), &p);
        eprintln!(
            "{name}: max |GPU − CPU| {dev:.2e} r; E₃ CPU {ec:.6e}, GPU {eg:.6e} (E₀ {e0:.4e}); \
             guard CPU {} GPU {}; prepare {:.2} ms, upload {:.2} ms, pass + read-back {:.2} ms, \
             finish {:.2} ms",
            cpu.stats.guard_triggers,
            gpu_frame.stats.guard_triggers,
            t.prepare * 1e3,
            t.upload * 1e3,
            t.gpu * 1e3,
            t.finish * 1e3
        );
        assert_eq!(gpu_frame.theta.len(), cpu.theta.len());
        assert!(dev < 1e-3, "{name}: the GPU's knot points are {dev} r from the CPU's");
        // The energy reached: the CPU's, up to what f32 rounding of the residuals leaves.
        assert!((eg - ec).abs() <= 1e-3 * e0 + 1e-7, "{name}: E₃ GPU {eg} against CPU {ec}");
    }
    // A solver built for another model is refused.
    let other =
        KnotModel::new(&StitchMesh::flat(&chart, 4, 4, sw, sc).unwrap(), &sk, (sw, sc)).unwrap();
    let e = solver.solve(&gpu, &other, &rest, &p).unwrap_err();
    assert!(e.to_string().contains("the pass was built for"), "{e}");
}
