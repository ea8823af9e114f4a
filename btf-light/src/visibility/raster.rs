//! Visibility of one hemicube by projecting the mesh onto it (Sattler et al. 2003, §5.2:
//! the `V(x, p_α)` of [S03 eq. 9]), with the answer of one ray per pixel centre.
//!
//! Per frame (vertex side) the BVH is walked nearest child first. A node whose box lies
//! below the cone of the lowest pixel rays around the ray origin (`z < 0.9 · min_p(d_z /
//! |d_xy|) · |xy|`, which includes everything below the tangent plane) cannot hold a point
//! `o + t·d` of any pixel ray, and is skipped; so is a node whose projection onto every hemicube face
//! covers only pixels that are already occluded (hierarchical occlusion culling — inside a
//! closed garment the near wall hides the rest). A surviving triangle is clipped to each
//! face's pyramid of directions and projected (`u = p_u / p_m`, `v = p_v / p_m`); only the
//! still-visible pixels whose centres fall into the projected rectangle, widened by a
//! margin, are tested — with the very ray-triangle test ([`tri_hit`]) and the very ray
//! (same origin, same `f32` direction) the reference ray caster uses. A pixel is therefore
//! occluded here exactly when some triangle's test hits, as in the reference; the margin
//! (`2·10⁻³` face units plus a term growing for triangles close to the origin) only has to
//! cover the rounding of the projection, which is of order `10⁻⁶`.
//!
//! A far node over few still-visible pixels is finished instead by casting those pixels'
//! rays through its subtree as one packet, and near-triangle pixels are tested eight at a
//! time; both run the same tests lane by lane (see `ray_lanes`).

use super::bvh::{Bvh, Tri, dot, sub};
use super::raster_face::{Rect, face_bounds, face_of, ratio_range, span_mask, xy_distance};
use super::ray_lanes::{FrameRays, Packet, RowWord, TriFromOrigin, packet_hits, tri_rows};
use crate::hemicube::{Face, Hemicube, HemicubeFrame, faces};

/// Nodes with at most this many still-visible pixels under their projection are finished
/// by casting those pixels' rays through the node's subtree, as one packet.
const RAY_CAST_BELOW: usize = 48;

/// The rasteriser of one hemicube frame.
pub(super) struct FrameRaster<'a> {
    cube: &'a Hemicube,
    faces: [Face; 5],
    res: usize,
    step: f32,
    /// Words per pixel row of the occlusion mask.
    wpr: usize,
    /// Occluded-pixel mask, rows of every face in turn (`3 res` rows).
    occ: Vec<u64>,
    row_base: [usize; 5],
    occluded: usize,
    frame: HemicubeFrame,
    origin: [f32; 3],
    eps: f32,
    /// 0.9 × the smallest `z / √(x² + y²)` of any pixel centre: geometry below this cone
    /// around the origin lies under every pixel's ray.
    cone: f32,
    /// The pixel rays of the frame.
    rays: FrameRays,
    /// Scratch: open row words of a rectangle.
    rows: Vec<RowWord>,
}

