//! Wavefront OBJ output: `v`, `vt`, `vn` and `f p/t/n` records (1-based), positions and
//! normals sharing indices, UVs indexed separately so seams keep a closed surface closed;
//! a mesh with materials gets `usemtl NAME` before each run of its faces and an `mtllib`
//! beside it (`NAME.mtl`, one `newmtl` per material) so OBJ readers keep the names.
//! Written to a temporary file and renamed into place (the `.mtl` first).

use super::Mesh;
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Writes `mesh` to `path` as OBJ with a comment header `comment`.
pub fn write_obj(mesh: &Mesh, path: &Path, comment: &str) -> Result<()> {
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
