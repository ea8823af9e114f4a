//! What the garment tests measure: boundary loops and manifoldness of the welded mesh,
//! penetration into the body (signed distance sampled over every triangle), self-
//! intersection (a bounding-volume hierarchy over the triangles and an exact
//! segment–triangle test between non-adjacent pairs), degenerate triangles, the area
//! distortion between each triangle's panel shape and its draped shape, the continuity of
//! the warp direction inside panels and the agreement of tangent frames across seams.

use super::sdf::SdfGrid;
use crate::mesh::Mesh;
use crate::vec3::{V3, add, cross, dot, length, normalize_or, scale, sub};
use std::collections::HashMap;

/// Topology of a mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topology {
    /// Boundary loops and their lengths in edges.
    pub boundary_loops: Vec<usize>,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Interior edges whose two triangles run them the same way (inconsistent winding).
    pub misoriented_edges: usize,
    /// Vertices whose triangles do not form one fan (a pinch).
    pub non_manifold_vertices: usize,
    /// Connected components.
    pub components: usize,
}

/// Boundary loops, manifoldness and orientation of `triangles` over `n` vertices.
pub fn topology(n: usize, triangles: &[[u32; 3]]) -> Topology {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut undirected: HashMap<(u32, u32), u32> = HashMap::new();
    for (&(a, b), &c) in &directed {
        *undirected.entry((a.min(b), a.max(b))).or_default() += c;
    }
    let non_manifold_edges = undirected.values().filter(|&&c| c > 2).count();
    let misoriented_edges = directed
        .iter()
        .filter(|&(&(a, b), &c)| {
            a < b && (c > 1 || directed.get(&(b, a)).copied().unwrap_or(0) > 1)
        })
        .count();
    // Boundary half-edges a → b with no b → a.
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) {
            next.entry(a).or_default().push(b);
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut used: HashMap<(u32, u32), bool> = HashMap::new();
    let mut loops = Vec::new();
    for s in starts {
        for &first in &next[&s].clone() {
            if used.contains_key(&(s, first)) {
                continue;
            }
            let (mut a, mut b) = (s, first);
            let mut len = 0;
            loop {
                used.insert((a, b), true);
                len += 1;
                if b == s {
                    break;
                }
                let Some(cands) = next.get(&b) else { break };
                let Some(&c) = cands.iter().find(|&&c| !used.contains_key(&(b, c))) else { break };
                a = b;
                b = c;
            }
            loops.push(len);
        }
    }
    loops.sort_unstable_by(|a, b| b.cmp(a));
    // Vertex fans: triangles around a vertex connected through shared edges.
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (ti, t) in triangles.iter().enumerate() {
        for &v in t {
            around[v as usize].push(ti);
        }
    }
    let mut non_manifold_vertices = 0;
    for (v, ts) in around.iter().enumerate() {
        if ts.len() <= 1 {
            continue;
        }
        let others = |ti: usize| -> Vec<u32> {
            triangles[ti].iter().copied().filter(|&w| w != v as u32).collect()
        };
        let mut seen = vec![false; ts.len()];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(i) = stack.pop() {
            let oi = others(ts[i]);
            for j in 0..ts.len() {
                if !seen[j] && others(ts[j]).iter().any(|w| oi.contains(w)) {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        if seen.iter().any(|s| !s) {
            non_manifold_vertices += 1;
        }
    }
    // Components.
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for t in triangles {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, t[0] as usize), find(&mut parent, t[k] as usize));
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut used_v = vec![false; n];
    for t in triangles {
        for &v in t {
            used_v[v as usize] = true;
        }
    }
    let components = (0..n).filter(|&i| used_v[i] && find(&mut parent, i) == i).count();
    Topology {
        boundary_loops: loops,
        non_manifold_edges,
        misoriented_edges,
        non_manifold_vertices,
        components,
    }
}

/// Smallest signed distance to the body over each triangle's corners, edge midpoints and
/// centroid (m).
pub fn min_body_distance(mesh: &Mesh, sdf: &SdfGrid) -> f64 {
    let bary = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.5, 0.5, 0.0],
        [0.0, 0.5, 0.5],
        [0.5, 0.0, 0.5],
        [1.0 / 3.0; 3],
    ];
    mesh.triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| mesh.positions[i as usize]);
            bary.iter()
                .map(|w| {
                    sdf.query(add(add(scale(p[0], w[0]), scale(p[1], w[1])), scale(p[2], w[2]))).0
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Smallest signed distance of the mesh's vertices to the body (m).
pub fn min_vertex_distance(mesh: &Mesh, sdf: &SdfGrid) -> f64 {
    mesh.positions.iter().map(|&p| sdf.query(p).0).fold(f64::INFINITY, f64::min)
}

/// Smallest triangle angle (degrees) and area (m²).
pub fn worst_triangle(mesh: &Mesh) -> (f64, f64) {
    let mut angle = 180.0f64;
    let mut area = f64::INFINITY;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        angle = angle.min(super::isosurface::min_angle(a, b, c).to_degrees());
        area = area.min(0.5 * length(cross(sub(b, a), sub(c, a))));
    }
    (angle, area)
}

struct Node {
    lo: V3,
    hi: V3,
    /// Children, or a leaf's triangle range.
    kids: Option<(usize, usize)>,
    range: (usize, usize),
}

/// Pairs of triangles that share no vertex and intersect.
pub fn self_intersections(mesh: &Mesh) -> Vec<(u32, u32)> {
    let tris = &mesh.triangles;
    let p = |i: u32| mesh.positions[i as usize];
    let boxes: Vec<(V3, V3)> = tris
        .iter()
        .map(|t| {
            let q = t.map(p);
            (
                [0, 1, 2].map(|k| q.iter().map(|v| v[k]).fold(f64::MAX, f64::min)),
                [0, 1, 2].map(|k| q.iter().map(|v| v[k]).fold(f64::MIN, f64::max)),
            )
        })
        .collect();
    let mut order: Vec<usize> = (0..tris.len()).collect();
    let mut nodes: Vec<Node> = Vec::new();
    fn build(
        nodes: &mut Vec<Node>,
        order: &mut [usize],
        offset: usize,
        boxes: &[(V3, V3)],
    ) -> usize {
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for &i in order.iter() {
            for k in 0..3 {
                lo[k] = lo[k].min(boxes[i].0[k]);
                hi[k] = hi[k].max(boxes[i].1[k]);
            }
        }
        let id = nodes.len();
        nodes.push(Node { lo, hi, kids: None, range: (offset, offset + order.len()) });
        if order.len() > 8 {
            let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap();
            let mid = order.len() / 2;
            order.select_nth_unstable_by(mid, |&a, &b| {
                (boxes[a].0[axis] + boxes[a].1[axis])
                    .total_cmp(&(boxes[b].0[axis] + boxes[b].1[axis]))
            });
            let (l, r) = order.split_at_mut(mid);
            let a = build(nodes, l, offset, boxes);
            let b = build(nodes, r, offset + mid, boxes);
            nodes[id].kids = Some((a, b));
        }
        id
    }
    if tris.is_empty() {
        return Vec::new();
    }
    build(&mut nodes, &mut order, 0, &boxes);
    let overlap = |a: &(V3, V3), lo: V3, hi: V3| (0..3).all(|k| a.0[k] <= hi[k] && a.1[k] >= lo[k]);
    let mut hits = Vec::new();
    let mut stack = Vec::new();
    for (ti, t) in tris.iter().enumerate() {
        stack.clear();
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let node = &nodes[ni];
            if !overlap(&boxes[ti], node.lo, node.hi) {
                continue;
            }
            if let Some((a, b)) = node.kids {
                stack.push(a);
                stack.push(b);
                continue;
            }
            for &tj in &order[node.range.0..node.range.1] {
                if tj <= ti || !overlap(&boxes[ti], boxes[tj].0, boxes[tj].1) {
                    continue;
                }
                let u = tris[tj];
                if t.iter().any(|v| u.contains(v)) {
                    continue;
                }
                if triangles_intersect(t.map(p), u.map(p)) {
                    hits.push((ti as u32, tj as u32));
                }
            }
        }
    }
    hits.sort_unstable();
    hits
}

