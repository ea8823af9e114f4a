//! Sub-pixel detection of the plate's point markers and border lines in a (luminance)
//! raw image, given a predicted homography.
//!
//! A point marker is looked for inside the back-projected disc of radius `r + margin`
//! around its predicted centre: the background level is the median of the surrounding
//! annulus, the marker is the 4-connected bright component through the brightest pixel
//! of the search disc (threshold half-way between background and plateau), and its position is the
//! background-subtracted intensity centroid (a moment estimate). Components that touch
//! the search border, or whose area differs from the projected disc's (`|det J| π r²`),
//! are rejected as occluded or merged. Because the centroid of a projected disc is not the
//! projection of its centre, [`disc_centroid_bias`] gives the correction from the current
//! homography (the area centroid of the projected circle, by the polygon formula).
//!
//! A border line is sampled along its centre line; each sample's position across the line
//! is the background-subtracted centroid of a bilinear profile along the image normal of
//! the projected line.

use super::homography::apply;
use super::homography::{LineMatch, PointMatch};
use nalgebra::{Matrix3, Vector3};

/// A luminance image (row-major, top-left origin).
#[derive(Debug, Clone)]
pub struct Gray {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Values.
    pub data: Vec<f32>,
}

impl Gray {
    fn at(&self, c: usize, r: usize) -> f32 {
        self.data[r * self.width + c]
    }
    /// Bilinear value at continuous position `(u, v)` (pixel centres at `+½`), clamped.
    pub fn bilinear(&self, u: f64, v: f64) -> f64 {
        let (x, y) = (u - 0.5, v - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let cl = |a: f64, n: usize| (a.max(0.0) as usize).min(n - 1);
        let (xa, xb) = (cl(x0, self.width), cl(x0 + 1.0, self.width));
        let (ya, yb) = (cl(y0, self.height), cl(y0 + 1.0, self.height));
        let top = self.at(xa, ya) as f64 * (1.0 - fx) + self.at(xb, ya) as f64 * fx;
        let bot = self.at(xa, yb) as f64 * (1.0 - fx) + self.at(xb, yb) as f64 * fx;
        top * (1.0 - fy) + bot * fy
    }
}

/// Why a marker was not used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Miss {
    /// Its search disc is (partly) outside the image.
    OutsideImage,
    /// No marker brighter than the background (missing, dark or unlit).
    NoContrast,
    /// Its blob touches the search border or has the wrong area (occluded, merged).
    BadShape,
    /// Found, but inconsistent with the other markers under one homography.
    Outlier,
}

/// One point marker's detection.
pub type Detection = Result<[f64; 2], Miss>;

fn median(v: &mut [f32]) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let m = v.len() / 2;
    *v.select_nth_unstable_by(m, f32::total_cmp).1
}

/// Jacobian determinant (px² per mm²) of `h` at plate point `p`.
fn area_scale(h: &Matrix3<f64>, p: [f64; 2]) -> f64 {
    let e = 1e-3;
    let (a, bx, by) = (apply(h, p), apply(h, [p[0] + e, p[1]]), apply(h, [p[0], p[1] + e]));
    let (jx, jy) = ([bx[0] - a[0], bx[1] - a[1]], [by[0] - a[0], by[1] - a[1]]);
    (jx[0] * jy[1] - jx[1] * jy[0]).abs() / (e * e)
}

