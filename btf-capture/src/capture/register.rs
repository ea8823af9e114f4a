//! Registration of one view slot: the homography from the sample plane (mm) to the raw
//! images of that view, which share one plate pose (the robot places the plate once per
//! view; only the lamp moves).
//!
//! The images of the most frontal lights (brightest markers) are averaged, which lowers the
//! noise by `√k`. Point markers are detected around their nominal positions, matched by
//! layout index, and an exhaustive 4-subset consensus rejects outliers (H&Z Alg. 4.4);
//! markers missed at first are looked for again around the consensus prediction. When no
//! four agree (a plate placed so far off that the far markers left their windows, or a
//! window that held the wrong blob), a pose search fits the plate pose to every three
//! markers found ([`super::pose`]) and looks again around each fitted pose. The
//! centroids are then corrected for the perspective bias of a projected disc, the border
//! lines are sampled, and Levenberg–Marquardt minimises the point and point-on-line
//! residuals together (H&Z eq. 4.8); line samples further than `4 · 1.4826 · MAD` from
//! the fit are dropped and the fit repeated.

use super::homography::{self, LineMatch, PointMatch, apply};
use super::layout::CaptureLayout;
use super::markers::{self, Detection, Gray, Miss};
use super::pose::{self, Pose, Prior};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The registration of a view slot, as recorded in the store's provenance.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Registration {
    /// View slot.
    pub view: usize,
    /// Homography plate mm → image pixels, rows.
    pub homography: [[f64; 3]; 3],
    /// Point markers found (of the layout's).
    pub markers_found: usize,
    /// Point markers kept after outlier rejection.
    pub markers_used: usize,
    /// Border-line samples used.
    pub line_samples: usize,
    /// RMS of the point-marker residuals (pixels).
    pub marker_rms_px: f64,
    /// RMS of the line residuals (pixels).
    pub line_rms_px: f64,
    /// Registered from the nominal pose (`--fallback nominal`), not from the markers.
    pub fallback_nominal: bool,
    /// Markers not used, with the reason.
    pub missed: Vec<String>,
}

impl Registration {
    /// The homography as a matrix.
    pub fn matrix(&self) -> Matrix3<f64> {
        let h = &self.homography;
        Matrix3::from_fn(|r, c| h[r][c])
    }
}

fn to_rows(h: &Matrix3<f64>) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| h[(r, c)]))
}

/// Knobs of the registration.
#[derive(Debug, Clone, Copy)]
pub struct RegisterOptions {
    /// How far beyond a marker's rim to look for it around its nominal position (mm).
    pub search_margin_mm: f64,
    /// Consensus tolerance (pixels).
    pub consensus_tol_px: f64,
    /// Use the border lines in the refinement (off by default: their samples are biased
    /// by up to a quarter pixel in some views, see the crate README).
    pub use_lines: bool,
    /// The plate's placement error assumed by the pose search ([`pose::fit`]).
    pub pose_prior: Prior,
    /// How far beyond a marker's rim the pose search looks for it around where a fitted
    /// pose puts it (mm).
    pub pose_margin_mm: f64,
    /// Run the pose search when the markers found first do not agree (on by default; off
    /// only to measure what it adds).
    pub pose_search: bool,
    /// A homography whose plate pose lies further from nominal than this many standard
    /// deviations of `pose_prior` (rotation angle or shift length) is refused: markers
    /// matched to their neighbours' blobs can agree under one homography, for a plate
    /// that would have to sit some 20 mm off (seen at θ_v = 75° with 3°/3 mm errors).
    pub pose_limit_sigmas: f64,
    /// Largest predicted uncertainty (3 σ, pixels) of the registration over the sample
    /// square (a 5 × 5 grid), propagated from the marker residuals through the homography
    /// fit ([`grid_uncertainty_px`]); beyond it the registration is refused. Markers that
    /// agree within the consensus tolerance but all sit on one side of the sample (the rest
    /// outside the image at a grazing view) fix the homography poorly where the sample is:
    /// seen at θ_v = 75° with 3° / 3 mm pose errors, registered 5.6 and 24 px off.
    pub max_uncertainty_px: f64,
}

