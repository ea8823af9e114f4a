//! Cloth–cloth contact for the XPBD garment solver ([`super::drape`]): every node is kept
//! at least `d` (the fabric's half-thickness) from every triangle that is not its
//! neighbour, on the side it was on when the pair was first found, with Coulomb friction
//! between the layers.
//!
//! A node `p` over a triangle `q₀q₁q₂` (its closest point inside the triangle, unit normal
//! `n`, barycentrics `b`) on remembered side `s = ±1` has the constraint
//! `C = s n·(p − Σ bₖ qₖ) − d ≥ 0`; a node beside it (closest point `c` on an edge or a
//! corner) keeps its true distance, `C = |p − c| − d ≥ 0`, pushed along `(p − c)/|p − c|`.
//! A violated one is projected like every XPBD constraint with zero compliance
//! ([XPBD eq. 18] with `α = 0`): `Δλ = −C / (w_p + Σ bₖ² w_k)`, `p += w_p Δλ n`,
//! `qₖ −= w_k bₖ Δλ n` (the "triangle collision" constraint of position-based dynamics,
//! Müller et al. 2007 §4.4, there for nodes over the triangle only). Momentum is conserved:
//! the node's and the triangle's impulses are equal and opposite. Friction is the
//! position-based Coulomb law of Macklin et al. 2014 §6.1 on the node's motion relative to
//! the triangle over the sub-step: cancelled while below `μ_s` times the push, else reduced
//! by `μ_k` times it (the drape uses the fabric's coefficients; without them the trousers'
//! inseams, pressed together between the thighs, never came to rest).
//!
//! Correction (session 19): this module first used the plane distance `s n·(p − q₀)` for
//! every pair, also for a node beside the triangle — whose plane distance can be 0 while it
//! is a centimetre away — so nodes near the extended plane of a neighbouring layer's
//! triangles were pushed off it every sub-step. At 10 000 vertices that held the trousers'
//! inseams jittering at 0.4–0.8 m/s (never at rest in 4 s, seams 4.3 mm open) and kept the
//! skirt's drape going for minutes; with true distances beside the triangle the trousers
//! rest after 1.8 s with the seams 0.4 mm apart and the skirt takes 25 s. A side is taken
//! only over the triangle; a pair found beside it has none until its node is over it.
//!
//! Candidates are found in a spatial hash ([`crate::sim::hashgrid`]) of the triangles'
//! boxes inflated by `d` plus a margin `2d`, and the list is reused until some node has
//! moved half the margin since it was built (a Verlet list, as the knit simulation's
//! [`crate::sim::collide`]); the search runs in parallel over nodes, in node order. Each
//! node's ignored triangles (below) are listed once for the run and dropped by a binary
//! search before any closest point, and a bucket's boxes are read in sequence in single
//! precision (widened past their rounding): the same list as the direct search, which
//! spent most of its time on a node's own sheet — at 40 000 vertices ~84 % of a skirt's
//! drape (the bucket walk 56 %, closest points 28 %). A node
//! moves far less than `d` per sub-step (≤ 1 mm against 3 mm at the garments' sub-steps),
//! so it cannot pass through a triangle between two projections, and remembering the side
//! it was found on — carried over when the list is rebuilt — pushes a node that did get
//! through back to its own side rather than further. A side found more than `d` wrong is
//! taken back instead: the node was found beside the triangle, its offset in the triangle's
//! plane and its sign arbitrary. (A longer margin rebuilt less often but took many such
//! sides: 4d left the seams 6–9 mm open at 3 000 vertices, the mesh spacing 12 mm at 1 500.)
//!
//! Neighbours: a node ignores every triangle with a corner in its welded one-ring, through
//! a weld map (the sewing runs on unwelded panels whose seam partners become one vertex).
//! In a flat sheet the nearest other triangles are then a triangle's height away (8.6 mm
//! at 10 000 vertices, 4.3 mm at 40 000, against d = 3 mm), so a sheet does not push its
//! own nodes; across a seam the two first rows are free to meet however they approach.
//! Given the panels' flat shapes ([`SelfContact::with_rest_shape`]) a node also ignores
//! its own panel's triangles within a radius in the flat panel (the garments use the list's
//! reach, 3d): a flat sheet then has no pair with itself at any resolution. At 10 000
//! vertices that changes nothing (the one-ring already covers 3d); at 40 000, where the
//! reach is two mesh spacings, the second and third rings had filled the list (~20 pairs a
//! node, each projected three times a sub-step) and the T-shirt took more than 395 s
//! (stopped) — with the exclusion 116 s. A fold tighter than the radius goes unseen:
//! at 3d = 9 mm along the panel, a U-fold whose legs come within d of each other is a
//! crease of radius < 1.5 mm, below what the meshes resolve.
//! Tried and dropped: keeping the one-ring's triangles of other panels, and of the node's
//! own panel within 45° of the normal (the influence cone of [C03 §4.1.2]) — the panels'
//! first rows then met at the armpit junction from several sides and held the side seams
//! open (6.7 mm at 3 000 vertices, 6.4 mm and never at rest at 10 000).
//!
//! What this does not do: edge–edge contact (two creases crossing between their nodes, or a
//! one-ring's rows folding through each other at a seam junction) and untangling a mesh
//! that starts with crossings — [`super::sew`] places its panels apart and smooths away
//! the few crossings the junctions and creases leave.