/// Detects the point marker centred at `centre_mm` (radius `radius_mm`) near where `h`
/// predicts it, searching `margin_mm` beyond its rim.
pub fn detect_point(
    img: &Gray,
    h: &Matrix3<f64>,
    centre_mm: [f64; 2],
    radius_mm: f64,
    margin_mm: f64,
) -> Detection {
    let hinv = h.try_inverse().ok_or(Miss::OutsideImage)?;
    let search = radius_mm + margin_mm;
    let ring: Vec<[f64; 2]> = (0..32)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 32.0;
            apply(h, [centre_mm[0] + search * a.cos(), centre_mm[1] + search * a.sin()])
        })
        .collect();
    let lo = ring.iter().fold([f64::INFINITY; 2], |m, p| [m[0].min(p[0]), m[1].min(p[1])]);
    let hi = ring.iter().fold([f64::NEG_INFINITY; 2], |m, p| [m[0].max(p[0]), m[1].max(p[1])]);
    if lo[0] < 0.0 || lo[1] < 0.0 || hi[0] >= img.width as f64 || hi[1] >= img.height as f64 {
        return Err(Miss::OutsideImage);
    }
    let (c0, r0, c1, r1) = (lo[0] as usize, lo[1] as usize, hi[0] as usize + 1, hi[1] as usize + 1);
    let (bw, bh) = (c1 - c0, r1 - r0);
    // Distance (mm, on the plate) of every pixel centre of the box from the marker centre.
    let dist: Vec<f64> = (0..bw * bh)
        .map(|k| {
            let p = apply(&hinv, [(c0 + k % bw) as f64 + 0.5, (r0 + k / bw) as f64 + 0.5]);
            ((p[0] - centre_mm[0]).powi(2) + (p[1] - centre_mm[1]).powi(2)).sqrt()
        })
        .collect();
    let val = |k: usize| img.at(c0 + k % bw, r0 + k / bw);
    let mut annulus: Vec<f32> =
        (0..bw * bh).filter(|&k| dist[k] > radius_mm + 1.0 && dist[k] <= search).map(val).collect();
    let bg = median(&mut annulus);
    let mut dev: Vec<f32> = annulus.iter().map(|v| (v - bg).abs()).collect();
    let sigma = 1.4826 * median(&mut dev).max(0.5);
    // The marker may sit up to the margin away from its prediction: seed at the brightest
    // pixel of the search disc, plateau = median of the pixels above half its contrast.
    let search_px: Vec<usize> = (0..bw * bh).filter(|&k| dist[k] <= search).collect();
    let &seed =
        search_px.iter().max_by(|&&a, &&b| val(a).total_cmp(&val(b))).ok_or(Miss::NoContrast)?;
    let half = bg + 0.5 * (val(seed) - bg);
    let mut bright: Vec<f32> = search_px.iter().map(|&k| val(k)).filter(|&v| v > half).collect();
    let level = median(&mut bright);
    if level - bg < 8.0 * sigma {
        return Err(Miss::NoContrast);
    }
    let thr = bg + 0.5 * (level - bg);
    // Every bright component of the search disc is a candidate; the marker is the one of
    // the right size that does not run into the window's rim (a border line, the sample's
    // texture or a marker cut by the rim does), nearest to the prediction. A wide window
    // may hold several; the brightest pixel alone could seed the wrong one.
    let inside = |k: usize| dist[k] <= search && val(k) > thr;
    let expected = area_scale(h, centre_mm) * std::f64::consts::PI * radius_mm * radius_mm;
    let mut labelled = vec![false; bw * bh];
    let mut best: Option<(f64, Vec<usize>)> = None;
    let mut any = false;
    for &start in std::iter::once(&seed).chain(&search_px) {
        if labelled[start] || !inside(start) {
            continue;
        }
        let blob = flood(bw, bh, start, inside);
        for &k in &blob {
            labelled[k] = true;
        }
        any = true;
        let touches = blob.iter().any(|&k| dist[k] > search - 1.0);
        let area = blob.len() as f64;
        if touches || area < 0.5 * expected - 2.0 || area > 1.6 * expected + 4.0 {
            continue;
        }
        let near = blob.iter().map(|&k| dist[k]).fold(f64::INFINITY, f64::min);
        if best.as_ref().is_none_or(|b| near < b.0) {
            best = Some((near, blob));
        }
    }
    let Some((_, blob)) = best else {
        return Err(if any { Miss::BadShape } else { Miss::NoContrast });
    };
    // Centroid over the blob grown by one pixel, weights clamped to [0, 1].
    let mut in_blob = vec![false; bw * bh];
    for &k in &blob {
        in_blob[k] = true;
    }
    let (mut sw, mut su, mut sv) = (0.0, 0.0, 0.0);
    for k in 0..bw * bh {
        let (x, y) = (k % bw, k / bw);
        let near = (y.saturating_sub(1)..(y + 2).min(bh))
            .any(|yy| (x.saturating_sub(1)..(x + 2).min(bw)).any(|xx| in_blob[yy * bw + xx]));
        if near {
            let w = ((val(k) - bg) / (level - bg)).clamp(0.0, 1.0) as f64;
            sw += w;
            su += w * ((c0 + x) as f64 + 0.5);
            sv += w * ((r0 + y) as f64 + 0.5);
        }
    }
    let centroid = [su / sw, sv / sw];
    if centroid.iter().all(|v| v.is_finite()) { Ok(centroid) } else { Err(Miss::NoContrast) }
}

