//! The cost baselines and the sweep built on them: plain texture mapping reads slot 0's
//! mean; the read bound makes exactly the reads it is asked for (one mean then the packed
//! eigentexture layers of each slot, summed, in whole slots: a hashed share of pixels one
//! slot more); the sweep's rows carry the read counts the packing predicts and errors that
//! fall with `c`.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::cost_sweep::{self, SweepConfig};
use btf_render::material::MaterialData;
use btf_render::{Baseline, ReadForm, RenderOptions, Scene, render_scene};
use half::f16;

const SIZE: u32 = 32;

fn ortho_plane(dir: &std::path::Path) -> Scene {
    SceneBuilder::new(dir, SIZE)
        .mesh("plane.obj")
        .material("m.eigen")
        .ortho(Ortho { eye: [0.5, 0.5, 3.0], ..OVER_PLANE })
        .light(directional([0.3, 0.2, 1.0]))
        .build()
}

fn render(scene: &Scene, gpu: &btf_render::Gpu, baseline: Baseline) -> btf_render::Frame {
    render_scene(gpu, scene, RenderOptions { baseline: Some(baseline), ..Default::default() })
        .unwrap()
}

/// RGBA value of texel `t` in a packed layer of raw little-endian f16 bytes.
fn texel_f16(bytes: &[u8], layer: usize, texels: usize, t: usize) -> [f32; 4] {
    let at = |k: usize| {
        let i = ((layer * texels + t) * 4 + k) * 2;
        f16::from_le_bytes([bytes[i], bytes[i + 1]]).to_f32()
    };
    [at(0), at(1), at(2), at(3)]
}

#[test]
fn baselines_read_what_they_claim() {
    let Some(gpu) = gpu("baselines_read_what_they_claim") else { return };
    let dir = tempfile::tempdir().unwrap();
    let store = write_store(dir.path(), "m.eigen", Pattern::Checker, 32, 32, 16, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 2);
    let scene = ortho_plane(dir.path());
    let data = MaterialData::load(&store, None).unwrap();
    let texels = (SIZE * SIZE) as usize;
    // One pixel per texel: pixel (x, y) samples texel (x, y) exactly.
    let mut mean = Vec::new();
    let mut bound13 = Vec::new();
    for t in 0..texels {
        let m: Vec<f32> = (0..4).map(|k| data.mean_layers[t * 4 + k].to_f32()).collect();
        let mut acc = [m[0], m[1], m[2], m[3]];
        for layer in 0..12 {
            let e = texel_f16(&data.eigen_layers, layer, texels, t);
            for k in 0..4 {
                acc[k] += e[k];
            }
        }
        mean.extend_from_slice(&m[..3]);
        bound13.extend((0..3).map(|k| acc[k] + acc[3] * 1e-6));
    }
    let plain = render(&scene, &gpu, Baseline::Plain);
    let e = assert_close("plain-texture", SIZE, SIZE, &mean, &plain.rgb, 1e-3);
    let full =
        render(&scene, &gpu, Baseline::ReadBound { reads_per_pixel: 13.0, form: ReadForm::Loop });
    let e13 = assert_close("read-bound-13", SIZE, SIZE, &bound13, &full.rgb, 1e-3);
    assert!(plain.stats.ran("plain texture") && full.stats.ran("read bound"));
    // the grouped form makes the same reads (three per constant-length loop iteration)
    for reads in [13.0, 19.5] {
        let looped = render(
            &scene,
            &gpu,
            Baseline::ReadBound { reads_per_pixel: reads, form: ReadForm::Loop },
        );
        let grouped = render(
            &scene,
            &gpu,
            Baseline::ReadBound { reads_per_pixel: reads, form: ReadForm::Groups },
        );
        assert_close("read-bound groups vs loop", SIZE, SIZE, &looped.rgb, &grouped.rgb, 1e-6);
    }
    // 19.5 reads = 1.5 slots of 13: slot 0 everywhere, a second slot on about half the pixels.
    let half =
        render(&scene, &gpu, Baseline::ReadBound { reads_per_pixel: 19.5, form: ReadForm::Loop });
    let differ = (0..texels)
        .filter(|&t| (0..3).any(|k| (half.rgb[t * 3 + k] - full.rgb[t * 3 + k]).abs() > 1e-4))
        .count() as f64
        / texels as f64;
    // below one slot: no reads on most pixels (black), the whole slot on the rest
    let tenth =
        render(&scene, &gpu, Baseline::ReadBound { reads_per_pixel: 1.3, form: ReadForm::Loop });
    let black = (0..texels).filter(|&t| (0..3).all(|k| tenth.rgb[t * 3 + k] == 0.0)).count() as f64
        / texels as f64;
    eprintln!(
        "plain vs slot-0 mean {e:.1e}; 13 reads vs CPU sum {e13:.1e}; share of pixels with a second slot at 19.5 reads: {differ:.3}; without reads at 1.3: {black:.3}"
    );
    // 1024 pixels, binomial(0.9): ±5 standard deviations.
    assert!((black - 0.9).abs() < 0.05, "share without reads {black}");
    assert!((differ - 0.5).abs() < 0.08, "share with a second slot {differ}");
}

