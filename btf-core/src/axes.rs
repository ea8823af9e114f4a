//! The direction arrays of a store: the polar angle θ and azimuth φ, in degrees, of every
//! view slot and every light, as four one-dimensional Zarr arrays beside the data
//! (`view_theta_deg`, `view_phi_deg` along `view`; `light_theta_deg`, `light_phi_deg` along
//! `light`), so a reader needs no sampling code to know which direction slot `j` or light
//! `i` is. The frame is the tangent frame of docs/DESIGN.md §3: `+z` the surface normal,
//! `+x` along texture `+u` (increasing column), `+y` along increasing row; θ from `+z`,
//! φ from `+x` toward `+y` in `[0°, 360°)`. The slot order is the sampling's numbering
//! (ring by ring from the pole, by increasing φ within a ring).
//!
//! Every store writer adds them at commit ([`write`]); readers check them against the
//! sampling in the group attributes ([`check`]). Stores written before issue #25 have none
//! and stay readable.

use crate::sampling::Sampling;
use crate::store::BtfMeta;
use crate::zarr::{self, ArrayMeta, DType, Limits, ZarrArray};
use crate::{Error, Result};
use serde_json::json;
use std::path::Path;

/// The frame the angles are given in, as recorded in each array's attributes.
pub const FRAME: &str = "tangent space of the sample: +z surface normal, +x along texture +u \
    (increasing column x), +y along increasing row y; theta from +z, phi from +x toward +y \
    in [0, 360)";

/// Largest difference (degrees) between a stored angle and the sampling's: the arrays are
/// `f64` copies of the sampling's own `f64` angles, so anything above rounding is foreign.
pub const TOLERANCE_DEG: f64 = 1e-9;

/// The four arrays: name, axis, which sampling, angle (0 = θ, 1 = φ).
const ARRAYS: [(&str, &str, bool, usize); 4] = [
    ("view_theta_deg", "view", true, 0),
    ("view_phi_deg", "view", true, 1),
    ("light_theta_deg", "light", false, 0),
    ("light_phi_deg", "light", false, 1),
];

fn angles(s: &Sampling, which: usize) -> Vec<f64> {
    s.directions().iter().map(|d| if which == 0 { d.theta_deg } else { d.phi_deg }).collect()
}

/// Writes the four direction arrays of `meta`'s samplings into the store folder `dir`.
pub fn write(dir: &Path, meta: &BtfMeta) -> Result<()> {
    for (name, axis, view, which) in ARRAYS {
        let s = if view { &meta.view_sampling } else { &meta.light_sampling };
        let values = angles(s, which);
        let n = values.len() as u64;
        let a = ArrayMeta {
            attributes: json!({
                "units": "degree",
                "angle": if which == 0 { "theta (polar, from the surface normal)" } else { "phi (azimuth)" },
                "frame": FRAME,
                "sampling": s.name,
                "order": "the sampling's numbering: ring by ring from the pole, increasing phi within a ring from the ring's offset",
            }),
            ..ArrayMeta::new(vec![n], vec![n], DType::F64, &[axis])
        };
        let arr = ZarrArray::create(&dir.join(name), a)?;
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        arr.write_chunk(&[0], &raw)?;
    }
    Ok(())
}

/// The stored angles of a store: `(view θ, view φ, light θ, light φ)` in degrees, or
/// `None` for a store written before the arrays existed.
pub type Angles = [Vec<f64>; 4];

/// Reads the four direction arrays of the store at `path` (`None` when it has none).
pub fn read(path: &Path) -> Result<Option<Angles>> {
    if !path.join(ARRAYS[0].0).join("zarr.json").exists() {
        return Ok(None);
    }
    let mut out: Angles = Default::default();
    for ((name, ..), o) in ARRAYS.iter().zip(out.iter_mut()) {
        let arr = ZarrArray::open(&path.join(name), &Limits::default())?;
        let m = arr.meta();
        if m.shape.len() != 1 || m.dtype != DType::F64 || m.chunk_shape != m.shape {
            return Err(Error::Corrupt {
                path: path.join(name).join("zarr.json"),
                what: "a direction array must be one f64 chunk of one dimension".into(),
            });
        }
        *o = zarr::decode_f64(&arr.read_chunk(&[0])?);
    }
    Ok(Some(out))
}

/// Checks the direction arrays of the store at `path`, when it has them, against the
/// samplings of its metadata; the error names the array and the slot or light.
pub fn check(path: &Path, meta: &BtfMeta) -> Result<()> {
    let Some(stored) = read(path)? else { return Ok(()) };
    for ((name, _, view, which), got) in ARRAYS.iter().zip(&stored) {
        let s = if *view { &meta.view_sampling } else { &meta.light_sampling };
        let want = angles(s, *which);
        let bad = |what: String| Error::Corrupt { path: path.join(name), what };
        if got.len() != want.len() {
            return Err(bad(format!("{} angles, the sampling has {}", got.len(), want.len())));
        }
        // Written so that a NaN fails too.
        let close = |i: usize| (got[i] - want[i]).abs() <= TOLERANCE_DEG;
        if let Some(i) = (0..want.len()).find(|&i| !close(i)) {
            return Err(bad(format!(
                "entry {i} is {}°, the sampling '{}' says {}°",
                got[i], s.name, want[i]
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ubo81_angles_round_trip_and_a_wrong_one_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let s = Sampling::ubo81();
        let meta = BtfMeta::new(s.clone(), s, 4, 4);
        write(dir.path(), &meta).unwrap();
        let [vt, vp, lt, lp] = read(dir.path()).unwrap().unwrap();
        // DESIGN.md §3: ubo81 rings θ = 0, 15, …, 75 with 1, 6, 12, 18, 20, 24 directions.
        assert_eq!(vt.len(), 81);
        assert_eq!((vt[0], vt[1], vt[7], vt[80]), (0.0, 15.0, 30.0, 75.0));
        // Ring 1 (6 directions): Δφ = 60°; slot 2 is its second direction.
        assert!((vp[2] - 60.0).abs() <= TOLERANCE_DEG, "{}", vp[2]);
        // Last ring (24 directions, Δφ = 15°): the last light is at φ = 345°.
        assert!((lp[80] - 345.0).abs() <= TOLERANCE_DEG && lt == vt, "{}", lp[80]);
        check(dir.path(), &meta).unwrap();
        let other = Sampling::by_name("ubo81-h1").unwrap();
        let e = check(dir.path(), &BtfMeta::new(other.clone(), other, 4, 4)).unwrap_err();
        let e = e.to_string();
        assert!(e.contains("view_theta_deg") && e.contains("entry 1 is 15°"), "{e}");
    }
}
