//! The memory ceiling for buffers whose size a file claims: before a reader allocates
//! what a header or store metadata says it needs, the size is checked here against the
//! machine's physical memory, so an absurd but consistent claim ends in an error naming
//! the file and field instead of an aborting allocation. [`LazyRows`] holds an image a
//! decoder fills pixel by pixel with memory that follows the rows actually decoded, not the
//! size its header claims.

use crate::{Error, Result};

/// Physical memory in bytes (`MemTotal` of `/proc/meminfo`), `None` where unknown.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The largest single buffer a claimed size may ask for: the physical memory, or 64 GiB
/// where it cannot be read.
pub fn max_alloc_bytes() -> u64 {
    physical_memory().unwrap_or(64 << 30)
}

/// Refuses a buffer of `bytes` (`None`: the size computation overflowed) beyond
/// [`max_alloc_bytes`]; `what` names the file and the field that claim it.
pub fn check_alloc(bytes: Option<u64>, what: &str) -> Result<()> {
    let limit = max_alloc_bytes();
    match bytes {
        Some(b) if b <= limit => Ok(()),
        Some(b) => Err(Error::Limit(format!(
            "{what}: needs {b} bytes of memory, more than this machine's {limit}"
        ))),
        None => Err(Error::Limit(format!("{what}: the claimed size overflows"))),
    }
}

/// A `width × height` image that a decoder fills pixel by pixel (rows in any order, the
/// pixels of a row usually left to right), each row allocated when its first pixel
/// arrives: a file whose header claims a large image but holds little data costs little.
#[derive(Debug)]
pub struct LazyRows<T> {
    width: usize,
    height: usize,
    rows: std::collections::BTreeMap<usize, Vec<T>>,
    cur_y: usize,
    cur: Vec<T>,
}

impl<T: Copy + Default> LazyRows<T> {
    /// An empty image; nothing is allocated yet.
    pub fn new(width: usize, height: usize) -> Self {
        LazyRows { width, height, rows: Default::default(), cur_y: usize::MAX, cur: Vec::new() }
    }

    /// Sets pixel `(x, y)`; positions outside the image are ignored.
    pub fn set(&mut self, x: usize, y: usize, v: T) {
        if x >= self.width || y >= self.height {
            return;
        }
        if y != self.cur_y {
            if !self.cur.is_empty() {
                self.rows.insert(self.cur_y, std::mem::take(&mut self.cur));
            }
            self.cur = self.rows.remove(&y).unwrap_or_else(|| vec![T::default(); self.width]);
            self.cur_y = y;
        }
        self.cur[x] = v;
    }

    /// The row-major pixels, or the index of the first row that no pixel was set in.
    pub fn into_vec(mut self) -> std::result::Result<Vec<T>, usize> {
        if !self.cur.is_empty() {
            self.rows.insert(self.cur_y, std::mem::take(&mut self.cur));
        }
        if let Some(missing) = (0..self.height).find(|y| !self.rows.contains_key(y)) {
            return Err(missing);
        }
        let mut out = Vec::with_capacity(self.width * self.height);
        while let Some((_, row)) = self.rows.pop_first() {
            out.extend_from_slice(&row);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_sizes_are_refused_by_name() {
        assert!(check_alloc(Some(1 << 20), "a").is_ok());
        let e = check_alloc(Some(u64::MAX), "s.btf/zarr.json: btf.width").unwrap_err();
        assert!(matches!(e, Error::Limit(_)), "{e}");
        assert!(e.to_string().contains("btf.width"), "{e}");
        let e = check_alloc(None, "x.exr: dataWindow").unwrap_err().to_string();
        assert!(e.contains("dataWindow") && e.contains("overflows"), "{e}");
    }

    #[test]
    fn lazy_rows_fill_in_any_order_and_name_a_missing_row() {
        let mut r = LazyRows::<u8>::new(3, 2);
        for (x, y) in [(0, 1), (1, 1), (2, 1), (0, 0), (1, 0), (2, 0), (5, 9)] {
            r.set(x, y, (10 * y + x) as u8);
        }
        assert_eq!(r.into_vec().unwrap(), vec![0, 1, 2, 10, 11, 12]);
        // A header claiming 2^40 pixels with one row of data allocates one row.
        let mut r = LazyRows::<[f32; 3]>::new(4, 1 << 38);
        r.set(0, 7, [1.0; 3]);
        assert_eq!(r.into_vec().unwrap_err(), 0);
    }
}
