//! Frames along a yarn curve: `T` is the unit tangent (analytic derivative of the
//! Catmull–Rom curve), `N` is the stitch-surface normal made perpendicular to `T`, and
//! `B = T × N` (DESIGN §0 and §2.3 item 9: [W19 §3.1] hangs every fiber phase on `N̂` but
//! never defines it; a frame that flips or drifts makes fibers crawl).
//!
//! **Fallback.** Where the surface normal is nearly parallel to the tangent
//! (`|n·T| > 0.95`, DESIGN's threshold) or where a curve has no normals (BCC files), `N` is
//! carried along by the rotation-minimising frame of the double-reflection method (Wang,
//! Jüttler, Zheng & Liu 2008). Switching between the two outright would make `N` jump, so we
//! blend, which DESIGN does not say: between `|n·T| = 0.9` and `0.95` the carried `N` is
//! rotated about `T` towards the projected normal by a smoothstep fraction of the angle
//! between them. The frame is therefore continuous everywhere; in the anchored region it
//! is exactly the projected normal.
//!
//! **Closed and periodic curves.** Propagation starts at a fully anchored sample when one
//! exists, so the frame returns to itself after one period. A closed curve with no anchor
//! at all (a BCC loop) would come back rotated by the frame's holonomy angle; that angle is
//! spread linearly over the period so the frame closes, as is usual for rotation-minimising
//! frames of closed curves. An open curve without normals starts from world `+z` made
//! perpendicular to `T` (z-up world; `+x` if `T` is within 18° of `z`).
//!
//! The frame is tabulated at `samples_per_segment` parameter steps and, between samples,
//! carried from the sample before by the same double reflection, so [`CurveFrames::frame_at`]
//! is continuous in `u` and reproduces the table at the samples.

use crate::curve::YarnCurve;
use crate::vec3::{self, V3};

/// An orthonormal frame: tangent `t`, normal `n`, binormal `b = t × n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit tangent.
    pub t: V3,
    /// Unit normal (⟂ t).
    pub n: V3,
    /// Unit binormal `t × n`.
    pub b: V3,
}

impl Frame {
    /// The frame of tangent `t` and a normal `n` already perpendicular to it.
    pub fn new(t: V3, n: V3) -> Self {
        Frame { t, n, b: vec3::cross(t, n) }
    }
}

/// Where anchoring starts to give way to the carried frame.
pub const ANCHOR_FULL: f64 = 0.9;
/// Where the carried (rotation-minimising) frame takes over entirely (DESIGN §0).
pub const ANCHOR_NONE: f64 = 0.95;

