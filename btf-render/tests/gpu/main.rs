//! The GPU integration tests of btf-render, one binary with a module per area (wgpu's
//! `tests/wgpu-gpu` habit): the renders against analytic or CPU references — the golden
//! reconstruction of `[S03 eq. 2–5]`, shadows and the smooth boundary of `[S03 eq. 6]`,
//! thin cloth (`[TC eq. 7–9]`), the environment background — and the passes' bookkeeping.
//! Each test skips without an adapter unless `BTF_REQUIRE_GPU=1` (then it fails). The CPU
//! light-transport tests are btf-light's (`btf-light/tests/light`).

mod common;

mod background;
mod baselines;
mod corner_ids;
mod encode;
mod eq6;
mod golden;
mod mipmaps;
mod passes;
mod shadow_cube;
mod shadows;
mod thin;
mod thin_env;
