//! Interpolation weights between measured directions ([S03 eq. 3] for the
//! light weights `τ_m`, [S03 eq. 5] for the view weights `ω_m`).
//!
//! "Four nearest" brackets `θ` between two rings (weight `t` to the outer one) and, on each
//! ring, `φ` between two neighbours (weight `s`, wrapping past 360°); the products give at
//! most four `(index, weight)` pairs. A one-direction ring (the pole) takes its whole ring
//! weight, so the weights stay continuous as `θ → 0` whatever `φ` does. Beyond the last ring
//! a view clamps to that ring; a light clamps as well and its weights are scaled by
//! `cos θ / cos θ_last`, reaching zero at the horizon. Below the horizon a light has no
//! weights at all. `Nearest` picks the ring nearest in `θ`, then the sample nearest in `φ`
//! (same clamping and fading).

use crate::direction::{Direction, wrap_phi_deg};
use crate::sampling::Sampling;
use serde::{Deserialize, Serialize};

/// How to turn a direction into measured samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum InterpMode {
    /// The single nearest sample.
    Nearest,
    /// The paper's bilinear "four nearest" interpolation.
    #[default]
    Four,
}

impl std::str::FromStr for InterpMode {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "nearest" => Ok(InterpMode::Nearest),
            "four" => Ok(InterpMode::Four),
            o => Err(crate::Error::Invalid(format!("unknown interpolation '{o}' (nearest|four)"))),
        }
    }
}

/// Up to four `(direction index, weight)` pairs. Weights are ≥ 0; they sum to 1 except for a
/// light beyond the last ring (sum = horizon fade) or below the horizon (empty).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Weights {
    entries: [(usize, f64); 4],
    len: usize,
}

impl Weights {
    fn push(&mut self, index: usize, weight: f64) {
        if weight <= 0.0 {
            return;
        }
        if let Some(e) = self.entries[..self.len].iter_mut().find(|e| e.0 == index) {
            e.1 += weight;
            return;
        }
        self.entries[self.len] = (index, weight);
        self.len += 1;
    }

    fn scale(&mut self, f: f64) {
        for e in &mut self.entries[..self.len] {
            e.1 *= f;
        }
        if f <= 0.0 {
            self.len = 0;
        }
    }

    /// The non-zero pairs.
    pub fn as_slice(&self) -> &[(usize, f64)] {
        &self.entries[..self.len]
    }

    /// Number of non-zero pairs.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no sample contributes (a light below the horizon).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Sum of the weights.
    pub fn sum(&self) -> f64 {
        self.as_slice().iter().map(|e| e.1).sum()
    }

    /// Weight of direction `index` (0 when absent).
    pub fn weight_of(&self, index: usize) -> f64 {
        self.as_slice().iter().filter(|e| e.0 == index).map(|e| e.1).sum()
    }

    /// Fixed-size form for GPU upload: indices and weights padded with `(0, 0.0)`.
    pub fn padded(&self) -> ([u32; 4], [f32; 4]) {
        let mut idx = [0u32; 4];
        let mut w = [0f32; 4];
        for (k, &(i, wt)) in self.as_slice().iter().enumerate() {
            idx[k] = i as u32;
            w[k] = wt as f32;
        }
        (idx, w)
    }
}

/// Rings bracketing `theta_deg`: `(inner, outer, t)` with weight `t` on the outer ring.
fn ring_bracket(s: &Sampling, theta_deg: f64) -> (usize, usize, f64) {
    let rings = &s.rings;
    let last = rings.len() - 1;
    if theta_deg <= rings[0].theta_deg {
        return (0, 0, 0.0);
    }
    if theta_deg >= rings[last].theta_deg {
        return (last, last, 0.0);
    }
    let r = rings.partition_point(|ring| ring.theta_deg <= theta_deg) - 1;
    let t = (theta_deg - rings[r].theta_deg) / (rings[r + 1].theta_deg - rings[r].theta_deg);
    (r, r + 1, t.clamp(0.0, 1.0))
}

/// The two neighbours of `phi_deg` on ring `r` with their weights.
fn ring_neighbours(s: &Sampling, r: usize, phi_deg: f64) -> [(usize, f64); 2] {
    let ring = &s.rings[r];
    let start = s.ring_start(r);
    if ring.count == 1 {
        return [(start, 1.0), (start, 0.0)];
    }
    let u = wrap_phi_deg(phi_deg - ring.phi_offset_deg) / s.ring_step_deg(r);
    let k = u.floor();
    let frac = (u - k).clamp(0.0, 1.0);
    let k = (k as usize) % ring.count;
    [(start + k, 1.0 - frac), (start + (k + 1) % ring.count, frac)]
}

impl Sampling {
    /// Weights of the measured directions for a view direction (clamped beyond the last
    /// ring, never faded).
    pub fn view_weights(&self, view: Direction, mode: InterpMode) -> Weights {
        self.weights(view, mode)
    }

    /// Weights of the measured directions for a light direction: faded by
    /// `cos θ / cos θ_last` beyond the last ring and empty at or below the horizon.
    pub fn light_weights(&self, light: Direction, mode: InterpMode) -> Weights {
        if light.theta_deg >= 90.0 || !light.theta_deg.is_finite() {
            return Weights::default();
        }
        let mut w = self.weights(light, mode);
        let last = self.rings[self.rings.len() - 1].theta_deg;
        if light.theta_deg > last {
            w.scale(light.cos_theta() / last.to_radians().cos());
        }
        w
    }

