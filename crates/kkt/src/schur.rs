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
//! (for planar bars `S` is diagonal) and one LDLᵀ of the `m × m` matrix `C`,
//! whose pattern is that of `B Bᵀ`: block-tridiagonal for a chain, so its
//! factorization costs O(m). `C` is factored by its envelope
//! (`crate::envelope`) in the constraints' own order when that is at most
//! `FILL_SLACK` times the factor AMD gives, else by faer's sparse LDLᵀ after
//! AMD on the triangle faer reads. `C` is symmetric positive definite when `S` is and
//! `B` has full row rank; a block without an inverse, or a pivot of `C` at the
//! rounding level (a redundant constraint), is an error naming the unknown.
//!
//! The blocks are the connected components of the pattern of `S` (entries
//! `(i, j)` with `i, j < n_primal`); a component larger than
//! [`MAX_BLOCK`] unknowns makes the analysis fail (use LDLᵀ then). The
//! backend reads `S`, `B` and `D` only (the matrix is symmetric), keeps
//! compact copies of them, and computes its own products and norm for the
//! residual check of `KktSolver`.
//!
//! A chain (`S` diagonal, `C` by its envelope in the constraints' own order)
//! takes leaner paths: the factorization is one pass over the columns whose
//! slots in `C` come from the envelope's row pointers (no table of pairs), and
//! the residual check is formed inside the solve ([`Schur::solve_checked`]).

use crate::envelope::EnvelopeLdlt;
use crate::sparse_ldlt::{SparseLdlt, kkt_ordering};
use crate::{Csc, KktError, max_abs};

/// The largest diagonal block of `S` that the Schur backend inverts densely.
pub const MAX_BLOCK: usize = 12;

/// How much larger (in stored values) the factor of `C` in the constraints'
/// own order may be than with AMD and still be preferred for its locality.
const FILL_SLACK: f64 = 1.25;

/// One diagonal block of `S`.
#[derive(Clone, Debug)]
struct Block {
    /// The block's unknowns, ascending (global indices `< n_primal`).
    coords: std::ops::Range<usize>,
    /// Its entries of `S`: `(position in the KKT values, local i, local j)`.
    s_entries: std::ops::Range<usize>,
    /// Its entries of `B`: `(position in the KKT values, local row, local j)`.
    b_entries: std::ops::Range<usize>,
    /// Its rows in `Parts::rows` (original constraint indices).
    rows: std::ops::Range<usize>,
    /// Number of constraint rows touching it.
    n_rows: usize,
    /// Offset of its inverse (`k × k`, row-major) in `inverse`.
    inverse: usize,
    /// Its contributions to `C`: `(local row, local row, slot in C)`.
    pairs: std::ops::Range<usize>,
}

/// The block structure while it is being built.
struct Parts {
    blocks: Vec<Block>,
    coords: Vec<usize>,
    s_entries: Vec<(usize, usize, usize)>,
    b_entries: Vec<(usize, usize, usize)>,
    /// Each block's rows (original constraint indices), block after block.
    rows: Vec<usize>,
}

