//! A closed, manifold triangle mesh of the zero set of an implicit function: marching
//! tetrahedra on a regular grid (each cube split into the six Kuhn tetrahedra around its
//! main diagonal, so neighbouring cubes cut their shared faces alike and the surface has no
//! cracks), then a few rounds of tangential relaxation, projection back onto the zero set
//! (Newton steps along the field's gradient) and Delaunay edge flips, which turn the
//! slivers of marching tetrahedra into near-equilateral triangles without changing the
//! topology.
//!
//! The field is negative inside; triangles are wound counter-clockwise seen from outside.

use crate::vec3::{V3, add, cross, dot, length, normalize_or, scale, sub};
use rayon::prelude::*;
use std::collections::HashMap;

/// The six tetrahedra of a cube whose corners are numbered by bits `x | y << 1 | z << 2`.
const KUHN: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Triangles (counter-clockwise from outside) of the zero set of `f` inside the box
/// `[lo, hi]`, sampled every `h` metres; `f` must be positive on the box's border.
pub fn marching_tetrahedra(
    f: &(dyn Fn(V3) -> f64 + Sync),
    lo: V3,
    hi: V3,
    h: f64,
) -> (Vec<V3>, Vec<[u32; 3]>) {
    let n = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / h).ceil() as usize + 1);
    let node = |i: usize, j: usize, k: usize| {
        [lo[0] + i as f64 * h, lo[1] + j as f64 * h, lo[2] + k as f64 * h]
    };
    let idx = |i: usize, j: usize, k: usize| (k * n[1] + j) * n[0] + i;
    let mut values = vec![0.0; n[0] * n[1] * n[2]];
    values.par_chunks_mut(n[0] * n[1]).enumerate().for_each(|(k, slab)| {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let v = f(node(i, j, k));
                // No value exactly zero: the surface then never passes through a node.
                slab[j * n[0] + i] = if v.abs() < 1e-9 * h { 1e-9 * h } else { v };
            }
        }
    });
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut on_edge: HashMap<(usize, usize), u32> = HashMap::new();
    let mut vertex = |a: usize, b: usize, pa: V3, pb: V3, positions: &mut Vec<V3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *on_edge.entry(key).or_insert_with(|| {
            let (va, vb) = (values[a], values[b]);
            let t = (va / (va - vb)).clamp(0.05, 0.95);
            positions.push(add(pa, scale(sub(pb, pa), t)));
            (positions.len() - 1) as u32
        })
    };
    for k in 0..n[2] - 1 {
        for j in 0..n[1] - 1 {
            for i in 0..n[0] - 1 {
                let corner = |c: usize| (i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                let ids: [usize; 8] = std::array::from_fn(|c| {
                    let (a, b, cc) = corner(c);
                    idx(a, b, cc)
                });
                let neg = ids.iter().filter(|&&id| values[id] < 0.0).count();
                if neg == 0 || neg == 8 {
                    continue;
                }
                for tet in KUHN {
                    let tid = tet.map(|c| ids[c]);
                    let tp = tet.map(|c| {
                        let (a, b, cc) = corner(c);
                        node(a, b, cc)
                    });
                    let inside: Vec<usize> = (0..4).filter(|&q| values[tid[q]] < 0.0).collect();
                    let outside: Vec<usize> = (0..4).filter(|&q| values[tid[q]] >= 0.0).collect();
                    let polygon: Vec<u32> = match inside.len() {
                        1 | 3 => {
                            let (lone, others) = if inside.len() == 1 {
                                (inside[0], outside.clone())
                            } else {
                                (outside[0], inside.clone())
                            };
                            others
                                .iter()
                                .map(|&o| {
                                    vertex(tid[lone], tid[o], tp[lone], tp[o], &mut positions)
                                })
                                .collect()
                        }
                        2 => {
                            let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
                            // The quad a-c, a-d, b-d, b-c goes round the cut.
                            vec![
                                vertex(tid[a], tid[c], tp[a], tp[c], &mut positions),
                                vertex(tid[a], tid[d], tp[a], tp[d], &mut positions),
                                vertex(tid[b], tid[d], tp[b], tp[d], &mut positions),
                                vertex(tid[b], tid[c], tp[b], tp[c], &mut positions),
                            ]
                        }
                        _ => continue,
                    };
                    // Orient from the inside nodes towards the outside ones.
                    let centroid = |qs: &[usize]| {
                        let s = qs.iter().fold([0.0; 3], |s, &q| add(s, tp[q]));
                        scale(s, 1.0 / qs.len() as f64)
                    };
                    let out_dir = sub(centroid(&outside), centroid(&inside));
                    for w in 1..polygon.len() - 1 {
                        let mut t = [polygon[0], polygon[w], polygon[w + 1]];
                        let [p0, p1, p2] = t.map(|v| positions[v as usize]);
                        if dot(cross(sub(p1, p0), sub(p2, p0)), out_dir) < 0.0 {
                            t.swap(1, 2);
                        }
                        triangles.push(t);
                    }
                }
            }
        }
    }
    (positions, triangles)
}

