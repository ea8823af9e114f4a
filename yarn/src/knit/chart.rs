//! Stitch charts in a small text format of our own (DESIGN §1.6 leaves the format open).
//!
//! ```text
//! # a comment: '#' to the end of the line, anywhere
//! name: rib 2x2
//! k k p p      # one row per course, drawn as knitters draw charts:
//! k k p p      # the LAST row is course 0, the first column wale 0
//! ```
//!
//! - The first non-blank, non-comment line is `name: <text>` (required, non-empty).
//! - Every other non-blank line is a row; spaces and tabs inside a row are ignored. All
//!   rows must have the same number of stitches.
//! - Stitches: `k` knit, `p` purl, `+` increase (make one), `/` decrease (two together),
//!   `o` yarn-over, `<` cable crossing to the left (the stitches that travel left pass in
//!   front), `>` cable crossing to the right (those travelling right pass in front). A run of
//!   `2m` equal cable characters in a row is one m-over-m cross (`<<<<` = 2 over 2);
//!   runs do not continue across the chart's edge, must have even length and `m ≤ 3`.
//! - Errors name the source, the line and the column (1-based, counting characters of the
//!   line as written).
//!
//! A chart tiles the plane: [`Chart::at`] wraps course and wale. The built-ins are
//! [`Chart::BUILTIN`]; `flame` is a hashed knit/purl chart (no period smaller than its
//! size), the non-periodic pattern of DESIGN §1.6 and [H25]'s "Flame".

use crate::hash::hash_keys;
use crate::{Error, Result};

/// One stitch of a chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stitch {
    /// `k`.
    Knit,
    /// `p`.
    Purl,
    /// `+` (make one).
    Increase,
    /// `/` (knit two together).
    Decrease,
    /// `o`.
    YarnOver,
    /// `<`: part of a cable crossing to the left.
    CableLeft,
    /// `>`: part of a cable crossing to the right.
    CableRight,
}

impl Stitch {
    /// The chart character.
    pub fn symbol(self) -> char {
        match self {
            Stitch::Knit => 'k',
            Stitch::Purl => 'p',
            Stitch::Increase => '+',
            Stitch::Decrease => '/',
            Stitch::YarnOver => 'o',
            Stitch::CableLeft => '<',
            Stitch::CableRight => '>',
        }
    }

    /// The stitch of a chart character.
    pub fn from_symbol(c: char) -> Option<Self> {
        Some(match c {
            'k' => Stitch::Knit,
            'p' => Stitch::Purl,
            '+' => Stitch::Increase,
            '/' => Stitch::Decrease,
            'o' => Stitch::YarnOver,
            '<' => Stitch::CableLeft,
            '>' => Stitch::CableRight,
            _ => return None,
        })
    }

    /// True for the two cable stitches.
    pub fn is_cable(self) -> bool {
        matches!(self, Stitch::CableLeft | Stitch::CableRight)
    }
}

/// Where a cable stitch sits in its cross.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CablePart {
    /// Stitches per side (`m` of an m-over-m cross).
    pub half: usize,
    /// Position in the run, `0..2m`.
    pub index: usize,
}

/// A stitch chart (course 0 at the bottom).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Chart {
    /// The chart's name.
    pub name: String,
    /// Stitches per course.
    pub width: usize,
    /// Courses.
    pub height: usize,
    /// Stitches `[course][wale]`, course 0 first.
    cells: Vec<Stitch>,
}

/// Largest cable half-width `m`.
pub const MAX_CABLE_HALF: usize = 3;

impl Chart {
    /// Names of the built-in charts.
    pub const BUILTIN: [&'static str; 9] = [
        "stockinette",
        "reverse-stockinette",
        "garter",
        "rib1x1",
        "rib2x2",
        "seed",
        "basketweave",
        "cable2x2",
        "flame",
    ];

    /// A chart from rows given course 0 first (validated as a parsed chart is).
    pub fn from_courses(name: &str, courses: Vec<Vec<Stitch>>) -> Result<Self> {
        let mut text = format!("name: {name}\n");
        for row in courses.iter().rev() {
            text.extend(row.iter().map(|s| s.symbol()));
            text.push('\n');
        }
        Chart::parse(&text, name)
    }