/// The analysed structure and reused buffers of the Schur backend.
pub(crate) struct Schur {
    n_primal: usize,
    blocks: Vec<Block>,
    /// Unknowns of all blocks, block after block.
    coords: Vec<usize>,
    /// `(KKT value position, local i, local j)` of every block's `S` entries.
    s_entries: Vec<(usize, usize, usize)>,
    /// `(KKT value position, local row, local column)` of every block's `B`.
    b_entries: Vec<(usize, usize, usize)>,
    /// `(local row r, local row s, position of C[r, s] in c.values)` for the
    /// pairs in the triangle the factorization reads (empty when `banded`:
    /// the envelope gives the positions).
    pairs: Vec<(u16, u16, u32)>,
    /// Index in `d_all` of each entry of `D` in the read triangle, and its
    /// slot in `C`.
    d_entries: Vec<(usize, usize)>,
    /// Every entry of `D`: `(KKT value position, row, column)` (multiplier
    /// indices), for products with the whole matrix.
    d_all: Vec<(usize, usize, usize)>,
    /// The values of `S` (parallel to `s_entries`) and `D` (to `d_all`) of the
    /// last factorization: with `b_values` the whole matrix, compactly.
    s_values: Vec<f64>,
    d_values: Vec<f64>,
    /// Dense inverses of the blocks.
    inverse: Vec<f64>,
    /// Whether every block is the unknown `i` alone, in order (`S` diagonal):
    /// `inverse[i]` is then `1 / S_ii`.
    diagonal: bool,
    /// For a diagonal `S`, compactly: the position of `S_jj` in the KKT values
    /// and the range of column `j`'s pairs (`pair_ptr[j]..pair_ptr[j + 1]`).
    diag_s: Vec<usize>,
    pair_ptr: Vec<usize>,
    /// `C` and its factorization, in `C`'s elimination order.
    cf: CFactor,
    /// `c_inv[r]` = position of constraint `r` in `C`'s order; `c_fwd` the
    /// inverse.
    c_inv: Vec<usize>,
    c_fwd: Vec<usize>,
    /// Scratch: a block (row-major), `B_K` (rows × k) and `B_K S_K⁻¹`.
    block: Vec<f64>,
    bk: Vec<f64>,
    w: Vec<f64>,
    /// Scratch of length `n_primal` and `m` (in `C`'s order).
    x: Vec<f64>,
    y: Vec<f64>,
    /// The `B` entries of the KKT matrix by primal column (column `j`'s are
    /// `b_col_ptr[j]..b_col_ptr[j + 1]`): the position of the row in C's
    /// order, and the position in the KKT values. Apart and on 32 bits: the
    /// solve reads the rows only, and at 10⁵ bodies it streams them from memory.
    b_col_ptr: Vec<u32>,
    b_rows: Vec<u32>,
    b_pos: Vec<u32>,
    /// Whether `C`'s order is the constraints' own (`c_fwd` the identity).
    natural: bool,
    /// Absolute row sums of the last factored matrix (`n + m`).
    row_sums: Vec<f64>,
    /// The values of the last factored KKT matrix's `B` entries, by column.
    b_values: Vec<f64>,
    /// `S` diagonal and `C` factored by its envelope in the constraints' own
    /// order (a chain): [`factor`](Schur::factor) takes its one-pass path.
    banded: bool,
    /// `‖A‖∞` of the last factorization when its one-pass path formed it.
    norm: Option<f64>,
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
        };
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
                        row_local[i - n] = 0;
                        this.rows.push(i - n);
                    }
                }
            }
            // Rows ascending, then local indices: for one unknown, the order
            // of its column's B entries.
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
            let n_rows = this.rows.len() - r0;
            for &r in &this.rows[r0..] {
                row_local[r] = usize::MAX;
            }
            this.blocks.push(Block {
                coords: c0..this.coords.len(),
                s_entries: s0..this.s_entries.len(),
                b_entries: b0..this.b_entries.len(),
                rows: r0..this.rows.len(),
                n_rows,
                inverse: inv_len,
                pairs: 0..0,
            });
            inv_len += k * k;
            max_k = max_k.max(k);
            max_rows = max_rows.max(n_rows);
        }
        if max_rows > usize::from(u16::MAX) {
            return Err(KktError::Structure(format!(
                "a block of S touches {max_rows} constraint rows; the Schur backend takes at most {}",
                u16::MAX
            )));
        }
        // C's pattern (original constraint order): every block's row pairs,
        // D's entries, and the diagonal.
        let mut d_pos = Vec::new();
        for j in n..a.n {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                if a.row_idx[p] >= n {
                    d_pos.push((p, a.row_idx[p] - n, j - n));
                }
            }
        }
        let mut pattern: Vec<(usize, usize)> = Vec::new();
        for b in &this.blocks {
            let rows = &this.rows[b.rows.clone()];
            for &r in rows {
                for &s in rows {
                    pattern.push((s, r));
                }
            }
        }
        pattern.extend(d_pos.iter().map(|&(_, r, s)| (s, r)));
        pattern.extend((0..m).map(|r| (r, r)));
        let c_orig = csc_of(m, &mut pattern);
        // (csc_of sorted and deduplicated `pattern`: it is C's entry list.)
        // How C is factored: in the constraints' own order by its envelope
        // when that is at most FILL_SLACK times the factor AMD gives (a
        // chain's joints in order: a band of width 3, factored and solved in
        // sequential passes), else by faer's sparse LDLᵀ after AMD, on the
        // one triangle it reads (faer then factors it in place).
        let first: Vec<usize> = (0..m)
            .map(|i| c_orig.row_idx[c_orig.col_ptr[i]..c_orig.col_ptr[i + 1]][0].min(i))
            .collect();
        // (None: too large for its 32-bit row pointers.)
        let envelope = EnvelopeLdlt::new(&first);
        let (c_fwd, c_inv) = kkt_ordering(&c_orig, m, Default::default())?;
        let mut permuted: Vec<(usize, usize)> =
            pattern.iter().map(|&(s, r)| (c_inv[s], c_inv[r])).collect();
        let c_amd = csc_of(m, &mut permuted);
        let amd = SparseLdlt::preordered(&c_amd)?;
        let narrow = envelope.filter(|e| e.len() as f64 <= FILL_SLACK * amd.factor_len() as f64);
        let (c_fwd, c_inv, cf) = if let Some(envelope) = narrow {
            let identity: Vec<usize> = (0..m).collect();
            (identity.clone(), identity, CFactor::Envelope(envelope))
        } else {
            let upper = amd.reads_upper();
            let mut triangle: Vec<(usize, usize)> = (0..m)
                .flat_map(|s| {
                    c_amd.row_idx[c_amd.col_ptr[s]..c_amd.col_ptr[s + 1]]
                        .iter()
                        .map(move |&r| (s, r))
                })
                .filter(|&(s, r)| if upper { r <= s } else { r >= s })
                .collect();
            let c_tri = csc_of(m, &mut triangle);
            let cf = match SparseLdlt::preordered_triangle(&c_tri, upper)? {
                Some(ldlt) => CFactor::Sparse {
                    c: c_tri,
                    ldlt: Box::new(ldlt),
                },
                None => CFactor::Sparse {
                    c: c_amd,
                    ldlt: Box::new(amd),
                },
            };
            (c_fwd, c_inv, cf)
        };
        let read = |r: usize, s: usize| cf.reads(r, s);
        let slot = |cf: &CFactor, r: usize, s: usize| cf.slot(r, s);
        let c = &cf;
        let mut pairs = Vec::new();
        let mut blocks = this.blocks;
        for b in &mut blocks {
            let start = pairs.len();
            let rows = &this.rows[b.rows.clone()];
            for (lr, &r) in rows.iter().enumerate() {
                for (ls, &s) in rows.iter().enumerate() {
                    let (pr, ps) = (c_inv[r], c_inv[s]);
                    if read(pr, ps) {
                        let at = u32::try_from(slot(c, pr, ps)).map_err(|_| {
                            KktError::Structure("C has more than 2³² entries".to_string())
                        })?;
                        // Lossless: both below max_rows ≤ u16::MAX.
                        pairs.push((lr as u16, ls as u16, at));
                    }
                }
            }
            b.pairs = start..pairs.len();
        }
        let d_entries = d_pos
            .iter()
            .enumerate()
            .filter(|&(_, &(_, r, s))| read(c_inv[r], c_inv[s]))
            .map(|(k, &(_, r, s))| (k, slot(c, c_inv[r], c_inv[s])))
            .collect();
        // B by primal column, rows in C's order, for the products in the solve.
        let fits = |x: usize| {
            u32::try_from(x).map_err(|_| {
                KktError::Structure(
                    "the Schur backend indexes the KKT entries with 32 bits".to_string(),
                )
            })
        };
        let (mut b_col_ptr, mut b_rows, mut b_pos) = (vec![0; n + 1], Vec::new(), Vec::new());
        for j in 0..n {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i >= n {
                    b_rows.push(fits(c_inv[i - n])?);
                    b_pos.push(fits(p)?);
                }
            }
            b_col_ptr[j + 1] = fits(b_rows.len())?;
        }
        let diagonal = this.coords.iter().enumerate().all(|(i, &c)| i == c)
            && blocks.iter().all(|b| b.coords.len() == 1);
        let (diag_s, pair_ptr) = if diagonal {
            (
                blocks
                    .iter()
                    .map(|b| this.s_entries[b.s_entries.start].0)
                    .collect(),
                std::iter::once(0)
                    .chain(blocks.iter().map(|b| b.pairs.end))
                    .collect(),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let n_s_entries = this.s_entries.len();
        let natural = c_fwd.iter().enumerate().all(|(k, &r)| k == r);
        let banded = diagonal && natural && matches!(cf, CFactor::Envelope(_));
        // The one-pass factorization computes C's slots from the envelope:
        // no table of pairs (8 bytes a pair, about 20 pairs a bar).
        let (pairs, pair_ptr) = if banded {
            (Vec::new(), Vec::new())
        } else {
            (pairs, pair_ptr)
        };
        Ok(Self {
            banded,
            norm: None,
            n_primal: n,
            diagonal,
            diag_s,
            pair_ptr,
            blocks,
            coords: this.coords,
            s_entries: this.s_entries,
            b_entries: this.b_entries,
            pairs,
            d_entries,
            s_values: vec![0.0; n_s_entries],
            d_values: vec![0.0; d_pos.len()],
            d_all: d_pos,
            inverse: vec![0.0; inv_len],
            cf,
            c_inv,
            c_fwd,
            block: vec![0.0; max_k * max_k],
            bk: vec![0.0; max_rows * max_k],
            w: vec![0.0; max_rows * max_k],
            x: vec![0.0; n],
            y: vec![0.0; m],
            b_values: vec![0.0; b_rows.len()],
            natural,
            row_sums: vec![0.0; a.n],
            b_col_ptr,
            b_rows,
            b_pos,
        })
    }

    /// Whether `C` is factored by its envelope (else by faer after AMD).
    #[cfg(test)]
    pub(crate) fn uses_envelope(&self) -> bool {
        matches!(self.cf, CFactor::Envelope(_))
    }

    /// Whether the last factorization took the one-pass path.
    #[cfg(test)]
    pub(crate) fn is_banded(&self) -> bool {
        self.banded
    }

    /// Spoils the last factorization (scales the inverse of `S_jj`), so that
    /// tests can see the residual check fail.
    #[cfg(test)]
    pub(crate) fn spoil(&mut self, j: usize, factor: f64) {
        self.inverse[j] *= factor;
    }

    /// Inverts every block of `S`, forms `C = B S⁻¹ Bᵀ − D` and factors it.
    ///
    /// # Errors
    /// [`KktError::Singular`] naming the primal unknown without a pivot in its
    /// block, or the multiplier whose pivot in `C` vanishes.
    pub(crate) fn factor(&mut self, values: &[f64]) -> Result<(), KktError> {
        self.cf.values_mut().fill(0.0);
        self.norm = None;
        if self.banded {
            return self.factor_banded(values);
        }
        // Gather S, B and D (all the matrix: its Bᵀ mirrors B), checking them.
        // With B, its part of the absolute row sums (for `norm_inf`).
        let mut finite = 0.0;
        let n = self.n_primal;
        self.row_sums.fill(0.0);
        let (wp, wm) = self.row_sums.split_at_mut(n);
        for (j, w) in wp.iter_mut().enumerate() {
            let mut column = 0.0;
            for q in range(&self.b_col_ptr, j) {
                let (row, p) = (self.b_rows[q], self.b_pos[q]);
                let v = values[p as usize];
                self.b_values[q] = v;
                finite += 0.0 * v;
                column += v.abs();
                let r = if self.natural {
                    row as usize
                } else {
                    self.c_fwd[row as usize]
                };
                wm[r] += v.abs();
            }
            *w = column;
        }
        if self.diagonal {
            for (v, &p) in self.s_values.iter_mut().zip(&self.diag_s) {
                *v = values[p];
                finite += 0.0 * *v;
            }
        } else {
            for (v, &(p, _, _)) in self.s_values.iter_mut().zip(&self.s_entries) {
                *v = values[p];
                finite += 0.0 * *v;
            }
        }
        for (v, &(p, _, _)) in self.d_values.iter_mut().zip(&self.d_all) {
            *v = values[p];
            finite += 0.0 * *v;
        }
        if f64::is_nan(finite) {
            return Err(KktError::NonFinite);
        }
        if self.diagonal {
            self.factor_diagonal()?;
        } else {
            self.factor_blocks(values)?;
        }
        for &(k, slot) in &self.d_entries {
            self.cf.values_mut()[slot] -= self.d_values[k];
        }
        self.cf.factor().map_err(|e| match e {
            KktError::Singular { unknown } => KktError::Singular {
                unknown: unknown.map(|k| self.n_primal + self.c_fwd[k]),
            },
            e => e,
        })
    }

    /// [`factor`](Self::factor) for a diagonal `S` and `C` in its envelope
    /// in the constraints' own order (a chain), in one pass over the columns:
    /// `S_jj` and column `j` of `B` gathered and checked, `C += b_r b_s / S_jj`
    /// into slots computed from the envelope's row pointers, and the absolute
    /// row sums of the whole matrix for `‖A‖∞` (kept in [`Self::norm`]). The
    /// values, the errors and their order are those of the general path.
    fn factor_banded(&mut self, values: &[f64]) -> Result<(), KktError> {
        let n = self.n_primal;
        let CFactor::Envelope(env) = &mut self.cf else {
            return Err(KktError::Structure(
                "the one-pass Schur factorization needs the envelope".to_string(),
            ));
        };
        let wm = &mut self.row_sums[n..];
        wm.fill(0.0);
        let (mut finite, mut wp_max) = (0.0f64, 0.0f64);
        let mut zero_pivot = None;
        for j in 0..n {
            let s = values[self.diag_s[j]];
            self.s_values[j] = s;
            finite += 0.0 * s;
            if s == 0.0 && zero_pivot.is_none() {
                zero_pivot = Some(j);
            }
            let inv = 1.0 / s;
            self.inverse[j] = inv;
            let col = range(&self.b_col_ptr, j);
            let mut column = 0.0;
            for q in col.clone() {
                let v = values[self.b_pos[q] as usize];
                self.b_values[q] = v;
                finite += 0.0 * v;
                column += v.abs();
                wm[self.b_rows[q] as usize] += v.abs();
            }
            let w = column + s.abs();
            wp_max = if w > wp_max { w } else { wp_max };
            // The lower triangle of b bᵀ / S_jj (rows ascending in a column).
            let (rows, bv) = (&self.b_rows[col.clone()], &self.b_values[col]);
            for (a, (&r, &br)) in rows.iter().zip(bv).enumerate() {
                for (&s_row, &bs) in rows[..=a].iter().zip(bv) {
                    env.add(r as usize, s_row as usize, br * inv * bs);
                }
            }
        }
        for (v, &(p, r, _)) in self.d_values.iter_mut().zip(&self.d_all) {
            *v = values[p];
            finite += 0.0 * *v;
            wm[r] += v.abs();
        }
        if f64::is_nan(finite) {
            return Err(KktError::NonFinite);
        }
        if let Some(j) = zero_pivot {
            return Err(KktError::Singular { unknown: Some(j) });
        }
        let norm = wm.iter().fold(wp_max, |m: f64, &x| m.max(x));
        for &(k, slot) in &self.d_entries {
            env.values_mut()[slot] -= self.d_values[k];
        }
        self.norm = Some(norm);
        env.factor().map_err(|k| KktError::Singular {
            unknown: Some(self.n_primal + k),
        })
    }

    /// `S` diagonal: `C += b_r b_s / S_jj` over the pairs of each column `j`.
    fn factor_diagonal(&mut self) -> Result<(), KktError> {
        let c_values = self.cf.values_mut();
        for (j, (&s, inv_j)) in self.s_values.iter().zip(&mut self.inverse).enumerate() {
            // One unknown: its only S entry is the diagonal.
            if s == 0.0 {
                return Err(KktError::Singular { unknown: Some(j) });
            }
            let inv = 1.0 / s;
            *inv_j = inv;
            let bv = &self.b_values[range(&self.b_col_ptr, j)];
            for &(r, s, slot) in &self.pairs[self.pair_ptr[j]..self.pair_ptr[j + 1]] {
                c_values[slot as usize] += bv[usize::from(r)] * inv * bv[usize::from(s)];
            }
        }
        Ok(())
    }

    /// General blocks: dense `S_K⁻¹`, `W = B_K S_K⁻¹`, `C += W B_Kᵀ`.
    fn factor_blocks(&mut self, values: &[f64]) -> Result<(), KktError> {
        let c_values = self.cf.values_mut();
        for b in &self.blocks {
            let k = b.coords.len();
            let blk = &mut self.block[..k * k];
            blk.fill(0.0);
            for &(p, i, j) in &self.s_entries[b.s_entries.clone()] {
                blk[i * k + j] += values[p];
            }
            let inv = &mut self.inverse[b.inverse..b.inverse + k * k];
            invert(blk, inv, k).map_err(|l| KktError::Singular {
                unknown: Some(self.coords[b.coords.start + l]),
            })?;
            let nr = b.n_rows;
            let bk = &mut self.bk[..nr * k];
            bk.fill(0.0);
            for &(p, r, j) in &self.b_entries[b.b_entries.clone()] {
                bk[r * k + j] += values[p];
            }
            let w = &mut self.w[..nr * k];
            for r in 0..nr {
                for l in 0..k {
                    w[r * k + l] = (0..k).map(|j| bk[r * k + j] * inv[j * k + l]).sum();
                }
            }
            for &(r, s, slot) in &self.pairs[b.pairs.clone()] {
                let (r, s) = (usize::from(r), usize::from(s));
                let v: f64 = (0..k).map(|l| w[r * k + l] * bk[s * k + l]).sum();
                c_values[slot as usize] += v;
            }
        }
        Ok(())
    }

    /// The entries of `S` of the last factorization as `(row, column, value)`
    /// in global unknowns.
    fn s_global(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        s_global(&self.blocks, &self.coords, &self.s_entries, &self.s_values)
    }

    /// `y = A x` for the last factored matrix, from the compact copies of
    /// `S`, `B` and `D` (`A = [[S, Bᵀ], [B, D]]`).
    pub(crate) fn mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n_primal;
        y.fill(0.0);
        let (yp, ym) = y.split_at_mut(n);
        let (xp, xm) = x.split_at(n);
        if self.diagonal {
            for ((yj, &s), &xj) in yp.iter_mut().zip(&self.s_values).zip(xp) {
                *yj = s * xj;
            }
        } else {
            for (i, j, v) in self.s_global() {
                yp[i] += v * xp[j];
            }
        }
        for j in 0..n {
            let (mut acc, xj) = (yp[j], xp[j]);
            for q in range(&self.b_col_ptr, j) {
                let row = self.b_rows[q] as usize;
                let r = if self.natural { row } else { self.c_fwd[row] };
                acc += self.b_values[q] * xm[r];
                ym[r] += self.b_values[q] * xj;
            }
            yp[j] = acc;
        }
        for (&(_, r, s), &v) in self.d_all.iter().zip(&self.d_values) {
            ym[r] += v * xm[s];
        }
    }

    /// `‖A‖∞`, the largest absolute row sum of the last factored matrix
    /// (completes the row sums that [`factor`](Self::factor) began with `B`).
    pub(crate) fn norm_inf(&mut self) -> f64 {
        if let Some(norm) = self.norm {
            return norm;
        }
        let n = self.n_primal;
        let (wp, wm) = self.row_sums.split_at_mut(n);
        if self.diagonal {
            for (w, s) in wp.iter_mut().zip(&self.s_values) {
                *w += s.abs();
            }
        } else {
            for (i, _, v) in s_global(&self.blocks, &self.coords, &self.s_entries, &self.s_values) {
                wp[i] += v.abs();
            }
        }
        for (&(_, r, _), &v) in self.d_all.iter().zip(&self.d_values) {
            wm[r] += v.abs();
        }
        self.row_sums.iter().fold(0.0, |m: f64, &x| m.max(x))
    }

    /// Solves in place with the last factorization; returns `‖x‖∞` (as
    /// [`max_abs`] would).
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        if self.diagonal && self.natural {
            return self.solve_diagonal(rhs, false).0;
        }
        self.solve_general(rhs)
    }

    /// Whether [`solve_checked`](Self::solve_checked) forms the residual on
    /// the way (`S` diagonal, `C` in the constraints' own order).
    pub(crate) fn checks_in_solve(&self) -> bool {
        self.diagonal && self.natural
    }

    /// [`solve_in_place`](Self::solve_in_place) that also returns
    /// `‖A x − b‖∞`, formed in the solve's own sweeps instead of a product
    /// with the matrix afterwards (the check of the first solve after each
    /// factorization); for [`checks_in_solve`](Self::checks_in_solve) only.
    /// Returns `(‖x‖∞, ‖A x − b‖∞)`.
    pub(crate) fn solve_checked(&mut self, rhs: &mut [f64]) -> (f64, f64) {
        debug_assert!(self.checks_in_solve());
        self.solve_diagonal(rhs, true)
    }

    /// The solve for a diagonal `S` and `C` in the constraints' own order:
    /// the steps of the general path in two sweeps over `B` and no scratch
    /// (each pass over `B` at 10⁵ bodies streams it from memory):
    /// `g ← B S⁻¹ f − g`, `g ← C⁻¹ g`, `f ← S⁻¹ (f − Bᵀ g)`. With `check`, the
    /// second sweep also forms the residual `A x − b`: for a primal row `j`,
    /// `S_jj x_j − s_j` (`s_j = f_j − (Bᵀ y)_j`, formed anyway), for a
    /// constraint row `(B x + D y − g)_r`, accumulated in the scratch `y`
    /// from `−g` and the `x_j` as they come. Returns
    /// `(‖x‖∞, ‖A x − b‖∞)` (the residual 0 without `check`).
    fn solve_diagonal(&mut self, rhs: &mut [f64], check: bool) -> (f64, f64) {
        let n = self.n_primal;
        let (f, g) = rhs.split_at_mut(n);
        let res = &mut self.y;
        if check {
            // The constraint rows' residual starts at D y − g.
            for (r, &gr) in res.iter_mut().zip(g.iter()) {
                *r = -gr;
            }
        }
        // The envelope solve stores −C⁻¹ w: then w = g − B S⁻¹ f needs no
        // pass negating g first, and −C⁻¹ w = C⁻¹ (B S⁻¹ f − g) = y bit for
        // bit (negation is exact and rounding symmetric).
        let envelope = matches!(self.cf, CFactor::Envelope(_));
        if !envelope {
            for gr in g.iter_mut() {
                *gr = -*gr;
            }
        }
        let sign = if envelope { -1.0 } else { 1.0 };
        for (j, (&fj, &inv)) in f.iter().zip(&self.inverse).enumerate() {
            let xj = sign * (inv * fj);
            for q in range(&self.b_col_ptr, j) {
                g[self.b_rows[q] as usize] += self.b_values[q] * xj;
            }
        }
        let g_norm = match &mut self.cf {
            CFactor::Envelope(e) => e.solve(g, true),
            cf => {
                cf.solve_in_place(g);
                max_abs(g)
            }
        };
        if check {
            for (&(_, r, c), &v) in self.d_all.iter().zip(&self.d_values) {
                res[r] += v * g[c];
            }
        }
        // ‖f‖∞ on the way; `0 · x` carries a NaN or an infinity.
        let (mut f_max, mut nan, mut primal_res) = (0.0f64, 0.0f64, 0.0f64);
        for (j, (fj, &inv)) in f.iter_mut().zip(&self.inverse).enumerate() {
            let mut s = *fj;
            let col = range(&self.b_col_ptr, j);
            for q in col.clone() {
                s -= self.b_values[q] * g[self.b_rows[q] as usize];
            }
            let x = inv * s;
            *fj = x;
            f_max = if x.abs() > f_max { x.abs() } else { f_max };
            nan += 0.0 * x;
            if check {
                let r = (self.s_values[j] * x - s).abs();
                primal_res = if r > primal_res { r } else { primal_res };
                for q in col {
                    res[self.b_rows[q] as usize] += self.b_values[q] * x;
                }
            }
        }
        let residual = if check {
            primal_res.max(max_abs(res))
        } else {
            0.0
        };
        let x_norm = if nan.is_nan() {
            // A NaN or an infinity: max_abs tells which (a rare path).
            max_abs(rhs)
        } else {
            f_max.max(g_norm)
        };
        (x_norm, residual)
    }

    /// The solve for block-diagonal `S` or `C` in another order.
    fn solve_general(&mut self, rhs: &mut [f64]) -> f64 {
        let n = self.n_primal;
        let (f, g) = rhs.split_at_mut(n);
        // y = −g in C's order, x = S⁻¹ f, then y += B x: C y = B S⁻¹ f − g.
        if self.natural {
            for (y, &gr) in self.y.iter_mut().zip(g.iter()) {
                *y = -gr;
            }
        } else {
            for (r, &gr) in g.iter().enumerate() {
                self.y[self.c_inv[r]] = -gr;
            }
        }
        self.apply_inverse(f);
        for j in 0..n {
            let xj = self.x[j];
            for q in range(&self.b_col_ptr, j) {
                self.y[self.b_rows[q] as usize] += self.b_values[q] * xj;
            }
        }
        self.cf.solve_in_place(&mut self.y);
        // x = S⁻¹ (f − Bᵀ y).
        for (j, fj) in f.iter_mut().enumerate() {
            let mut s = *fj;
            for q in range(&self.b_col_ptr, j) {
                s -= self.b_values[q] * self.y[self.b_rows[q] as usize];
            }
            *fj = s;
        }
        self.apply_inverse(f);
        f.copy_from_slice(&self.x);
        if self.natural {
            g.copy_from_slice(&self.y);
        } else {
            for (r, gr) in g.iter_mut().enumerate() {
                *gr = self.y[self.c_inv[r]];
            }
        }
        max_abs(rhs)
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

/// The positions `ptr[j]..ptr[j + 1]` (column `j`'s `B` entries in `b_rows`,
/// `b_pos`, `b_values`).
#[inline]
fn range(ptr: &[u32], j: usize) -> std::ops::Range<usize> {
    ptr[j] as usize..ptr[j + 1] as usize
}

/// The entries of block-diagonal `S` as `(row, column, value)` in global
/// unknowns (free function so that callers may hold other fields mutably).
fn s_global<'a>(
    blocks: &'a [Block],
    coords: &'a [usize],
    s_entries: &'a [(usize, usize, usize)],
    s_values: &'a [f64],
) -> impl Iterator<Item = (usize, usize, f64)> + 'a {
    blocks.iter().flat_map(move |b| {
        let local = &coords[b.coords.clone()];
        s_entries[b.s_entries.clone()]
            .iter()
            .zip(&s_values[b.s_entries.clone()])
            .map(move |(&(_, i, j), &v)| (local[i], local[j], v))
    })
}

