//! Eight hemicube pixel rays at a time for the rasteriser of [`super::raster`] (Sattler et
//! al. 2003, §5.2: the `V(x, p_α)` of [S03 eq. 9]): the reference's any-hit tests — the slab test
//! of a BVH box and the Möller–Trumbore test of [`super::bvh`] — evaluated for eight
//! rays in lanes ("an octet"), plus a packet traversal of a BVH subtree with up to
//! [`PACKET`] rays that visits each node once for all the rays still open, nearer child
//! first.
//!
//! Exactness. Each lane performs the very `f32` operations of the scalar tests in the same
//! order (no fused multiply-add, IEEE division, the same NaN handling of `min`/`max` and
//! comparisons), on the very ray (`FrameRays` holds `to_world` of the pixel direction and
//! its reciprocal exactly as [`super::bvh::Bvh::occluded`] forms them), so a lane reports a
//! hit exactly when the scalar test does. Per triangle `s = o − p₀`, `q = s × e₁` and
//! `e₂ · q` do not depend on the ray and are formed once, as the scalar test forms them.
//! With AVX2 (detected at run time) the lanes become one 8-wide vector; elsewhere the same
//! code runs as scalar loops.

use super::bvh::{Bvh, Node, Tri, cross, dot, sub};
use crate::hemicube::HemicubeFrame;

/// Most rays in one packet (the lane masks are a `u64`).
pub(super) const PACKET: usize = 64;

/// World directions and their reciprocals of every pixel of one frame, one array per axis,
/// padded by one octet so any eight consecutive pixels can be loaded.
pub(super) struct FrameRays {
    pub(super) dir: [Vec<f32>; 3],
    pub(super) inv: [Vec<f32>; 3],
    /// The tangent-space pixel directions, one array per axis.
    tangent: [Vec<f32>; 3],
}

impl FrameRays {
    /// Room for the pixels of the tangent-space directions `dirs`.
    pub(super) fn new(dirs: &[[f32; 3]]) -> FrameRays {
        let v = || vec![0f32; dirs.len() + 8];
        let axis = |a: usize| dirs.iter().map(|d| d[a]).collect();
        FrameRays {
            dir: [v(), v(), v()],
            inv: [v(), v(), v()],
            tangent: [axis(0), axis(1), axis(2)],
        }
    }

    /// The rays of `frame`: [`HemicubeFrame::to_world`] of every pixel direction and its
    /// reciprocal, per axis (the same operations in the same order, so the same bits).
    pub(super) fn set(&mut self, frame: &HemicubeFrame) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above); the kernel is plain safe code.
            #[allow(unsafe_code)]
            unsafe {
                self.set_avx2(frame)
            };
            return;
        }
        self.set_kernel(frame);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn set_avx2(&mut self, frame: &HemicubeFrame) {
        self.set_kernel(frame);
    }

    #[inline(always)]
    fn set_kernel(&mut self, frame: &HemicubeFrame) {
        let [t, b, n] = frame.axes;
        let [x, y, z] = &self.tangent;
        for a in 0..3 {
            let (dir, inv) = (&mut self.dir[a], &mut self.inv[a]);
            for (((d, i), &x), (&y, &z)) in
                dir.iter_mut().zip(inv.iter_mut()).zip(x).zip(y.iter().zip(z))
            {
                *d = x * t[a] + y * b[a] + z * n[a];
                *i = 1.0 / *d;
            }
        }
    }
}

/// `N` lanes of one axis starting at pixel `p`.
#[inline(always)]
fn lanes<const N: usize>(v: &[f32], p: usize) -> &[f32; N] {
    v[p..p + N].try_into().unwrap_or(&[0.0; N])
}

/// The slab test of [`super::bvh`] for `N ≤ 32` rays with reciprocal directions `inv`
/// (bit `l` = lane `l`).
#[inline(always)]
fn slab<const N: usize>(node: &Node, o: [f32; 3], t_min: f32, inv: [&[f32; N]; 3]) -> u32 {
    let lo = sub(node.lo, o);
    let hi = sub(node.hi, o);
    let mut bits = 0u32;
    for l in 0..N {
        let (mut t0, mut t1) = (t_min, f32::INFINITY);
        for a in 0..3 {
            let ta = lo[a] * inv[a][l];
            let tb = hi[a] * inv[a][l];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        bits |= ((t0 <= t1) as u32) << l;
    }
    bits
}

/// A triangle with the ray-independent parts of the test for rays from one origin.
pub(super) struct TriFromOrigin<'a> {
    tri: &'a Tri,
    s: [f32; 3],
    q: [f32; 3],
    e2_q: f32,
}

