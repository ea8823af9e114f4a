//! Yarn centre curves: `YarnCurve` is a uniform Catmull–Rom spline (cardinal, tension 0 —
//! the BCC `C0` type of [W19 §5] and the spline of [C03 §3] with DESIGN §1.3 item 5's
//! choice) with, per control point, a **length coordinate** fixed at rest ([W19 §5]: it is
//! not updated when the curve deforms), a colour, a yarn-params id and optionally the
//! stitch-surface normal that anchors the frame ([`crate::frame`]). `YarnSet` is a list of
//! curves and an optional period `[px, py]` for periodic patches.
//!
//! **Parametrisation.** Segment `i` joins control points `P_i` and `P_{i+1}`; the global
//! parameter is `u ∈ [0, segments]`. An open curve of `n` points has `n − 1` segments and
//! interpolates every point; its end tangents use phantom points extrapolated linearly
//! (`P_{−1} = 2P_0 − P_1`, `P_n = 2P_{n−1} − P_{n−2}`), a choice of ours (the papers are
//! silent). A closed curve of `n ≥ 3` points has `n` segments and wraps: `P_{i+n} = P_i +
//! shift`. A zero `shift` is an ordinary loop; a non-zero one makes the curve a periodic
//! course of a patch (one period of control points; the curve continues into the next
//! period translated by `shift`, and its length coordinate by `length_wrap`). Length
//! coordinates are interpolated with the same Catmull–Rom basis, which reproduces a
//! linear sequence exactly, so on uniformly spaced points z(u) is exact arc length.
//!
//! **Hard cases (DESIGN §4.4).** Coincident and zero-length control points are allowed:
//! where the derivative vanishes the tangent falls back to the second derivative, then to
//! the chord towards the next distinct control point (then the previous one). A curve
//! whose points all coincide has no direction and is refused, as are open curves of fewer
//! than two and closed curves of fewer than three points. A closed curve of three points
//! is an ordinary smooth loop. Non-finite values are refused naming the curve and point.

mod basis;
mod length;
mod set;

pub(crate) use basis::combine;
pub use basis::{basis, basis_d1, basis_d2};
pub use set::YarnSet;

use crate::vec3::{self, V3};
use crate::{Error, Result};

/// The default yarn colour (linear RGB).
pub const DEFAULT_COLOR: [f32; 3] = [0.8, 0.8, 0.8];

/// A uniform Catmull–Rom yarn centre curve (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct YarnCurve {
    /// Control points (metres).
    pub points: Vec<V3>,
    /// Length coordinate per control point (metres), non-decreasing, fixed at rest.
    pub length_coords: Vec<f64>,
    /// Colour per control point (linear RGB).
    pub colors: Vec<[f32; 3]>,
    /// Yarn-params id per control point (an index into the caller's `[YarnParams]`).
    pub params_ids: Vec<u32>,
    /// Optional stitch-surface normal per control point (frame anchoring).
    pub normals: Option<Vec<V3>>,
    /// Closed (wrapping) curve.
    pub closed: bool,
    /// Translation of one wrap of a closed curve (zero for a loop; a lattice vector for a
    /// periodic course).
    pub shift: V3,
    /// Length-coordinate increment of one wrap of a closed curve.
    pub length_wrap: f64,
}

impl YarnCurve {
    /// An open curve through `points`, default colour and params id 0, length
    /// coordinates set to the rest arc length.
    pub fn open(points: Vec<V3>) -> Result<Self> {
        Self::build(points, false, [0.0; 3])
    }

    /// A closed loop through `points` (at least three).
    pub fn closed(points: Vec<V3>) -> Result<Self> {
        Self::build(points, true, [0.0; 3])
    }

    /// One period of a periodic course: closed with `P_{i+n} = P_i + shift`.
    pub fn periodic(points: Vec<V3>, shift: V3) -> Result<Self> {
        Self::build(points, true, shift)
    }

    fn build(points: Vec<V3>, closed: bool, shift: V3) -> Result<Self> {
        let n = points.len();
        let mut c = YarnCurve {
            points,
            length_coords: vec![0.0; n],
            colors: vec![DEFAULT_COLOR; n],
            params_ids: vec![0; n],
            normals: None,
            closed,
            shift,
            length_wrap: 0.0,
        };
        c.validate(0).map_err(strip_index)?;
        c.set_rest_length_coords();
        Ok(c)
    }

    /// Sets the surface normals (one per control point, finite, non-zero).
    pub fn with_normals(mut self, normals: Vec<V3>) -> Result<Self> {
        self.normals = Some(normals);
        self.validate(0).map_err(strip_index)?;
        Ok(self)
    }

    /// Sets one colour for every control point.
    pub fn with_color(mut self, color: [f32; 3]) -> Self {
        self.colors = vec![color; self.points.len()];
        self
    }

