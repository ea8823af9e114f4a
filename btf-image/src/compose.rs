//! Composing report pictures: images side by side, and nearest-neighbour enlargement so
//! small textures stay visible in reports and contact sheets.

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
    }
}