/// The weight of the surface normal: 1 for `|n·T| ≤ 0.9`, 0 from 0.95, smoothstep between.
pub fn anchor_weight(n_dot_t: f64) -> f64 {
    let x = ((ANCHOR_NONE - n_dot_t.abs()) / (ANCHOR_NONE - ANCHOR_FULL)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Carries the normal `r0` of the frame at `(x0, t0)` to `(x1, t1)` by two reflections
/// (rotation-minimising to second order), then re-orthogonalises it to `t1`.
pub fn double_reflection(x0: V3, t0: V3, r0: V3, x1: V3, t1: V3) -> V3 {
    let v1 = vec3::sub(x1, x0);
    let c1 = vec3::dot(v1, v1);
    let (rl, tl) = if c1 > 0.0 {
        (
            vec3::add_scaled(r0, v1, -2.0 / c1 * vec3::dot(v1, r0)),
            vec3::add_scaled(t0, v1, -2.0 / c1 * vec3::dot(v1, t0)),
        )
    } else {
        (r0, t0)
    };
    let v2 = vec3::sub(t1, tl);
    let c2 = vec3::dot(v2, v2);
    let r1 = if c2 > 0.0 { vec3::add_scaled(rl, v2, -2.0 / c2 * vec3::dot(v2, rl)) } else { rl };
    vec3::normalize(vec3::reject(r1, t1)).unwrap_or_else(|| vec3::any_perpendicular(t1))
}

/// The output normal for a carried normal `r` (the rotation-minimising state, never itself
/// pulled towards the surface) at tangent `t` with surface normal `s`: `r` rotated about
/// `t` towards the projected normal by `anchor_weight(s·t)` of the angle between them.
/// Where anchoring is full the carried state restarts from the projected normal. The
/// angle is unwrapped against the previous sample's `theta_ref` (the projected normal
/// flips by π where the tangent passes through the normal; unwrapping turns that into a
/// continuous rotation across the blend band, never a jump between ±π). Returns the output
/// normal, the unwrapped angle and the carried state to continue from.
fn anchor(r: V3, t: V3, s: Option<V3>, theta_ref: f64) -> (V3, f64, V3) {
    let Some(s) = s else { return (r, theta_ref, r) };
    let Some(target) = vec3::normalize(vec3::reject(s, t)) else { return (r, theta_ref, r) };
    let w = anchor_weight(vec3::dot(s, t));
    if w >= 1.0 {
        // Fully anchored: the output is the projected normal and the carried state restarts
        // from it.
        return (target, 0.0, target);
    }
    let raw = vec3::signed_angle(r, target, t);
    let tau = std::f64::consts::TAU;
    let theta = raw + tau * ((theta_ref - raw) / tau).round();
    let n = if w <= 0.0 { r } else { vec3::normalize_or(vec3::rotate(r, t, w * theta), target) };
    (n, theta, r)
}

/// A read-only view of [`CurveFrames`]' table: samples `k = 0..=M` at `u_k =
/// k/samples_per_segment`.
#[derive(Debug, Clone, Copy)]
pub struct FrameTable<'a> {
    /// Table steps per curve segment.
    pub samples_per_segment: usize,
    /// The curve is closed (the table covers one period).
    pub closed: bool,
    /// Holonomy angle spread over a closed curve with no anchor (0 otherwise).
    pub holonomy: f64,
    /// Curve points at the samples.
    pub x: &'a [V3],
    /// Frames at the samples.
    pub frames: &'a [Frame],
    /// Unwrapped anchoring angle at the samples.
    pub theta: &'a [f64],
    /// Carried rotation-minimising normal at the samples.
    pub carry: &'a [V3],
}

/// The tabulated frames of one curve.
#[derive(Debug, Clone)]
pub struct CurveFrames {
    samples_per_segment: usize,
    closed: bool,
    /// Samples of one period: `M = segments · samples_per_segment`.
    m: usize,
    /// Holonomy angle spread over a closed curve with no anchor (0 otherwise).
    holonomy: f64,
    /// Positions at the samples `u_k = k/samples_per_segment`, `k = 0..=M`.
    x: Vec<V3>,
    /// Frames at the samples (holonomy correction included), `k = 0..=M`.
    frames: Vec<Frame>,
    /// Unwrapped anchoring angle at the samples (see `anchor`).
    theta: Vec<f64>,
    /// Carried rotation-minimising normal at the samples (see `anchor`).
    carry: Vec<V3>,
}

impl CurveFrames {
    /// Builds the frames of `curve` with `samples_per_segment ≥ 1` table steps per segment.
    pub fn new(curve: &YarnCurve, samples_per_segment: usize) -> Self {
        let sps = samples_per_segment.max(1);
        let m = curve.segment_count() * sps;
        let u = |k: usize| k as f64 / sps as f64;
        let x: Vec<V3> = (0..=m).map(|k| curve.point(u(k))).collect();
        let t: Vec<V3> = (0..=m).map(|k| curve.tangent(u(k))).collect();
        let s: Vec<Option<V3>> = (0..=m).map(|k| curve.surface_normal(u(k))).collect();
        let full = |k: usize| s[k].is_some_and(|n| anchor_weight(vec3::dot(n, t[k])) >= 1.0);
        let start = if curve.closed { (0..m).find(|&k| full(k)).unwrap_or(0) } else { 0 };
        let (r0, theta0) = match s[start] {
            Some(n) if full(start) => {
                (vec3::normalize_or(vec3::reject(n, t[start]), [0.0; 3]), 0.0)
            }
            _ => {
                let (_, th, carry) =
                    anchor(vec3::any_perpendicular(t[start]), t[start], s[start], 0.0);
                (carry, th)
            }
        };
        // Carried (rotation-minimising) state, output normal and unwrapped angle per sample.
        let mut carry = vec![[0.0; 3]; m + 1];
        let mut r = vec![[0.0; 3]; m + 1];
        let mut theta = vec![0.0; m + 1];
        carry[start] = r0;
        r[start] = anchor(r0, t[start], s[start], theta0).0;
        theta[start] = theta0;
        let steps = if curve.closed { m } else { m - start };
        // Walk j = 1..=steps from `start`; on closed curves index k wraps through M ≡ 0.
        let pos = |j: usize| curve.point(u(start + j));
        let mut prev = (pos(0), t[start], r0, theta0);
        let mut end = r0;
        for j in 1..=steps {
            let k = if curve.closed { (start + j) % m } else { start + j };
            let xk = pos(j);
            let carried = double_reflection(prev.0, prev.1, prev.2, xk, t[k]);
            let (rk, th, state) = anchor(carried, t[k], s[k], prev.3);
            if curve.closed && j == steps {
                end = rk;
            } else {
                r[k] = rk;
                theta[k] = th;
                carry[k] = state;
            }
            prev = (xk, t[k], state, th);
        }
        let holonomy =
            if curve.closed && !full(start) { vec3::signed_angle(end, r0, t[start]) } else { 0.0 };
        let mut frames: Vec<Frame> = Vec::with_capacity(m + 1);
        for k in 0..=m {
            let kk = if curve.closed { k % m } else { k };
            let j = if curve.closed { (kk + m - start) % m } else { k };
            let rot = if holonomy != 0.0 { holonomy * j as f64 / m as f64 } else { 0.0 };
            let n = if rot != 0.0 { vec3::rotate(r[kk], t[kk], rot) } else { r[kk] };
            frames.push(Frame::new(t[kk], n));
        }
        let wrap = |k: usize| if curve.closed { k % m } else { k };
        let theta = (0..=m).map(|k| theta[wrap(k)]).collect();
        let carry = (0..=m)
            .map(|k| {
                let j = if curve.closed { (wrap(k) + m - start) % m } else { k };
                let rot = holonomy * j as f64 / m as f64;
                if rot != 0.0 {
                    vec3::rotate(carry[wrap(k)], t[wrap(k)], rot)
                } else {
                    carry[wrap(k)]
                }
            })
            .collect();
        CurveFrames {
            samples_per_segment: sps,
            closed: curve.closed,
            m,
            holonomy,
            x,
            frames,
            theta,
            carry,
        }
    }

    /// The table behind [`Self::frame_at`], for renderers that evaluate frames themselves
    /// (the GPU fiber passes of `yarn-render` upload it and repeat `frame_at` in WGSL).
    pub fn table(&self) -> FrameTable<'_> {
        FrameTable {
            samples_per_segment: self.samples_per_segment,
            closed: self.closed,
            holonomy: self.holonomy,
            x: &self.x,
            frames: &self.frames,
            theta: &self.theta,
            carry: &self.carry,
        }
    }

    /// The frame at parameter `u` (closed curves wrap).
    pub fn frame_at(&self, curve: &YarnCurve, u: f64) -> Frame {
        let sps = self.samples_per_segment as f64;
        let m = self.m as f64;
        // The frame depends only on the parameter within the base period.
        let uu = if self.closed {
            let w = (u * sps / m).floor();
            (u - w * m / sps).clamp(0.0, m / sps)
        } else {
            u.clamp(0.0, m / sps)
        };
        let pos = uu * sps;
        let k = (pos.floor() as usize).min(self.m.saturating_sub(1));
        let frac = pos - k as f64;
        if frac == 0.0 {
            return self.frames[k];
        }
        let t = curve.tangent(uu);
        let f0 = &self.frames[k];
        let carried = double_reflection(self.x[k], f0.t, self.carry[k], curve.point(uu), t);
        let (mut n, _, _) = anchor(carried, t, curve.surface_normal(uu), self.theta[k]);
        if self.holonomy != 0.0 {
            n = vec3::rotate(n, t, self.holonomy * frac / m);
        }
        Frame::new(t, n)
    }
}

#[cfg(test)]
mod tests;
