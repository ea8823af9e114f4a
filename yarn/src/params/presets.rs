//! Yarn presets of our own, in the style of [Z16]'s fitted yarns (two or three plies, an
//! elliptical ply flattened towards the yarn axis, ε and β of the same order, ρ_min near 1,
//! s between 1 and 2, hair and loop densities giving a flyaway in a few percent of the
//! migration periods) but scaled to knitting yarns and written in metres. They are **not**
//! copies of [Z16]'s files (those carry a non-commercial header and have no stated unit:
//! import them at run time with [`super::zhao`]). The fiber pitch has the opposite sign of
//! the ply pitch, as in a balanced plied yarn (S-twisted singles plied Z).
//!
//! The values are data, in `presets/*.toml` (metres): `cotton-2ply`, a smooth two-ply cotton
//! of 0.5 mm tube radius with few flyaways; `fleece-3ply`, a fuzzy, loosely twisted
//! three-ply with many hairs; `fine-2ply`, a fine, tightly twisted two-ply of 0.16 mm.

use super::YarnParams;
use crate::{Error, Result};

/// Names of the presets.
pub const NAMES: [&str; 3] = ["cotton-2ply", "fleece-3ply", "fine-2ply"];

impl YarnParams {
    /// A preset by name (see [`NAMES`]).
    pub fn preset(name: &str) -> Result<Self> {
        let text = match name {
            "cotton-2ply" => include_str!("presets/cotton-2ply.toml"),
            "fleece-3ply" => include_str!("presets/fleece-3ply.toml"),
            "fine-2ply" => include_str!("presets/fine-2ply.toml"),
            other => {
                return Err(Error::Invalid(format!(
                    "unknown yarn preset '{other}' (known: {})",
                    NAMES.join(", ")
                )));
            }
        };
        let p = YarnParams::from_toml(text, name)?;
        debug_assert!(p.validate().is_ok());
        Ok(p)
    }
}
