//! Wavefront OBJ output: `v`, `vt`, `vn` and `f p/t/n` records (1-based), positions and
//! normals sharing indices, UVs indexed separately so seams keep a closed surface closed;
//! a mesh with materials (or one material name given for every face) gets `usemtl NAME`
//! before each run of its faces and an `mtllib` beside it (`NAME.mtl`, one `newmtl` per
//! material) so OBJ readers keep the names. Written to a temporary file and renamed into
//! place (the `.mtl` first). [`read_obj`] reads positions and faces back with their shared
//! indices (a body given on the command line), so closedness can be checked on the
//! positions.

use super::Mesh;
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Writes `mesh` to `path` as OBJ with a comment header `comment`.
pub fn write_obj(mesh: &Mesh, path: &Path, comment: &str) -> Result<()> {
    write_obj_material(mesh, path, comment, None)
}

/// [`write_obj`] with every face in material `material` (an OBJ `usemtl` line).
pub fn write_obj_material(
    mesh: &Mesh,
    path: &Path,
    comment: &str,
    material: Option<&str>,
) -> Result<()> {
    let tagged;
    let mesh = match material {
        Some(name) if mesh.triangle_material.is_empty() => {
            let mut m = mesh.clone();
            m.tag_material(name);
            tagged = m;
            &tagged
        }
        _ => mesh,
    };
    let finite =
        mesh.positions.iter().chain(&mesh.normals).all(|p| p.iter().all(|v| v.is_finite()))
            && mesh.uvs.iter().all(|t| t.iter().all(|v| v.is_finite()));
    if !finite
        || mesh.normals.len() != mesh.positions.len()
        || mesh.triangles.len() != mesh.triangle_uvs.len()
        || !mesh.triangle_material.is_empty()
            && (mesh.triangle_material.len() != mesh.triangles.len()
                || mesh.triangle_material.iter().any(|&m| m as usize >= mesh.material_names.len()))
        || mesh.material_names.iter().any(|n| n.is_empty() || n.contains(char::is_whitespace))
    {
        return Err(Error::Invalid(format!(
            "{}: mesh has non-finite or inconsistent data",
            path.display()
        )));
    }
    let mut s = String::with_capacity(
        64 * (mesh.positions.len() * 2 + mesh.uvs.len() + mesh.triangles.len()),
    );
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let _ = writeln!(
        s,
        "# {} vertices, {} triangles; +z up, metres; UV v up",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for p in &mesh.positions {
        let _ = writeln!(s, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2]);
    }
    for t in &mesh.uvs {
        let _ = writeln!(s, "vt {:.6} {:.6}", t[0], t[1]);
    }
    for n in &mesh.normals {
        let _ = writeln!(s, "vn {:.6} {:.6} {:.6}", n[0], n[1], n[2]);
    }
    let materials = !mesh.triangle_material.is_empty();
    if materials {
        let mtl_path = path.with_extension("mtl");
        let mtl: String =
            mesh.material_names.iter().map(|n| format!("newmtl {n}\nKd 0.8 0.8 0.8\n")).collect();
        btf_core::fs::write_atomic(&mtl_path, mtl.as_bytes())?;
        let name = mtl_path.file_name().unwrap_or_default().to_string_lossy();
        s = format!("mtllib {name}\n{s}");
    }
    let mut current = None;
    for (i, (f, ft)) in mesh.triangles.iter().zip(&mesh.triangle_uvs).enumerate() {
        if materials && current != Some(mesh.triangle_material[i]) {
            current = Some(mesh.triangle_material[i]);
            let _ =
                writeln!(s, "usemtl {}", mesh.material_names[mesh.triangle_material[i] as usize]);
        }
        let _ = writeln!(
            s,
            "f {}/{}/{} {}/{}/{} {}/{}/{}",
            f[0] + 1,
            ft[0] + 1,
            f[0] + 1,
            f[1] + 1,
            ft[1] + 1,
            f[1] + 1,
            f[2] + 1,
            ft[2] + 1,
            f[2] + 1
        );
    }
    Ok(btf_core::fs::write_atomic(path, s.as_bytes())?)
}

/// Reads the positions and faces of an OBJ file (polygons fanned into triangles), keeping
/// the file's position indices; UVs and normals are not read.
pub fn read_obj(path: &Path) -> Result<Mesh> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut mesh = Mesh::default();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<f64> = it.take(3).map(|x| x.parse().unwrap_or(f64::NAN)).collect();
                if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
                    return Err(Error::Invalid(format!(
                        "{}:{}: bad vertex",
                        path.display(),
                        ln + 1
                    )));
                }
                mesh.positions.push([v[0], v[1], v[2]]);
            }
            Some("f") => {
                let n = mesh.positions.len() as i64;
                let idx: Option<Vec<u32>> = it
                    .map(|w| {
                        let i: i64 = w.split('/').next()?.parse().ok()?;
                        let i = if i < 0 { n + i } else { i - 1 };
                        (0..n).contains(&i).then_some(i as u32)
                    })
                    .collect();
                let Some(idx) = idx.filter(|v| v.len() >= 3) else {
                    return Err(Error::Invalid(format!("{}:{}: bad face", path.display(), ln + 1)));
                };
                for k in 1..idx.len() - 1 {
                    mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return Err(Error::Invalid(format!("{}: no faces", path.display())));
    }
    mesh.triangle_uvs = mesh.triangles.clone();
    mesh.uvs = vec![[0.0; 2]; mesh.positions.len()];
    mesh.compute_normals();
    Ok(mesh)
}
