//! Robust plane homographies (sample mm → image pixels) from marker correspondences: the
//! normalised direct linear transform (Hartley & Zisserman, *Multiple View Geometry*,
//! Alg. 4.2, eq. 4.3 solved by SVD), outlier rejection by exhaustive minimal-set consensus
//! (RANSAC with every 4-subset, which is cheap for a dozen markers), and Levenberg–Marquardt
//! refinement of the geometric error (H&Z eq. 4.8) over point residuals plus point-on-line
//! residuals for samples of the border lines.

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, Vector3};

/// A point correspondence: plate mm ↔ image pixels.
#[derive(Debug, Clone, Copy)]
pub struct PointMatch {
    /// Position on the plate (mm).
    pub plate_mm: [f64; 2],
    /// Observed image position (pixels).
    pub image_px: [f64; 2],
}

/// An image point observed on a known plate line `a·x + b·y + c = 0` (mm).
#[derive(Debug, Clone, Copy)]
pub struct LineMatch {
    /// The plate line `(a, b, c)`.
    pub plate_line: [f64; 3],
    /// Observed image position (pixels).
    pub image_px: [f64; 2],
}

/// Similarity that centres points and scales their mean distance to √2 (H&Z §4.4.4).
fn normaliser(pts: &[[f64; 2]]) -> Matrix3<f64> {
    let n = pts.len().max(1) as f64;
    let (mx, my) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p[0] / n, a.1 + p[1] / n));
    let d = pts.iter().map(|p| ((p[0] - mx).powi(2) + (p[1] - my).powi(2)).sqrt()).sum::<f64>() / n;
    let s = if d > 1e-12 { std::f64::consts::SQRT_2 / d } else { 1.0 };
    Matrix3::new(s, 0.0, -s * mx, 0.0, s, -s * my, 0.0, 0.0, 1.0)
}

/// Whether three plate points are collinear to within a relative `1e-3` (the sine of the
/// angle they make).
fn collinear(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
    let cross = (u[0] * v[1] - u[1] * v[0]).abs();
    cross <= 1e-3 * u[0].hypot(u[1]) * v[0].hypot(v[1])
}

/// Applies a homography to a point.
pub fn apply(h: &Matrix3<f64>, p: [f64; 2]) -> [f64; 2] {
    let q = h * Vector3::new(p[0], p[1], 1.0);
    [q.x / q.z, q.y / q.z]
}

/// Whether some four of `pts` have no three on a line — what a plane homography needs to
/// be determined.
pub fn general_position(pts: &[[f64; 2]]) -> bool {
    let n = pts.len();
    if n < 4 {
        return false;
    }
    let mut idx = [0usize, 1, 2, 3];
    loop {
        let q = idx.map(|i| pts[i]);
        let bad = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
            .iter()
            .any(|&(i, j, k)| collinear(q[i], q[j], q[k]));
        if !bad {
            return true;
        }
        if !next_combination(&mut idx, n) {
            return false;
        }
    }
}

