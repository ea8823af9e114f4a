//! Images: stratified pixel supersampling over a camera, one path per sample, a
//! deterministic seed per (pixel, sample), and per-pixel statistics.
//!
//! **Samples.** `spp = k_x·k_y` strata (the most square factorisation), one jittered sample
//! in each ([`PixelSampler::Stratified`]); [`PixelSampler::Random`] draws the positions
//! independently (for measuring the `1/√spp` law). Every random number of sample `s` of
//! pixel `(i, j)` comes from the stream `hash(seed, i, j, s)`, and rows are computed in
//! parallel but kept in order, so an image has identical bits for any thread count.
//!
//! **Per pixel:** the mean radiance, the variance of that mean (the sample variance by
//! Welford's update divided by `spp`; with stratification it overestimates the error, so
//! tests using it are conservative), the fraction of camera rays that hit a fiber
//! (coverage) and the fraction that reached the backing plane (direct transmittance).

use crate::camera::Camera;
use crate::integrator::{FirstHit, PathSettings, Scene, trace_path};
use crate::rng::Rng;
use crate::{Error, Result};
use rayon::prelude::*;
use std::time::Instant;

/// How sample positions are placed in a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelSampler {
    /// One jittered sample per stratum of a `k_x × k_y` grid.
    Stratified,
    /// Independent uniform positions.
    Random,
}

/// Image options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of every random number.
    pub seed: u64,
    /// Sample placement.
    pub sampler: PixelSampler,
    /// Path options.
    pub path: PathSettings,
}

impl RenderSettings {
    /// `w × h`, `spp` stratified samples, seed 1, default paths.
    pub fn new(width: usize, height: usize, spp: u32) -> Self {
        RenderSettings {
            width,
            height,
            spp,
            seed: 1,
            sampler: PixelSampler::Stratified,
            path: PathSettings::default(),
        }
    }
}

/// A rendered image with per-pixel statistics (row-major, RGB interleaved).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Mean radiance.
    pub rgb: Vec<f32>,
    /// Variance of the mean, per channel.
    pub variance: Vec<f32>,
    /// Fraction of camera rays hitting a fiber first.
    pub coverage: Vec<f32>,
    /// Fraction of camera rays reaching the backing plane.
    pub backing: Vec<f32>,
}

impl Image {
    /// Pixel `(x, y)`'s mean radiance.
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        let i = 3 * (y * self.width + x);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Standard error of pixel `(x, y)`'s channel `c`.
    pub fn std_error(&self, x: usize, y: usize, c: usize) -> f64 {
        (self.variance[3 * (y * self.width + x) + c] as f64).max(0.0).sqrt()
    }

    /// Mean of the backing fractions (the direct transmittance of a patch).
    pub fn mean_backing(&self) -> f64 {
        self.backing.iter().map(|v| *v as f64).sum::<f64>() / self.backing.len().max(1) as f64
    }
}

/// Work done.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RenderStats {
    /// Camera rays.
    pub camera_rays: u64,
    /// All rays (camera, continuation, shadow).
    pub rays: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl RenderStats {
    /// Rays per second.
    pub fn rays_per_second(&self) -> f64 {
        if self.seconds > 0.0 { self.rays as f64 / self.seconds } else { 0.0 }
    }
}

/// One finished row: mean, variance, coverage, backing fractions, rays.
type Row = (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>, u64);

/// The most square `k_x × k_y = n` (`k_x ≤ k_y`).
pub fn strata(n: u32) -> (u32, u32) {
    let mut kx = (n as f64).sqrt().floor() as u32;
    while kx > 1 && !n.is_multiple_of(kx) {
        kx -= 1;
    }
    let kx = kx.max(1);
    (kx, n / kx)
}

/// Largest image accepted (pixels).
pub const MAX_PIXELS: usize = 1 << 26;

/// Renders `scene` through `camera`.
pub fn render(scene: &Scene, camera: &Camera, s: &RenderSettings) -> Result<(Image, RenderStats)> {
    render_with(scene, camera, s, &|| {})
}

