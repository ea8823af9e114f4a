//! The sRGB transfer function (IEC 61966-2-1) between the 8/16-bit encoded values of
//! UBO2003 images and our linear values, with a 256-entry table for 8-bit decoding.
//!
//! Precision of an 8-bit round trip: encoding rounds to the nearest code, so the linear
//! error is at most half a code times the slope of the decoding curve, which is largest at
//! 1.0: `0.5/255 · 2.4/1.055 · 1 ≈ 4.5e-3` of the export scale (16-bit: `1.7e-5`).

use std::sync::OnceLock;

/// Linear value of an sRGB-encoded value in `[0, 1]`.
pub fn decode(s: f32) -> f32 {
    if s <= 0.04045 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) }
}

/// sRGB encoding of a linear value, clamped to `[0, 1]`.
pub fn encode(l: f32) -> f32 {
    let l = l.clamp(0.0, 1.0);
    if l <= 0.003_130_8 { l * 12.92 } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 }
}

/// Linear values of the 256 8-bit codes.
pub fn table8() -> &'static [f32; 256] {
    static T: OnceLock<[f32; 256]> = OnceLock::new();
    T.get_or_init(|| std::array::from_fn(|i| decode(i as f32 / 255.0)))
}

/// Largest linear error of an 8-bit round trip for values in `[0, 1]`.
pub const MAX_ERR_8BIT: f32 = 0.5 / 255.0 * 2.4 / 1.055;
/// Largest linear error of a 16-bit round trip for values in `[0, 1]`.
pub const MAX_ERR_16BIT: f32 = 0.5 / 65535.0 * 2.4 / 1.055;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_within_the_stated_bound() {
        let mut worst8 = 0f32;
        let mut worst16 = 0f32;
        for i in 0..=10_000 {
            let l = i as f32 / 10_000.0;
            let q8 = (encode(l) * 255.0).round() as usize;
            worst8 = worst8.max((table8()[q8] - l).abs());
            let q16 = (encode(l) * 65535.0).round();
            worst16 = worst16.max((decode(q16 / 65535.0) - l).abs());
        }
        assert!(worst8 <= MAX_ERR_8BIT && worst8 > 0.5 * MAX_ERR_8BIT, "{worst8}");
        assert!(worst16 <= MAX_ERR_16BIT * 1.5, "{worst16}");
        assert_eq!(table8()[0], 0.0);
        assert!((table8()[255] - 1.0).abs() < 1e-6);
        assert!((decode(encode(0.18)) - 0.18).abs() < 1e-6);
    }
}
