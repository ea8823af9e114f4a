//! The daylight sky of Preetham, Shirley & Smits 1999 ("A Practical Analytic Model for
//! Daylight"): the Perez et al. distribution `F(θ, γ) = (1 + A e^{B/cos θ})(1 + C e^{Dγ} +
//! E cos²γ)` for luminance `Y` and chromaticities `x`, `y`, with coefficients linear in the
//! turbidity `T` and zenith values from the paper's appendix (zenith luminance in kcd/m²
//! from `χ = (4/9 − T/120)(π − 2θ_s)`, zenith chromaticity cubic in `θ_s`). A sky value is
//! `zenith · F(θ, γ) / F(0, θ_s)`, converted from CIE xyY to linear Rec. 709 RGB.
//!
//! The sun is a disc of angular radius 0.2667° whose radiance is the extraterrestrial solar
//! luminance (1.9e9 cd/m² = 128 klx over 6.8e-5 sr) attenuated along the relative air mass
//! (Kasten's formula) by Rayleigh scattering and aerosols (Ångström, `β = 0.04608 T −
//! 0.04586`, `α = 1.3`) at 650/570/475 nm — the attenuation terms of Preetham's appendix.
//! Its energy is put into the pixels it covers (by 16×16 supersampling, renormalised so the
//! map integrates to exactly `L_sun · Ω_sun`). Below the horizon is a diffuse ground of
//! albedo 0.2 lit by the sun and the sky.

use super::EnvMap;
use crate::{Error, Result};
use std::f64::consts::PI;

/// Angular radius of the sun disc, radians.
pub const SUN_RADIUS_RAD: f64 = 0.2667 * PI / 180.0;
const SUN_LUMINANCE_KCD: f64 = 1.88e6;
const GROUND_ALBEDO: f64 = 0.2;

/// Preetham's sky for one sun position and turbidity.
#[derive(Debug, Clone)]
pub struct SkyModel {
    sun: [f64; 3],
    theta_s: f64,
    coef: [[f64; 5]; 3],
    zenith: [f64; 3],
    norm: [f64; 3],
    turbidity: f64,
}

fn perez(c: &[f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    (1.0 + c[0] * (c[1] / cos_theta.max(0.01)).exp())
        * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * gamma.cos().powi(2))
}

fn xyy_to_rgb(x: f64, y: f64, lum: f64) -> [f64; 3] {
    let (cx, cz) = (x / y * lum, (1.0 - x - y) / y * lum);
    [
        3.2406 * cx - 1.5372 * lum - 0.4986 * cz,
        -0.9689 * cx + 1.8758 * lum + 0.0415 * cz,
        0.0557 * cx - 0.2040 * lum + 1.0570 * cz,
    ]
    .map(|c| c.max(0.0))
}

impl SkyModel {
    /// The sky for `params` (turbidity in `[1.7, 10]`, sun elevation in `[0.5°, 90°]`).
    pub fn new(params: &super::EnvParams) -> Result<Self> {
        let t = params.turbidity;
        if !(1.7..=10.0).contains(&t) {
            return Err(Error::Invalid(format!(
                "turbidity {t} is outside Preetham's range [1.7, 10]"
            )));
        }
        let el = params.sun_elevation_deg;
        if !(0.5..=90.0).contains(&el) || !params.sun_azimuth_deg.is_finite() {
            return Err(Error::Invalid(format!("sun elevation {el} deg is outside [0.5, 90]")));
        }
        let theta_s = (90.0 - el).to_radians();
        let az = params.sun_azimuth_deg.to_radians();
        let sun = [theta_s.sin() * az.cos(), theta_s.sin() * az.sin(), theta_s.cos()];
        let coef = [
            [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ],
            [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ],
            [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ],
        ];
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let y_z = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
        let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let poly = |m: [[f64; 4]; 3]| {
            let row = |r: [f64; 4]| r.iter().zip(th).map(|(a, b)| a * b).sum::<f64>();
            t * t * row(m[0]) + t * row(m[1]) + row(m[2])
        };
        let x_z = poly([
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]);
        let yc_z = poly([
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]);
        let zenith = [y_z.max(0.0), x_z, yc_z];
        let norm = std::array::from_fn(|k| perez(&coef[k], 1.0, theta_s));
        Ok(SkyModel { sun, theta_s, coef, zenith, norm, turbidity: t })
    }

