//! Light incidence correction: the robot tilts the plate a little differently for every
//! view (≈ 1°), so a lamp at the nominal polar angle `θ_l` meets the sample at `θ_l'`, and
//! the irradiance on the sample is `E cos θ_l'` instead of `E cos θ_l` — about 6 % off at
//! `θ_l = 75°` for a 1° tilt. The registration gives the plate pose (the homography
//! decomposed, [`CaptureLayout::pose_from_homography`]), hence `cos θ_l' = r₃ · l` with `r₃`
//! the plate normal in the lab and `l` the lamp direction; every image of the slot is
//! scaled by `cos θ_l / cos θ_l'`.
//!
//! The correction is exact for the cosine factor of the BTF (DESIGN.md radiometry: the
//! BTF contains `cos θ_l`; a flat Lambertian sample becomes exactly its nominal value) and
//! first order for the rest (self-shadowing, the local BRDF): those depend on the light
//! direction in ways only the material knows. Sattler et al. 2003 (§3.2) rectify the
//! geometry only; this is the radiometric counterpart of their rectification.

use super::layout::CaptureLayout;
use nalgebra::{Matrix3, Vector3};

/// Below this cosine (θ ≳ 87°) a light is left uncorrected: the ratio of two small
/// cosines amplifies noise more than it removes bias.
const MIN_COSINE: f64 = 0.05;

/// The gain `cos θ_l / cos θ_l'` of every light of view slot `view` registered with
/// homography `h` (sample mm → pixels); 1 where the pose cannot be recovered or a cosine
/// is below [`MIN_COSINE`].
pub fn light_cosine_gains(layout: &CaptureLayout, view: usize, h: &Matrix3<f64>) -> Vec<f64> {
    let n = layout.sampling.len();
    let Some((rotation, _)) = layout.pose_from_homography(view, h) else {
        return vec![1.0; n];
    };
    let normal_lab = rotation.column(2).into_owned();
    (0..n)
        .map(|i| {
            let l = Vector3::from(layout.sampling.direction(i).to_vector());
            let (nominal, actual) = (l.z, normal_lab.dot(&l));
            if nominal < MIN_COSINE || actual < MIN_COSINE { 1.0 } else { nominal / actual }
        })
        .collect()
}

/// The tilt (degrees) of the plate normal from the lab's `+z` under homography `h`.
pub fn tilt_deg(layout: &CaptureLayout, view: usize, h: &Matrix3<f64>) -> Option<f64> {
    let (rotation, _) = layout.pose_from_homography(view, h)?;
    Some(rotation[(2, 2)].clamp(-1.0, 1.0).acos().to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::layout::tests::layout;

    #[test]
    fn gains_undo_the_tilted_plates_cosine() {
        let l = layout();
        // Tilt the plate by 1° about the lab y axis: the lamp at θ = 75°, φ = 0 (towards
        // +x) then meets the plate at 74°, the one at φ = 180° at 76°.
        let r =
            *nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), 1f64.to_radians()).matrix();
        for view in 0..l.sampling.len() {
            let h = l.homography(view, &r, &Vector3::new(0.5, -1.0, 0.3));
            let g = light_cosine_gains(&l, view, &h);
            let c = |deg: f64| deg.to_radians().cos();
            let want = [1.0 / c(1.0), c(75.0) / c(74.0), 1.0 / 1.0, c(75.0) / c(76.0)];
            // Lights 1 (φ = 0) and 3 (φ = 180°); lights 2, 4 (φ = 90°, 270°) are tilted
            // about their own axis, so their cosine changes only to second order.
            assert!((g[0] - want[0]).abs() < 1e-12, "view {view}: {g:?}");
            assert!((g[1] - want[1]).abs() < 1e-12, "view {view}: {g:?}");
            assert!((g[3] - want[3]).abs() < 1e-12, "view {view}: {g:?}");
            assert!((g[2] - 1.0).abs() < 1e-3 && (g[4] - 1.0).abs() < 1e-3, "{g:?}");
            assert!((tilt_deg(&l, view, &h).unwrap() - 1.0).abs() < 1e-9);
        }
        assert_eq!(light_cosine_gains(&l, 0, &Matrix3::zeros()), vec![1.0; 5]);
    }
}
