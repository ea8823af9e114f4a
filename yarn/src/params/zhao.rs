//! Import of a [Z16] fitted yarn, `config_step2.txt`: lines `key: value` or
//! `key: mean sigma`, `#` comments. The files state no unit (SOURCES.md guesses mm from the
//! ply radius ≈ 0.05 and fiber radius 0.002), so the caller must say which one
//! ([`LengthUnit`]: `m | cm | mm | um`); there is no default, and an unknown unit is
//! refused rather than guessed (DESIGN §0).
//!
//! Mapping (everything converted to metres and radians):
//! - `ply_num`, `fiber_num` → `ply_count`, `fibers_per_ply` (fibers per ply, as [Z16]'s
//!   parser resizes each ply to `fiber_num`);
//! - `yarn_radius` → `ply_center_distance = yarn_radius/2` ([Z16]'s code places the ply
//!   centres at half the yarn radius);
//! - `ellipse_short` → `ply_ellipse_n`, `ellipse_long` → `ply_ellipse_b` ([Z16]'s code
//!   scales the axis pointing at the yarn centre by the short one);
//! - `alpha`, `yarn_alpha` → `fiber_pitch`, `ply_pitch`, negated when
//!   `fiber_clock_wise` / `yarn_clock_wise` is 1;
//! - `epsilon, beta, R_max, rho_min, rho_max, s_i` unchanged; `use_migration: 0` sets
//!   ρ_min = ρ_max = 1 (no migration, as [Z16]'s `helixRadius` then returns `R_i`);
//! - flyaway densities (per file unit of length) are divided by the unit; `ze, r0, re, r1`
//!   are lengths; `pe` is an angle and stays; `use_flyaways: 0` zeroes the densities;
//! - `fiber_radius` if present, else the caller's value, else 0.002 file units (the value
//!   of Montazeri's scenes, SOURCES.md), reported in [`ZhaoImport::fiber_radius_source`].
//!
//! `hair_curvature` is 1 ([Z16]'s hair is straight) and `core_fraction` 0.5.

use super::{Gaussian, YarnParams};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::str::FromStr;

/// The length unit of an imported file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// Metres.
    Metre,
    /// Centimetres.
    Centimetre,
    /// Millimetres.
    Millimetre,
    /// Micrometres.
    Micrometre,
}

impl LengthUnit {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Metre => 1.0,
            LengthUnit::Centimetre => 1e-2,
            LengthUnit::Millimetre => 1e-3,
            LengthUnit::Micrometre => 1e-6,
        }
    }
}

impl FromStr for LengthUnit {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "m" => LengthUnit::Metre,
            "cm" => LengthUnit::Centimetre,
            "mm" => LengthUnit::Millimetre,
            "um" => LengthUnit::Micrometre,
            other => {
                return Err(Error::Invalid(format!(
                    "length unit '{other}': give one of m, cm, mm, um (the Zhao config files \
                     state none, so none is guessed)"
                )));
            }
        })
    }
}

/// The result of an import: the params and what the file held that was not used.
#[derive(Debug, Clone)]
pub struct ZhaoImport {
    /// The validated params, in metres.
    pub params: YarnParams,
    /// Keys present in the file and not used (in file order).
    pub ignored_keys: Vec<String>,
    /// Where the fiber radius came from: `"file"`, `"caller"` or `"default 0.002 file units"`.
    pub fiber_radius_source: &'static str,
}

const IGNORED: [&str; 8] = [
    "z_step_size",
    "z_step_num",
    "fly_step_size",
    "aabb_min",
    "aabb_max",
    "mu",
    "sigma",
    "flyaway_num",
];

