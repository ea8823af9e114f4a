//! A small software rasteriser for looking at meshes without a GPU: perspective camera,
//! z-buffer, Lambert shading from a head light, and optional stripes along a texture
//! coordinate (to see where a panel's grain runs). For development and test pictures only;
//! the product's renders are `btf render`'s.

use crate::mesh::Mesh;
use crate::vec3::{V3, cross, dot, normalize_or, sub};
use crate::{Error, Result};
use std::path::Path;

/// One mesh in a preview: its colour (linear RGB) and stripes every `stripe_m` metres of
/// texture `u` (0 = none).
pub struct PreviewItem<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// Linear RGB albedo.
    pub colour: [f64; 3],
    /// Stripe period along `u` (m of UV), 0 for none.
    pub stripe_m: f64,
}

/// Renders `items` seen from `eye` towards `target` (`+z` up) into a `w × h` PNG.
pub fn render_png(
    items: &[PreviewItem],
    eye: V3,
    target: V3,
    fov_y_deg: f64,
    w: usize,
    h: usize,
    path: &Path,
) -> Result<()> {
    let fwd = normalize_or(sub(target, eye), [0.0, 1.0, 0.0]);
    let right = normalize_or(cross(fwd, [0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]);
    let up = cross(right, fwd);
    let f = 0.5 * h as f64 / (0.5 * fov_y_deg.to_radians()).tan();
    let project = |p: V3| {
        let d = sub(p, eye);
        let z = dot(d, fwd);
        [0.5 * w as f64 + f * dot(d, right) / z, 0.5 * h as f64 - f * dot(d, up) / z, z]
    };
    let mut depth = vec![f64::INFINITY; w * h];
    let mut rgb = vec![[0.03f64, 0.03, 0.04]; w * h];
    let light =
        normalize_or(sub([eye[0] - 0.8, eye[1] + 0.3, eye[2] + 1.5], target), [0.0, 0.0, 1.0]);
    for it in items {
        let m = it.mesh;
        for (ti, t) in m.triangles.iter().enumerate() {
            let p = t.map(|i| project(m.positions[i as usize]));
            if p.iter().any(|q| q[2] <= 1e-3) {
                continue;
            }
            let n = t.map(|i| m.normals.get(i as usize).copied().unwrap_or([0.0, 0.0, 1.0]));
            let uv = m.triangle_uvs.get(ti).map(|tu| tu.map(|i| m.uvs[i as usize]));
            let x0 = p.iter().map(|q| q[0]).fold(f64::MAX, f64::min).floor().max(0.0) as usize;
            let x1 = (p.iter().map(|q| q[0]).fold(f64::MIN, f64::max).ceil() as usize)
                .min(w.saturating_sub(1));
            let y0 = p.iter().map(|q| q[1]).fold(f64::MAX, f64::min).floor().max(0.0) as usize;
            let y1 = (p.iter().map(|q| q[1]).fold(f64::MIN, f64::max).ceil() as usize)
                .min(h.saturating_sub(1));
            let area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
            if area.abs() < 1e-12 {
                continue;
            }
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |a: [f64; 3], b: [f64; 3]| {
                        (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])
                    };
                    let l = [e(p[1], p[2]) / area, e(p[2], p[0]) / area, e(p[0], p[1]) / area];
                    if l.iter().any(|&v| v < 0.0) {
                        continue;
                    }
                    let z = l[0] * p[0][2] + l[1] * p[1][2] + l[2] * p[2][2];
                    let cell = y * w + x;
                    if z >= depth[cell] {
                        continue;
                    }
                    depth[cell] = z;
                    let nrm: V3 =
                        std::array::from_fn(|k| l[0] * n[0][k] + l[1] * n[1][k] + l[2] * n[2][k]);
                    let nrm = normalize_or(nrm, [0.0, 0.0, 1.0]);
                    let shade = 0.18 + 0.82 * dot(nrm, light).abs();
                    let mut stripe = 1.0;
                    if let (Some(uv), true) = (uv, it.stripe_m > 0.0) {
                        let u = l[0] * uv[0][0] + l[1] * uv[1][0] + l[2] * uv[2][0];
                        let s = (std::f64::consts::TAU * u / it.stripe_m).sin();
                        stripe = 0.72 + 0.28 * s;
                    }
                    rgb[cell] = std::array::from_fn(|k| it.colour[k] * shade * stripe);
                }
            }
        }
    }
    let bytes: Vec<u8> = rgb
        .iter()
        .flat_map(|c| c.map(|v| (255.0 * v.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8))
        .collect();
    image::save_buffer(path, &bytes, w as u32, h as u32, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::Image { path: path.to_path_buf(), what: e.to_string() })
}
