//! GPU tests of the fiber passes (lavapipe in CI; skipped without an adapter unless
//! `BTF_REQUIRE_GPU=1`).

mod btf;
mod coherence;
mod common;
mod effects;
mod expand;
mod fiber_shadows;
mod hairs;
mod knot;
mod lights;
mod lod;
mod lumislice;
mod oblique;
mod reference;
mod scene;
mod strips;
