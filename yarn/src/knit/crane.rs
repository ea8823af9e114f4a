//! Keenan Crane's closed-form plain-knit yarn (keenancrane/plain-knit-yarn, MIT; DESIGN
//! §2.6): `γ(t) = (t + a sin 2t, h cos t, d cos 2t)` with `a = 3/2`, `h = 4`, `d = 1`, one
//! stitch per `2π` of t (the x extent of a stitch), courses offset by `h + 1/2` in y, tube
//! radius `R = 4/5`; all scaled by `scale` metres per unit ([`CraneKnit::for_yarn_radius`]
//! picks the scale that gives a tube radius r).
//!
//! Its speed `‖γ'(t)‖ = scale·√((1 + 2a cos 2t)² + h² sin²t + 4d² sin²2t)` is exact, so its
//! arc length by quadrature is a ground truth for our curve-length routine and for
//! Catmull–Rom fits of the curve ([`CraneKnit::yarn_set`]: control points at
//! `t_k = 2πk/N`, a periodic course per row, exactly periodic in x and y).

use crate::curve::{YarnCurve, YarnSet};
use crate::quad;
use crate::vec3::V3;
use crate::{Error, Result};
use std::f64::consts::TAU;

/// Crane's plain-knit curve (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CraneKnit {
    /// `a` (3/2).
    pub a: f64,
    /// `h` (4).
    pub h: f64,
    /// `d` (1).
    pub d: f64,
    /// Tube radius in curve units (4/5).
    pub tube: f64,
    /// Metres per curve unit.
    pub scale: f64,
}

impl CraneKnit {
    /// The published constants at `scale` metres per unit.
    pub fn new(scale: f64) -> Self {
        CraneKnit { a: 1.5, h: 4.0, d: 1.0, tube: 0.8, scale }
    }

    /// The scale whose tube radius is `yarn_radius` metres.
    pub fn for_yarn_radius(yarn_radius: f64) -> Self {
        Self::new(yarn_radius / 0.8)
    }

    /// Tube radius (metres).
    pub fn yarn_radius(&self) -> f64 {
        self.tube * self.scale
    }

    /// Wale spacing (metres): one stitch per `2π`.
    pub fn wale_spacing(&self) -> f64 {
        TAU * self.scale
    }

    /// Course spacing (metres): `h + 1/2`.
    pub fn course_spacing(&self) -> f64 {
        (self.h + 0.5) * self.scale
    }

    /// `γ(t)` of course `course` (metres).
    pub fn point(&self, t: f64, course: i64) -> V3 {
        let s = self.scale;
        [
            s * (t + self.a * (2.0 * t).sin()),
            s * (self.h * t.cos() + (self.h + 0.5) * course as f64),
            s * self.d * (2.0 * t).cos(),
        ]
    }

    /// `γ'(t)`.
    pub fn derivative(&self, t: f64) -> V3 {
        let s = self.scale;
        [
            s * (1.0 + 2.0 * self.a * (2.0 * t).cos()),
            -s * self.h * t.sin(),
            -2.0 * s * self.d * (2.0 * t).sin(),
        ]
    }

    /// The exact speed `‖γ'(t)‖`.
    pub fn speed(&self, t: f64) -> f64 {
        let (c2, s1, s2) = ((2.0 * t).cos(), t.sin(), (2.0 * t).sin());
        let x = 1.0 + 2.0 * self.a * c2;
        self.scale * (x * x + self.h * self.h * s1 * s1 + 4.0 * self.d * self.d * s2 * s2).sqrt()
    }

    /// Arc length on `[t0, t1]` by adaptive Gauss–Legendre quadrature of the exact speed.
    pub fn arc_length(&self, t0: f64, t1: f64) -> f64 {
        // Panels of a quarter stitch: the speed is smooth, the adaptive rule converges fast.
        let n = (((t1 - t0).abs() / (0.25 * TAU)).ceil() as usize).max(1);
        let h = (t1 - t0) / n as f64;
        (0..n)
            .map(|k| {
                let a = t0 + k as f64 * h;
                quad::adaptive(a, a + h, 1e-15 * self.scale, |t| self.speed(t))
            })
            .sum()
    }

    /// A periodic patch of `courses` courses of `stitches` stitches, each course a periodic
    /// Catmull–Rom curve through `samples_per_stitch` points per stitch.
    pub fn yarn_set(
        &self,
        stitches: usize,
        courses: usize,
        samples_per_stitch: usize,
    ) -> Result<YarnSet> {
        if stitches == 0 || courses == 0 || samples_per_stitch < 3 {
            return Err(Error::Invalid(format!(
                "Crane patch of {stitches} stitches × {courses} courses with {samples_per_stitch} samples per stitch \
                 (needs ≥ 1, ≥ 1, ≥ 3)"
            )));
        }
        let n = stitches * samples_per_stitch;
        let curves = (0..courses as i64)
            .map(|c| {
                let pts = (0..n)
                    .map(|k| self.point(TAU * k as f64 / samples_per_stitch as f64, c))
                    .collect();
                YarnCurve::periodic(pts, [stitches as f64 * self.wale_spacing(), 0.0, 0.0])
            })
            .collect::<Result<Vec<_>>>()?;
        YarnSet::new(
            curves,
            Some([stitches as f64 * self.wale_spacing(), courses as f64 * self.course_spacing()]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_length_routine_and_catmull_rom_fits_converge_to_cranes_length() {
        let k = CraneKnit::new(1.0);
        // An independent reference: composite Simpson with 2·10⁵ intervals per stitch.
        let n = 200_000;
        let h = TAU / n as f64;
        let simpson: f64 = (0..n)
            .map(|i| {
                let t = i as f64 * h;
                h / 6.0 * (k.speed(t) + 4.0 * k.speed(t + 0.5 * h) + k.speed(t + h))
            })
            .sum();
        let ours = k.arc_length(0.0, TAU);
        eprintln!("Crane stitch length: adaptive GL {ours:.12}, Simpson {simpson:.12}");
        assert!((ours / simpson - 1.0).abs() < 1e-10);
        // Our curve-length routine on the Catmull–Rom fit converges to it.
        let mut prev = f64::INFINITY;
        for spl in [8, 16, 32, 64, 128] {
            let set = k.yarn_set(2, 1, spl).unwrap();
            let len = set.curves[0].length_wrap / 2.0;
            let err = (len / ours - 1.0).abs();
            eprintln!(
                "Catmull-Rom fit, {spl:3} points per stitch: relative length error {err:.2e}"
            );
            assert!(err < prev, "not converging at {spl}");
            prev = err;
        }
        assert!(prev < 1e-6, "{prev}");
        // Periodic in x and y.
        let set = k.yarn_set(3, 2, 16).unwrap();
        let c = &set.curves[0];
        let shifted = crate::vec3::add(c.point(0.37), [3.0 * TAU, 0.0, 0.0]);
        assert!(crate::vec3::distance(shifted, c.point(48.37)) < 1e-12);
        assert_eq!(set.period, Some([3.0 * TAU, 9.0]));
    }
}
