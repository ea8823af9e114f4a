//! Readers and writers of the Bonn BTF database formats.
//!
//! - [`ubo2003`]: UBO2003/ATRIUM folders (and zips) of per-(view, light) images whose names
//!   carry `tl/pl/tv/pv` angle tags in degrees;
//! - [`ubo2014`]: UBO2014 binary `.btf` files — [`header`] (signatures, metadata versions
//!   1–4, sampling, rotations), payloads [`svd`] (FMF, DFMF), [`pvf`] (per-view PCA) and
//!   [`bdi`] (uncompressed), all parsed through the bounds-checked [`bytes`] reader;
//! - [`export`]: our stores as PVF files and UBO2003 image folders.
//!
//! **Direction convention.** Bonn angles are `θ` from the normal and `φ` from the texture
//! `x` axis (increasing column) toward `y` (increasing scan line), `x = sin θ cos φ`,
//! `y = sin θ sin φ`, as in the public Bonn readers; textures are stored scan line by scan
//! line with `x` fastest and the first scan line is our row 0. This is exactly our tangent
//! frame (DESIGN.md §3), so angles map unchanged and no row is flipped; `φ` is folded into
//! `[0°, 360°)` and the pole's `φ` is ignored. UBO2014 stores radians, UBO2003 names degrees.
//!
//! **Radiometry.** 8-bit images are sRGB-encoded and linearised on import; `.hdr`/`.exr`
//! are linear. UBO2014 files whose cosine flag is 0 do not contain `cos θ_light`; it is
//! multiplied in on import so that stores follow our convention. The header's RGB scale
//! factor is recorded in the provenance, not applied.

pub mod bdi;
pub mod bytes;
pub mod directions;
pub mod export;
pub mod header;
pub mod pvf;
pub mod svd;
pub mod ubo2003;
pub mod ubo2014;
