//! The mesostructure of a synthetic sample as a periodic height field with albedo, and the
//! two ray marches that turn it into a BTF (DESIGN.md §5): the view ray through a texel of
//! the reference plane is marched down to the surface it really hits (parallax and
//! masking), and the light ray from that point is marched up until it leaves the relief
//! (self-shadowing). Shadows are softened as if the light were a small disc of angular
//! radius `k` (wider for fuzzy fibre surfaces): along the light ray the smallest clearance
//! angle `min_t (z(t) − h(t)) / t` is compared with `k`, and the visible fraction of the
//! disc is approximated by `smoothstep(−k, k, ·)`. Averaging a hard shadow over a small
//! cone of light directions keeps the energy balance of the hard shadow, which an
//! attenuating "leaky" fibre volume on top of a fully lit surface would not.
//!
//! Units are texels: texel `(x, y)` is the unit square with centre `(x + ½, y + ½)`, heights
//! are in texel widths and the reference plane lies at the top of the relief, `z = h_max`.
//! Samples are stored at texel centres and interpolated bilinearly with wrap-around, so the
//! surface tiles seamlessly.

use crate::vec3::{V3, normalize_or};

/// A periodic height field with per-texel albedo and a fibre softness.
#[derive(Debug, Clone)]
pub struct Surface {
    size: usize,
    height: Vec<f64>,
    albedo: Vec<[f64; 3]>,
    normal: Vec<V3>,
    h_min: f64,
    h_max: f64,
    /// Angular radius (radians) of the light disc that softens shadows; 0 = hard.
    penumbra: f64,
}

/// Where a view ray meets the surface, with what the local model needs.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// Position in texel units (`z` is the height).
    pub pos: V3,
    /// Unit normal (smoothly interpolated).
    pub normal: V3,
    /// Diffuse albedo (linear RGB).
    pub albedo: [f64; 3],
}

impl Surface {
    /// A surface from heights and albedos (`size²` entries each, row-major `[y][x]`).
    /// Normals come from central differences of the heights; `penumbra` is the angular
    /// radius (radians) of the shadow-softening light disc.
    pub fn new(size: usize, height: Vec<f64>, albedo: Vec<[f64; 3]>, penumbra: f64) -> Self {
        assert_eq!(height.len(), size * size);
        assert_eq!(albedo.len(), size * size);
        let n = size as isize;
        let at = |x: isize, y: isize| height[(y.rem_euclid(n) * n + x.rem_euclid(n)) as usize];
        let mut normal = Vec::with_capacity(size * size);
        for y in 0..n {
            for x in 0..n {
                let dx = 0.5 * (at(x + 1, y) - at(x - 1, y));
                let dy = 0.5 * (at(x, y + 1) - at(x, y - 1));
                normal.push(normalize_or([-dx, -dy, 1.0], [0.0, 0.0, 1.0]));
            }
        }
        let h_min = height.iter().cloned().fold(f64::INFINITY, f64::min);
        let h_max = height.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        Surface { size, height, albedo, normal, h_min, h_max, penumbra: penumbra.clamp(0.0, 0.5) }
    }

    /// Texels per side.
    pub fn size(&self) -> usize {
        self.size
    }
    /// Lowest and highest height (texel units).
    pub fn height_range(&self) -> (f64, f64) {
        (self.h_min, self.h_max)
    }
    /// The albedo stored for texel `(x, y)`.
    pub fn albedo_texel(&self, x: usize, y: usize) -> [f64; 3] {
        self.albedo[y * self.size + x]
    }

    /// Bilinear weights and the four sample indices around position `(px, py)`.
    #[inline]
    fn corners(&self, px: f64, py: f64) -> ([usize; 4], f64, f64) {
        let n = self.size as f64;
        let fx = (px - 0.5).rem_euclid(n);
        let fy = (py - 0.5).rem_euclid(n);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let s = self.size;
        let x0 = (x0 as usize).min(s - 1);
        let y0 = (y0 as usize).min(s - 1);
        let x1 = if x0 + 1 == s { 0 } else { x0 + 1 };
        let y1 = if y0 + 1 == s { 0 } else { y0 + 1 };
        ([y0 * s + x0, y0 * s + x1, y1 * s + x0, y1 * s + x1], tx, ty)
    }

    /// Height at a position (bilinear, periodic).
    #[inline]
    pub fn height_at(&self, px: f64, py: f64) -> f64 {
        let (c, tx, ty) = self.corners(px, py);
        let h = &self.height;
        let a = h[c[0]] + (h[c[1]] - h[c[0]]) * tx;
        let b = h[c[2]] + (h[c[3]] - h[c[2]]) * tx;
        a + (b - a) * ty
    }