#[test]
fn sweep_rows_have_predicted_reads_and_falling_error() {
    let Some(gpu) = gpu("sweep_rows_have_predicted_reads_and_falling_error") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 16, 16, 8, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 4);
    let scene = SceneBuilder::new(dir.path(), 32)
        .mesh("plane.obj")
        .material("m.eigen")
        .perspective([0.5, -0.4, 1.0], [0.5, 0.5, 0.0], [0.0, 0.0, 1.0], 50.0)
        .light(directional([0.3, 0.2, 1.0]))
        .build();
    let config = SweepConfig { components: vec![4, 8, 32], repeats: 1 };
    let mut calls = 0;
    let r = cost_sweep::run(&gpu, &scene, &config, &mut |_, _| calls += 1).unwrap();
    assert_eq!((r.rows.len(), calls, r.reference_components), (8, 8, 8), "32 > stored is skipped");
    let row = |c: usize, e: &str, b: &str| {
        r.rows.iter().find(|x| x.components == c && x.evaluation == e && x.blending == b).unwrap()
    };
    for x in &r.rows {
        eprintln!(
            "c={} {} {}: err {:.2e}, reads {:.2}, btf {:.2} ms, plain {:.2} ms, bound {:.2} ms",
            x.components,
            x.evaluation,
            x.blending,
            x.rel_rmse,
            x.reads_per_pixel,
            x.btf_ms,
            x.plain_ms,
            x.read_bound_ms
        );
        assert!(x.btf_ms > 0.0 && x.plain_ms > 0.0 && x.read_bound_ms > 0.0);
        assert!(x.ratio_read_bound.is_finite() && x.ratio_plain.is_finite());
    }
    // Nearest view and light: one slot, 1 + 3⌈c/4⌉ reads.
    assert_eq!(row(4, "per-pixel", "nearest").reads_per_pixel, 4.0);
    assert_eq!(row(8, "per-pixel", "nearest").reads_per_pixel, 7.0);
    // The reference setting reproduces the reference; fewer components cost accuracy.
    assert!(row(8, "per-pixel", "four").rel_rmse < 1e-6);
    assert!(row(4, "per-pixel", "four").rel_rmse > 1e-3);
    assert!(row(4, "per-vertex", "four").rel_rmse > row(8, "per-vertex", "four").rel_rmse);
    assert!(r.per_pixel_reads_le_per_vertex);
    assert_eq!(r.fits.len(), 4);
}

/// The packed f16 weight layout (material.rs) holds every scaled weight and bias at its
/// documented place, within f16's rounding (2⁻¹¹ relative), for an odd and an even `G`.
#[test]
fn packed_weights_hold_every_weight_and_bias() {
    let dir = tempfile::tempdir().unwrap();
    for (components, name) in [(4, "g1.eigen"), (8, "g2.eigen"), (12, "g3.eigen")] {
        let store =
            write_store(dir.path(), name, Pattern::Checker, 8, 8, components, Quantization::F16);
        let data = MaterialData::load(&store, None).unwrap();
        let packed = data.packed_weights().expect("test weights fit f16");
        let g = data.groups;
        let stride = btf_render::material::packed_stride(g);
        let n_l = data.light_sampling.len();
        let half = |e: usize, h: usize| {
            let word = packed[e * stride + h / 8][(h % 8) / 2];
            f16::from_bits((word >> (16 * (h % 2))) as u16).to_f32()
        };
        let close = |a: f32, b: f32| (a - b).abs() <= b.abs() * 2f32.powi(-11) + 1e-7;
        for j in 0..data.view_sampling.len() {
            for i in 0..n_l {
                let e = j * n_l + i;
                for q in 0..g {
                    let row = data.weight_group(j, i, q);
                    for (k, &w) in row.iter().enumerate() {
                        assert!(
                            close(half(e, 4 * q + k), w),
                            "{name} slot {j} light {i} group {q}"
                        );
                    }
                }
                assert!(close(half(e, 4 * g), data.bias(j, i)), "{name} slot {j} light {i} bias");
            }
        }
        assert_eq!(packed.len(), n_l * data.view_sampling.len() * stride);
        // a weight beyond f16 (an HDR store) keeps the f32 rows
        let mut hdr = data.clone();
        hdr.weights[0][0] = 1e6;
        assert!(hdr.packed_weights().is_none(), "{name}: 1e6 must not be packed as f16");
    }
}

