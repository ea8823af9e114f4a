//! Stockinette knit as a yarn-tube height field, after the stitch skeleton of Chen et al.
//! 2003 (§3): each loop is placed by key points in its stitch cell of the `(u, v)` grid,
//! the key points are jittered slightly per loop (loop variation) and joined along the
//! course by a periodic cardinal (Catmull–Rom) spline, which gives the yarn's centre line.
//!
//! The key points are our own (ten per loop rather than the paper's six, so that the
//! centre line also carries a depth): the two legs forming the visible "V" are in front,
//! the loop head (reaching into the row above) and the sinker (between stitches, reaching
//! into the row below) pass behind the neighbouring rows' legs. The tube of radius `r` is
//! rasterised by splatting discs along the spline (height `z_c + √(r² − d²)`, highest
//! wins); gaps between loops show a dark floor.

use crate::noise::{Rng, hash01};

/// Key points of one loop in stitch-cell units (`a` across the column, `b` down the rows,
/// the cell is `[0, 1)²`) with the centre-line depth in yarn radii.
const KEY_POINTS: [(f64, f64, f64); 10] = [
    (0.00, 1.05, -0.9),  // sinker, behind the legs of the row below
    (0.40, 0.92, 0.1),   // bottom of the left leg
    (0.20, 0.45, 0.7),   // left leg, in front
    (0.14, 0.05, 0.2),   // top of the left leg
    (0.28, -0.12, -0.9), // head, left, behind the legs of the row above
    (0.50, -0.22, -1.0), // head top
    (0.72, -0.12, -0.9), // head, right
    (0.86, 0.05, 0.2),   // top of the right leg
    (0.80, 0.45, 0.7),   // right leg, in front
    (0.60, 0.92, 0.1),   // bottom of the right leg
];

fn catmull_rom(p0: [f64; 3], p1: [f64; 3], p2: [f64; 3], p3: [f64; 3], t: f64) -> [f64; 3] {
    let (t2, t3) = (t * t, t * t * t);
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = 0.5
            * (2.0 * p1[i]
                + (-p0[i] + p2[i]) * t
                + (2.0 * p0[i] - 5.0 * p1[i] + 4.0 * p2[i] - p3[i]) * t2
                + (-p0[i] + 3.0 * p1[i] - 3.0 * p2[i] + p3[i]) * t3);
    }
    out
}

/// Heights (texel units) and albedos of a stockinette texture of `size²` texels with
/// `cols` stitches across and `rows` down; `yarn` is the yarn colour.
pub fn stockinette(
    seed: u64,
    size: usize,
    cols: u32,
    rows: u32,
    yarn: [f64; 3],
) -> (Vec<f64>, Vec<[f64; 3]>) {
    let n = size as f64;
    let (cw, ch) = (n / cols.max(1) as f64, n / rows.max(1) as f64);
    let radius = 0.2 * cw.min(1.3 * ch);
    let floor = -1.2 * radius;
    let mut height = vec![floor; size * size];
    let mut albedo = vec![yarn.map(|c| c * 0.2); size * size];
    let mut rng = Rng::new(seed);
    for row in 0..rows {
        // The course of this row as a periodic list of key points in texel units.
        let mut pts: Vec<[f64; 3]> = Vec::new();
        for col in 0..cols {
            for &(a, b, z) in &KEY_POINTS {
                let ja = 0.03 * rng.normal();
                let jb = 0.03 * rng.normal();
                pts.push([(col as f64 + a + ja) * cw, (row as f64 + b + jb) * ch, z * radius]);
            }
        }
        let tint = 0.92 + 0.08 * hash01(seed, row as i64, 0, 7);
        let m = pts.len();
        // Periodic continuation in x: the point before the first is the last, shifted by -n.
        let get = |k: isize| {
            let idx = k.rem_euclid(m as isize) as usize;
            let wraps = k.div_euclid(m as isize) as f64;
            let p = pts[idx];
            [p[0] + wraps * n, p[1], p[2]]
        };
        for k in 0..m as isize {
            let (p0, p1, p2, p3) = (get(k - 1), get(k), get(k + 1), get(k + 2));
            let len = ((p2[0] - p1[0]).powi(2) + (p2[1] - p1[1]).powi(2)).sqrt();
            let steps = ((len / (0.25 * radius)).ceil() as usize).max(2);
            for s in 0..steps {
                let c = catmull_rom(p0, p1, p2, p3, s as f64 / steps as f64);
                let fibre = 0.85 + 0.15 * hash01(seed, row as i64, k as i64, s as i64);
                splat(
                    &mut height,
                    &mut albedo,
                    size,
                    c,
                    radius,
                    yarn.map(|y| (y * tint * fibre).min(1.0)),
                );
            }
        }
    }
    (height, albedo)
}

fn splat(
    height: &mut [f64],
    albedo: &mut [[f64; 3]],
    size: usize,
    c: [f64; 3],
    r: f64,
    colour: [f64; 3],
) {
    let n = size as isize;
    let (x0, x1) = ((c[0] - r - 0.5).floor() as isize, (c[0] + r - 0.5).ceil() as isize);
    let (y0, y1) = ((c[1] - r - 0.5).floor() as isize, (c[1] + r - 0.5).ceil() as isize);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (dx, dy) = (x as f64 + 0.5 - c[0], y as f64 + 0.5 - c[1]);
            let d2 = dx * dx + dy * dy;
            if d2 >= r * r {
                continue;
            }
            let h = c[2] + (r * r - d2).sqrt();
            let idx = (y.rem_euclid(n) * n + x.rem_euclid(n)) as usize;
            if h > height[idx] {
                height[idx] = h;
                // Fibres in the tube's flanks look a little darker (less exposed).
                albedo[idx] = colour.map(|a| a * (0.8 + 0.2 * (1.0 - d2 / (r * r)).sqrt()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legs_are_in_front_of_heads_and_texture_tiles() {
        let size = 64;
        let (h, a) = stockinette(5, size, 4, 5, [0.7, 0.2, 0.2]);
        assert!(
            h.iter().all(|v| v.is_finite())
                && a.iter().all(|c| c.iter().all(|&x| (0.0..=1.0).contains(&x)))
        );
        let at = |x: f64, y: f64| h[(y as usize % size) * size + (x as usize % size)];
        // Cells of 16 × 12.8 texels: the middle of a leg stands out in front.
        let leg = at(16.0 + 0.2 * 16.0, 12.8 + 0.45 * 12.8);
        let gap = h.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(leg > 0.5 * 0.2 * 16.0, "leg {leg}");
        assert!(gap < 0.0, "some floor between loops is visible: {gap}");
    }
}
