//! Garments made the way the clothing industry makes them: a parametric mannequin
//! ([`body`]), flat sewing-pattern panels with a grain ([`pattern`]), triangulated evenly
//! in 2-D so that the panel coordinates are the UVs in metres ([`mesher`]), placed around
//! the body, pulled together by seam springs until they merge into one manifold mesh and
//! draped under gravity by the XPBD solver of [`drape`] ([`sew`]; the draft used the explicit
//! mass–spring simulation of [`crate::sim`], whose ~50 µs time step made a garment take
//! minutes — it stays for the knit animation); [`check`]
//! measures what the tests assert (openings, penetration, self-intersection, strain, grain);
//! [`checkpoint`] snapshots a long sewing and drape so that it can be resumed bit for bit.
//!
//! One call makes a garment on its mannequin: [`draped`] (`kind`, `size`) for the demo,
//! [`make`] with [`GarmentOptions`] for everything else.

pub mod body;
pub mod check;
pub mod checkpoint;
pub mod drape;
pub mod isosurface;
pub mod mesher;
pub mod pattern;
pub mod preview;
pub mod sdf;
pub mod self_contact;
pub mod sew;
#[cfg(test)]
mod tests;

pub use body::{Body, BodyParams, Measurements, Size};
pub use pattern::{GarmentKind, Pattern, PatternOptions};
pub use sew::{DrapeSettings, Fabric, Garment};

use crate::Result;

/// Everything that shapes a garment.
#[derive(Debug, Clone, PartialEq)]
pub struct GarmentOptions {
    /// Body (and pattern) measurements.
    pub body: BodyParams,
    /// Target vertex count of the garment mesh.
    pub vertices: usize,
    /// Overrides of the pattern's lengths.
    pub pattern: PatternOptions,
    /// Fabric mechanics.
    pub fabric: Fabric,
    /// Simulation lengths and the rest criterion.
    pub drape: DrapeSettings,
}

impl GarmentOptions {
    /// Defaults for a size: 10 000 vertices, cotton jersey.
    pub fn new(size: Size) -> Self {
        GarmentOptions {
            body: BodyParams::new(size),
            vertices: 10_000,
            pattern: PatternOptions::default(),
            fabric: Fabric::default(),
            drape: DrapeSettings::default(),
        }
    }
}

/// Makes `kind` on the mannequin of `o.body` (or on `body` when given — a mesh read from
/// a file; the pattern is still drafted for `o.body`'s measurements). Returns the garment
/// and the body it was draped on.
pub fn make(
    kind: GarmentKind,
    o: &GarmentOptions,
    body: Option<Body>,
    progress: &mut sew::Progress<'_>,
) -> Result<(Garment, Body)> {
    make_resumable(kind, o, body, progress, None)
}

/// [`make`], taking snapshots of the sewing and drape as it goes and resuming one
/// ([`checkpoint`]); the result is bit for bit that of an uninterrupted run.
pub fn make_resumable(
    kind: GarmentKind,
    o: &GarmentOptions,
    body: Option<Body>,
    progress: &mut sew::Progress<'_>,
    checkpoints: Option<&mut checkpoint::Checkpointing<'_>>,
) -> Result<(Garment, Body)> {
    let man = body::Mannequin::new(&o.body)?;
    let pattern = Pattern::new(kind, &o.body.measurements, &man.landmarks, &o.pattern)?;
    progress("body", 0.0);
    let body = match body {
        Some(b) => b,
        None => Body::new(&o.body)?,
    };
    let g = sew::sew_and_drape(
        pattern,
        Some(&body),
        o.vertices,
        &o.fabric,
        &o.drape,
        progress,
        checkpoints,
    )?;
    Ok((g, body))
}

/// The demo's one call: `kind` in size `size` at 10 000 vertices on its mannequin.
pub fn draped(kind: GarmentKind, size: Size) -> Result<(Garment, Body)> {
    make(kind, &GarmentOptions::new(size), None, &mut |_, _| {})
}
