//! The collision proxy of a closed mesh: its signed distance (negative inside) sampled on a
//! regular grid, exact within a narrow band around the surface (point–triangle distances)
//! and clamped to ±band beyond, the sign from the parity of ray crossings along `+x` rows.
//! Queries interpolate trilinearly and return the gradient of the interpolant (the contact
//! normal), so a drape asks "how far, which way out" in a few multiplications per vertex.

use crate::mesh::Mesh;
use crate::vec3::{V3, add, cross, dot, length, normalize_or, scale, sub};
use crate::{Error, Result};
use rayon::prelude::*;

/// Signed distance samples on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGrid {
    /// Position of sample `(0, 0, 0)`.
    pub origin: V3,
    /// Grid step (m).
    pub step: f64,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Distances (m), `x` fastest.
    pub values: Vec<f32>,
    /// Distances are exact up to this value and clamped beyond it (m).
    pub band: f64,
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection §5.1.5)
/// and its barycentric weights.
pub fn closest_point_triangle(p: V3, a: V3, b: V3, c: V3) -> (V3, [f64; 3]) {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add(a, scale(ab, v)), [1.0 - v, v, 0.0]);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add(a, scale(ac, w)), [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add(b, scale(sub(c, b), w)), [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (add(a, add(scale(ab, v), scale(ac, w))), [1.0 - v - w, v, w])
}

impl SdfGrid {
    /// Samples the signed distance of the closed mesh every `step` metres, exactly within
    /// `band` of the surface.
    pub fn from_mesh(mesh: &Mesh, step: f64, band: f64) -> Result<SdfGrid> {
        if !(step.is_finite() && step > 0.0 && band.is_finite() && band >= 2.0 * step) {
            return Err(Error::Invalid(format!(
                "sdf: step {step} and band {band} (need band ≥ 2 step > 0)"
            )));
        }
        if mesh.triangles.is_empty() {
            return Err(Error::Invalid("sdf: the mesh has no triangles".into()));
        }
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for p in &mesh.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let pad = band + 2.0 * step;
        // An irrational offset keeps sample rows off the vertices of grid-made meshes.
        let origin: V3 = std::array::from_fn(|k| lo[k] - pad + 0.2718281828 * step);
        let dims: [usize; 3] =
            std::array::from_fn(|k| ((hi[k] + pad - origin[k]) / step).ceil() as usize + 1);
        let cells = dims[0] * dims[1] * dims[2];
        if cells > 200_000_000 {
            return Err(Error::Invalid(format!(
                "sdf: {cells} samples is too many (raise the step)"
            )));
        }
        let (nx, ny, nz) = (dims[0], dims[1], dims[2]);
        let tri: Vec<[V3; 3]> =
            mesh.triangles.iter().map(|t| t.map(|i| mesh.positions[i as usize])).collect();
        // Triangles by the z-planes their band-inflated boxes reach.
        let plane_range = |t: &[V3; 3], inflate: f64| {
            let z0 = t.iter().map(|p| p[2]).fold(f64::MAX, f64::min) - inflate;
            let z1 = t.iter().map(|p| p[2]).fold(f64::MIN, f64::max) + inflate;
            let k0 = ((z0 - origin[2]) / step).ceil().max(0.0) as usize;
            let k1 = (((z1 - origin[2]) / step).floor() as isize).min(nz as isize - 1);
            (k0, k1)
        };
        let mut by_plane: Vec<Vec<u32>> = vec![Vec::new(); nz];
        let mut by_plane_exact: Vec<Vec<u32>> = vec![Vec::new(); nz];
        for (ti, t) in tri.iter().enumerate() {
            let (k0, k1) = plane_range(t, band);
            if k1 >= k0 as isize {
                for k in k0..=k1 as usize {
                    by_plane[k].push(ti as u32);
                }
            }
            let (k0, k1) = plane_range(t, 0.0);
            if k1 >= k0 as isize {
                for k in k0..=k1 as usize {
                    by_plane_exact[k].push(ti as u32);
                }
            }
        }
        let mut values = vec![0f32; cells];
        values.par_chunks_mut(nx * ny).enumerate().for_each(|(k, slab)| {
            let z = origin[2] + k as f64 * step;
            let mut dist = vec![band; nx * ny];
            for &ti in &by_plane[k] {
                let t = &tri[ti as usize];
                let mut blo = [f64::MAX; 2];
                let mut bhi = [f64::MIN; 2];
                for p in t {
                    for a in 0..2 {
                        blo[a] = blo[a].min(p[a] - band);
                        bhi[a] = bhi[a].max(p[a] + band);
                    }
                }
                let i0 = ((blo[0] - origin[0]) / step).ceil().max(0.0) as usize;
                let i1 = (((bhi[0] - origin[0]) / step).floor() as usize).min(nx - 1);
                let j0 = ((blo[1] - origin[1]) / step).ceil().max(0.0) as usize;
                let j1 = (((bhi[1] - origin[1]) / step).floor() as usize).min(ny - 1);
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let p = [origin[0] + i as f64 * step, origin[1] + j as f64 * step, z];
                        let (c, _) = closest_point_triangle(p, t[0], t[1], t[2]);
                        let d = length(sub(p, c));
                        let cell = &mut dist[j * nx + i];
                        if d < *cell {
                            *cell = d;
                        }
                    }
                }
            }
            // Sign: parity of crossings of the +x ray of each row with the triangles.
            let mut crossings: Vec<Vec<f64>> = vec![Vec::new(); ny];
            for &ti in &by_plane_exact[k] {
                let t = &tri[ti as usize];
                let ylo = t.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
                let yhi = t.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
                let j0 = ((ylo - origin[1]) / step).ceil().max(0.0) as usize;
                let j1 = ((yhi - origin[1]) / step).floor();
                if j1 < 0.0 {
                    continue;
                }
                for j in j0..=(j1 as usize).min(ny - 1) {
                    let y = origin[1] + j as f64 * step;
                    if let Some(x) = row_crossing(t, y, z) {
                        crossings[j].push(x);
                    }
                }
            }
            for j in 0..ny {
                let xs = &mut crossings[j];
                xs.sort_by(f64::total_cmp);
                let usable = xs.len().is_multiple_of(2);
                for i in 0..nx {
                    let x = origin[0] + i as f64 * step;
                    let before = xs.partition_point(|&c| c < x);
                    let inside = usable && before % 2 == 1;
                    let d = dist[j * nx + i];
                    slab[j * nx + i] = if inside { -d as f32 } else { d as f32 };
                }
            }
        });
        Ok(SdfGrid { origin, step, dims, values, band })
    }

    fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values[(k * self.dims[1] + j) * self.dims[0] + i] as f64
    }

    /// Signed distance at `p` (m) and the unit gradient (outward normal); outside the grid,
    /// the band's value and the direction away from the grid's centre.
    pub fn query(&self, p: V3) -> (f64, V3) {
        let g: V3 = std::array::from_fn(|k| (p[k] - self.origin[k]) / self.step);
        let inside_grid = (0..3).all(|k| g[k] >= 0.0 && g[k] < (self.dims[k] - 1) as f64);
        if !inside_grid {
            let centre: V3 = std::array::from_fn(|k| {
                self.origin[k] + 0.5 * self.step * (self.dims[k] - 1) as f64
            });
            return (self.band, normalize_or(sub(p, centre), [0.0, 0.0, 1.0]));
        }
        let (i, j, k) = (g[0] as usize, g[1] as usize, g[2] as usize);
        let (fx, fy, fz) = (g[0] - i as f64, g[1] - j as f64, g[2] - k as f64);
        let c = |a: usize, b: usize, c: usize| self.at(i + a, j + b, k + c);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let (c00, c10) = (lerp(c(0, 0, 0), c(1, 0, 0), fx), lerp(c(0, 1, 0), c(1, 1, 0), fx));
        let (c01, c11) = (lerp(c(0, 0, 1), c(1, 0, 1), fx), lerp(c(0, 1, 1), c(1, 1, 1), fx));
        let (c0, c1) = (lerp(c00, c10, fy), lerp(c01, c11, fy));
        let d = lerp(c0, c1, fz);
        let dx = {
            let y0 = lerp(c(1, 0, 0) - c(0, 0, 0), c(1, 1, 0) - c(0, 1, 0), fy);
            let y1 = lerp(c(1, 0, 1) - c(0, 0, 1), c(1, 1, 1) - c(0, 1, 1), fy);
            lerp(y0, y1, fz)
        };
        let dy = {
            let x0 = lerp(c(0, 1, 0) - c(0, 0, 0), c(1, 1, 0) - c(1, 0, 0), fx);
            let x1 = lerp(c(0, 1, 1) - c(0, 0, 1), c(1, 1, 1) - c(1, 0, 1), fx);
            lerp(x0, x1, fz)
        };
        let dz = c1 - c0;
        (d, normalize_or([dx, dy, dz], [0.0, 0.0, 1.0]))
    }
}

