//! Triangle meshes from OBJ files (via tobj): positions, normals, UVs and material ids.
//!
//! Missing normals are computed as area-weighted face normals accumulated over vertices
//! that share a position (so UV seams do not split the shading); zero-area triangles add
//! nothing and a vertex left with a zero normal takes the normal of a neighbouring face or
//! `+z`. Provided normals of zero length are replaced the same way. Missing UVs are an
//! error unless a planar projection is asked for. The tangent frame that the BTF lookup
//! needs is derived from the UVs in [`crate::tangent`].

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// Largest OBJ file we read (bytes).
pub const MAX_OBJ_BYTES: u64 = 2 << 30;

/// Axis pair of a planar UV projection (`u` along the first axis, `v` along the second).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlanarUv {
    /// `u = x`, `v = y`.
    Xy,
    /// `u = x`, `v = −z` (a ground plane seen from above).
    Xz,
    /// `u = z`, `v = y`.
    Zy,
}

/// An indexed triangle mesh with one material id per triangle.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Vertex positions (world units).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates, OBJ convention (`v` up).
    pub uvs: Vec<[f32; 2]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Material id of each triangle (index into `material_names`).
    pub triangle_material: Vec<u32>,
    /// Material names (`usemtl`), in order of first use; `""` for faces without one.
    pub material_names: Vec<String>,
    /// How many vertex normals had to be computed or repaired.
    pub repaired_normals: usize,
}

impl Mesh {
    /// Loads an OBJ. Without UVs the load fails unless `planar` gives a projection.
    pub fn load_obj(path: &Path, planar: Option<PlanarUv>) -> Result<Mesh> {
        let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        if meta.len() > MAX_OBJ_BYTES {
            return Err(Error::Limit(format!(
                "{}: {} bytes is more than {MAX_OBJ_BYTES}",
                path.display(),
                meta.len()
            )));
        }
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Mesh::parse_obj(&text, &path.display().to_string(), planar)
    }

    /// Parses OBJ text; `name` is used in error messages.
    pub fn parse_obj(text: &str, name: &str, planar: Option<PlanarUv>) -> Result<Mesh> {
        let scan = prescan(text, name)?;
        let mtl: String = scan.usemtl.iter().map(|m| format!("newmtl {m}\n")).collect();
        let opts =
            tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
        // tobj calls the material loader only for an `mtllib` line and otherwise drops every
        // `usemtl`; the materials we need are just the names, so declare one library first
        // and turn the file's own `mtllib` lines into comments (a second library would
        // append the names again and shift every material id past the list).
        let own: String = text
            .lines()
            .map(|l| if l.trim_start().starts_with("mtllib") { "#" } else { l })
            .flat_map(|l| [l, "\n"])
            .collect();
        let text = format!("mtllib usemtl-names.mtl\n{own}");
        let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
            tobj::load_mtl_buf(&mut mtl.as_bytes())
        })
        .map_err(|e| Error::Invalid(format!("{name}: {e}")))?;
        let mut mesh = Mesh { material_names: scan.usemtl.clone(), ..Default::default() };
        let none_id = scan.usemtl.len() as u32;
        let mut any_missing_uv = false;
        let mut normals_given = true;
        for m in &models {
            let g = &m.mesh;
            let base = mesh.positions.len() as u32;
            let n = g.positions.len() / 3;
            mesh.positions.extend(g.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
            if g.normals.len() == g.positions.len() {
                mesh.normals.extend(g.normals.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
            } else {
                normals_given = false;
                mesh.normals.extend(std::iter::repeat_n([0.0; 3], n));
            }
            if g.texcoords.len() == 2 * n {
                mesh.uvs.extend(g.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]));
            } else {
                any_missing_uv = true;
                mesh.uvs.extend(std::iter::repeat_n([0.0; 2], n));
            }
            let mat = match g.material_id {
                Some(i) if i < scan.usemtl.len() => i as u32,
                Some(i) => {
                    return Err(Error::Invalid(format!(
                        "{name}: material id {i} of object '{}' outside its {} usemtl names",
                        m.name,
                        scan.usemtl.len()
                    )));
                }
                None => none_id,
            };
            for t in g.indices.chunks_exact(3) {
                mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
                mesh.triangle_material.push(mat);
            }
        }
        if mesh.triangle_material.contains(&none_id) {
            mesh.material_names.push(String::new());
        }
        if mesh.triangles.is_empty() {
            return Err(Error::Invalid(format!("{name}: no faces")));
        }
        if let Some(i) = mesh.positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::Invalid(format!(
                "{name}: vertex {} has a non-finite position",
                i + 1
            )));
        }
        match (any_missing_uv, planar) {
            (_, Some(p)) => mesh.project_uvs(p),
            (true, None) => {
                return Err(Error::Invalid(format!(
                    "{name}: faces without texture coordinates (add `vt`, or set `planar_uv` in the scene)"
                )));
            }
            _ => {}
        }
        if let Some(i) = mesh.uvs.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
            return Err(Error::Invalid(format!(
                "{name}: texture coordinate of vertex {} is not finite",
                i + 1
            )));
        }
        mesh.repair_normals(!normals_given);
        Ok(mesh)
    }

    /// Replaces the UVs by a planar projection of the positions onto the unit square of
    /// the mesh's bounding box (longest side = 1).
    pub fn project_uvs(&mut self, p: PlanarUv) {
        let (lo, hi) = self.bounds();
        let size = (0..3).map(|a| hi[a] - lo[a]).fold(0f32, f32::max).max(f32::MIN_POSITIVE);
        for (uv, q) in self.uvs.iter_mut().zip(&self.positions) {
            let r = |a: usize| (q[a] - lo[a]) / size;
            *uv = match p {
                PlanarUv::Xy => [r(0), r(1)],
                PlanarUv::Xz => [r(0), 1.0 - r(2)],
                PlanarUv::Zy => [r(2), r(1)],
            };
        }
    }

    /// Axis-aligned bounds `(min, max)`.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut lo = [f32::MAX; 3];
        let mut hi = [f32::MIN; 3];
        for p in &self.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        (lo, hi)
    }

    /// Face normal scaled by twice the area (zero for a degenerate triangle).
    pub fn face_area_normal(&self, t: usize) -> [f32; 3] {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ]
    }

    /// Computes all normals (`recompute_all`) or only the unusable ones (zero, non-finite).
    pub fn repair_normals(&mut self, recompute_all: bool) {
        // Accumulate per position so that split vertices (UV seams) share their normal.
        let mut key_of: HashMap<[u32; 3], usize> = HashMap::new();
        let keys: Vec<usize> = self
            .positions
            .iter()
            .map(|p| {
                let n = key_of.len();
                *key_of.entry(p.map(f32::to_bits)).or_insert(n)
            })
            .collect();
        let mut acc = vec![[0f64; 3]; key_of.len()];
        let mut fallback: Vec<Option<[f64; 3]>> = vec![None; key_of.len()];
        for t in 0..self.triangles.len() {
            let n = self.face_area_normal(t).map(f64::from);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if !(len > 0.0 && len.is_finite()) {
                continue;
            }
            for &v in &self.triangles[t] {
                let k = keys[v as usize];
                for a in 0..3 {
                    acc[k][a] += n[a];
                }
                fallback[k].get_or_insert(n.map(|c| c / len));
            }
        }
        for (v, normal) in self.normals.iter_mut().enumerate() {
            let len = normal.iter().map(|c| c * c).sum::<f32>().sqrt();
            if !recompute_all && len.is_finite() && len > 1e-12 {
                *normal = normal.map(|c| c / len);
                continue;
            }
            let k = keys[v];
            let s = acc[k];
            let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let n =
                if l > 1e-12 { s.map(|c| c / l) } else { fallback[k].unwrap_or([0.0, 0.0, 1.0]) };
            *normal = n.map(|c| c as f32);
            self.repaired_normals += 1;
        }
    }
}

