//! Stitch-mesh checks: flat periodicity, exact affine maps, inverse UV lookup on a
//! cylinder with a seam, and the named error for a cell without a preimage.

use super::*;
use std::f64::consts::TAU;

fn stockinette() -> Chart {
    Chart::builtin("stockinette").unwrap()
}

#[test]
fn flat_patch_is_exactly_periodic() {
    let m = StitchMesh::flat(&stockinette(), 8, 4, 0.004, 0.003).unwrap();
    let l = m.lattice.unwrap();
    assert_eq!(l, [[0.032, 0.0, 0.0], [0.0, 0.012, 0.0]]);
    for k in 0..50 {
        let (w, c) = (-3.7 + 0.31 * k as f64, -1.35 + 0.17 * k as f64);
        let (p, n) = m.eval(w, c);
        let (q, _) = m.eval(w + 8.0, c);
        let (r, _) = m.eval(w, c + 4.0);
        assert!(vec3::distance(vec3::add(p, l[0]), q) < 1e-15);
        assert!(vec3::distance(vec3::add(p, l[1]), r) < 1e-15);
        assert!(vec3::distance(p, [0.004 * w, 0.003 * c, 0.0]) < 1e-15);
        assert_eq!(n, [0.0, 0.0, 1.0]);
    }
    assert!(StitchMesh::flat(&Chart::builtin("rib2x2").unwrap(), 6, 2, 1e-3, 1e-3).is_err());
}

#[test]
fn affine_maps_move_corners_exactly() {
    let m = StitchMesh::flat(&stockinette(), 4, 4, 0.004, 0.003).unwrap();
    let (eu, ev, g) = (0.3, -0.1, 0.25);
    let s = m.stretch(eu, ev).unwrap();
    let h = m.shear(g).unwrap();
    for c in 0..=4 {
        for w in 0..=4 {
            let i = c * 5 + w;
            let (x, y) = (0.004 * w as f64, 0.003 * c as f64);
            assert_eq!(s.corners[i], [(1.0 + eu) * x, (1.0 + ev) * y, 0.0]);
            assert_eq!(h.corners[i], [x + g * y, y, 0.0]);
        }
    }
    assert_eq!(h.lattice.unwrap()[1], [g * 0.012, 0.012, 0.0]);
    // The sheared patch still wraps by its (sheared) lattice.
    let (p, _) = h.eval(1.3, 0.6);
    let (q, _) = h.eval(1.3, 4.6);
    assert!(vec3::distance(vec3::add(p, [g * 0.012, 0.012, 0.0]), q) < 1e-15);
    assert!(m.map_affine([[1.0, 2.0], [0.5, 1.0]]).is_err());
}

/// A cylinder of radius `r` and height `h` along z, `n` facets around, `rows` rings; the UV
/// chart is `[0, 1]²` with a seam at u = 0 ≡ 1 (duplicated UVs, shared positions).
fn cylinder(r: f64, h: f64, n: usize, rows: usize) -> SurfaceMesh {
    let mut m = SurfaceMesh::default();
    for j in 0..=rows {
        for i in 0..n {
            let a = TAU * i as f64 / n as f64;
            m.positions.push([r * a.cos(), r * a.sin(), h * j as f64 / rows as f64]);
            m.normals.push([a.cos(), a.sin(), 0.0]);
        }
        for i in 0..=n {
            m.uvs.push([i as f64 / n as f64, j as f64 / rows as f64]);
        }
    }
    let p = |i: usize, j: usize| (j * n + i % n) as u32;
    let t = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..rows {
        for i in 0..n {
            m.triangles.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            m.triangle_uvs.push([t(i, j), t(i + 1, j), t(i + 1, j + 1)]);
            m.triangles.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            m.triangle_uvs.push([t(i, j), t(i + 1, j + 1), t(i, j + 1)]);
        }
    }
    m
}