impl Default for RegisterOptions {
    fn default() -> Self {
        RegisterOptions {
            search_margin_mm: 6.0,
            consensus_tol_px: 2.0,
            use_lines: false,
            pose_prior: Prior { rotation_deg: 3.0, translation_mm: 3.0 },
            pose_margin_mm: 4.0,
            pose_search: true,
            pose_limit_sigmas: 5.0,
            max_uncertainty_px: 0.5,
        }
    }
}

fn describe(miss: Miss) -> &'static str {
    match miss {
        Miss::OutsideImage => "outside the image",
        Miss::NoContrast => "not found (no contrast)",
        Miss::BadShape => "occluded or merged (wrong shape)",
        Miss::Outlier => "inconsistent with the other markers (outlier)",
    }
}

/// Registers view `view` from its averaged luminance image; `Err` carries a description of
/// what was missing when fewer than 4 markers agree.
pub fn register(
    layout: &CaptureLayout,
    view: usize,
    img: &Gray,
    opt: &RegisterOptions,
) -> Result<Registration, String> {
    let plate = &layout.plate;
    let (marks, radius) = (&plate.point_markers_mm, plate.marker_radius_mm);
    let detect_all = |h: &Matrix3<f64>| -> Vec<Detection> {
        marks
            .iter()
            .map(|&m| markers::detect_point(img, h, m, radius, opt.search_margin_mm))
            .collect()
    };
    let nominal = detect_all(&layout.nominal_homography(view));
    let mut found = best_detections(marks, nominal, |dz| {
        detect_all(&layout.homography(view, &Matrix3::identity(), &Vector3::new(0.0, 0.0, dz)))
    });
    let raw = |found: &[Detection]| -> Vec<(usize, PointMatch)> {
        found
            .iter()
            .enumerate()
            .filter_map(|(k, d)| {
                d.ok().map(|p| (k, PointMatch { plate_mm: marks[k], image_px: p }))
            })
            .collect()
    };
    let missed_text = |found: &[Detection]| -> Vec<String> {
        found
            .iter()
            .enumerate()
            .filter_map(|(k, d)| {
                d.err().map(|m| format!("marker {k} at {:?} mm {}", marks[k], describe(m)))
            })
            .collect()
    };
    let first = raw(&found);
    let pts: Vec<PointMatch> = first.iter().map(|p| p.1).collect();
    let first_consensus = homography::consensus(&pts, opt.consensus_tol_px).map(|(h, _)| h);
    let aliased = first_consensus.and_then(|h| implausible(layout, view, &h, opt));
    let searched = match first_consensus.filter(|_| aliased.is_none()) {
        Some(h) => Some((h, None)),
        None if opt.pose_search => {
            pose_search(layout, view, img, opt, &found).map(|(h, again)| (h, Some(again)))
        }
        None => None,
    };
    let Some((h1, again)) = searched else {
        let m = missed_text(&found);
        let what = if let Some(why) = &aliased {
            format!("the {} point markers found agree only on {why}", pts.len())
        } else if pts.len() < 4 {
            format!("{} of {} point markers found (4 must agree)", pts.len(), marks.len())
        } else {
            format!(
                "{} of {} point markers found, but no 4 of them agree within {} px under one \
                 homography",
                pts.len(),
                marks.len(),
                opt.consensus_tol_px
            )
        };
        let search = if opt.pose_search {
            format!(
                ", nor does any plate pose fitted to 3 of them (prior {}° / {} mm) find 4 that \
                 agree",
                opt.pose_prior.rotation_deg, opt.pose_prior.translation_mm
            )
        } else {
            " (pose search off)".to_string()
        };
        return Err(format!("{what}{search}: {}", m.join("; ")));
    };
    if let Some(again) = again {
        found = again;
    }
    for (k, d) in found.iter_mut().enumerate() {
        if d.is_err() {
            *d = markers::detect_point(img, &h1, marks[k], radius, 2.0);
        }
    }
    let found_count = found.iter().filter(|d| d.is_ok()).count();
    let all = raw(&found);
    let (_, inliers) =
        homography::consensus(&all.iter().map(|p| p.1).collect::<Vec<_>>(), opt.consensus_tol_px)
            .ok_or_else(|| "markers disagree after the second search".to_string())?;
    let outliers: Vec<usize> =
        all.iter().zip(&inliers).filter(|(_, k)| !**k).map(|(p, _)| p.0).collect();
    for &k in &outliers {
        found[k] = Err(Miss::Outlier);
    }
    let mut h = h1;
    let mut lines: Vec<LineMatch> = Vec::new();
    for _ in 0..2 {
        let pts = markers::corrected_matches(&h, marks, radius, &found);
        h = homography::dlt(&pts).unwrap_or(h);
        if opt.use_lines {
            let span = plate.sample_mm / 2.0;
            lines = markers::sample_border_lines(
                img,
                &h,
                plate.border_offset_mm,
                plate.border_width_mm,
                span,
            );
        }
        let before = h;
        h = homography::refine(&h, &pts, &lines, 1.0);
        if !lines.is_empty() {
            lines = drop_line_outliers(&h, lines);
            h = homography::refine(&h, &pts, &lines, 1.0);
        }
        if !h.iter().all(|v| v.is_finite()) {
            h = before;
        }
    }
    if let Some(why) = implausible(layout, view, &h, opt) {
        return Err(format!("the markers agree only on {why}"));
    }
    let pts = markers::corrected_matches(&h, marks, radius, &found);
    let rms = |e: Vec<f64>| (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt();
    let marker_rms = rms(pts.iter().map(|m| homography::point_error(&h, m)).collect());
    let half = plate.sample_mm / 2.0;
    let uncertainty = grid_uncertainty_px(&h, &pts, marker_rms.max(NOISE_FLOOR_PX), half);
    // NaN (a degenerate fit) is refused too.
    if uncertainty.is_nan() || uncertainty > opt.max_uncertainty_px {
        let used: Vec<String> = pts.iter().map(|m| format!("{:?}", m.plate_mm)).collect();
        return Err(format!(
            "the {} markers that agree ({} mm; residual {marker_rms:.2} px) fix the sample's \
             registration only to ±{uncertainty:.2} px (3 σ), beyond {} px: they do not \
             surround the sample well enough",
            pts.len(),
            used.join(", "),
            opt.max_uncertainty_px
        ));
    }
    Ok(Registration {
        view,
        homography: to_rows(&h),
        markers_found: found_count,
        markers_used: pts.len(),
        line_samples: lines.len(),
        marker_rms_px: marker_rms,
        line_rms_px: rms(lines.iter().map(|l| homography::line_error(&h, l)).collect()),
        fallback_nominal: false,
        missed: missed_text(&found),
    })
}

/// The smallest marker residual assumed when propagating uncertainty (pixels): the
/// detector's noise at grazing views, so that 4 markers fitted exactly still carry some.
const NOISE_FLOOR_PX: f64 = 0.1;

/// The 3 σ uncertainty (pixels) of where `h` puts the points of a 5 × 5 grid on the square
/// `±half` mm, when each marker position in `pts` is uncertain by `sigma_px` per axis:
/// `Cov(h) = σ² (JᵀJ)⁻¹` for the Jacobian `J` of the projected markers with respect to the
/// eight free entries of `h` (`h₃₃` fixed), propagated to each grid point by its own
/// Jacobian (first order, numerical derivatives with steps relative to each entry).
/// Infinite when the markers do not determine `h`.
pub fn grid_uncertainty_px(h: &Matrix3<f64>, pts: &[PointMatch], sigma_px: f64, half: f64) -> f64 {
    let h = h / h[(2, 2)];
    let scale = h.norm();
    let jacobian = |p: [f64; 2]| -> nalgebra::SMatrix<f64, 2, 8> {
        let mut j = nalgebra::SMatrix::<f64, 2, 8>::zeros();
        for k in 0..8 {
            let (r, c) = (k / 3, k % 3);
            // Columns in units of each entry's own size, so that JᵀJ is well conditioned
            // (the product with the grid's Jacobian below does not depend on the units).
            let unit = h[(r, c)].abs().max(1e-3 * scale);
            let step = 1e-6 * unit;
            let (mut hp, mut hm) = (h, h);
            hp[(r, c)] += step;
            hm[(r, c)] -= step;
            let (a, b) = (apply(&hp, p), apply(&hm, p));
            j[(0, k)] = (a[0] - b[0]) / 2e-6;
            j[(1, k)] = (a[1] - b[1]) / 2e-6;
        }
        j
    };
    let mut jtj = nalgebra::SMatrix::<f64, 8, 8>::zeros();
    for m in pts {
        let j = jacobian(m.plate_mm);
        jtj += j.transpose() * j;
    }
    let Some(cov) = jtj.try_inverse() else { return f64::INFINITY };
    let mut worst = 0.0f64;
    for i in 0..5 {
        for k in 0..5 {
            let p = [half * (i as f64 / 2.0 - 1.0), half * (k as f64 / 2.0 - 1.0)];
            let j = jacobian(p);
            let var = (j * cov * j.transpose()).trace();
            worst = worst.max(if var >= 0.0 { var.sqrt() } else { f64::INFINITY });
        }
    }
    3.0 * sigma_px * worst
}

/// The pose search, when the markers found around the nominal pose (and the plate-height
/// steps) do not give 4 that agree: the plate may sit so far from nominal that the far
/// markers lie outside their windows, or a window held the wrong blob. From each search
/// start (nominal, Δz = ±2, ±4 mm) and each 3 markers found there (2 when only 2 were), the
/// plate pose is fitted ([`pose::fit`], with the robot's tolerance as a prior), every
/// marker is looked for again within `pose_margin_mm` of where that pose puts it, and the
/// consensus of what is found is scored; the set with the most agreeing markers (then the
/// smaller summed error) wins. `None` when no set has 4 that agree. The starts also include
/// the nominal pose searched with twice the window.
fn pose_search(
    layout: &CaptureLayout,
    view: usize,
    img: &Gray,
    opt: &RegisterOptions,
    nominal: &[Detection],
) -> Option<(Matrix3<f64>, Vec<Detection>)> {
    let plate = &layout.plate;
    let (marks, radius) = (&plate.point_markers_mm, plate.marker_radius_mm);
    let detect_all = |h: &Matrix3<f64>, margin: f64| -> Vec<Detection> {
        marks.iter().map(|&m| markers::detect_point(img, h, m, radius, margin)).collect()
    };
    // Around the nominal pose with a window twice as wide too: a plate shifted in its own
    // plane moves every marker alike, by up to 3σ of the translation error (9 mm at 3 mm).
    let wide = detect_all(&layout.nominal_homography(view), 2.0 * opt.search_margin_mm);
    let mut starts: Vec<(Pose, Vec<Detection>)> =
        vec![(Pose::zeros(), nominal.to_vec()), (Pose::zeros(), wide)];
    for dz in [-2.0, 2.0, -4.0, 4.0] {
        let p = Pose::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, dz]);
        starts.push((p, detect_all(&pose::homography(layout, view, &p), opt.search_margin_mm)));
    }
    // Subsets already tried (marker index and position to 0.01 px), across the starts.
    let mut tried = std::collections::HashSet::new();
    let mut best: Option<(usize, f64, Matrix3<f64>, Vec<Detection>)> = None;
    for (start, found) in &starts {
        let ok: Vec<(usize, [f64; 2])> =
            found.iter().enumerate().filter_map(|(k, d)| d.ok().map(|p| (k, p))).collect();
        let size = ok.len().min(3);
        if size < 2 {
            continue;
        }
        for subset in combinations(ok.len(), size) {
            let chosen: Vec<(usize, [f64; 2])> = subset.iter().map(|&i| ok[i]).collect();
            let key: Vec<(usize, i64, i64)> = chosen
                .iter()
                .map(|(k, p)| (*k, (p[0] * 100.0).round() as i64, (p[1] * 100.0).round() as i64))
                .collect();
            if !tried.insert(key) {
                continue;
            }
            let obs: Vec<([f64; 2], [f64; 2])> =
                chosen.iter().map(|(k, p)| (marks[*k], *p)).collect();
            let Some(p) = pose::fit(layout, view, &obs, start, &opt.pose_prior) else { continue };
            let again = detect_all(&pose::homography(layout, view, &p), opt.pose_margin_mm);
            let pts: Vec<PointMatch> = again
                .iter()
                .enumerate()
                .filter_map(|(k, d)| d.ok().map(|q| PointMatch { plate_mm: marks[k], image_px: q }))
                .collect();
            let Some((h, inliers)) = homography::consensus(&pts, opt.consensus_tol_px) else {
                continue;
            };
            if implausible(layout, view, &h, opt).is_some() {
                continue;
            }
            let count = inliers.iter().filter(|k| **k).count();
            let cost: f64 =
                pts.iter().map(|m| homography::point_error(&h, m).min(opt.consensus_tol_px)).sum();
            if best.as_ref().is_none_or(|b| count > b.0 || (count == b.0 && cost < b.1)) {
                best = Some((count, cost, h, again));
            }
            if count == marks.len() {
                break;
            }
        }
    }
    best.map(|(_, _, h, found)| (h, found))
}

