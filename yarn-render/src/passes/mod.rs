//! One module per GPU pass, its WGSL in `../shaders/` (prefixed by the generator).
//!
//! - [`expand`]: `fiber_expand`, fiber points of an instance list into a storage buffer;
//! - [`lod`]: `fiber_lod`, culling and level of detail into an indirect draw;
//! - [`draw`]: `fiber_draw`, the strips and their shading;
//! - [`shadow`]: `yarn_tube_shadow`, the tube shadow maps;
//! - [`fiber_shadow`]: the fiber shadow maps' light views (drawn by [`draw`]'s
//!   `fs_shadow` pipeline).

pub mod draw;
pub mod expand;
pub mod fiber_shadow;
pub mod lod;
pub mod shadow;

/// A 1-D dispatch of `n` invocations in workgroups of `wg`, folded into two dimensions when
/// it exceeds the 65 535-workgroup limit (shaders index `gid.x + gid.y·nwg.x·wg`).
pub fn dispatch_size(n: u64, wg: u32) -> (u32, u32) {
    let groups = n.div_ceil(wg as u64).max(1);
    if groups <= 65_535 { (groups as u32, 1) } else { (65_535, groups.div_ceil(65_535) as u32) }
}
