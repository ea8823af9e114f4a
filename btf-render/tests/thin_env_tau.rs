//! Per-texel thickness under an environment light (`transmission/env.rs`, τ nodes): the
//! 2-D tables `[τ_j × μ_k]` interpolated like the shader, against the f64 quadrature at
//! thicknesses between the nodes, with the linear-interpolation remainder as the bound;
//! and the cost of the textured tables against the scalar ones.

mod common;
#[path = "common/curtain_env.rs"]
mod curtain_env;

use btf_light::thin_tables::{
    MU_NODES, ROWS_PER_SIDE, SlabParams, TAU_NODES, VEC4_PER_VERTEX, interpolate, mu_node, tables,
    tau_node,
};
use curtain_env::*;

#[test]
fn textured_tables_interpolate_in_tau_within_the_linear_remainder() {
    let dir = tempfile::tempdir().unwrap();
    let c = curtain_env(dir.path());
    let n = c.mesh.positions.len();
    let albedo = [0.9, 0.8, 0.7];
    let slab = SlabParams { tau: 2.0, textured: true, albedo };
    let scalar = SlabParams { textured: false, ..slab };
    // Cost of the 8 τ nodes against the scalar table, back to back.
    let t0 = std::time::Instant::now();
    let got = tables(&c.env, &vec![Some(slab); n]).unwrap();
    let textured_s = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    tables(&c.env, &vec![Some(scalar); n]).unwrap();
    let scalar_s = t0.elapsed().as_secs_f64();
    eprintln!(
        "tables of {n} vertices: textured {textured_s:.3} s, scalar {scalar_s:.3} s, ratio {:.2}",
        textured_s / scalar_s
    );
    let mus: Vec<f64> = (0..MU_NODES).map(mu_node).collect();
    let (mut worst_a, mut worst_t, mut worst_ratio) = (0f64, [0f64; 2], 0f64);
    for v in (0..n).step_by(n / 5) {
        for side in 0..2 {
            let f = side * n + v;
            let rows = &got[v * VEC4_PER_VERTEX + side * ROWS_PER_SIDE..][..ROWS_PER_SIDE];
            // τ = 0 is the transparent row exactly.
            let (a, t) = interpolate(rows, &slab, 0.5, 0.0);
            assert_eq!((a, t), ([1.0; 3], [0.0; 3]));
            for j in 0..TAU_NODES - 1 {
                let (lo, hi) = (tau_node(2.0, j), tau_node(2.0, j + 1));
                let tau = lo + 0.37 * (hi - lo);
                let (a_ref, t_ref, _) = reference(&c, f, tau, albedo, &mus);
                // Linear interpolation's remainder |f''| (τ − τ_j)(τ_{j+1} − τ)/2, with
                // |f''| the largest of central differences at both ends and the middle.
                let h = 0.25 * (hi - lo);
                let second = |x: f64| {
                    let at = |x: f64| reference(&c, f, x, albedo, &mus);
                    let (l, m, r) = (at(x - h), at(x), at(x + h));
                    let d2 = |p: f64, q: f64, s: f64| (p - 2.0 * q + s).abs() / (h * h);
                    let a = [0, 1, 2].map(|ch| d2(l.0[ch], m.0[ch], r.0[ch]));
                    let t: Vec<[f64; 3]> = (0..MU_NODES)
                        .map(|k| [0, 1, 2].map(|ch| d2(l.1[k][ch], m.1[k][ch], r.1[k][ch])))
                        .collect();
                    (a, t)
                };
                let ends = [lo.max(h), 0.5 * (lo + hi), hi].map(second);
                let remainder = (tau - lo) * (hi - tau) / 2.0;
                for ch in 0..3 {
                    let bound_a =
                        1.25 * remainder * ends.iter().map(|e| e.0[ch]).fold(0.0, f64::max);
                    let (a, _) = interpolate(rows, &slab, 1.0, tau);
                    let err = (a[ch] - a_ref[ch]).abs();
                    assert!(err <= bound_a + 1e-6, "A at τ {tau}: error {err} > {bound_a}");
                    worst_a = worst_a.max(err);
                    for (k, &mu) in mus.iter().enumerate() {
                        let bound =
                            1.25 * remainder * ends.iter().map(|e| e.1[k][ch]).fold(0.0, f64::max);
                        let (_, t) = interpolate(rows, &slab, mu, tau);
                        let err = (t[ch] - t_ref[k][ch]).abs();
                        let floor = 1e-6 * t_ref[k][ch].abs() + 1e-9;
                        assert!(
                            err <= bound + floor,
                            "vertex {v} side {side} τ {tau} μ {mu}: T {} vs {}, bound {bound}",
                            t[ch],
                            t_ref[k][ch]
                        );
                        worst_ratio = worst_ratio.max(err / (bound + floor));
                        if mu >= 0.05 && t_ref[k][ch] >= 1e-2 * t_ref[MU_NODES - 1][ch] {
                            let w = &mut worst_t[(j > 0) as usize];
                            *w = w.max(err / t_ref[k][ch]);
                        }
                    }
                }
            }
        }
    }
    // The constant-texture render of `curtain_limits_under_an_environment`: τ = 0.4 with
    // τ_max = 1; its image tolerance is this table error.
    let unit = SlabParams { tau: 1.0, ..slab };
    let got = tables(&c.env, &vec![Some(unit); n]).unwrap();
    let (mut worst_share, mut worst_t04) = (0f64, 0f64);
    for v in (0..n).step_by(n / 13) {
        for side in 0..2 {
            let rows = &got[v * VEC4_PER_VERTEX + side * ROWS_PER_SIDE..][..ROWS_PER_SIDE];
            let probe: Vec<f64> = (0..=16).map(|i| 0.05 + 0.95 * i as f64 / 16.0).collect();
            let (a_ref, t_ref, _) = reference(&c, side * n + v, 0.4, albedo, &probe);
            for (i, &mu) in probe.iter().enumerate() {
                let (a, t) = interpolate(rows, &unit, mu, 0.4);
                let alpha = (-0.4 / mu).exp();
                for ch in 0..3 {
                    let share_ref = 1.0 - alpha * a_ref[ch];
                    worst_share = worst_share.max(alpha * (a[ch] - a_ref[ch]).abs() / share_ref);
                    worst_t04 = worst_t04.max((t[ch] - t_ref[i][ch]).abs() / t_ref[i][ch]);
                }
            }
        }
    }
    eprintln!(
        "τ = 0.4 (τ_max 1), μ ∈ [0.05, 1]: worst relative error of the share {worst_share:.2e}, of T {worst_t04:.2e}"
    );
    // Bilinear: the √μ interpolation alone is ≤ 1 % for τ ≥ 0.1, μ ≥ 0.05 (env.rs), the τ
    // direction adds its linear remainder; measured 0.67 % (share) and 2.6 % (T).
    assert!(worst_share < 1e-2 && worst_t04 < 3e-2, "{worst_share} {worst_t04}");
    eprintln!(
        "τ interpolation: worst |ΔA| {worst_a:.2e}; worst relative ΔT at μ ≥ 0.05 where T ≥ 10⁻² T(μ = 1): {:.2e} in [τ_0, τ_1], {:.2e} above; worst error / bound {worst_ratio:.2}",
        worst_t[0], worst_t[1]
    );
}