    /// Unit direction towards the sun.
    pub fn sun_direction(&self) -> [f64; 3] {
        self.sun
    }

    /// Sky luminance `Y` (kcd/m²) at the zenith.
    pub fn zenith_luminance(&self) -> f64 {
        self.zenith[0]
    }

    /// Sky radiance (linear RGB, kcd/m²) for a direction above the horizon (no sun disc).
    pub fn sky_rgb(&self, d: [f64; 3]) -> [f64; 3] {
        let cos_t = d[2].max(1e-3);
        let cos_g = (d[0] * self.sun[0] + d[1] * self.sun[1] + d[2] * self.sun[2]).clamp(-1.0, 1.0);
        let gamma = cos_g.acos();
        let v: [f64; 3] = std::array::from_fn(|k| {
            self.zenith[k] * perez(&self.coef[k], cos_t, gamma) / self.norm[k]
        });
        xyy_to_rgb(v[1], v[2], v[0])
    }

    /// Radiance of the sun disc (linear RGB, kcd/m²) after the atmosphere.
    pub fn sun_rgb(&self) -> [f64; 3] {
        let el_deg = 90.0 - self.theta_s.to_degrees();
        let air_mass = 1.0 / (self.theta_s.cos() + 0.50572 * (el_deg + 6.07995).powf(-1.6364));
        let beta = 0.04608 * self.turbidity - 0.04586;
        let tau = |lambda_um: f64| {
            (-0.008735 * lambda_um.powf(-4.08) * air_mass).exp()
                * (-beta * lambda_um.powf(-1.3) * air_mass).exp()
        };
        [0.65, 0.57, 0.475].map(|l| SUN_LUMINANCE_KCD * tau(l))
    }

    /// Solid angle of the sun disc (sr).
    pub fn sun_solid_angle() -> f64 {
        2.0 * PI * (1.0 - SUN_RADIUS_RAD.cos())
    }

    /// Irradiance on the horizontal ground (klx per channel): sun + sky dome.
    fn ground_irradiance(&self) -> [f64; 3] {
        let sun = self.sun_rgb();
        let mut e: [f64; 3] =
            std::array::from_fn(|c| sun[c] * Self::sun_solid_angle() * self.sun[2]);
        let (nu, nv) = (32, 64);
        for iu in 0..nu {
            let mu = ((iu as f64 + 0.5) / nu as f64).sqrt();
            let s = (1.0 - mu * mu).sqrt();
            for iv in 0..nv {
                let phi = 2.0 * PI * (iv as f64 + 0.5) / nv as f64;
                let l = self.sky_rgb([s * phi.cos(), s * phi.sin(), mu]);
                (0..3).for_each(|c| e[c] += PI * l[c] / (nu * nv) as f64);
            }
        }
        e
    }

    /// The full map: sky, sun disc and ground.
    pub fn render(&self, width: usize) -> Result<EnvMap> {
        let ground = self.ground_irradiance().map(|e| GROUND_ALBEDO * e / PI);
        let mut map =
            EnvMap::from_fn(width, |d| if d[2] > 0.0 { self.sky_rgb(d) } else { ground })?;
        self.add_sun(&mut map);
        Ok(map)
    }