/// Unit gradient of `f` at `p` by central differences of step `eps`, and its length.
pub fn gradient(f: &(dyn Fn(V3) -> f64 + Sync), p: V3, eps: f64) -> (V3, f64) {
    let g: V3 = std::array::from_fn(|k| {
        let mut a = p;
        let mut b = p;
        a[k] += eps;
        b[k] -= eps;
        (f(a) - f(b)) / (2.0 * eps)
    });
    let len = length(g);
    (normalize_or(g, [0.0, 0.0, 1.0]), len)
}

/// Moves `p` onto the zero set of `f` with a few Newton steps along the gradient.
pub fn project(f: &(dyn Fn(V3) -> f64 + Sync), mut p: V3, eps: f64) -> V3 {
    for _ in 0..4 {
        let v = f(p);
        let (n, len) = gradient(f, p, eps);
        if len < 1e-9 {
            break;
        }
        p = sub(p, scale(n, v / len));
        if v.abs() < 1e-7 {
            break;
        }
    }
    p
}

/// Improves the triangles of a mesh lying on the zero set of `f`: `rounds` of edge flips,
/// tangential relaxation towards the 1-ring's area-weighted centroid and re-projection.
pub fn improve(
    f: &(dyn Fn(V3) -> f64 + Sync),
    positions: &mut [V3],
    triangles: &mut [[u32; 3]],
    rounds: usize,
    eps: f64,
) {
    for _ in 0..rounds {
        flip_edges(positions, triangles);
        let mut sum = vec![[0.0; 3]; positions.len()];
        let mut weight = vec![0.0; positions.len()];
        for t in triangles.iter() {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let area = 0.5 * length(cross(sub(b, a), sub(c, a)));
            let centre = scale(add(add(a, b), c), 1.0 / 3.0);
            for &i in t {
                sum[i as usize] = add(sum[i as usize], scale(centre, area));
                weight[i as usize] += area;
            }
        }
        let moved: Vec<V3> = positions
            .par_iter()
            .enumerate()
            .map(|(i, &p)| {
                if weight[i] <= 0.0 {
                    return p;
                }
                let target = scale(sum[i], 1.0 / weight[i]);
                let (n, _) = gradient(f, p, eps);
                let d = sub(target, p);
                let tangential = sub(d, scale(n, dot(d, n)));
                project(f, add(p, scale(tangential, 0.8)), eps)
            })
            .collect();
        positions.copy_from_slice(&moved);
    }
    flip_edges(positions, triangles);
}

