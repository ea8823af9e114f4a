//! Data model and numerics of the BTF toolkit.
//!
//! A bidirectional texture function (BTF) gives, for every texel of a flat sample, the
//! radiance reflected towards a view direction per unit irradiance arriving from a light
//! direction, both sampled on the hemisphere (Sattler et al. 2003, §3). This crate holds
//! what every other crate shares:
//!
//! - [`direction`]: tangent-space directions and their (θ, φ) angles;
//! - [`sampling`]: the measured ring samplings (`ubo81`, `ubo81-h1`, `dome151`, custom);
//! - [`interp`]: nearest and "four nearest" interpolation weights ([S03 eq. 3] and 5);
//! - [`zarr`], [`store`], [`eigen`]: the chunked on-disk BTF and eigen stores;
//! - [`pca`]: the per-view-slot PCA ([S03 eq. 1]);
//! - [`reconstruct`]: CPU reconstruction for any view and light ([S03 eq. 2–5]);
//! - [`fs`]: atomic writes, leftovers, and the output rules (never an input, replace only
//!   what the toolkit made);
//! - [`shard`]: shards of a batch job — partition, job records every writer agrees on,
//!   content fingerprints of stores;
//! - [`metrics`]: error measures (relative RMSE, PSNR, Eckart–Young);
//! - [`thin_slab`]: thin semi-transparent cloth as an optically thin slab (first-order
//!   reflection/transmission, direct transmittance, Monte-Carlo reference).
//!
//! No GPU code and no image-format crates live here.

pub mod axes;
pub mod blosc;
pub mod compress;
pub mod direct_io;
pub mod direction;
pub mod eigen;
pub mod error;
pub mod fs;
pub mod gemm;
pub mod interp;
pub mod kernels;
pub mod mapped;
pub mod memory;
pub mod metrics;
pub mod pca;
pub mod reconstruct;
pub mod sampling;
pub mod shard;
pub mod simd;
pub mod store;
pub mod thin_slab;
pub mod zarr;

/// The largest radiance (environment pixels), irradiance or intensity (lights) and the
/// largest scale factor (exposures) any input may hold: 5·10⁴ times the solar disc's
/// broadband radiance (≈ 2·10⁷ W m⁻² sr⁻¹). Products and sums of such values over a frame
/// (a few lights, 2²⁷ map pixels, exposures) stay far inside `f32`, whose maximum (3.4·10³⁸)
/// an RGBE exponent or an EXR pixel can otherwise reach, so a map or scene beyond it is
/// refused by name instead of rendering infinities.
pub const MAX_RADIANCE: f32 = 1e12;

pub use direction::Direction;
pub use error::{Error, Result};
pub use interp::{InterpMode, Weights};
pub use sampling::{Ring, Sampling};
