//! The yarn cross-section density for the volumetric reference of [C03 §5.1] (the density
//! image a lumislice is built from, Fig. 6 there), computed from the fiber model instead of
//! drawn.
//!
//! - **n_A**, fiber centres per unit cross-section area (m⁻²), on a `res × res` grid in the
//!   slice frame that turns with the plies (DESIGN §1.3 item 9: one table serves every
//!   twisted slice): the regular fibers of a straight yarn ([`crate::fiber::FiberModel`],
//!   migration and loops included, hairs excluded) at `samples` length coordinates over one
//!   ply twist `|α_ply|`, each centre splatted bilinearly with weight `1/samples`. The grid
//!   is sized so that every splat lands inside, so `∫ n_A dA` equals the number of fibers
//!   exactly (to rounding).
//! - **Azimuthally averaged** variant ([`RadialDensity`]): the same centres binned by
//!   distance from the yarn axis in annuli, divided by the annulus area; also integrates to
//!   the fiber count. It is the density seen in the fixed yarn frame over one twist, and
//!   what DESIGN §1.3 item 13 uses for ρ(d, i).
//! - **Extinction** (DESIGN §1.3 item 10): `σ_⊥ = 2 r_f n_A`, Beer–Lambert for randomly
//!   placed cylinders of radius `r_f` crossing a ray perpendicular to them. Fibers run along
//!   the yarn, so a ray at angle β to the yarn axis sees `σ(β) = σ_⊥ sin β`
//!   ([`Extinction::Anisotropic`], the physical variant). [C03 eq. 5 and 9] treat the yarn
//!   as isotropic (`γρ` whatever the direction); [`Extinction::Isotropic`] keeps that
//!   literal variant (`σ_⊥` in every direction) for comparison. At `sin β = 0` the
//!   anisotropic extinction is exactly 0 (light along the fibers passes between them).

use crate::fiber::{EffectiveTwist, FiberModel, FiberTable};
use crate::params::YarnParams;
use crate::{Error, Result};

/// Which extinction law [`CrossSectionDensity::sigma`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extinction {
    /// `σ_⊥ sin β` (fibers aligned with the yarn).
    Anisotropic,
    /// `σ_⊥` in every direction ([C03]'s literal isotropic medium).
    Isotropic,
}

/// Options of [`CrossSectionDensity::from_params`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensityOptions {
    /// Grid resolution (cells per side).
    pub res: usize,
    /// Length-coordinate samples over one ply twist.
    pub samples: usize,
    /// Seed of the fiber table.
    pub seed: u64,
    /// Include loop slots.
    pub loops: bool,
}

impl Default for DensityOptions {
    fn default() -> Self {
        DensityOptions { res: 64, samples: 256, seed: 1, loops: true }
    }
}

/// Fiber-centre density on a grid in the co-rotating slice frame (see module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSectionDensity {
    /// Cells per side.
    pub res: usize,
    /// The grid spans `[−half_width, half_width]²` (metres); x along the slice `N'`, y along
    /// `B'`.
    pub half_width: f64,
    /// Fiber centres per m², row-major `[y][x]`.
    pub n_a: Vec<f64>,
    /// Fiber radius r_f (metres).
    pub fiber_radius: f64,
    /// Number of regular fibers the density represents.
    pub fiber_count: usize,
    /// Azimuthally averaged profile of the same centres.
    pub radial: RadialDensity,
}

/// Fiber-centre density by distance from the yarn axis (annuli of width `dr`).
#[derive(Debug, Clone, PartialEq)]
pub struct RadialDensity {
    /// Annulus width (metres).
    pub dr: f64,
    /// Fiber centres per m² in annulus `k` (`k·dr ≤ r < (k+1)·dr`).
    pub n_a: Vec<f64>,
}

impl RadialDensity {
    /// n_A at radius `r` (piecewise constant; 0 outside).
    pub fn n_a_at(&self, r: f64) -> f64 {
        let k = (r / self.dr).floor();
        if k < 0.0 || k as usize >= self.n_a.len() { 0.0 } else { self.n_a[k as usize] }
    }

