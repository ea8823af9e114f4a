//! Even triangulation of a flat panel: the outline's points (given, spaced about `h`) plus
//! an equilateral lattice of spacing `h` inside it (kept `0.6 h` away from the outline, so no
//! lattice point encroaches on an outline segment), joined by an incremental Delaunay
//! triangulation (Bowyer–Watson with a walking point location), cut to the outline, with
//! the points near the outline relaxed and Lawson flips restoring the Delaunay property.
//! Every outline segment is an edge of the result, and the outline's points keep their
//! indices `0 … B−1`, so seams can refer to them.

use crate::{Error, Result};
use std::collections::HashMap;

/// A point of a panel (m).
pub type P2 = [f64; 2];

/// A triangulated panel: points (the outline first) and counter-clockwise triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh2 {
    /// Points; the first `outline` are the outline's, in order.
    pub points: Vec<P2>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// How many points the outline has.
    pub outline: usize,
}

fn orient(a: P2, b: P2, c: P2) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Positive when `d` lies inside the circumcircle of the counter-clockwise `abc`.
fn incircle(a: P2, b: P2, c: P2, d: P2) -> f64 {
    let (ax, ay) = (a[0] - d[0], a[1] - d[1]);
    let (bx, by) = (b[0] - d[0], b[1] - d[1]);
    let (cx, cy) = (c[0] - d[0], c[1] - d[1]);
    (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay)
        + (cx * cx + cy * cy) * (ax * by - bx * ay)
}

/// Whether `p` is inside the closed polygon `poly` (even–odd rule).
pub fn inside_polygon(poly: &[P2], p: P2) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn polygon_area(poly: &[P2]) -> f64 {
    let n = poly.len();
    0.5 * (0..n)
        .map(|i| poly[i][0] * poly[(i + 1) % n][1] - poly[(i + 1) % n][0] * poly[i][1])
        .sum::<f64>()
}

#[derive(Clone, Copy)]
struct Tri {
    v: [u32; 3],
    /// Neighbour across the edge opposite `v[i]`.
    n: [i64; 3],
    alive: bool,
}

struct Delaunay {
    pts: Vec<P2>,
    tris: Vec<Tri>,
    last: usize,
}

impl Delaunay {
    fn contains(&self, t: usize, p: P2) -> Option<usize> {
        let v = self.tris[t].v;
        for i in 0..3 {
            let (a, b) = (self.pts[v[(i + 1) % 3] as usize], self.pts[v[(i + 2) % 3] as usize]);
            if orient(a, b, p) < 0.0 {
                return Some(i);
            }
        }
        None
    }

    fn locate(&self, p: P2) -> usize {
        let mut t = self.last;
        for _ in 0..self.tris.len() {
            match self.contains(t, p) {
                None => return t,
                Some(i) => {
                    let nb = self.tris[t].n[i];
                    if nb < 0 {
                        break;
                    }
                    t = nb as usize;
                }
            }
        }
        // Fallback: scan (only when the walk leaves the hull, which the super triangle prevents).
        (0..self.tris.len())
            .find(|&t| self.tris[t].alive && self.contains(t, p).is_none())
            .unwrap_or(self.last)
    }

    fn insert(&mut self, pi: u32) {
        let p = self.pts[pi as usize];
        let start = self.locate(p);
        let mut bad = vec![start];
        let mut is_bad: HashMap<usize, bool> = HashMap::from([(start, true)]);
        let mut q = 0;
        while q < bad.len() {
            let t = bad[q];
            q += 1;
            for i in 0..3 {
                let nb = self.tris[t].n[i];
                if nb < 0 || is_bad.contains_key(&(nb as usize)) {
                    continue;
                }
                let nbu = nb as usize;
                let v = self.tris[nbu].v.map(|k| self.pts[k as usize]);
                let inside = incircle(v[0], v[1], v[2], p) > 0.0;
                is_bad.insert(nbu, inside);
                if inside {
                    bad.push(nbu);
                }
            }
        }
        // Cavity boundary edges (a → b) with their outer neighbours.
        let mut new_by_start: HashMap<u32, usize> = HashMap::new();
        let mut new_by_end: HashMap<u32, usize> = HashMap::new();
        let mut created = Vec::new();
        for &t in &bad {
            for i in 0..3 {
                let nb = self.tris[t].n[i];
                if nb >= 0 && is_bad.get(&(nb as usize)).copied().unwrap_or(false) {
                    continue;
                }
                let v = self.tris[t].v;
                let (a, b) = (v[(i + 1) % 3], v[(i + 2) % 3]);
                let id = self.tris.len();
                self.tris.push(Tri { v: [a, b, pi], n: [-1, -1, nb], alive: true });
                if nb >= 0 {
                    let o = &mut self.tris[nb as usize];
                    for k in 0..3 {
                        let (oa, ob) = (o.v[(k + 1) % 3], o.v[(k + 2) % 3]);
                        if oa == b && ob == a {
                            o.n[k] = id as i64;
                        }
                    }
                }
                new_by_start.insert(a, id);
                new_by_end.insert(b, id);
                created.push(id);
            }
        }
        for &id in &created {
            let [a, b, _] = self.tris[id].v;
            self.tris[id].n[0] = new_by_start.get(&b).map_or(-1, |&x| x as i64);
            self.tris[id].n[1] = new_by_end.get(&a).map_or(-1, |&x| x as i64);
        }
        for &t in &bad {
            self.tris[t].alive = false;
        }
        self.last = *created.last().unwrap_or(&start);
    }
}

