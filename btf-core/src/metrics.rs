//! Error measures between a reference and an approximation: squared error, relative RMSE
//! `‖a − b‖ / ‖a‖` and PSNR `10 log₁₀(peak² / MSE)` (the pictures of them, heat maps with
//! the one colour ramp, are `btf_image::heatmap`).

/// `Σ (a − b)²` in `f64`.
pub fn sse(reference: &[f32], approx: &[f32]) -> f64 {
    reference.iter().zip(approx).map(|(&a, &b)| ((a as f64) - (b as f64)).powi(2)).sum()
}

/// `‖a − b‖ / ‖a‖` (0 when both are zero, ∞ when only the reference is).
pub fn rel_rmse(reference: &[f32], approx: &[f32]) -> f64 {
    let e = sse(reference, approx);
    let n: f64 = reference.iter().map(|&a| (a as f64).powi(2)).sum();
    rel_rmse_from(e, n)
}

/// Relative RMSE from an error sum and a reference energy.
pub fn rel_rmse_from(sse: f64, energy: f64) -> f64 {
    if energy > 0.0 {
        (sse / energy).sqrt()
    } else if sse > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// PSNR in dB for a mean squared error and a peak value (∞ for a perfect match).
pub fn psnr_db(mse: f64, peak: f64) -> f64 {
    if mse <= 0.0 { f64::INFINITY } else { 10.0 * (peak * peak / mse).log10() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basic_values() {
        assert_eq!(sse(&[1.0, 2.0], &[1.0, 4.0]), 4.0);
        assert!((rel_rmse(&[3.0, 4.0], &[3.0, 4.5]) - 0.1).abs() < 1e-12);
        assert!((psnr_db(0.01, 1.0) - 20.0).abs() < 1e-12);
        assert_eq!(psnr_db(0.0, 1.0), f64::INFINITY);
    }
}
