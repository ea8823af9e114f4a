//! Meshes with normals and UVs for rendering BTFs on: a plane, a sphere, a curtain, a
//! cloth draped over a sphere by a mass-spring simulation ([`cloth`], after Chen et al.
//! 2003 §4) and simple garments ([`shapes`]), written as OBJ.
//!
//! **Conventions.** World `+z` is up; lengths are metres. UVs follow OBJ (`v` up): texel
//! `(x, y)` of an `H × W` normtexture sits at `u = (x + ½)/W`, `v = 1 − (y + ½)/H`, so the
//! texture's increasing-row direction is `−∂P/∂v`. Every chart is laid out so that
//! `∂P/∂u × ∂P/∂v` points along the outward (front) normal: a texture shown upright
//! appears upright, unmirrored, on the front side. The plane and the sphere span
//! `[0, 1]²`; the curtain, drape and garments use one UV unit per metre of fabric, so one
//! material scale fits all of them (the BTF tiles). Normals are area-weighted vertex
//! normals over the welded positions, so they are smooth across UV seams.

pub mod cloth;
pub mod obj;
pub mod shapes;

pub use obj::{read_obj, write_obj, write_obj_material};

use crate::vec3::{V3, cross, length, normalize_or, sub};
use crate::{Error, Result};
use std::collections::HashMap;

/// A triangle mesh with per-position normals and a separate UV index per corner.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions (metres).
    pub positions: Vec<V3>,
    /// Unit normal per position.
    pub normals: Vec<V3>,
    /// Texture coordinates (OBJ convention, `v` up).
    pub uvs: Vec<[f64; 2]>,
    /// Position (and normal) indices of each triangle, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// UV indices of each triangle's corners.
    pub triangle_uvs: Vec<[u32; 3]>,
    /// Material names (OBJ `usemtl`, declared in the `mtllib` written beside the OBJ);
    /// empty for a mesh without materials.
    pub material_names: Vec<String>,
    /// Index into `material_names` of each triangle; empty when there are no materials.
    pub triangle_material: Vec<u32>,
}

/// The mesh kinds of `btf synth mesh`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshKind {
    /// 1 × 1 m square in the `xy` plane, normal `+z`.
    Plane,
    /// UV sphere of radius 0.5 m (closed).
    Sphere,
    /// 1 × 1 m cloth dropped over a sphere of radius 0.3 m standing on the ground.
    Drape,
    /// 1.2 × 1.5 m curtain with pleats, front facing `−y`.
    Curtain,
    /// Shirt: torso and two sleeves with folds.
    Shirt,
    /// Trousers: hip part and two legs with folds.
    Trousers,
}

impl MeshKind {
    /// Parses a lower-case name.
    pub fn from_name(name: &str) -> Result<Self> {
        Ok(match name {
            "plane" => MeshKind::Plane,
            "sphere" => MeshKind::Sphere,
            "drape" => MeshKind::Drape,
            "curtain" => MeshKind::Curtain,
            "shirt" => MeshKind::Shirt,
            "trousers" => MeshKind::Trousers,
            other => {
                return Err(Error::Invalid(format!(
                    "unknown mesh kind '{other}' (known: plane, sphere, drape, curtain, shirt, trousers)"
                )));
            }
        })
    }
}

/// Mesh density: about 900 (`Low`) or 9000 (`High`) vertices, like Sattler et al. 2003,
/// Table 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    /// About 900 vertices.
    Low,
    /// About 9000 vertices.
    High,
}

impl Resolution {
    /// Parses `low` or `high`.
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "low" => Ok(Resolution::Low),
            "high" => Ok(Resolution::High),
            other => {
                Err(Error::Invalid(format!("unknown resolution '{other}' (known: low, high)")))
            }
        }
    }
}