impl<'a> FrameRaster<'a> {
    pub(super) fn new(cube: &'a Hemicube) -> FrameRaster<'a> {
        let res = cube.res as usize;
        let faces = faces(res);
        let wpr = res.div_ceil(64);
        let mut row_base = [0; 5];
        for f in 1..5 {
            row_base[f] = row_base[f - 1] + faces[f - 1].rows;
        }
        FrameRaster {
            cube,
            faces,
            res,
            step: 2.0 / res as f32,
            wpr,
            occ: vec![0; 3 * res * wpr],
            row_base,
            occluded: 0,
            frame: HemicubeFrame { origin: [0.0; 3], axes: [[0.0; 3]; 3] },
            origin: [0.0; 3],
            eps: 0.0,
            cone: 0.9
                * cube.dirs.iter().map(|d| d[2] / d[0].hypot(d[1])).fold(f32::INFINITY, f32::min),
            rays: FrameRays::new(&cube.dirs),
            rows: Vec::new(),
        }
    }

    /// Computes the visibility bits of `frame` into `out` (bit set = pixel sees the sky);
    /// rays start `eps` above the vertex along the normal and count hits beyond `eps`.
    pub(super) fn run(&mut self, bvh: &Bvh, frame: &HemicubeFrame, eps: f32, out: &mut [u64]) {
        self.frame = *frame;
        self.origin = [0, 1, 2].map(|a| frame.origin[a] + eps * frame.axes[2][a]);
        self.eps = eps;
        self.rays.set(frame);
        self.occ.fill(0);
        self.occluded = 0;
        self.walk(bvh);
        out.fill(0);
        for (f, face) in self.faces.iter().enumerate() {
            for r in 0..face.rows {
                let row = &self.occ[(self.row_base[f] + r) * self.wpr..][..self.wpr];
                let p0 = face.start + r * self.res;
                for (w, &occ) in row.iter().enumerate() {
                    let n = (self.res - 64 * w).min(64);
                    set_bits(out, p0 + 64 * w, !occ & span_mask(0, n - 1));
                }
            }
        }
    }

    fn walk(&mut self, bvh: &Bvh) {
        let (nodes, tris) = (bvh.nodes(), bvh.tris());
        if nodes.is_empty() {
            return;
        }
        let total = self.cube.len();
        let mut stack = vec![0u32];
        while let Some(me) = stack.pop() {
            if self.occluded == total {
                return;
            }
            let node = &nodes[me as usize];
            let Some(rects) = self.box_rects(node.lo, node.hi) else { continue };
            let open = self.visible_in(&rects, RAY_CAST_BELOW);
            if open == 0 {
                continue;
            }
            if open <= RAY_CAST_BELOW {
                // Few pixels left under a far node: rays through its subtree are cheaper
                // than projecting its triangles one by one.
                self.cast_packets(bvh, me, &rects);
                continue;
            }
            if node.count > 0 {
                let s = node.start_or_right as usize;
                for t in &tris[s..s + node.count as usize] {
                    self.triangle(t);
                }
                continue;
            }
            let (l, r) = (me + 1, node.start_or_right);
            let (dl, dr) =
                (self.centre_dist2(&nodes[l as usize]), self.centre_dist2(&nodes[r as usize]));
            if dl <= dr {
                stack.extend([r, l]);
            } else {
                stack.extend([l, r]);
            }
        }
    }

    fn centre_dist2(&self, n: &super::bvh::Node) -> f32 {
        (0..3).map(|a| (0.5 * (n.lo[a] + n.hi[a]) - self.origin[a]).powi(2)).sum()
    }

    /// Tangent-space coordinates of world point `q` relative to the ray origin.
    fn tangent(&self, q: [f32; 3]) -> [f32; 3] {
        let rel = sub(q, self.origin);
        self.frame.axes.map(|a| dot(rel, a))
    }

    /// The pixel rectangles of a world box, or `None` when it lies below the tangent plane.
    fn box_rects(&self, lo: [f32; 3], hi: [f32; 3]) -> Option<[Option<Rect>; 5]> {
        let centre = self.tangent([0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])));
        let half = [0, 1, 2].map(|a| 0.5 * (hi[a] - lo[a]));
        let mut t_lo = [0f32; 3];
        let mut t_hi = [0f32; 3];
        for (a, axis) in self.frame.axes.iter().enumerate() {
            let e: f32 = (0..3).map(|b| axis[b].abs() * half[b]).sum();
            let tol = 1e-5 * (centre[a].abs() + e);
            t_lo[a] = centre[a] - e - tol;
            t_hi[a] = centre[a] + e + tol;
        }
        if t_hi[2] < self.cone * xy_distance(&t_lo, &t_hi) {
            return None;
        }
        let dist2: f32 = (0..3).map(|a| (t_lo[a].max(0.0) + (-t_hi[a]).max(0.0)).powi(2)).sum();
        let margin = self.margin(dist2.sqrt(), 0.0);
        Some([0, 1, 2, 3, 4].map(|f| {
            let face = self.faces[f];
            let (m0, m1) = if face.sign > 0.0 {
                (t_lo[face.major], t_hi[face.major])
            } else {
                (-t_hi[face.major], -t_lo[face.major])
            };
            if m1 <= 0.0 {
                return None;
            }
            let u = ratio_range(t_lo[face.u], t_hi[face.u], m0, m1);
            let v = ratio_range(t_lo[face.v], t_hi[face.v], m0, m1);
            self.rect(f, u, v, margin)
        }))
    }

    /// Face-coordinate margin for geometry at distance `dist` from the origin with extent
    /// `extent`: covers the `f32` rounding of the projection and of the reference test.
    fn margin(&self, dist: f32, extent: f32) -> f32 {
        2e-3 + 256.0 * f32::EPSILON * (1.0 + extent / dist.max(self.eps))
    }

    /// Pixels of face `f` whose centres lie in `u × v` widened by `margin`.
    fn rect(&self, f: usize, u: (f32, f32), v: (f32, f32), margin: f32) -> Option<Rect> {
        let face = self.faces[f];
        let (c0, c1) = self.centre_range(u, -1.0, self.res, margin)?;
        let (r0, r1) = self.centre_range(v, face.v_min, face.rows, margin)?;
        Some(Rect { face: f, c0, c1, r0, r1 })
    }

    /// Indices `i < n` of the pixel centres `min + (i + ½)·step` within `[a − margin,
    /// b + margin]`; NaN bounds keep the whole range.
    fn centre_range(
        &self,
        (a, b): (f32, f32),
        min: f32,
        n: usize,
        margin: f32,
    ) -> Option<(usize, usize)> {
        let inv = 1.0 / self.step;
        let lo = ((a - margin - min) * inv - 0.5).max(-1.0).min(n as f32 + 1.0);
        let hi = ((b + margin - min) * inv - 0.5).min(n as f32).max(-2.0);
        // ceil and floor by truncation (both bounded, no libm call).
        let l = lo as i32 + ((lo as i32 as f32) < lo) as i32;
        let h = hi as i32 - (hi < hi as i32 as f32) as i32;
        let (l, h) = (l.max(0), h.min(n as i32 - 1));
        (l <= h).then_some((l as usize, h as usize))
    }

    /// The column masks of `r` per occlusion word (words `c0 / 64 ..= c1 / 64`).
    fn word_masks(r: &Rect) -> ([u64; 8], usize, usize) {
        // Rows hold at most 512 pixels (`RES_RANGE`), 8 words.
        let (w0, w1) = (r.c0 / 64, (r.c1 / 64).min(7));
        let mut m = [0u64; 8];
        for (w, m) in m.iter_mut().enumerate().take(w1 + 1).skip(w0) {
            *m = span_mask(r.c0.max(64 * w) - 64 * w, r.c1.min(64 * w + 63) - 64 * w);
        }
        (m, w0, w1)
    }

    /// Number of still-visible pixels in `rects`, counted up to just above `limit`.
    fn visible_in(&self, rects: &[Option<Rect>; 5], limit: usize) -> usize {
        let mut open = 0;
        for r in rects.iter().flatten() {
            let (m, w0, w1) = Self::word_masks(r);
            for row in r.r0..=r.r1 {
                let base = (self.row_base[r.face] + row) * self.wpr;
                for w in w0..=w1 {
                    open += (!self.occ[base + w] & m[w]).count_ones() as usize;
                }
                if open > limit {
                    return open;
                }
            }
        }
        open
    }

    /// The open row words of `r` into `self.rows`.
    fn open_rows(&mut self, r: &Rect) {
        self.rows.clear();
        let face = self.faces[r.face];
        let (m, w0, w1) = Self::word_masks(r);
        for row in r.r0..=r.r1 {
            let base = (self.row_base[r.face] + row) * self.wpr;
            for w in w0..=w1 {
                let open = !self.occ[base + w] & m[w];
                if open != 0 {
                    let pixel0 = face.start + row * self.res + 64 * w;
                    self.rows.push(RowWord { pixel0, word: base + w, open });
                }
            }
        }
    }

    /// Casts the rays of the open pixels of `rects` through the subtree of node `root`, in
    /// packets, and marks the hit ones.
    fn cast_packets(&mut self, bvh: &Bvh, root: u32, rects: &[Option<Rect>; 5]) {
        let mut packet = Packet::new();
        for r in rects.iter().flatten() {
            self.open_rows(r);
            for k in 0..self.rows.len() {
                let rw = self.rows[k];
                let mut bits = rw.open;
                while bits != 0 {
                    let c = bits.trailing_zeros() as usize;
                    let bit = (64 * rw.word + c) as u32;
                    if !packet.push(&self.rays, rw.pixel0 + c, bit) {
                        self.flush(bvh, root, &packet);
                        packet.len = 0;
                        continue;
                    }
                    bits &= bits - 1;
                }
            }
        }
        self.flush(bvh, root, &packet);
    }

    fn flush(&mut self, bvh: &Bvh, root: u32, packet: &Packet) {
        if packet.len == 0 {
            return;
        }
        let mut hits = packet_hits(bvh, root, self.origin, self.eps, packet);
        self.occluded += hits.count_ones() as usize;
        while hits != 0 {
            let b = packet.bit[hits.trailing_zeros() as usize] as usize;
            self.occ[b / 64] |= 1 << (b % 64);
            hits &= hits - 1;
        }
    }

    /// Tests one triangle against the still-visible pixels it may cover.
    fn triangle(&mut self, t: &Tri) {
        let p0 = self.tangent(t.p0);
        let e1 = self.frame.axes.map(|a| dot(t.e1, a));
        let e2 = self.frame.axes.map(|a| dot(t.e2, a));
        let corners = [p0, [0, 1, 2].map(|a| p0[a] + e1[a]), [0, 1, 2].map(|a| p0[a] + e2[a])];
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for c in &corners {
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f32::max);
        let tol =
            1e-5 * (extent + (0..3).map(|a| lo[a].abs().max(hi[a].abs())).fold(0.0, f32::max));
        if hi[2] + tol < self.cone * (xy_distance(&lo, &hi) - tol) {
            return;
        }
        let dist2: f32 = (0..3).map(|a| (lo[a].max(0.0) + (-hi[a]).max(0.0)).powi(2)).sum();
        let margin = self.margin(dist2.sqrt(), extent);
        let [a, b, c] = corners.map(|p| face_of(&p, tol));
        if let Some(f) = a.filter(|&f| b == Some(f) && c == Some(f)) {
            // Inside one pyramid (the common case): project the corners.
            let face = self.faces[f];
            let (mut u, mut v) = ((f32::MAX, f32::MIN), (f32::MAX, f32::MIN));
            for p in &corners {
                let m = face.sign * p[face.major];
                let (pu, pv) = (p[face.u] / m, p[face.v] / m);
                u = (u.0.min(pu), u.1.max(pu));
                v = (v.0.min(pv), v.1.max(pv));
            }
            if let Some(r) = self.rect(f, u, v, margin) {
                self.test_pixels(&r, t);
            }
            return;
        }
        for f in 0..5 {
            let Some((u, v)) = face_bounds(&self.faces[f], &corners, tol) else { continue };
            if let Some(r) = self.rect(f, u, v, margin) {
                self.test_pixels(&r, t);
            }
        }
    }

    fn test_pixels(&mut self, r: &Rect, t: &Tri) {
        self.open_rows(r);
        if self.rows.is_empty() {
            return;
        }
        let tf = TriFromOrigin::new(t, self.origin);
        self.occluded += tri_rows(&tf, self.eps, &self.rays, &self.rows, &mut self.occ) as usize;
    }
}

/// ORs the bits of `word` into the bit set `out` starting at bit `at`.
fn set_bits(out: &mut [u64], at: usize, word: u64) {
    let (i, s) = (at / 64, at % 64);
    out[i] |= word << s;
    if s > 0 && word >> (64 - s) != 0 {
        out[i + 1] |= word >> (64 - s);
    }
}
