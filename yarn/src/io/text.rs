//! Text writers for inspection and external reference renders.
//!
//! - **Mitsuba 3 curve text** (the `linearcurve` / `bsplinecurve` shapes' file format,
//!   SOURCES.md §c.5): one `x y z radius` line per point, a blank line between curves.
//!   Explicit fibers are written as they are (polylines: load them as `linearcurve`). Yarn
//!   centre curves are written as polylines sampled from the Catmull–Rom curve
//!   (`samples_per_segment` per segment) with the given radius: a uniform Catmull–Rom curve
//!   is only C¹ and is not a uniform cubic B-spline, so writing its control points for
//!   `bsplinecurve` would draw a different curve.
//! - **OBJ polylines**: `v x y z` lines, then one `l i j k …` line per polyline (1-based).
//!
//! Numbers are written with Rust's shortest round-trip formatting, so the text parses back
//! to the same `f32` values.

use crate::curve::YarnSet;
use crate::fiber::Fibers;
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

fn write_with(
    path: &Path,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    btf_core::fs::write_atomic_with(path, produce).map_err(Error::from)
}

/// Writes explicit fibers as Mitsuba 3 curve text (`x y z radius`, blank line between
/// fibers).
pub fn write_mitsuba_fibers(path: &Path, fibers: &Fibers) -> Result<()> {
    write_with(path, |w| {
        for k in 0..fibers.fiber_count() {
            if k > 0 {
                writeln!(w)?;
            }
            let (a, b) = (fibers.offsets[k] as usize, fibers.offsets[k + 1] as usize);
            for i in a..b {
                let p = fibers.points[i];
                writeln!(w, "{} {} {} {}", p[0], p[1], p[2], fibers.radii[i])?;
            }
        }
        Ok(())
    })
}

/// Writes yarn centre curves as Mitsuba 3 curve text (polylines of `samples_per_segment`
/// points per segment, radius `radius`).
pub fn write_mitsuba_yarns(
    path: &Path,
    set: &YarnSet,
    radius: f64,
    samples_per_segment: usize,
) -> Result<()> {
    set.validate()?;
    write_with(path, |w| {
        for (k, c) in set.curves.iter().enumerate() {
            if k > 0 {
                writeln!(w)?;
            }
            for p in c.sample_polyline(samples_per_segment) {
                let q = p.map(|v| v as f32);
                writeln!(w, "{} {} {} {}", q[0], q[1], q[2], radius as f32)?;
            }
        }
        Ok(())
    })
}

/// Writes explicit fibers as OBJ polylines.
pub fn write_obj_fibers(path: &Path, fibers: &Fibers) -> Result<()> {
    write_with(path, |w| {
        writeln!(w, "# {} fibers, {} points (metres)", fibers.fiber_count(), fibers.points.len())?;
        for p in &fibers.points {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        for k in 0..fibers.fiber_count() {
            write!(w, "l")?;
            for i in fibers.offsets[k]..fibers.offsets[k + 1] {
                write!(w, " {}", i + 1)?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

/// Writes yarn centre curves as OBJ polylines (`samples_per_segment` per segment).
pub fn write_obj_yarns(path: &Path, set: &YarnSet, samples_per_segment: usize) -> Result<()> {
    set.validate()?;
    let lines: Vec<Vec<[f32; 3]>> = set
        .curves
        .iter()
        .map(|c| {
            c.sample_polyline(samples_per_segment).iter().map(|p| p.map(|v| v as f32)).collect()
        })
        .collect();
    write_with(path, |w| {
        writeln!(w, "# {} yarn curves (metres)", lines.len())?;
        for l in &lines {
            for p in l {
                writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
            }
        }
        let mut base = 1;
        for l in &lines {
            write!(w, "l")?;
            for i in 0..l.len() {
                write!(w, " {}", base + i)?;
            }
            writeln!(w)?;
            base += l.len();
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::YarnCurve;
    use crate::fiber::{GenOptions, generate_fibers};
    use crate::params::YarnParams;

    #[test]
    fn writers_produce_text_that_parses_back() {
        let p = YarnParams::preset("fine-2ply").unwrap();
        let pts: Vec<[f64; 3]> = (0..4).map(|i| [0.001 * i as f64, 0.0, 0.0]).collect();
        let set = YarnSet::new(vec![YarnCurve::open(pts).unwrap()], None).unwrap();
        let fib =
            generate_fibers(&set, &[p], &GenOptions { hairs: false, ..GenOptions::default() })
                .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("fibers.txt");
        write_mitsuba_fibers(&m, &fib).unwrap();
        let text = std::fs::read_to_string(&m).unwrap();
        let curves: Vec<Vec<[f32; 4]>> = text
            .split("\n\n")
            .map(|block| {
                block
                    .lines()
                    .filter(|l| !l.is_empty())
                    .map(|l| {
                        let v: Vec<f32> = l.split(' ').map(|t| t.parse().unwrap()).collect();
                        [v[0], v[1], v[2], v[3]]
                    })
                    .collect()
            })
            .collect();
        assert_eq!(curves.len(), fib.fiber_count());
        for (k, c) in curves.iter().enumerate() {
            let pts = fib.fiber_points(k);
            assert_eq!(c.len(), pts.len());
            for (a, b) in c.iter().zip(pts) {
                assert_eq!([a[0], a[1], a[2]], *b);
                assert_eq!(a[3], p_radius(&fib));
            }
        }
        let o = dir.path().join("fibers.obj");
        write_obj_fibers(&o, &fib).unwrap();
        let text = std::fs::read_to_string(&o).unwrap();
        let v = text.lines().filter(|l| l.starts_with("v ")).count();
        let lines: Vec<&str> = text.lines().filter(|l| l.starts_with("l ")).collect();
        assert_eq!(v, fib.points.len());
        assert_eq!(lines.len(), fib.fiber_count());
        let idx: Vec<usize> = lines[1].split(' ').skip(1).map(|t| t.parse().unwrap()).collect();
        assert_eq!(idx[0], fib.offsets[1] as usize + 1);
        let y = dir.path().join("yarn.obj");
        write_obj_yarns(&y, &set, 4).unwrap();
        let t = std::fs::read_to_string(&y).unwrap();
        assert_eq!(t.lines().filter(|l| l.starts_with("v ")).count(), 13);
        let ym = dir.path().join("yarn.txt");
        write_mitsuba_yarns(&ym, &set, 2e-4, 4).unwrap();
        let t = std::fs::read_to_string(&ym).unwrap();
        assert_eq!(t.lines().filter(|l| !l.is_empty()).count(), 13);
        assert!(t.lines().next().unwrap().ends_with(" 0.0002"));
    }

    fn p_radius(f: &Fibers) -> f32 {
        f.radii[0]
    }
}
