//! A bounding-volume hierarchy over the mesh triangles for the occlusion rays of the
//! visibility maps ([S03 §5.2]: `V(x, p_α)` of [S03 eq. 9]).
//!
//! Built top-down by the binned surface-area heuristic over triangle centroids (the median
//! of the longest axis where no bin boundary splits a set; leaves of at most [`LEAF_SIZE`]
//! triangles), stored flat in depth-first order so the left child of a
//! node is the next node. Queries are any-hit: a ray is occluded as soon as one triangle
//! is hit in `(t_min, ∞)`. Triangles are double-sided (cloth occludes from both sides), the
//! test is Möller–Trumbore in `f32`; zero-area triangles never report a hit.

/// Most triangles per leaf.
pub const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    pub(super) lo: [f32; 3],
    pub(super) hi: [f32; 3],
    /// Leaf: first triangle; inner: index of the right child.
    pub(super) start_or_right: u32,
    /// Triangles in a leaf, 0 for an inner node.
    pub(super) count: u32,
}

/// Precomputed triangle: a vertex and two edges.
#[derive(Debug, Clone, Copy)]
pub(super) struct Tri {
    pub(super) p0: [f32; 3],
    pub(super) e1: [f32; 3],
    pub(super) e2: [f32; 3],
}

/// The hierarchy.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    tris: Vec<Tri>,
}

