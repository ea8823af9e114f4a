//! Parametric meshes: plane, UV sphere, pleated curtain and simple garments (shirt,
//! trousers) made of tubes whose radius carries folds (sinusoidal pleats around and
//! wrinkles along the tube), enough relief for self-shadowing. Garment parts overlap where
//! they join (a sleeve starts inside the torso); each part is its own UV chart.

use super::Mesh;
use crate::vec3::{V3, add, cross, normalize_or, scale};
use std::f64::consts::PI;

/// 1 × 1 m plane in `z = 0` (normal `+z`) with `n × n` vertices; `u = x`, `v = y`.
pub fn plane(n: usize) -> Mesh {
    let mut m = Mesh::default();
    let k = n.max(2) - 1;
    m.add_grid(k, k, false, |s, t| [s - 0.5, t - 0.5, 0.0], |s, t| [s, t]);
    m.compute_normals();
    m
}

/// UV sphere of radius 0.5 m: `nu` columns, `nv` bands; `u = φ/2π` (east), `v = 1 − θ/π`.
pub fn sphere((nu, nv): (usize, usize)) -> Mesh {
    let r = 0.5;
    let at = |s: f64, t: f64| {
        let (theta, phi) = (PI * (1.0 - t), 2.0 * PI * s);
        [r * theta.sin() * phi.cos(), r * theta.sin() * phi.sin(), r * theta.cos()]
    };
    let mut m = Mesh::default();
    // Interior bands as a wrapped grid from the first to the last ring.
    let (t0, t1) = (1.0 / nv as f64, 1.0 - 1.0 / nv as f64);
    m.add_grid(nu, nv - 2, true, |s, t| at(s, t0 + (t1 - t0) * t), |s, t| [s, t0 + (t1 - t0) * t]);
    // Pole caps: one position per pole, one UV per cap triangle.
    let south = m.positions.len() as u32;
    m.positions.push([0.0, 0.0, -r]);
    m.positions.push([0.0, 0.0, r]);
    let last_ring = ((nv - 2) * nu) as u32;
    let uv_cols = nu + 1;
    let last_uv_row = ((nv - 2) * uv_cols) as u32;
    for i in 0..nu {
        let (a, b) = (i as u32, ((i + 1) % nu) as u32);
        let pole_uv = m.uvs.len() as u32;
        m.uvs.push([(i as f64 + 0.5) / nu as f64, 0.0]);
        m.uvs.push([(i as f64 + 0.5) / nu as f64, 1.0]);
        m.triangles.push([south, b, a]);
        m.triangle_uvs.push([pole_uv, i as u32 + 1, i as u32]);
        m.triangles.push([last_ring + a, last_ring + b, south + 1]);
        m.triangle_uvs.push([last_uv_row + i as u32, last_uv_row + i as u32 + 1, pole_uv + 1]);
    }
    m.compute_normals();
    m
}

/// Curtain 1.2 m wide, 1.5 m high, hanging in the `xz` plane with its front towards `−y`;
/// pleats deepen towards the hem. `u = x`, `v = z` in metres.
pub fn curtain((nu, nv): (usize, usize)) -> Mesh {
    let (w, h) = (1.2, 1.5);
    let mut m = Mesh::default();
    m.add_grid(
        nu,
        nv,
        false,
        |s, t| {
            let depth = 0.025 + 0.045 * (1.0 - t);
            let y = depth * (2.0 * PI * 7.0 * s + 0.6 * (3.0 * t).sin()).sin();
            [w * (s - 0.5), y, h * t]
        },
        |s, t| [w * s, h * t],
    );
    m.compute_normals();
    m
}

/// The axis of a [`tube`]: from `base` along unit `dir` for `len`; `side` is the unit
/// vector at angle 0.
struct TubeAxis {
    base: V3,
    dir: V3,
    side: V3,
    len: f64,
}

/// A tube around `axis`, radius `radius(s, t)` at angle `2πs` and fraction `t` of the
/// length. UVs: `u` = arc length around (m) + `u0`, `v` = distance along the axis (m).
fn tube(
    m: &mut Mesh,
    (nu, nv): (usize, usize),
    TubeAxis { base, dir: axis, side, len }: TubeAxis,
    u0: f64,
    radius: impl Fn(f64, f64) -> f64,
) {
    let other = cross(axis, side);
    let mean_r = radius(0.0, 0.5);
    m.add_grid(
        nu,
        nv,
        true,
        |s, t| {
            let (sn, cs) = (2.0 * PI * s).sin_cos();
            let dir = add(scale(side, cs), scale(other, sn));
            add(add(base, scale(axis, len * t)), scale(dir, radius(s, t)))
        },
        |s, t| [u0 + 2.0 * PI * mean_r * s, len * t],
    );
}

