//! Inverse UV lookup: which surface point has texture coordinates `(u, v)`?
//! (DESIGN §1.6: a chart is mapped onto a garment through its UVs.)
//!
//! [`SurfaceMesh`] is the plain mesh this crate takes (f64; the same field layout as
//! `datasets::mesh::Mesh`, which the CLI converts). [`UvLocator`] bins the UV triangles
//! into a uniform grid over their UV bounding box (about one triangle per cell) and answers
//! a query by barycentric point location among the triangles of one cell. Points on an edge
//! or a vertex (within 1e-10 of the triangle's barycentric range) are inside; of several
//! candidates the one with the largest smallest barycentric coordinate wins, so shared
//! edges give the same point either way. Triangles of zero UV area are skipped. The 3-D
//! point and normal are the barycentric blends of the triangle's corners (the normal
//! re-normalised; the face normal where the blend vanishes).

use crate::vec3::{self, V3};
use crate::{Error, Result};

/// A triangle mesh with positions, normals and UVs (OBJ convention, `v` up).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions (metres).
    pub positions: Vec<V3>,
    /// Unit normal per position.
    pub normals: Vec<V3>,
    /// Texture coordinates.
    pub uvs: Vec<[f64; 2]>,
    /// Position (and normal) indices per triangle.
    pub triangles: Vec<[u32; 3]>,
    /// UV indices per triangle.
    pub triangle_uvs: Vec<[u32; 3]>,
}

