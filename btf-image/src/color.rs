//! Colour encodings: the sRGB transfer function (IEC 61966-2-1) between linear values and
//! 8/16-bit display codes, and the one error colour ramp of every heat map in the toolkit
//! (green = no error → yellow → red = the chosen full scale, as the difference images of
//! `[S03 Fig. 6, 13]`).
//!
//! Precision of an 8-bit round trip: encoding rounds to the nearest code, so the linear
//! error is at most half a code times the slope of the decoding curve, largest at 1.0:
//! `0.5/255 · 2.4/1.055 ≈ 4.5e-3` ([`MAX_ERR_8BIT`]; 16-bit: `1.7e-5`).

use std::sync::OnceLock;

/// sRGB encoding of a linear value: `[0, 1]` → `[0, 1]`, values outside clamped, NaN → 0.
pub fn srgb_encode(linear: f32) -> f32 {
    if linear.is_nan() || linear <= 0.0 {
        return 0.0;
    }
    if linear >= 1.0 {
        return 1.0;
    }
    if linear <= 0.003_130_8 { 12.92 * linear } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

/// The 8-bit sRGB code of a linear value (rounded to the nearest code).
pub fn srgb_encode8(linear: f32) -> u8 {
    (srgb_encode(linear) * 255.0).round() as u8
}

/// Linear value of an sRGB-encoded value in `[0, 1]`.
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.04045 { encoded / 12.92 } else { ((encoded + 0.055) / 1.055).powf(2.4) }
}

/// Linear values of the 256 8-bit codes.
pub fn srgb_table8() -> &'static [f32; 256] {
    static T: OnceLock<[f32; 256]> = OnceLock::new();
    T.get_or_init(|| std::array::from_fn(|i| srgb_decode(i as f32 / 255.0)))
}

/// Largest linear error of an 8-bit round trip for values in `[0, 1]`.
pub const MAX_ERR_8BIT: f32 = 0.5 / 255.0 * 2.4 / 1.055;
/// Largest linear error of a 16-bit round trip for values in `[0, 1]`.
pub const MAX_ERR_16BIT: f32 = 0.5 / 65535.0 * 2.4 / 1.055;

/// The error ramp: `t = 0` green, `t = ½` yellow, `t ≥ 1` (and non-finite `t`) red; 8-bit
/// sRGB.
pub fn heat_ramp(t: f64) -> [u8; 3] {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 1.0 };
    let r = (2.0 * t).min(1.0);
    let g = (2.0 * (1.0 - t)).min(1.0);
    [(r * 255.0).round() as u8, (g * 255.0).round() as u8, 0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_midpoint_and_round_trip_bounds() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.2140) - 0.5).abs() < 1e-3);
        assert_eq!(srgb_encode(7.0), 1.0);
        assert_eq!(srgb_encode(f32::NAN), 0.0);
        assert_eq!((srgb_encode8(0.0), srgb_encode8(1.0)), (0, 255));
        let (mut worst8, mut worst16) = (0f32, 0f32);
        for i in 0..=10_000 {
            let l = i as f32 / 10_000.0;
            worst8 = worst8.max((srgb_table8()[srgb_encode8(l) as usize] - l).abs());
            let q16 = (srgb_encode(l) * 65535.0).round();
            worst16 = worst16.max((srgb_decode(q16 / 65535.0) - l).abs());
        }
        assert!(worst8 <= MAX_ERR_8BIT && worst8 > 0.5 * MAX_ERR_8BIT, "{worst8}");
        assert!(worst16 <= MAX_ERR_16BIT * 1.5, "{worst16}");
        assert_eq!(srgb_table8()[0], 0.0);
        assert!((srgb_table8()[255] - 1.0).abs() < 1e-6);
        assert!((srgb_decode(srgb_encode(0.18)) - 0.18).abs() < 1e-6);
    }

    #[test]
    fn ramp_goes_green_yellow_red() {
        assert_eq!(heat_ramp(0.0), [0, 255, 0]);
        assert_eq!(heat_ramp(0.5), [255, 255, 0]);
        assert_eq!(heat_ramp(1.0), [255, 0, 0]);
        assert_eq!(heat_ramp(7.0), [255, 0, 0]);
        assert_eq!(heat_ramp(f64::NAN), [255, 0, 0]);
    }
}