/// Imports a [Z16] `config_step2.txt` (text `text`, named `source` in messages) in `unit`.
pub fn import_zhao_config(
    text: &str,
    source: &str,
    unit: LengthUnit,
    fiber_radius: Option<f64>,
) -> Result<ZhaoImport> {
    let mut values: BTreeMap<String, (usize, Vec<f64>)> = BTreeMap::new();
    let mut ignored = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let Some((key, rest)) = line.split_once(':') else {
            return Err(Error::Invalid(format!(
                "{source}:{}: expected 'key: value', found '{line}'",
                i + 1
            )));
        };
        let key = key.trim().to_owned();
        if IGNORED.contains(&key.as_str()) || !KNOWN.contains(&key.as_str()) {
            ignored.push(key);
            continue;
        }
        let nums: Result<Vec<f64>> = rest
            .split_whitespace()
            .map(|t| {
                t.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                    Error::Invalid(format!(
                        "{source}:{}: {key}: '{t}' is not a finite number",
                        i + 1
                    ))
                })
            })
            .collect();
        values.insert(key, (i + 1, nums?));
    }
    let get = |key: &str, n: usize| -> Result<Option<Vec<f64>>> {
        match values.get(key) {
            None => Ok(None),
            Some((line, v)) if v.len() == n => {
                let _ = line;
                Ok(Some(v.clone()))
            }
            Some((line, v)) => Err(Error::Invalid(format!(
                "{source}:{line}: {key} has {} numbers, expected {n}",
                v.len()
            ))),
        }
    };
    let need = |key: &str| -> Result<f64> {
        get(key, 1)?.map(|v| v[0]).ok_or_else(|| {
            Error::Invalid(format!(
                "{source}: missing key '{key}' (a Zhao config_step2.txt has it)"
            ))
        })
    };
    let opt =
        |key: &str, default: f64| -> Result<f64> { Ok(get(key, 1)?.map_or(default, |v| v[0])) };
    let gauss = |key: &str, m: f64| -> Result<Gaussian> {
        Ok(get(key, 2)?.map_or(Gaussian::new(0.0, 0.0), |v| Gaussian::new(v[0] * m, v[1] * m)))
    };
    let count = |key: &str| -> Result<u32> {
        let v = need(key)?;
        if v < 0.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
            return Err(Error::Invalid(format!("{source}: {key} = {v} is not a count")));
        }
        Ok(v as u32)
    };
    let u = unit.metres();
    let sign = |key: &str| -> Result<f64> { Ok(if opt(key, 0.0)? != 0.0 { -1.0 } else { 1.0 }) };
    let migration = opt("use_migration", 1.0)? != 0.0;
    let flyaways = opt("use_flyaways", 1.0)? != 0.0;
    let (fiber_radius, fiber_radius_source) = match (get("fiber_radius", 1)?, fiber_radius) {
        (Some(v), _) => (v[0] * u, "file"),
        (None, Some(r)) => (r, "caller"),
        (None, None) => (0.002 * u, "default 0.002 file units"),
    };
    let stem = std::path::Path::new(source)
        .file_stem()
        .map_or_else(|| source.to_owned(), |s| s.to_string_lossy().into_owned());
    let params = YarnParams {
        name: stem,
        ply_count: count("ply_num")?,
        fibers_per_ply: count("fiber_num")?,
        ply_center_distance: 0.5 * need("yarn_radius")? * u,
        ply_ellipse_n: need("ellipse_short")? * u,
        ply_ellipse_b: need("ellipse_long")? * u,
        ply_pitch: sign("yarn_clock_wise")? * need("yarn_alpha")? * u,
        fiber_pitch: sign("fiber_clock_wise")? * need("alpha")? * u,
        density_epsilon: need("epsilon")?,
        density_beta: need("beta")?,
        r_max: opt("R_max", 1.0)?,
        rho_min: if migration { need("rho_min")? } else { 1.0 },
        rho_max: if migration { opt("rho_max", 1.0)? } else { 1.0 },
        migration_rate: need("s_i")?,
        fiber_radius,
        hair_density: if flyaways { opt("flyaway_hair_density", 0.0)? / u } else { 0.0 },
        hair_ze: gauss("flyaway_hair_ze", u)?,
        hair_r0: gauss("flyaway_hair_r0", u)?,
        hair_re: gauss("flyaway_hair_re", u)?,
        hair_pe: gauss("flyaway_hair_pe", 1.0)?,
        hair_curvature: 1.0,
        loop_density: if flyaways { opt("flyaway_loop_density", 0.0)? / u } else { 0.0 },
        loop_r1: gauss("flyaway_loop_r1", u)?,
        core_fraction: 0.5,
    };
    params.validate().map_err(|e| match e {
        Error::Invalid(m) => Error::Invalid(format!("{source}: {m}")),
        other => other,
    })?;
    Ok(ZhaoImport { params, ignored_keys: ignored, fiber_radius_source })
}