/// `x` where the line `{(·, y, z)}` crosses triangle `t` (half-open edge rules, so a row
/// through a shared edge counts once).
fn row_crossing(t: &[V3; 3], y: f64, z: f64) -> Option<f64> {
    let e = |a: V3, b: V3| (b[1] - a[1]) * (z - a[2]) - (b[2] - a[2]) * (y - a[1]);
    let w = [e(t[1], t[2]), e(t[2], t[0]), e(t[0], t[1])];
    let area = w[0] + w[1] + w[2];
    if area == 0.0 {
        return None;
    }
    let top_left = |a: V3, b: V3| {
        let (dy, dz) = (b[1] - a[1], b[2] - a[2]);
        dz > 0.0 || (dz == 0.0 && dy < 0.0)
    };
    let sgn = area.signum();
    let edges = [(t[1], t[2]), (t[2], t[0]), (t[0], t[1])];
    for q in 0..3 {
        let v = w[q] * sgn;
        let (a, b) = if sgn > 0.0 { edges[q] } else { (edges[q].1, edges[q].0) };
        if v < 0.0 || (v == 0.0 && !top_left(a, b)) {
            return None;
        }
    }
    let l = [w[0] / area, w[1] / area, w[2] / area];
    Some(l[0] * t[0][0] + l[1] * t[1][0] + l[2] * t[2][0])
}

/// Normal of triangle `abc` (unit; zero for a degenerate one).
pub fn unit_normal(a: V3, b: V3, c: V3) -> V3 {
    normalize_or(cross(sub(b, a), sub(c, a)), [0.0; 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_distance_is_exact_in_the_band_and_signed() {
        let m = crate::mesh::shapes::sphere((64, 33));
        let g = SdfGrid::from_mesh(&m, 0.02, 0.08).unwrap();
        for p in [
            [0.0, 0.0, 0.0],
            [0.3, 0.1, -0.2],
            [0.52, 0.0, 0.0],
            [0.1, 0.45, 0.1],
            [0.0, -0.0, 0.56],
        ] {
            let (d, n) = g.query(p);
            let exact = length(p) - 0.5;
            let want = exact.clamp(-0.08, 0.08);
            assert!((d - want).abs() < 4e-3, "{p:?}: {d} vs {want}");
            if exact.abs() < 0.05 && length(p) > 0.0 {
                assert!(dot(n, normalize_or(p, [0.0; 3])) > 0.99, "{p:?}: normal {n:?}");
            }
        }
    }
}
