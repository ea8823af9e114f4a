//! MADYPG `.pyp` periodic yarn patterns (Sperl et al. 2021, MIT; SOURCES.md), read into a
//! periodic [`YarnSet`]. Units are metres.
//!
//! Sections start with `*name` (the rest of that line is a comment listing the fields):
//! `*pattern` holds `px py radius num_vertedges`; `*Q` one line `x y z t` per vertex (`t`,
//! a twist, is not used); `*E` one line `v0 v1 dx dy` per edge: the yarn runs from vertex
//! `v0` to vertex `v1` translated by `(dx·px, dy·py)` — read so because the rest lengths of
//! `*RL` match those translated distances [derived from the files]. Other sections (rest
//! lengths, curvatures, twists, directors) are skipped.
//!
//! Every vertex must have exactly one outgoing and one incoming edge, so the edges form
//! cycles; each cycle becomes one closed curve whose `shift` is the sum of its edges'
//! translations (a periodic course when non-zero, a loop otherwise). Counts that disagree
//! with `num_vertedges`, indices out of range, non-finite numbers and vertices without
//! exactly one edge in and out are refused naming the line or the vertex.

use crate::curve::{YarnCurve, YarnSet};
use crate::vec3::V3;
use crate::{Error, Result};
use std::path::Path;

/// Most vertices a pattern may have.
pub const MAX_VERTICES: usize = 1 << 22;

/// A periodic yarn pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct PypPattern {
    /// Period `[px, py]` (metres).
    pub period: [f64; 2],
    /// Yarn radius (metres).
    pub radius: f64,
    /// The cycles as closed curves, with `period` set.
    pub set: YarnSet,
}

fn numbers(line: &str, n: usize, source: &str, ln: usize) -> Result<Vec<f64>> {
    let v: Vec<f64> = line
        .split_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| {
            Error::Invalid(format!("{source}:{ln}: '{line}' is not {n} finite numbers"))
        })?;
    if v.len() != n {
        return Err(Error::Invalid(format!("{source}:{ln}: {} numbers, expected {n}", v.len())));
    }
    Ok(v)
}

/// Parses `.pyp` text (`source` names it in messages).
pub fn parse_pyp(text: &str, source: &str) -> Result<PypPattern> {
    let mut section = String::new();
    let mut header: Option<(f64, f64, f64, usize)> = None;
    let mut q: Vec<V3> = Vec::new();
    let mut edges: Vec<(usize, usize, f64, f64, usize)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let (ln, line) = (i + 1, raw.trim());
        if line.is_empty() {
            continue;
        }
        if let Some(rest) = line.strip_prefix('*') {
            section = rest.split_whitespace().next().unwrap_or("").to_owned();
            continue;
        }
        match section.as_str() {
            "pattern" => {
                let v = numbers(line, 4, source, ln)?;
                if !(v[0] > 0.0 && v[1] > 0.0 && v[2] >= 0.0) || v[3] < 0.0 || v[3].fract() != 0.0 {
                    return Err(Error::Invalid(format!(
                        "{source}:{ln}: bad pattern header '{line}'"
                    )));
                }
                if v[3] as usize > MAX_VERTICES {
                    return Err(Error::Limit(format!(
                        "{source}:{ln}: {} vertices (at most {MAX_VERTICES})",
                        v[3]
                    )));
                }
                header = Some((v[0], v[1], v[2], v[3] as usize));
            }
            "Q" => {
                let v = numbers(line, 4, source, ln)?;
                if q.len() >= MAX_VERTICES {
                    return Err(Error::Limit(format!(
                        "{source}:{ln}: more than {MAX_VERTICES} vertices"
                    )));
                }
                q.push([v[0], v[1], v[2]]);
            }
            "E" => {
                let v = numbers(line, 4, source, ln)?;
                if v[0] < 0.0 || v[1] < 0.0 || v.iter().any(|x| x.fract() != 0.0) {
                    return Err(Error::Invalid(format!(
                        "{source}:{ln}: edge '{line}' is not integers"
                    )));
                }
                if edges.len() >= MAX_VERTICES {
                    return Err(Error::Limit(format!(
                        "{source}:{ln}: more than {MAX_VERTICES} edges"
                    )));
                }
                edges.push((v[0] as usize, v[1] as usize, v[2], v[3], ln));
            }
            _ => {}
        }
    }
    let (px, py, radius, n) =
        header.ok_or_else(|| Error::Invalid(format!("{source}: no *pattern section")))?;
    if q.len() != n || edges.len() != n {
        return Err(Error::Invalid(format!(
            "{source}: the pattern declares {n} vertices and edges, the file has {} vertices and {} edges",
            q.len(),
            edges.len()
        )));
    }
    let mut next: Vec<Option<(usize, f64, f64)>> = vec![None; n];
    let mut incoming = vec![0usize; n];
    for &(a, b, dx, dy, ln) in &edges {
        if a >= n || b >= n {
            return Err(Error::Invalid(format!(
                "{source}:{ln}: edge {a} → {b} names a vertex ≥ {n}"
            )));
        }
        if next[a].replace((b, dx, dy)).is_some() {
            return Err(Error::Invalid(format!(
                "{source}:{ln}: vertex {a} has two outgoing edges"
            )));
        }
        incoming[b] += 1;
    }
    if let Some(v) = (0..n).find(|&v| next[v].is_none() || incoming[v] != 1) {
        return Err(Error::Invalid(format!(
            "{source}: vertex {v} has {} outgoing and {} incoming edges (the yarn must run \
             through every vertex once)",
            next[v].is_some() as usize,
            incoming[v]
        )));
    }
    let mut seen = vec![false; n];
    let mut curves = Vec::new();
    for start in 0..n {
        if seen[start] {
            continue;
        }
        let (mut v, mut ox, mut oy) = (start, 0.0, 0.0);
        let mut pts = Vec::new();
        while !seen[v] {
            seen[v] = true;
            pts.push([q[v][0] + ox * px, q[v][1] + oy * py, q[v][2]]);
            let (w, dx, dy) = next[v].expect("checked");
            ox += dx;
            oy += dy;
            v = w;
        }
        let shift = [ox * px, oy * py, 0.0];
        let c = YarnCurve::periodic(pts, shift).map_err(|e| match e {
            Error::Invalid(m) => {
                Error::Invalid(format!("{source}: the cycle through vertex {start}: {m}"))
            }
            other => other,
        })?;
        curves.push(c);
    }
    Ok(PypPattern { period: [px, py], radius, set: YarnSet::new(curves, Some([px, py]))? })
}

