//! Synthetic data with known ground truth: mesostructure BTF materials, a virtual
//! gonioreflectometer, HDR environments and garment meshes (DESIGN.md §5).
