//! `SigmaField`: the extinction of the yarn cross-section, `σ = 2 r_f n_A` per metre of
//! *in-plane* path (DESIGN §2.3 item 10; [C03 §5.1]'s density made physical), on a square
//! grid in the slice frame that turns with the plies (x along ply 0's direction `N'`, y
//! along `B'`), as `yarn::density::CrossSectionDensity` computes it from the fiber model
//! over one ply twist.
//!
//! **Symmetrised.** The `n_ply` plies are statistically identical, but one fiber table
//! draws different fibers for each, so the raw density is only approximately
//! `n_ply`-fold symmetric. [W19 §4.1] samples the density *function*, which is symmetric,
//! and its self-shadow texture relies on that to store only `[0, 2π/n_ply]`. We therefore
//! evaluate `σ(q) = (1/n_ply) Σ_k σ_raw(R(2πk/n_ply) q)`: exactly periodic, and still
//! integrating to the same number of fibers. [`SigmaField::symmetrized`] bakes that mean
//! into a grid (for the AO march, where speed matters more than exact periodicity).

use yarn::density::CrossSectionDensity;

/// σ on a grid, with an optional rotational mean at lookup (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SigmaField {
    /// Cells per side.
    pub res: usize,
    /// The grid spans `[−half_width, half_width]²` (metres).
    pub half_width: f64,
    /// σ per metre, row-major `[y][x]`, bilinear between cell centres, 0 outside.
    pub sigma: Vec<f64>,
    /// Lookups average over this many rotations by `2π/fold` (1: plain bilinear).
    pub fold: usize,
}

impl SigmaField {
    /// `2 r_f n_A` of a density, averaged over `fold` rotations at lookup.
    pub fn from_density(d: &CrossSectionDensity, fold: usize) -> Self {
        let s = 2.0 * d.fiber_radius;
        SigmaField {
            res: d.res,
            half_width: d.half_width,
            sigma: d.n_a.iter().map(|n| s * n).collect(),
            fold: fold.max(1),
        }
    }

    /// A field from a function of `(x, y)` (metres), sampled at cell centres.
    pub fn from_fn(res: usize, half_width: f64, f: impl Fn(f64, f64) -> f64) -> Self {
        let cell = 2.0 * half_width / res as f64;
        let mut sigma = vec![0.0; res * res];
        for j in 0..res {
            for i in 0..res {
                let x = -half_width + (i as f64 + 0.5) * cell;
                let y = -half_width + (j as f64 + 0.5) * cell;
                sigma[j * res + i] = f(x, y);
            }
        }
        SigmaField { res, half_width, sigma, fold: 1 }
    }

    /// The rotational mean baked into a plain grid (`fold` = 1).
    pub fn symmetrized(&self) -> Self {
        if self.fold == 1 {
            return self.clone();
        }
        Self::from_fn(self.res, self.half_width, |x, y| self.at(x, y))
    }

    /// Cell size (metres).
    pub fn cell(&self) -> f64 {
        2.0 * self.half_width / self.res as f64
    }

    /// The largest σ of the grid (0 for an empty yarn).
    pub fn max(&self) -> f64 {
        self.sigma.iter().copied().fold(0.0, f64::max)
    }

    fn bilinear(&self, x: f64, y: f64) -> f64 {
        let cell = self.cell();
        let gx = (x + self.half_width) / cell - 0.5;
        let gy = (y + self.half_width) / cell - 0.5;
        let n = self.res as f64;
        if !(gx > -1.0 && gy > -1.0 && gx < n && gy < n) {
            return 0.0;
        }
        let (x0, y0) = (gx.floor(), gy.floor());
        let (fx, fy) = (gx - x0, gy - y0);
        let at = |i: f64, j: f64| {
            if i < 0.0 || j < 0.0 || i >= n || j >= n {
                0.0
            } else {
                self.sigma[j as usize * self.res + i as usize]
            }
        };
        (1.0 - fx) * (1.0 - fy) * at(x0, y0)
            + fx * (1.0 - fy) * at(x0 + 1.0, y0)
            + (1.0 - fx) * fy * at(x0, y0 + 1.0)
            + fx * fy * at(x0 + 1.0, y0 + 1.0)
    }

    /// σ at `(x, y)` in the slice frame (metres), per metre.
    pub fn at(&self, x: f64, y: f64) -> f64 {
        if self.fold == 1 {
            return self.bilinear(x, y);
        }
        let mut s = 0.0;
        for k in 0..self.fold {
            let (sn, cs) = (std::f64::consts::TAU * k as f64 / self.fold as f64).sin_cos();
            s += self.bilinear(cs * x - sn * y, sn * x + cs * y);
        }
        s / self.fold as f64
    }

    /// Optical depth `∫₀^∞ σ(q + t·dir) dt` of the ray from `q` along the unit in-plane
    /// direction `dir`, midpoint rule with `step` (metres), until it leaves the grid.
    pub fn optical_depth(&self, q: [f64; 2], dir: [f64; 2], step: f64) -> f64 {
        // Distance to leave the square [−h, h]² (with a margin for the bilinear skirt).
        let h = self.half_width + self.cell();
        let mut t_exit = f64::INFINITY;
        for a in 0..2 {
            if dir[a] > 1e-300 {
                t_exit = t_exit.min((h - q[a]) / dir[a]);
            } else if dir[a] < -1e-300 {
                t_exit = t_exit.min((-h - q[a]) / dir[a]);
            }
        }
        if t_exit.is_nan() || t_exit <= 0.0 || !t_exit.is_finite() {
            return 0.0;
        }
        let n = (t_exit / step).ceil().max(1.0) as usize;
        let dt = t_exit / n as f64;
        let mut d = 0.0;
        for k in 0..n {
            let t = (k as f64 + 0.5) * dt;
            d += self.at(q[0] + t * dir[0], q[1] + t * dir[1]);
        }
        d * dt
    }
}

/// The symmetrised extinction of `params` ([`yarn::density::CrossSectionDensity`] with the
/// bake's grid, samples, seed and loop flag; folded over the `n_ply` plies).
pub fn field_for(
    params: &yarn::YarnParams,
    settings: &crate::BakeSettings,
) -> crate::Result<SigmaField> {
    let opts = yarn::density::DensityOptions {
        res: settings.density_res,
        samples: settings.density_samples,
        seed: settings.seed,
        loops: settings.loops,
    };
    let d = CrossSectionDensity::from_params(params, &opts)?;
    Ok(SigmaField::from_density(&d, params.ply_count as usize))
}
