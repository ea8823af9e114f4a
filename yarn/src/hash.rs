//! Deterministic random numbers from keys: every random quantity of the fiber generator,
//! the flame chart and the loop jitter is a pure function of a key tuple (seed, yarn, ply,
//! fiber, period, stream), never of a shared generator's state. So the output is identical
//! bit for bit whatever the number of rayon threads and whatever order work runs in, and a
//! periodic patch can ask for "the same period" by reducing its index.
//!
//! The mixer is SplitMix64's finaliser (Steele, Lea & Flood 2014), chained over the keys;
//! a [`KeyRng`] then steps a SplitMix64 sequence from that state.

/// SplitMix64's finaliser: a bijective 64-bit mixer.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// Hashes a key tuple into 64 bits (order matters; `[a, b] != [b, a]`).
pub fn hash_keys(keys: &[u64]) -> u64 {
    let mut h = 0x243f_6a88_85a3_08d3_u64; // π's fraction: a fixed, non-zero start
    for (i, &k) in keys.iter().enumerate() {
        h = mix64(h ^ mix64(k.wrapping_add(GOLDEN.wrapping_mul(i as u64 + 1))));
    }
    h
}

/// Hashes a byte string into 64 bits: [`hash_keys`] over its little-endian 8-byte words
/// (the last zero-padded) and its length (cache keys and checksums).
pub fn hash_bytes(bytes: &[u8]) -> u64 {
    let mut words: Vec<u64> = bytes
        .chunks(8)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..c.len()].copy_from_slice(c);
            u64::from_le_bytes(b)
        })
        .collect();
    words.push(bytes.len() as u64);
    hash_keys(&words)
}

/// A uniform number in `[0, 1)` from 64 bits (the top 53).
#[inline]
pub fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A small generator seeded by a key tuple: SplitMix64 steps from [`hash_keys`].
#[derive(Debug, Clone)]
pub struct KeyRng {
    state: u64,
}

impl KeyRng {
    /// The generator of one key tuple.
    pub fn new(keys: &[u64]) -> Self {
        KeyRng { state: hash_keys(keys) }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(self.state)
    }

    /// A uniform number in `[0, 1)`.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// Two uniform numbers.
    #[inline]
    pub fn uniform2(&mut self) -> [f64; 2] {
        [self.uniform(), self.uniform()]
    }

    /// Three uniform numbers.
    #[inline]
    pub fn uniform3(&mut self) -> [f64; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }

    /// A standard normal number (Box–Muller, the cosine branch; `1 − u` keeps the
    /// logarithm finite).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniforms_have_the_moments_of_u01_and_keys_are_ordered() {
        let mut r = KeyRng::new(&[7, 1, 2]);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            s1 += u;
            s2 += u * u;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        // Standard error of the mean: sqrt(1/12/n) = 6.5e-4; allow 5 of them.
        assert!((mean - 0.5).abs() < 3.3e-3, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 2e-3, "var {var}");
        assert_ne!(hash_keys(&[1, 2]), hash_keys(&[2, 1]));
        assert_ne!(hash_keys(&[0]), hash_keys(&[0, 0]));
        let mut g = KeyRng::new(&[3]);
        let m: f64 = (0..100_000).map(|_| g.normal()).sum::<f64>() / 1e5;
        assert!(m.abs() < 0.016, "normal mean {m}");
    }
}
