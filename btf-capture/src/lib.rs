//! Capture processing: raw photographs of a sample on its holder become normtextures
//! (Sattler et al. 2003, §3.2), and the Bonn database formats are read and written.

pub mod bonn;
pub mod capture;
pub mod decode;
pub mod error;

pub use error::{Error, Result};