struct Prescan {
    usemtl: Vec<String>,
}

/// Checks what tobj reports without a location: numbers in `v`/`vt`/`vn` lines and face
/// indices in range, naming the line; collects `usemtl` names in order of first use.
fn prescan(text: &str, name: &str) -> Result<Prescan> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    let mut usemtl: Vec<String> = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let bad = |what: String| Error::Invalid(format!("{name}:{}: {what}", ln + 1));
        let mut it = line.split_whitespace();
        let Some(tag) = it.next() else { continue };
        let nums =
            |it: std::str::SplitWhitespace, min: usize, kind: &str, idx: i64| -> Result<()> {
                let parsed: Vec<_> = it.map(str::parse::<f32>).collect();
                if parsed.len() < min || parsed.iter().any(|p| p.is_err()) {
                    return Err(bad(format!("{kind} {idx}: expected {min} numbers in '{line}'")));
                }
                Ok(())
            };
        match tag {
            "v" => {
                nv += 1;
                nums(it, 3, "vertex", nv)?;
            }
            "vt" => {
                nt += 1;
                nums(it, 1, "texture coordinate", nt)?;
            }
            "vn" => {
                nn += 1;
                nums(it, 3, "normal", nn)?;
            }
            "f" => {
                let corners: Vec<&str> = it.collect();
                if corners.len() < 3 {
                    return Err(bad(format!("face with {} corners", corners.len())));
                }
                for c in corners {
                    let kinds = [(nv, "vertex"), (nt, "texture coordinate"), (nn, "normal")];
                    for (part, (count, kind)) in c.split('/').zip(kinds) {
                        if part.is_empty() {
                            continue;
                        }
                        let i: i64 = part
                            .parse()
                            .map_err(|_| bad(format!("face corner '{c}' is not a number")))?;
                        let resolved = if i < 0 { count + 1 + i } else { i };
                        if resolved < 1 || resolved > count {
                            return Err(bad(format!(
                                "face refers to {kind} {i}, but only {count} are defined so far"
                            )));
                        }
                    }
                }
            }
            "usemtl" => {
                let m = line.trim_start()[6..].trim().to_owned();
                if !m.is_empty() && !usemtl.contains(&m) {
                    usemtl.push(m);
                }
            }
            _ => {}
        }
    }
    Ok(Prescan { usemtl })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file naming its own material library (as `datasets`' OBJ writer does) keeps its
    /// `usemtl` names once, in order of first use, and every triangle's id points into them.
    #[test]
    fn an_own_mtllib_keeps_names_and_ids() {
        let obj = "mtllib shirt.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                   vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nusemtl torso\nf 1/1 2/2 3/3\n\
                   usemtl sleeve\nf 2/2 4/4 3/3\nusemtl torso\nf 1/1 2/2 4/4\n";
        let m = Mesh::parse_obj(obj, "shirt.obj", None).unwrap();
        assert_eq!(m.material_names, ["torso", "sleeve"]);
        let mut ids = m.triangle_material.clone();
        ids.sort_unstable();
        assert_eq!(ids, [0, 0, 1], "two torso triangles and one sleeve");
    }
}
