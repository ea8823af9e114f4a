//! Fuzzes OBJ meshes as the renderer loads them (`Mesh::parse_obj`, behind `load_obj`):
//! the first byte picks whether a planar UV projection is given (as `planar_uv` in a
//! scene), the rest is the OBJ text.
#![no_main]

use btf_light::mesh::{Mesh, PlanarUv};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let Ok(text) = std::str::from_utf8(rest) else { return };
    let planar = match pick % 4 {
        0 => None,
        1 => Some(PlanarUv::Xy),
        2 => Some(PlanarUv::Xz),
        _ => Some(PlanarUv::Zy),
    };
    if let Ok(m) = Mesh::parse_obj(text, "fuzz.obj", planar) {
        let n = m.positions.len() as u32;
        assert!(m.triangles.iter().flatten().all(|&i| i < n));
        assert_eq!(m.normals.len(), m.positions.len());
        assert_eq!(m.uvs.len(), m.positions.len());
    }
});