    fn weights(&self, d: Direction, mode: InterpMode) -> Weights {
        let mut w = Weights::default();
        let (r0, r1, t) = ring_bracket(self, d.theta_deg);
        match mode {
            InterpMode::Four => {
                for &(i, s) in &ring_neighbours(self, r0, d.phi_deg) {
                    w.push(i, (1.0 - t) * s);
                }
                if r1 != r0 {
                    for &(i, s) in &ring_neighbours(self, r1, d.phi_deg) {
                        w.push(i, t * s);
                    }
                }
            }
            InterpMode::Nearest => {
                let r = if t > 0.5 { r1 } else { r0 };
                w.push(self.nearest_on_ring(r, d.phi_deg), 1.0);
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l1(a: &Weights, b: &Weights, n: usize) -> f64 {
        (0..n).map(|i| (a.weight_of(i) - b.weight_of(i)).abs()).sum()
    }

    #[test]
    fn exact_at_every_sample_direction() {
        for name in crate::sampling::SAMPLING_NAMES {
            let s = Sampling::by_name(name).unwrap();
            for i in 0..s.len() {
                let w = s.view_weights(s.direction(i), InterpMode::Four);
                assert!((w.weight_of(i) - 1.0).abs() < 1e-12, "{name} {i}: {w:?}");
                let n = s.light_weights(s.direction(i), InterpMode::Nearest);
                assert_eq!(n.as_slice(), &[(i, 1.0)], "{name} {i}");
            }
        }
    }

    #[test]
    fn continuous_across_phi_wrap_pole_and_rings() {
        let s = Sampling::by_name("dome151").unwrap();
        let n = s.len();
        let eps = 1e-9;
        for &theta in &[5.0, 11.0, 20.0, 45.0, 60.0, 74.999, 80.0, 89.99] {
            let a = s.light_weights(Direction::new(theta, 360.0 - eps), InterpMode::Four);
            let b = s.light_weights(Direction::new(theta, 0.0), InterpMode::Four);
            assert!(l1(&a, &b, n) < 1e-6, "theta {theta}: {a:?} vs {b:?}");
        }
        // Near the pole every azimuth gives (almost) the pole sample.
        for phi in [0.0, 90.0, 271.0] {
            let w = s.view_weights(Direction::new(1e-9, phi), InterpMode::Four);
            assert!((w.weight_of(0) - 1.0).abs() < 1e-9);
        }
        // Across each ring boundary.
        for ring in &s.rings[1..] {
            let a = s.view_weights(Direction::new(ring.theta_deg - eps, 33.0), InterpMode::Four);
            let b = s.view_weights(Direction::new(ring.theta_deg + eps, 33.0), InterpMode::Four);
            assert!(l1(&a, &b, n) < 1e-6);
        }
    }

    #[test]
    fn light_fades_to_zero_at_horizon_and_vanishes_below() {
        let s = Sampling::ubo81();
        let at_last = s.light_weights(Direction::new(75.0, 10.0), InterpMode::Four);
        assert!((at_last.sum() - 1.0).abs() < 1e-12);
        let mid = s.light_weights(Direction::new(82.5, 10.0), InterpMode::Four);
        let expect = 82.5f64.to_radians().cos() / 75f64.to_radians().cos();
        assert!((mid.sum() - expect).abs() < 1e-12);
        let near = s.light_weights(Direction::new(90.0 - 1e-9, 10.0), InterpMode::Four);
        assert!(near.sum() < 1e-9);
        assert!(s.light_weights(Direction::new(90.0, 10.0), InterpMode::Four).is_empty());
        assert!(s.light_weights(Direction::new(120.0, 10.0), InterpMode::Nearest).is_empty());
        // Views clamp instead of fading.
        let v = s.view_weights(Direction::new(89.0, 10.0), InterpMode::Four);
        assert!((v.sum() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn at_most_four_pairs_summing_to_one() {
        let s = Sampling::ubo81();
        for k in 0..2000 {
            let theta = (k as f64 * 0.0451) % 75.0;
            let phi = (k as f64 * 7.77) % 360.0;
            let w = s.view_weights(Direction::new(theta, phi), InterpMode::Four);
            assert!(w.len() <= 4);
            assert!((w.sum() - 1.0).abs() < 1e-12);
            assert!(w.as_slice().iter().all(|e| e.1 > 0.0 && e.1 <= 1.0));
        }
    }

    proptest::proptest! {
        #[test]
        fn weights_are_lipschitz_continuous(theta in 0.0f64..89.9, phi in 0.0f64..360.0, dt in -1e-4f64..1e-4, dp in -1e-4f64..1e-4) {
            // A step of 1e-4 degrees may change the weights by at most a few 1e-4/Δ, where
            // Δ ≥ 6.5° is the smallest ring spacing in θ or φ in these samplings.
            for name in crate::sampling::SAMPLING_NAMES {
                let s = Sampling::by_name(name).unwrap();
                let a = s.light_weights(Direction::new(theta, phi), InterpMode::Four);
                let b = s.light_weights(Direction::new((theta + dt).max(0.0), phi + dp), InterpMode::Four);
                let d = l1(&a, &b, s.len());
                proptest::prop_assert!(d < 4.0 * 2e-4 / 6.0, "{name} {theta} {phi}: {d}");
                proptest::prop_assert!(a.sum() <= 1.0 + 1e-12);
            }
        }
    }
}
