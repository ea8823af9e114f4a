//! Height fields and albedo maps of the non-yarn kinds, in normalised coordinates
//! `(u, v) ∈ [0, 1)²` (`u = (x + ½)/N` along columns, `v = (y + ½)/N` along rows) with an
//! integer number of pattern repeats, so every texture tiles.
//!
//! Heights are returned in units of one pattern period and scaled to texels by the caller.
//! - `lambert`: flat, albedo = base × (checker + noise) — the analytic validation case;
//! - `corduroy`: rounded wales running along `+y` (constant in `v`) separated by grooves
//!   showing the darker backing, with pile noise — anisotropic by construction;
//! - `woven`: plain weave, warp threads along `y` and weft along `x` crossing over/under
//!   alternately (a cosine undulation), two yarn colours, twist stripes;
//! - `wallpaper`: embossed paint — rosettes in a diamond lattice of raised ridges;
//! - `stone`: fractal relief (fBm), mottled albedo with speckles.

use crate::noise::{fbm, hash01};

/// Height (periods) and albedo of one texel.
pub type TexelFn<'a> = dyn Fn(f64, f64) -> (f64, [f64; 3]) + Sync + 'a;

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn mul(c: [f64; 3], s: f64) -> [f64; 3] {
    c.map(|x| (x * s).clamp(0.0, 1.0))
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// The Lambert validation pattern: `base × (0.55 + 0.3·checker + 0.15·noise)`, 2×2
/// checks per repeat.
pub fn lambert_albedo(seed: u64, repeats: u32, base: [f64; 3], u: f64, v: f64) -> [f64; 3] {
    let r = 2.0 * repeats.max(1) as f64;
    let checker = (((u * r).floor() + (v * r).floor()) as i64).rem_euclid(2) as f64;
    let noise = fbm(seed, u, v, 4 * repeats.max(1), 3, 0.5);
    mul(base, 0.55 + 0.3 * checker + 0.15 * noise)
}

/// Corduroy wales along `+y`: profile across `x`, pile noise along the wale.
pub fn corduroy(seed: u64, repeats: u32, base: [f64; 3], u: f64, v: f64) -> (f64, [f64; 3]) {
    let r = repeats.max(1) as f64;
    let s = (u * r).fract();
    // A flat-topped wale (super-ellipse of order 3) filling 84 % of the period; the rest
    // is a narrow groove down to the backing.
    let q = ((s - 0.5) / 0.42).abs();
    let profile = if q < 1.0 { (1.0 - q.powi(3)).cbrt() } else { 0.0 };
    let pile = fbm(seed, u, v, 16 * repeats.max(1), 3, 0.5);
    let h = profile * (0.94 + 0.06 * pile);
    let shade = 0.45 + 0.55 * smoothstep(0.0, 0.3, profile);
    (h, mul(base, shade * (0.9 + 0.2 * pile)))
}

/// Plain weave of warp (colour `warp`) along `y` and weft (colour `weft`) along `x`.
pub fn woven(
    seed: u64,
    repeats: u32,
    warp: [f64; 3],
    weft: [f64; 3],
    u: f64,
    v: f64,
) -> (f64, [f64; 3]) {
    use std::f64::consts::PI;
    let r = repeats.max(1) as f64;
    let (gu, gv) = (u * r, v * r);
    let (i, j) = (gu.floor(), gv.floor());
    let (a, b) = (gu - i, gv - j);
    let tube = |w: f64| {
        let q = (w - 0.5) / 0.46;
        if q.abs() < 1.0 { Some((1.0 - q * q).sqrt()) } else { None }
    };
    // Warp thread i is on top where (i + j) is even; the weft does the opposite.
    let c_warp = 0.25 + 0.25 * (PI * (gv - 0.5 - i)).cos();
    let c_weft = 0.25 - 0.25 * (PI * (gu - 0.5 - j)).cos();
    let jitter = 0.9 + 0.2 * fbm(seed, u, v, 8 * repeats.max(1), 2, 0.5);
    let h_warp = tube(a).map(|p| c_warp + 0.45 * p);
    let h_weft = tube(b).map(|p| c_weft + 0.45 * p);
    let twist =
        |along: f64, across: f64| 0.88 + 0.12 * (2.0 * PI * (6.0 * along + 1.5 * across)).sin();
    match (h_warp, h_weft) {
        (Some(hw), Some(hf)) if hw >= hf => (hw, mul(warp, twist(b, a) * jitter)),
        (_, Some(hf)) => (hf, mul(weft, twist(a, b) * jitter)),
        (Some(hw), None) => (hw, mul(warp, twist(b, a) * jitter)),
        (None, None) => (0.0, mul(warp, 0.25)),
    }
}

/// Embossed wallpaper: rosette and diamond ridges (motif colour) on a paint ground.
pub fn wallpaper(
    seed: u64,
    repeats: u32,
    ground: [f64; 3],
    motif: [f64; 3],
    u: f64,
    v: f64,
) -> (f64, [f64; 3]) {
    let r = repeats.max(1) as f64;
    let (a, b) = ((u * r).fract() - 0.5, (v * r).fract() - 0.5);
    let rad = (a * a + b * b).sqrt();
    let petals = 0.22 + 0.07 * (6.0 * b.atan2(a)).cos();
    let rosette = 1.0 - smoothstep(petals - 0.03, petals + 0.01, rad);
    let centre = 1.0 - smoothstep(0.05, 0.07, rad);
    let diamond = 1.0 - smoothstep(0.015, 0.04, (a.abs() + b.abs() - 0.5).abs());
    let stipple = fbm(seed, u, v, 32 * repeats.max(1), 3, 0.6);
    let raised = rosette.max(diamond);
    let h = 0.8 * raised + 0.2 * centre + 0.08 * stipple;
    let albedo = mix(ground, motif, raised.max(centre));
    (h, mul(albedo, 0.95 + 0.1 * stipple))
}

/// Fractal stone relief with mottled albedo and bright speckles.
pub fn stone(
    seed: u64,
    repeats: u32,
    base: [f64; 3],
    u: f64,
    v: f64,
    size: usize,
) -> (f64, [f64; 3]) {
    let rel = fbm(seed, u, v, 4 * repeats.max(1), 6, 0.55);
    let ridged = 1.0 - (2.0 * fbm(seed ^ 0x5EED, u, v, 2 * repeats.max(1), 5, 0.5) - 1.0).abs();
    let h = 0.7 * rel + 0.3 * ridged * ridged;
    let mottle = fbm(seed ^ 0xC0105, u, v, 8 * repeats.max(1), 4, 0.6);
    let texel = ((u * size as f64) as i64, (v * size as f64) as i64);
    let speckle = if hash01(seed ^ 0x5BEC, texel.0, texel.1, 1) > 0.97 { 1.35 } else { 1.0 };
    let tint = mix(base, mul(base, 0.6), mottle);
    (h, mul(tint, (0.75 + 0.4 * rel) * speckle))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_tile_and_stay_in_range() {
        let base = [0.6, 0.5, 0.4];
        for &(u, v) in &[(0.013, 0.52), (0.5, 0.0), (0.99, 0.7)] {
            let all = [
                corduroy(1, 4, base, u, v),
                woven(1, 6, base, [0.2, 0.3, 0.7], u, v),
                wallpaper(1, 2, base, [0.7, 0.5, 0.2], u, v),
                stone(1, 1, base, u, v, 32),
            ];
            for (h, a) in all {
                assert!((-0.01..=1.5).contains(&h), "{h}");
                assert!(a.iter().all(|&c| (0.0..=1.0).contains(&c)), "{a:?}");
            }
            let (h0, _) = corduroy(1, 4, base, u, v);
            let (h1, _) = corduroy(1, 4, base, u + 1.0, v + 1.0);
            assert!((h0 - h1).abs() < 1e-9);
        }
        // Corduroy is constant along y apart from the small pile noise.
        let (a, _) = corduroy(1, 4, base, 0.1, 0.2);
        let (b, _) = corduroy(1, 4, base, 0.1, 0.7);
        assert!((a - b).abs() < 0.1 * a.max(b));
    }
}