    /// Parses the text format (see the module documentation).
    pub fn parse(text: &str, source: &str) -> Result<Self> {
        let mut name: Option<String> = None;
        let mut rows: Vec<(usize, Vec<(usize, Stitch)>)> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let content = raw.split('#').next().unwrap_or("");
            if content.trim().is_empty() {
                continue;
            }
            if name.is_none() {
                let n = content.trim().strip_prefix("name:").map(str::trim).unwrap_or("");
                if n.is_empty() {
                    return Err(Error::Invalid(format!(
                        "{source}: line {line_no}, column 1: a chart starts with 'name: <text>'"
                    )));
                }
                name = Some(n.to_owned());
                continue;
            }
            let mut row = Vec::new();
            for (col, ch) in content.chars().enumerate() {
                if ch == ' ' || ch == '\t' || ch == '\r' {
                    continue;
                }
                let s = Stitch::from_symbol(ch).ok_or_else(|| {
                    Error::Invalid(format!(
                        "{source}: line {line_no}, column {}: unknown stitch '{ch}' (known: k p + / o < >)",
                        col + 1
                    ))
                })?;
                row.push((col + 1, s));
            }
            rows.push((line_no, row));
        }
        let name = name.ok_or_else(|| {
            Error::Invalid(format!("{source}: empty chart (no name line, no rows)"))
        })?;
        let Some((_, first)) = rows.first() else {
            return Err(Error::Invalid(format!("{source}: chart '{name}' has no rows")));
        };
        let width = first.len();
        for (line_no, row) in &rows {
            if row.len() != width {
                let col = row.get(width).or(row.last()).map_or(1, |c| c.0);
                return Err(Error::Invalid(format!(
                    "{source}: line {line_no}, column {col}: row of {} stitches, the first row has {width}",
                    row.len()
                )));
            }
            // Cable runs: even length, at most 2·MAX_CABLE_HALF.
            let mut k = 0;
            while k < row.len() {
                let s = row[k].1;
                let mut e = k + 1;
                while e < row.len() && row[e].1 == s {
                    e += 1;
                }
                if s.is_cable() {
                    let len = e - k;
                    if len % 2 != 0 {
                        return Err(Error::Invalid(format!(
                            "{source}: line {line_no}, column {}: a cable run of {len} '{}' (a cross needs an even number)",
                            row[k].0,
                            s.symbol()
                        )));
                    }
                    if len / 2 > MAX_CABLE_HALF {
                        return Err(Error::Unsupported(format!(
                            "{source}: line {line_no}, column {}: a {}-over-{} cable (at most {MAX_CABLE_HALF}-over-{MAX_CABLE_HALF}: wider crossings pull loops too far for the key-point templates)",
                            row[k].0,
                            len / 2,
                            len / 2
                        )));
                    }
                }
                k = e;
            }
        }
        let height = rows.len();
        let cells = rows.iter().rev().flat_map(|(_, r)| r.iter().map(|c| c.1)).collect();
        Ok(Chart { name, width, height, cells })
    }

    /// The text of the chart (parses back to an equal chart).
    pub fn to_text(&self) -> String {
        let mut t = format!("name: {}\n", self.name);
        for c in (0..self.height).rev() {
            t.extend((0..self.width).map(|w| self.cells[c * self.width + w].symbol()));
            t.push('\n');
        }
        t
    }

    /// The stitch at `(course, wale)`, wrapping (charts tile).
    pub fn at(&self, course: i64, wale: i64) -> Stitch {
        let c = course.rem_euclid(self.height as i64) as usize;
        let w = wale.rem_euclid(self.width as i64) as usize;
        self.cells[c * self.width + w]
    }

    /// The cable cross a stitch belongs to (runs do not wrap across the chart's edge).
    pub fn cable_part(&self, course: i64, wale: i64) -> Option<CablePart> {
        let s = self.at(course, wale);
        if !s.is_cable() {
            return None;
        }
        let w = wale.rem_euclid(self.width as i64) as usize;
        let row = |x: usize| self.at(course, x as i64);
        let mut start = w;
        while start > 0 && row(start - 1) == s {
            start -= 1;
        }
        let mut end = w + 1;
        while end < self.width && row(end) == s {
            end += 1;
        }
        // Runs were validated even; a long run is a sequence of crosses only if parsed so.
        Some(CablePart { half: (end - start) / 2, index: w - start })
    }

    /// A built-in chart by name ([`Chart::BUILTIN`]).
    pub fn builtin(name: &str) -> Result<Self> {
        let rows: &[&str] = match name {
            "stockinette" => &["kkkk", "kkkk", "kkkk", "kkkk"],
            "reverse-stockinette" => &["pppp", "pppp", "pppp", "pppp"],
            "garter" => &["pppp", "kkkk"],
            "rib1x1" => &["kpkp", "kpkp"],
            "rib2x2" => &["kkpp", "kkpp"],
            "seed" => &["pkpk", "kpkp"],
            "basketweave" => &[
                "ppppkkkk", "ppppkkkk", "ppppkkkk", "ppppkkkk", "kkkkpppp", "kkkkpppp", "kkkkpppp",
                "kkkkpppp",
            ],
            "cable2x2" => &["ppkkkkpp", "ppkkkkpp", "ppkkkkpp", "pp<<<<pp"],
            "flame" => return Ok(Chart::flame(16, 16, 1)),
            other => {
                return Err(Error::Invalid(format!(
                    "unknown chart '{other}' (built-in: {})",
                    Chart::BUILTIN.join(", ")
                )));
            }
        };
        let mut text = format!("name: {name}\n");
        for r in rows {
            text.push_str(r);
            text.push('\n');
        }
        Chart::parse(&text, name)
    }

    /// A hashed knit/purl chart: purl where `hash(seed, course, wale)` falls below a
    /// threshold that rises and falls along the course like flames.
    pub fn flame(width: usize, height: usize, seed: u64) -> Chart {
        let (width, height) = (width.max(1), height.max(1));
        let mut cells = Vec::with_capacity(width * height);
        for c in 0..height {
            for w in 0..width {
                let phase = std::f64::consts::TAU * w as f64 / width as f64;
                let threshold = 0.5 + 0.35 * (phase + 0.7 * c as f64).sin();
                let u = crate::hash::unit_f64(hash_keys(&[seed, c as u64, w as u64]));
                cells.push(if u < threshold { Stitch::Purl } else { Stitch::Knit });
            }
        }
        Chart { name: format!("flame-{width}x{height}-{seed}"), width, height, cells }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_parses_and_round_trips() {
        for name in Chart::BUILTIN {
            let c = Chart::builtin(name).unwrap();
            let back = Chart::parse(&c.to_text(), name).unwrap();
            assert_eq!(back, c, "{name}");
            assert!(c.width > 0 && c.height > 0);
        }
        let g = Chart::builtin("garter").unwrap();
        assert_eq!(
            (g.at(0, 0), g.at(1, 0), g.at(2, 5)),
            (Stitch::Knit, Stitch::Purl, Stitch::Knit)
        );
        let cable = Chart::builtin("cable2x2").unwrap();
        assert_eq!(cable.cable_part(0, 3), Some(CablePart { half: 2, index: 1 }));
        assert_eq!(cable.cable_part(1, 3), None);
        let f = Chart::builtin("flame").unwrap();
        let purls = (0..16)
            .flat_map(|c| (0..16).map(move |w| (c, w)))
            .filter(|&(c, w)| f.at(c, w) == Stitch::Purl)
            .count();
        assert!(purls > 60 && purls < 200, "{purls}");
    }

    #[test]
    fn bad_charts_are_refused_with_line_and_column() {
        let cases = [
            ("name: x\nkkk\nkk\n", "line 3, column 2"),
            ("name: x\nkqk\n", "line 2, column 2: unknown stitch 'q'"),
            ("", "empty chart"),
            ("# only a comment\nname: x\n", "no rows"),
            ("kkk\n", "line 1, column 1"),
            ("name: x\nk<<<k\n", "line 2, column 2: a cable run of 3"),
            ("name: x\n<<<<<<<<\n", "4-over-4"),
        ];
        for (text, want) in cases {
            let e = Chart::parse(text, "t.chart").unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let c = Chart::parse("# top\nname: two\n k p # wale 0 is k\n p k\n", "c").unwrap();
        assert_eq!((c.at(0, 0), c.at(1, 0)), (Stitch::Purl, Stitch::Knit));
    }
}