fn flood(bw: usize, bh: usize, seed: usize, inside: impl Fn(usize) -> bool) -> Vec<usize> {
    let mut seen = vec![false; bw * bh];
    let (mut stack, mut out) = (vec![seed], Vec::new());
    seen[seed] = true;
    while let Some(k) = stack.pop() {
        if !inside(k) {
            continue;
        }
        out.push(k);
        let (x, y) = (k % bw, k / bw);
        let mut push = |n: usize| {
            if !seen[n] {
                seen[n] = true;
                stack.push(n);
            }
        };
        if x > 0 {
            push(k - 1)
        }
        if x + 1 < bw {
            push(k + 1)
        }
        if y > 0 {
            push(k - bw)
        }
        if y + 1 < bh {
            push(k + bw)
        }
    }
    out
}

/// Image offset (pixels) of the area centroid of the projected disc from the projected
/// centre, under `h`: subtract it from a measured centroid to get the centre's image.
pub fn disc_centroid_bias(h: &Matrix3<f64>, centre_mm: [f64; 2], radius_mm: f64) -> [f64; 2] {
    let n = 256;
    let poly: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / n as f64;
            apply(h, [centre_mm[0] + radius_mm * a.cos(), centre_mm[1] + radius_mm * a.sin()])
        })
        .collect();
    let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let cr = p[0] * q[1] - q[0] * p[1];
        a2 += cr;
        cx += (p[0] + q[0]) * cr;
        cy += (p[1] + q[1]) * cr;
    }
    let c = apply(h, centre_mm);
    [cx / (3.0 * a2) - c[0], cy / (3.0 * a2) - c[1]]
}

/// Point matches of every detected marker, centroid bias removed with `h`.
pub fn corrected_matches(
    h: &Matrix3<f64>,
    markers_mm: &[[f64; 2]],
    radius_mm: f64,
    found: &[Detection],
) -> Vec<PointMatch> {
    markers_mm
        .iter()
        .zip(found)
        .filter_map(|(m, d)| {
            let p = d.ok()?;
            let b = disc_centroid_bias(h, *m, radius_mm);
            let image_px = [p[0] - b[0], p[1] - b[1]];
            image_px.iter().all(|v| v.is_finite()).then_some(PointMatch { plate_mm: *m, image_px })
        })
        .collect()
}