use crate::garment::sdf::closest_point_triangle;
use crate::sim::friction::Friction;
use crate::sim::hashgrid::HashGrid;
use crate::vec3::{V3, cross, dot, length, scale, sub};
use rayon::prelude::*;

/// A node near a triangle, on side `side` (±1 along the triangle's normal; 0 while the node
/// has only been beside it).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pair {
    node: u32,
    tri: u32,
    side: f64,
}

/// Cloth–cloth contact state: the triangles, the neighbour exclusion and the Verlet list.
#[derive(Debug, Clone)]
pub struct SelfContact {
    triangles: Vec<[u32; 3]>,
    /// Welded id of each node.
    weld: Vec<u32>,
    /// Welded one-ring of each welded vertex (itself included), sorted.
    ring: Vec<Vec<u32>>,
    /// Panel coordinates: each triangle's panel and corners, each node's (panel, point) for
    /// every panel it lies on; empty when not given ([`SelfContact::with_rest_shape`]).
    tri_rest: Vec<(u16, [[f64; 2]; 3])>,
    node_rest: Vec<Vec<(u16, [f64; 2])>>,
    /// A node ignores the triangles of its own panel within this distance in the panel (m).
    rest_exclusion: f64,
    /// Distance kept between a node and a triangle (m).
    distance: f64,
    /// Friction between cloth layers.
    pub friction: Friction,
    /// Extra reach of the candidate list (m).
    margin: f64,
    /// Cell size of the hash grid (m).
    cell: f64,
    pairs: Vec<Pair>,
    built_at: Vec<V3>,
    /// Each node's ignored triangles, sorted ([`SelfContact::exclusions`]; empty until the
    /// first list search).
    excluded: Vec<Vec<u32>>,
}

