//! Indoor environments, in the same units as the sky (kcd/m²).
//!
//! - **studio**: a dark room (0.03) with a grey floor and four rectangular soft boxes (key,
//!   fill, top strip, rim) with soft edges — the usual product-photography set-up;
//! - **interior**: a 5 × 4 × 2.6 m room seen from 1.2 m above the floor. The window in the
//!   `+x` wall shows the Preetham sky of [`super::sky`] (with the sun when it is in view);
//!   sunlight through the window makes a bright patch on the floor; a ceiling lamp glows.
//!   The walls' radiance is `ρ/π · E` with the irradiance of an integrating sphere,
//!   `E = Φ_in / (A_room (1 − ρ̄))`, `Φ_in` being the flux through the window — a crude but
//!   energy-consistent stand-in for interreflection.

use super::sky::SkyModel;
use super::{EnvMap, EnvParams};
use crate::Result;
use std::f64::consts::PI;

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A rectangular soft box centred at (elevation, azimuth) with angular half-sizes.
struct SoftBox {
    elevation_deg: f64,
    azimuth_deg: f64,
    half_width_deg: f64,
    half_height_deg: f64,
    radiance: [f64; 3],
}

impl SoftBox {
    fn eval(&self, d: [f64; 3]) -> f64 {
        let (el, az) = (self.elevation_deg.to_radians(), self.azimuth_deg.to_radians());
        let c = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let e1 = [-az.sin(), az.cos(), 0.0];
        let e2 = [-el.sin() * az.cos(), -el.sin() * az.sin(), el.cos()];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let z = dot(d, c);
        if z <= 0.0 {
            return 0.0;
        }
        let a = dot(d, e1).atan2(z).to_degrees().abs();
        let b = dot(d, e2).atan2(z).to_degrees().abs();
        let edge = 1.5;
        (1.0 - smoothstep(self.half_width_deg - edge, self.half_width_deg + edge, a))
            * (1.0 - smoothstep(self.half_height_deg - edge, self.half_height_deg + edge, b))
    }
}

/// The photo studio.
pub fn studio(width: usize) -> Result<EnvMap> {
    let boxes = [
        SoftBox {
            elevation_deg: 30.0,
            azimuth_deg: 45.0,
            half_width_deg: 25.0,
            half_height_deg: 18.0,
            radiance: [30.0, 28.5, 27.0],
        },
        SoftBox {
            elevation_deg: 15.0,
            azimuth_deg: 200.0,
            half_width_deg: 35.0,
            half_height_deg: 25.0,
            radiance: [5.4, 5.8, 6.3],
        },
        SoftBox {
            elevation_deg: 75.0,
            azimuth_deg: 0.0,
            half_width_deg: 10.0,
            half_height_deg: 40.0,
            radiance: [12.0; 3],
        },
        SoftBox {
            elevation_deg: 20.0,
            azimuth_deg: 300.0,
            half_width_deg: 8.0,
            half_height_deg: 30.0,
            radiance: [20.0; 3],
        },
    ];
    EnvMap::from_fn(width, |d| {
        let mut l = if d[2] < 0.0 { [0.06; 3] } else { [0.03; 3] };
        for b in &boxes {
            let w = b.eval(d);
            (0..3).for_each(|c| l[c] += w * b.radiance[c]);
        }
        l
    })
    .map_err(Into::into)
}

const ROOM_MIN: [f64; 3] = [-2.5, -2.0, -1.2];
const ROOM_MAX: [f64; 3] = [2.5, 2.0, 1.4];
/// Window on the `x = max` wall: `y` and `z` ranges.
const WINDOW: ([f64; 2], [f64; 2]) = ([-1.0, 1.0], [-0.3, 1.0]);
const GLASS_TRANSMITTANCE: f64 = 0.85;

fn in_window(y: f64, z: f64) -> bool {
    let ((y0, y1), (z0, z1)) = ((WINDOW.0[0], WINDOW.0[1]), (WINDOW.1[0], WINDOW.1[1]));
    let mullion = (y - 0.5 * (y0 + y1)).abs() < 0.03 || (z - 0.35).abs() < 0.03;
    y > y0 && y < y1 && z > z0 && z < z1 && !mullion
}

