//! The gather of [S03 eq. 10] (§5.3) organised for speed: the sums of
//! [`Radiances::gather_reference`], bit for bit, for all frames of a mesh.
//!
//! A vertex's front frame `(T, B, N)` and back frame `(T, B, −N)` (two-sided cloth, as
//! [`HemicubeFrame::of_mesh`] builds them) see every environment source at the same tangent
//! coordinates `x, y` and at `±z`: each source is transformed once per vertex and lands in
//! exactly one of the two hemicubes (or on the horizon of both). The RGB sums of a light are
//! kept side by side, so a visible source adds four 4-lane products `h_k · power` instead of
//! twelve scalar ones; the additions happen in the reference's order, so the result is
//! identical, not merely close.

use super::{GatherInput, Radiances, rotate_z};
use crate::env_cube::EnvCube;
use crate::hemicube::HemicubeFrame;
#[cfg(doc)]
use crate::hemicube::pixel_of;
use rayon::prelude::*;

/// Gathers `g` for the environment turned by `rotation_deg` about world `+z` (eq. 10): the
/// sums of [`Radiances::gather_reference`], bit for bit (see the module doc).
pub(super) fn gather(input: &GatherInput, env: &EnvCube, rotation_deg: f64) -> Radiances {
    let n_l = input.lights;
    let n = input.frames.len();
    let (sin, cos) = rotation_deg.to_radians().sin_cos();
    let rot = (cos as f32, sin as f32);
    let sources = Sources::new(env);
    let mut g = vec![0f32; n * 3 * n_l];
    let row = 3 * n_l;
    if let Some(half) = mirrored_half(input.frames) {
        let (front, back) = g.split_at_mut(half * row);
        front.par_chunks_mut(row).zip(back.par_chunks_mut(row)).enumerate().for_each_init(
            || Scratch::new(n_l, sources.len()),
            |s, (v, (fo, bo))| {
                let bits = [input.visibility.frame_bits(v), input.visibility.frame_bits(half + v)];
                if bits.iter().all(|b| occluded(b)) {
                    return; // no visible pixel: g stays 0, as every sum would be
                }
                s.run(input, &sources, &input.frames[v], bits, rot);
                s.write(0, fo);
                s.write(1, bo);
            },
        );
    } else {
        g.par_chunks_mut(row).enumerate().for_each_init(
            || Scratch::new(n_l, sources.len()),
            |s, (f, out)| {
                let bits = input.visibility.frame_bits(f);
                if occluded(bits) {
                    return;
                }
                s.run(input, &sources, &input.frames[f], [bits, &[]], rot);
                s.write(0, out);
            },
        );
    }
    Radiances { frames: n, lights: n_l, g }
}

/// Whether a frame sees nothing: fully occluded, or not computed (a vertex side the
/// camera never shows). Its sums are all zero, so the gather skips it.
fn occluded(bits: &[u64]) -> bool {
    bits.iter().all(|&w| w == 0)
}

/// `Some(V)` when the frames are `V` front sides followed by their mirrored back sides
/// (same origin and tangents, negated normal), as [`HemicubeFrame::of_mesh`] builds them.
fn mirrored_half(frames: &[HemicubeFrame]) -> Option<usize> {
    let half = frames.len() / 2;
    let mirrored = |f: &HemicubeFrame, b: &HemicubeFrame| {
        f.origin == b.origin
            && f.axes[0] == b.axes[0]
            && f.axes[1] == b.axes[1]
            && f.axes[2].map(|c| -c) == b.axes[2]
    };
    (half > 0
        && frames.len() == 2 * half
        && (0..half).all(|v| mirrored(&frames[v], &frames[half + v])))
    .then_some(half)
}

/// The environment's sources, directions as separate coordinate arrays (so the per-vertex
/// transform vectorises) and RGB power padded to four lanes.
struct Sources {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    power: Vec<[f32; 4]>,
}

impl Sources {
    fn new(env: &EnvCube) -> Sources {
        let coord = |a: usize| env.dirs.iter().map(|d| d[a]).collect();
        Sources {
            xs: coord(0),
            ys: coord(1),
            zs: coord(2),
            power: env.power.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect(),
        }
    }

    fn len(&self) -> usize {
        self.xs.len()
    }
}

/// Per-thread buffers of the gather: the pixel (and side) of every source, and the RGB
/// sums per light of the two sides.
struct Scratch {
    lights: usize,
    /// `pixel · 2 + side`, or `u32::MAX` for a source on the horizon.
    code: Vec<u32>,
    acc: Vec<[f32; 4]>,
}

/// The rotated tangent axes of a frame and what [`source_codes`] needs besides.
struct CodeInput<'a> {
    axes: [[f32; 3]; 3],
    res: usize,
    two_sided: bool,
    src: &'a Sources,
}

