//! The render-only jitter filter of Chen et al. 2003 §4.2 ("position averaging" after the
//! update): a centred moving average of window 3 over the *rendered* frames,
//! `x̄ₖ = (xₖ₋₁ + xₖ + xₖ₊₁)/3`, with the two-frame average at the ends. The paper averages
//! the state itself, which damps real motion and breaks momentum; here the filter takes
//! recorded frames and returns new ones, so nothing it computes can reach the simulation.

use crate::vec3::V3;
use crate::{Error, Result};

/// The window-3 moving average of `frames` (each a list of node positions, all of one
/// length). One frame is returned as it is.
pub fn moving_average(frames: &[Vec<V3>]) -> Result<Vec<Vec<V3>>> {
    let Some(first) = frames.first() else { return Ok(Vec::new()) };
    if let Some((k, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != first.len()) {
        return Err(Error::Invalid(format!(
            "moving average: frame {k} has {} nodes, frame 0 has {}",
            f.len(),
            first.len()
        )));
    }
    let n = frames.len();
    Ok((0..n)
        .map(|k| {
            let window = &frames[k.saturating_sub(1)..(k + 2).min(n)];
            let w = 1.0 / window.len() as f64;
            (0..first.len())
                .map(|i| {
                    let s = window
                        .iter()
                        .fold([0.0; 3], |s, f| [s[0] + f[i][0], s[1] + f[i][1], s[2] + f[i][2]]);
                    [s[0] * w, s[1] * w, s[2] * w]
                })
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_linear_motion_and_divides_alternating_jitter_by_three() {
        // x = t + 0.03·(−1)^t: the drift survives, the jitter drops to a third (and flips).
        let frames: Vec<Vec<V3>> = (0..10)
            .map(|t| {
                let j = if t % 2 == 0 { 0.03 } else { -0.03 };
                vec![[t as f64 + j, 2.0 * t as f64, 0.0]]
            })
            .collect();
        let s = moving_average(&frames).unwrap();
        assert_eq!(s.len(), 10);
        for (t, f) in s.iter().enumerate().take(9).skip(1) {
            let j = if t % 2 == 0 { -0.01 } else { 0.01 };
            assert!((f[0][0] - (t as f64 + j)).abs() < 1e-12, "frame {t}: {}", f[0][0]);
            assert!((f[0][1] - 2.0 * t as f64).abs() < 1e-12);
        }
        // The ends average two frames.
        assert!((s[0][0][1] - 1.0).abs() < 1e-12);
        assert!(moving_average(&[vec![[0.0; 3]], vec![]]).is_err());
        assert!(moving_average(&[]).unwrap().is_empty());
    }
}