/// Why the plate pose behind `h` cannot be the robot's: further from nominal than
/// `pose_limit_sigmas` standard deviations of the prior in rotation angle or shift length
/// (or no pose at all). `None` for a plausible pose.
fn implausible(
    layout: &CaptureLayout,
    view: usize,
    h: &Matrix3<f64>,
    opt: &RegisterOptions,
) -> Option<String> {
    let Some((r, t)) = layout.pose_from_homography(view, h) else {
        return Some("a homography no plate pose explains".into());
    };
    let angle = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    let shift = t.norm();
    let (max_angle, max_shift) = (
        opt.pose_limit_sigmas * opt.pose_prior.rotation_deg,
        opt.pose_limit_sigmas * opt.pose_prior.translation_mm,
    );
    (angle > max_angle || shift > max_shift).then(|| {
        format!(
            "a plate {angle:.1}° / {shift:.1} mm from its nominal pose, beyond {max_angle}° / \
             {max_shift} mm ({} σ of the placement prior): markers matched to the wrong blobs",
            opt.pose_limit_sigmas
        )
    })
}

/// Every `k`-subset of `0..n`, in lexicographic order.
fn combinations(n: usize, k: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut idx: Vec<usize> = (0..k).collect();
    if k > n {
        return out;
    }
    loop {
        out.push(idx.clone());
        let Some(i) = (0..k).rev().find(|&i| idx[i] < n - k + i) else { return out };
        idx[i] += 1;
        for j in i + 1..k {
            idx[j] = idx[j - 1] + 1;
        }
    }
}