/// Triangulates the counter-clockwise polygon `outline` (points spaced about `h`) with
/// interior lattice points of spacing `h`.
pub fn triangulate(outline: &[P2], h: f64) -> Result<Mesh2> {
    if outline.len() < 3 || !(h.is_finite() && h > 0.0) {
        return Err(Error::Invalid(
            "mesher: an outline needs 3 points and a positive spacing".into(),
        ));
    }
    if polygon_area(outline) <= 0.0 {
        return Err(Error::Invalid("mesher: the outline must run counter-clockwise".into()));
    }
    let nb = outline.len();
    let mut lo = [f64::MAX; 2];
    let mut hi = [f64::MIN; 2];
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    // Interior lattice points, rows along x.
    let row = h * 3f64.sqrt() / 2.0;
    let mut pts: Vec<P2> = outline.to_vec();
    let rows = ((hi[1] - lo[1]) / row).ceil() as usize + 1;
    let cols = ((hi[0] - lo[0]) / h).ceil() as usize + 2;
    for j in 0..rows {
        let y = lo[1] + (j as f64 + 0.5) * row;
        for i in 0..cols {
            let x = lo[0] + (i as f64 + if j % 2 == 1 { 0.5 } else { 0.0 }) * h;
            let p = [x, y];
            if !inside_polygon(outline, p) {
                continue;
            }
            let near =
                (0..nb).any(|s| segment_distance(p, outline[s], outline[(s + 1) % nb]) < 0.6 * h);
            if !near {
                pts.push(p);
            }
        }
    }
    let n = pts.len();
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let r = 20.0 * (hi[0] - lo[0]).max(hi[1] - lo[1]).max(h);
    let mut all = pts.clone();
    all.push([c[0] - r, c[1] - r]);
    all.push([c[0] + r, c[1] - r]);
    all.push([c[0], c[1] + r]);
    let (s0, s1, s2) = (n as u32, n as u32 + 1, n as u32 + 2);
    let mut d = Delaunay {
        pts: all,
        tris: vec![Tri { v: [s0, s1, s2], n: [-1; 3], alive: true }],
        last: 0,
    };
    for i in 0..n as u32 {
        d.insert(i);
    }
    let mut triangles: Vec<[u32; 3]> = d
        .tris
        .iter()
        .filter(|t| t.alive && t.v.iter().all(|&v| (v as usize) < n))
        .map(|t| t.v)
        .filter(|t| {
            let [a, b, cc] = t.map(|i| pts[i as usize]);
            inside_polygon(outline, [(a[0] + b[0] + cc[0]) / 3.0, (a[1] + b[1] + cc[1]) / 3.0])
        })
        .collect();
    let mut mesh = Mesh2 { points: pts, triangles: Vec::new(), outline: nb };
    // Every outline segment must be an edge.
    let edge_set: std::collections::HashSet<(u32, u32)> =
        triangles.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
    for s in 0..nb {
        let (a, b) = (s as u32, ((s + 1) % nb) as u32);
        if !edge_set.contains(&(a, b)) {
            return Err(Error::Invalid(format!(
                "mesher: outline segment {s} ({:?} → {:?}) is not an edge (outline too coarse for h = {h})",
                outline[s],
                outline[(s + 1) % nb]
            )));
        }
    }
    relax(&mut mesh.points, &triangles, nb, h);
    lawson_flips(&mesh.points, &mut triangles);
    mesh.triangles = triangles;
    Ok(mesh)
}

