//! Cloth–cloth contact (self-collision), Chen et al. 2003 §4.1.2–4.1.3 with the knit
//! design's choices (§1.3 items 3, 16): every node is tested against the triangles that do
//! not contain it, found through a [`HashGrid`] of triangle boxes inflated by the contact
//! reach plus a margin; the candidate list is rebuilt only when some node has moved more
//! than half the margin since the last build (a Verlet list). A node closer than `T` to a
//! triangle is pushed away by the thickness field ([`super::field`], constants `c₇, c₈`)
//! and the reaction goes to the triangle's nodes by barycentric weight. Each candidate
//! remembers which side of the triangle the node was on when it was found, so a node that
//! did cross is pushed back to its side rather than further through.
//!
//! [C03 §4.1.2] lets a triangle act on a point only when the distance vector lies within
//! 45° of the triangle's normal (the influence cone, [`SelfContact::cone_cos`]); without it
//! every node of a flat sheet would be pushed sideways by the neighbouring cells'
//! triangles, whose closest points lie in the sheet's own plane. Self-friction is the
//! dynamic law of [C03 eq. 3] with the layer field's push as the normal force and no
//! static part ([C03 §4.1.3]); the paper's `c₈` is replaced by the C¹ barrier of
//! [`super::field`], like `c₆`.

use super::field::ThicknessField;
use super::hashgrid::HashGrid;
use crate::garment::sdf::closest_point_triangle;
use crate::vec3::{V3, cross, dot, length, normalize_or, scale, sub};
use rayon::prelude::*;

/// A node near a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The node.
    pub node: u32,
    /// The triangle.
    pub tri: u32,
    /// The side of the triangle (±1 along its normal) the node was on when found.
    pub side: f64,
}

/// Self-collision constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContact {
    /// Field between cloth layers (`c₇`, reach `T`, barrier from `τ`).
    pub field: ThicknessField,
    /// Extra reach of the candidate search beyond `T` (m).
    pub margin: f64,
    /// Dynamic friction between layers (`K_d`; Chen has no static self-friction).
    pub dynamic_friction: f64,
    /// Cosine of the influence cone's half-angle: a triangle pushes a node only if
    /// `|d̂ · n̂| ≥ cone_cos` (`cos 45°` in [C03 §4.1.2]; 0 = the whole half-space).
    pub cone_cos: f64,
}

fn tri_points(x: &[V3], t: [u32; 3]) -> [V3; 3] {
    t.map(|i| x[i as usize])
}

/// All (node, triangle) pairs closer than `reach`, the node not a corner of the triangle,
/// sorted by node then triangle.
pub fn candidates(x: &[V3], triangles: &[[u32; 3]], reach: f64) -> Vec<Candidate> {
    let boxes: Vec<(V3, V3)> = triangles
        .iter()
        .map(|&t| {
            let p = tri_points(x, t);
            let lo = [0, 1, 2].map(|k| p.iter().map(|q| q[k]).fold(f64::MAX, f64::min) - reach);
            let hi = [0, 1, 2].map(|k| p.iter().map(|q| q[k]).fold(f64::MIN, f64::max) + reach);
            (lo, hi)
        })
        .collect();
    let mean_edge = if triangles.is_empty() {
        reach
    } else {
        triangles
            .iter()
            .take(512)
            .map(|&t| {
                let p = tri_points(x, t);
                length(sub(p[1], p[0]))
            })
            .sum::<f64>()
            / triangles.len().min(512) as f64
    };
    let grid = HashGrid::build(&boxes, (2.0 * reach).max(mean_edge));
    let per_node: Vec<Vec<Candidate>> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            let p = x[i];
            let mut found: Vec<u32> = grid
                .query(p)
                .iter()
                .copied()
                .filter(|&ti| {
                    let t = triangles[ti as usize];
                    let (lo, hi) = boxes[ti as usize];
                    !t.contains(&(i as u32)) && (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])
                })
                .collect();
            found.sort_unstable();
            found.dedup();
            found
                .into_iter()
                .filter_map(|ti| {
                    let q = tri_points(x, triangles[ti as usize]);
                    let (c, _) = closest_point_triangle(p, q[0], q[1], q[2]);
                    if length(sub(p, c)) >= reach {
                        return None;
                    }
                    let n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
                    let side = if dot(sub(p, c), n) >= 0.0 { 1.0 } else { -1.0 };
                    Some(Candidate { node: i as u32, tri: ti, side })
                })
                .collect()
        })
        .collect();
    per_node.into_iter().flatten().collect()
}