    /// `∫ n_A dA` (exact for the annuli).
    pub fn integral(&self) -> f64 {
        let pi = std::f64::consts::PI;
        self.n_a
            .iter()
            .enumerate()
            .map(|(k, n)| n * pi * self.dr * self.dr * ((k + 1) * (k + 1) - k * k) as f64)
            .sum()
    }
}

impl CrossSectionDensity {
    /// The density of the regular fibers of `params` (straight yarn, one ply twist).
    pub fn from_params(params: &YarnParams, opts: &DensityOptions) -> Result<Self> {
        params.validate()?;
        if opts.res < 4 || opts.res > 4096 || opts.samples == 0 || opts.samples > 1 << 20 {
            return Err(Error::Limit(format!(
                "density grid {}² with {} samples (res in 4..=4096, samples in 1..=2^20)",
                opts.res, opts.samples
            )));
        }
        let mut p = params.clone();
        if !opts.loops {
            p.loop_density = 0.0;
        }
        let table = FiberTable::new(&p, opts.seed, 0);
        let model = FiberModel { params: &p, table: &table, twist: EffectiveTwist::nominal(&p) };
        Ok(Self::accumulate(&model, opts))
    }

    fn accumulate(model: &FiberModel, opts: &DensityOptions) -> Self {
        let p = model.params;
        let (np, nf) = (p.ply_count as usize, p.fibers_per_ply as usize);
        let period = p.ply_pitch.abs();
        let mut pts = Vec::with_capacity(np * nf * opts.samples);
        for k in 0..opts.samples {
            let z = period * (k as f64 + 0.5) / opts.samples as f64;
            // Rotate into the slice frame that turns with the plies.
            let (s, c) = (std::f64::consts::TAU * z / model.twist.ply_pitch).sin_cos();
            for ply in 0..np {
                for f in 0..nf {
                    let [a, b] = model.fiber_offset(z, ply, f);
                    pts.push([c * a + s * b, -s * a + c * b]);
                }
            }
        }
        let reach = pts.iter().map(|q| q[0].abs().max(q[1].abs())).fold(0.0, f64::max);
        let reach = if reach > 0.0 { reach } else { p.yarn_radius().max(1e-9) };
        let res = opts.res;
        // Two cells of margin so every bilinear splat stays inside the grid.
        let cell = 2.0 * reach / (res as f64 - 4.0);
        let half_width = 0.5 * cell * res as f64;
        let w = 1.0 / opts.samples as f64;
        let mut n_a = vec![0.0; res * res];
        for q in &pts {
            let gx = (q[0] + half_width) / cell - 0.5;
            let gy = (q[1] + half_width) / cell - 0.5;
            let (x0, y0) = (gx.floor(), gy.floor());
            let (fx, fy) = (gx - x0, gy - y0);
            let (x0, y0) = (x0 as usize, y0 as usize);
            for (dx, dy, wt) in [
                (0, 0, (1.0 - fx) * (1.0 - fy)),
                (1, 0, fx * (1.0 - fy)),
                (0, 1, (1.0 - fx) * fy),
                (1, 1, fx * fy),
            ] {
                n_a[(y0 + dy) * res + x0 + dx] += w * wt;
            }
        }
        let area = cell * cell;
        n_a.iter_mut().for_each(|v| *v /= area);
        let bins = res / 2;
        let r_max = pts.iter().map(|q| q[0].hypot(q[1])).fold(0.0, f64::max);
        let dr = (r_max * (1.0 + 1e-9)).max(1e-12) / bins as f64;
        let mut radial = vec![0.0; bins];
        for q in &pts {
            let k = ((q[0].hypot(q[1]) / dr) as usize).min(bins - 1);
            radial[k] += w;
        }
        let pi = std::f64::consts::PI;
        for (k, v) in radial.iter_mut().enumerate() {
            *v /= pi * dr * dr * ((k + 1) * (k + 1) - k * k) as f64;
        }
        CrossSectionDensity {
            res,
            half_width,
            n_a,
            fiber_radius: p.fiber_radius,
            fiber_count: np * nf,
            radial: RadialDensity { dr, n_a: radial },
        }
    }