/// `pixel_of(res, x, y, ±z) · 2 + side` of every source, without branches so that it
/// vectorises: the same divisions and comparisons as [`pixel_of`], hence the same
/// pixel, with every case computed and the right one selected.
#[inline(always)]
fn codes_kernel(c: &CodeInput, out: &mut [u32]) {
    let [t, b, n] = c.axes;
    let res = c.res as f32;
    let half = (c.res / 2) as f32;
    let top = res * res;
    // `(a · n) as usize` of the reference for `a ≥ 0`, kept in floats (exact below 2²⁴) so
    // that the loop has no integer overflow checks and vectorises.
    let cell = |a: f32, n: f32| (a * n).floor().min(n - 1.0);
    let src = c.src;
    let it = out.iter_mut().zip(&src.xs).zip(&src.ys).zip(&src.zs);
    for (((code, &dx), &dy), &dz) in it {
        let zs = dx * n[0] + dy * n[1] + dz * n[2];
        let x = dx * t[0] + dy * t[1] + dz * t[2];
        let y = dx * b[0] + dy * b[1] + dz * b[2];
        let back = zs < 0.0;
        let z = if back { -zs } else { zs };
        let (ax, ay) = (x.abs(), y.abs());
        let is_top = z >= ax && z >= ay;
        let xf = ax >= ay;
        let m = if is_top {
            z
        } else if xf {
            ax
        } else {
            ay
        };
        let un = if is_top || !xf { x } else { y };
        let u = (un / m + 1.0) * 0.5;
        let v = (if is_top { y } else { z }) / m;
        let (v_top, v_side) = ((v + 1.0) * 0.5, v);
        let col = cell(u, res);
        let face = if xf { (x <= 0.0) as u32 as f32 } else { 2.0 + (y <= 0.0) as u32 as f32 };
        let p_top = cell(v_top, res) * res + col;
        let p_side = top + face * res * half + cell(v_side, half) * res + col;
        let p = if is_top { p_top } else { p_side };
        let keep = zs > 0.0 || (c.two_sided && back);
        let coded = 2.0 * p + back as u32 as f32;
        *code = if keep { coded as i32 as u32 } else { u32::MAX };
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn codes_avx2(c: &CodeInput, out: &mut [u32]) {
    codes_kernel(c, out);
}

/// [`codes_kernel`] with 8-lane vectors where the CPU has them.
#[allow(unsafe_code)]
fn source_codes(c: &CodeInput, out: &mut [u32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the kernel is plain safe code.
        unsafe { codes_avx2(c, out) };
        return;
    }
    codes_kernel(c, out);
}

impl Scratch {
    fn new(lights: usize, sources: usize) -> Scratch {
        Scratch { lights, code: vec![0; sources], acc: vec![[0.0; 4]; 2 * lights] }
    }

    /// Accumulates the sources of `frame` (side 0) and of its mirror (side 1, `bits[1]`
    /// non-empty) for the environment rotated by `(cos δ, sin δ)`.
    fn run(
        &mut self,
        input: &GatherInput,
        src: &Sources,
        frame: &HemicubeFrame,
        bits: [&[u64]; 2],
        rot: (f32, f32),
    ) {
        let c = CodeInput {
            axes: frame.axes.map(|a| rotate_z(a, rot.0, rot.1)),
            res: input.visibility.res as usize,
            two_sided: !bits[1].is_empty(),
            src,
        };
        source_codes(&c, &mut self.code);
        self.acc.fill([0.0; 4]);
        let n_l = self.lights;
        for (&code, pw) in self.code.iter().zip(&src.power) {
            if code == u32::MAX {
                continue;
            }
            let (p, side) = ((code >> 1) as usize, (code & 1) as usize);
            if bits[side][p / 64] >> (p % 64) & 1 == 0 {
                continue;
            }
            let (idx, h) = (input.table.index[p], input.table.interp[p]);
            let acc = &mut self.acc[side * n_l..(side + 1) * n_l];
            for k in 0..4 {
                let a = &mut acc[idx[k] as usize];
                *a = [
                    a[0] + h[k] * pw[0],
                    a[1] + h[k] * pw[1],
                    a[2] + h[k] * pw[2],
                    a[3] + h[k] * pw[3],
                ];
            }
        }
    }

    /// Writes side `side`'s sums as rows `(channel) × light`.
    fn write(&self, side: usize, out: &mut [f32]) {
        let n_l = self.lights;
        for (i, a) in self.acc[side * n_l..(side + 1) * n_l].iter().enumerate() {
            for ch in 0..3 {
                out[ch * n_l + i] = a[ch];
            }
        }
    }
}
