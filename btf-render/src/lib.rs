//! The wgpu renderer: BTF-textured meshes under point, directional and environment lights
//! (Sattler et al. 2003, §4.2–5).
