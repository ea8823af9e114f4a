//! The local reflection model at a point of the mesostructure: Lambert + microfacet
//! specular (GGX/Trowbridge–Reitz distribution with height-correlated Smith masking and
//! Schlick's Fresnel) + a fabric sheen lobe (the "Charlie" inverted-Gaussian-like
//! distribution `sin^(1/r) θ_h` of Estevez & Kulla 2017 with the Neubelt–Pettineo
//! visibility term).
//!
//! Energy is conserved by construction, not by tuning. With `E_s(μ)` the directional albedo
//! of the specular lobe, the diffuse lobe is coupled as in Kelemen & Szirmay-Kalos 2001:
//! `f_d = ρ/π · (1 − E_s(μ_i))(1 − E_s(μ_o)) / (1 − Ē_s)`, `Ē_s = 2∫E_s(μ)μ dμ`, so that the
//! base layer reflects `E_s + ρ(1 − E_s) ≤ 1`. The sheen lies on top and the base is
//! attenuated by `min(1 − E_sh(μ_i), 1 − E_sh(μ_o))` (albedo scaling), so the total stays
//! ≤ 1 and the model remains reciprocal. The albedo tables are integrated numerically once
//! per material: the specular one by a stratified grid over the GGX half-vector density
//! `D(h)(n·h)`, the sheen one by a cosine-weighted grid.

use crate::vec3::{V3, dot, normalize_or};
use std::f64::consts::PI;

const TABLE: usize = 64;

/// Parameters of the local reflection model (the albedo comes per texel).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BrdfParams {
    /// Fresnel reflectance at normal incidence of the specular lobe; 0 disables it.
    pub spec_f0: f64,
    /// GGX roughness `α` (perceptual roughness squared), clamped to `[0.02, 1]`.
    pub spec_alpha: f64,
    /// Sheen colour (per-channel weight in `[0, 1]`); zero disables the lobe.
    pub sheen_color: [f64; 3],
    /// Sheen roughness `r` in `(0, 1]`.
    pub sheen_roughness: f64,
}

/// The reflection model with its precomputed albedo tables.
#[derive(Debug, Clone)]
pub struct Brdf {
    p: BrdfParams,
    e_spec: Vec<f64>,
    e_spec_avg: f64,
    e_sheen: Vec<f64>,
    sheen_scale: f64,
}

