//! BTF materials for the GPU (`[S03 eq. 2–5]`): an eigen store's view slots packed for few
//! texture reads ([`pack`], CPU) and uploaded as texture arrays, a weight buffer and a
//! sampling uniform ([`gpu`]). The layout and its error are described in [`pack`].

pub mod gpu;
pub mod pack;

pub use gpu::{MaterialGpu, SamplingsRaw};
pub use pack::{MAX_RINGS, MaterialData, packed_stride};