impl SelfContact {
    /// Contact between `triangles` (over unwelded node ids) of nodes that weld onto
    /// `weld[i]`; nodes keep `distance` from non-neighbouring triangles. `spacing` is the
    /// mesh's edge length (the hash grid's cell follows it).
    pub fn new(triangles: Vec<[u32; 3]>, weld: Vec<u32>, distance: f64, spacing: f64) -> Self {
        let nw = weld.iter().map(|&w| w as usize + 1).max().unwrap_or(0);
        let mut ring: Vec<Vec<u32>> = (0..nw as u32).map(|i| vec![i]).collect();
        for t in &triangles {
            let w = t.map(|i| weld[i as usize]);
            for a in w {
                ring[a as usize].extend_from_slice(&w);
            }
        }
        for r in &mut ring {
            r.sort_unstable();
            r.dedup();
        }
        // The list's reach is 3d: a pair is found (and its side taken) while the node is
        // within 3d of the triangle (a longer reach: see the module notes).
        let margin = 2.0 * distance;
        SelfContact {
            triangles,
            weld,
            ring,
            tri_rest: Vec::new(),
            node_rest: Vec::new(),
            rest_exclusion: 0.0,
            distance,
            friction: Friction { static_coef: 0.0, dynamic_coef: 0.0 },
            margin,
            cell: spacing.max(distance) + 2.0 * (distance + margin),
            pairs: Vec::new(),
            built_at: Vec::new(),
            excluded: Vec::new(),
        }
    }

    /// The triangles each node ignores, sorted: those with a corner in its welded one-ring
    /// (the node itself included) and, given the panels' flat shapes, those of its own
    /// panel within [`SelfContact::with_rest_shape`]'s radius in the flat panel. Fixed for
    /// the run, so computed once; the list search then drops a node's own sheet with a
    /// binary search instead of a closest point in 3-D and one in the panel per candidate
    /// (at 40 000 vertices nearly every candidate is one of these).
    fn exclusions(&self, n: usize) -> Vec<Vec<u32>> {
        let mut of_weld: Vec<Vec<u32>> = vec![Vec::new(); self.ring.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &c in tri {
                of_weld[self.weld[c as usize] as usize].push(t as u32);
            }
        }
        // The flat panels side by side in one grid: panel `k` at height 1000 k.
        let lift = |p: [f64; 2], panel: u16| [p[0], p[1], 1000.0 * panel as f64];
        let r = self.rest_exclusion;
        let rest_boxes: Vec<(V3, V3)> = self
            .tri_rest
            .iter()
            .map(|&(panel, q)| {
                let z = 1000.0 * panel as f64;
                let lo = [0, 1].map(|k| q[0][k].min(q[1][k]).min(q[2][k]) - r);
                let hi = [0, 1].map(|k| q[0][k].max(q[1][k]).max(q[2][k]) + r);
                ([lo[0], lo[1], z], [hi[0], hi[1], z])
            })
            .collect();
        let rest_grid = HashGrid::build(&rest_boxes, self.cell);
        (0..n)
            .into_par_iter()
            .map(|i| {
                let mut out: Vec<u32> = self.ring[self.weld[i] as usize]
                    .iter()
                    .flat_map(|&w| of_weld[w as usize].iter().copied())
                    .collect();
                for &(panel, p) in self.node_rest.get(i).map_or(&[][..], |v| &v[..]) {
                    for &t in rest_grid.query(lift(p, panel)) {
                        let (tp, q) = self.tri_rest[t as usize];
                        if tp != panel {
                            continue;
                        }
                        let (c, _) = closest_point_triangle(
                            lift(p, 0),
                            lift(q[0], 0),
                            lift(q[1], 0),
                            lift(q[2], 0),
                        );
                        let e = sub(lift(p, 0), c);
                        if dot(e, e) < r * r {
                            out.push(t);
                        }
                    }
                }
                out.sort_unstable();
                out.dedup();
                out
            })
            .collect()
    }

    /// Also ignores, for every node, the triangles of its own panel that lie within
    /// `radius` of it in the flat panel: `tri_rest[t]` is triangle `t`'s panel and its
    /// corners' panel coordinates, `node_rest[i]` node `i`'s (panel, coordinates) on every
    /// panel it lies on (a seam node on two).
    pub fn with_rest_shape(
        mut self,
        tri_rest: Vec<(u16, [[f64; 2]; 3])>,
        node_rest: Vec<Vec<(u16, [f64; 2])>>,
        radius: f64,
    ) -> Self {
        self.tri_rest = tri_rest;
        self.node_rest = node_rest;
        self.rest_exclusion = radius;
        self
    }

