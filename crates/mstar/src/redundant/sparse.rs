//! The dependent rows of a sparse `B` by Gaussian elimination of its rows in
//! order: each row is reduced by the kept rows before it (each normalized
//! at a pivot column of its own), and what is left of it decides, as in the
//! dense Gram–Schmidt of `super::dependent_rows`: a remainder of at most
//! `1e-10` of the row's norm makes it dependent.
//!
//! The pivot of a kept row is, among its remaining entries of at least a
//! tenth of the largest (threshold pivoting, growth at most 10 a row), the
//! column that the fewest later rows hold: eliminating it touches the fewest
//! rows, which keeps the fill small (none beyond a joint's neighbours on a
//! chain or an N-four-bar). The fill is bounded: past the budget the
//! elimination stops and says so rather than guess.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use mstar_model::Pattern;

/// No kept row has its pivot in this column.
const NONE: u32 = u32::MAX;

/// The elimination stopped: its kept rows held more entries than the budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FillExceeded {
    /// The budget, entries.
    pub(crate) budget: usize,
}

/// A kept row, reduced and scaled to 1 at its pivot column.
struct KeptRow {
    cols: Vec<u32>,
    vals: Vec<f64>,
}

/// The rows of `B` (pattern `p`, `values`) in CSR form, duplicates kept
/// (the accumulator sums them).
fn csr(p: &Pattern, values: &[f64]) -> (Vec<usize>, Vec<(u32, f64)>) {
    let mut start = vec![0usize; p.nrows + 1];
    for &(r, _) in &p.entries {
        start[r + 1] += 1;
    }
    for r in 0..p.nrows {
        start[r + 1] += start[r];
    }
    let mut next = start.clone();
    let mut entries = vec![(0u32, 0.0); p.entries.len()];
    for (&(r, c), &v) in p.entries.iter().zip(values) {
        entries[next[r]] = (u32::try_from(c).unwrap_or(NONE), v);
        next[r] += 1;
    }
    (start, entries)
}

/// The elimination's state: the kept rows, the pivot row of each column,
/// how many rows not yet reduced hold each column, and a dense accumulator
/// with the list of its non-zero columns.
struct Elimination {
    kept: Vec<KeptRow>,
    pivot_row: Vec<u32>,
    later: Vec<u32>,
    work: Vec<f64>,
    marked: Vec<bool>,
    nz: Vec<u32>,
    stored: usize,
}

impl Elimination {
    fn new(ncols: usize, later: Vec<u32>) -> Self {
        Self {
            kept: Vec::new(),
            pivot_row: vec![NONE; ncols],
            later,
            work: vec![0.0; ncols],
            marked: vec![false; ncols],
            nz: Vec::new(),
            stored: 0,
        }
    }

    /// Adds `x` to column `c` of the accumulator, queueing the kept row
    /// whose pivot `c` is, the first time `c` is touched.
    fn add(&mut self, c: u32, x: f64, queue: &mut BinaryHeap<Reverse<u32>>) {
        let k = c as usize;
        if !self.marked[k] {
            self.marked[k] = true;
            self.nz.push(c);
            if self.pivot_row[k] != NONE {
                queue.push(Reverse(self.pivot_row[k]));
            }
        }
        self.work[k] += x;
    }

    /// Reduces the row `row` by the kept rows, oldest first (a kept row is
    /// zero at the pivots of those before it, so a cleared pivot stays
    /// clear); returns the row's norm.
    fn reduce(&mut self, row: &[(u32, f64)]) -> f64 {
        let mut queue = BinaryHeap::new();
        let mut norm2 = 0.0;
        for &(c, v) in row {
            self.add(c, v, &mut queue);
        }
        for &c in &self.nz {
            norm2 += self.work[c as usize] * self.work[c as usize];
        }
        while let Some(Reverse(k)) = queue.pop() {
            let kept = &self.kept[k as usize];
            let pivot = kept.cols[0] as usize;
            let f = self.work[pivot];
            if f == 0.0 {
                continue;
            }
            for j in 1..kept.cols.len() {
                let (c, v) = (self.kept[k as usize].cols[j], self.kept[k as usize].vals[j]);
                self.add(c, -f * v, &mut queue);
            }
            self.work[pivot] = 0.0;
        }
        norm2.sqrt()
    }

    /// Keeps the reduced row in the accumulator when what is left of it is
    /// above `1e-10 norm`; clears the accumulator either way. Whether it
    /// was kept.
    fn keep_or_drop(&mut self, norm: f64) -> bool {
        let free = |e: &Self, c: u32| e.pivot_row[c as usize] == NONE;
        let (mut rest2, mut largest) = (0.0f64, 0.0f64);
        for &c in &self.nz {
            if free(self, c) {
                let x = self.work[c as usize];
                rest2 += x * x;
                largest = largest.max(x.abs());
            }
        }
        let rest = rest2.sqrt();
        // Threshold pivoting: the column fewest later rows hold.
        let pivot = self
            .nz
            .iter()
            .copied()
            .filter(|&c| free(self, c) && self.work[c as usize].abs() >= 0.1 * largest)
            .min_by_key(|&c| (self.later[c as usize], c));
        let independent = !(rest.is_nan() || norm.is_nan() || norm == 0.0 || rest <= 1e-10 * norm);
        let keep = independent && pivot.is_some();
        if let (true, Some(pivot)) = (keep, pivot) {
            let p = self.work[pivot as usize];
            // Sized at once: growing 2·10⁵ short rows one push at a time
            // took a third of the elimination at 10⁵ bodies.
            let len = self.nz.len();
            let mut row = KeptRow {
                cols: Vec::with_capacity(len),
                vals: Vec::with_capacity(len),
            };
            row.cols.push(pivot);
            row.vals.push(1.0);
            for &c in &self.nz {
                let x = self.work[c as usize];
                if c != pivot && free(self, c) && x != 0.0 {
                    row.cols.push(c);
                    row.vals.push(x / p);
                }
            }
            self.stored += row.cols.len();
            self.pivot_row[pivot as usize] = u32::try_from(self.kept.len()).unwrap_or(NONE);
            self.kept.push(row);
        }
        for &c in &self.nz {
            self.work[c as usize] = 0.0;
            self.marked[c as usize] = false;
        }
        self.nz.clear();
        keep
    }
}

/// The rows of `B` kept (each independent of the kept rows before it) and
/// the rows that depend on the rows before them, in order, as
/// `super::dependent_rows` finds them, with at most `budget` entries in
/// the kept rows.
///
/// # Errors
/// [`FillExceeded`] when the kept rows need more entries than `budget`.
pub(crate) fn dependent_rows(
    p: &Pattern,
    values: &[f64],
    budget: usize,
) -> Result<(Vec<usize>, Vec<usize>), FillExceeded> {
    let (start, entries) = csr(p, values);
    let mut later = vec![0u32; p.ncols];
    for &(_, c) in &p.entries {
        later[c] += 1;
    }
    let mut e = Elimination::new(p.ncols, later);
    let (mut kept, mut dependent) = (Vec::new(), Vec::new());
    for r in 0..p.nrows {
        let row = &entries[start[r]..start[r + 1]];
        for &(c, _) in row {
            e.later[c as usize] -= 1;
        }
        let norm = e.reduce(row);
        if e.keep_or_drop(norm) {
            kept.push(r);
        } else {
            dependent.push(r);
        }
        if e.stored > budget {
            return Err(FillExceeded { budget });
        }
    }
    Ok((kept, dependent))
}
