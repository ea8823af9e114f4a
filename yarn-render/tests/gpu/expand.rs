//! CPU = GPU fiber positions: `fiber_expand` read back against
//! `yarn::fiber::FiberModel::fiber_point` (DESIGN §2.5: 1e-5 of the yarn radius in f32).

use crate::common::{cotton, crane_patch, open_wave};
use btf_render::Gpu;
use yarn::fiber::{EffectiveTwist, FiberModel, FiberTable, PeriodKind};
use yarn::{CurveFrames, YarnSet};
use yarn_render::passes::expand::{ExpandPass, all_instances};
use yarn_render::{PackOptions, PackedYarns, YarnBuffers};

/// Largest distance GPU − CPU over every fiber of every segment at `n_sub` steps, in units
/// of the yarn radius; also the number of loop slots the compared points crossed.
fn worst_error(gpu: &Gpu, set: &YarnSet, n_sub: u32) -> (f64, usize) {
    let p = cotton();
    let opts = PackOptions { seed: 7, frame_samples_per_segment: 4, tiles: [1, 1] };
    let packed = PackedYarns::new(set, std::slice::from_ref(&p), &opts).unwrap();
    let data = YarnBuffers::new(gpu, &packed).unwrap();
    let pass = ExpandPass::new(gpu, &data).unwrap();
    let inst = all_instances(&packed);
    let pts = pass.read(gpu, &data, &inst, n_sub, true).unwrap();
    let mut worst: f64 = 0.0;
    let mut loops = std::collections::BTreeSet::new();
    let models: Vec<_> = set
        .curves
        .iter()
        .enumerate()
        .map(|(ci, c)| {
            let table = FiberTable::new(&p, opts.seed, ci as u64);
            let twist = EffectiveTwist::for_curve(&p, c);
            (table, twist, CurveFrames::new(c, opts.frame_samples_per_segment))
        })
        .collect();
    for (i, &[seg, pf]) in inst.iter().enumerate() {
        let s = &packed.segments[seg as usize];
        let (ci, si) = (s.ids[0] as usize, s.ids[1] as usize);
        let (table, twist, frames) = &models[ci];
        let model = FiberModel { params: &p, table, twist: *twist };
        let (ply, f) = ((pf >> 16) as usize, (pf & 0xffff) as usize);
        for k in 0..=n_sub as usize {
            let u = si as f64 + k as f64 / n_sub as f64;
            let q = model.fiber_point(&set.curves[ci], frames, ply, f, u);
            let g = pts[i * (n_sub as usize + 1) + k];
            let d =
                (0..3).map(|a| (g[a] as f64 + packed.origin[a] - q[a]).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d / p.yarn_radius());
            let z = set.curves[ci].length_coord(u);
            let slot = model.slot_coord(z, ply, f).floor() as i64;
            if matches!(model.period_kind(ply, f, slot), PeriodKind::Loop { .. }) {
                loops.insert((ci, ply, f, slot));
            }
        }
    }
    (worst, loops.len())
}

#[test]
fn gpu_fibers_equal_the_cpu_generator_to_1e_5_of_the_yarn_radius() {
    let Some(gpu) = Gpu::for_tests("gpu_fibers_equal_the_cpu_generator") else { return };
    // Closed periodic courses (whole turns per wrap, slot keys reduced per wrap).
    let (err, loops) = worst_error(&gpu, &crane_patch(2, 2), 6);
    eprintln!("Crane patch 2×2: worst |GPU − CPU| = {err:.2e} yarn radii, {loops} loop slots");
    assert!(loops >= 5, "the comparison must cross loop slots (hash on the GPU): {loops}");
    assert!(err < 1e-5, "{err:e}");
    // An open yarn anchored to surface normals.
    let (err, loops) = worst_error(&gpu, &open_wave(), 8);
    eprintln!("open wave: worst |GPU − CPU| = {err:.2e} yarn radii, {loops} loop slots");
    assert!(err < 1e-5, "{err:e}");
}

#[test]
fn every_wgsl_file_is_valid() {
    let programs = yarn_render::wgsl_programs();
    assert_eq!(programs.len(), 8);
    for (name, src) in programs {
        btf_render::gpu::validate_wgsl(name, &src).unwrap();
    }
}

/// DESIGN §2.5 "pull = expand": the fiber points the vertex stage of `fiber_draw`
/// evaluates (its decoding and generator call, rasterised as points into an f32 target by
/// `FiberRenderer::pulled_points`) equal `fiber_expand`'s on the same instance list, bit
/// for bit.
#[test]
fn pulled_fiber_points_equal_the_expand_pass_bit_for_bit() {
    let Some(gpu) = Gpu::for_tests("pulled_fiber_points_equal_the_expand_pass") else { return };
    let p = cotton();
    let opts = PackOptions { seed: 7, frame_samples_per_segment: 4, tiles: [1, 1] };
    let packed = PackedYarns::new(&crane_patch(2, 2), std::slice::from_ref(&p), &opts).unwrap();
    let n_sub = 6;
    let settings = yarn_render::FiberSettings {
        n_sub,
        lod_px: 0.0,
        cull: false,
        msaa: 1,
        effects: yarn_render::FiberEffects::none(),
        ..Default::default()
    };
    let bcsdf = yarn::bcsdf::FiberBcsdf::khungurn(&Default::default()).unwrap();
    let r = yarn_render::FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
    let c = [0, 1, 2].map(|a| 0.5 * (packed.bounds.0[a] + packed.bounds.1[a]));
    let cam = yarn_render::FiberCamera::perspective(
        [c[0], c[1] - 0.03, c[2] + 0.03],
        c,
        [0.0, 0.0, 1.0],
        40.0,
    );
    let (inst, pulled) = r.pulled_points(&gpu, &cam, &[]).unwrap();
    let data = YarnBuffers::new(&gpu, &packed).unwrap();
    let expanded =
        ExpandPass::new(&gpu, &data).unwrap().read(&gpu, &data, &inst, n_sub, true).unwrap();
    assert_eq!(pulled.len(), expanded.len());
    let differ = pulled
        .iter()
        .zip(&expanded)
        .filter(|(a, b)| (0..3).any(|k| a[k].to_bits() != b[k].to_bits()))
        .count();
    let worst = pulled
        .iter()
        .zip(&expanded)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0f32, f32::max);
    eprintln!(
        "{} instances × {} points: {differ} of {} points differ in any bit (worst {worst:e} m)",
        inst.len(),
        n_sub + 1,
        pulled.len()
    );
    assert!(inst.len() > 100, "{}", inst.len());
    assert!(pulled.iter().all(|q| q[3] == 1.0), "every probe texel written");
    assert_eq!(differ, 0, "worst {worst:e}");
}
