//! Counter-based random numbers: every sample of every pixel has its own stream, seeded by
//! a hash of `(seed, pixel, sample)`, so an image has identical bits for any thread count
//! and any pixel order (the same key hashing as `yarn::hash`).

/// A stream of uniform numbers for one key tuple: the generator of `yarn::hash` (SplitMix64
/// steps from the hashed key), so fibers and light paths share one random-number rule.
pub type Rng = yarn::hash::KeyRng;

#[cfg(test)]
mod tests {
    use super::Rng;

    #[test]
    fn streams_are_reproducible_and_uniform() {
        let mut a = Rng::new(&[1, 2, 3]);
        let mut b = Rng::new(&[1, 2, 3]);
        let xs: Vec<f64> = (0..10_000).map(|_| a.uniform()).collect();
        assert!(xs.iter().all(|&x| x == b.uniform() && (0.0..1.0).contains(&x)));
        // Mean of 10⁴ uniforms: 0.5 ± 4·(1/√12)/100.
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((m - 0.5).abs() < 4.0 * 0.2887 / 100.0, "{m}");
        assert_ne!(Rng::new(&[1, 2, 4]).uniform(), Rng::new(&[1, 2, 3]).uniform());
    }
}