impl<'a> TriFromOrigin<'a> {
    #[inline(always)]
    pub(super) fn new(tri: &'a Tri, o: [f32; 3]) -> Self {
        let s = sub(o, tri.p0);
        let q = cross(s, tri.e1);
        TriFromOrigin { tri, s, q, e2_q: dot(tri.e2, q) }
    }
}

/// [`super::bvh::tri_hit`] for `N ≤ 32` rays with directions `d` (bit `l` = lane `l`).
#[inline(always)]
fn tri<const N: usize>(t: &TriFromOrigin, t_min: f32, d: [&[f32; N]; 3]) -> u32 {
    let mut bits = 0u32;
    for l in 0..N {
        let dl = [d[0][l], d[1][l], d[2][l]];
        let pv = cross(dl, t.tri.e2);
        let det = dot(t.tri.e1, pv);
        let inv = 1.0 / det;
        let u = dot(t.s, pv) * inv;
        let v = dot(dl, t.q) * inv;
        // `det.abs() < 1e-20` is a miss in the scalar test; NaN is not (it fails on `u`).
        let hit = (det.abs() >= 1e-20 || det.is_nan())
            & (0.0..=1.0).contains(&u)
            & !(v < 0.0 || u + v > 1.0)
            & (t.e2_q * inv > t_min);
        bits |= (hit as u32) << l;
    }
    bits
}

/// Up to [`PACKET`] rays of one frame, packed into lanes, with the occlusion-mask bit
/// each one answers for.
pub(super) struct Packet {
    dir: [[f32; PACKET]; 3],
    inv: [[f32; PACKET]; 3],
    pub(super) bit: [u32; PACKET],
    pub(super) len: usize,
}

impl Packet {
    pub(super) fn new() -> Packet {
        Packet { dir: [[0.0; PACKET]; 3], inv: [[0.0; PACKET]; 3], bit: [0; PACKET], len: 0 }
    }

    /// Adds the ray of pixel `p` of `rays` for occlusion-mask bit `bit`; false when full.
    pub(super) fn push(&mut self, rays: &FrameRays, p: usize, bit: u32) -> bool {
        let k = self.len;
        if k == PACKET {
            return false;
        }
        for a in 0..3 {
            self.dir[a][k] = rays.dir[a][p];
            self.inv[a][k] = rays.inv[a][p];
        }
        self.bit[k] = bit;
        self.len += 1;
        true
    }

    /// Lanes of group `k` of `N` rays.
    #[inline(always)]
    fn group<const N: usize>(v: &[[f32; PACKET]; 3], k: usize) -> [&[f32; N]; 3] {
        [0, 1, 2].map(|a| lanes(&v[a], N * k))
    }
}

/// The lanes of `packet` (bit `k` = ray `k`) whose rays from `o` hit a triangle under
/// node `root`, with the node tests of [`Bvh::occluded_below`].
#[inline(always)]
fn packet_hits_kernel<const N: usize>(
    bvh: &Bvh,
    root: u32,
    o: [f32; 3],
    t_min: f32,
    packet: &Packet,
) -> u64 {
    let lane_mask = (1u64 << N) - 1;
    let (nodes, tris) = (bvh.nodes(), bvh.tris());
    let n = packet.len.min(PACKET);
    let all = if n == 64 { u64::MAX } else { (1u64 << n) - 1 };
    let groups = n.div_ceil(N);
    let mut open = all;
    let mut stack = [(root, all); 64];
    let mut sp = 1usize;
    while sp > 0 {
        sp -= 1;
        let (me, m) = stack[sp];
        let Some(node) = nodes.get(me as usize) else { continue };
        let mut live = 0u64;
        for k in 0..groups {
            let lm = (m & open) >> (N * k) & lane_mask;
            if lm != 0 {
                let bits = slab::<N>(node, o, t_min, Packet::group(&packet.inv, k)) as u64;
                live |= (bits & lm) << (N * k);
            }
        }
        if live == 0 {
            continue;
        }
        if node.count > 0 {
            let s = node.start_or_right as usize;
            for t in tris.get(s..s + node.count as usize).unwrap_or(&[]) {
                let tf = TriFromOrigin::new(t, o);
                for k in 0..groups {
                    let lm = live >> (N * k) & lane_mask;
                    if lm != 0 {
                        let h = tri::<N>(&tf, t_min, Packet::group(&packet.dir, k)) as u64 & lm;
                        live &= !(h << (N * k));
                        open &= !(h << (N * k));
                    }
                }
                if live == 0 {
                    break;
                }
            }
            if open == 0 {
                break;
            }
        } else if sp + 2 <= stack.len() {
            // Depth-first layout: the left child directly follows its parent. The nearer
            // child is visited first (any hit ends a ray).
            let (l, r) = (me + 1, node.start_or_right);
            let near_left = match (nodes.get(l as usize), nodes.get(r as usize)) {
                (Some(a), Some(b)) => centre_dist2(a, o) <= centre_dist2(b, o),
                _ => true,
            };
            let (first, second) = if near_left { (l, r) } else { (r, l) };
            stack[sp] = (second, live);
            stack[sp + 1] = (first, live);
            sp += 2;
        }
    }
    all & !open
}