    /// The candidate list (node, triangle, remembered side) and the positions it was built
    /// at, for a snapshot ([`super::checkpoint`]).
    pub fn list(&self) -> (Vec<(u32, u32, f64)>, Vec<V3>) {
        (self.pairs.iter().map(|p| (p.node, p.tri, p.side)).collect(), self.built_at.clone())
    }

    /// Restores a list taken by [`SelfContact::list`]; pairs naming a node or triangle this
    /// contact does not have are refused.
    pub fn set_list(&mut self, pairs: &[(u32, u32, f64)], built_at: Vec<V3>) -> crate::Result<()> {
        let n = self.weld.len();
        if let Some(&(node, tri, _)) = pairs
            .iter()
            .find(|&&(node, tri, _)| node as usize >= n || tri as usize >= self.triangles.len())
        {
            return Err(crate::Error::Invalid(format!(
                "garment snapshot: contact pair (node {node}, triangle {tri}) outside the mesh"
            )));
        }
        if !built_at.is_empty() && built_at.len() != n {
            return Err(crate::Error::Invalid(format!(
                "garment snapshot: contact list built at {} positions for {n} nodes",
                built_at.len()
            )));
        }
        self.pairs = pairs.iter().map(|&(node, tri, side)| Pair { node, tri, side }).collect();
        self.built_at = built_at;
        Ok(())
    }

    /// Rebuilds the candidate list when some node has moved half the margin since the last
    /// build (or there is none yet).
    fn refresh(&mut self, x: &[V3]) {
        let stale = self.built_at.len() != x.len()
            || x.iter().zip(&self.built_at).any(|(p, q)| {
                let d = sub(*p, *q);
                dot(d, d) > 0.25 * self.margin * self.margin
            });
        if !stale {
            return;
        }
        let reach = self.distance + self.margin;
        let boxes: Vec<(V3, V3)> = self
            .triangles
            .iter()
            .map(|t| {
                let q = t.map(|i| x[i as usize]);
                let lo = [0, 1, 2].map(|k| q[0][k].min(q[1][k]).min(q[2][k]) - reach);
                let hi = [0, 1, 2].map(|k| q[0][k].max(q[1][k]).max(q[2][k]) + reach);
                (lo, hi)
            })
            .collect();
        let grid = HashGrid::build(&boxes, self.cell);
        if self.excluded.len() != x.len() {
            self.excluded = self.exclusions(x.len());
        }
        // The boxes again in the grid's own order, in single precision and widened by more
        // than its rounding: a bucket is then filtered reading memory in sequence (the
        // exact test follows, so the list is the same as with the double-precision boxes).
        let items = grid.items();
        let widen = |v: f64, s: f64| (v + s * (1e-6 + 1e-6 * v.abs())) as f32;
        let item_boxes: Vec<[f32; 6]> = items
            .par_iter()
            .map(|&t| {
                let (lo, hi) = boxes[t as usize];
                [
                    widen(lo[0], -1.0),
                    widen(lo[1], -1.0),
                    widen(lo[2], -1.0),
                    widen(hi[0], 1.0),
                    widen(hi[1], 1.0),
                    widen(hi[2], 1.0),
                ]
            })
            .collect();
        let old = std::mem::take(&mut self.pairs);
        let this = &*self;
        let per_node: Vec<Vec<Pair>> = x
            .par_iter()
            .enumerate()
            .map(|(i, &p)| {
                let ignored = &this.excluded[i];
                let i = i as u32;
                let pf = p.map(|c| c as f32);
                let range = grid.query_range(p);
                // A bucket holds each triangle once (the grid registers an item once per
                // bucket), in triangle order: no sorting or deduplication needed.
                let found = item_boxes[range.clone()]
                    .iter()
                    .zip(&items[range])
                    .filter(|(b, _)| {
                        pf[0] >= b[0]
                            && pf[0] <= b[3]
                            && pf[1] >= b[1]
                            && pf[1] <= b[4]
                            && pf[2] >= b[2]
                            && pf[2] <= b[5]
                    })
                    .map(|(_, &t)| t)
                    .filter(|t| ignored.binary_search(t).is_err());
                let mut out = Vec::new();
                for t in found {
                    let tri = this.triangles[t as usize];
                    let q = tri.map(|k| x[k as usize]);
                    let (c, b) = closest_point_triangle(p, q[0], q[1], q[2]);
                    let v = sub(p, c);
                    if dot(v, v) > reach * reach {
                        continue;
                    }
                    let n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
                    let side = match old.binary_search_by(|o| (o.node, o.tri).cmp(&(i, t))) {
                        Ok(k) => old[k].side,
                        Err(_) if b.iter().all(|&bk| bk > 0.0) => {
                            if dot(v, n) >= 0.0 {
                                1.0
                            } else {
                                -1.0
                            }
                        }
                        Err(_) => 0.0,
                    };
                    out.push(Pair { node: i, tri: t, side });
                }
                out
            })
            .collect();
        self.pairs = per_node.concat();
        self.built_at = x.to_vec();
    }

