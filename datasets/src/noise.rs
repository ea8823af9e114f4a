//! Deterministic randomness for the generators: a counter-based hash (SplitMix64 finaliser)
//! and periodic value noise / fractional Brownian motion on the unit torus.
//!
//! Everything is a pure function of `(seed, coordinates)`, so results never depend on the
//! thread schedule and textures tile seamlessly: noise of period `p` lattice cells wraps at
//! `u = 1`.

/// SplitMix64 finaliser: a well-mixed 64-bit hash of `x`.
pub fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Uniform value in `[0, 1)` from a seed and up to three integer coordinates.
pub fn hash01(seed: u64, a: i64, b: i64, c: i64) -> f64 {
    let h = mix64(seed ^ mix64(a as u64 ^ mix64(b as u64 ^ mix64(c as u64))));
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// A small sequential generator for parameter jitter (SplitMix64 stream).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A stream starting from `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(mix64(seed))
    }
    /// Next uniform value in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        (mix64(self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform value in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
    /// Approximately standard normal value (sum of four uniforms, rescaled).
    pub fn normal(&mut self) -> f64 {
        let s: f64 = (0..4).map(|_| self.next_f64()).sum();
        (s - 2.0) * 3f64.sqrt()
    }
}

fn smooth(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Periodic value noise in `[0, 1]` at `(u, v)` on the unit torus with `period` lattice
/// cells per unit (quintic interpolation, so the gradient is continuous).
pub fn value_noise(seed: u64, u: f64, v: f64, period: u32) -> f64 {
    let p = period.max(1) as i64;
    let (x, y) = (u * p as f64, v * p as f64);
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (smooth(x - x0), smooth(y - y0));
    let (ix, iy) = (x0 as i64, y0 as i64);
    let at = |i: i64, j: i64| hash01(seed, i.rem_euclid(p), j.rem_euclid(p), 0);
    let a = at(ix, iy) + (at(ix + 1, iy) - at(ix, iy)) * tx;
    let b = at(ix, iy + 1) + (at(ix + 1, iy + 1) - at(ix, iy + 1)) * tx;
    a + (b - a) * ty
}

/// Periodic fractional Brownian motion: `octaves` of [`value_noise`] with doubling
/// frequency and amplitude factor `gain`, normalised to `[0, 1]`.
pub fn fbm(seed: u64, u: f64, v: f64, base_period: u32, octaves: u32, gain: f64) -> f64 {
    let (mut sum, mut norm, mut amp) = (0.0, 0.0, 1.0);
    for o in 0..octaves {
        sum += amp * value_noise(mix64(seed.wrapping_add(o as u64)), u, v, base_period << o);
        norm += amp;
        amp *= gain;
    }
    if norm > 0.0 { sum / norm } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_periodic_bounded_and_seeded() {
        for &(u, v) in &[(0.1, 0.2), (0.77, 0.5), (0.0, 0.999)] {
            let a = fbm(7, u, v, 4, 5, 0.5);
            let b = fbm(7, u + 1.0, v - 1.0, 4, 5, 0.5);
            assert!((a - b).abs() < 1e-12, "{a} {b}");
            assert!((0.0..=1.0).contains(&a));
        }
        assert_ne!(value_noise(1, 0.3, 0.3, 4), value_noise(2, 0.3, 0.3, 4));
        let mut r = Rng::new(3);
        let mean: f64 = (0..10_000).map(|_| r.next_f64()).sum::<f64>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
    }
}