    /// Cell size (metres).
    pub fn cell_size(&self) -> f64 {
        2.0 * self.half_width / self.res as f64
    }

    /// `∫ n_A dA` over the grid.
    pub fn integral(&self) -> f64 {
        self.n_a.iter().sum::<f64>() * self.cell_size() * self.cell_size()
    }

    /// n_A at slice coordinates `(x, y)` (bilinear between cell centres; 0 outside).
    pub fn n_a_at(&self, x: f64, y: f64) -> f64 {
        let cell = self.cell_size();
        let gx = (x + self.half_width) / cell - 0.5;
        let gy = (y + self.half_width) / cell - 0.5;
        let (x0, y0) = (gx.floor(), gy.floor());
        let (fx, fy) = (gx - x0, gy - y0);
        let at = |i: f64, j: f64| {
            if i < 0.0 || j < 0.0 || i >= self.res as f64 || j >= self.res as f64 {
                0.0
            } else {
                self.n_a[j as usize * self.res + i as usize]
            }
        };
        (1.0 - fx) * (1.0 - fy) * at(x0, y0)
            + fx * (1.0 - fy) * at(x0 + 1.0, y0)
            + (1.0 - fx) * fy * at(x0, y0 + 1.0)
            + fx * fy * at(x0 + 1.0, y0 + 1.0)
    }

    /// `σ_⊥ = 2 r_f n_A` (per metre) at `(x, y)`.
    pub fn sigma_perp(&self, x: f64, y: f64) -> f64 {
        2.0 * self.fiber_radius * self.n_a_at(x, y)
    }

    /// Extinction (per metre) for a ray at angle β to the yarn axis (`sin_beta ∈ [0, 1]`).
    pub fn sigma(&self, x: f64, y: f64, sin_beta: f64, law: Extinction) -> f64 {
        let s = self.sigma_perp(x, y);
        match law {
            Extinction::Anisotropic => s * sin_beta.clamp(0.0, 1.0),
            Extinction::Isotropic => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn density_integrates_to_the_fiber_count_and_sigma_is_two_rf_na() {
        for name in crate::params::presets::NAMES {
            let p = YarnParams::preset(name).unwrap();
            let d = CrossSectionDensity::from_params(&p, &DensityOptions::default()).unwrap();
            let n = (p.ply_count * p.fibers_per_ply) as f64;
            assert!((d.integral() / n - 1.0).abs() < 1e-12, "{name}: {}", d.integral());
            assert!((d.radial.integral() / n - 1.0).abs() < 1e-12, "{name}");
            for (x, y) in [(0.0, 0.0), (1e-4, -5e-5), (0.3 * d.half_width, 0.1 * d.half_width)] {
                let s = d.sigma_perp(x, y);
                assert_eq!(s, 2.0 * p.fiber_radius * d.n_a_at(x, y));
                assert_eq!(d.sigma(x, y, 0.0, Extinction::Anisotropic), 0.0);
                assert_eq!(d.sigma(x, y, 0.0, Extinction::Isotropic), s);
                assert!((d.sigma(x, y, 0.5, Extinction::Anisotropic) - 0.5 * s).abs() <= 1e-15 * s);
            }
            assert_eq!(d.n_a_at(2.0 * d.half_width, 0.0), 0.0);
        }
        let mut thin = YarnParams::preset("fine-2ply").unwrap();
        thin.fiber_radius = 0.0;
        let d = CrossSectionDensity::from_params(&thin, &DensityOptions::default()).unwrap();
        assert!(d.n_a.iter().all(|v| v.is_finite()) && d.sigma_perp(0.0, 0.0) == 0.0);
    }
}