/// Samples the four border lines (centre lines at `±offset_mm`, width `width_mm`) along
/// their inner `±span_mm`, returning the observed centre positions.
pub fn sample_border_lines(
    img: &Gray,
    h: &Matrix3<f64>,
    offset_mm: f64,
    width_mm: f64,
    span_mm: f64,
) -> Vec<LineMatch> {
    let Some(hinv) = h.try_inverse() else { return Vec::new() };
    let mut out = Vec::new();
    for (axis, sign) in [(0usize, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)] {
        let line =
            if axis == 0 { [1.0, 0.0, -sign * offset_mm] } else { [0.0, 1.0, -sign * offset_mm] };
        let l = hinv.transpose() * Vector3::from(line);
        let norm = (l.x * l.x + l.y * l.y).sqrt();
        let n_img = [l.x / norm, l.y / norm];
        let at = |s: f64| if axis == 0 { [sign * offset_mm, s] } else { [s, sign * offset_mm] };
        let (a, b) = (apply(h, at(-span_mm)), apply(h, at(span_mm)));
        let len_px = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        let count = (len_px as usize).clamp(8, 2000);
        for k in 0..count {
            let s = -span_mm + 2.0 * span_mm * (k as f64 + 0.5) / count as f64;
            if let Some(q) = line_centre(img, h, at(s), axis, n_img, width_mm) {
                out.push(LineMatch { plate_line: line, image_px: q });
            }
        }
    }
    out
}

/// The observed centre of the line through plate point `p_mm` (across `axis`), searched
/// along the image normal `n_img`.
fn line_centre(
    img: &Gray,
    h: &Matrix3<f64>,
    p_mm: [f64; 2],
    axis: usize,
    n_img: [f64; 2],
    width_mm: f64,
) -> Option<[f64; 2]> {
    let q0 = apply(h, p_mm);
    let mut off = p_mm;
    off[axis] += 1.0;
    let q1 = apply(h, off);
    let px_per_mm = ((q1[0] - q0[0]) * n_img[0] + (q1[1] - q0[1]) * n_img[1]).abs();
    let (half, reach) = ((width_mm / 2.0 + 1.0) * px_per_mm, (width_mm / 2.0 + 2.5) * px_per_mm);
    if !(px_per_mm > 1e-3 && reach < 200.0) {
        return None;
    }
    let inside =
        |u: f64, v: f64| u >= 0.0 && v >= 0.0 && u < img.width as f64 && v < img.height as f64;
    let (e0, e1) = (
        [q0[0] - reach * n_img[0], q0[1] - reach * n_img[1]],
        [q0[0] + reach * n_img[0], q0[1] + reach * n_img[1]],
    );
    if !inside(e0[0], e0[1]) || !inside(e1[0], e1[1]) {
        return None;
    }
    let steps = ((2.0 * reach / 0.25) as usize).max(16);
    let prof: Vec<(f64, f64)> = (0..=steps)
        .map(|k| {
            let s = -reach + 2.0 * reach * k as f64 / steps as f64;
            (s, img.bilinear(q0[0] + s * n_img[0], q0[1] + s * n_img[1]))
        })
        .collect();
    let mut outer: Vec<f32> =
        prof.iter().filter(|(s, _)| s.abs() > half).map(|(_, v)| *v as f32).collect();
    let bg = median(&mut outer) as f64;
    let peak = prof.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    if outer.len() < 4 || peak - bg < 4.0 * (bg.max(1.0)).sqrt() {
        return None;
    }
    let (mut sw, mut ss) = (0.0, 0.0);
    for &(s, v) in prof.iter().filter(|(s, _)| s.abs() <= half) {
        let w = (v - bg).max(0.0);
        sw += w;
        ss += w * s;
    }
    let s = ss / sw;
    (sw > 0.0 && s.abs() < half).then(|| [q0[0] + s * n_img[0], q0[1] + s * n_img[1]])
}

/// The plate's nine point markers of the default capture layout (mm; the last one the
/// orientation marker), for this crate's unit tests.
#[cfg(test)]
pub(crate) const TEST_MARKS: [[f64; 2]; 9] = [
    [-60.0, -60.0],
    [0.0, -60.0],
    [60.0, -60.0],
    [60.0, 0.0],
    [60.0, 60.0],
    [0.0, 60.0],
    [-60.0, 60.0],
    [-60.0, 0.0],
    [30.0, 60.0],
];

#[cfg(test)]
mod tests {
    use super::*;

    const MARKS: [[f64; 2]; 9] = TEST_MARKS;

