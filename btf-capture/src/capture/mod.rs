//! Capture processing (Sattler et al. 2003, §3.2): raw photographs of a sample on its
//! marker plate become tileable normtextures in a BTF store.
//!
//! - [`layout`] — `capture.toml`: sampling, naming, intrinsics, marker layout, radiometry;
//!   nominal cameras and homographies;
//! - [`config`] — strict TOML reading and range checks naming the file and the key;
//! - [`raw`] — raw images (PNG/TIFF with left-aligned `bits`, EXR) as linear DN;
//! - [`markers`] — sub-pixel point-marker and border-line detection;
//! - [`homography`] — normalised DLT, consensus outlier rejection, LM refinement;
//! - [`pose`] — the plate pose behind a few markers (prior-regularised fit), to search by;
//! - [`register`] — one view slot's homography from its images;
//! - [`rectify`] — resampling onto the output texel grid (bilinear or footprint filter);
//! - [`incidence`] — the lamp's cosine on the tilted plate (radiometric correction);
//! - [`blend`] — linear edge blending for tileability;
//! - [`process`] — the streaming, parallel, resumable driver;
//! - [`score`] — accuracy against a synthetic capture's ground truth.

pub mod blend;
pub mod config;
pub mod homography;
pub mod incidence;
pub mod layout;
pub mod markers;
pub mod pose;
pub mod process;
pub mod raw;
pub mod rectify;
pub mod register;
pub mod score;

pub use layout::CaptureLayout;
pub use process::{ProcessOptions, ProcessReport, Roi, finalize_shards, process};
pub use rectify::Filter;
