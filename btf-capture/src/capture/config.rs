//! Strict reading of the capture's TOML files (`capture.toml`, `truth.toml`): a parse or
//! schema error (a misspelt key or table, a missing one, a wrong type) becomes an
//! [`Error::Config`] naming the file, the line and the `[table] key` it happened in, and
//! every number read is range-checked by a [`Checker`], whose [`Error::ConfigValue`]
//! names the file, the key and the value
//! (`capture.toml: [plate] size_mm = -140: must be > 0`). Structs read this way carry `#[serde(deny_unknown_fields)]`, as the scene files
//! do, so that nothing in a file is silently ignored.

use crate::{Error, Result};
use serde::de::DeserializeOwned;

/// Parses `text` (the contents of `file`) strictly, mapping the TOML error to the key.
pub fn parse<T: DeserializeOwned>(file: &str, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| {
        let (key, line) = match e.span() {
            Some(span) => locate(text, span.start),
            None => ("document".to_string(), None),
        };
        let at = line.map(|l| format!(" (line {l})")).unwrap_or_default();
        Error::config(file, &key, format!("{}{at}", e.message().trim()))
    })
}

/// The `[table] key` (or `[table]`, or `key` at the top level) around byte `pos` of a
/// TOML text, and its 1-based line.
fn locate(text: &str, pos: usize) -> (String, Option<usize>) {
    let pos = pos.min(text.len());
    let before = text.get(..pos).unwrap_or("");
    let line_no = before.matches('\n').count() + 1;
    let line = text.lines().nth(line_no - 1).unwrap_or("").trim();
    if line.starts_with('[') {
        return (line.to_string(), Some(line_no));
    }
    let table = before
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.split('#').next().unwrap_or(l).trim().to_string());
    let key = line.split_once('=').map(|(k, _)| k.trim().to_string());
    let name = match (table, key) {
        (Some(t), Some(k)) => format!("{t} {k}"),
        (Some(t), None) => t,
        (None, Some(k)) => k,
        (None, None) => "document".to_string(),
    };
    (name, Some(line_no))
}

/// Range checks of the values of one file; every failure names the file and the key.
#[derive(Debug, Clone, Copy)]
pub struct Checker<'a> {
    /// The file's name as shown to the user.
    pub file: &'a str,
}

impl Checker<'_> {
    /// An [`Error::ConfigValue`] for `key` holding `value`.
    pub fn bad(&self, key: &str, value: impl std::fmt::Display, what: impl Into<String>) -> Error {
        Error::config_value(self.file, key, value, what)
    }

    /// An [`Error::Config`] for `key`.
    pub fn wrong(&self, key: &str, what: impl Into<String>) -> Error {
        Error::config(self.file, key, what)
    }

    /// `v` is finite.
    pub fn finite(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_finite() { Ok(v) } else { Err(self.bad(key, v, "must be a finite number")) }
    }

    /// `v` is finite, `> 0` and `≤ max`.
    pub fn positive(&self, key: &str, v: f64, max: f64) -> Result<f64> {
        self.finite(key, v)?;
        if v <= 0.0 {
            return Err(self.bad(key, v, "must be > 0"));
        }
        if v > max {
            return Err(self.bad(key, v, format!("must be ≤ {max}")));
        }
        Ok(v)
    }

    /// `v` is finite and in `[lo, hi]`.
    pub fn within(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
        self.finite(key, v)?;
        if !(lo..=hi).contains(&v) {
            return Err(self.bad(key, v, format!("must be in [{lo}, {hi}]")));
        }
        Ok(v)
    }

    /// Integer `v` is in `lo..=hi`.
    pub fn count(&self, key: &str, v: u64, lo: u64, hi: u64) -> Result<u64> {
        if !(lo..=hi).contains(&v) {
            return Err(self.bad(key, v, format!("must be in {lo}..={hi}")));
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Doc {
        a: f64,
        t: Inner,
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Inner {
        b: u32,
    }

    fn message(text: &str) -> String {
        parse::<Doc>("f.toml", text).unwrap_err().to_string()
    }

    #[test]
    fn parse_errors_name_the_file_table_key_and_line() {
        let e = message("a = 1.0\n[t]\nb = 1\nc = 2\n");
        assert!(e.starts_with("f.toml: [t] c: unknown field `c`"), "{e}");
        assert!(e.contains("(line 4)"), "{e}");
        let e = message("a = 1.0\n[t]\nb = 1\n[u]\nb = 1\n");
        assert!(e.starts_with("f.toml: [u]: unknown field `u`"), "{e}");
        let e = message("a = 1.0\n[t]\nb = -3\n");
        assert!(e.starts_with("f.toml: [t] b: "), "{e}");
        let e = message("a = 1.0\n");
        assert!(e.contains("missing field `t`"), "{e}");
    }

    #[test]
    fn checks_name_the_key_and_value() {
        let c = Checker { file: "capture.toml" };
        let e = c.positive("[plate] size_mm", -140.0, 1e4).unwrap_err().to_string();
        assert_eq!(e, "capture.toml: [plate] size_mm = -140: must be > 0");
        let e = c.positive("[plate] border_width_mm", f64::INFINITY, 1e4).unwrap_err();
        assert_eq!(
            e.to_string(),
            "capture.toml: [plate] border_width_mm = inf: must be a finite number"
        );
        let e = c.within("[camera] x", f64::NAN, 0.0, 1.0).unwrap_err().to_string();
        assert_eq!(e, "capture.toml: [camera] x = NaN: must be a finite number");
        assert_eq!(c.within("k", 0.5, 0.0, 1.0).unwrap(), 0.5);
        assert!(c.count("[camera] bits", 17, 1, 16).unwrap_err().to_string().contains("1..=16"));
    }
}