/// A shirt: torso (elliptic tube narrowing to the neck) and two sleeves with folds.
/// About 880 vertices (`high = false`) or 9000.
pub fn shirt(high: bool) -> Mesh {
    let (torso, sleeve) = if high { ((96, 51), (48, 41)) } else { ((32, 16), (12, 13)) };
    let mut m = Mesh::default();
    let torso_axis =
        TubeAxis { base: [0.0; 3], dir: [0.0, 0.0, 1.0], side: [1.0, 0.0, 0.0], len: 0.72 };
    tube(&mut m, torso, torso_axis, 0.0, |s, t| {
        let phi = 2.0 * PI * s;
        let (a, b) = (0.19, 0.12);
        let ellipse = a * b / ((b * phi.cos()).powi(2) + (a * phi.sin()).powi(2)).sqrt();
        let shoulder = if t > 0.82 { 1.0 - 0.55 * ((t - 0.82) / 0.18).powf(1.5) } else { 1.0 };
        let folds =
            1.0 + 0.08 * (1.0 - t) * (7.0 * phi + 3.0 * t).sin() + 0.025 * (38.0 * t + phi).sin();
        ellipse * shoulder * folds
    });
    for side in [-1.0f64, 1.0] {
        let angle = 40f64.to_radians();
        // From the cuff up to the shoulder (ending inside the torso), so v points up.
        let axis = [-side * angle.cos(), 0.0, angle.sin()];
        let shoulder = [side * 0.14, 0.0, 0.6];
        let len = 0.58;
        let base = add(shoulder, scale(axis, -len));
        let side_vec = normalize_or(cross(axis, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        let sleeve_axis = TubeAxis { base, dir: axis, side: side_vec, len };
        tube(&mut m, sleeve, sleeve_axis, 2.0 + side, |s, t| {
            let r = 0.05 + 0.025 * t;
            r * (1.0
                + 0.07 * (28.0 * t + 2.0 * PI * s).sin() * (1.0 - t)
                + 0.04 * (5.0 * 2.0 * PI * s).sin())
        });
    }
    m.compute_normals();
    m
}

/// Trousers: a hip tube from the waist to below the crotch and two legs with folds
/// pooling at the hem. About 900 vertices (`high = false`) or 9000.
pub fn trousers(high: bool) -> Mesh {
    let (hip, leg) = if high { ((96, 31), (72, 40)) } else { ((32, 8), (24, 12)) };
    let mut m = Mesh::default();
    let hip_axis =
        TubeAxis { base: [0.0, 0.0, 0.7], dir: [0.0, 0.0, 1.0], side: [1.0, 0.0, 0.0], len: 0.3 };
    tube(&mut m, hip, hip_axis, 0.0, |s, t| {
        let phi = 2.0 * PI * s;
        let (a, b) = (0.2 - 0.02 * t, 0.14 - 0.02 * t);
        let ellipse = a * b / ((b * phi.cos()).powi(2) + (a * phi.sin()).powi(2)).sqrt();
        ellipse * (1.0 + 0.02 * (9.0 * phi).sin() * t)
    });
    for (k, side) in [-1.0f64, 1.0].into_iter().enumerate() {
        tube(
            &mut m,
            leg,
            TubeAxis {
                base: [side * 0.1, 0.0, 0.0],
                dir: [0.0, 0.0, 1.0],
                side: [1.0, 0.0, 0.0],
                len: 0.8,
            },
            2.0 + k as f64,
            |s, t| {
                let phi = 2.0 * PI * s;
                let r = 0.075 + 0.025 * t;
                let pooling = 0.08 * (1.0 - t).powi(3) * (22.0 * t + 3.0 * phi).sin();
                let knee = 0.04 * (-((t - 0.45) / 0.08).powi(2)).exp() * (4.0 * phi).sin();
                r * (1.0 + pooling + knee + 0.03 * (6.0 * phi + 9.0 * t).sin())
            },
        );
    }
    m.compute_normals();
    m
}
