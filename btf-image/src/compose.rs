//! Composing report pictures: images side by side (with captions) or stacked, and
//! nearest-neighbour enlargement so small textures stay visible in reports and contact
//! sheets.

use image::RgbImage;

/// Places images side by side (top-aligned) on white with `gap` pixels between them.
pub fn side_by_side(images: &[&RgbImage], gap: u32) -> RgbImage {
    let w: u32 =
        images.iter().map(|i| i.width()).sum::<u32>() + gap * images.len().saturating_sub(1) as u32;
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(w.max(1), h.max(1), image::Rgb([255, 255, 255]));
    let mut x0 = 0;
    for img in images {
        image::imageops::replace(&mut out, *img, x0 as i64, 0);
        x0 += img.width() + gap;
    }
    out
}

/// Height of a caption band under a captioned image.
pub const CAPTION_H: u32 = 28;

/// Images side by side (as [`side_by_side`]), each with its caption centred in a band of
/// [`CAPTION_H`] pixels below it — at twice the font size when it fits the image's width.
pub fn captioned_strip(images: &[(&RgbImage, &str)], gap: u32) -> RgbImage {
    let captioned: Vec<RgbImage> = images
        .iter()
        .map(|(img, caption)| {
            let mut out = RgbImage::from_pixel(
                img.width(),
                img.height() + CAPTION_H,
                image::Rgb([255, 255, 255]),
            );
            image::imageops::replace(&mut out, *img, 0, 0);
            let scale = if crate::text::width(caption, 2) <= img.width() as i64 { 2 } else { 1 };
            let y = img.height() as i64 + (CAPTION_H as i64 - 8 * scale) / 2;
            let cx = img.width() as i64 / 2;
            crate::text::draw_centred(&mut out, cx, y, caption, [0, 0, 0], scale);
            out
        })
        .collect();
    side_by_side(&captioned.iter().collect::<Vec<_>>(), gap)
}

/// Images one above the other (left-aligned) on white with `gap` pixels between them.
pub fn stacked(images: &[&RgbImage], gap: u32) -> RgbImage {
    let h: u32 = images.iter().map(|i| i.height()).sum::<u32>()
        + gap * images.len().saturating_sub(1) as u32;
    let w = images.iter().map(|i| i.width()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(w.max(1), h.max(1), image::Rgb([255, 255, 255]));
    let mut y0 = 0;
    for img in images {
        image::imageops::replace(&mut out, *img, 0, y0 as i64);
        y0 += img.height() + gap;
    }
    out
}

/// Nearest-neighbour enlargement by the integer factor that brings the width to at least
/// `min_size` (1 when it is already that wide).
pub fn upscale(img: &RgbImage, min_size: u32) -> RgbImage {
    let f = (min_size / img.width().max(1)).max(1);
    image::imageops::resize(
        img,
        img.width() * f,
        img.height() * f,
        image::imageops::FilterType::Nearest,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_add_up_and_pixels_are_kept() {
        let a = RgbImage::from_pixel(3, 2, image::Rgb([1, 2, 3]));
        let b = RgbImage::from_pixel(4, 5, image::Rgb([9, 9, 9]));
        let s = side_by_side(&[&a, &b], 2);
        assert_eq!(s.dimensions(), (9, 5));
        assert_eq!((s.get_pixel(2, 1).0, s.get_pixel(4, 0).0), ([1, 2, 3], [255; 3]));
        assert_eq!(s.get_pixel(8, 4).0, [9, 9, 9]);
        let u = upscale(&a, 128);
        assert_eq!(u.dimensions(), (126, 84));
        let v = stacked(&[&a, &b], 3);
        assert_eq!(v.dimensions(), (4, 10));
        assert_eq!(
            (v.get_pixel(0, 0).0, v.get_pixel(3, 0).0, v.get_pixel(0, 9).0),
            ([1, 2, 3], [255; 3], [9; 3])
        );
    }

    #[test]
    fn captions_sit_in_a_band_below_each_image() {
        let a = RgbImage::from_pixel(128, 64, image::Rgb([9, 9, 9]));
        let s = captioned_strip(&[(&a, "c = 16"), (&a, "original")], 4);
        assert_eq!(s.dimensions(), (260, 64 + CAPTION_H));
        // Ink only in the bands, inside each image's column; the images untouched.
        let ink = |x0: u32, x1: u32| {
            (x0..x1)
                .flat_map(|x| (64..64 + CAPTION_H).map(move |y| (x, y)))
                .filter(|&(x, y)| s.get_pixel(x, y).0 == [0, 0, 0])
                .count()
        };
        assert!(ink(0, 128) > 50 && ink(132, 260) > 50, "{} {}", ink(0, 128), ink(132, 260));
        assert!((0..64).all(|y| s.get_pixel(60, y).0 == [9, 9, 9]));
    }
}