fn lerp_table(t: &[f64], mu: f64) -> f64 {
    let x = (mu.clamp(0.0, 1.0) * TABLE as f64 - 0.5).clamp(0.0, (TABLE - 1) as f64);
    let i = (x.floor() as usize).min(TABLE - 2);
    let f = x - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

fn smith_lambda(alpha: f64, mu: f64) -> f64 {
    let mu = mu.max(1e-6);
    let tan2 = (1.0 - mu * mu).max(0.0) / (mu * mu);
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

fn ggx_d(alpha: f64, nh: f64) -> f64 {
    let a2 = alpha * alpha;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

fn schlick(f0: f64, vh: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - vh.clamp(0.0, 1.0)).powi(5)
}

impl Brdf {
    /// Builds the model and integrates its albedo tables.
    pub fn new(mut p: BrdfParams) -> Self {
        p.spec_f0 = p.spec_f0.clamp(0.0, 1.0);
        p.spec_alpha = p.spec_alpha.clamp(0.02, 1.0);
        p.sheen_roughness = p.sheen_roughness.clamp(0.05, 1.0);
        p.sheen_color = p.sheen_color.map(|c| c.clamp(0.0, 1.0));
        let mut b = Brdf {
            p,
            e_spec: vec![0.0; TABLE],
            e_spec_avg: 0.0,
            e_sheen: vec![0.0; TABLE],
            sheen_scale: 1.0,
        };
        if p.spec_f0 > 0.0 {
            b.e_spec = (0..TABLE).map(|k| b.spec_albedo((k as f64 + 0.5) / TABLE as f64)).collect();
            b.e_spec_avg = (0..TABLE)
                .map(|k| 2.0 * b.e_spec[k] * (k as f64 + 0.5) / TABLE as f64)
                .sum::<f64>()
                / TABLE as f64;
        }
        if p.sheen_color.iter().any(|&c| c > 0.0) {
            b.e_sheen =
                (0..TABLE).map(|k| b.sheen_albedo_unit((k as f64 + 0.5) / TABLE as f64)).collect();
            let max = b.e_sheen.iter().cloned().fold(0.0, f64::max);
            if max > 1.0 {
                b.sheen_scale = 1.0 / max;
                b.e_sheen.iter_mut().for_each(|e| *e /= max);
            }
        }
        b
    }

    /// The parameters in use (after clamping).
    pub fn params(&self) -> &BrdfParams {
        &self.p
    }

    fn spec(&self, mu_i: f64, mu_o: f64, nh: f64, vh: f64) -> f64 {
        let a = self.p.spec_alpha;
        let g2 = 1.0 / (1.0 + smith_lambda(a, mu_i) + smith_lambda(a, mu_o));
        ggx_d(a, nh) * g2 * schlick(self.p.spec_f0, vh) / (4.0 * mu_i * mu_o)
    }

    fn sheen_unit(&self, mu_i: f64, mu_o: f64, nh: f64) -> f64 {
        let inv_r = 1.0 / self.p.sheen_roughness;
        let sin_h = (1.0 - nh * nh).max(0.0).sqrt();
        let d = (2.0 + inv_r) * sin_h.powf(inv_r) / (2.0 * PI);
        let v = 1.0 / (4.0 * (mu_i + mu_o - mu_i * mu_o));
        self.sheen_scale * d * v
    }

    /// Directional albedo of the specular lobe at `μ_i`, by a 64×64 stratified grid over
    /// the half-vector density `D(h)(n·h)`.
    fn spec_albedo(&self, mu_i: f64) -> f64 {
        let a = self.p.spec_alpha;
        let l = [(1.0 - mu_i * mu_i).max(0.0).sqrt(), 0.0, mu_i];
        let n = 64;
        let mut sum = 0.0;
        for iu in 0..n {
            let u = (iu as f64 + 0.5) / n as f64;
            let tan_h = a * (u / (1.0 - u)).sqrt();
            let cos_h = 1.0 / (1.0 + tan_h * tan_h).sqrt();
            let sin_h = tan_h * cos_h;
            for iv in 0..n {
                let phi = 2.0 * PI * (iv as f64 + 0.5) / n as f64;
                let h = [sin_h * phi.cos(), sin_h * phi.sin(), cos_h];
                let lh = dot(l, h);
                if lh <= 0.0 {
                    continue;
                }
                let o_z = 2.0 * lh * h[2] - l[2];
                if o_z <= 0.0 {
                    continue;
                }
                let g2 = 1.0 / (1.0 + smith_lambda(a, mu_i) + smith_lambda(a, o_z));
                sum += g2 * schlick(self.p.spec_f0, lh) * lh / (mu_i * cos_h);
            }
        }
        sum / (n * n) as f64
    }

    /// Directional albedo of the unit-colour sheen lobe at `μ_i`, by a 96×96
    /// cosine-weighted grid over outgoing directions.
    fn sheen_albedo_unit(&self, mu_i: f64) -> f64 {
        let l = [(1.0 - mu_i * mu_i).max(0.0).sqrt(), 0.0, mu_i];
        let n = 96;
        let mut sum = 0.0;
        for iu in 0..n {
            let mu_o = ((iu as f64 + 0.5) / n as f64).sqrt();
            let s = (1.0 - mu_o * mu_o).sqrt();
            for iv in 0..n {
                let phi = 2.0 * PI * (iv as f64 + 0.5) / n as f64;
                let o = [s * phi.cos(), s * phi.sin(), mu_o];
                let h = normalize_or([l[0] + o[0], l[1] + o[1], l[2] + o[2]], [0.0, 0.0, 1.0]);
                sum += self.sheen_unit(mu_i, mu_o, h[2]);
            }
        }
        PI * sum / (n * n) as f64
    }

    /// The BRDF `f(n, v, l)` per RGB channel for diffuse albedo `rho` (1/sr). `n`, `v`, `l`
    /// are unit vectors; zero when the light or the view is behind the local surface.
    pub fn eval(&self, n: V3, v: V3, l: V3, rho: [f64; 3]) -> [f64; 3] {
        let mu_i = dot(n, l);
        if mu_i <= 0.0 {
            return [0.0; 3];
        }
        // A point seen by the view ray may carry a smoothed normal facing slightly away.
        let mu_o = dot(n, v).max(1e-4);
        let mu_i = mu_i.min(1.0);
        let h = normalize_or([v[0] + l[0], v[1] + l[1], v[2] + l[2]], n);
        let nh = dot(n, h).clamp(0.0, 1.0);
        let (mut base_spec, mut diffuse_scale) = (0.0, 1.0);
        if self.p.spec_f0 > 0.0 {
            base_spec = self.spec(mu_i, mu_o, nh, dot(v, h));
            diffuse_scale = (1.0 - lerp_table(&self.e_spec, mu_i))
                * (1.0 - lerp_table(&self.e_spec, mu_o))
                / (1.0 - self.e_spec_avg).max(1e-9);
        }
        let sheen = if self.e_sheen.iter().any(|&e| e > 0.0) {
            self.sheen_unit(mu_i, mu_o, nh)
        } else {
            0.0
        };
        let (esh_i, esh_o) = (lerp_table(&self.e_sheen, mu_i), lerp_table(&self.e_sheen, mu_o));
        let mut out = [0.0; 3];
        for c in 0..3 {
            let sc = self.p.sheen_color[c];
            let base = base_spec + rho[c].clamp(0.0, 1.0) / PI * diffuse_scale;
            let atten = (1.0 - sc * esh_i).min(1.0 - sc * esh_o);
            out[c] = sc * sheen + base * atten;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directional albedo of the full model by a fine cosine-weighted grid.
    fn albedo(b: &Brdf, mu_i: f64, rho: f64) -> [f64; 3] {
        let l = [(1.0 - mu_i * mu_i).sqrt(), 0.0, mu_i];
        let n = 400;
        let mut sum = [0.0; 3];
        for iu in 0..n {
            let mu_o = ((iu as f64 + 0.5) / n as f64).sqrt();
            let s = (1.0 - mu_o * mu_o).sqrt();
            for iv in 0..n {
                let phi = 2.0 * PI * (iv as f64 + 0.5) / n as f64;
                let f = b.eval([0.0, 0.0, 1.0], [s * phi.cos(), s * phi.sin(), mu_o], l, [rho; 3]);
                (0..3).for_each(|c| sum[c] += PI * f[c] / (n * n) as f64);
            }
        }
        sum
    }

    #[test]
    fn white_lambert_reflects_everything_and_full_model_at_most_one() {
        let lam = Brdf::new(BrdfParams {
            spec_f0: 0.0,
            spec_alpha: 0.5,
            sheen_color: [0.0; 3],
            sheen_roughness: 0.5,
        });
        let a = albedo(&lam, 0.6, 1.0);
        assert!((a[0] - 1.0).abs() < 1e-3, "{a:?}");
        let full = Brdf::new(BrdfParams {
            spec_f0: 0.05,
            spec_alpha: 0.3,
            sheen_color: [0.8, 0.6, 1.0],
            sheen_roughness: 0.4,
        });
        for &mu in &[0.05, 0.3, 0.7, 1.0] {
            let a = albedo(&full, mu, 1.0);
            // A white base loses at most what the albedo scaling under the sheen discards.
            assert!(a.iter().all(|&x| x <= 1.0 + 0.01 && x > 0.8), "mu {mu}: {a:?}");
        }
    }
}
