//! Minimum clearance between different yarn pieces (DESIGN §3.5, §3.3 item 9): the
//! smallest distance between the centre lines of two different courses (periodic images
//! included; a course's own images along the wales are the same yarn and skipped), divided
//! by the yarn diameter `2r`. Yarns of radius `r` interpenetrate where the ratio is below
//! 1. [H25]'s run-time model has no contact term, so this is the number that exposes it.
//!
//! Each curve is sampled `per_segment` points per Catmull–Rom segment; segment pairs are
//! found through a uniform grid (cell = the larger of `4r` and the longest sample chord),
//! their distance by the closest points of two segments, and the best pair is refined on
//! the curves themselves by coordinate descent on the two curve parameters.

use crate::curve::YarnSet;
use crate::vec3::{self, V3};
use std::collections::HashMap;

/// The closest approach of two different yarn pieces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearance {
    /// Distance between centre lines (metres); `INFINITY` when no two pieces come within
    /// one grid cell of each other.
    pub distance: f64,
    /// `distance / 2r`.
    pub ratio: f64,
    /// The two curves.
    pub curves: (usize, usize),
    /// The point on the first curve (`None` with an infinite distance).
    pub at: Option<V3>,
}

/// Closest points of segments `p0p1` and `q0q1`: the distance and the two parameters.
fn segment_distance(p0: V3, p1: V3, q0: V3, q1: V3) -> (f64, f64, f64) {
    let d1 = vec3::sub(p1, p0);
    let d2 = vec3::sub(q1, q0);
    let r = vec3::sub(p0, q0);
    let (a, e, f) = (vec3::dot(d1, d1), vec3::dot(d2, d2), vec3::dot(d2, r));
    let (s, t) = if a <= 1e-300 && e <= 1e-300 {
        (0.0, 0.0)
    } else if a <= 1e-300 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = vec3::dot(d1, r);
        if e <= 1e-300 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = vec3::dot(d1, d2);
            let den = a * e - b * b;
            let mut s = if den > 0.0 { ((b * f - c * e) / den).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let pa = vec3::add_scaled(p0, d1, s);
    let pb = vec3::add_scaled(q0, d2, t);
    (vec3::distance(pa, pb), s, t)
}

/// The minimum clearance of `set` (see the module documentation). `lattice`: the two
/// lattice vectors of a periodic patch (images at −1, 0, +1 in each).
pub fn min_clearance(
    set: &YarnSet,
    lattice: Option<[V3; 2]>,
    radius: f64,
    per_segment: usize,
) -> Clearance {
    let per = per_segment.max(1);
    // Samples: (curve, u, point) per curve, one period of a closed curve plus its end.
    let samples: Vec<Vec<(f64, V3)>> = set
        .curves
        .iter()
        .map(|c| {
            let m = c.segment_count() * per;
            (0..=m)
                .map(|k| {
                    let u = k as f64 / per as f64;
                    (u, c.point(u))
                })
                .collect()
        })
        .collect();
    let images: Vec<(i64, i64)> = match lattice {
        Some(_) => (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))).collect(),
        None => vec![(0, 0)],
    };
    let offset = |(sx, sy): (i64, i64)| {
        lattice.map_or([0.0; 3], |l| {
            vec3::add(vec3::scale(l[0], sx as f64), vec3::scale(l[1], sy as f64))
        })
    };
    let mut chord: f64 = 0.0;
    for s in &samples {
        for w in s.windows(2) {
            chord = chord.max(vec3::distance(w[0].1, w[1].1));
        }
    }
    let cell = (4.0 * radius).max(chord);
    let key = |p: V3| [0, 1, 2].map(|i| (p[i] / cell).floor() as i64);
    // Grid of segments (curve, image, segment index).
    let mut grid: HashMap<[i64; 3], Vec<(u32, u16, u32)>> = HashMap::new();
    for (ci, s) in samples.iter().enumerate() {
        for (ii, &img) in images.iter().enumerate() {
            let off = offset(img);
            for (k, w) in s.windows(2).enumerate() {
                let (a, b) = (vec3::add(w[0].1, off), vec3::add(w[1].1, off));
                let (ka, kb) = (key(a), key(b));
                for x in ka[0].min(kb[0])..=ka[0].max(kb[0]) {
                    for y in ka[1].min(kb[1])..=ka[1].max(kb[1]) {
                        for z in ka[2].min(kb[2])..=ka[2].max(kb[2]) {
                            grid.entry([x, y, z])
                                .or_default()
                                .push((ci as u32, ii as u16, k as u32));
                        }
                    }
                }
            }
        }
    }
    let mut best = (f64::INFINITY, 0usize, 0usize, 0.0, 0.0, [0.0; 3]);
    for (ci, s) in samples.iter().enumerate() {
        for w in s.windows(2) {
            let (a, b) = (w[0].1, w[1].1);
            let (ka, kb) = (key(a), key(b));
            for x in ka[0].min(kb[0]) - 1..=ka[0].max(kb[0]) + 1 {
                for y in ka[1].min(kb[1]) - 1..=ka[1].max(kb[1]) + 1 {
                    for z in ka[2].min(kb[2]) - 1..=ka[2].max(kb[2]) + 1 {
                        let Some(list) = grid.get(&[x, y, z]) else { continue };
                        for &(cj, ii, kj) in list {
                            let img = images[ii as usize];
                            if cj as usize == ci && img.1 == 0 {
                                continue; // the same course (its wale images are the same yarn)
                            }
                            let off = offset(img);
                            let t = &samples[cj as usize];
                            let (q0, q1) = (
                                vec3::add(t[kj as usize].1, off),
                                vec3::add(t[kj as usize + 1].1, off),
                            );
                            let (d, sa, sb) = segment_distance(a, b, q0, q1);
                            if d < best.0 {
                                let ua = w[0].0 + sa * (w[1].0 - w[0].0);
                                let ub = t[kj as usize].0
                                    + sb * (t[kj as usize + 1].0 - t[kj as usize].0);
                                best = (d, ci, cj as usize, ua, ub, off);
                            }
                        }
                    }
                }
            }
        }
    }
    let (mut d, i, j, mut ua, mut ub, off) = best;
    if d.is_finite() {
        let (ca, cb) = (&set.curves[i], &set.curves[j]);
        let dist = |x: f64, y: f64| vec3::distance(ca.point(x), vec3::add(cb.point(y), off));
        d = d.min(dist(ua, ub));
        let mut step = 0.25 / per as f64;
        while step > 1e-10 {
            let mut moved = false;
            for (dx, dy) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
                let e = dist(ua + dx, ub + dy);
                if e < d {
                    d = e;
                    ua += dx;
                    ub += dy;
                    moved = true;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
    }
    let at = d.is_finite().then(|| set.curves[i].point(ua));
    Clearance { distance: d, ratio: d / (2.0 * radius), curves: (i, j), at }
}