    /// Adds the sun disc so that its integral over the map is exactly `L_sun · Ω_sun`.
    pub(crate) fn add_sun(&self, map: &mut EnvMap) {
        let (c0, r0) = map.pixel_of(self.sun);
        let reach = (SUN_RADIUS_RAD / (PI / map.height as f64)).ceil() as isize + 1;
        let cos_r = SUN_RADIUS_RAD.cos();
        let k = 16;
        let mut covered = Vec::new();
        for dr in -reach..=reach {
            let row = r0 as isize + dr;
            if row < 0 || row >= map.height as isize {
                continue;
            }
            // Near the poles a row wraps around: widen the column range.
            let st = (PI * (row as f64 + 0.5) / map.height as f64).sin().max(1e-3);
            let creach = ((reach as f64 / st).ceil() as isize).min(map.width as isize / 2);
            for dc in -creach..=creach {
                let col = (c0 as isize + dc).rem_euclid(map.width as isize) as usize;
                let mut hits = 0;
                for i in 0..k * k {
                    let t =
                        PI * (row as f64 + ((i / k) as f64 + 0.5) / k as f64) / map.height as f64;
                    let p = 2.0 * PI * (col as f64 + ((i % k) as f64 + 0.5) / k as f64)
                        / map.width as f64;
                    let d = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
                    if d[0] * self.sun[0] + d[1] * self.sun[1] + d[2] * self.sun[2] >= cos_r {
                        hits += 1;
                    }
                }
                if hits > 0 {
                    let omega = map.pixel_solid_angle(row as usize) * hits as f64 / (k * k) as f64;
                    covered.push((row as usize, col, omega));
                }
            }
        }
        if covered.is_empty() {
            covered.push((r0, c0, 1.0));
        }
        let total: f64 = covered.iter().map(|c| c.2).sum();
        let power = self.sun_rgb().map(|l| l * Self::sun_solid_angle());
        for (row, col, omega) in covered {
            let share = omega / total / map.pixel_solid_angle(row);
            let px = &mut map.pixels[row * map.width + col];
            (0..3).for_each(|c| px[c] += (power[c] * share) as f32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::EnvParams;

    #[test]
    fn zenith_matches_preetham_and_sun_carries_its_power() {
        let p = EnvParams { sun_elevation_deg: 45.0, sun_azimuth_deg: 0.0, turbidity: 3.0 };
        let sky = SkyModel::new(&p).unwrap();
        // Zenith luminance from the appendix formula, evaluated by hand for T = 3, θs = 45°.
        let chi = (4.0 / 9.0 - 3.0 / 120.0) * (PI / 2.0);
        let want = (4.0453 * 3.0 - 4.9710) * chi.tan() - 0.2155 * 3.0 + 2.4192;
        let z = sky.sky_rgb([0.0, 0.0, 1.0]);
        let lum = 0.2126 * z[0] + 0.7152 * z[1] + 0.0722 * z[2];
        assert!((lum / want - 1.0).abs() < 0.01, "{lum} vs {want}");
        // A clear sky is blue at the zenith and brighter near the sun than opposite it.
        assert!(z[2] > z[0]);
        let near = sky.sky_rgb([0.6, 0.0, 0.8])[1];
        let far = sky.sky_rgb([-0.6, 0.0, 0.8])[1];
        assert!(near > 2.0 * far, "{near} {far}");

        for width in [64, 512] {
            let with_sun = sky.render(width).unwrap();
            let ground = sky.ground_irradiance().map(|e| GROUND_ALBEDO * e / PI);
            let no_sun =
                EnvMap::from_fn(width, |d| if d[2] > 0.0 { sky.sky_rgb(d) } else { ground })
                    .unwrap();
            let (a, b) = (with_sun.integral(), no_sun.integral());
            let want = sky.sun_rgb()[1] * SkyModel::sun_solid_angle();
            assert!(((a[1] - b[1]) / want - 1.0).abs() < 1e-4, "width {width}");
        }
        // At 2048 pixels the disc is resolved: with its centre on a pixel centre, that pixel
        // is fully covered and carries the sun's radiance, ~1e5 times the zenith sky.
        let p = EnvParams {
            sun_elevation_deg: 90.0 - 256.5 * 180.0 / 1024.0,
            sun_azimuth_deg: 0.5 * 360.0 / 2048.0,
            turbidity: 3.0,
        };
        let sky = SkyModel::new(&p).unwrap();
        let mut map = EnvMap { width: 2048, height: 1024, pixels: vec![[0.0; 3]; 2048 * 1024] };
        sky.add_sun(&mut map);
        let max = map.pixels.iter().map(|p| p[1]).fold(0.0, f32::max) as f64;
        assert!((max / sky.sun_rgb()[1] - 1.0).abs() < 0.05, "{max}");
        assert!(max / z[1] > 3e4, "dynamic range {}", max / z[1]);
    }
}
