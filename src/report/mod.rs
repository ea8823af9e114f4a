//! Report writers: what a sweep or a batch job measured, as CSV, Markdown and pictures
//! (plots and heat maps from `btf_image`).

pub mod compress_sweep;
pub mod demo;
pub mod doc;
pub mod relight;
pub mod thin;
