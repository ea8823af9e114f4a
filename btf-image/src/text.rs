//! Text drawn into 8-bit images with the 8×8 bitmap font of `font8x8`, at integer scales:
//! the labels of plots, image strips and colour bars, so no system font is needed. A glyph
//! is `8·scale` pixels wide and high; characters outside ASCII are drawn by their nearest
//! ASCII stand-in (`≥` as `>=`, `×` as `x`, `θ` as `theta`, …).

use image::{Rgb, RgbImage};

/// Glyph size at scale 1, pixels.
pub const GLYPH: i64 = 8;

/// `s` with non-ASCII characters replaced by ASCII stand-ins.
pub fn ascii(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '≥' => out.push_str(">="),
            '≤' => out.push_str("<="),
            '×' | '·' => out.push(if ch == '×' { 'x' } else { '*' }),
            'θ' => out.push_str("theta"),
            'φ' => out.push_str("phi"),
            'δ' => out.push_str("delta"),
            'µ' | 'μ' => out.push('u'),
            '–' | '—' | '−' => out.push('-'),
            '°' => out.push_str("deg"),
            c if c.is_ascii() => out.push(c),
            _ => out.push('?'),
        }
    }
    out
}

/// Width in pixels of `s` drawn at `scale`.
pub fn width(s: &str, scale: i64) -> i64 {
    ascii(s).len() as i64 * GLYPH * scale
}

/// Sets one pixel when it lies inside the image.
pub fn put(img: &mut RgbImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(c));
    }
}

/// Draws `s` with its top-left corner at `(x, y)`.
pub fn draw(img: &mut RgbImage, x: i64, y: i64, s: &str, color: [u8; 3], scale: i64) {
    for (k, ch) in ascii(s).bytes().enumerate() {
        let glyph = font8x8::legacy::BASIC_LEGACY.get(ch as usize).copied().unwrap_or([0; 8]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + (k as i64 * GLYPH + col) * scale + dx;
                        put(img, px, y + row as i64 * scale + dy, color);
                    }
                }
            }
        }
    }
}

/// Draws `s` centred horizontally on `cx`.
pub fn draw_centred(img: &mut RgbImage, cx: i64, y: i64, s: &str, color: [u8; 3], scale: i64) {
    draw(img, cx - width(s, scale) / 2, y, s, color, scale);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stand_ins_widths_and_glyph_bounds() {
        assert_eq!(ascii("c ≥ 8 × 2, 5 µs"), "c >= 8 x 2, 5 us");
        assert_eq!(width("ab", 2), 32);
        let mut img = RgbImage::from_pixel(40, 20, Rgb([255; 3]));
        draw(&mut img, 2, 3, "HI", [0, 0, 0], 2);
        // Every inked pixel lies inside the two 16 × 16 glyph cells.
        let inked: Vec<(u32, u32)> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 == [0, 0, 0])
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(inked.len() > 40, "{}", inked.len());
        assert!(inked.iter().all(|&(x, y)| (2..34).contains(&x) && (3..19).contains(&y)));
    }
}