/// Whether segment `a–b` crosses triangle `t` (Möller–Trumbore, ends included).
fn segment_hits(a: V3, b: V3, t: [V3; 3]) -> bool {
    let d = sub(b, a);
    let (e1, e2) = (sub(t[1], t[0]), sub(t[2], t[0]));
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det.abs() < 1e-18 {
        return false;
    }
    let inv = 1.0 / det;
    let tv = sub(a, t[0]);
    let u = dot(tv, pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let s = dot(e2, qv) * inv;
    (0.0..=1.0).contains(&s)
}

/// Whether two triangles intersect (an edge of one crosses the other).
pub fn triangles_intersect(a: [V3; 3], b: [V3; 3]) -> bool {
    (0..3).any(|k| segment_hits(a[k], a[(k + 1) % 3], b))
        || (0..3).any(|k| segment_hits(b[k], b[(k + 1) % 3], a))
}

/// Per-triangle `A_3D / A_panel − 1`.
pub fn area_distortion(mesh: &Mesh) -> Vec<f64> {
    mesh.triangles
        .iter()
        .zip(&mesh.triangle_uvs)
        .map(|(t, tu)| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let [p, q, r] = tu.map(|i| mesh.uvs[i as usize]);
            let a3 = 0.5 * length(cross(sub(b, a), sub(c, a)));
            let a2 = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])).abs();
            a3 / a2 - 1.0
        })
        .collect()
}