/// [`render`], calling `on_row` after each finished row (for a progress bar).
pub fn render_with(
    scene: &Scene,
    camera: &Camera,
    s: &RenderSettings,
    on_row: &(dyn Fn() + Sync),
) -> Result<(Image, RenderStats)> {
    if s.path.max_bounces == 0 {
        return Err(Error::Invalid("max_bounces must be ≥ 1".into()));
    }
    let top = scene.fibers.z_range()[1];
    render_pixels(camera, s, top, on_row, |o, d, rng| {
        let r = trace_path(scene, o, d, rng, &s.path);
        (r.radiance, r.first, r.rays)
    })
}

/// The pixel loop shared by the path tracer and the volume marcher: `radiance(o, d, rng)`
/// returns one sample's radiance, what the camera ray hit first, and the rays it traced.
pub fn render_pixels(
    camera: &Camera,
    s: &RenderSettings,
    top: f64,
    on_row: &(dyn Fn() + Sync),
    radiance: impl Fn([f64; 3], [f64; 3], &mut Rng) -> ([f64; 3], FirstHit, u64) + Sync,
) -> Result<(Image, RenderStats)> {
    let (w, h) = (s.width, s.height);
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS || s.spp == 0 {
        return Err(Error::Invalid(format!(
            "image {w}×{h} with {} samples per pixel (1..={MAX_PIXELS} pixels, spp ≥ 1)",
            s.spp
        )));
    }
    let t0 = Instant::now();
    let (kx, ky) = strata(s.spp);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut rgb = vec![0f32; 3 * w];
            let mut var = vec![0f32; 3 * w];
            let mut cov = vec![0f32; w];
            let mut back = vec![0f32; w];
            let mut rays = 0u64;
            for x in 0..w {
                let mut mean = [0.0f64; 3];
                let mut m2 = [0.0f64; 3];
                let (mut hits, mut backs) = (0u32, 0u32);
                for k in 0..s.spp {
                    let mut rng = Rng::new(&[s.seed, x as u64, y as u64, k as u64]);
                    let [u, v] = rng.uniform2();
                    let (fx, fy) = match s.sampler {
                        PixelSampler::Stratified => {
                            (((k % kx) as f64 + u) / kx as f64, ((k / kx) as f64 + v) / ky as f64)
                        }
                        PixelSampler::Random => (u, v),
                    };
                    let (o, d) = camera.ray(x as f64 + fx, y as f64 + fy, w, h, top);
                    let (l, first, r) = radiance(o, d, &mut rng);
                    rays += r;
                    match first {
                        FirstHit::Fiber => hits += 1,
                        FirstHit::Backing => backs += 1,
                        FirstHit::Escaped => {}
                    }
                    let n = (k + 1) as f64;
                    for c in 0..3 {
                        let delta = l[c] - mean[c];
                        mean[c] += delta / n;
                        m2[c] += delta * (l[c] - mean[c]);
                    }
                }
                let n = s.spp as f64;
                for c in 0..3 {
                    rgb[3 * x + c] = mean[c] as f32;
                    var[3 * x + c] = if s.spp > 1 { (m2[c] / (n - 1.0) / n) as f32 } else { 0.0 };
                }
                cov[x] = hits as f32 / s.spp as f32;
                back[x] = backs as f32 / s.spp as f32;
            }
            on_row();
            (rgb, var, cov, back, rays)
        })
        .collect();
    let mut img = Image {
        width: w,
        height: h,
        rgb: Vec::with_capacity(3 * w * h),
        variance: Vec::with_capacity(3 * w * h),
        coverage: Vec::with_capacity(w * h),
        backing: Vec::with_capacity(w * h),
    };
    let mut rays = 0;
    for (rgb, var, cov, back, r) in rows {
        img.rgb.extend(rgb);
        img.variance.extend(var);
        img.coverage.extend(cov);
        img.backing.extend(back);
        rays += r;
    }
    if let Some(i) = img.rgb.iter().position(|v| !v.is_finite()) {
        return Err(Error::Invalid(format!(
            "pixel ({}, {}) came out non-finite ({}): a light or BCSDF parameter out of range?",
            (i / 3) % w,
            i / 3 / w,
            img.rgb[i]
        )));
    }
    let stats = RenderStats {
        camera_rays: (w * h) as u64 * s.spp as u64,
        rays,
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((img, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_are_the_most_square_factorisation() {
        assert_eq!(strata(16), (4, 4));
        assert_eq!(strata(8), (2, 4));
        assert_eq!(strata(7), (1, 7));
        assert_eq!(strata(1), (1, 1));
        assert_eq!(strata(64), (8, 8));
    }
}