/// The same pairs by testing every node against every triangle (for tests).
pub fn candidates_brute_force(x: &[V3], triangles: &[[u32; 3]], reach: f64) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for (i, &p) in x.iter().enumerate() {
        for (ti, &t) in triangles.iter().enumerate() {
            if t.contains(&(i as u32)) {
                continue;
            }
            let q = tri_points(x, t);
            let (c, _) = closest_point_triangle(p, q[0], q[1], q[2]);
            if length(sub(p, c)) < reach {
                out.push((i as u32, ti as u32));
            }
        }
    }
    out
}

/// One contact's push: the node's force and the triangle's barycentric weights.
#[derive(Debug, Clone, Copy)]
pub struct Push {
    /// Force on the node (N); the triangle's corners get `−w_k` times it.
    pub force: V3,
    /// Barycentric weights of the contact point.
    pub weights: [f64; 3],
    /// Stiffness of the push (N/m), for the time-step bound.
    pub stiffness: f64,
    /// Magnitude of the push (N), for friction.
    pub magnitude: f64,
    /// Unit direction of the push.
    pub normal: V3,
}

impl SelfContact {
    /// The push of candidate `c` at positions `x`, if the node is within reach.
    pub fn push(&self, c: &Candidate, x: &[V3], triangles: &[[u32; 3]]) -> Option<Push> {
        let p = x[c.node as usize];
        let q = tri_points(x, triangles[c.tri as usize]);
        let (cp, w) = closest_point_triangle(p, q[0], q[1], q[2]);
        let n_tri = normalize_or(cross(sub(q[1], q[0]), sub(q[2], q[0])), [0.0, 0.0, 1.0]);
        let d_vec = sub(p, cp);
        let d = length(d_vec);
        // Outside the influence cone (e.g. a neighbour in the sheet's own plane, whose side
        // is only rounding noise): no push.
        if self.cone_cos > 0.0 && d > 1e-12 && dot(d_vec, n_tri).abs() < self.cone_cos * d {
            return None;
        }
        let same_side = dot(d_vec, n_tri) * c.side >= 0.0;
        let (dist, dir) = if same_side && d > 1e-9 {
            (d, scale(d_vec, 1.0 / d))
        } else {
            // On or through the triangle: push back to the remembered side.
            (if same_side { 0.0 } else { -d }, scale(n_tri, c.side))
        };
        if dist >= self.field.thickness {
            return None;
        }
        let (f, k) = self.field.force(dist);
        Some(Push { force: scale(dir, f), weights: w, stiffness: k, magnitude: f, normal: dir })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_grid_finds_the_same_pairs_as_brute_force() {
        // Two crumpled sheets close together.
        let n = 12;
        let mut x = Vec::new();
        let mut tris = Vec::new();
        for layer in 0..2 {
            let base = x.len() as u32;
            for j in 0..n {
                for i in 0..n {
                    let (u, v) = (i as f64 * 0.02, j as f64 * 0.02);
                    let z = layer as f64 * 0.006 + 0.004 * (u * 40.0).sin() * (v * 31.0).cos();
                    x.push([u + 0.003 * layer as f64, v, z]);
                }
            }
            for j in 0..n - 1 {
                for i in 0..n - 1 {
                    let id = |a: usize, b: usize| base + (b * n + a) as u32;
                    tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
        for reach in [0.004, 0.008, 0.015] {
            let fast: Vec<(u32, u32)> =
                candidates(&x, &tris, reach).iter().map(|c| (c.node, c.tri)).collect();
            let slow = candidates_brute_force(&x, &tris, reach);
            assert_eq!(fast, slow, "reach {reach}");
            // the layers are 6 mm apart (± 8 mm of crumple): the wider reaches meet the
            // other sheet, the narrowest may not
            assert!(reach < 0.008 || !slow.is_empty(), "reach {reach}: no pair to compare");
        }
    }
}
