//! Ring samplings of the hemisphere: the measured view and light directions.
//!
//! A sampling is a list of rings `{θ, count, φ offset}`; direction `k` of ring `r` lies at
//! `φ = offset + k · 360° / count`. Directions are numbered ring by ring from the pole
//! outwards and, within a ring, by increasing `φ` from the ring's offset (DESIGN.md §3).
//! The classic Bonn samplings are the H1/H2 sets of Sattler et al. 2003, Table 1, and the
//! 151-direction dome of UBO2014.

use crate::direction::{Direction, wrap_phi_deg};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// One ring of directions at a common polar angle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ring {
    /// Polar angle of the ring, degrees.
    pub theta_deg: f64,
    /// Number of directions on the ring (1 for the pole).
    pub count: usize,
    /// Azimuth of the ring's first direction, degrees.
    pub phi_offset_deg: f64,
}

/// A named list of rings, with the flat numbering of its directions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sampling {
    /// Name (`ubo81`, `ubo81-h1`, `dome151` or `custom`).
    pub name: String,
    /// Rings ordered by increasing θ.
    pub rings: Vec<Ring>,
    #[serde(skip)]
    ring_start: Vec<usize>,
}

/// The names [`Sampling::by_name`] knows.
pub const SAMPLING_NAMES: [&str; 3] = ["ubo81", "ubo81-h1", "dome151"];

impl Sampling {
    /// Builds a sampling from rings, checking that it is usable: θ strictly increasing in
    /// `[0, 90)`, counts ≥ 1, a ring at θ = 0 has exactly one direction.
    pub fn new(name: impl Into<String>, rings: Vec<Ring>) -> Result<Self> {
        if rings.is_empty() {
            return Err(Error::Invalid("a sampling needs at least one ring".into()));
        }
        for (r, ring) in rings.iter().enumerate() {
            if !(ring.theta_deg.is_finite() && (0.0..90.0).contains(&ring.theta_deg)) {
                return Err(Error::Invalid(format!(
                    "ring {r}: theta {} deg is outside [0, 90)",
                    ring.theta_deg
                )));
            }
            if ring.count == 0 || ring.count > 100_000 {
                return Err(Error::Invalid(format!(
                    "ring {r}: count {} is not in 1..=100000",
                    ring.count
                )));
            }
            if ring.theta_deg == 0.0 && ring.count != 1 {
                return Err(Error::Invalid(format!("ring {r}: the pole ring must have count 1")));
            }
            if !ring.phi_offset_deg.is_finite() {
                return Err(Error::Invalid(format!("ring {r}: phi offset is not finite")));
            }
            if r > 0 && ring.theta_deg <= rings[r - 1].theta_deg {
                return Err(Error::Invalid(format!(
                    "ring {r}: theta must increase from ring to ring"
                )));
            }
        }
        let mut s = Sampling { name: name.into(), rings, ring_start: Vec::new() };
        s.index_rings();
        Ok(s)
    }

    fn index_rings(&mut self) {
        self.ring_start.clear();
        let mut start = 0;
        for ring in &self.rings {
            self.ring_start.push(start);
            start += ring.count;
        }
        self.ring_start.push(start);
    }

    /// Restores the internal index after deserialisation (serde skips it).
    pub fn validated(self) -> Result<Self> {
        Sampling::new(self.name, self.rings)
    }

    /// One of the built-in samplings by name.
    pub fn by_name(name: &str) -> Result<Self> {
        let ring = |theta_deg: f64, count: usize, phi_offset_deg: f64| Ring {
            theta_deg,
            count,
            phi_offset_deg,
        };
        let counts = [1usize, 6, 12, 18, 20, 24];
        let rings: Vec<Ring> = match name {
            "ubo81" => [0.0, 15.0, 30.0, 45.0, 60.0, 75.0]
                .iter()
                .zip(counts)
                .map(|(&t, c)| ring(t, c, 0.0))
                .collect(),
            "ubo81-h1" => [0.0, 17.0, 34.0, 51.0, 68.0, 85.0]
                .iter()
                .zip(counts)
                .map(|(&t, c)| ring(t, c, 0.0))
                .collect(),
            "dome151" => {
                let thetas = [0.0, 11.0, 23.5, 30.0, 37.5, 45.0, 52.5, 60.0, 67.5, 75.0];
                let counts = [1usize, 6, 12, 12, 12, 18, 18, 24, 24, 24];
                let offsets = [0.0, 15.0, 0.0, 15.0, 0.0, 0.0, 7.5, 0.0, 7.5, 0.0];
                (0..10).map(|r| ring(thetas[r], counts[r], offsets[r])).collect()
            }
            other => {
                return Err(Error::Invalid(format!(
                    "unknown sampling '{other}' (known: {})",
                    SAMPLING_NAMES.join(", ")
                )));
            }
        };
        Sampling::new(name, rings)
    }

