//! Maps the direction lists found in Bonn files (and UBO2003 file names) onto our ring
//! samplings: a built-in sampling (`ubo81`, `ubo81-h1`, `dome151`) when every direction is
//! within 0.5° of one of its samples, otherwise a custom ring sampling recovered from the
//! directions (rings by equal θ, evenly spaced φ). The result is the sampling and the
//! permutation from file order to our flat index (DESIGN.md §3 numbering).
//!
//! Convention mapping: Bonn's `φ` is measured from the texture `x` axis (increasing column)
//! toward `y` (`x = sin θ cos φ`, `y = sin θ sin φ`), and textures are stored scan line by
//! scan line with `x` fastest, the first stored line becoming our row 0. That is our frame
//! (`+x` = increasing column, `+y` = increasing row), so angles are taken over unchanged and
//! rows are not flipped.

use crate::{Error, Result};
use btf_core::direction::wrap_phi_deg;
use btf_core::{Direction, Ring, Sampling};

/// Angular tolerance for matching a direction to a sample, degrees.
pub const MATCH_TOL_DEG: f64 = 0.5;

/// A sampling and where each file direction goes in it.
#[derive(Debug, Clone)]
pub struct DirectionMap {
    /// The sampling the directions form.
    pub sampling: Sampling,
    /// `ours[k]` = our flat index of the file's direction `k`.
    pub ours: Vec<usize>,
}

impl DirectionMap {
    /// The file index of our direction `i`.
    pub fn file_index(&self, i: usize) -> usize {
        self.ours.iter().position(|&o| o == i).expect("a bijection")
    }
}

