//! Rectification: resampling a raw image onto the frontal plane of the sample through the
//! registered homography (the rectification step of Sattler et al. 2003, §3.2), straight to
//! the output texel grid (no intermediate image, so no second resampling filter).
//!
//! Two filters:
//! - **bilinear** — one bilinear sample at the texel centre's image position; it aliases
//!   wherever a texel covers more than about a pixel (minification);
//! - **footprint** — the texel's square is mapped to the image and averaged (a box
//!   prefilter the size of the texel, applied in the image): `kx × ky` bilinear sub-samples
//!   with `k = ⌈|J e| / 0.5 px⌉` along each texel axis `e`, `J` the Jacobian of the
//!   homography at the texel, so sub-samples are never more than half a pixel apart — the
//!   anisotropic footprint at grazing views (foreshortened ~4× at θ = 75°) is respected
//!   along both axes.
//!
//! Because the homography is the same for every light of a view slot, the resampling is
//! built once per slot as a sparse matrix of `(pixel, weight)` taps ([`Plan`]), with the
//! radiometric gain and flat field folded in, and applied to each light image.

use super::homography::apply;
use super::raw::RawImage;
use nalgebra::Matrix3;

/// The resampling filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Filter {
    /// One bilinear sample per texel.
    Bilinear,
    /// Box over the texel's image footprint, sub-sampled at ≤ ½ pixel.
    Footprint,
}

impl Filter {
    /// Parses `bilinear` or `footprint`.
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "bilinear" => Some(Filter::Bilinear),
            "footprint" => Some(Filter::Footprint),
            _ => None,
        }
    }
    /// The name [`Filter::from_name`] reads.
    pub fn name(self) -> &'static str {
        match self {
            Filter::Bilinear => "bilinear",
            Filter::Footprint => "footprint",
        }
    }
}

/// A square grid of texels on the sample plane: texel `(col, row)` has its centre at
/// `origin_mm + ((col + ½), (row + ½)) · texel_mm` (rows run along sample `+y`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Corner of texel (0, 0) (mm).
    pub origin_mm: [f64; 2],
    /// Texel side (mm).
    pub texel_mm: f64,
    /// Texels per side.
    pub n: usize,
}

impl Grid {
    /// Centre of texel `(col, row)` on the plate (mm).
    pub fn centre_mm(&self, col: usize, row: usize) -> [f64; 2] {
        [
            self.origin_mm[0] + (col as f64 + 0.5) * self.texel_mm,
            self.origin_mm[1] + (row as f64 + 0.5) * self.texel_mm,
        ]
    }
}

/// Raw pixels per texel at the grid's centre through homography `h`, along the texel
/// direction the camera resolves worst and best: the singular values of `J · texel`, `J`
/// the homography's Jacobian there. Below about one pixel along an axis, texel detail finer
/// than a pixel is lost before any filter sees it (BENCHMARKS.md #4: the camera's
/// resolution, not the processing, then bounds the store's error).
pub fn pixels_per_texel(h: &Matrix3<f64>, grid: &Grid) -> [f64; 2] {
    let half = grid.n as f64 / 2.0 * grid.texel_mm;
    let c = [grid.origin_mm[0] + half, grid.origin_mm[1] + half];
    let t = grid.texel_mm;
    let p = apply(h, c);
    let d = |q: [f64; 2]| [q[0] - p[0], q[1] - p[1]];
    let (u, v) = (d(apply(h, [c[0] + t, c[1]])), d(apply(h, [c[0], c[1] + t])));
    // singular values of the 2×2 [u v]: √((a ± √(a² − 4 det²)) / 2), a its squared norm
    let a = u[0] * u[0] + u[1] * u[1] + v[0] * v[0] + v[1] * v[1];
    let det = u[0] * v[1] - u[1] * v[0];
    let root = (a * a - 4.0 * det * det).max(0.0).sqrt();
    [((a - root) / 2.0).max(0.0).sqrt(), ((a + root) / 2.0).sqrt()]
}

/// The resampling of one view slot: per texel, taps `(pixel index, weight)`.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Texels per side.
    pub n: usize,
    taps: Vec<(u32, f32)>,
    starts: Vec<u32>,
}

impl Plan {
    /// Builds the taps of `grid` under homography `h` (plate mm → pixels) for images of
    /// `width × height`; `gain(u, v)` multiplies the value read at image position `(u, v)`
    /// (radiometric scale and flat field). Fails when a texel centre falls outside the
    /// image (an ROI the camera did not see).
    pub fn new(
        h: &Matrix3<f64>,
        grid: &Grid,
        width: usize,
        height: usize,
        filter: Filter,
        gain: impl Fn(f64, f64) -> f64,
    ) -> Result<Self, [usize; 2]> {
        let n = grid.n;
        let mut taps = Vec::with_capacity(n * n * 4);
        let mut starts = Vec::with_capacity(n * n + 1);
        for row in 0..n {
            for col in 0..n {
                starts.push(taps.len() as u32);
                let c = grid.centre_mm(col, row);
                let q = apply(h, c);
                if !(q[0] >= 0.0 && q[1] >= 0.0 && q[0] <= width as f64 && q[1] <= height as f64) {
                    return Err([col, row]);
                }
                let g = gain(q[0], q[1]);
                let (kx, ky) = match filter {
                    Filter::Bilinear => (1, 1),
                    Filter::Footprint => {
                        let d = grid.texel_mm;
                        let (qx, qy) = (apply(h, [c[0] + d, c[1]]), apply(h, [c[0], c[1] + d]));
                        let k = |p: [f64; 2]| {
                            let len = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                            ((len / 0.5).ceil() as usize).clamp(1, 32)
                        };
                        (k(qx), k(qy))
                    }
                };
                let w = g / (kx * ky) as f64;
                for sy in 0..ky {
                    for sx in 0..kx {
                        let p = [
                            c[0] + ((sx as f64 + 0.5) / kx as f64 - 0.5) * grid.texel_mm,
                            c[1] + ((sy as f64 + 0.5) / ky as f64 - 0.5) * grid.texel_mm,
                        ];
                        let s = apply(h, p);
                        push_bilinear(&mut taps, s[0], s[1], width, height, w);
                    }
                }
            }
        }
        starts.push(taps.len() as u32);
        Ok(Plan { n, taps, starts })
    }