/// `∂P/∂u` and `∂P/∂v` of a triangle.
pub fn tangents(mesh: &Mesh, ti: usize) -> (V3, V3) {
    let t = mesh.triangles[ti];
    let tu = mesh.triangle_uvs[ti];
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    let [p, q, r] = tu.map(|i| mesh.uvs[i as usize]);
    let (e1, e2) = (sub(b, a), sub(c, a));
    let (du1, dv1, du2, dv2) = (q[0] - p[0], q[1] - p[1], r[0] - p[0], r[1] - p[1]);
    let det = du1 * dv2 - du2 * dv1;
    let dpdu = scale(sub(scale(e1, dv2), scale(e2, dv1)), 1.0 / det);
    let dpdv = scale(sub(scale(e2, du1), scale(e1, du2)), 1.0 / det);
    (dpdu, dpdv)
}

/// Angle (degrees) of `v` measured in the plane of unit normal `n` from the unit `e`.
fn angle_in_plane(v: V3, e: V3, n: V3) -> f64 {
    dot(cross(e, v), n).atan2(dot(e, v)).to_degrees()
}

fn wrap_deg(a: f64) -> f64 {
    (a + 180.0).rem_euclid(360.0) - 180.0
}

/// Grain and seam figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrainReport {
    /// Largest change of the warp direction across an interior edge of a panel, measured
    /// against the shared edge in each triangle's own plane (degrees).
    pub warp_jump_max_deg: f64,
    /// Mean of the same (degrees).
    pub warp_jump_mean_deg: f64,
    /// Largest disagreement across a seam edge between the change of the warp direction
    /// and the change the two panels' grains make with the seam (degrees).
    pub seam_frame_max_deg: f64,
    /// Mean of the same (degrees).
    pub seam_frame_mean_deg: f64,
    /// Triangles whose `∂P/∂u × ∂P/∂v` opposes the front normal.
    pub mirrored: usize,
}

/// Warp continuity inside panels and tangent-frame agreement across seams.
pub fn grain(mesh: &Mesh, triangle_panel: &[u16]) -> GrainReport {
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (ti, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(ti);
        }
    }
    let mut keys: Vec<(u32, u32)> = edges.keys().copied().collect();
    keys.sort_unstable();
    let (mut inner, mut seam) = (Vec::new(), Vec::new());
    let mut mirrored = 0;
    for ti in 0..mesh.triangles.len() {
        let (du, dv) = tangents(mesh, ti);
        let [a, b, c] = mesh.triangles[ti].map(|i| mesh.positions[i as usize]);
        if dot(cross(du, dv), cross(sub(b, a), sub(c, a))) <= 0.0 {
            mirrored += 1;
        }
    }
    for key in keys {
        let ts = &edges[&key];
        if ts.len() != 2 {
            continue;
        }
        let e3 = normalize_or(
            sub(mesh.positions[key.1 as usize], mesh.positions[key.0 as usize]),
            [1.0, 0.0, 0.0],
        );
        // Warp angle to the edge in 3-D and in each panel's UV.
        let mut a3 = [0.0; 2];
        let mut a2 = [0.0; 2];
        for (s, &ti) in ts.iter().enumerate() {
            let t = mesh.triangles[ti];
            let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
            let n = normalize_or(cross(sub(q, p), sub(r, p)), [0.0, 0.0, 1.0]);
            let (_, dv) = tangents(mesh, ti);
            a3[s] = angle_in_plane(dv, e3, n);
            let k0 = t.iter().position(|&v| v == key.0).unwrap();
            let k1 = t.iter().position(|&v| v == key.1).unwrap();
            let tu = mesh.triangle_uvs[ti];
            let (u0, u1) = (mesh.uvs[tu[k0] as usize], mesh.uvs[tu[k1] as usize]);
            let e2 = [u1[0] - u0[0], u1[1] - u0[1]];
            // Angle from the edge to the panel's +v, counter-clockwise in the panel.
            a2[s] = e2[0].atan2(e2[1]).to_degrees();
        }
        let jump3 = wrap_deg(a3[1] - a3[0]);
        if triangle_panel[ts[0]] == triangle_panel[ts[1]] && {
            let [t0, t1] = [mesh.triangle_uvs[ts[0]], mesh.triangle_uvs[ts[1]]];
            // Same UV chart across the edge: the corners share UV indices.
            let k = [key.0, key.1].map(|v| {
                let i0 = mesh.triangles[ts[0]].iter().position(|&w| w == v).unwrap();
                let i1 = mesh.triangles[ts[1]].iter().position(|&w| w == v).unwrap();
                t0[i0] == t1[i1]
            });
            k[0] && k[1]
        } {
            inner.push(jump3.abs());
        } else {
            // The grains' change across the seam, as drawn in the two panels.
            let jump2 = wrap_deg(a2[1] - a2[0]);
            seam.push(wrap_deg(jump3 - jump2).abs());
        }
    }
    let stat = |v: &[f64]| {
        if v.is_empty() {
            (0.0, 0.0)
        } else {
            (v.iter().copied().fold(0.0, f64::max), v.iter().sum::<f64>() / v.len() as f64)
        }
    };
    let (wm, wa) = stat(&inner);
    let (sm, sa) = stat(&seam);
    GrainReport {
        warp_jump_max_deg: wm,
        warp_jump_mean_deg: wa,
        seam_frame_max_deg: sm,
        seam_frame_mean_deg: sa,
        mirrored,
    }
}