/// Ranks a set of detections: first whether four found markers fix a homography (no three
/// on a line of the plate), then how many were found.
fn rank(marks: &[[f64; 2]], found: &[Detection]) -> (bool, usize) {
    let pts: Vec<[f64; 2]> =
        found.iter().zip(marks).filter(|(d, _)| d.is_ok()).map(|(_, m)| *m).collect();
    (homography::general_position(&pts), pts.len())
}

/// The detections to register from: `nominal` (around the nominal pose) unless every marker
/// was found there, else the best ([`rank`]) of it and `search(Δz)` for Δz = ±2, ±4 mm. A
/// plate higher or lower than nominal by Δz moves every marker by Δz · tan θ_v on the plate
/// (6.8 mm for 1.8 mm at 75°, past the search margin; at 60° an error of 1–2 mm already
/// pushes the foreshortened blobs onto their search borders). The search stops once a set
/// holds every marker.
fn best_detections(
    marks: &[[f64; 2]],
    nominal: Vec<Detection>,
    mut search: impl FnMut(f64) -> Vec<Detection>,
) -> Vec<Detection> {
    let mut found = nominal;
    for dz in [-2.0, 2.0, -4.0, 4.0] {
        if rank(marks, &found).1 == marks.len() {
            break;
        }
        let again = search(dz);
        if rank(marks, &again) > rank(marks, &found) {
            found = again;
        }
    }
    found
}