    /// Taps per texel on average (the cost of the filter).
    pub fn taps_per_texel(&self) -> f64 {
        self.taps.len() as f64 / (self.n * self.n) as f64
    }

    /// Resamples one raw image: `n · n` RGB texels, row-major.
    pub fn apply(&self, img: &RawImage) -> Vec<[f32; 3]> {
        (0..self.n * self.n)
            .map(|t| {
                let mut acc = [0f32; 3];
                for &(k, w) in &self.taps[self.starts[t] as usize..self.starts[t + 1] as usize] {
                    let p = img.rgb[k as usize];
                    acc[0] += w * p[0];
                    acc[1] += w * p[1];
                    acc[2] += w * p[2];
                }
                acc
            })
            .collect()
    }
}

fn push_bilinear(taps: &mut Vec<(u32, f32)>, u: f64, v: f64, width: usize, height: usize, w: f64) {
    let (x, y) = (u - 0.5, v - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let cl = |a: f64, n: usize| (a.max(0.0) as usize).min(n - 1);
    for (dy, wy) in [(0.0, 1.0 - fy), (1.0, fy)] {
        for (dx, wx) in [(0.0, 1.0 - fx), (1.0, fx)] {
            let ww = w * wx * wy;
            if ww != 0.0 {
                let idx = cl(y0 + dy, height) * width + cl(x0 + dx, width);
                taps.push((idx as u32, ww as f32));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stripes(width: usize, height: usize, period_px: f64) -> RawImage {
        let rgb = (0..width * height)
            .map(|k| {
                let x = (k % width) as f64 + 0.5;
                let v = if (x / period_px).floor() as i64 % 2 == 0 { 1.0 } else { 0.0 };
                [v as f32; 3]
            })
            .collect();
        RawImage { width, height, rgb }
    }

    #[test]
    fn footprint_averages_what_bilinear_aliases() {
        // 1-px stripes seen with 4 px per texel horizontally: the true texel mean is ½,
        // while every texel centre falls on a bright pixel centre.
        let img = stripes(256, 64, 1.0);
        let h = Matrix3::new(4.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let grid = Grid { origin_mm: [1.125, 8.0], texel_mm: 1.0, n: 32 };
        let err = |f: Filter| {
            let plan = Plan::new(&h, &grid, 256, 64, f, |_, _| 1.0).unwrap();
            let out = plan.apply(&img);
            out.iter().map(|p| (p[0] as f64 - 0.5).abs()).fold(0.0, f64::max)
        };
        assert!(err(Filter::Footprint) < 1e-6, "{}", err(Filter::Footprint));
        assert!(err(Filter::Bilinear) > 0.4);
    }

    #[test]
    fn pixels_per_texel_are_the_footprints_axes() {
        let grid = Grid { origin_mm: [-8.0, -8.0], texel_mm: 0.5, n: 32 };
        // 3 px per mm along x, 3·cos 75° along y (a 75° view foreshortens one axis), rotated
        let (c, s) = (0.6f64, 0.8f64);
        let f = 75f64.to_radians().cos();
        let h =
            Matrix3::new(3.0 * c, -3.0 * f * s, 100.0, 3.0 * s, 3.0 * f * c, 50.0, 0.0, 0.0, 1.0);
        let [lo, hi] = pixels_per_texel(&h, &grid);
        assert!((hi - 1.5).abs() < 1e-12 && (lo - 1.5 * f).abs() < 1e-12, "{lo} {hi}");
        let [lo, hi] = pixels_per_texel(&Matrix3::identity(), &grid);
        assert!((lo - 0.5).abs() < 1e-12 && (hi - 0.5).abs() < 1e-12);
    }

    #[test]
    fn gain_scales_and_outside_is_refused() {
        let img = RawImage { width: 8, height: 8, rgb: vec![[2.0, 4.0, 8.0]; 64] };
        let grid = Grid { origin_mm: [0.0, 0.0], texel_mm: 1.0, n: 4 };
        let plan =
            Plan::new(&Matrix3::identity(), &grid, 8, 8, Filter::Footprint, |_, _| 0.5).unwrap();
        assert!(plan.apply(&img).iter().all(|p| *p == [1.0, 2.0, 4.0]));
        let far = Grid { origin_mm: [6.0, 0.0], ..grid };
        assert_eq!(
            Plan::new(&Matrix3::identity(), &far, 8, 8, Filter::Bilinear, |_, _| 1.0).unwrap_err(),
            [2, 0]
        );
    }
}