/// `C` and how it is factored.
enum CFactor {
    /// By its lower envelope, in the constraints' own order.
    Envelope(EnvelopeLdlt),
    /// faer's sparse LDLᵀ of the triangle it reads, after AMD.
    Sparse { c: Csc, ldlt: Box<SparseLdlt> },
}

impl CFactor {
    /// Whether entry `(r, s)` (in `C`'s order) is stored and read.
    fn reads(&self, r: usize, s: usize) -> bool {
        match self {
            Self::Envelope(_) => r >= s,
            Self::Sparse { ldlt, .. } => {
                if ldlt.reads_upper() {
                    r <= s
                } else {
                    r >= s
                }
            }
        }
    }

    /// Position of a read entry `(r, s)` in [`values_mut`](Self::values_mut).
    fn slot(&self, r: usize, s: usize) -> usize {
        match self {
            Self::Envelope(e) => e.slot(r, s),
            Self::Sparse { c, .. } => {
                let col = &c.row_idx[c.col_ptr[s]..c.col_ptr[s + 1]];
                c.col_ptr[s] + col.binary_search(&r).unwrap_or(0)
            }
        }
    }

    fn values_mut(&mut self) -> &mut [f64] {
        match self {
            Self::Envelope(e) => e.values_mut(),
            Self::Sparse { c, .. } => &mut c.values,
        }
    }

