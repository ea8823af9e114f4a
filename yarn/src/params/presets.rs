//! Yarn presets of our own, in the style of [Z16]'s fitted yarns (two or three plies, an
//! elliptical ply flattened towards the yarn axis, ε and β of the same order, ρ_min near 1,
//! s between 1 and 2, hair and loop densities giving a flyaway in a few percent of the
//! migration periods) but scaled to knitting yarns and written in metres. They are **not**
//! copies of [Z16]'s files (those carry a non-commercial header and have no stated unit:
//! import them at run time with [`super::zhao`]). The fiber pitch has the opposite sign of
//! the ply pitch, as in a balanced plied yarn (S-twisted singles plied Z).

use super::{Gaussian, YarnParams};
use crate::{Error, Result};

/// Names of the presets.
pub const NAMES: [&str; 3] = ["cotton-2ply", "fleece-3ply", "fine-2ply"];

impl YarnParams {
    /// A preset by name (see [`NAMES`]).
    pub fn preset(name: &str) -> Result<Self> {
        let p = match name {
            "cotton-2ply" => cotton_2ply(),
            "fleece-3ply" => fleece_3ply(),
            "fine-2ply" => fine_2ply(),
            other => {
                return Err(Error::Invalid(format!(
                    "unknown yarn preset '{other}' (known: {})",
                    NAMES.join(", ")
                )));
            }
        };
        debug_assert!(p.validate().is_ok());
        Ok(p)
    }
}

const MM: f64 = 1e-3;
const UM: f64 = 1e-6;

/// A smooth two-ply cotton: 0.5 mm tube radius, few flyaways.
fn cotton_2ply() -> YarnParams {
    YarnParams {
        name: "cotton-2ply".into(),
        ply_count: 2,
        fibers_per_ply: 80,
        ply_center_distance: 0.20 * MM,
        ply_ellipse_n: 0.16 * MM,
        ply_ellipse_b: 0.22 * MM,
        ply_pitch: 2.4 * MM,
        fiber_pitch: -3.0 * MM,
        density_epsilon: 0.10,
        density_beta: 0.60,
        r_max: 1.0,
        rho_min: 0.80,
        rho_max: 1.0,
        migration_rate: 1.5,
        fiber_radius: 8.0 * UM,
        hair_density: 3000.0,
        hair_ze: Gaussian::new(0.10 * MM, 0.45 * MM),
        hair_r0: Gaussian::new(0.18 * MM, 0.04 * MM),
        hair_re: Gaussian::new(0.15 * MM, 0.12 * MM),
        hair_pe: Gaussian::new(0.40, 0.40),
        hair_curvature: 2.0,
        loop_density: 2000.0,
        loop_r1: Gaussian::new(0.30 * MM, 0.06 * MM),
        core_fraction: 0.4,
    }
}

/// A fuzzy three-ply fleece: thicker, loosely twisted, many hairs.
fn fleece_3ply() -> YarnParams {
    YarnParams {
        name: "fleece-3ply".into(),
        ply_count: 3,
        fibers_per_ply: 60,
        ply_center_distance: 0.28 * MM,
        ply_ellipse_n: 0.20 * MM,
        ply_ellipse_b: 0.26 * MM,
        ply_pitch: 4.0 * MM,
        fiber_pitch: -5.0 * MM,
        density_epsilon: 0.20,
        density_beta: 0.40,
        r_max: 1.0,
        rho_min: 0.70,
        rho_max: 1.0,
        migration_rate: 1.2,
        fiber_radius: 10.0 * UM,
        hair_density: 8000.0,
        hair_ze: Gaussian::new(0.20 * MM, 0.80 * MM),
        hair_r0: Gaussian::new(0.22 * MM, 0.05 * MM),
        hair_re: Gaussian::new(0.30 * MM, 0.20 * MM),
        hair_pe: Gaussian::new(0.50, 0.45),
        hair_curvature: 2.0,
        loop_density: 4000.0,
        loop_r1: Gaussian::new(0.40 * MM, 0.08 * MM),
        core_fraction: 0.3,
    }
}

/// A fine, tightly twisted two-ply: 0.16 mm tube radius.
fn fine_2ply() -> YarnParams {
    YarnParams {
        name: "fine-2ply".into(),
        ply_count: 2,
        fibers_per_ply: 50,
        ply_center_distance: 0.08 * MM,
        ply_ellipse_n: 0.06 * MM,
        ply_ellipse_b: 0.085 * MM,
        ply_pitch: 0.8 * MM,
        fiber_pitch: -0.9 * MM,
        density_epsilon: 0.05,
        density_beta: 0.30,
        r_max: 1.0,
        rho_min: 0.85,
        rho_max: 1.0,
        migration_rate: 1.8,
        fiber_radius: 5.0 * UM,
        hair_density: 2000.0,
        hair_ze: Gaussian::new(0.02 * MM, 0.15 * MM),
        hair_r0: Gaussian::new(0.07 * MM, 0.015 * MM),
        hair_re: Gaussian::new(0.05 * MM, 0.04 * MM),
        hair_pe: Gaussian::new(0.40, 0.35),
        hair_curvature: 2.0,
        loop_density: 1500.0,
        loop_r1: Gaussian::new(0.11 * MM, 0.02 * MM),
        core_fraction: 0.5,
    }
}
