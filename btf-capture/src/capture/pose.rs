//! The plate pose behind a few point markers, for the registration's pose search.
//!
//! A view's homography (sample mm → pixels) is `K · A · [r₁ r₂ t − c]` for the plate pose
//! `p_lab = R · p + t` ([`CaptureLayout::homography`]). When the robot misplaces the plate
//! by more than the search windows allow (a 4.5° tilt at θ_v = 75° moves the far markers by
//! some 18 mm on the plate), the homography of a marker subset is not defined (three
//! markers, or a collinear four) and the nominal one is too far off to look around. The
//! pose is: six parameters, the rotation vector `ω` (`R = exp([ω]×)`, lab frame, rad) and the
//! translation `t` (mm) away from nominal. They are fitted to the markers' image positions
//! by Levenberg–Marquardt on the reprojection error (Hartley & Zisserman, *Multiple View
//! Geometry*, §A6.2), with the robot's placement error as a Gaussian prior: extra residuals
//! `ωᵢ / σ_ω` and `tᵢ / σ_t` beside the pixel residuals (σ = 1 px), a maximum a posteriori
//! estimate. Three markers fix all six parameters and the prior only picks the solution
//! near the nominal pose among the perspective-three-point ambiguities; two fix four and the
//! prior holds the rest at nominal. The result is a prediction to search around, never a
//! registration: the homography the store records is always fitted to ≥ 4 agreeing markers.

use super::homography::apply;
use super::layout::CaptureLayout;
use nalgebra::{Matrix3, Rotation3, SMatrix, SVector, Vector3};

/// A plate pose away from nominal: `[ω_x, ω_y, ω_z]` (rad), `[t_x, t_y, t_z]` (mm).
pub type Pose = SVector<f64, 6>;

/// The Gaussian prior of the plate's placement error (standard deviations).
#[derive(Debug, Clone, Copy)]
pub struct Prior {
    /// Rotation about any axis (degrees).
    pub rotation_deg: f64,
    /// Translation along any axis (mm).
    pub translation_mm: f64,
}

/// The homography of view `view` with the plate at `pose`.
pub fn homography(layout: &CaptureLayout, view: usize, pose: &Pose) -> Matrix3<f64> {
    let r = Rotation3::new(Vector3::new(pose[0], pose[1], pose[2])).into_inner();
    layout.homography(view, &r, &Vector3::new(pose[3], pose[4], pose[5]))
}

fn residuals(
    layout: &CaptureLayout,
    view: usize,
    matches: &[([f64; 2], [f64; 2])],
    pose: &Pose,
    prior: &Prior,
) -> Vec<f64> {
    let h = homography(layout, view, pose);
    let (sr, st) = (prior.rotation_deg.to_radians(), prior.translation_mm);
    let mut r = Vec::with_capacity(2 * matches.len() + 6);
    for (mm, px) in matches {
        let p = apply(&h, *mm);
        r.push(p[0] - px[0]);
        r.push(p[1] - px[1]);
    }
    r.extend((0..3).map(|k| pose[k] / sr));
    r.extend((3..6).map(|k| pose[k] / st));
    r
}

