//! Fiber shadow maps (ours; [W19 §4.1] shadows other yarns by tube maps and a yarn's own
//! fibers by the statistical self-shadow volume): the depth of every fiber, hair and core
//! strip as the light sees it — `fiber_lod` and `fiber_draw`'s vertex stage run with the
//! light as the camera, so the strips face the light — read at the shaded fiber's axis
//! moved towards the light by the fiber radius. That is the CPU reference's shadow ray
//! (`yarn_ref`: from the fiber axis, past the fiber's own segment), with what a depth map
//! can resolve: a fiber shadows a point when it covers the texel's centre, so the map must
//! resolve the fibers — a texel is a fraction of a fiber width.
//!
//! That resolution comes from fitting the map to what the camera sees: a directional
//! light's orthographic map spans, across the light, only the part of the yarns' bounding
//! box inside the camera's frustum ([`fitted_view`]; every caster of a seen point lies on
//! the light ray through it, so casters outside that rectangle shadow nothing seen), and in
//! depth the whole box (every caster). A point light outside the yarns gets the
//! perspective counterpart ([`fitted_point_view`]: the square cone from the light about the
//! seen part, in depth the box), so a far point light's map is as fine as the directional
//! light's; among the yarns (inside the box, or so near that the seen part spans more than
//! 120° from it) it keeps [`super::shadow::point_cameras`] over the whole bounding sphere.

use crate::view::ViewSetup;
use crate::{Error, Result};
use nalgebra::{Matrix4, Vector3, Vector4};

/// A half-space `n·p + w ≥ 0`.
type Plane = [f64; 4];

fn inside(pl: &Plane, p: &Vector3<f64>) -> f64 {
    pl[0] * p.x + pl[1] * p.y + pl[2] * p.z + pl[3]
}

/// The part of segment `a`–`b` inside every plane of `planes`, if any.
fn clip_segment(
    a: Vector3<f64>,
    b: Vector3<f64>,
    planes: &[Plane],
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for pl in planes {
        let (da, db) = (inside(pl, &a), inside(pl, &b));
        if da < 0.0 && db < 0.0 {
            return None;
        }
        if da < 0.0 {
            t0 = t0.max(da / (da - db));
        } else if db < 0.0 {
            t1 = t1.min(da / (da - db));
        }
        if t0 > t1 {
            return None;
        }
    }
    Some((a + (b - a) * t0, a + (b - a) * t1))
}

/// The 12 edges of the box with corners `c` (index bits x, y, z).
fn box_edges(c: &[Vector3<f64>; 8]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut out = Vec::with_capacity(12);
    for i in 0..8usize {
        for bit in [1usize, 2, 4] {
            if i & bit == 0 {
                out.push((c[i], c[i | bit]));
            }
        }
    }
    out
}

/// Points whose bounding box is that of the intersection of the axis-aligned box `lo..hi`
/// and the frustum of `cam` (clip `[−1, 1]² × [0, 1]`): the two solids' edges clipped by
/// each other (every vertex of the intersection ends such a clipped edge). Empty when they
/// do not meet.
pub fn visible_part(cam: &ViewSetup, lo: [f64; 3], hi: [f64; 3]) -> Vec<Vector3<f64>> {
    let Some(inv) = cam.view_proj.try_inverse() else { return Vec::new() };
    let corner = |i: usize| {
        let ndc = Vector4::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { 0.0 } else { 1.0 },
            1.0,
        );
        let p = inv * ndc;
        Vector3::new(p.x / p.w, p.y / p.w, p.z / p.w)
    };
    let frustum: [Vector3<f64>; 8] = std::array::from_fn(corner);
    let cube = box_corners(lo, hi);
    let box_planes: Vec<Plane> = (0..3)
        .flat_map(|a| {
            let mut n = [0.0; 3];
            n[a] = 1.0;
            [[n[0], n[1], n[2], -lo[a]], [-n[0], -n[1], -n[2], hi[a]]]
        })
        .collect();
    let frustum_planes = cam.planes();
    let mut out = Vec::new();
    let mut add = |edges: Vec<(Vector3<f64>, Vector3<f64>)>, planes: &[Plane]| {
        for (a, b) in edges {
            if let Some((p, q)) = clip_segment(a, b, planes) {
                out.extend([p, q]);
            }
        }
    };
    add(box_edges(&cube), &frustum_planes);
    if frustum.iter().all(|p| p.iter().all(|x| x.is_finite())) {
        add(box_edges(&frustum), &box_planes);
    }
    out
}