/// Reads a `.pyp` file.
pub fn read_pyp(path: &Path) -> Result<PypPattern> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.len() > 1 << 30 {
        return Err(Error::Limit(format!(
            "{}: {} bytes (at most 1 GiB)",
            path.display(),
            meta.len()
        )));
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_pyp(&text, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vec3;

    /// A fixture of our own in the format: one course of 4 vertices crossing the x period,
    /// and a small closed ring.
    const FIXTURE: &str = "\
*pattern # px py radius num_vertedges
0.004 0.003 0.0002 7

*Q # dofs: x y z t
0.0005 0.0010 0.0001 0.0
0.0015 0.0020 -0.0001 0.1
0.0025 0.0010 0.0001 0.0
0.0035 0.0000 -0.0001 -0.1
0.0010 0.0015 0.0 0.0
0.0020 0.0015 0.0 0.0
0.0015 0.0025 0.0 0.0

*E # edges: v0 v1 dx dy
0 1 0 0
1 2 0 0
2 3 0 0
3 0 1 0
4 5 0 0
5 6 0 0
6 4 0 0

*RL # rest lengths
0.0014
0.0014
0.0014
0.0011
0.001
0.001
0.001
";

    #[test]
    fn fixture_parses_into_a_periodic_course_and_a_ring() {
        let p = parse_pyp(FIXTURE, "fixture.pyp").unwrap();
        assert_eq!(p.period, [0.004, 0.003]);
        assert_eq!(p.radius, 0.0002);
        assert_eq!(p.set.curves.len(), 2);
        let course = &p.set.curves[0];
        assert_eq!(course.shift, [0.004, 0.0, 0.0]);
        assert_eq!(course.points.len(), 4);
        // The edge 3 → 0 crosses the period: the next point is vertex 0 shifted by px.
        assert!(vec3::distance(course.point(4.0), [0.0045, 0.0010, 0.0001]) < 1e-15);
        assert_eq!(p.set.curves[1].shift, [0.0, 0.0, 0.0]);
        for (bad, what) in [
            (FIXTURE.replace("3 0 1 0", "3 1 1 0"), "vertex"),
            (FIXTURE.replace("0.004 0.003 0.0002 7", "0.004 0.003 0.0002 8"), "declares 8"),
            (FIXTURE.replace("0.0025 0.0010", "nan 0.0010"), "fixture.pyp:7:"),
            (FIXTURE.replace("6 4 0 0", "6 9 0 0"), "≥ 7"),
        ] {
            let e = parse_pyp(&bad, "fixture.pyp").unwrap_err().to_string();
            assert!(e.contains(what), "{what}: {e}");
        }
    }
}