/// The separable per-vertex layout (per_vertex.rs) holds the same coefficients as the full
/// one: its scalars times each vertex's irradiance give every entry of the full layout, for
/// coloured HDR point and directional lights, and its f16 packing keeps each scalar within
/// f16's rounding.
#[test]
fn separable_per_vertex_layout_times_irradiance_is_the_full_layout() {
    use btf_core::InterpMode;
    use btf_light::mesh::Mesh;
    use btf_render::math::Vec3;
    use btf_render::per_vertex::{self, VertexEvalInput, VertexLight};
    let dir = tempfile::tempdir().unwrap();
    let mesh = Mesh::parse_obj(&plane_obj(3, false), "plane.obj", None).unwrap();
    let tangents = btf_light::tangent::compute_tangents(&mesh);
    let lights = [
        VertexLight { pos_or_dir: Vec3::new(0.4, 0.3, 0.6), point: true, color: [3e4, 2e4, 1e4] },
        VertexLight { pos_or_dir: Vec3::new(-0.2, 0.5, 0.8), point: false, color: [0.7, 1.1, 0.4] },
    ];
    for (components, name) in [(4, "g1.eigen"), (12, "g3.eigen")] {
        let store =
            write_store(dir.path(), name, Pattern::Checker, 8, 8, components, Quantization::F16);
        let data = MaterialData::load(&store, None).unwrap();
        let g = data.groups;
        let n = mesh.positions.len();
        let compute = |separable| {
            let input = VertexEvalInput {
                eye: Vec3::new(0.6, 0.2, 1.5),
                ortho_to_camera: None,
                lights: &lights,
                view_mode: InterpMode::Four,
                light_mode: InterpMode::Four,
                groups_stride: g,
                separable,
            };
            per_vertex::compute(
                &mesh.positions,
                &mesh.normals,
                &tangents,
                &vec![0; n],
                &[&data],
                &input,
            )
        };
        let (full, sep) = (compute(false), compute(true));
        assert_eq!(full.slots, sep.slots);
        let (k, ks) = (per_vertex::stride(g), per_vertex::scalar_stride(g));
        assert_eq!(sep.coef.len(), n * 2 * 4 * ks);
        assert_eq!(sep.irradiance.len(), n * 2);
        let packed = per_vertex::pack_scalars_f16(&sep.coef, g);
        let ps = per_vertex::packed_scalar_stride(g);
        assert_eq!(ps, (1 + 2 * g).div_ceil(4));
        let mut checked = 0;
        for v in 0..n {
            for l in 0..2 {
                let e = sep.irradiance[v * 2 + l];
                for m in 0..4 {
                    let entry = (v * 2 + l) * 4 + m;
                    let f = &full.coef[entry * k..][..k];
                    let s = &sep.coef[entry * ks..][..ks];
                    let mut expect = vec![
                        [s[0][0] * e[0], s[0][0] * e[1], s[0][0] * e[2], 0.0],
                        [s[0][1] * e[0], s[0][1] * e[1], s[0][1] * e[2], 0.0],
                    ];
                    for q in 0..g {
                        let y = s[1 + q];
                        expect.push([y[0] * e[0], y[0] * e[1], y[0] * e[2], y[1] * e[0]]);
                        expect.push([y[1] * e[1], y[1] * e[2], y[2] * e[0], y[2] * e[1]]);
                        expect.push([y[2] * e[2], y[3] * e[0], y[3] * e[1], y[3] * e[2]]);
                    }
                    let scale = f.iter().flatten().fold(0f32, |a, x| a.max(x.abs()));
                    for (a, b) in expect.iter().flatten().zip(f.iter().flatten()) {
                        assert!((a - b).abs() <= 1e-6 * scale, "{name} v{v} l{l} m{m}: {a} vs {b}");
                    }
                    checked += (scale > 0.0) as usize;
                    // the f16 scalars: word 0 the head, words 1 + 2q, 2 + 2q group q
                    let words: Vec<u32> =
                        packed[entry * ps..][..ps].iter().flatten().copied().collect();
                    let h =
                        |i: usize| f16::from_bits((words[i / 2] >> (16 * (i % 2))) as u16).to_f32();
                    let mut want = vec![s[0][0], s[0][1]];
                    want.extend(s[1..].iter().flatten());
                    for (i, &w) in want.iter().enumerate() {
                        assert!(
                            (h(i) - w).abs() <= w.abs() * 2f32.powi(-11) + 2f32.powi(-24),
                            "{name} v{v} l{l} m{m} scalar {i}"
                        );
                    }
                }
            }
        }
        assert!(checked > n, "{name}: most entries are lit ({checked})");
    }
}