    /// Point-sampled plate (as the virtual gonioreflectometer renders it), `ss²` samples
    /// per pixel.
    fn render(h: &Matrix3<f64>, w: usize, hgt: usize, ss: usize) -> Gray {
        let hinv = h.try_inverse().unwrap();
        let albedo = |p: [f64; 2]| {
            if MARKS.iter().any(|m| (p[0] - m[0]).powi(2) + (p[1] - m[1]).powi(2) <= 16.0) {
                return 1000.0;
            }
            let on = |u: f64, v: f64| (u.abs() - 46.0).abs() <= 1.5 && v.abs() <= 47.5;
            if on(p[0], p[1]) || on(p[1], p[0]) { 1000.0 } else { 50.0 }
        };
        let data = (0..w * hgt)
            .map(|k| {
                let mut s = 0.0;
                for a in 0..ss * ss {
                    let (dx, dy) =
                        (((a % ss) as f64 + 0.5) / ss as f64, ((a / ss) as f64 + 0.5) / ss as f64);
                    s += albedo(apply(&hinv, [(k % w) as f64 + dx, (k / w) as f64 + dy]));
                }
                (s / (ss * ss) as f64) as f32
            })
            .collect();
        Gray { width: w, height: hgt, data }
    }

    fn frontal() -> Matrix3<f64> {
        // 0.96 px/mm, image up = +y, centred in 320×240, slightly tilted.
        Matrix3::new(0.96, 0.01, 160.3, 0.008, -0.95, 120.2, 1e-5, 2e-5, 1.0)
    }

    #[test]
    fn markers_are_found_to_a_tenth_of_a_pixel() {
        // With the pixel area integrated (4×4 samples) as a real sensor does; a point-sampled
        // image is only good to ~0.2 px (its disc edge is aliased).
        for ss in [4] {
            let h = frontal();
            let img = render(&h, 320, 240, ss);
            let mut worst = 0f64;
            for m in MARKS {
                let p = detect_point(&img, &h, m, 4.0, 6.0).unwrap();
                let b = disc_centroid_bias(&h, m, 4.0);
                let t = apply(&h, m);
                worst =
                    worst.max(((p[0] - b[0] - t[0]).powi(2) + (p[1] - b[1] - t[1]).powi(2)).sqrt());
            }
            assert!(worst < 0.1, "supersampling {ss}: worst marker error {worst} px");
        }
    }

    #[test]
    fn line_samples_lie_on_the_projected_lines() {
        let h = frontal();
        let img = render(&h, 320, 240, 4);
        let lines = sample_border_lines(&img, &h, 46.0, 3.0, 40.0);
        assert!(lines.len() > 200, "{}", lines.len());
        let mean: f64 =
            lines.iter().map(|l| super::super::homography::line_error(&h, l)).sum::<f64>()
                / lines.len() as f64;
        let rms = (lines
            .iter()
            .map(|l| super::super::homography::line_error(&h, l).powi(2))
            .sum::<f64>()
            / lines.len() as f64)
            .sqrt();
        assert!(mean.abs() < 0.02 && rms < 0.15, "mean {mean}, rms {rms}");
    }

    #[test]
    fn an_occluded_marker_is_reported_not_misplaced() {
        let h = frontal();
        let mut img = render(&h, 320, 240, 1);
        // Cover the right half of marker 3 with plate.
        let c = apply(&h, [60.0, 0.0]);
        for r in 0..240 {
            for col in 0..320 {
                let (dx, dy) = (col as f64 + 0.5 - c[0], r as f64 + 0.5 - c[1]);
                if dx > -0.5 && dx * dx + dy * dy < 49.0 {
                    img.data[r * 320 + col] = 50.0;
                }
            }
        }
        assert_eq!(detect_point(&img, &h, [60.0, 0.0], 4.0, 6.0), Err(Miss::BadShape));
        assert!(detect_point(&img, &h, [0.0, 60.0], 4.0, 6.0).is_ok());
    }
}