/// The eight corners of the box `lo..hi` (bit `a` of the index: `hi` on axis `a`).
fn box_corners(lo: [f64; 3], hi: [f64; 3]) -> [Vector3<f64>; 8] {
    std::array::from_fn(|i| {
        Vector3::new(
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        )
    })
}

/// [`visible_part`], or the whole box's corners when the camera sees none of it.
fn seen_or_box(cam: &ViewSetup, lo: [f64; 3], hi: [f64; 3]) -> Vec<Vector3<f64>> {
    let seen = visible_part(cam, lo, hi);
    if seen.is_empty() { box_corners(lo, hi).to_vec() } else { seen }
}

/// The orthographic map of the directional light `to_light` (unit, towards the light) for
/// what `cam` sees of the yarns inside `lo..hi` (origin-relative, reach included), `size²`
/// texels: across the light the bounding square of [`visible_part`] (the whole box when
/// the camera sees none of it) with two texels of margin for the PCF taps, in depth the
/// whole box. Its view setup (for `fiber_lod` and `fiber_draw`) and its metres per texel.
pub fn fitted_view(
    to_light: [f64; 3],
    cam: &ViewSetup,
    lo: [f64; 3],
    hi: [f64; 3],
    size: u32,
) -> Result<(ViewSetup, f64)> {
    let d = Vector3::new(to_light[0], to_light[1], to_light[2]);
    if !(d.norm() > 0.0 && d.norm().is_finite()) || size == 0 {
        return Err(Error::Invalid(format!("fiber shadow map: light direction {to_light:?}")));
    }
    let d = d.normalize();
    let up = if d.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
    let f = -d;
    let s = f.cross(&up).normalize();
    let u = s.cross(&f);
    let corners = box_corners(lo, hi);
    let seen = seen_or_box(cam, lo, hi);
    let range = |pts: &[Vector3<f64>], axis: &Vector3<f64>| {
        pts.iter()
            .map(|p| p.dot(axis))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)))
    };
    let (a0, a1) = range(&seen, &s);
    let (b0, b1) = range(&seen, &u);
    let (c0, c1) = range(&corners, &d);
    let extent = (a1 - a0).max(b1 - b0).max(1e-9);
    // Two texels of margin on each side.
    let side = extent * size as f64 / (size as f64 - 4.0).max(1.0);
    let depth = (c1 - c0).max(1e-9) * 1.02;
    let (ac, bc, top) = (0.5 * (a0 + a1), 0.5 * (b0 + b1), c1 + 0.01 * depth);
    let k = 2.0 / side;
    #[rustfmt::skip]
    let view_proj = Matrix4::new(
        k * s.x, k * s.y, k * s.z, -k * ac,
        k * u.x, k * u.y, k * u.z, -k * bc,
        -d.x / depth, -d.y / depth, -d.z / depth, top / depth,
        0.0, 0.0, 0.0, 1.0,
    );
    if !view_proj.iter().all(|x| x.is_finite()) {
        return Err(Error::Invalid("fiber shadow map: degenerate bounds".into()));
    }
    let setup = ViewSetup {
        view_proj,
        eye: s * ac + u * bc + d * top,
        forward: f,
        px_per_metre: size as f64 / side,
        orthographic: true,
    };
    Ok((setup, side / size as f64))
}

