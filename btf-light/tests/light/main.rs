//! The tests of btf-light, one binary and no GPU: environment lighting on the CPU after
//! Sattler et al. 2003 §5 (`[S03 eq. 7–13]`) and the thin-cloth environment tables
//! (`[TC eq. 7–8]`). The renderer's GPU tests are `btf-render/tests/gpu`.

mod common;
mod eigenweights;
mod gather;
mod thin_tables;
mod visibility;