/// Builds a mesh of `kind` at `res`.
pub fn synth_mesh(kind: MeshKind, res: Resolution) -> Result<Mesh> {
    let hi = res == Resolution::High;
    Ok(match kind {
        MeshKind::Plane => shapes::plane(if hi { 95 } else { 30 }),
        MeshKind::Sphere => shapes::sphere(if hi { (128, 71) } else { (40, 23) }),
        MeshKind::Curtain => shapes::curtain(if hi { (120, 75) } else { (36, 25) }),
        MeshKind::Drape => cloth::drape(&cloth::DrapeParams::new(if hi { 95 } else { 30 }))?.mesh,
        MeshKind::Shirt => shapes::shirt(hi),
        MeshKind::Trousers => shapes::trousers(hi),
    })
}

impl Mesh {
    /// Gives the triangles added since the last call (all untagged ones) material `name`.
    pub fn tag_material(&mut self, name: &str) {
        let id = self.material_names.len() as u32;
        self.material_names.push(name.to_owned());
        self.triangle_material.resize(self.triangles.len(), id);
    }

    /// Appends a `nu × nv` grid chart: `pos(s, t)` and `uv(s, t)` for `s, t ∈ [0, 1]`;
    /// with `wrap`, the column `s = 1` reuses the positions of `s = 0` (a closed tube)
    /// while keeping its own UVs.
    pub fn add_grid(
        &mut self,
        nu: usize,
        nv: usize,
        wrap: bool,
        pos: impl Fn(f64, f64) -> V3,
        uv: impl Fn(f64, f64) -> [f64; 2],
    ) {
        let p0 = self.positions.len() as u32;
        let t0 = self.uvs.len() as u32;
        let cols = if wrap { nu } else { nu + 1 };
        for j in 0..=nv {
            for i in 0..cols {
                self.positions.push(pos(i as f64 / nu as f64, j as f64 / nv as f64));
            }
            for i in 0..=nu {
                self.uvs.push(uv(i as f64 / nu as f64, j as f64 / nv as f64));
            }
        }
        let p = |i: usize, j: usize| p0 + (j * cols + if wrap { i % nu } else { i }) as u32;
        let t = |i: usize, j: usize| t0 + (j * (nu + 1) + i) as u32;
        for j in 0..nv {
            for i in 0..nu {
                self.triangles.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                self.triangle_uvs.push([t(i, j), t(i + 1, j), t(i + 1, j + 1)]);
                self.triangles.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
                self.triangle_uvs.push([t(i, j), t(i + 1, j + 1), t(i, j + 1)]);
            }
        }
    }

    /// Recomputes area-weighted vertex normals from the triangles.
    pub fn compute_normals(&mut self) {
        let mut n = vec![[0.0; 3]; self.positions.len()];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|i| self.positions[i as usize]);
            let f = cross(sub(b, a), sub(c, a));
            for &i in tri {
                (0..3).for_each(|k| n[i as usize][k] += f[k]);
            }
        }
        self.normals = n.into_iter().map(|v| normalize_or(v, [0.0, 0.0, 1.0])).collect();
    }

    /// Smallest triangle area (m²).
    pub fn min_triangle_area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                0.5 * length(cross(sub(b, a), sub(c, a)))
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Edges used by exactly one triangle (open boundary) and by more than two
    /// (non-manifold), over the position indices.
    pub fn edge_counts(&self) -> (usize, usize) {
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let boundary = uses.values().filter(|&&c| c == 1).count();
        let non_manifold = uses.values().filter(|&&c| c > 2).count();
        (boundary, non_manifold)
    }

    /// Triangles whose UV layout is mirrored with respect to their winding (clockwise or
    /// degenerate in UV space while counter-clockwise in space); zero for every mesh made
    /// here, so `∂P/∂u × ∂P/∂v` agrees with the front normal everywhere.
    pub fn mirrored_uv_triangles(&self) -> usize {
        self.triangle_uvs
            .iter()
            .filter(|tu| {
                let [a, b, c] = tu.map(|i| self.uvs[i as usize]);
                (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) <= 0.0
            })
            .count()
    }
}
