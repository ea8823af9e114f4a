//! A binned-SAH bounding volume hierarchy over axis-aligned boxes, in the flat-array style
//! of `btf-light/src/visibility/bvh.rs`: `f32` nodes of 32 bytes, the left child right after
//! its parent, leaves indexing a permutation of the primitives.
//!
//! **Build.** Each node bins its primitives' centroids into 16 bins per axis and takes the
//! split that minimises the surface-area heuristic `A_L·n_L + A_R·n_R` (unit traversal and
//! intersection costs); a node of at most [`MAX_LEAF`] primitives whose best split costs
//! no less than `A·n` becomes a leaf, and so does one whose centroids coincide (split by
//! index instead when it is large). Subtrees of more than [`PARALLEL_MIN`] primitives are
//! built with `rayon::join` and stitched in a fixed order, so the tree — node order
//! included — is identical for any thread count.
//!
//! **Traversal.** Closest hit visits the nearer child first and prunes by the best
//! distance so far; any hit stops at the first accepted primitive. The slab test is in
//! `f32` with the primitive boxes rounded outwards and the comparison padded by a relative
//! 1e-5, so the box test never rejects what the `f64` primitive test would accept.

use rayon::join;

/// Largest leaf.
pub const MAX_LEAF: usize = 4;
/// Subtrees larger than this are built in parallel.
pub const PARALLEL_MIN: usize = 1 << 14;
const BINS: usize = 16;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: [f32; 3],
    /// Upper corner.
    pub max: [f32; 3],
}

impl Aabb {
    /// The empty box.
    pub const EMPTY: Aabb = Aabb { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] };

    /// Grows to contain `o`.
    #[inline]
    pub fn grow(&mut self, o: &Aabb) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(o.min[k]);
            self.max[k] = self.max[k].max(o.max[k]);
        }
    }

    /// Grows to contain point `p`.
    #[inline]
    pub fn grow_point(&mut self, p: [f32; 3]) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(p[k]);
            self.max[k] = self.max[k].max(p[k]);
        }
    }

    /// Half the surface area (0 for an empty box).
    #[inline]
    pub fn half_area(&self) -> f32 {
        let e = [self.max[0] - self.min[0], self.max[1] - self.min[1], self.max[2] - self.min[2]];
        if e.iter().any(|x| x.is_nan() || *x < 0.0) {
            return 0.0;
        }
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// Centre.
    #[inline]
    pub fn centroid(&self) -> [f32; 3] {
        [
            0.5 * (self.min[0] + self.max[0]),
            0.5 * (self.min[1] + self.max[1]),
            0.5 * (self.min[2] + self.max[2]),
        ]
    }

    /// The box of a capsule, rounded outwards to `f32`.
    pub fn of_capsule(a: [f64; 3], b: [f64; 3], r: f64) -> Aabb {
        let mut bx = Aabb::EMPTY;
        for k in 0..3 {
            let lo = a[k].min(b[k]) - r;
            let hi = a[k].max(b[k]) + r;
            bx.min[k] = round_down(lo);
            bx.max[k] = round_up(hi);
        }
        bx
    }
}

fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x { f.next_down() } else { f }
}

fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

/// A node: a leaf when `count > 0` (primitives `prims[first..first + count]`), otherwise
/// an interior node whose left child follows it and whose right child is `first`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Node {
    /// Box lower corner.
    pub min: [f32; 3],
    /// First primitive (leaf) or right child (interior).
    pub first: u32,
    /// Box upper corner.
    pub max: [f32; 3],
    /// Primitive count (0 for interior nodes).
    pub count: u32,
}

/// The hierarchy.
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    /// Nodes, root first.
    pub nodes: Vec<Node>,
    /// Primitive indices in leaf order.
    pub prims: Vec<u32>,
}

/// A ray prepared for slab tests.
#[derive(Debug, Clone, Copy)]
pub struct SlabRay {
    o: [f32; 3],
    inv: [f32; 3],
}

impl SlabRay {
    /// From an `f64` origin and direction.
    pub fn new(o: [f64; 3], d: [f64; 3]) -> Self {
        SlabRay { o: o.map(|x| x as f32), inv: d.map(|x| (1.0 / x) as f32) }
    }