/// The maximum a posteriori pose behind `matches` (plate mm, image px), starting from
/// `start`; `None` when the fit does not converge to finite values.
pub fn fit(
    layout: &CaptureLayout,
    view: usize,
    matches: &[([f64; 2], [f64; 2])],
    start: &Pose,
    prior: &Prior,
) -> Option<Pose> {
    let cost_of = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut p = *start;
    let mut r = residuals(layout, view, matches, &p, prior);
    let mut cost = cost_of(&r);
    let mut lambda = 1e-3;
    // Steps for the forward differences: 1 µrad and 1 µm.
    let step = |k: usize| if k < 3 { 1e-6 } else { 1e-3 };
    for _ in 0..40 {
        let mut jtj = SMatrix::<f64, 6, 6>::zeros();
        let mut jtr = SVector::<f64, 6>::zeros();
        let cols: Vec<Vec<f64>> = (0..6)
            .map(|k| {
                let mut q = p;
                q[k] += step(k);
                let rk = residuals(layout, view, matches, &q, prior);
                rk.iter().zip(&r).map(|(a, b)| (a - b) / step(k)).collect()
            })
            .collect();
        for a in 0..6 {
            jtr[a] = cols[a].iter().zip(&r).map(|(j, e)| j * e).sum();
            for b in 0..6 {
                jtj[(a, b)] = cols[a].iter().zip(&cols[b]).map(|(x, y)| x * y).sum();
            }
        }
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj;
            for k in 0..6 {
                a[(k, k)] *= 1.0 + lambda;
            }
            let Some(delta) = a.lu().solve(&(-jtr)) else { break };
            let q = p + delta;
            let rq = residuals(layout, view, matches, &q, prior);
            let cq = cost_of(&rq);
            if cq.is_finite() && cq < cost {
                let gain = (cost - cq) / cost.max(1e-300);
                (p, r, cost) = (q, rq, cq);
                lambda = (lambda * 0.3).max(1e-12);
                improved = gain > 1e-10;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    p.iter().all(|v| v.is_finite()).then_some(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::layout::tests::layout as test_layout;

    const MARKS: [[f64; 2]; 9] = crate::capture::markers::TEST_MARKS;

    fn observe(
        l: &CaptureLayout,
        view: usize,
        truth: &Pose,
        which: &[usize],
    ) -> Vec<([f64; 2], [f64; 2])> {
        let h = homography(l, view, truth);
        which.iter().map(|&k| (MARKS[k], apply(&h, MARKS[k]))).collect()
    }

    fn max_error(l: &CaptureLayout, view: usize, a: &Pose, b: &Pose) -> f64 {
        let (ha, hb) = (homography(l, view, a), homography(l, view, b));
        MARKS
            .iter()
            .map(|&m| {
                let (p, q) = (apply(&ha, m), apply(&hb, m));
                (p[0] - q[0]).hypot(p[1] - q[1])
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn three_markers_recover_a_pose_far_past_the_tolerance() {
        // 4.5° and 4.5 mm (3σ at 1.5° / 1.5 mm), at the most grazing view of the layout.
        let l = test_layout();
        let view = (0..l.sampling.len())
            .max_by(|&a, &b| {
                l.sampling.direction(a).theta_deg.total_cmp(&l.sampling.direction(b).theta_deg)
            })
            .unwrap();
        let w = Vector3::new(0.6, -0.8, 0.3).normalize() * 4.5f64.to_radians();
        let truth = Pose::from_column_slice(&[w.x, w.y, w.z, 4.5, -3.0, 4.5]);
        let prior = Prior { rotation_deg: 3.0, translation_mm: 3.0 };
        let nominal_error = max_error(&l, view, &Pose::zeros(), &truth);
        assert!(nominal_error > 20.0, "the test pose must be far off: {nominal_error} px");
        // Noise-free: the data fix the pose exactly (the prior's pull is 1 px against ≫).
        let obs = observe(&l, view, &truth, &[0, 2, 5]);
        let fitted = fit(&l, view, &obs, &Pose::zeros(), &prior).unwrap();
        let e = max_error(&l, view, &fitted, &truth);
        assert!(e < 0.05 * nominal_error, "3 markers: {e} px of {nominal_error}");
        // Two markers: the prior holds what they cannot fix, yet the prediction comes much
        // closer than nominal.
        let two = fit(&l, view, &observe(&l, view, &truth, &[0, 4]), &Pose::zeros(), &prior);
        let e2 = max_error(&l, view, &two.unwrap(), &truth);
        assert!(e2 < 0.5 * nominal_error, "2 markers: {e2} px of {nominal_error}");
    }
}