impl SurfaceMesh {
    /// Checks sizes, indices and finiteness (the error names the triangle or vertex).
    pub fn validate(&self) -> Result<()> {
        if self.normals.len() != self.positions.len() {
            return Err(Error::Invalid(format!(
                "surface mesh: {} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            )));
        }
        if self.triangle_uvs.len() != self.triangles.len() {
            return Err(Error::Invalid(format!(
                "surface mesh: {} UV triangles for {} triangles",
                self.triangle_uvs.len(),
                self.triangles.len()
            )));
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !vec3::is_finite(*p) || !vec3::is_finite(self.normals[i]) {
                return Err(Error::Invalid(format!("surface mesh: vertex {i} is not finite")));
            }
        }
        if let Some(i) = self.uvs.iter().position(|uv| !(uv[0].is_finite() && uv[1].is_finite())) {
            return Err(Error::Invalid(format!("surface mesh: uv {i} is not finite")));
        }
        for (t, (tri, tuv)) in self.triangles.iter().zip(&self.triangle_uvs).enumerate() {
            if tri.iter().any(|&i| i as usize >= self.positions.len())
                || tuv.iter().any(|&i| i as usize >= self.uvs.len())
            {
                return Err(Error::Invalid(format!(
                    "surface mesh: triangle {t} has an index out of range"
                )));
            }
        }
        Ok(())
    }
}

/// A uniform-grid locator over a mesh's UV triangles.
#[derive(Debug, Clone)]
pub struct UvLocator<'a> {
    mesh: &'a SurfaceMesh,
    lo: [f64; 2],
    cell: [f64; 2],
    dims: [usize; 2],
    /// Triangle indices per grid cell (CSR).
    starts: Vec<u32>,
    items: Vec<u32>,
}

const EPS: f64 = 1e-10;

impl<'a> UvLocator<'a> {
    /// Builds the grid (the mesh is validated first).
    pub fn new(mesh: &'a SurfaceMesh) -> Result<Self> {
        mesh.validate()?;
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for tuv in &mesh.triangle_uvs {
            for &i in tuv {
                let uv = mesh.uvs[i as usize];
                for a in 0..2 {
                    lo[a] = lo[a].min(uv[a]);
                    hi[a] = hi[a].max(uv[a]);
                }
            }
        }
        if mesh.triangles.is_empty() {
            lo = [0.0; 2];
            hi = [1.0; 2];
        }
        let side = ((mesh.triangles.len() as f64).sqrt().ceil() as usize).clamp(1, 1024);
        let dims = [side, side];
        let cell = [0, 1].map(|a| ((hi[a] - lo[a]) / side as f64).max(1e-300));
        let cell_of = |uv: [f64; 2], a: usize| {
            (((uv[a] - lo[a]) / cell[a]).floor().max(0.0) as usize).min(dims[a] - 1)
        };
        let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); side * side];
        for (t, tuv) in mesh.triangle_uvs.iter().enumerate() {
            let uv = tuv.map(|i| mesh.uvs[i as usize]);
            let area = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1])
                - (uv[2][0] - uv[0][0]) * (uv[1][1] - uv[0][1]);
            if area.abs() <= 1e-300 {
                continue;
            }
            let (mut a0, mut a1) = ([usize::MAX; 2], [0usize; 2]);
            for p in uv {
                for a in 0..2 {
                    a0[a] = a0[a].min(cell_of(p, a));
                    a1[a] = a1[a].max(cell_of(p, a));
                }
            }
            for y in a0[1]..=a1[1] {
                for x in a0[0]..=a1[0] {
                    buckets[y * side + x].push(t as u32);
                }
            }
        }
        let mut starts = Vec::with_capacity(side * side + 1);
        let mut items = Vec::new();
        starts.push(0);
        for b in buckets {
            items.extend(b);
            starts.push(items.len() as u32);
        }
        Ok(UvLocator { mesh, lo, cell, dims, starts, items })
    }

    /// The triangle containing `uv` and the barycentric coordinates there, if any.
    pub fn locate(&self, uv: [f64; 2]) -> Option<(usize, [f64; 3])> {
        let mut idx = [0usize; 2];
        for a in 0..2 {
            let g = (uv[a] - self.lo[a]) / self.cell[a];
            // Points on the outer boundary belong to the last cell.
            if !(g >= -EPS && g <= self.dims[a] as f64 + EPS) {
                return None;
            }
            idx[a] = (g.floor().max(0.0) as usize).min(self.dims[a] - 1);
        }
        let b = idx[1] * self.dims[0] + idx[0];
        let mut best: Option<(usize, [f64; 3], f64)> = None;
        for &t in &self.items[self.starts[b] as usize..self.starts[b + 1] as usize] {
            let tuv = self.mesh.triangle_uvs[t as usize].map(|i| self.mesh.uvs[i as usize]);
            let l = barycentric(tuv, uv);
            let m = l[0].min(l[1]).min(l[2]);
            if m >= -EPS && best.is_none_or(|(_, _, bm)| m > bm) {
                best = Some((t as usize, l, m));
            }
        }
        best.map(|(t, l, _)| (t, l))
    }

    /// The surface point and unit normal at `uv`, if it has a preimage.
    pub fn sample(&self, uv: [f64; 2]) -> Option<(V3, V3)> {
        let (t, l) = self.locate(uv)?;
        let tri = self.mesh.triangles[t];
        let p = tri.map(|i| self.mesh.positions[i as usize]);
        let n = tri.map(|i| self.mesh.normals[i as usize]);
        let mut pos = [0.0; 3];
        let mut nrm = [0.0; 3];
        for k in 0..3 {
            pos = vec3::add_scaled(pos, p[k], l[k]);
            nrm = vec3::add_scaled(nrm, n[k], l[k]);
        }
        let face = vec3::normalize_or(
            vec3::cross(vec3::sub(p[1], p[0]), vec3::sub(p[2], p[0])),
            [0.0, 0.0, 1.0],
        );
        Some((pos, vec3::normalize_or(nrm, face)))
    }
}

/// Barycentric coordinates of `p` in the 2-D triangle `t`.
fn barycentric(t: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let (x0, y0) = (t[0][0], t[0][1]);
    let d = (t[1][0] - x0) * (t[2][1] - y0) - (t[2][0] - x0) * (t[1][1] - y0);
    let l1 = ((p[0] - x0) * (t[2][1] - y0) - (t[2][0] - x0) * (p[1] - y0)) / d;
    let l2 = ((t[1][0] - x0) * (p[1] - y0) - (p[0] - x0) * (t[1][1] - y0)) / d;
    [1.0 - l1 - l2, l1, l2]
}
