//! Schur complement on the primal block, for KKT matrices `[[S, Bᵀ], [B, D]]`
//! whose `S` is block-diagonal with small blocks.
//!
//! Rigid bodies and point masses that interact only through constraints give
//! exactly that: `S_T = c_a M + c_u K_T + c_v C_T` couples the coordinates of
//! one body (its mass, the constraint Hessian on its own angle, its own force
//! Jacobians), and every coupling between bodies lives in `B`. Then
//!
//! ```text
//! C y = B S⁻¹ f − g,   C = B S⁻¹ Bᵀ − D,   x = S⁻¹ (f − Bᵀ y)
//! ```
//!
//! solves `[[S, Bᵀ], [B, D]] [x; y] = [f; g]` with one dense inverse per block
//! (a 3 × 3 one per planar body) and one sparse LDLᵀ of the `m × m` matrix `C`,
//! whose pattern is that of `B Bᵀ`: block-tridiagonal for a chain, so its
//! factorization costs O(m). `C` is symmetric positive definite when `S` is and
//! `B` has full row rank; a block without an inverse, or a pivot of `C` at the
//! rounding level (a redundant constraint), is an error naming the unknown.
//!
//! The blocks are the connected components of the pattern of `S` (entries
//! `(i, j)` with `i, j < n_primal`); a component larger than
//! [`MAX_BLOCK`] unknowns makes the analysis fail (use LDLᵀ then).

use crate::sparse_ldlt::SparseLdlt;
use crate::{Csc, KktError};

/// The largest diagonal block of `S` that the Schur backend inverts densely.
pub const MAX_BLOCK: usize = 12;

/// One diagonal block of `S`.
#[derive(Clone, Debug)]
struct Block {
    /// The block's unknowns, ascending (global indices `< n_primal`).
    coords: std::ops::Range<usize>,
    /// Its entries of `S`: `(position in the KKT values, local i, local j)`.
    s_entries: std::ops::Range<usize>,
    /// Its entries of `B`: `(position in the KKT values, local row, local j)`.
    b_entries: std::ops::Range<usize>,
    /// The constraint rows touching it, ascending (indices into `rows`).
    rows: std::ops::Range<usize>,
    /// Offset of its inverse (`k × k`, row-major) in `inverse`.
    inverse: usize,
    /// Offset of its `|rows|²` slots of `C` in `c_slots`.
    c_slots: usize,
}

/// The block structure while it is being built.
struct Parts {
    blocks: Vec<Block>,
    coords: Vec<usize>,
    s_entries: Vec<(usize, usize, usize)>,
    b_entries: Vec<(usize, usize, usize)>,
    rows: Vec<usize>,
    c_slots: Vec<usize>,
}

/// The analysed structure and reused buffers of the Schur backend.
pub(crate) struct Schur {
    n_primal: usize,
    m: usize,
    blocks: Vec<Block>,
    /// Unknowns of all blocks, block after block.
    coords: Vec<usize>,
    /// `(KKT value position, local i, local j)` of every block's `S` entries.
    s_entries: Vec<(usize, usize, usize)>,
    /// `(KKT value position, local row, local column)` of every block's `B`.
    b_entries: Vec<(usize, usize, usize)>,
    /// Position in `c.values` of `C[r, s]` for every block's row pairs.
    c_slots: Vec<usize>,
    /// Position in the KKT values of each entry of `D` and its slot in `C`.
    d_entries: Vec<(usize, usize)>,
    /// Dense inverses of the blocks.
    inverse: Vec<f64>,
    /// Whether every block is the unknown `i` alone, in order (`S` diagonal):
    /// `inverse[i]` is then `1 / S_ii`.
    diagonal: bool,
    /// `C` (both triangles).
    c: Csc,
    ldlt: SparseLdlt,
    /// Scratch: a block (row-major) and `B_K S_K⁻¹`.
    block: Vec<f64>,
    w: Vec<f64>,
    /// Scratch of length `n_primal`.
    x: Vec<f64>,
    /// The `B` entries of the KKT matrix by primal column: `(row − n, position)`.
    b_col_ptr: Vec<usize>,
    b_cols: Vec<(usize, usize)>,
    /// The values of the last factored KKT matrix's `B` entries, by column.
    b_values: Vec<f64>,
}