const KNOWN: [&str; 25] = [
    "fiber_radius",
    "ply_num",
    "fiber_num",
    "yarn_radius",
    "ellipse_long",
    "ellipse_short",
    "alpha",
    "yarn_alpha",
    "yarn_clock_wise",
    "fiber_clock_wise",
    "epsilon",
    "beta",
    "R_max",
    "rho_min",
    "rho_max",
    "s_i",
    "use_migration",
    "use_flyaways",
    "flyaway_hair_density",
    "flyaway_hair_ze",
    "flyaway_hair_r0",
    "flyaway_hair_re",
    "flyaway_hair_pe",
    "flyaway_loop_density",
    "flyaway_loop_r1",
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A config in [Z16]'s format with numbers of our own.
    const FIXTURE: &str = "\
ply_num: 2
fiber_num: 40
z_step_size: 0.01
aabb_min: [-0.1,-0.1,-1]
yarn_clock_wise: 0
fiber_clock_wise: 1
yarn_alpha: 0.5
alpha: 0.6
yarn_radius: 0.04
ellipse_long: 0.03
ellipse_short: 0.02
epsilon: 0.1
R_max: 1
beta: 0.5
rho_min: 0.8
rho_max: 1
s_i: 1.5
use_migration: 1
use_flyaways: 1
flyaway_hair_density: 20 # per file unit
flyaway_hair_ze: 0.01 0.05
flyaway_hair_r0: 0.03 0.005
flyaway_hair_re: 0.02 0.01
flyaway_hair_pe: 0.4 0.3
flyaway_loop_density: 10
flyaway_loop_r1: 0.04 0.008
";

    #[test]
    fn import_converts_units_and_handedness_and_refuses_to_guess() {
        let imp =
            import_zhao_config(FIXTURE, "yarn9/config_step2.txt", LengthUnit::Millimetre, None)
                .unwrap();
        let p = &imp.params;
        assert_eq!((p.ply_count, p.fibers_per_ply), (2, 40));
        assert!((p.ply_center_distance - 0.02e-3).abs() < 1e-18);
        assert_eq!((p.ply_ellipse_n, p.ply_ellipse_b), (0.02e-3, 0.03e-3));
        assert!(p.fiber_pitch < 0.0 && p.ply_pitch > 0.0);
        assert!((p.fiber_pitch + 0.6e-3).abs() < 1e-18);
        assert!((p.hair_density - 20_000.0).abs() < 1e-9);
        assert!((p.loop_r1.mean - 0.04e-3).abs() < 1e-18);
        assert_eq!(p.hair_pe, Gaussian::new(0.4, 0.3));
        assert_eq!(imp.fiber_radius_source, "default 0.002 file units");
        assert_eq!(imp.ignored_keys, vec!["z_step_size".to_owned(), "aabb_min".to_owned()]);
        for bad in ["", "inch", "MM", "millimetre"] {
            assert!(bad.parse::<LengthUnit>().is_err(), "{bad}");
        }
        let missing = FIXTURE.replace("beta: 0.5\n", "");
        let e = import_zhao_config(&missing, "c.txt", LengthUnit::Metre, None).unwrap_err();
        assert!(e.to_string().contains("'beta'"), "{e}");
        let nan = FIXTURE.replace("alpha: 0.6", "alpha: nan");
        let e = import_zhao_config(&nan, "c.txt", LengthUnit::Metre, None).unwrap_err();
        assert!(e.to_string().contains("c.txt:8"), "{e}");
    }
}