/// Smallest angle of a triangle (radians).
pub fn min_angle(a: V3, b: V3, c: V3) -> f64 {
    let ang = |p: V3, q: V3, r: V3| {
        let (u, v) = (sub(q, p), sub(r, p));
        let cosv = dot(u, v) / (length(u) * length(v)).max(1e-300);
        cosv.clamp(-1.0, 1.0).acos()
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

/// Flips interior edges whose two triangles are nearly coplanar when the flip raises the
/// smaller of their minimum angles (a surface version of Lawson's flips); keeps the mesh
/// manifold (an edge that already exists is never created).
pub fn flip_edges(positions: &[V3], triangles: &mut [[u32; 3]]) {
    for _pass in 0..6 {
        let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (ti, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.entry((a.min(b), a.max(b))).or_default().push(ti);
            }
        }
        let mut keys: Vec<(u32, u32)> = edges.keys().copied().collect();
        keys.sort_unstable();
        let mut touched = vec![false; triangles.len()];
        let mut flips = 0;
        for key in keys {
            let ts = &edges[&key];
            if ts.len() != 2 || touched[ts[0]] || touched[ts[1]] {
                continue;
            }
            let (t0, t1) = (ts[0], ts[1]);
            let (a, b) = key;
            let opp = |t: [u32; 3]| *t.iter().find(|&&v| v != a && v != b).unwrap();
            let (c, d) = (opp(triangles[t0]), opp(triangles[t1]));
            if c == d || edges.contains_key(&(c.min(d), c.max(d))) {
                continue;
            }
            let p = |i: u32| positions[i as usize];
            let n0 = normalize_or(tri_normal(p, triangles[t0]), [0.0; 3]);
            let n1 = normalize_or(tri_normal(p, triangles[t1]), [0.0; 3]);
            if dot(n0, n1) < 0.94 {
                continue;
            }
            let before = min_angle(p(a), p(b), p(c)).min(min_angle(p(a), p(b), p(d)));
            let after = min_angle(p(c), p(d), p(a)).min(min_angle(p(c), p(d), p(b)));
            if after <= before + 1e-3 {
                continue;
            }
            // Keep the winding: t0 = (a, b, c) in some rotation; the new triangles are
            // (c, d, b) and (d, c, a) when t0 runs a → b.
            let runs_ab = (0..3).any(|k| triangles[t0][k] == a && triangles[t0][(k + 1) % 3] == b);
            let (new0, new1) =
                if runs_ab { ([c, a, d], [d, b, c]) } else { ([c, b, d], [d, a, c]) };
            let nn0 = normalize_or(tri_normal(p, new0), [0.0; 3]);
            let nn1 = normalize_or(tri_normal(p, new1), [0.0; 3]);
            if dot(nn0, n0) < 0.5 || dot(nn1, n0) < 0.5 {
                continue;
            }
            triangles[t0] = new0;
            triangles[t1] = new1;
            touched[t0] = true;
            touched[t1] = true;
            flips += 1;
        }
        if flips == 0 {
            break;
        }
    }
}

/// Unnormalised normal `(b − a) × (c − a)` of triangle `t`.
pub fn tri_normal(p: impl Fn(u32) -> V3, t: [u32; 3]) -> V3 {
    let [a, b, c] = t.map(p);
    cross(sub(b, a), sub(c, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_is_closed_manifold_and_on_the_surface() {
        let f = |p: V3| length(p) - 0.3;
        let (mut pos, mut tris) = marching_tetrahedra(&f, [-0.4; 3], [0.4; 3], 0.05);
        improve(&f, &mut pos, &mut tris, 3, 1e-4);
        let mut m =
            crate::Mesh { positions: pos.clone(), triangles: tris.clone(), ..Default::default() };
        m.compute_normals();
        assert_eq!(m.edge_counts(), (0, 0));
        let worst = pos.iter().map(|&p| (length(p) - 0.3).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-5, "off the sphere by {worst}");
        // Outward winding: the enclosed volume is positive and close to 4/3 π r³.
        let vol: f64 = tris
            .iter()
            .map(|t| dot(pos[t[0] as usize], cross(pos[t[1] as usize], pos[t[2] as usize])) / 6.0)
            .sum();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.027;
        assert!((vol / exact - 1.0).abs() < 0.03, "volume {vol} vs {exact}");
        let worst_angle = tris
            .iter()
            .map(|t| min_angle(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]))
            .fold(f64::MAX, f64::min);
        assert!(worst_angle.to_degrees() > 5.0, "min angle {}", worst_angle.to_degrees());
    }
}
