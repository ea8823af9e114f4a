//! Error heat maps between a reference and an approximation (linear RGB images): per
//! pixel, the length of the RGB difference over a full scale, drawn with the one ramp of
//! [`crate::color::heat_ramp`] — the pictures of `[S03 Fig. 6, 13]`.

use crate::color::heat_ramp;

/// Per pixel `‖a − b‖ / full_scale` through the green → yellow → red ramp, as 8-bit RGB
/// (`[y][x][rgb]`). Pixels where `mask` is false (no geometry) are drawn black.
pub fn error_heatmap(
    reference: &[f32],
    approx: &[f32],
    full_scale: f32,
    mask: Option<&[bool]>,
) -> Vec<u8> {
    let scale = full_scale.max(f32::MIN_POSITIVE) as f64;
    reference
        .chunks_exact(3)
        .zip(approx.chunks_exact(3))
        .enumerate()
        .flat_map(|(i, (r, a))| {
            if mask.is_some_and(|m| !m[i]) {
                return [0, 0, 0];
            }
            let d: f64 = (0..3).map(|c| ((r[c] - a[c]) as f64).powi(2)).sum::<f64>().sqrt();
            heat_ramp(d / scale)
        })
        .collect()
}

/// [`error_heatmap`] as an image (`w × h`).
pub fn error_heatmap_image(
    w: usize,
    h: usize,
    reference: &[f32],
    approx: &[f32],
    full_scale: f32,
    mask: Option<&[bool]>,
) -> image::RgbImage {
    image::RgbImage::from_raw(
        w as u32,
        h as u32,
        error_heatmap(reference, approx, full_scale, mask),
    )
    .expect("two RGB images of w × h pixels")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_error_is_green_full_scale_red_outside_the_mask_black() {
        let r = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let a = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 3.0];
        let mask = [false, true, true];
        assert_eq!(error_heatmap(&r, &a, 2.0, Some(&mask)), vec![0, 0, 0, 0, 255, 0, 255, 0, 0]);
        assert_eq!(&error_heatmap(&r, &a, 4.0, None)[..6], &[0, 255, 0, 0, 255, 0]);
        assert_eq!(&error_heatmap(&r, &a, 4.0, None)[6..], &[255, 255, 0]);
    }
}