    /// Factors; a zero pivot names its row of `C` (in `C`'s order).
    fn factor(&mut self) -> Result<(), KktError> {
        match self {
            Self::Envelope(e) => e
                .factor()
                .map_err(|k| KktError::Singular { unknown: Some(k) }),
            Self::Sparse { c, ldlt } => ldlt.factor(c),
        }
    }

    fn solve_in_place(&mut self, y: &mut [f64]) {
        match self {
            Self::Envelope(e) => e.solve_in_place(y),
            Self::Sparse { ldlt, .. } => ldlt.solve_in_place(y),
        }
    }
}

/// The `n × n` CSC pattern of the `(column, row)` pairs (sorted and
/// deduplicated in place), values zero.
fn csc_of(n: usize, pairs: &mut Vec<(usize, usize)>) -> Csc {
    pairs.sort_unstable();
    pairs.dedup();
    let mut c = Csc {
        n,
        col_ptr: vec![0; n + 1],
        row_idx: Vec::with_capacity(pairs.len()),
        values: vec![0.0; pairs.len()],
    };
    for &(col, row) in pairs.iter() {
        c.col_ptr[col + 1] += 1;
        c.row_idx.push(row);
    }
    for j in 0..n {
        c.col_ptr[j + 1] += c.col_ptr[j];
    }
    c
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
