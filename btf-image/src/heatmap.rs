//! Error heat maps between a reference and an approximation (linear RGB images): per
//! pixel, the length of the RGB difference over a full scale, drawn with the one ramp of
//! [`crate::color::heat_ramp`] — the pictures of `[S03 Fig. 6, 13]` — and the colour bar that
//! reads them; scalar maps (ꟻLIP, [`crate::flip`]) through the same ramp.

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

/// Per pixel `value / full_scale` through the ramp, as an image (`w × h`, `values`
/// row-major): scalar error maps such as ꟻLIP (full scale 1). Pixels where `mask` is false
/// are drawn black.
pub fn value_heatmap_image(
    w: usize,
    h: usize,
    values: &[f32],
    full_scale: f32,
    mask: Option<&[bool]>,
) -> image::RgbImage {
    let scale = full_scale.max(f32::MIN_POSITIVE) as f64;
    let rgb =
        values
            .iter()
            .enumerate()
            .flat_map(|(i, &v)| {
                if mask.is_some_and(|m| !m[i]) { [0, 0, 0] } else { heat_ramp(v as f64 / scale) }
            })
            .collect();
    image::RgbImage::from_raw(w as u32, h as u32, rgb).expect("w × h values")
}

/// A horizontal colour bar of the ramp, `width` pixels wide: the ramp from `t = 0` to
/// `t = 1` over `[margin, width − margin)`, with a tick and a label under it at each
/// `(t, label)` (e.g. `(0.0, "0")`, `(1.0, ">= 10 % of peak")`).
pub fn colour_bar(width: u32, labels: &[(f64, &str)]) -> image::RgbImage {
    let (margin, bar_h, h) = (COLOUR_BAR_MARGIN as i64, 18i64, 48u32);
    let mut img = image::RgbImage::from_pixel(width, h, image::Rgb([255, 255, 255]));
    let span = (width as i64 - 2 * margin).max(1);
    for x in 0..span {
        let c = heat_ramp(x as f64 / (span - 1).max(1) as f64);
        for y in 4..4 + bar_h {
            crate::text::put(&mut img, margin + x, y, c);
        }
    }
    for &(t, label) in labels {
        let x = margin + (t.clamp(0.0, 1.0) * (span - 1) as f64).round() as i64;
        for y in 4 + bar_h..4 + bar_h + 6 {
            crate::text::put(&mut img, x, y, [0, 0, 0]);
        }
        let w = crate::text::width(label, 1);
        // Labels stay inside the image: the last one ends at the right edge at most.
        let x0 = (x - w / 2).clamp(0, width as i64 - w);
        crate::text::draw(&mut img, x0, 4 + bar_h + 10, label, [0, 0, 0], 1);
    }
    img
}

/// Space left and right of a [`colour_bar`]'s ramp, pixels.
pub const COLOUR_BAR_MARGIN: u32 = 24;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_bar_runs_green_to_red_with_ticks() {
        let bar = colour_bar(248, &[(0.0, "0"), (0.5, "5 %"), (1.0, ">= 10 %")]);
        assert_eq!(bar.dimensions(), (248, 48));
        let m = COLOUR_BAR_MARGIN;
        assert_eq!(bar.get_pixel(m, 10).0, [0, 255, 0]);
        assert_eq!(bar.get_pixel(248 - m - 1, 10).0, [255, 0, 0]);
        // Half way the ramp is yellow (within one pixel step of 1/199 of the ramp).
        let mid = bar.get_pixel(m + 100, 10).0;
        assert!(mid[0] >= 250 && mid[1] >= 250 && mid[2] == 0, "{mid:?}");
        // A tick under t = 0.5 at pixel m + 100 (span 200 → 0.5 · 199 = 99.5 → 100).
        assert_eq!(bar.get_pixel(m + 100, 24).0, [0, 0, 0]);
    }

    #[test]
    fn zero_error_is_green_full_scale_red_outside_the_mask_black() {
        let r = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let a = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 3.0];
        let mask = [false, true, true];
        assert_eq!(error_heatmap(&r, &a, 2.0, Some(&mask)), vec![0, 0, 0, 0, 255, 0, 255, 0, 0]);
        assert_eq!(&error_heatmap(&r, &a, 4.0, None)[..6], &[0, 255, 0, 0, 255, 0]);
        assert_eq!(&error_heatmap(&r, &a, 4.0, None)[6..], &[255, 255, 0]);
        let img = value_heatmap_image(3, 1, &[0.0, 0.5, 1.0], 1.0, Some(&[true, true, false]));
        assert_eq!(img.into_raw(), vec![0, 255, 0, 255, 255, 0, 0, 0, 0]);
    }
}
