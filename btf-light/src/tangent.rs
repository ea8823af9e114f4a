//! The per-vertex tangent frame from the UV parametrisation (DESIGN.md §3).
//!
//! Tangent space is the frame in which the BTF was measured: `+x` along texture `+u`,
//! `+y` along increasing texture *row* and `+z` the normal. OBJ's `v` grows upwards, the
//! opposite of image rows (texture row = `(1 − v) · h`), so `+y` is the direction of
//! `−∂P/∂v`. Per triangle, `∂P/∂u` and `∂P/∂v` follow from the edge vectors and UV deltas;
//! they are accumulated over a vertex's triangles weighted by area, then made orthogonal to
//! the vertex normal. A vertex keeps `T = +x` as a unit vector and a sign `s` with
//! `B = s · (N × T) = +y`; `s = −1` for an unmirrored OBJ mapping. Triangles with
//! degenerate UVs contribute nothing; a vertex without any usable triangle gets an arbitrary
//! frame around its normal (finite, never NaN).

use crate::math::{Vec3, any_perpendicular, v3};
use crate::mesh::Mesh;

/// Per-vertex tangents `[Tx, Ty, Tz, s]`, `B = s · (N × T)`.
pub fn compute_tangents(mesh: &Mesh) -> Vec<[f32; 4]> {
    let n = mesh.positions.len();
    let mut acc_u = vec![Vec3::zeros(); n];
    let mut acc_v = vec![Vec3::zeros(); n];
    for tri in &mesh.triangles {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (p0, p1, p2) = (v3(mesh.positions[i0]), v3(mesh.positions[i1]), v3(mesh.positions[i2]));
        let (t0, t1, t2) = (mesh.uvs[i0], mesh.uvs[i1], mesh.uvs[i2]);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (du1, dv1, du2, dv2) = (t1[0] - t0[0], t1[1] - t0[1], t2[0] - t0[0], t2[1] - t0[1]);
        let det = du1 * dv2 - du2 * dv1;
        let area = e1.cross(&e2).norm() * 0.5;
        let uv_area = det.abs() * 0.5;
        if !(uv_area > 1e-12 && area > 0.0 && area.is_finite()) {
            continue;
        }
        let dpdu = (e1 * dv2 - e2 * dv1) / det;
        let dpdv = (e2 * du1 - e1 * du2) / det;
        let (Some(du), Some(dv)) = (dpdu.try_normalize(0.0), dpdv.try_normalize(0.0)) else {
            continue;
        };
        for i in [i0, i1, i2] {
            acc_u[i] += du * area;
            acc_v[i] += dv * area;
        }
    }
    (0..n).map(|i| frame_from(v3(mesh.normals[i]), acc_u[i], acc_v[i])).collect()
}

/// Orthonormalises accumulated `∂P/∂u`, `∂P/∂v` against `normal` into `[T, s]`.
fn frame_from(normal: Vec3, dpdu: Vec3, dpdv: Vec3) -> [f32; 4] {
    let n = normal.try_normalize(0.0).unwrap_or(Vec3::z());
    let row_dir = -dpdv; // +y of tangent space: increasing texture row = −v
    let t = (dpdu - n * n.dot(&dpdu))
        .try_normalize(1e-12)
        .or_else(|| (row_dir - n * n.dot(&row_dir)).try_normalize(1e-12).map(|b| b.cross(&n)))
        .unwrap_or_else(|| any_perpendicular(n));
    // Without information (row_dir = 0) assume the usual unmirrored OBJ mapping, s = −1.
    let s = if n.cross(&t).dot(&row_dir) > 0.0 { 1.0 } else { -1.0 };
    [t.x, t.y, t.z, s]
}

/// The frame `(T, B, N)` of a vertex: tangent-space `+x`, `+y`, `+z` in world space.
pub fn frame(normal: [f32; 3], tangent: [f32; 4]) -> (Vec3, Vec3, Vec3) {
    let n = v3(normal).try_normalize(0.0).unwrap_or(Vec3::z());
    let t = Vec3::new(tangent[0], tangent[1], tangent[2]);
    let t = (t - n * n.dot(&t)).try_normalize(1e-12).unwrap_or_else(|| any_perpendicular(n));
    (t, n.cross(&t) * tangent[3], n)
}

/// World direction → tangent-space components `(d·T, d·B, d·N)`.
pub fn to_tangent(d: Vec3, (t, b, n): (Vec3, Vec3, Vec3)) -> [f64; 3] {
    [d.dot(&t) as f64, d.dot(&b) as f64, d.dot(&n) as f64]
}

#[cfg(test)]
mod tests {
    use super::*;

    const PLANE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    const PLANE_ROT90: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0 0\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

    fn frames(obj: &str) -> Vec<(Vec3, Vec3, Vec3)> {
        let m = Mesh::parse_obj(obj, "test.obj", None).unwrap();
        compute_tangents(&m).iter().zip(&m.normals).map(|(t, n)| frame(*n, *t)).collect()
    }

    fn close(a: Vec3, b: [f32; 3]) -> bool {
        (a - v3(b)).norm() < 1e-5
    }

    #[test]
    fn plane_u_along_x_rows_along_minus_y() {
        // u grows with world x, v with world y: texture rows grow towards world −y.
        for (t, b, n) in frames(PLANE) {
            assert!(
                close(t, [1.0, 0.0, 0.0])
                    && close(b, [0.0, -1.0, 0.0])
                    && close(n, [0.0, 0.0, 1.0])
            );
        }
    }

    #[test]
    fn rotated_uvs_rotate_the_frame() {
        // u = 1 − y and v = x: +x_tangent = world −y, rows grow along world −x.
        for (t, b, _) in frames(PLANE_ROT90) {
            assert!(close(t, [0.0, -1.0, 0.0]), "{t:?}");
            assert!(close(b, [-1.0, 0.0, 0.0]), "{b:?}");
        }
    }

    #[test]
    fn mirrored_uvs_flip_the_sign_and_degenerate_uvs_stay_finite() {
        let mirrored =
            PLANE.replace("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1", "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0");
        for (_, b, _) in frames(&mirrored) {
            assert!(close(b, [0.0, 1.0, 0.0]), "{b:?}");
        }
        let degenerate = PLANE.replace(
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1",
            "vt 0.5 0.5\nvt 0.5 0.5\nvt 0.5 0.5\nvt 0.5 0.5",
        );
        for (t, b, n) in frames(&degenerate) {
            assert!(t.iter().chain(b.iter()).all(|c| c.is_finite()));
            assert!(
                t.dot(&n).abs() < 1e-6
                    && (t.norm() - 1.0).abs() < 1e-5
                    && (b.norm() - 1.0).abs() < 1e-5
            );
        }
    }
}
