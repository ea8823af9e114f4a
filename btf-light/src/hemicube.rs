//! The hemicube of a vertex ([S03 §5.1–5.2, eq. 9]): the discretisation of
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
//! One face table ([`faces`]) defines the layout for the pixel directions, the rasteriser
//! of the visibility maps and the inverse map [`pixel_of`]; [`HemicubeFrame`] places a
//! hemicube at a vertex side in world space.
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

/// One face of the layout: the major axis with its sign, and the axes of the face
/// coordinates `u = p_u / (s p_m)` (columns) and `v = p_v / (s p_m)` (rows, from `v_min`).
/// The one table behind the pixel directions, the rasteriser and [`pixel_of`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Face {
    pub(crate) major: usize,
    pub(crate) sign: f32,
    pub(crate) u: usize,
    pub(crate) v: usize,
    pub(crate) v_min: f32,
    /// Pixel rows (`res` on the top face, `res/2` on the sides); every face has `res`
    /// columns.
    pub(crate) rows: usize,
    /// First pixel of the face in the layout.
    pub(crate) start: usize,
}

impl Face {
    /// The tangent-space point with face coordinates `(a, b)` on the face plane.
    fn point(&self, a: f64, b: f64) -> [f64; 3] {
        let mut p = [0.0; 3];
        p[self.major] = self.sign as f64;
        p[self.u] = a;
        p[self.v] = b;
        p
    }
}

/// The five faces: top (`+z`), then `+x`, `−x`, `+y`, `−y`.
pub(crate) fn faces(res: usize) -> [Face; 5] {
    let (half, top) = (res / 2, res * res);
    let side = |major, sign, u, k: usize| Face {
        major,
        sign,
        u,
        v: 2,
        v_min: 0.0,
        rows: half,
        start: top + k * res * half,
    };
    [
        Face { major: 2, sign: 1.0, u: 0, v: 1, v_min: -1.0, rows: res, start: 0 },
        side(0, 1.0, 1, 0),
        side(0, -1.0, 1, 1),
        side(1, 1.0, 0, 2),
        side(1, -1.0, 0, 3),
    ]
}

/// The pixel containing tangent-space `(x, y, z)`, `z > 0` — the inverse of the layout
/// (what a source of the environment falls into in the gathers of `[S03 eq. 10]`). Written
/// out per face rather than through [`faces`]: it runs once per source and frame, and its
/// operation order is what the fast and the reference gathers share bit for bit.
pub fn pixel_of(res: usize, x: f32, y: f32, z: f32) -> usize {
    let cell = |a: f32, n: usize| ((a * n as f32) as usize).min(n - 1);
    let (half, top) = (res / 2, res * res);
    let (ax, ay) = (x.abs(), y.abs());
    if z >= ax && z >= ay {
        let (u, v) = ((x / z + 1.0) * 0.5, (y / z + 1.0) * 0.5);
        return cell(v, res) * res + cell(u, res);
    }
    let (face, m, a) = if ax >= ay {
        (if x > 0.0 { 0 } else { 1 }, ax, y)
    } else {
        (if y > 0.0 { 2 } else { 3 }, ay, x)
    };
    let (u, v) = ((a / m + 1.0) * 0.5, z / m);
    top + face * res * half + cell(v, half) * res + cell(u, res)
}

/// The frame of one hemicube: origin and tangent-space axes in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HemicubeFrame {
    /// Vertex position (world).
    pub origin: [f32; 3],
    /// Tangent-space `+x`, `+y`, `+z` (the side's normal) in world space.
    pub axes: [[f32; 3]; 3],
}

impl HemicubeFrame {
    /// World direction of a tangent-space direction.
    pub fn to_world(&self, d: [f32; 3]) -> [f32; 3] {
        let [t, b, n] = self.axes;
        [0, 1, 2].map(|a| d[0] * t[a] + d[1] * b[a] + d[2] * n[a])
    }

    /// The frames of every vertex: front sides `(T, B, N)` first, then, when `two_sided`,
    /// the back sides `(T, B, −N)` (the renderer's frame for a vertex seen from behind).
    pub fn of_mesh(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        tangents: &[[f32; 4]],
        two_sided: bool,
    ) -> Vec<HemicubeFrame> {
        let sides: &[f32] = if two_sided { &[1.0, -1.0] } else { &[1.0] };
        let mut out = Vec::with_capacity(positions.len() * sides.len());
        for &s in sides {
            for v in 0..positions.len() {
                let (t, b, n) = crate::tangent::frame(normals[v], tangents[v]);
                let n = n * s;
                out.push(HemicubeFrame {
                    origin: positions[v],
                    axes: [t.into(), b.into(), n.into()],
                });
            }
        }
        out
    }
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
        for face in faces(res as usize) {
            for row in 0..face.rows {
                let b0 = face.v_min as f64 + row as f64 * step;
                for col in 0..res {
                    let a0 = -1.0 + col as f64 * step;
                    let p = face.point(a0 + 0.5 * step, b0 + 0.5 * step);
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
    fn pixel_of_a_direction_is_the_pixel_whose_centre_it_is() {
        for res in [2usize, 8, 16] {
            let cube = Hemicube::new(res as u32).unwrap();
            for (p, d) in cube.dirs.iter().enumerate() {
                assert_eq!(pixel_of(res, d[0], d[1], d[2]), p, "res {res}");
            }
            // Every face's first pixel is where the table says the face starts.
            for f in faces(res) {
                let d = cube.dirs[f.start];
                assert!(d[f.major] * f.sign > 0.0, "res {res}, face at {}", f.start);
            }
        }
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