    /// Entry distance into the box if it is hit within `[0, t_max]`.
    #[inline]
    fn hit(&self, n: &Node, t_max: f32) -> Option<f32> {
        let mut t0 = 0f32;
        let mut t1 = t_max * (1.0 + 1e-5) + 1e-30;
        for k in 0..3 {
            let a = (n.min[k] - self.o[k]) * self.inv[k];
            let b = (n.max[k] - self.o[k]) * self.inv[k];
            // `min`/`max` drop a NaN (0·∞ when the origin lies on a slab of a parallel ray).
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        // Pad: the box was rounded outwards, the ray origin to f32 (relative 6e-8); an
        // infinite bound (a parallel ray outside a slab, an unbounded query) is no reason
        // to pad.
        if t0 > t1 {
            if !(t0.is_finite() && t1.is_finite()) {
                return None;
            }
            let pad = 1e-5 * t0.abs().max(t1.abs()) + 1e-30;
            if t0 > t1 + pad {
                return None;
            }
        }
        Some(t0)
    }
}

impl Bvh {
    /// Builds over `boxes` (deterministic for any thread count).
    pub fn build(boxes: &[Aabb]) -> Bvh {
        if boxes.is_empty() {
            return Bvh::default();
        }
        let centroids: Vec<[f32; 3]> = boxes.iter().map(Aabb::centroid).collect();
        let mut prims: Vec<u32> = (0..boxes.len() as u32).collect();
        let ctx = Ctx { boxes, centroids: &centroids };
        let nodes = ctx.subtree(&mut prims, 0);
        Bvh { nodes, prims }
    }

    /// Bytes held by nodes and the permutation.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.prims.len() * 4
    }

