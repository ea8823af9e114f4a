//! Yarn and knit foundation (issue 18, DESIGN §0 of `shared/knit/DESIGN.md`).
#![forbid(unsafe_code)]

pub mod bcsdf;
pub mod curve;
pub mod density;
pub mod error;
pub mod fiber;
pub mod frame;
pub mod hash;
pub mod io;
pub mod knit;
pub mod params;
pub mod quad;
pub mod special;
pub mod stats;
pub mod vec3;

pub use error::{Error, Result};
pub use params::{Gaussian, YarnParams};