/// The room interior lit through its window by the sky of `params`.
pub fn interior(params: &EnvParams, width: usize) -> Result<EnvMap> {
    let sky = SkyModel::new(params)?;
    let sun = sky.sun_direction();
    let sun_rgb = sky.sun_rgb();
    let sun_irr = sun_rgb.map(|l| l * SkyModel::sun_solid_angle() * GLASS_TRANSMITTANCE);
    // Flux through the window: diffuse sky (radiance at the window's centre direction,
    // times π) plus the direct sun when it shines in (x-component of the sun direction).
    let area_window = (WINDOW.0[1] - WINDOW.0[0]) * (WINDOW.1[1] - WINDOW.1[0]);
    let sky_in = sky.sky_rgb([0.9, 0.0, 0.436]);
    let flux: [f64; 3] = std::array::from_fn(|c| {
        area_window * (PI * sky_in[c] * GLASS_TRANSMITTANCE + sun_irr[c] * sun[0].max(0.0))
    });
    let size = [0, 1, 2].map(|k| ROOM_MAX[k] - ROOM_MIN[k]);
    let area_room = 2.0 * (size[0] * size[1] + size[1] * size[2] + size[0] * size[2]);
    let mean_albedo = 0.5;
    let e_amb = flux.map(|f| f / (area_room * (1.0 - mean_albedo)));
    let wall = [0.75, 0.72, 0.65];
    let floor = [0.35, 0.22, 0.12];
    EnvMap::from_fn(width, |d| {
        // Exit point of the ray from the viewer (origin) through the room box.
        let (mut t, mut axis) = (f64::INFINITY, 0);
        for k in 0..3 {
            if d[k].abs() > 1e-12 {
                let tk = if d[k] > 0.0 { ROOM_MAX[k] / d[k] } else { ROOM_MIN[k] / d[k] };
                if tk < t {
                    (t, axis) = (tk, k);
                }
            }
        }
        let p = [d[0] * t, d[1] * t, d[2] * t];
        if axis == 0 && d[0] > 0.0 && in_window(p[1], p[2]) {
            return if d[2] > 0.0 {
                let mut l = sky.sky_rgb(d);
                if d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] >= super::sky::SUN_RADIUS_RAD.cos()
                {
                    l = [0, 1, 2].map(|c| l[c] + sun_rgb[c]);
                }
                l.map(|x| x * GLASS_TRANSMITTANCE)
            } else {
                [0.2 * e_amb[0] * 8.0 / PI; 3]
            };
        }
        if axis == 2 && d[2] > 0.0 {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            let lamp = 1.0 - smoothstep(0.22, 0.25, r);
            return std::array::from_fn(|c| 0.8 * e_amb[c] / PI + lamp * [6.0, 5.4, 4.5][c]);
        }
        if axis == 2 {
            // Floor: planks along x, plus the sun patch cast through the window.
            let plank = 0.85 + 0.15 * ((p[1] * 6.0).floor() * 12.9898).sin().abs();
            let mut e = e_amb;
            if sun[0] > 0.0 && sun[2] > 0.0 {
                let s = (ROOM_MAX[0] - p[0]) / sun[0];
                if in_window(p[1] + s * sun[1], p[2] + s * sun[2]) {
                    (0..3).for_each(|c| e[c] += sun_irr[c] * sun[2]);
                }
            }
            return std::array::from_fn(|c| floor[c] * plank * e[c] / PI);
        }
        let tint = if axis == 1 && d[1] > 0.0 { [0.55, 0.62, 0.7] } else { wall };
        std::array::from_fn(|c| tint[c] * e_amb[c] / PI)
    })
    .map_err(Into::into)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn studio_boxes_and_interior_window_are_where_documented() {
        let s = studio(256).unwrap();
        let key = {
            let (el, az) = (30f64.to_radians(), 45f64.to_radians());
            s.pixels[{
                let (c, r) = s.pixel_of([el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]);
                r * s.width + c
            }]
        };
        assert!((key[0] - 30.0).abs() < 0.1, "{key:?}");
        let p = EnvParams { sun_elevation_deg: 35.0, sun_azimuth_deg: 10.0, turbidity: 3.0 };
        let m = interior(&p, 256).unwrap();
        let at = |p: [f64; 3]| {
            let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            let (c, r) = m.pixel_of([p[0] / n, p[1] / n, p[2] / n]);
            m.pixels[r * m.width + c]
        };
        // Through the window (+x, a little up) is sky, much brighter than the opposite wall;
        // the sun patch on the floor is brighter than the floor in shade.
        let window = at([0.95, 0.1, 0.2]);
        let wall = at([-0.95, 0.1, 0.2]);
        assert!(window[2] > 5.0 * wall[2], "{window:?} {wall:?}");
        let sun = [
            35f64.to_radians().cos() * 10f64.to_radians().cos(),
            35f64.to_radians().cos() * 10f64.to_radians().sin(),
            35f64.to_radians().sin(),
        ];
        // Floor point that sees the window centre along the sun direction.
        let t = (0.6 - ROOM_MIN[2]) / sun[2];
        let patch = [ROOM_MAX[0] - t * sun[0], 0.5 - t * sun[1], ROOM_MIN[2]];
        assert!(patch[0] > ROOM_MIN[0], "the sun patch lies on the floor");
        let lit = at(patch);
        let shade = at([-2.0, -1.5, ROOM_MIN[2]]);
        assert!(lit[1] > 3.0 * shade[1], "{lit:?} {shade:?}");
    }
}
