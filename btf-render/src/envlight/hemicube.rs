//! The hemicube of a vertex (Sattler et al. 2003, §5.1–5.2, eq. 9): the discretisation of
//! the hemisphere above a surface point into the pixels of half a cube, built once in
//! tangent space and shared by every vertex.
//!
//! Layout. The cube has half-size 1 around the vertex: the top face `z = 1` holds
//! `res × res` pixels over `x, y ∈ [−1, 1]`; the side faces `x = +1, x = −1, y = +1,
//! y = −1` hold `res × res/2` pixels each over the free axis `∈ [−1, 1]` and `z ∈ [0, 1]`,
//! so there are `3 res²` pixels. Each pixel stores its centre direction and its solid angle.
//!
//! Solid angles. The classic per-pixel value is `dA / |p|³` for the pixel centre `p` (the
//! cosine of the face over the squared distance); it is the midpoint rule of the exact
//! integral and sums to 2π only up to `O(res⁻²)`. We store the exact solid angle of each
//! pixel's rectangle, `Ω = Σ± atan(ab / √(1 + a² + b²))` over its corners `(a, b)`, which
//! sums to 2π to rounding; [`Hemicube::midpoint_solid_angle`] gives the `dA/|p|³` value.
//!
//! The shared table (§5.2, Fig. 11): pixel → the four nearest measured light directions
//! `d_k` with bilinear weights `h_{d_k}` (DESIGN.md §3 interpolation, including the horizon
//! fade beyond the last ring), stored premultiplied by the pixel's solid angle so that the
//! integral of eq. 10 becomes a plain weighted sum.

use crate::{Error, Result};
use btf_core::{Direction, InterpMode, Sampling};

/// Smallest and largest supported resolutions (pixels across the top face).
pub const RES_RANGE: std::ops::RangeInclusive<u32> = 2..=512;

/// Pixel directions and solid angles of a hemicube of resolution `res`.
#[derive(Debug, Clone)]
pub struct Hemicube {
    /// Pixels across the top face (even).
    pub res: u32,
    /// Unit centre direction of every pixel, tangent space.
    pub dirs: Vec<[f32; 3]>,
    /// Exact solid angle of every pixel, steradians.
    pub solid_angle: Vec<f64>,
}

/// `∫∫ dA / (1 + a² + b²)^{3/2}` over `[0, a] × [0, b]` of a face at distance 1.
fn corner_term(a: f64, b: f64) -> f64 {
    (a * b / (1.0 + a * a + b * b).sqrt()).atan()
}

/// Exact solid angle of the rectangle `[a0, a1] × [b0, b1]` on a face at distance 1.
fn rect_solid_angle(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    corner_term(a1, b1) - corner_term(a0, b1) - corner_term(a1, b0) + corner_term(a0, b0)
}

/// The face-local rectangle and the map from face coordinates to tangent space.
struct Face {
    cols: u32,
    rows: u32,
    b_min: f64,
    to_tangent: fn(f64, f64) -> [f64; 3],
}

fn faces(res: u32) -> [Face; 5] {
    let half = res / 2;
    [
        Face { cols: res, rows: res, b_min: -1.0, to_tangent: |a, b| [a, b, 1.0] },
        Face { cols: res, rows: half, b_min: 0.0, to_tangent: |a, b| [1.0, a, b] },
        Face { cols: res, rows: half, b_min: 0.0, to_tangent: |a, b| [-1.0, a, b] },
        Face { cols: res, rows: half, b_min: 0.0, to_tangent: |a, b| [a, 1.0, b] },
        Face { cols: res, rows: half, b_min: 0.0, to_tangent: |a, b| [a, -1.0, b] },
    ]
}

impl Hemicube {
    /// Builds the hemicube; `res` must be even and within [`RES_RANGE`].
    pub fn new(res: u32) -> Result<Hemicube> {
        if !RES_RANGE.contains(&res) || !res.is_multiple_of(2) {
            return Err(Error::Invalid(format!(
                "hemicube resolution {res} must be even and in {}..={}",
                RES_RANGE.start(),
                RES_RANGE.end()
            )));
        }
        let n = 3 * (res as usize).pow(2);
        let mut cube = Hemicube { res, dirs: Vec::with_capacity(n), solid_angle: vec![] };
        cube.solid_angle.reserve(n);
        let step = 2.0 / res as f64;
        for face in faces(res) {
            for row in 0..face.rows {
                let b0 = face.b_min + row as f64 * step;
                for col in 0..face.cols {
                    let a0 = -1.0 + col as f64 * step;
                    let p = (face.to_tangent)(a0 + 0.5 * step, b0 + 0.5 * step);
                    let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    cube.dirs.push(p.map(|c| (c / len) as f32));
                    cube.solid_angle.push(rect_solid_angle(a0, a0 + step, b0, b0 + step));
                }
            }
        }
        Ok(cube)
    }