#[test]
fn uv_lookup_on_a_cylinder_with_a_seam() {
    let (r, h, n, rows) = (0.1, 0.2, 12, 4);
    let cyl = cylinder(r, h, n, rows);
    let chart = stockinette();
    // Corners on every other vertex ring and at the midpoints of the facets' chords.
    let layout = UvLayout {
        origin: [0.0, 0.0],
        wale_du: 0.5 / n as f64,
        course_dv: 0.5 / rows as f64,
        wales: 2 * n,
        courses: 2 * rows,
    };
    let m = StitchMesh::on_surface(&cyl, &chart, &layout).unwrap();
    let ring = |i: usize, z: f64| {
        let a = TAU * (i % n) as f64 / n as f64;
        [r * a.cos(), r * a.sin(), z]
    };
    let mut worst: f64 = 0.0;
    for c in 0..=2 * rows {
        for w in 0..=2 * n {
            let z = h * c as f64 / (2 * rows) as f64;
            let expect = if w % 2 == 0 {
                ring(w / 2, z)
            } else {
                vec3::lerp(ring(w / 2, z), ring(w / 2 + 1, z), 0.5)
            };
            worst = worst.max(vec3::distance(m.corners[c * (2 * n + 1) + w], expect));
        }
    }
    assert!(worst < 1e-9 * r, "worst {worst}");
    // The seam: wale 0 and wale 2n (u = 0 and u = 1) are the same 3-D points.
    for c in 0..=2 * rows {
        let row = c * (2 * n + 1);
        assert!(vec3::distance(m.corners[row], m.corners[row + 2 * n]) < 1e-12);
    }
    // Normals interpolate radially.
    let nrm = m.normals[2 * n + 1 + 2];
    assert!((nrm[0] - (TAU / n as f64).cos()).abs() < 1e-12);
    // A layout running off the chart names the first cell without a preimage.
    let off =
        UvLayout { origin: [0.25, 0.75], wale_du: 0.05, course_dv: 0.1, wales: 3, courses: 4 };
    let e = StitchMesh::on_surface(&cyl, &chart, &off).unwrap_err().to_string();
    assert!(
        e.contains("stitch cell (course 2, wale 0)") && e.contains("uv (0.250000, 1.050000)"),
        "{e}"
    );
}

#[test]
fn derivatives_are_those_of_the_bilinear_map() {
    // A flat patch with its corners displaced (non-parallelogram cells, out of plane),
    // periodic and open: ∂x/∂w and ∂x/∂c against central differences of `eval` inside a
    // cell (the map is bilinear there, so the difference is exact up to rounding).
    let mut m = StitchMesh::flat(&stockinette(), 4, 4, 0.004, 0.003).unwrap();
    for (i, p) in m.corners.iter_mut().enumerate() {
        let x = i as f64;
        p[0] += 4e-4 * (1.7 * x).sin();
        p[1] += 3e-4 * (2.3 * x).cos();
        p[2] += 5e-4 * (0.9 * x).sin();
    }
    for lattice in [m.lattice, None] {
        let mut m = m.clone();
        m.lattice = lattice;
        for k in 0..40 {
            let (w, c) = (0.13 + 0.097 * k as f64, 0.21 + 0.083 * k as f64);
            let (w, c) = (w.floor() + 0.1 + 0.8 * w.fract(), c.floor() + 0.1 + 0.8 * c.fract());
            let h = 1e-6;
            let (dw, dc) = m.derivatives(w, c);
            let fw = vec3::scale(vec3::sub(m.eval(w + h, c).0, m.eval(w - h, c).0), 0.5 / h);
            let fc = vec3::scale(vec3::sub(m.eval(w, c + h).0, m.eval(w, c - h).0), 0.5 / h);
            assert!(vec3::distance(dw, fw) < 1e-9, "∂x/∂w at ({w}, {c}): {dw:?} vs {fw:?}");
            assert!(vec3::distance(dc, fc) < 1e-9, "∂x/∂c at ({w}, {c}): {dc:?} vs {fc:?}");
        }
    }
}