    /// Sets one yarn-params id for every control point.
    pub fn with_params_id(mut self, id: u32) -> Self {
        self.params_ids = vec![id; self.points.len()];
        self
    }

    /// Checks counts, lengths and finiteness; `index` names the curve in messages.
    pub fn validate(&self, index: usize) -> Result<()> {
        let n = self.points.len();
        let kind = if self.closed { "closed" } else { "open" };
        let min = if self.closed { 3 } else { 2 };
        if n < min {
            return Err(Error::Invalid(format!(
                "curve {index}: {kind} curve with {n} control points (needs at least {min})"
            )));
        }
        let same = |what: &str, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(Error::Invalid(format!("curve {index}: {len} {what} for {n} control points")))
            }
        };
        same("length coordinates", self.length_coords.len())?;
        same("colours", self.colors.len())?;
        same("params ids", self.params_ids.len())?;
        for (i, p) in self.points.iter().enumerate() {
            if !vec3::is_finite(*p) {
                return Err(Error::Invalid(format!(
                    "curve {index}, control point {i}: non-finite position {p:?}"
                )));
            }
        }
        if let Some(normals) = &self.normals {
            same("normals", normals.len())?;
            for (i, nrm) in normals.iter().enumerate() {
                if vec3::normalize(*nrm).is_none() {
                    return Err(Error::Invalid(format!(
                        "curve {index}, control point {i}: normal {nrm:?} has no direction"
                    )));
                }
            }
        }
        for (i, w) in self.length_coords.windows(2).enumerate() {
            if !(w[0].is_finite() && w[1].is_finite() && w[1] >= w[0]) {
                return Err(Error::Invalid(format!(
                    "curve {index}, control point {}: length coordinate {} after {} \
                     (must be finite and non-decreasing)",
                    i + 1,
                    w[1],
                    w[0]
                )));
            }
        }
        if !(vec3::is_finite(self.shift) && self.length_wrap.is_finite()) {
            return Err(Error::Invalid(format!("curve {index}: non-finite shift or length wrap")));
        }
        let p0 = self.points[0];
        if self.points.iter().all(|&p| p == p0) && self.shift == [0.0; 3] {
            return Err(Error::Invalid(format!(
                "curve {index}: all {n} control points coincide (a curve of zero length has \
                 no direction)"
            )));
        }
        Ok(())
    }

    /// Number of segments (`n − 1` open, `n` closed).
    pub fn segment_count(&self) -> usize {
        if self.closed { self.points.len() } else { self.points.len() - 1 }
    }

    /// The control point of (virtual) index `k`: wrapped with `shift` on closed curves,
    /// linearly extrapolated phantoms beyond the ends of open ones.
    pub fn control_point(&self, k: isize) -> V3 {
        let n = self.points.len() as isize;
        if self.closed {
            let wraps = k.div_euclid(n);
            vec3::add_scaled(self.points[k.rem_euclid(n) as usize], self.shift, wraps as f64)
        } else if k < 0 {
            let (a, b) = (self.points[0], self.points[1]);
            vec3::add_scaled(a, vec3::sub(a, b), (-k) as f64)
        } else if k >= n {
            let (a, b) = (self.points[n as usize - 1], self.points[n as usize - 2]);
            vec3::add_scaled(a, vec3::sub(a, b), (k - n + 1) as f64)
        } else {
            self.points[k as usize]
        }
    }

    /// The length coordinate of (virtual) control point `k` (wrapped or extrapolated as
    /// [`Self::control_point`]).
    pub fn length_coord_at(&self, k: isize) -> f64 {
        let n = self.points.len() as isize;
        let z = &self.length_coords;
        if self.closed {
            z[k.rem_euclid(n) as usize] + self.length_wrap * k.div_euclid(n) as f64
        } else if k < 0 {
            z[0] + (z[0] - z[1]) * (-k) as f64
        } else if k >= n {
            let (a, b) = (z[n as usize - 1], z[n as usize - 2]);
            a + (a - b) * (k - n + 1) as f64
        } else {
            z[k as usize]
        }
    }

    /// Splits `u` into `(segment, t ∈ [0, 1])`; closed curves wrap (any `u`), open ones
    /// clamp to `[0, segments]`.
    pub fn locate(&self, u: f64) -> (isize, f64) {
        let m = self.segment_count() as f64;
        if self.closed {
            let s = u.floor();
            (s as isize, u - s)
        } else {
            let u = u.clamp(0.0, m);
            let s = u.floor().min(m - 1.0);
            (s as isize, u - s)
        }
    }

    fn window(&self, seg: isize) -> [V3; 4] {
        [-1, 0, 1, 2].map(|d| self.control_point(seg + d))
    }

    /// The curve point at `u`.
    pub fn point(&self, u: f64) -> V3 {
        let (s, t) = self.locate(u);
        let w = basis(t);
        combine(&self.window(s), w)
    }

    /// `dC/du` at `u` (analytic).
    pub fn derivative(&self, u: f64) -> V3 {
        let (s, t) = self.locate(u);
        combine(&self.window(s), basis_d1(t))
    }

    /// `d²C/du²` at `u` (analytic).
    pub fn second_derivative(&self, u: f64) -> V3 {
        let (s, t) = self.locate(u);
        combine(&self.window(s), basis_d2(t))
    }

    /// The point of segment `seg` (virtual index on closed curves) at local `t ∈ [0, 1]`
    /// (so the two segments meeting at a control point can both be asked there).
    pub fn segment_point(&self, seg: isize, t: f64) -> V3 {
        combine(&self.window(seg), basis(t))
    }

    /// `dC/du` of segment `seg` at local `t`.
    pub fn segment_derivative(&self, seg: isize, t: f64) -> V3 {
        combine(&self.window(seg), basis_d1(t))
    }

    /// The length coordinate z(u) (Catmull–Rom of the per-point values).
    pub fn length_coord(&self, u: f64) -> f64 {
        let (s, t) = self.locate(u);
        let b = basis(t);
        (0..4).map(|j| b[j] * self.length_coord_at(s - 1 + j as isize)).sum()
    }

    /// `dz/du` at `u`.
    pub fn length_coord_derivative(&self, u: f64) -> f64 {
        let (s, t) = self.locate(u);
        let b = basis_d1(t);
        (0..4).map(|j| b[j] * self.length_coord_at(s - 1 + j as isize)).sum()
    }

    /// The interpolated surface normal at `u` (unit), if the curve has normals.
    pub fn surface_normal(&self, u: f64) -> Option<V3> {
        let normals = self.normals.as_ref()?;
        let n = normals.len() as isize;
        let (s, t) = self.locate(u);
        let idx = |k: isize| -> V3 {
            if self.closed {
                normals[k.rem_euclid(n) as usize]
            } else {
                normals[k.clamp(0, n - 1) as usize]
            }
        };
        let w = [-1, 0, 1, 2].map(|d| vec3::normalize_or(idx(s + d), [0.0, 0.0, 1.0]));
        vec3::normalize(combine(&w, basis(t))).or_else(|| vec3::normalize(idx(s)))
    }

    /// The unit tangent at `u` with the fallbacks of the module documentation.
    pub fn tangent(&self, u: f64) -> V3 {
        let scale = self.scale();
        let d = self.derivative(u);
        if vec3::length(d) > 1e-9 * scale {
            return vec3::normalize_or(d, [1.0, 0.0, 0.0]);
        }
        let d2 = self.second_derivative(u);
        if vec3::length(d2) > 1e-9 * scale {
            // Near a cusp the derivative points along ±C''; take the side the curve moves
            // to (after the cusp for t below it, C' ≈ (t − t₀)·C'').
            return vec3::normalize_or(d2, [1.0, 0.0, 0.0]);
        }
        self.chord_direction(u)
    }

    /// The direction from the control point at or before `u` to the next distinct one
    /// (or from the previous distinct one), for segments of zero length.
    fn chord_direction(&self, u: f64) -> V3 {
        let (s, _) = self.locate(u);
        let here = self.control_point(s);
        let n = self.points.len() as isize;
        for k in 1..=n + 1 {
            if let Some(d) = vec3::normalize(vec3::sub(self.control_point(s + k), here)) {
                return d;
            }
        }
        for k in 1..=n + 1 {
            if let Some(d) = vec3::normalize(vec3::sub(here, self.control_point(s - k))) {
                return d;
            }
        }
        [1.0, 0.0, 0.0]
    }

    /// A length scale of the curve (largest control-point extent, or 1 m).
    pub fn scale(&self) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.points {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let e = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max).max(vec3::length(self.shift));
        if e > 0.0 { e } else { 1.0 }
    }

    /// Points of the curve at `per_segment` uniform parameter steps per segment, ending at
    /// `u = segments` (for closed curves the last point is the first plus `shift`).
    pub fn sample_polyline(&self, per_segment: usize) -> Vec<V3> {
        let k = per_segment.max(1);
        let m = self.segment_count();
        (0..=m * k).map(|j| self.point(j as f64 / k as f64)).collect()
    }
}

fn strip_index(e: Error) -> Error {
    match e {
        Error::Invalid(m) => Error::Invalid(m.replacen("curve 0: ", "curve: ", 1).replacen(
            "curve 0, ",
            "curve, ",
            1,
        )),
        other => other,
    }
}

#[cfg(test)]
mod tests;