    /// Number of pixels (`3 res²`).
    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    /// Always false (a hemicube has pixels).
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    /// The midpoint-rule solid angle `dA / |p|³` of pixel `p` (DESIGN.md §3).
    pub fn midpoint_solid_angle(&self, p: usize) -> f64 {
        let res = self.res as usize;
        let (top, side) = (res * res, res * res / 2);
        let step = 2.0 / res as f64;
        let (a, b) = if p < top {
            (-1.0 + (p % res) as f64 * step, -1.0 + (p / res) as f64 * step)
        } else {
            let q = (p - top) % side;
            (-1.0 + (q % res) as f64 * step, (q / res) as f64 * step)
        };
        let (a, b) = (a + 0.5 * step, b + 0.5 * step);
        step * step / (1.0 + a * a + b * b).powf(1.5)
    }
}

/// The shared table "pixel → four nearest measured light directions" with weights
/// `h_{d_k} · dω_p` (padded with weight 0).
#[derive(Debug, Clone)]
pub struct LightTable {
    /// Light indices per pixel.
    pub index: Vec<[u16; 4]>,
    /// Interpolation weight times solid angle per pixel.
    pub weight: Vec<[f32; 4]>,
    /// The interpolation weights `h_{d_k}` alone (without the solid angle).
    pub interp: Vec<[f32; 4]>,
}

impl LightTable {
    /// Builds the table of `cube` for a light sampling (four nearest or nearest).
    pub fn new(cube: &Hemicube, lights: &Sampling, mode: InterpMode) -> Result<LightTable> {
        if lights.len() > u16::MAX as usize {
            return Err(Error::Limit(format!("{} light directions", lights.len())));
        }
        let mut t = LightTable { index: vec![], weight: vec![], interp: vec![] };
        for (d, &omega) in cube.dirs.iter().zip(&cube.solid_angle) {
            let v = [d[0] as f64, d[1] as f64, d[2] as f64];
            let mut idx = [0u16; 4];
            let mut w = [0f32; 4];
            let mut h4 = [0f32; 4];
            if let Some(dir) = Direction::from_vector(v) {
                for (k, &(i, h)) in lights.light_weights(dir, mode).as_slice().iter().enumerate() {
                    idx[k] = i as u16;
                    w[k] = (h * omega) as f32;
                    h4[k] = h as f32;
                }
            }
            t.index.push(idx);
            t.weight.push(w);
            t.interp.push(h4);
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn solid_angles_sum_to_two_pi() {
        for res in [2, 8, 16, 32, 64] {
            let c = Hemicube::new(res).unwrap();
            assert_eq!(c.len(), 3 * (res * res) as usize);
            let sum: f64 = c.solid_angle.iter().sum();
            assert!((sum / (2.0 * PI) - 1.0).abs() < 1e-9, "res {res}: {sum}");
            // The midpoint rule dA/|p|³ converges to the same sum as O(res⁻²).
            let mid: f64 = (0..c.len()).map(|p| c.midpoint_solid_angle(p)).sum();
            let rel = (mid / (2.0 * PI) - 1.0).abs();
            assert!(rel < 0.5 / (res * res) as f64, "res {res}: midpoint off by {rel}");
            for (p, &o) in c.solid_angle.iter().enumerate() {
                let m = c.midpoint_solid_angle(p);
                assert!((o - m).abs() <= 0.05 * m + 1e-12, "pixel {p}: {o} vs {m}");
            }
        }
        assert!(Hemicube::new(7).is_err() && Hemicube::new(0).is_err());
    }

    #[test]
    fn directions_cover_the_upper_hemisphere_evenly() {
        let c = Hemicube::new(16).unwrap();
        // ∫ cos θ dω = π and ∫ n dω has no tangential part.
        let mut m = [0f64; 3];
        for (d, o) in c.dirs.iter().zip(&c.solid_angle) {
            assert!(d[2] > 0.0);
            (0..3).for_each(|a| m[a] += d[a] as f64 * o);
        }
        assert!(m[0].abs() < 1e-9 && m[1].abs() < 1e-9);
        assert!((m[2] / PI - 1.0).abs() < 2e-3, "{}", m[2]);
    }

    #[test]
    fn light_table_weights_integrate_the_interpolated_cosine() {
        let c = Hemicube::new(16).unwrap();
        let s = Sampling::ubo81();
        let t = LightTable::new(&c, &s, InterpMode::Four).unwrap();
        let cos_i: Vec<f64> = s.directions().iter().map(|d| d.cos_theta()).collect();
        let total: f64 = (0..c.len())
            .map(|p| {
                (0..4).map(|k| t.weight[p][k] as f64 * cos_i[t.index[p][k] as usize]).sum::<f64>()
            })
            .sum();
        // Linear interpolation of the concave cos θ across 15° rings stays below π by < 1 %.
        assert!(total < PI && total > 0.99 * PI, "{total}");
    }
}