    /// The `ubo81` sampling (Sattler's H2).
    pub fn ubo81() -> Self {
        Sampling::by_name("ubo81").expect("built-in sampling is valid")
    }

    /// Number of directions.
    pub fn len(&self) -> usize {
        *self.ring_start.last().unwrap_or(&0)
    }

    /// True when the sampling has no direction (never, for a validated sampling).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the first direction of ring `r`.
    pub fn ring_start(&self, r: usize) -> usize {
        self.ring_start[r]
    }

    /// Azimuth spacing of ring `r` in degrees.
    pub fn ring_step_deg(&self, r: usize) -> f64 {
        360.0 / self.rings[r].count as f64
    }

    /// The direction with flat index `i`.
    pub fn direction(&self, i: usize) -> Direction {
        let (r, k) = self.ring_of(i);
        let ring = &self.rings[r];
        Direction::new(
            ring.theta_deg,
            wrap_phi_deg(ring.phi_offset_deg + k as f64 * self.ring_step_deg(r)),
        )
    }

    /// All directions in index order.
    pub fn directions(&self) -> Vec<Direction> {
        (0..self.len()).map(|i| self.direction(i)).collect()
    }

    /// Ring and position within the ring of flat index `i`.
    pub fn ring_of(&self, i: usize) -> (usize, usize) {
        assert!(i < self.len(), "direction index {i} out of range 0..{}", self.len());
        let r = self.ring_start.partition_point(|&s| s <= i) - 1;
        (r, i - self.ring_start[r])
    }

    /// The flat index of the sample on `ring` nearest to the given azimuth in `phi_deg`.
    pub fn nearest_on_ring(&self, r: usize, phi_deg: f64) -> usize {
        let ring = &self.rings[r];
        let u = wrap_phi_deg(phi_deg - ring.phi_offset_deg) / self.ring_step_deg(r);
        self.ring_start[r] + (u.round() as usize) % ring.count
    }

    /// A compact description, e.g. for error messages and JSON.
    pub fn describe(&self) -> String {
        format!("{} ({} directions in {} rings)", self.name, self.len(), self.rings.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_counts() {
        assert_eq!(Sampling::by_name("ubo81").unwrap().len(), 81);
        assert_eq!(Sampling::by_name("ubo81-h1").unwrap().len(), 81);
        assert_eq!(Sampling::by_name("dome151").unwrap().len(), 151);
        assert!(Sampling::by_name("nope").is_err());
    }

    #[test]
    fn numbering_is_ring_by_ring_from_pole() {
        let s = Sampling::ubo81();
        assert_eq!(s.direction(0), Direction::new(0.0, 0.0));
        assert_eq!(s.direction(1), Direction::new(15.0, 0.0));
        assert_eq!(s.direction(2), Direction::new(15.0, 60.0));
        assert_eq!(s.direction(7), Direction::new(30.0, 0.0));
        assert_eq!(s.ring_of(80), (5, 23));
        assert!((s.direction(80).phi_deg - 345.0).abs() < 1e-12);
        let d = Sampling::by_name("dome151").unwrap();
        assert_eq!(d.direction(1), Direction::new(11.0, 15.0));
        assert_eq!(d.ring_of(150), (9, 23));
    }

    #[test]
    fn rejects_bad_rings() {
        let r = |t, c| Ring { theta_deg: t, count: c, phi_offset_deg: 0.0 };
        assert!(Sampling::new("x", vec![r(0.0, 2)]).is_err());
        assert!(Sampling::new("x", vec![r(10.0, 2), r(5.0, 2)]).is_err());
        assert!(Sampling::new("x", vec![r(95.0, 2)]).is_err());
        assert!(Sampling::new("x", vec![]).is_err());
        assert!(Sampling::new("x", vec![r(10.0, 0)]).is_err());
    }

    #[test]
    fn serde_round_trip_restores_index() {
        let s = Sampling::by_name("dome151").unwrap();
        let json = serde_json::to_string(&s).unwrap();
        let back: Sampling = serde_json::from_str::<Sampling>(&json).unwrap().validated().unwrap();
        assert_eq!(back.len(), 151);
        assert_eq!(back.direction(37), s.direction(37));
    }
}
