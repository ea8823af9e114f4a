//! A uniform spatial hash grid (knit design §1.3 item 16): boxes are registered in every
//! cell they overlap, cells hashed into a fixed table and stored as one sorted array
//! (counting sort, so the build is deterministic and allocation-light); a query returns the
//! items of the cell holding a point. It replaces Chen's O(n²) all-pairs collision test.

use crate::vec3::V3;

/// Items bucketed by cell.
#[derive(Debug, Clone, Default)]
pub struct HashGrid {
    cell: f64,
    starts: Vec<u32>,
    items: Vec<u32>,
}

fn hash(c: [i64; 3], table: usize) -> usize {
    let h = (c[0].wrapping_mul(73_856_093))
        ^ (c[1].wrapping_mul(19_349_663))
        ^ (c[2].wrapping_mul(83_492_791));
    (h.rem_euclid(table as i64)) as usize
}

impl HashGrid {
    /// Cell coordinates of `p`.
    fn cell_of(&self, p: V3) -> [i64; 3] {
        [0, 1, 2].map(|k| (p[k] / self.cell).floor() as i64)
    }

    /// Registers item `i` in every cell that its box `boxes[i] = (lo, hi)` overlaps.
    pub fn build(boxes: &[(V3, V3)], cell: f64) -> HashGrid {
        let table = (2 * boxes.len()).next_power_of_two().max(64);
        let mut g = HashGrid { cell, starts: vec![0; table + 1], items: Vec::new() };
        let cells = |b: &(V3, V3)| {
            let lo = g.cell_of(b.0);
            let hi = g.cell_of(b.1);
            let mut out = Vec::new();
            for i in lo[0]..=hi[0] {
                for j in lo[1]..=hi[1] {
                    for k in lo[2]..=hi[2] {
                        out.push(hash([i, j, k], table));
                    }
                }
            }
            out.sort_unstable();
            out.dedup();
            out
        };
        let per_item: Vec<Vec<usize>> = boxes.iter().map(cells).collect();
        let mut counts = vec![0u32; table + 1];
        for cs in &per_item {
            for &c in cs {
                counts[c + 1] += 1;
            }
        }
        for i in 0..table {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        g.items = vec![0; counts[table] as usize];
        for (item, cs) in per_item.iter().enumerate() {
            for &c in cs {
                g.items[fill[c] as usize] = item as u32;
                fill[c] += 1;
            }
        }
        g.starts = counts;
        g
    }

    /// Items registered in the cell holding `p` (may include items of other cells that
    /// share its hash; callers test the candidates exactly).
    pub fn query(&self, p: V3) -> &[u32] {
        &self.items[self.query_range(p)]
    }

    /// Where [`HashGrid::query`]'s items lie in [`HashGrid::items`] (for callers that keep
    /// per-entry data alongside, read in order).
    pub fn query_range(&self, p: V3) -> std::ops::Range<usize> {
        if self.items.is_empty() {
            return 0..0;
        }
        let table = self.starts.len() - 1;
        let c = hash(self.cell_of(p), table);
        self.starts[c] as usize..self.starts[c + 1] as usize
    }

    /// Every registration, bucket after bucket.
    pub fn items(&self) -> &[u32] {
        &self.items
    }
}