fn drop_line_outliers(h: &Matrix3<f64>, lines: Vec<LineMatch>) -> Vec<LineMatch> {
    let mut abs: Vec<f64> = lines.iter().map(|l| homography::line_error(h, l).abs()).collect();
    abs.sort_by(f64::total_cmp);
    let mad = abs.get(abs.len() / 2).copied().unwrap_or(0.0);
    let tol = (4.0 * 1.4826 * mad).max(0.05);
    lines.into_iter().filter(|l| homography::line_error(h, l).abs() <= tol).collect()
}

/// The registration used with `--fallback nominal`: the nominal pose, flagged.
pub fn nominal(layout: &CaptureLayout, view: usize, why: String) -> Registration {
    Registration {
        view,
        homography: to_rows(&layout.nominal_homography(view)),
        markers_found: 0,
        markers_used: 0,
        line_samples: 0,
        marker_rms_px: 0.0,
        line_rms_px: 0.0,
        fallback_nominal: true,
        missed: vec![why],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MARKS: [[f64; 2]; 9] = super::super::markers::TEST_MARKS;

    /// Detections of the markers `which` (the others missed).
    fn found(which: &[usize]) -> Vec<Detection> {
        (0..MARKS.len())
            .map(|k| if which.contains(&k) { Ok(MARKS[k]) } else { Err(Miss::BadShape) })
            .collect()
    }

    #[test]
    fn a_collinear_four_does_not_stop_the_plate_height_search() {
        // The noise-free 60° view: the nominal pose finds the bottom row and one more (three
        // on a line), Δz = −2 mm three markers, Δz = +2 mm all nine.
        let mut asked = vec![];
        let best = best_detections(&MARKS, found(&[0, 1, 2, 3]), |dz| {
            asked.push(dz);
            if dz == 2.0 { found(&(0..9).collect::<Vec<_>>()) } else { found(&[0, 1, 2]) }
        });
        assert_eq!(rank(&MARKS, &best), (true, 9));
        assert_eq!(asked, [-2.0, 2.0], "the search stops once every marker is found");
    }

    #[test]
    fn a_set_that_fixes_the_homography_beats_a_degenerate_one_of_the_same_size() {
        // Four each: the bottom row plus one (three on a line) against four corners.
        let degenerate = found(&[0, 1, 2, 3]);
        let general = found(&[0, 2, 4, 6]);
        assert_eq!(rank(&MARKS, &degenerate), (false, 4));
        let best = best_detections(&MARKS, degenerate, |_| general.clone());
        assert_eq!(rank(&MARKS, &best), (true, 4));
        // A complete nominal set is kept without any search.
        let all = found(&(0..9).collect::<Vec<_>>());
        let kept = best_detections(&MARKS, all, |_| unreachable!("no search needed"));
        assert_eq!(rank(&MARKS, &kept), (true, 9));
    }

    #[test]
    fn markers_on_one_side_of_the_sample_leave_it_uncertain() {
        // A mild perspective view of the plate at 3 px/mm; the 9 markers of the standard
        // plate surround the ±40 mm sample, the 5 towards its +x corner do not.
        let h = Matrix3::new(3.0, 0.2, 640.0, -0.1, 2.4, 480.0, 1e-4, 8e-4, 1.0);
        let marks = [
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
        let pts: Vec<PointMatch> =
            marks.iter().map(|&m| PointMatch { plate_mm: m, image_px: apply(&h, m) }).collect();
        let all = grid_uncertainty_px(&h, &pts, 0.1, 40.0);
        let side: Vec<PointMatch> = [1, 2, 3, 4, 8].iter().map(|&k| pts[k]).collect();
        let one_sided = grid_uncertainty_px(&h, &side, 0.1, 40.0);
        eprintln!("3σ over the sample: all 9 markers {all:.3} px, 5 on one side {one_sided:.3} px");
        assert!(all < 0.5 && one_sided > 4.0 * all, "{all} vs {one_sided}");
        // Halving the noise halves the uncertainty (first order); 3 markers cannot fix h.
        assert!((grid_uncertainty_px(&h, &pts, 0.05, 40.0) / all - 0.5).abs() < 1e-6);
        assert!(grid_uncertainty_px(&h, &pts[..3], 0.1, 40.0) > 1e3);
    }

    #[test]
    fn a_pose_beyond_the_prior_is_refused_as_aliased() {
        // 5 σ of the default prior is 15° / 15 mm: a plate 10 mm and 5° off passes, one
        // 20 mm off (a neighbour's blob taken for each marker) does not, in every view.
        let layout = super::super::layout::tests::layout();
        let opt = RegisterOptions::default();
        for view in 0..layout.sampling.len() {
            let pose = |w: [f64; 3], t: [f64; 3]| {
                let p = Pose::from_column_slice(&[w[0], w[1], w[2], t[0], t[1], t[2]]);
                pose::homography(&layout, view, &p)
            };
            let near = pose([0.0, 5f64.to_radians(), 0.0], [6.0, -6.0, 5.0]);
            assert_eq!(implausible(&layout, view, &near, &opt), None, "view {view}");
            let far = pose([0.0, 0.0, 0.0], [20.0, 0.0, 0.0]);
            let why = implausible(&layout, view, &far, &opt).expect("20 mm is refused");
            assert!(why.contains("20.0 mm") && why.contains("15 mm"), "view {view}: {why}");
            let turned = pose([0.0, 0.0, 20f64.to_radians()], [0.0; 3]);
            assert!(implausible(&layout, view, &turned, &opt).is_some(), "view {view}");
        }
    }
}