    fn hit_at(&self, pos: V3) -> Hit {
        let (c, tx, ty) = self.corners(pos[0], pos[1]);
        let w = [(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty];
        let (mut n, mut a) = ([0.0; 3], [0.0; 3]);
        for k in 0..4 {
            for i in 0..3 {
                n[i] += w[k] * self.normal[c[k]][i];
                a[i] += w[k] * self.albedo[c[k]][i];
            }
        }
        Hit { pos, normal: normalize_or(n, [0.0, 0.0, 1.0]), albedo: a }
    }

    /// Marches the ray from the reference-plane point above texel `(x, y)` against the
    /// view direction `view` (unit, pointing to the viewer, `view_z > 0`) down to the first
    /// surface point it meets; bisection refines the crossing to 1/64 of a step.
    pub fn view_hit(&self, x: usize, y: usize, view: V3) -> Hit {
        self.view_hit_at(x as f64 + 0.5, y as f64 + 0.5, view)
    }

    /// As [`Surface::view_hit`] from any point `(px, py)` of the reference plane (texel
    /// units), e.g. where a perspective camera ray meets the sample.
    pub fn view_hit_at(&self, px: f64, py: f64, view: V3) -> Hit {
        let start = [px, py, self.h_max];
        let d = [-view[0], -view[1], -view[2].max(1e-6)];
        let f =
            |t: f64| start[2] + t * d[2] - self.height_at(start[0] + t * d[0], start[1] + t * d[1]);
        let at = |t: f64| [start[0] + t * d[0], start[1] + t * d[1], start[2] + t * d[2]];
        if f(0.0) <= 0.0 {
            return self.hit_at(at(0.0));
        }
        let horiz = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let dt = 0.25 / horiz.max(-d[2]);
        let t_max = (self.h_max - self.h_min) / -d[2] + dt;
        let (mut t0, mut t1) = (0.0, dt);
        while f(t1) > 0.0 && t1 < t_max {
            t0 = t1;
            t1 += dt;
        }
        for _ in 0..6 {
            let tm = 0.5 * (t0 + t1);
            if f(tm) > 0.0 { t0 = tm } else { t1 = tm }
        }
        let (f0, f1) = (f(t0), f(t1));
        let t = if f0 - f1 > 1e-12 { t0 + (t1 - t0) * f0 / (f0 - f1) } else { t1 };
        let mut pos = at(t);
        pos[2] = self.height_at(pos[0], pos[1]);
        self.hit_at(pos)
    }

    /// Fraction of the light from unit direction `light` (pointing to the light) that
    /// reaches surface point `pos`: 0 below the horizon; otherwise the visible part of the
    /// softening disc (0 or 1 for hard shadows).
    pub fn light_transmittance(&self, pos: V3, light: V3) -> f64 {
        if light[2] <= 0.0 {
            return 0.0;
        }
        let k = self.penumbra;
        let horiz = (light[0] * light[0] + light[1] * light[1]).sqrt();
        let dt = 0.4 / horiz.max(light[2]);
        let bias = 1e-3 + 0.02 * dt;
        let t_cap = 2.0 * (self.h_max - self.h_min + 1.0) / light[2];
        let mut min_ratio = f64::INFINITY;
        let mut t = dt;
        while t < t_cap {
            let z = pos[2] + t * light[2];
            let clearance = z - self.height_at(pos[0] + t * light[0], pos[1] + t * light[1]);
            if k == 0.0 {
                if clearance < -bias {
                    return 0.0;
                }
                if z >= self.h_max {
                    return 1.0;
                }
            } else {
                min_ratio = min_ratio.min((clearance + bias) / t);
                if min_ratio <= -k {
                    return 0.0;
                }
                // Past the relief the ratio can no longer drop below k (or, for a light
                // below the disc radius, we stop at the top).
                if z - self.h_max >= k * t || (z >= self.h_max && light[2] <= k) {
                    break;
                }
            }
            t += dt;
        }
        if k == 0.0 { 1.0 } else { smoothstep(-k, k, min_ratio) }
    }
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ridge(size: usize) -> Surface {
        // A single ridge along y at x = size/2, 3 texels high, on a flat floor.
        let mut h = vec![0.0; size * size];
        for y in 0..size {
            for x in 0..size {
                let d = (x as f64 + 0.5 - size as f64 / 2.0).abs();
                h[y * size + x] = (3.0 - d).max(0.0);
            }
        }
        Surface::new(size, h, vec![[0.5; 3]; size * size], 0.0)
    }

    #[test]
    fn vertical_view_hits_straight_below_and_ridge_casts_shadow() {
        let s = ridge(16);
        let hit = s.view_hit(3, 5, [0.0, 0.0, 1.0]);
        assert!(
            (hit.pos[0] - 3.5).abs() < 1e-12
                && (hit.pos[1] - 5.5).abs() < 1e-12
                && hit.pos[2] == 0.0
        );
        // A grazing view across the ridge from +x lands on the ridge's +x flank.
        let v = normalize_or([1.0, 0.0, 0.3], [0.0; 3]);
        let hit = s.view_hit(13, 2, v);
        assert!(hit.pos[0] > 8.0 && hit.pos[0] < 11.5 && hit.pos[2] > 0.0, "{:?}", hit.pos);
        assert!((hit.pos[2] - s.height_at(hit.pos[0], hit.pos[1])).abs() < 1e-9);
        // Floor just +x of the ridge: shadowed from a low light at -x, lit from +x and along y.
        let p = [11.8, 4.5, 0.0];
        assert_eq!(s.light_transmittance(p, normalize_or([-1.0, 0.0, 0.3], [0.0; 3])), 0.0);
        assert_eq!(s.light_transmittance(p, normalize_or([1.0, 0.0, 0.3], [0.0; 3])), 1.0);
        assert_eq!(s.light_transmittance(p, normalize_or([0.0, 1.0, 0.3], [0.0; 3])), 1.0);
        assert_eq!(s.light_transmittance(p, [1.0, 0.0, 0.0]), 0.0);
    }
}