/// Moves interior points within `1.5 h` of the outline towards the centroid of their
/// neighbours, never inverting a triangle.
fn relax(pts: &mut [P2], tris: &[[u32; 3]], outline: usize, h: f64) {
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); pts.len()];
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); pts.len()];
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            nbrs[t[k] as usize].push(t[(k + 1) % 3]);
            incident[t[k] as usize].push(ti);
        }
    }
    let outline_pts: Vec<P2> = pts[..outline].to_vec();
    let near: Vec<bool> = (0..pts.len())
        .map(|i| {
            i >= outline
                && (0..outline).any(|s| {
                    segment_distance(pts[i], outline_pts[s], outline_pts[(s + 1) % outline])
                        < 1.5 * h
                })
        })
        .collect();
    for _ in 0..4 {
        for i in outline..pts.len() {
            if !near[i] || nbrs[i].is_empty() {
                continue;
            }
            let k = nbrs[i].len() as f64;
            let c = nbrs[i].iter().fold([0.0, 0.0], |s, &j| {
                [s[0] + pts[j as usize][0] / k, s[1] + pts[j as usize][1] / k]
            });
            let old = pts[i];
            pts[i] = [old[0] + 0.6 * (c[0] - old[0]), old[1] + 0.6 * (c[1] - old[1])];
            let ok = incident[i].iter().all(|&t| {
                let [a, b, cc] = tris[t].map(|v| pts[v as usize]);
                orient(a, b, cc) > 1e-3 * h * h
            });
            if !ok {
                pts[i] = old;
            }
        }
    }
}

/// Flips interior edges that violate the empty-circle property until none does.
pub fn lawson_flips(pts: &[P2], tris: &mut [[u32; 3]]) {
    for _ in 0..50 {
        let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                edges.insert((t[k], t[(k + 1) % 3]), ti);
            }
        }
        let mut keys: Vec<(u32, u32)> = edges.keys().copied().filter(|&(a, b)| a < b).collect();
        keys.sort_unstable();
        let mut touched = vec![false; tris.len()];
        let mut flips = 0;
        for (a, b) in keys {
            let (Some(&t0), Some(&t1)) = (edges.get(&(a, b)), edges.get(&(b, a))) else { continue };
            if touched[t0] || touched[t1] {
                continue;
            }
            let opp = |t: [u32; 3]| *t.iter().find(|&&v| v != a && v != b).unwrap();
            let (c, dd) = (opp(tris[t0]), opp(tris[t1]));
            // t0 runs a → b → c; t1 runs b → a → dd.
            let p = |i: u32| pts[i as usize];
            if incircle(p(a), p(b), p(c), p(dd)) <= 1e-12 {
                continue;
            }
            let (n0, n1) = ([a, dd, c], [dd, b, c]);
            if orient(p(n0[0]), p(n0[1]), p(n0[2])) <= 0.0
                || orient(p(n1[0]), p(n1[1]), p(n1[2])) <= 0.0
            {
                continue;
            }
            tris[t0] = n0;
            tris[t1] = n1;
            touched[t0] = true;
            touched[t1] = true;
            flips += 1;
        }
        if flips == 0 {
            break;
        }
    }
}

/// Smallest angle over the triangles (degrees).
pub fn min_angle_deg(m: &Mesh2) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| m.points[i as usize]);
            (0..3)
                .map(|k| {
                    let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
                    let cosv =
                        (u[0] * v[0] + u[1] * v[1]) / ((u[0].hypot(u[1])) * (v[0].hypot(v[1])));
                    cosv.clamp(-1.0, 1.0).acos().to_degrees()
                })
                .fold(180.0, f64::min)
        })
        .fold(180.0, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_is_covered_evenly() {
        let h = 0.05;
        let k = (2.0 * std::f64::consts::PI * 0.5 / h).round() as usize;
        let outline: Vec<P2> = (0..k)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * i as f64 / k as f64;
                [0.5 * a.cos(), 0.5 * a.sin()]
            })
            .collect();
        let m = triangulate(&outline, h).unwrap();
        let area: f64 = m
            .triangles
            .iter()
            .map(|t| {
                orient(m.points[t[0] as usize], m.points[t[1] as usize], m.points[t[2] as usize])
                    / 2.0
            })
            .sum();
        assert!((area - polygon_area(&outline)).abs() < 1e-9, "covers the polygon: {area}");
        assert!(m.triangles.iter().all(|t| orient(
            m.points[t[0] as usize],
            m.points[t[1] as usize],
            m.points[t[2] as usize]
        ) > 0.0));
        assert!(min_angle_deg(&m) > 25.0, "min angle {}", min_angle_deg(&m));
        // Vertices as expected for an equilateral lattice of spacing h.
        let expect = polygon_area(&outline) / (3f64.sqrt() / 2.0 * h * h);
        let ratio = m.points.len() as f64 / expect;
        assert!((0.85..1.15).contains(&ratio), "{} points for {expect:.0}", m.points.len());
    }
}