/// Squared distance from `o` to the centre of a node's box.
#[inline(always)]
fn centre_dist2(n: &Node, o: [f32; 3]) -> f32 {
    let c = [0, 1, 2].map(|a| 0.5 * (n.lo[a] + n.hi[a]) - o[a]);
    dot(c, c)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn packet_hits_avx2(bvh: &Bvh, root: u32, o: [f32; 3], t_min: f32, packet: &Packet) -> u64 {
    packet_hits_kernel::<8>(bvh, root, o, t_min, packet)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn packet_hits_avx512(bvh: &Bvh, root: u32, o: [f32; 3], t_min: f32, packet: &Packet) -> u64 {
    packet_hits_kernel::<16>(bvh, root, o, t_min, packet)
}

/// [`packet_hits_kernel`] with 16-lane (AVX-512) or 8-lane (AVX2) vectors where the CPU
/// has them.
#[allow(unsafe_code)]
pub(super) fn packet_hits(bvh: &Bvh, root: u32, o: [f32; 3], t_min: f32, packet: &Packet) -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above); plain safe code.
            return unsafe { packet_hits_avx512(bvh, root, o, t_min, packet) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above); plain safe code.
            return unsafe { packet_hits_avx2(bvh, root, o, t_min, packet) };
        }
    }
    packet_hits_kernel::<8>(bvh, root, o, t_min, packet)
}

/// One row word of open pixels for [`tri_rows`]: the pixel of bit 0, the index of the
/// occlusion word and its open bits to test.
#[derive(Debug, Clone, Copy)]
pub(super) struct RowWord {
    pub(super) pixel0: usize,
    pub(super) word: usize,
    pub(super) open: u64,
}

#[inline(always)]
fn tri_rows_kernel(
    tf: &TriFromOrigin,
    t_min: f32,
    rays: &FrameRays,
    rows: &[RowWord],
    occ: &mut [u64],
) -> u32 {
    let mut newly = 0;
    for r in rows {
        let mut bits = r.open;
        while bits != 0 {
            let c = bits.trailing_zeros() as usize;
            let lm = (bits >> c) as u32 & 0xff;
            bits &= !(0xffu64 << c);
            let p = r.pixel0 + c;
            let d = [lanes(&rays.dir[0], p), lanes(&rays.dir[1], p), lanes(&rays.dir[2], p)];
            let h = (tri::<8>(tf, t_min, d) & lm) as u64;
            if h != 0 {
                if let Some(w) = occ.get_mut(r.word) {
                    *w |= h << c;
                }
                newly += h.count_ones();
            }
        }
    }
    newly
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn tri_rows_avx2(
    tf: &TriFromOrigin,
    t_min: f32,
    rays: &FrameRays,
    rows: &[RowWord],
    occ: &mut [u64],
) -> u32 {
    tri_rows_kernel(tf, t_min, rays, rows, occ)
}

/// Tests the open pixels of `rows` against one triangle, sets the bits of the hit ones in
/// `occ` and returns how many were newly occluded.
#[allow(unsafe_code)]
pub(super) fn tri_rows(
    tf: &TriFromOrigin,
    t_min: f32,
    rays: &FrameRays,
    rows: &[RowWord],
    occ: &mut [u64],
) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the kernel is plain safe code.
        return unsafe { tri_rows_avx2(tf, t_min, rays, rows, occ) };
    }
    tri_rows_kernel(tf, t_min, rays, rows, occ)
}