/// The perspective map of the point light at `light` (origin-relative) for what `cam` sees
/// of the yarns inside `lo..hi`, `size²` texels: the square cone from the light about the
/// seen part's centre that holds every point of [`visible_part`] (the whole box when the
/// camera sees none of it) with two texels of margin, and in depth the box from its corner
/// nearest the light to its farthest (every caster between a seen point and the light lies
/// in the box, on the ray to that point, so inside the cone). `None` when the light is
/// among the yarns — a box corner at or behind it along the cone's axis, or a seen point
/// more than 60° off that axis — where one map cannot hold what it must.
pub fn fitted_point_view(
    light: [f64; 3],
    cam: &ViewSetup,
    lo: [f64; 3],
    hi: [f64; 3],
    size: u32,
) -> Result<Option<ViewSetup>> {
    let l = Vector3::new(light[0], light[1], light[2]);
    if !l.iter().all(|x| x.is_finite()) || size <= 4 {
        return Err(Error::Invalid(format!(
            "fiber shadow map: point light at {light:?}, {size}² texels"
        )));
    }
    let corners = box_corners(lo, hi);
    let seen = seen_or_box(cam, lo, hi);
    let centre = seen.iter().fold(Vector3::zeros(), |a, p| a + p) / seen.len() as f64;
    let Some(f) = (centre - l).try_normalize(1e-300) else { return Ok(None) };
    let up = if f.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
    let s = f.cross(&up).normalize();
    let u = s.cross(&f);
    // Tangent-plane coordinates of the seen points from the light.
    let max_tan = 60f64.to_radians().tan();
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in &seen {
        let v = p - l;
        let d = v.dot(&f);
        if d <= 0.0 {
            return Ok(None);
        }
        let (tx, ty) = (v.dot(&s) / d, v.dot(&u) / d);
        if tx.abs() > max_tan || ty.abs() > max_tan {
            return Ok(None);
        }
        (x0, x1, y0, y1) = (x0.min(tx), x1.max(tx), y0.min(ty), y1.max(ty));
    }
    let (near, far) = corners
        .iter()
        .map(|c| (c - l).dot(&f))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| (a.min(d), b.max(d)));
    if near <= 1e-3 * far {
        return Ok(None);
    }
    let (near, far) = (0.99 * near, 1.01 * far);
    // Two texels of margin on each side; square texels.
    let half = 0.5 * (x1 - x0).max(y1 - y0).max(1e-9) * size as f64 / (size as f64 - 4.0);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let k = 1.0 / half;
    let rx = (s - f * cx) * k;
    let ry = (u - f * cy) * k;
    let (a, b) = (far / (far - near), -far * near / (far - near));
    let rz = f * a;
    #[rustfmt::skip]
    let view_proj = Matrix4::new(
        rx.x, rx.y, rx.z, -rx.dot(&l),
        ry.x, ry.y, ry.z, -ry.dot(&l),
        rz.x, rz.y, rz.z, -rz.dot(&l) + b,
        f.x, f.y, f.z, -f.dot(&l),
    );
    if !view_proj.iter().all(|x| x.is_finite()) {
        return Err(Error::Invalid("fiber shadow map: degenerate point-light bounds".into()));
    }
    Ok(Some(ViewSetup {
        view_proj,
        eye: l,
        forward: f,
        px_per_metre: size as f64 / (2.0 * half),
        orthographic: false,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::FiberCamera;

    /// Seen points: the camera's rays through a 17 × 17 grid over the frame, at 9 depths,
    /// those inside the box.
    fn seen_points(setup: &ViewSetup, lo: [f64; 3], hi: [f64; 3]) -> Vec<Vector3<f64>> {
        let inv = setup.view_proj.try_inverse().unwrap();
        let mut out = Vec::new();
        for j in 0..=16 {
            for i in 0..=16 {
                for k in 0..=8 {
                    let ndc = Vector4::new(
                        -1.0 + i as f64 / 8.0,
                        -1.0 + j as f64 / 8.0,
                        k as f64 / 8.0,
                        1.0,
                    );
                    let p = inv * ndc;
                    let p = Vector3::new(p.x, p.y, p.z) / p.w;
                    if (0..3).all(|a| p[a] >= lo[a] - 1e-12 && p[a] <= hi[a] + 1e-12) {
                        out.push(p);
                    }
                }
            }
        }
        assert!(out.len() > 100, "{} seen points", out.len());
        out
    }

    fn project(m: &Matrix4<f64>, p: &Vector3<f64>) -> [f64; 3] {
        let c = m * Vector4::new(p.x, p.y, p.z, 1.0);
        [0.5 * c.x / c.w + 0.5, 0.5 - 0.5 * c.y / c.w, c.z / c.w]
    }

    #[test]
    fn a_fitted_map_holds_every_seen_point_and_every_caster_at_a_tenth_of_the_box() {
        // A flat patch 40 mm × 40 mm × 3 mm, the camera looking obliquely at its middle
        // 10 mm × 10 mm (the periodic tests' 3 × 3 tiles and their centre tile).
        let (lo, hi) = ([-0.02, -0.02, -0.0015], [0.02, 0.02, 0.0015]);
        let view = btf_core::Direction::new(45.0, 30.0).to_vector();
        let cam = FiberCamera::oblique(view, 0.0015, [-0.005, -0.005], [0.01, 0.01]);
        let setup = ViewSetup::new(&cam, [0.0; 3], [0.0; 3], 0.029, (48, 48)).unwrap();
        let to_light = btf_core::Direction::new(30.0, 200.0).to_vector();
        let (map, texel) = fitted_view(to_light, &setup, lo, hi, 1024).unwrap();
        for p in seen_points(&setup, lo, hi) {
            let x = project(&map.view_proj, &p);
            assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{p:?} → {x:?}");
            // Every caster above it on the light ray is in depth range too.
            for t in [0.0, 0.01, 0.05] {
                let q = p + Vector3::new(to_light[0], to_light[1], to_light[2]) * t;
                if (0..3).all(|a| q[a] >= lo[a] && q[a] <= hi[a]) {
                    let y = project(&map.view_proj, &q);
                    assert!((0.0..=1.0).contains(&y[2]), "caster {q:?} depth {}", y[2]);
                }
            }
        }
        // The seen part is the centre tile's oblique prism through the 3-mm box: its
        // shadow spans ~14 mm of the light's plane, not the box's 57-mm diagonal.
        let side = texel * 1024.0;
        assert!(side < 0.02, "map side {side} m");
        assert!(side > 0.01, "map side {side} m");
    }

    #[test]
    fn a_fitted_point_map_holds_every_seen_point_and_its_casters() {
        let (lo, hi) = ([-0.02, -0.02, -0.0015], [0.02, 0.02, 0.0015]);
        let view = btf_core::Direction::new(45.0, 30.0).to_vector();
        let cam = FiberCamera::oblique(view, 0.0015, [-0.005, -0.005], [0.01, 0.01]);
        let setup = ViewSetup::new(&cam, [0.0; 3], [0.0; 3], 0.029, (48, 48)).unwrap();
        let to_light = btf_core::Direction::new(30.0, 200.0).to_vector();
        for dist in [0.05, 3.0] {
            let light = to_light.map(|x| x * dist);
            let l = Vector3::new(light[0], light[1], light[2]);
            let map = fitted_point_view(light, &setup, lo, hi, 1024).unwrap().unwrap();
            for p in seen_points(&setup, lo, hi) {
                let x = project(&map.view_proj, &p);
                assert!(x.iter().all(|v| (0.0..=1.0).contains(v)), "{p:?} → {x:?}");
                // Every caster between it and the light, inside the box, too.
                for t in [0.1, 0.3, 0.6, 0.9] {
                    let q = p + (l - p) * t;
                    if (0..3).all(|a| q[a] >= lo[a] && q[a] <= hi[a]) {
                        let y = project(&map.view_proj, &q);
                        assert!(y.iter().all(|v| (0.0..=1.0).contains(v)), "caster {q:?} → {y:?}");
                    }
                }
            }
            // From 3 m the map spans about what the directional light's does: the seen
            // prism's ~14 mm at that distance, not the 57-mm diagonal of the box.
            if dist > 1.0 {
                let span = 3.0 * 1024.0 / map.px_per_metre;
                assert!(span > 0.01 && span < 0.02, "map span {span} m at 3 m");
            }
        }
        // Among the yarns: no single map.
        assert!(fitted_point_view([0.0, 0.0, 0.0], &setup, lo, hi, 1024).unwrap().is_none());
        assert!(fitted_point_view([0.0, 0.0, 0.002], &setup, lo, hi, 1024).unwrap().is_none());
    }

    #[test]
    fn clipped_edges_bound_the_intersection() {
        // A unit box and a frustum-free clip by two planes x ≤ 0.5, y ≤ 0.25.
        let planes = [[-1.0, 0.0, 0.0, 0.5], [0.0, -1.0, 0.0, 0.25]];
        let (p, q) =
            clip_segment(Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0), &planes)
                .unwrap();
        assert!((p - Vector3::new(0.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((q - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
        assert!(
            clip_segment(Vector3::new(0.0, 0.5, 0.0), Vector3::new(1.0, 0.5, 0.0), &planes)
                .is_none()
        );
    }
}