/// Our index of each direction, if `s` holds each one within tolerance, one to one.
fn match_all(s: &Sampling, dirs: &[Direction]) -> Option<Vec<usize>> {
    if s.len() != dirs.len() {
        return None;
    }
    let ours: Vec<Direction> = s.directions();
    let mut taken = vec![false; ours.len()];
    let mut out = Vec::with_capacity(dirs.len());
    for d in dirs {
        let (i, a) = ours
            .iter()
            .enumerate()
            .map(|(i, o)| (i, o.angle_to_deg(*d)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        if a > MATCH_TOL_DEG || taken[i] {
            return None;
        }
        taken[i] = true;
        out.push(i);
    }
    Some(out)
}

/// Rings recovered from directions: equal θ (within tolerance), evenly spaced φ.
fn recover_rings(dirs: &[Direction]) -> Option<Vec<Ring>> {
    let mut by_theta: Vec<&Direction> = dirs.iter().collect();
    by_theta.sort_by(|a, b| a.theta_deg.total_cmp(&b.theta_deg));
    let mut rings = Vec::new();
    let mut i = 0;
    while i < by_theta.len() {
        let t0 = by_theta[i].theta_deg;
        let mut j = i;
        while j < by_theta.len() && by_theta[j].theta_deg - t0 < MATCH_TOL_DEG {
            j += 1;
        }
        let group = &by_theta[i..j];
        // Files store f32 radians: round to 1e-3° so that 40° comes back as 40°.
        let round = |x: f64| (x * 1000.0).round() / 1000.0;
        let theta = round(group.iter().map(|d| d.theta_deg).sum::<f64>() / group.len() as f64);
        if theta < MATCH_TOL_DEG {
            if group.len() != 1 {
                return None;
            }
            rings.push(Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 });
        } else {
            let mut phis: Vec<f64> = group.iter().map(|d| d.phi_deg).collect();
            phis.sort_by(f64::total_cmp);
            let step = 360.0 / phis.len() as f64;
            let offset = round(phis[0]);
            let even = phis
                .iter()
                .enumerate()
                .all(|(k, p)| (p - offset - k as f64 * step).abs() < MATCH_TOL_DEG);
            if !even || offset >= step - MATCH_TOL_DEG {
                return None;
            }
            rings.push(Ring { theta_deg: theta, count: phis.len(), phi_offset_deg: offset });
        }
        i = j;
    }
    Some(rings)
}

/// Maps `(θ, φ)` pairs in degrees (file order) onto a sampling. `file` and `field` name the
/// source in errors.
pub fn map_directions(dirs_deg: &[(f64, f64)], file: &str, field: &str) -> Result<DirectionMap> {
    if dirs_deg.is_empty() {
        return Err(Error::invalid(file, field, "no directions"));
    }
    let mut dirs = Vec::with_capacity(dirs_deg.len());
    for (k, &(t, p)) in dirs_deg.iter().enumerate() {
        if !(t.is_finite() && p.is_finite() && (0.0..90.0).contains(&t)) {
            return Err(Error::invalid(
                file,
                field,
                format!("direction {k}: theta {t} deg, phi {p} deg is not above the horizon"),
            ));
        }
        // At the pole φ is meaningless: fold it to 0 as our Direction does.
        dirs.push(Direction::new(t, if t < 1e-6 { 0.0 } else { wrap_phi_deg(p) }));
    }
    for name in ["ubo81", "dome151", "ubo81-h1"] {
        let s = Sampling::by_name(name)?;
        if let Some(ours) = match_all(&s, &dirs) {
            return Ok(DirectionMap { sampling: s, ours });
        }
    }
    let rings = recover_rings(&dirs).ok_or_else(|| {
        Error::unsupported(
            file,
            format!(
                "{field}: the {} directions do not form rings of evenly spaced azimuths",
                dirs.len()
            ),
        )
    })?;
    let s = Sampling::new("custom", rings)
        .map_err(|e| Error::invalid(file, field, format!("recovered sampling: {e}")))?;
    let ours = match_all(&s, &dirs).ok_or_else(|| {
        Error::invalid(file, field, "duplicate directions (two map onto the same sample)")
    })?;
    Ok(DirectionMap { sampling: s, ours })
}

/// Radians `(θ, φ)` pairs as stored in UBO2014 files to degrees.
pub fn radians_to_degrees(dirs: &[[f32; 2]]) -> Vec<(f64, f64)> {
    dirs.iter().map(|d| ((d[0] as f64).to_degrees(), (d[1] as f64).to_degrees())).collect()
}

/// Our sampling's directions as `(θ, φ)` radians, in our order, for writing files.
pub fn sampling_radians(s: &Sampling) -> Vec<[f32; 2]> {
    s.directions()
        .iter()
        .map(|d| [d.theta_deg.to_radians() as f32, d.phi_deg.to_radians() as f32])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dome151_in_shuffled_order_maps_back() {
        let s = Sampling::by_name("dome151").unwrap();
        let mut dirs: Vec<(f64, f64)> =
            s.directions().iter().map(|d| (d.theta_deg, d.phi_deg)).collect();
        dirs.reverse();
        dirs[0].1 += 360.0; // φ past 360 folds
        let m = map_directions(&dirs, "f", "views").unwrap();
        assert_eq!(m.sampling.name, "dome151");
        assert_eq!(m.ours[0], 150);
        assert_eq!(m.ours[150], 0);
        assert_eq!(m.file_index(149), 1);
    }

    #[test]
    fn custom_rings_are_recovered() {
        let dirs = [(0.0, 123.0), (40.0, 10.0), (40.0, 130.0), (40.0, 250.0)];
        let m = map_directions(&dirs, "f", "lights").unwrap();
        assert_eq!(m.sampling.name, "custom");
        assert_eq!(m.sampling.rings[1].count, 3);
        assert!((m.sampling.rings[1].phi_offset_deg - 10.0).abs() < 1e-9);
        assert_eq!(m.ours, vec![0, 1, 2, 3]);
    }

    #[test]
    fn irregular_and_below_horizon_refused() {
        let e = map_directions(&[(30.0, 0.0), (30.0, 10.0)], "x.btf", "views").unwrap_err();
        assert!(e.to_string().contains("x.btf") && e.to_string().contains("rings"), "{e}");
        let e = map_directions(&[(95.0, 0.0)], "x.btf", "lights").unwrap_err();
        assert!(e.to_string().contains("'lights'"), "{e}");
    }
}