/// Normalised DLT from ≥ 4 correspondences; `None` when they are degenerate (no four of the
/// plate points in general position) or not finite (a NaN makes the SVD iterate forever).
pub fn dlt(matches: &[PointMatch]) -> Option<Matrix3<f64>> {
    let finite = |m: &PointMatch| m.plate_mm.iter().chain(&m.image_px).all(|v| v.is_finite());
    if matches.len() < 4 || !matches.iter().all(finite) {
        return None;
    }
    let plate: Vec<[f64; 2]> = matches.iter().map(|m| m.plate_mm).collect();
    if !general_position(&plate) {
        // Three of four on a line (or all on one): a whole family of homographies fits.
        return None;
    }
    let image: Vec<[f64; 2]> = matches.iter().map(|m| m.image_px).collect();
    let (tp, ti) = (normaliser(&plate), normaliser(&image));
    let mut a = DMatrix::<f64>::zeros(2 * matches.len().max(5), 9);
    for (k, m) in matches.iter().enumerate() {
        let [x, y] = apply(&tp, m.plate_mm);
        let [u, v] = apply(&ti, m.image_px);
        let r0 = [0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v];
        let r1 = [x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u];
        for c in 0..9 {
            a[(2 * k, c)] = r0[c];
            a[(2 * k + 1, c)] = r1[c];
        }
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    let (imin, smin) = svd
        .singular_values
        .iter()
        .enumerate()
        .fold((0, f64::INFINITY), |b, (i, &s)| if s < b.1 { (i, s) } else { b });
    let s_sorted = {
        let mut s: Vec<f64> = svd.singular_values.iter().copied().collect();
        s.sort_by(f64::total_cmp);
        s
    };
    // The null space must be one-dimensional: the second-smallest singular value must be
    // clearly above the smallest (collinear points make it two-dimensional).
    if s_sorted.len() < 9 || s_sorted[1] < 1e-9 * s_sorted[8] || !smin.is_finite() {
        return None;
    }
    let h = v_t.row(imin);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let h = ti.try_inverse()? * hn * tp;
    let scale = h[(2, 2)];
    (scale.abs() > 1e-300 && h.iter().all(|v| v.is_finite())).then(|| h / scale)
}

/// Reprojection error (pixels) of a point match.
pub fn point_error(h: &Matrix3<f64>, m: &PointMatch) -> f64 {
    let p = apply(h, m.plate_mm);
    ((p[0] - m.image_px[0]).powi(2) + (p[1] - m.image_px[1]).powi(2)).sqrt()
}

/// Signed distance (pixels) of a line observation from the projected plate line.
pub fn line_error(h: &Matrix3<f64>, m: &LineMatch) -> f64 {
    let Some(hinv) = h.try_inverse() else { return f64::INFINITY };
    let l = hinv.transpose() * Vector3::from(m.plate_line);
    (l.x * m.image_px[0] + l.y * m.image_px[1] + l.z) / (l.x * l.x + l.y * l.y).sqrt()
}

/// Exhaustive consensus over 4-subsets: the homography with the most matches within
/// `tol_px` (ties broken by the smaller summed error), re-estimated on its inliers. Returns
/// it with the inlier flags, or `None` when no subset gives ≥ 4 inliers.
pub fn consensus(matches: &[PointMatch], tol_px: f64) -> Option<(Matrix3<f64>, Vec<bool>)> {
    let n = matches.len();
    if n < 4 {
        return None;
    }
    let mut best: Option<(usize, f64, Matrix3<f64>)> = None;
    let mut idx = [0usize, 1, 2, 3];
    loop {
        let subset: Vec<PointMatch> = idx.iter().map(|&i| matches[i]).collect();
        if let Some(h) = dlt(&subset) {
            let errs: Vec<f64> = matches.iter().map(|m| point_error(&h, m)).collect();
            let count = errs.iter().filter(|e| **e <= tol_px).count();
            let cost: f64 = errs.iter().map(|e| e.min(tol_px)).sum();
            if best.as_ref().is_none_or(|b| count > b.0 || (count == b.0 && cost < b.1)) {
                best = Some((count, cost, h));
            }
        }
        if !next_combination(&mut idx, n) {
            break;
        }
    }
    let (count, _, h) = best?;
    if count < 4 {
        return None;
    }
    let inliers: Vec<bool> = matches.iter().map(|m| point_error(&h, m) <= tol_px).collect();
    let kept: Vec<PointMatch> =
        matches.iter().zip(&inliers).filter(|(_, k)| **k).map(|(m, _)| *m).collect();
    Some((dlt(&kept).unwrap_or(h), inliers))
}

fn next_combination(idx: &mut [usize; 4], n: usize) -> bool {
    let k = idx.len();
    for i in (0..k).rev() {
        if idx[i] < n - k + i {
            idx[i] += 1;
            for j in i + 1..k {
                idx[j] = idx[j - 1] + 1;
            }
            return true;
        }
    }
    false
}

fn residuals(
    h: &Matrix3<f64>,
    points: &[PointMatch],
    lines: &[LineMatch],
    w_line: f64,
) -> DVector<f64> {
    let mut r = Vec::with_capacity(2 * points.len() + lines.len());
    for m in points {
        let p = apply(h, m.plate_mm);
        r.push(p[0] - m.image_px[0]);
        r.push(p[1] - m.image_px[1]);
    }
    r.extend(lines.iter().map(|m| w_line * line_error(h, m)));
    DVector::from_vec(r)
}

/// Levenberg–Marquardt refinement of the summed squared geometric error: point residuals
/// and, weighted by `w_line`, point-on-line distances. The 8 free entries are perturbed in
/// a frame normalised by the image-side similarity so that the steps are well scaled.
pub fn refine(
    h0: &Matrix3<f64>,
    points: &[PointMatch],
    lines: &[LineMatch],
    w_line: f64,
) -> Matrix3<f64> {
    let image: Vec<[f64; 2]> = points.iter().map(|m| m.image_px).collect();
    let ti = normaliser(&image);
    let Some(ti_inv) = ti.try_inverse() else { return *h0 };
    let hn0 = ti * h0;
    let scale = hn0[(2, 2)];
    let to_h = |p: &SMatrix<f64, 8, 1>| {
        let hn = Matrix3::new(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], scale);
        ti_inv * hn
    };
    // Row-major free entries; `h₃₃` stays fixed at its starting value.
    let mut p = SMatrix::<f64, 8, 1>::from_fn(|k, _| hn0[(k / 3, k % 3)]);
    let mut r = residuals(&to_h(&p), points, lines, w_line);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..50 {
        let mut jac = DMatrix::<f64>::zeros(r.len(), 8);
        for k in 0..8 {
            let step = 1e-7 * p[k].abs().max(1e-3);
            let mut q = p;
            q[k] += step;
            let rk = residuals(&to_h(&q), points, lines, w_line);
            jac.set_column(k, &((rk - &r) / step));
        }
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * &r;
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj.clone();
            for k in 0..8 {
                a[(k, k)] *= 1.0 + lambda;
            }
            let Some(delta) = a.lu().solve(&(-&jtr)) else { break };
            let q = p + SMatrix::<f64, 8, 1>::from_iterator(delta.iter().copied());
            let rq = residuals(&to_h(&q), points, lines, w_line);
            let cq = rq.norm_squared();
            if cq.is_finite() && cq < cost {
                let gain = (cost - cq) / cost.max(1e-300);
                (p, r, cost) = (q, rq, cq);
                lambda = (lambda * 0.3).max(1e-12);
                improved = gain > 1e-12;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let h = to_h(&p);
    h / h[(2, 2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth() -> Matrix3<f64> {
        Matrix3::new(3.1, 0.2, 160.0, -0.1, -2.9, 120.0, 0.0004, 0.0011, 1.0)
    }

    fn layout() -> Vec<[f64; 2]> {
        let a = 60.0;
        vec![
            [-a, -a],
            [0.0, -a],
            [a, -a],
            [a, 0.0],
            [a, a],
            [0.0, a],
            [-a, a],
            [-a, 0.0],
            [30.0, a],
        ]
    }

    fn matches(h: &Matrix3<f64>) -> Vec<PointMatch> {
        layout().into_iter().map(|p| PointMatch { plate_mm: p, image_px: apply(h, p) }).collect()
    }

    #[test]
    fn three_markers_on_a_line_do_not_fix_a_homography() {
        // The case seen on a 60° view: one bottom row of markers plus one more. Three of
        // the four are collinear, so every homography of a one-parameter family fits them.
        let m = matches(&truth());
        let l_shape = [m[0], m[1], m[2], m[3]];
        assert!(dlt(&l_shape).is_none());
        assert!(consensus(&l_shape, 2.0).is_none());
        // Any fourth marker off that line settles it.
        let h = dlt(&[m[0], m[2], m[3], m[6]]).unwrap();
        assert!(m.iter().all(|p| point_error(&h, p) < 1e-6));
        assert!(!general_position(&layout()[..3]));
        assert!(!general_position(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]));
        assert!(general_position(&layout()));
    }

    #[test]
    fn dlt_recovers_an_exact_homography() {
        let h = dlt(&matches(&truth())).unwrap();
        for p in layout() {
            let (a, b) = (apply(&h, p), apply(&truth(), p));
            assert!((a[0] - b[0]).abs() < 1e-8 && (a[1] - b[1]).abs() < 1e-8);
        }
    }

    #[test]
    fn non_finite_points_are_refused() {
        let mut pts: Vec<PointMatch> = layout()
            .into_iter()
            .map(|p| PointMatch { plate_mm: p, image_px: [p[0] * 2.0 + 5.0, p[1] * 3.0] })
            .collect();
        assert!(dlt(&pts).is_some());
        pts[2].image_px[1] = f64::NAN;
        assert!(dlt(&pts).is_none());
    }

    #[test]
    fn collinear_points_are_refused() {
        let m: Vec<PointMatch> = (0..5)
            .map(|k| PointMatch { plate_mm: [k as f64, 0.0], image_px: [2.0 * k as f64, 1.0] })
            .collect();
        assert!(dlt(&m).is_none());
    }

    #[test]
    fn consensus_drops_a_gross_outlier_and_refine_fits_lines() {
        let mut m = matches(&truth());
        m[3].image_px[0] += 25.0;
        let (h, inl) = consensus(&m, 1.0).unwrap();
        assert_eq!(inl.iter().filter(|k| !**k).count(), 1);
        assert!(!inl[3]);
        // Lines alone pin the homography together with the points: perturb and refine.
        let lines: Vec<LineMatch> = (0..20)
            .map(|k| {
                let y = -40.0 + 4.0 * k as f64;
                LineMatch { plate_line: [1.0, 0.0, -46.0], image_px: apply(&truth(), [46.0, y]) }
            })
            .collect();
        let kept: Vec<PointMatch> =
            m.iter().zip(&inl).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
        let h1 = refine(
            &(h * Matrix3::new(1.0, 0.001, 0.05, 0.0, 1.0, -0.03, 0.0, 0.0, 1.0)),
            &kept,
            &lines,
            1.0,
        );
        for p in layout() {
            assert!(
                point_error(&h1, &PointMatch { plate_mm: p, image_px: apply(&truth(), p) }) < 1e-6
            );
        }
        assert!(lines.iter().all(|l| line_error(&h1, l).abs() < 1e-6));
    }
}