impl Schur {
    /// Analyses `a` (values ignored) whose first `n_primal` unknowns are primal.
    ///
    /// # Errors
    /// [`KktError::Structure`] when a diagonal block of `S` has more than
    /// [`MAX_BLOCK`] unknowns or the structure is not symmetric.
    pub(crate) fn new(a: &Csc, n_primal: usize) -> Result<Self, KktError> {
        let n = n_primal;
        let m = a.n - n;
        // Connected components of S's pattern (union–find).
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for j in 0..n {
            for &i in &a.row_idx[a.col_ptr[j]..a.col_ptr[j + 1]] {
                if i < n {
                    let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                    if ri != rj {
                        parent[ri.max(rj)] = ri.min(rj);
                    }
                }
            }
        }
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); n];
        for i in 0..n {
            let r = find(&mut parent, i);
            members[r].push(i);
        }
        let mut local = vec![0usize; n];
        let mut row_local = vec![usize::MAX; m];
        let mut this = Parts {
            blocks: Vec::new(),
            coords: Vec::with_capacity(n),
            s_entries: Vec::new(),
            b_entries: Vec::new(),
            rows: Vec::new(),
            c_slots: Vec::new(),
        };
        let mut c_pairs: Vec<(usize, usize)> = Vec::new();
        let (mut inv_len, mut max_k, mut max_rows) = (0, 0, 0);
        for group in members.iter().filter(|g| !g.is_empty()) {
            let k = group.len();
            if k > MAX_BLOCK {
                return Err(KktError::Structure(format!(
                    "the Schur backend needs a block-diagonal S with blocks of at most {MAX_BLOCK} unknowns; unknowns {}, {}, … form a block of {k}",
                    group[0], group[1]
                )));
            }
            let c0 = this.coords.len();
            for (l, &i) in group.iter().enumerate() {
                local[i] = l;
            }
            this.coords.extend_from_slice(group);
            let (s0, b0, r0) = (this.s_entries.len(), this.b_entries.len(), this.rows.len());
            for &j in group {
                for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                    let i = a.row_idx[p];
                    if i < n {
                        this.s_entries.push((p, local[i], local[j]));
                    } else if row_local[i - n] == usize::MAX {
                        row_local[i - n] = this.rows.len() - r0;
                        this.rows.push(i - n);
                    }
                }
            }
            // Rows ascending (for a reproducible pattern), then local indices.
            this.rows[r0..].sort_unstable();
            for (l, &r) in this.rows[r0..].iter().enumerate() {
                row_local[r] = l;
            }
            for &j in group {
                for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                    let i = a.row_idx[p];
                    if i >= n {
                        this.b_entries.push((p, row_local[i - n], local[j]));
                    }
                }
            }
            let rows = &this.rows[r0..];
            for &r in rows {
                for &s in rows {
                    c_pairs.push((r, s));
                }
            }
            for &r in rows {
                row_local[r] = usize::MAX;
            }
            this.blocks.push(Block {
                coords: c0..this.coords.len(),
                s_entries: s0..this.s_entries.len(),
                b_entries: b0..this.b_entries.len(),
                rows: r0..this.rows.len(),
                inverse: inv_len,
                c_slots: 0,
            });
            inv_len += k * k;
            max_k = max_k.max(k);
            max_rows = max_rows.max(rows.len());
        }
        // D: the multiplier block of the KKT matrix.
        let mut d_pos = Vec::new();
        for j in n..a.n {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i >= n {
                    d_pos.push((p, i - n, j - n));
                    c_pairs.push((i - n, j - n));
                }
            }
        }
        // Every multiplier keeps a diagonal entry (an unconstrained row would
        // otherwise have an empty column in C: reported by the pivot check).
        c_pairs.extend((0..m).map(|r| (r, r)));
        // C's pattern: (row, column) pairs, sorted by column then row, unique.
        let mut sorted: Vec<(usize, usize)> = c_pairs.iter().map(|&(r, s)| (s, r)).collect();
        sorted.sort_unstable();
        sorted.dedup();
        let mut c = Csc {
            n: m,
            col_ptr: vec![0; m + 1],
            row_idx: Vec::with_capacity(sorted.len()),
            values: vec![0.0; sorted.len()],
        };
        for &(col, row) in &sorted {
            c.col_ptr[col + 1] += 1;
            c.row_idx.push(row);
        }
        for j in 0..m {
            c.col_ptr[j + 1] += c.col_ptr[j];
        }
        let slot = |r: usize, s: usize| -> usize {
            let col = &c.row_idx[c.col_ptr[s]..c.col_ptr[s + 1]];
            c.col_ptr[s] + col.binary_search(&r).unwrap_or(0)
        };
        for b in &mut this.blocks {
            b.c_slots = this.c_slots.len();
            let rows = &this.rows[b.rows.clone()];
            for &r in rows {
                for &s in rows {
                    this.c_slots.push(slot(r, s));
                }
            }
        }
        let d_entries = d_pos.iter().map(|&(p, r, s)| (p, slot(r, s))).collect();
        // B by primal column, for the products in the solve.
        let (mut b_col_ptr, mut b_cols) = (vec![0; n + 1], Vec::new());
        for j in 0..n {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i >= n {
                    b_cols.push((i - n, p));
                }
            }
            b_col_ptr[j + 1] = b_cols.len();
        }
        let ldlt = SparseLdlt::new(&c, m)?;
        let diagonal = this.coords.iter().enumerate().all(|(i, &c)| i == c)
            && this.blocks.iter().all(|b| b.coords.len() == 1);
        Ok(Self {
            diagonal,
            n_primal: n,
            m,
            blocks: this.blocks,
            coords: this.coords,
            s_entries: this.s_entries,
            b_entries: this.b_entries,
            c_slots: this.c_slots,
            d_entries,
            inverse: vec![0.0; inv_len],
            c,
            ldlt,
            block: vec![0.0; max_k * max_k],
            w: vec![0.0; max_rows * max_k],
            x: vec![0.0; n],
            b_values: vec![0.0; b_cols.len()],
            b_col_ptr,
            b_cols,
        })
    }

    /// Inverts every block of `S`, forms `C = B S⁻¹ Bᵀ − D` and factors it.
    ///
    /// # Errors
    /// [`KktError::Singular`] naming the primal unknown without a pivot in its
    /// block, or the multiplier whose pivot in `C` vanishes.
    pub(crate) fn factor(&mut self, a: &Csc) -> Result<(), KktError> {
        let values = &a.values;
        self.c.values.fill(0.0);
        for b in &self.blocks {
            let k = b.coords.len();
            if k == 1 {
                // One unknown (a diagonal S): C += b_r b_s / s.
                let s: f64 = self.s_entries[b.s_entries.clone()]
                    .iter()
                    .map(|&(p, _, _)| values[p])
                    .sum();
                if s == 0.0 {
                    return Err(KktError::Singular {
                        unknown: Some(self.coords[b.coords.start]),
                    });
                }
                let inv = 1.0 / s;
                self.inverse[b.inverse] = inv;
                let entries = &self.b_entries[b.b_entries.clone()];
                let nr = entries.len();
                let slots = &self.c_slots[b.c_slots..b.c_slots + nr * nr];
                // With k = 1 every row appears once, in ascending order.
                for (r, &(pr, _, _)) in entries.iter().enumerate() {
                    let w = values[pr] * inv;
                    for (s, &(ps, _, _)) in entries.iter().enumerate() {
                        self.c.values[slots[r * nr + s]] += w * values[ps];
                    }
                }
                continue;
            }
            let blk = &mut self.block[..k * k];
            blk.fill(0.0);
            for &(p, i, j) in &self.s_entries[b.s_entries.clone()] {
                blk[i * k + j] += values[p];
            }
            let inv = &mut self.inverse[b.inverse..b.inverse + k * k];
            invert(blk, inv, k).map_err(|l| KktError::Singular {
                unknown: Some(self.coords[b.coords.start + l]),
            })?;
            // W = B_K S_K⁻¹ (rows × k), then C_K = W B_Kᵀ.
            let nr = b.rows.len();
            let w = &mut self.w[..nr * k];
            w.fill(0.0);
            for &(p, r, j) in &self.b_entries[b.b_entries.clone()] {
                let bv = values[p];
                for l in 0..k {
                    w[r * k + l] += bv * inv[j * k + l];
                }
            }
            let slots = &self.c_slots[b.c_slots..b.c_slots + nr * nr];
            for &(p, s, j) in &self.b_entries[b.b_entries.clone()] {
                let bv = values[p];
                for r in 0..nr {
                    self.c.values[slots[r * nr + s]] += w[r * k + j] * bv;
                }
            }
        }
        for &(p, slot) in &self.d_entries {
            self.c.values[slot] -= values[p];
        }
        for (v, &(_, p)) in self.b_values.iter_mut().zip(&self.b_cols) {
            *v = values[p];
        }
        self.ldlt.factor(&self.c).map_err(|e| match e {
            KktError::Singular { unknown } => KktError::Singular {
                unknown: unknown.map(|r| self.n_primal + r),
            },
            e => e,
        })
    }

    /// Solves in place with the last factorization.
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = self.n_primal;
        let (f, g) = rhs.split_at_mut(n);
        // x = S⁻¹ f.
        self.apply_inverse(f);
        // C y = B S⁻¹ f − g.
        for v in g.iter_mut() {
            *v = -*v;
        }
        for j in 0..n {
            let xj = self.x[j];
            for q in self.b_col_ptr[j]..self.b_col_ptr[j + 1] {
                g[self.b_cols[q].0] += self.b_values[q] * xj;
            }
        }
        debug_assert_eq!(g.len(), self.m);
        self.ldlt.solve_in_place(g);
        // x = S⁻¹ (f − Bᵀ y).
        for (j, fj) in f.iter_mut().enumerate() {
            let mut s = *fj;
            for q in self.b_col_ptr[j]..self.b_col_ptr[j + 1] {
                s -= self.b_values[q] * g[self.b_cols[q].0];
            }
            *fj = s;
        }
        self.apply_inverse(f);
        f.copy_from_slice(&self.x);
    }

    /// `self.x = S⁻¹ f` block by block.
    fn apply_inverse(&mut self, f: &[f64]) {
        if self.diagonal {
            for ((x, &fi), &d) in self.x.iter_mut().zip(f).zip(&self.inverse) {
                *x = d * fi;
            }
            return;
        }
        for b in &self.blocks {
            let coords = &self.coords[b.coords.clone()];
            let k = coords.len();
            let inv = &self.inverse[b.inverse..b.inverse + k * k];
            for (i, &ci) in coords.iter().enumerate() {
                let row = &inv[i * k..(i + 1) * k];
                self.x[ci] = row.iter().zip(coords).map(|(a, &cj)| a * f[cj]).sum();
            }
        }
    }
}