    /// Projects every violated pair once, in list order (deterministic); `prev` holds the
    /// positions at the start of the sub-step: friction acts on the node's motion relative
    /// to the triangle since then. The nodes and corners of every pair pushed are appended to
    /// `touched`.
    pub fn project(&mut self, x: &mut [V3], prev: &[V3], inv_mass: &[f64], touched: &mut Vec<u32>) {
        self.refresh(x);
        let d = self.distance;
        for pr in &mut self.pairs {
            let tri = self.triangles[pr.tri as usize];
            let i = pr.node as usize;
            let q = tri.map(|k| x[k as usize]);
            let nn = cross(sub(q[1], q[0]), sub(q[2], q[0]));
            let nl = length(nn);
            if nl < 1e-18 {
                continue;
            }
            let n = scale(nn, 1.0 / nl);
            // The plane distance bounds the true one from below: most pairs are cleared
            // without finding the closest point.
            let hp = dot(sub(x[i], q[0]), n);
            if hp.abs() >= d && pr.side * hp > -d {
                continue;
            }
            let (c, b) = closest_point_triangle(x[i], q[0], q[1], q[2]);
            let over = b.iter().all(|&bk| bk > 0.0);
            let (dir, h) = if over {
                if pr.side == 0.0 {
                    pr.side = if hp >= 0.0 { 1.0 } else { -1.0 };
                }
                let h = pr.side * hp;
                if h < -d {
                    // More than d behind: no node moves that far between two projections,
                    // so the side was taken wrongly — it is on its own side; keep that one.
                    pr.side = -pr.side;
                    continue;
                }
                (scale(n, pr.side), h)
            } else {
                // Beside the triangle: the node keeps d from its nearest edge or corner, in
                // the direction away from it (no side: it is not over the triangle).
                let r = sub(x[i], c);
                let l = length(r);
                if l < 1e-12 {
                    continue;
                }
                (scale(r, 1.0 / l), l)
            };
            if h >= d {
                continue;
            }
            let n = dir;
            let w =
                inv_mass[i] + (0..3).map(|k| b[k] * b[k] * inv_mass[tri[k] as usize]).sum::<f64>();
            if w == 0.0 {
                continue;
            }
            let dl = (d - h) / w;
            // Friction: the node's tangential motion relative to the triangle over the
            // sub-step is cancelled while it is below μ_s times the push, else reduced by
            // μ_k times it (position-based Coulomb friction, Macklin et al. 2014 §6.1),
            // shared by the same weights as the push.
            let rel = sub(
                sub(x[i], prev[i]),
                (0..3).fold([0.0; 3], |s, k| {
                    let j = tri[k] as usize;
                    crate::vec3::add(s, scale(sub(x[j], prev[j]), b[k]))
                }),
            );
            let tangential = sub(rel, scale(n, dot(rel, n)));
            let t = length(tangential);
            let push = d - h;
            let f = if t < self.friction.static_coef * push {
                1.0
            } else if t > 0.0 {
                (self.friction.dynamic_coef * push / t).min(1.0)
            } else {
                0.0
            };
            let slip = scale(tangential, f / w);
            touched.push(pr.node);
            touched.extend_from_slice(&tri);
            x[i] = crate::vec3::add(x[i], scale(n, inv_mass[i] * dl));
            x[i] = sub(x[i], scale(slip, inv_mass[i]));
            for k in 0..3 {
                let j = tri[k] as usize;
                x[j] = sub(x[j], scale(n, inv_mass[j] * b[k] * dl));
                x[j] = crate::vec3::add(x[j], scale(slip, inv_mass[j] * b[k]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node falling onto a pinned triangle stops at the contact distance above it, and a
    /// free node and free triangle share the push by their masses (momentum conserved).
    #[test]
    fn a_node_stops_at_the_distance_and_momentum_is_conserved() {
        let tri = vec![[0u32, 1, 2]];
        let weld = vec![0, 1, 2, 3];
        let d = 0.003;
        let mut c = SelfContact::new(tri.clone(), weld.clone(), d, 0.1);
        let mut x = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.02, 0.02, 0.004]];
        let pinned = [0.0, 0.0, 0.0, 1.0];
        // Sink the node step by step through the plane: it never goes below d.
        for _ in 0..20 {
            x[3][2] -= 0.0005;
            let p = x.clone();
            c.project(&mut x, &p, &pinned, &mut Vec::new());
            assert!(x[3][2] >= d - 1e-12, "{}", x[3][2]);
        }
        assert!((x[3][2] - d).abs() < 1e-12);
        // Free everything: masses 1 (triangle corners) and 2 (node).
        let w = [1.0, 1.0, 1.0, 0.5];
        let mut c = SelfContact::new(tri, weld, d, 0.1);
        let before = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.02, 0.02, 0.001]];
        let mut x = before.clone();
        let p = x.clone();
        c.project(&mut x, &p, &w, &mut Vec::new());
        let mut momentum = [0.0; 3];
        for (k, (p, q)) in x.iter().zip(&before).enumerate() {
            let m = 1.0 / w[k];
            for a in 0..3 {
                momentum[a] += m * (p[a] - q[a]);
            }
        }
        assert!(momentum.iter().all(|m| m.abs() < 1e-15), "{momentum:?}");
        // One projection moves along the triangle's normal before the push: it tilts the
        // triangle (corners pushed by their barycentric weights), so the distance after is
        // d only to first order.
        let (cp, _) = closest_point_triangle(x[3], x[0], x[1], x[2]);
        let after = length(sub(x[3], cp));
        assert!((after - d).abs() < 0.05 * d, "{after}");
    }

    /// A node that got through (placed below, found above) is pushed back to the side it
    /// was found on; neighbours through the weld map are never pushed.
    #[test]
    fn sides_are_remembered_and_neighbours_ignored() {
        let tri = vec![[0u32, 1, 2]];
        let d = 0.003;
        let mut c = SelfContact::new(tri.clone(), vec![0, 1, 2, 3], d, 0.1);
        let mut x = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.02, 0.02, 0.005]];
        let w = [0.0, 0.0, 0.0, 1.0];
        let p = x.clone();
        c.project(&mut x, &p, &w, &mut Vec::new());
        x[3][2] = -0.001;
        let p = x.clone();
        c.project(&mut x, &p, &w, &mut Vec::new());
        assert!((x[3][2] - d).abs() < 1e-12, "{}", x[3][2]);
        // Node 3 welds onto corner 0: a neighbour, left where it is.
        let mut c = SelfContact::new(tri, vec![0, 1, 2, 0], d, 0.1);
        let mut y = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.02, 0.02, 0.001]];
        let p = y.clone();
        c.project(&mut y, &p, &w, &mut Vec::new());
        assert_eq!(y[3], [0.02, 0.02, 0.001]);
    }

    /// A node beside a triangle keeps its true distance from the nearest edge, not from the
    /// triangle's plane: 1 cm beyond an edge in the plane it is left alone (the plane
    /// distance, 0, would push it by d), 1 mm beyond it is pushed straight away from the
    /// edge to d, and it takes no side until it is over the triangle.
    #[test]
    fn a_node_beside_a_triangle_keeps_its_distance_from_the_edge() {
        let tri = vec![[0u32, 1, 2]];
        let d = 0.003;
        let w = [0.0, 0.0, 0.0, 1.0];
        // Edge 0–1 lies on y = 0; the node is below it (y < 0), in the plane z = 0.
        let mut c = SelfContact::new(tri.clone(), vec![0, 1, 2, 3], d, 0.1);
        let mut x = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.05, -0.006, 0.0]];
        let p = x.clone();
        let mut touched = Vec::new();
        c.project(&mut x, &p, &w, &mut touched);
        assert_eq!(x[3], [0.05, -0.006, 0.0]);
        assert!(touched.is_empty());
        x[3] = [0.05, -0.001, 0.0005];
        let p = x.clone();
        c.project(&mut x, &p, &w, &mut touched);
        let r = [x[3][0] - 0.05, x[3][1], x[3][2]];
        assert!((length(r) - d).abs() < 1e-12, "{:?}", x[3]);
        // Along (p − c): the direction it had, scaled to d.
        let k = d / (0.001f64.powi(2) + 0.0005f64.powi(2)).sqrt();
        assert!((x[3][1] + 0.001 * k).abs() < 1e-12 && (x[3][2] - 0.0005 * k).abs() < 1e-12);
        assert_eq!(touched, vec![3, 0, 1, 2]);
        assert_eq!(c.pairs[0].side, 0.0);
        // Over the triangle, just below its plane: the side is taken there (−1) and kept.
        x[3] = [0.02, 0.02, -0.001];
        let p = x.clone();
        c.project(&mut x, &p, &w, &mut touched);
        assert_eq!(c.pairs[0].side, -1.0);
        assert!((x[3][2] + d).abs() < 1e-12, "{:?}", x[3]);
    }

    /// Given the panels' flat shapes, a node ignores its own panel's triangles within the
    /// radius in the panel (a coplanar neighbour 5 mm beyond an edge, inside the 9 mm list
    /// reach, is a pair without them) but not another panel's at the same place.
    #[test]
    fn own_panel_triangles_near_in_the_panel_are_ignored() {
        let tri = vec![[0u32, 1, 2]];
        let d = 0.003;
        let x = vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.05, -0.005, 0.0]];
        let w = [0.0, 0.0, 0.0, 1.0];
        let uv = |p: V3| [p[0], p[1]];
        let tri_rest = vec![(0u16, [uv(x[0]), uv(x[1]), uv(x[2])])];
        for (node_panel, pairs) in [(None, 1), (Some(0u16), 0), (Some(1), 1)] {
            let mut c = SelfContact::new(tri.clone(), vec![0, 1, 2, 3], d, 0.1);
            if let Some(p) = node_panel {
                let node_rest = vec![vec![], vec![], vec![], vec![(p, uv(x[3]))]];
                c = c.with_rest_shape(tri_rest.clone(), node_rest, 3.0 * d);
            }
            let mut y = x.clone();
            c.project(&mut y, &x, &w, &mut Vec::new());
            assert_eq!(c.pairs.len(), pairs, "node on panel {node_panel:?}");
        }
    }
}