pub(super) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(super) fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
pub(super) fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Bvh {
    /// Builds the hierarchy of `triangles` over `positions` (indices must be in range).
    pub fn new(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Bvh {
        let corners: Vec<[[f32; 3]; 3]> =
            triangles.iter().map(|t| t.map(|i| positions[i as usize])).collect();
        let centroid = |c: &[[f32; 3]; 3]| -> [f32; 3] {
            [0, 1, 2].map(|a| (c[0][a] + c[1][a] + c[2][a]) / 3.0)
        };
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let cents: Vec<[f32; 3]> = corners.iter().map(centroid).collect();
        let mut bvh =
            Bvh { nodes: Vec::with_capacity(2 * triangles.len() / LEAF_SIZE + 1), tris: vec![] };
        if !triangles.is_empty() {
            bvh.build(&corners, &cents, &mut order, 0);
        }
        bvh.tris = order
            .iter()
            .map(|&t| {
                let c = corners[t as usize];
                Tri { p0: c[0], e1: sub(c[1], c[0]), e2: sub(c[2], c[0]) }
            })
            .collect();
        bvh
    }

    fn build(
        &mut self,
        corners: &[[[f32; 3]; 3]],
        cents: &[[f32; 3]],
        order: &mut [u32],
        start: usize,
    ) -> usize {
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        let (mut clo, mut chi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for &t in order.iter() {
            for p in &corners[t as usize] {
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            let c = cents[t as usize];
            for a in 0..3 {
                clo[a] = clo[a].min(c[a]);
                chi[a] = chi[a].max(c[a]);
            }
        }
        let me = self.nodes.len();
        self.nodes.push(Node { lo, hi, start_or_right: start as u32, count: order.len() as u32 });
        if order.len() <= LEAF_SIZE {
            return me;
        }
        let mid = match sah_split(corners, cents, order, clo, chi) {
            Some(mid) => mid,
            None => {
                // No useful binned split (centroids bunched in one bin): the median of the
                // longest axis, unless every centroid coincides.
                let axis = (0..3)
                    .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
                    .unwrap_or(0);
                if chi[axis] <= clo[axis] {
                    return me;
                }
                let mid = order.len() / 2;
                order.select_nth_unstable_by(mid, |&a, &b| {
                    cents[a as usize][axis].total_cmp(&cents[b as usize][axis])
                });
                mid
            }
        };
        let (left, right) = order.split_at_mut(mid);
        self.build(corners, cents, left, start);
        let r = self.build(corners, cents, right, start + mid);
        self.nodes[me].start_or_right = r as u32;
        self.nodes[me].count = 0;
        me
    }

    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.tris.len()
    }

    /// The flat node array (depth-first; the left child follows its parent).
    pub(super) fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The triangles in leaf order.
    pub(super) fn tris(&self) -> &[Tri] {
        &self.tris
    }

    /// Whether the ray `origin + t·dir`, `t > t_min`, hits any triangle.
    pub fn occluded(&self, origin: [f32; 3], dir: [f32; 3], t_min: f32) -> bool {
        !self.nodes.is_empty() && self.occluded_below(0, origin, dir, t_min)
    }

    /// [`Bvh::occluded`] restricted to the triangles under node `root` (same tests, so a
    /// hit there is a hit of the whole query).
    pub(super) fn occluded_below(
        &self,
        root: u32,
        origin: [f32; 3],
        dir: [f32; 3],
        t_min: f32,
    ) -> bool {
        let inv = dir.map(|d| 1.0 / d);
        let mut stack = [root; 64];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let me = stack[sp];
            let node = &self.nodes[me as usize];
            if !slab_hit(node, origin, inv, t_min) {
                continue;
            }
            if node.count > 0 {
                let s = node.start_or_right as usize;
                let hit = self.tris[s..s + node.count as usize]
                    .iter()
                    .any(|t| tri_hit(t, origin, dir, t_min));
                if hit {
                    return true;
                }
            } else if sp + 2 <= stack.len() {
                // Depth-first layout: the left child directly follows its parent.
                stack[sp] = node.start_or_right;
                stack[sp + 1] = me + 1;
                sp += 2;
            }
        }
        false
    }
}

/// Bins per axis of the surface-area split.
const SAH_BINS: usize = 16;

/// Box of `lo..hi` grown by the corners of a triangle.
fn grow(b: &mut ([f32; 3], [f32; 3]), c: &[[f32; 3]; 3]) {
    for p in c {
        for a in 0..3 {
            b.0[a] = b.0[a].min(p[a]);
            b.1[a] = b.1[a].max(p[a]);
        }
    }
}

/// The smallest box holding both (an empty box, `MAX..MIN`, leaves the other as it is).
fn union(a: &([f32; 3], [f32; 3]), b: &([f32; 3], [f32; 3])) -> ([f32; 3], [f32; 3]) {
    ([0, 1, 2].map(|k| a.0[k].min(b.0[k])), [0, 1, 2].map(|k| a.1[k].max(b.1[k])))
}

/// Half the surface area of a box (0 for an empty one).
fn half_area(b: &([f32; 3], [f32; 3])) -> f32 {
    let e = [0, 1, 2].map(|a| (b.1[a] - b.0[a]).max(0.0));
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// The bin of centroid `c` along `axis` of the centroid bounds `clo..chi` (extent > 0).
fn bin(c: &[f32; 3], axis: usize, clo: [f32; 3], chi: [f32; 3]) -> usize {
    let scale = SAH_BINS as f32 / (chi[axis] - clo[axis]);
    (((c[axis] - clo[axis]) * scale) as usize).min(SAH_BINS - 1)
}

/// Partitions `order` by the binned surface-area heuristic (the split minimising
/// `A_left · n_left + A_right · n_right` over [`SAH_BINS`] centroid bins per axis) and
/// returns the size of the left part, or `None` when no bin boundary splits the set.
fn sah_split(
    corners: &[[[f32; 3]; 3]],
    cents: &[[f32; 3]],
    order: &mut [u32],
    clo: [f32; 3],
    chi: [f32; 3],
) -> Option<usize> {
    let empty = ([f32::MAX; 3], [f32::MIN; 3]);
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        let extent = chi[axis] - clo[axis];
        if extent <= 0.0 {
            continue;
        }
        let mut boxes = [empty; SAH_BINS];
        let mut counts = [0usize; SAH_BINS];
        for &t in order.iter() {
            let b = bin(&cents[t as usize], axis, clo, chi);
            counts[b] += 1;
            grow(&mut boxes[b], &corners[t as usize]);
        }
        // Right-to-left sweep: cost of the right part for each boundary.
        let mut right = [0f32; SAH_BINS];
        let (mut acc, mut n) = (empty, 0usize);
        for b in (1..SAH_BINS).rev() {
            n += counts[b];
            acc = union(&acc, &boxes[b]);
            right[b] = half_area(&acc) * n as f32;
        }
        let (mut acc, mut n) = (empty, 0usize);
        for b in 0..SAH_BINS - 1 {
            n += counts[b];
            acc = union(&acc, &boxes[b]);
            if n == 0 || n == order.len() {
                continue;
            }
            let cost = half_area(&acc) * n as f32 + right[b + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    let (_, axis, split) = best?;
    let left_of = |t: &u32| bin(&cents[*t as usize], axis, clo, chi) < split;
    // An in-place partition (deterministic, so the same mesh always gives the same tree).
    let mut i = 0;
    for j in 0..order.len() {
        if left_of(&order[j]) {
            order.swap(i, j);
            i += 1;
        }
    }
    Some(i)
}

fn slab_hit(n: &Node, o: [f32; 3], inv: [f32; 3], t_min: f32) -> bool {
    let (mut t0, mut t1) = (t_min, f32::INFINITY);
    for a in 0..3 {
        let ta = (n.lo[a] - o[a]) * inv[a];
        let tb = (n.hi[a] - o[a]) * inv[a];
        // NaN (0·∞ on a slab boundary) is treated as "inside" by min/max.
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    t0 <= t1
}

pub(super) fn tri_hit(t: &Tri, o: [f32; 3], d: [f32; 3], t_min: f32) -> bool {
    let p = cross(d, t.e2);
    let det = dot(t.e1, p);
    if det.abs() < 1e-20 {
        return false;
    }
    let inv = 1.0 / det;
    let s = sub(o, t.p0);
    let u = dot(s, p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = cross(s, t.e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    dot(t.e2, q) * inv > t_min
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(pos: &[[f32; 3]], tris: &[[u32; 3]], o: [f32; 3], d: [f32; 3]) -> bool {
        tris.iter().any(|t| {
            let c = t.map(|i| pos[i as usize]);
            tri_hit(&Tri { p0: c[0], e1: sub(c[1], c[0]), e2: sub(c[2], c[0]) }, o, d, 1e-4)
        })
    }

    #[test]
    fn matches_brute_force_on_random_rays() {
        // A wavy 12×12 sheet and rays from below and above it.
        let n = 12;
        let mut pos = vec![];
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                pos.push([x, y, 0.1 * (6.0 * x).sin() * (4.0 * y).cos()]);
            }
        }
        let mut tris = vec![];
        for j in 0..n as u32 {
            for i in 0..n as u32 {
                let a = j * (n as u32 + 1) + i;
                tris.push([a, a + 1, a + n as u32 + 2]);
                tris.push([a, a + n as u32 + 2, a + n as u32 + 1]);
            }
        }
        let bvh = Bvh::new(&pos, &tris);
        let mut seed = 1u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        let mut hits = 0;
        for _ in 0..2000 {
            let o = [rnd() * 1.4 - 0.2, rnd() * 1.4 - 0.2, rnd() * 0.6 - 0.3];
            let d = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5];
            let expect = brute(&pos, &tris, o, d);
            assert_eq!(bvh.occluded(o, d, 1e-4), expect, "{o:?} {d:?}");
            hits += expect as usize;
        }
        assert!(hits > 200 && hits < 1800, "{hits}");
        assert!(!Bvh::new(&pos, &[]).occluded([0.0; 3], [0.0, 0.0, 1.0], 0.0));
    }

    #[test]
    fn degenerate_sets_build_and_answer_like_brute_force() {
        // 300 copies of one triangle, 50 zero-area slivers on a line and one far triangle:
        // the binned split must neither loop nor lose triangles.
        let pos = vec![
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [0.0, 0.0, 2.0],
            [1.0, 1.0, 2.0],
            [2.0, 2.0, 2.0],
            [5.0, 5.0, 3.0],
            [6.0, 5.0, 3.0],
            [5.0, 6.0, 3.0],
        ];
        let mut tris = vec![[0u32, 1, 2]; 300];
        tris.extend(std::iter::repeat_n([3u32, 4, 5], 50));
        tris.push([6, 7, 8]);
        let bvh = Bvh::new(&pos, &tris);
        assert_eq!(bvh.triangles(), tris.len());
        let leaves: usize = bvh.nodes().iter().map(|n| n.count as usize).sum();
        assert_eq!(leaves, tris.len());
        for (o, d, hit) in [
            ([0.2, 0.2, 0.0], [0.0, 0.0, 1.0], true),
            ([0.9, 0.9, 0.0], [0.0, 0.0, 1.0], false),
            ([5.2, 5.2, 0.0], [0.0, 0.0, 1.0], true),
            ([3.0, 3.0, 0.0], [0.0, 0.0, 1.0], false),
        ] {
            assert_eq!(bvh.occluded(o, d, 1e-4), hit, "{o:?}");
            assert_eq!(brute(&pos, &tris, o, d), hit, "{o:?}");
        }
    }
}