/// Inverts the row-major `k × k` matrix `a` (destroyed) into `inv` by
/// Gauss–Jordan elimination with partial pivoting. A pivot at most `k ε` times
/// the largest entry of its column is taken for zero: `Err(local column)`.
fn invert(a: &mut [f64], inv: &mut [f64], k: usize) -> Result<(), usize> {
    inv.fill(0.0);
    for i in 0..k {
        inv[i * k + i] = 1.0;
    }
    let eps = (k as f64) * f64::EPSILON;
    for col in 0..k {
        let scale = (0..k).fold(0.0f64, |s, i| s.max(a[i * k + col].abs()));
        let (mut p, mut best) = (col, a[col * k + col].abs());
        for i in col + 1..k {
            let v = a[i * k + col].abs();
            if v > best {
                (p, best) = (i, v);
            }
        }
        if best <= eps * scale || best == 0.0 {
            return Err(col);
        }
        if p != col {
            for j in 0..k {
                a.swap(p * k + j, col * k + j);
                inv.swap(p * k + j, col * k + j);
            }
        }
        let d = 1.0 / a[col * k + col];
        for j in 0..k {
            a[col * k + j] *= d;
            inv[col * k + j] *= d;
        }
        for i in 0..k {
            if i != col {
                let f = a[i * k + col];
                if f != 0.0 {
                    for j in 0..k {
                        a[i * k + j] -= f * a[col * k + j];
                        inv[i * k + j] -= f * inv[col * k + j];
                    }
                }
            }
        }
    }
    Ok(())
}