    /// The root box (empty for an empty tree).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| Aabb { min: n.min, max: n.max })
    }

    /// Closest hit: `test(prim, t_max)` returns the primitive's hit distance below `t_max`
    /// (the traversal passes the best distance so far), or `None`.
    #[inline]
    pub fn closest(
        &self,
        ray: &SlabRay,
        mut t_max: f64,
        mut test: impl FnMut(u32, f64) -> Option<f64>,
    ) -> Option<(u32, f64)> {
        if self.nodes.is_empty() || ray.hit(&self.nodes[0], t_max as f32).is_none() {
            return None;
        }
        let mut best = None;
        let mut stack = [0u32; 64];
        let mut sp = 0;
        let mut idx = 0u32;
        loop {
            let n = &self.nodes[idx as usize];
            if n.count > 0 {
                for &p in &self.prims[n.first as usize..(n.first + n.count) as usize] {
                    if let Some(t) = test(p, t_max).filter(|t| *t < t_max) {
                        t_max = t;
                        best = Some((p, t));
                    }
                }
            } else {
                let (l, r) = (idx + 1, n.first);
                let hl = ray.hit(&self.nodes[l as usize], t_max as f32);
                let hr = ray.hit(&self.nodes[r as usize], t_max as f32);
                match (hl, hr) {
                    (Some(a), Some(b)) => {
                        let (near, far) = if a <= b { (l, r) } else { (r, l) };
                        stack[sp] = far;
                        sp += 1;
                        idx = near;
                        continue;
                    }
                    (Some(_), None) => {
                        idx = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        idx = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node still in reach of the (shrunken) best distance.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                idx = stack[sp];
                if ray.hit(&self.nodes[idx as usize], t_max as f32).is_some() {
                    break;
                }
            }
        }
    }

    /// Any hit: true as soon as `test(prim)` accepts a primitive (within `t_max`, which
    /// the test itself applies).
    #[inline]
    pub fn any(&self, ray: &SlabRay, t_max: f64, mut test: impl FnMut(u32) -> bool) -> bool {
        if self.nodes.is_empty() || ray.hit(&self.nodes[0], t_max as f32).is_none() {
            return false;
        }
        let mut stack = [0u32; 64];
        let mut sp = 0;
        let mut idx = 0u32;
        loop {
            let n = &self.nodes[idx as usize];
            if n.count > 0 {
                for &p in &self.prims[n.first as usize..(n.first + n.count) as usize] {
                    if test(p) {
                        return true;
                    }
                }
            } else {
                let (l, r) = (idx + 1, n.first);
                let hl = ray.hit(&self.nodes[l as usize], t_max as f32).is_some();
                let hr = ray.hit(&self.nodes[r as usize], t_max as f32).is_some();
                if hl {
                    if hr {
                        stack[sp] = r;
                        sp += 1;
                    }
                    idx = l;
                    continue;
                }
                if hr {
                    idx = r;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            idx = stack[sp];
        }
    }

    /// Visits every leaf primitive whose box contains point `p`.
    pub fn points_query(&self, p: [f64; 3], mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let q = p.map(|x| x as f32);
        let inside = |n: &Node| (0..3).all(|k| n.min[k] <= q[k] && q[k] <= n.max[k]);
        let mut stack = [0u32; 64];
        let mut sp = 0;
        let mut idx = 0u32;
        if !inside(&self.nodes[0]) {
            return;
        }
        loop {
            let n = &self.nodes[idx as usize];
            if n.count > 0 {
                for &pr in &self.prims[n.first as usize..(n.first + n.count) as usize] {
                    visit(pr);
                }
            } else {
                let (l, r) = (idx + 1, n.first);
                let il = inside(&self.nodes[l as usize]);
                let ir = inside(&self.nodes[r as usize]);
                if il {
                    if ir {
                        stack[sp] = r;
                        sp += 1;
                    }
                    idx = l;
                    continue;
                }
                if ir {
                    idx = r;
                    continue;
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            idx = stack[sp];
        }
    }

    /// Depth of the deepest leaf (the traversal stack holds 64).
    pub fn depth(&self) -> usize {
        fn rec(nodes: &[Node], i: usize) -> usize {
            let n = &nodes[i];
            if n.count > 0 { 1 } else { 1 + rec(nodes, i + 1).max(rec(nodes, n.first as usize)) }
        }
        if self.nodes.is_empty() { 0 } else { rec(&self.nodes, 0) }
    }
}

struct Ctx<'a> {
    boxes: &'a [Aabb],
    centroids: &'a [[f32; 3]],
}

impl Ctx<'_> {
    /// Builds the subtree of `prims` (whose first element is at `offset` in the final
    /// permutation); child indices are relative to the returned vector's start.
    fn subtree(&self, prims: &mut [u32], offset: usize) -> Vec<Node> {
        let mut nodes = Vec::with_capacity(2 * prims.len() / MAX_LEAF + 1);
        self.build_into(&mut nodes, prims, offset, 0);
        nodes
    }

    fn build_into(&self, nodes: &mut Vec<Node>, prims: &mut [u32], offset: usize, depth: usize) {
        let mut bounds = Aabb::EMPTY;
        let mut cb = Aabb::EMPTY;
        for &p in prims.iter() {
            bounds.grow(&self.boxes[p as usize]);
            cb.grow_point(self.centroids[p as usize]);
        }
        let me = nodes.len();
        nodes.push(Node {
            min: bounds.min,
            max: bounds.max,
            first: offset as u32,
            count: prims.len() as u32,
        });
        let n = prims.len();
        if n <= 1 {
            return;
        }
        let mid = match self.best_split(prims, &bounds, &cb) {
            Some(m) => m,
            None if n <= MAX_LEAF => return,
            // Coincident centroids or no useful split: halve by index to bound leaf size.
            None => n / 2,
        };
        // Depth guard: 64-entry traversal stacks (never reached by SAH trees of < 2^32).
        if depth > 60 {
            return;
        }
        let (left, right) = prims.split_at_mut(mid);
        if n > PARALLEL_MIN {
            let (ln, rn) =
                join(|| self.subtree(left, offset), || self.subtree(right, offset + mid));
            let base = nodes.len();
            nodes.extend(ln.iter().map(|x| shift(*x, base)));
            let rbase = nodes.len();
            nodes.extend(rn.iter().map(|x| shift(*x, rbase)));
            nodes[me].first = rbase as u32;
        } else {
            self.build_into(nodes, left, offset, depth + 1);
            let rbase = nodes.len();
            self.build_into(nodes, right, offset + mid, depth + 1);
            nodes[me].first = rbase as u32;
        }
        nodes[me].count = 0;
    }

    /// The SAH split: partitions `prims` in place and returns the left count, or `None`
    /// when a leaf is no more expensive.
    fn best_split(&self, prims: &mut [u32], bounds: &Aabb, cb: &Aabb) -> Option<usize> {
        let n = prims.len();
        let mut best: Option<(f32, usize, usize)> = None; // cost, axis, split bin
        for axis in 0..3 {
            let (lo, hi) = (cb.min[axis], cb.max[axis]);
            if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                continue;
            }
            let scale = BINS as f32 / (hi - lo);
            let mut bins = [(Aabb::EMPTY, 0usize); BINS];
            for &p in prims.iter() {
                let b = bin_of(self.centroids[p as usize][axis], lo, scale);
                bins[b].0.grow(&self.boxes[p as usize]);
                bins[b].1 += 1;
            }
            let mut right_area = [0f32; BINS];
            let mut right_count = [0usize; BINS];
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in (1..BINS).rev() {
                acc.grow(&bins[i].0);
                cnt += bins[i].1;
                right_area[i] = acc.half_area();
                right_count[i] = cnt;
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in 1..BINS {
                acc.grow(&bins[i - 1].0);
                cnt += bins[i - 1].1;
                if cnt == 0 || right_count[i] == 0 {
                    continue;
                }
                let cost = acc.half_area() * cnt as f32 + right_area[i] * right_count[i] as f32;
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis, i));
                }
            }
        }
        let (cost, axis, split) = best?;
        let leaf_cost = bounds.half_area() * n as f32;
        if n <= MAX_LEAF && cost >= leaf_cost {
            return None;
        }
        let (lo, hi) = (cb.min[axis], cb.max[axis]);
        let scale = BINS as f32 / (hi - lo);
        let mut i = 0;
        let mut j = n;
        while i < j {
            if bin_of(self.centroids[prims[i] as usize][axis], lo, scale) < split {
                i += 1;
            } else {
                j -= 1;
                prims.swap(i, j);
            }
        }
        (i > 0 && i < n).then_some(i)
    }
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

fn shift(mut n: Node, base: usize) -> Node {
    if n.count == 0 {
        n.first += base as u32;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = Rng::new(&[seed]);
        (0..n)
            .map(|_| {
                let c = rng.uniform3();
                let h = 0.01 * rng.uniform();
                Aabb::of_capsule(c, [c[0] + h, c[1], c[2] + h], 0.005)
            })
            .collect()
    }

    #[test]
    fn every_primitive_is_in_exactly_one_leaf_inside_its_ancestors() {
        let boxes = random_boxes(50_000, 3);
        let bvh = Bvh::build(&boxes);
        let mut seen = vec![0u32; boxes.len()];
        fn check(bvh: &Bvh, boxes: &[Aabb], i: usize, seen: &mut [u32]) {
            let n = bvh.nodes[i];
            let contains = |b: &Aabb| (0..3).all(|k| n.min[k] <= b.min[k] && b.max[k] <= n.max[k]);
            if n.count > 0 {
                for &p in &bvh.prims[n.first as usize..(n.first + n.count) as usize] {
                    assert!(contains(&boxes[p as usize]));
                    seen[p as usize] += 1;
                }
            } else {
                for c in [i + 1, n.first as usize] {
                    let m = bvh.nodes[c];
                    assert!(contains(&Aabb { min: m.min, max: m.max }));
                    check(bvh, boxes, c, seen);
                }
            }
        }
        check(&bvh, &boxes, 0, &mut seen);
        assert!(seen.iter().all(|&c| c == 1));
        assert!(bvh.depth() < 40, "depth {}", bvh.depth());
    }

    #[test]
    fn build_is_identical_for_one_and_two_threads() {
        let boxes = random_boxes(80_000, 5);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let a = one.install(|| Bvh::build(&boxes));
        let b = two.install(|| Bvh::build(&boxes));
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.prims, b.prims);
    }

    #[test]
    fn coincident_boxes_still_give_bounded_leaves() {
        let boxes = vec![Aabb::of_capsule([0.0; 3], [0.0; 3], 1.0); 1000];
        let bvh = Bvh::build(&boxes);
        assert!(bvh.nodes.iter().all(|n| n.count as usize <= MAX_LEAF));
        assert_eq!(bvh.prims.len(), 1000);
    }
}
