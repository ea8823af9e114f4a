//! The volumetric reference of DESIGN §1.4–1.5: a ray marcher over the **union** of the
//! swept yarn tubes of a `YarnSet`, with the cross-section density of `yarn::density`.
//!
//! - [`density`]: the density field `n_A` (fiber centres per unit cross-section area) in
//!   the co-rotating slice frame, and the extinction laws — the anisotropic
//!   `σ(ω) = 2 r_f n_A sin∠(ω, T)` (DESIGN §1.3 item 10), the literal isotropic `γρ` of
//!   [C03 eq. 5, 9] (`2 r_f n_A` in every direction), and the helix-tilt correction of
//!   DESIGN §2.3 item 10.
//! - [`tubes`]: the tubes (polyline samples of the curves with frames and length
//!   coordinates, capsules of the density's reach in a BVH), the density at a point (nearest
//!   centre-line sample per yarn, rotated into the slice frame by `2πz/α_ply`; yarns add) and
//!   the ray's intervals inside the tubes.
//! - [`march`]: optical depth and transmittance by marching each tube interval with `n`
//!   equal steps `≤ Δs` (jittered or midpoint), single scattering with the Kajiya–Kay phase
//!   towards every light with transmittance through all yarns (exact [C03 eq. 9] per
//!   pixel, with the self-attenuation of DESIGN §1.3 item 11 and the physical extinction),
//!   and Monte-Carlo multiple scattering with an isotropic phase and albedo ϖ.

pub mod density;
pub mod march;
pub mod tubes;

pub use density::{ExtinctionLaw, SliceDensity, TiltModel, UniformDisk};
pub use march::{Phase, VolumeSettings, render_volume};
pub use tubes::VolumeScene;
