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
//! `FILL_SLACK` times the factor AMD gives, else in the reverse
//! Cuthill–McKee order (`crate::rcm`; a closed loop's rows, which the
//! constraints' own order spreads apart) when that one is, else by faer's
//! sparse LDLᵀ after AMD on the triangle faer reads. `C` is symmetric positive definite when `S` is and
//! `B` has full row rank; a block without an inverse, or a pivot of `C` at the
//! rounding level (a redundant constraint), is an error naming the unknown.
//!
//! The blocks are the connected components of the pattern of `S` (entries
//! `(i, j)` with `i, j < n_primal`); a component larger than
//! [`MAX_BLOCK`] unknowns makes the analysis fail (use LDLᵀ then). A
//! constraint row whose `B` entries all lie in one block of two or more
//! unknowns, with no entry of `D` in its row or column (a body's
//! normalization `pᵀp = 1`), is eliminated with that block: the block's
//! inverse is that of the saddle point `[[S_K, B_lᵀ], [B_l, 0]]`, and `C`
//! holds the other rows only (for a chain of bodies in Euler parameters,
//! 3 rows a spherical joint instead of 4 a bar: a smaller `C`, fewer pairs). The
//! backend reads `S`, `B` and `D` only (the matrix is symmetric), keeps
//! compact copies of them, and computes its own products and norm for the
//! residual check of `KktSolver`.
//!
//! A chain (`S` diagonal, `C` by its envelope in the constraints' own order)
//! takes leaner paths: the factorization is one pass over the columns whose
//! slots in `C` come from the envelope's row pointers (no table of pairs), and
//! the residual check is formed inside the solve ([`Schur::solve_checked`]).
//!
//! The symbolic analysis is in `analyse.rs`; this file holds the numeric
//! factorization, the solves and the products.

mod analyse;
mod blocks;
#[cfg(test)]
mod lu_tests;
mod refine;

use crate::backend::{Backend, KktBackend, Registration, Structure};
use crate::envelope::EnvelopeLdlt;
use crate::envelope_lu::EnvelopeLu;
use crate::sparse_ldlt::SparseLdlt;
use crate::{Csc, Finite, KktError, KktOptions, MaxAbs, max_abs};

/// The `schur` backend.
pub(crate) const REGISTRATION: Registration = Registration {
    backend: Backend::SCHUR,
    summary: "Schur complement on a block-diagonal S_T (bodies coupled only by constraints)",
    structure: Structure::PLAIN,
    symmetric: true,
    analyse: |a, options: &KktOptions| {
        let np = options.require_n_primal(Backend::SCHUR)?;
        Ok(Box::new(Schur::new(a, np)?))
    },
    automatic: Some(10),
    needs_n_primal: true,
};

/// The `schur-lu` backend: the same elimination for an `S` whose blocks are
/// not symmetric (the exact iteration matrix of bodies in Euler parameters,
/// whose gyroscopic blocks are not; docs/theory.md, "Spatial bodies"), `C`
/// factored by an envelope LU without pivoting.
pub(crate) const REGISTRATION_LU: Registration = Registration {
    backend: Backend::SCHUR_LU,
    summary: "Schur complement on a block-diagonal, unsymmetric S_T (LU of C by its envelope)",
    structure: Structure::PLAIN,
    symmetric: false,
    analyse: |a, options: &KktOptions| {
        let np = options.require_n_primal(Backend::SCHUR_LU)?;
        Ok(Box::new(Schur::with_symmetry(a, np, Symmetry::General)?))
    },
    automatic: Some(20),
    needs_n_primal: true,
};

/// Whether the Schur backend may take `S` (and so `C`) as symmetric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Symmetry {
    /// `S` and `D` symmetric: `C` by LDLᵀ on one triangle (`schur`).
    Symmetric,
    /// Any values on a symmetric pattern: `C` by LU on both triangles of its
    /// envelope (`schur-lu`).
    General,
}

/// The largest diagonal block of `S` that the Schur backend inverts densely.
pub const MAX_BLOCK: usize = 12;

/// How much larger (in stored values) the envelope of `C` (in the
/// constraints' own order or the reverse Cuthill–McKee order) may be than
/// its factor with AMD and still be preferred for its locality.
const FILL_SLACK: f64 = 1.25;

/// One diagonal block of `S`.
#[derive(Clone, Debug)]
struct Block {
    /// The block's unknowns in the KKT system: its `k` primal unknowns
    /// ascending, then `n_primal + r` for each constraint row `r` local to
    /// it (eliminated with the block, not a row of `C`), ascending.
    coords: std::ops::Range<usize>,
    /// Number of its primal unknowns.
    k: usize,
    /// Its entries of `S`: `(position in the KKT values, local i, local j)`.
    s_entries: std::ops::Range<usize>,
    /// Its entries of `B`: `(position in the KKT values, local row, local j)`.
    b_entries: std::ops::Range<usize>,
    /// Its rows in `analyse::Parts::rows` (original constraint indices).
    rows: std::ops::Range<usize>,
    /// Number of its rows of `C` (its local rows are not counted).
    n_rows: usize,
    /// Offset of its inverse (row-major, of the primal unknowns and the local
    /// rows' multipliers: the saddle point `[[S_K, B_lᵀ], [B_l, 0]]`) in
    /// `inverse`.
    inverse: usize,
    /// Its contributions to `C`: `(local row, local row, slot in C)`.
    pairs: std::ops::Range<usize>,
}

/// The analysed structure and reused buffers of the Schur backend.
#[derive(Clone)]
pub(crate) struct Schur {
    n_primal: usize,
    blocks: Vec<Block>,
    /// Unknowns of all blocks, block after block.
    coords: Vec<usize>,
    /// `(KKT value position, local i, local j)` of every block's `S` entries.
    s_entries: Vec<blocks::Entry>,
    /// The same entries' global `(row, column)` (empty when `diagonal`):
    /// products and norms with `S` read them in one pass, without the
    /// blocks' lists.
    s_global: Vec<(u32, u32)>,
    /// `(KKT value position, local row, local column)` of every block's `B`.
    b_entries: Vec<blocks::Entry>,
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
    /// Scratch of length `n_primal + m` (the blocks' unknowns, with their
    /// local multipliers) and `m` (in `C`'s order; the rows of `C` first).
    x: Vec<f64>,
    y: Vec<f64>,
    /// The dimension of `C`: the constraint rows not local to a block.
    m_c: usize,
    /// The `B` entries of the KKT matrix by primal column (column `j`'s are
    /// `b_col_ptr[j]..b_col_ptr[j + 1]`): the position of the row in C's
    /// order, and the position in the KKT values. Apart and on 32 bits: the
    /// solve reads the rows only, and on a long chain it streams them from memory.
    b_col_ptr: Vec<u32>,
    b_rows: Vec<u32>,
    b_pos: Vec<u32>,
    /// The same entries' rows in the constraints' own order when that is not
    /// `C`'s (empty when it is): for the products and row sums.
    b_orig: Vec<u32>,
    /// The multipliers' part of a right-hand side in `C`'s order, for the
    /// solve of a diagonal `S` when that order is not the constraints' own.
    g_ordered: Vec<f64>,
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
    /// Whether every solve takes one step of iterative refinement
    /// (`schur-lu`: `refine.rs` says why), with its scratch `b` and
    /// `b − A x` (`n + m` each; empty without).
    refine: bool,
    refine_b: Vec<f64>,
    refine_r: Vec<f64>,
}

impl Schur {
    /// Whether `C` is factored by its envelope (else by faer after AMD).
    #[cfg(test)]
    pub(crate) fn uses_envelope(&self) -> bool {
        matches!(self.cf, CFactor::Envelope(_))
    }

    /// Whether `C`'s order is the constraints' own.
    #[cfg(test)]
    pub(crate) fn natural_order(&self) -> bool {
        self.natural
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
    /// [`KktError::NonFinite`] for a NaN or infinite value it reads;
    /// [`KktError::Singular`] naming the primal unknown without a pivot in its
    /// block, or the multiplier whose pivot in `C` vanishes.
    fn factor_matrix(&mut self, values: &[f64]) -> Result<(), KktError> {
        self.cf.values_mut().fill(0.0);
        self.norm = None;
        if self.banded {
            return self.factor_banded(values);
        }
        self.gather(values)?;
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

    /// Copies `S`, `B` and `D` (all the matrix: its `Bᵀ` mirrors `B`),
    /// checking that they are finite, and forms the absolute row sums of the
    /// whole matrix on the way (their largest is [`norm_inf`](Self::norm_inf)).
    fn gather(&mut self, values: &[f64]) -> Result<(), KktError> {
        let mut finite = Finite::new();
        let n = self.n_primal;
        self.row_sums.fill(0.0);
        let (wp, wm) = self.row_sums.split_at_mut(n);
        for (j, w) in wp.iter_mut().enumerate() {
            let mut column = 0.0;
            let rows = if self.natural {
                &self.b_rows
            } else {
                &self.b_orig
            };
            for q in range(&self.b_col_ptr, j) {
                let (row, p) = (rows[q], self.b_pos[q]);
                let v = values[p as usize];
                self.b_values[q] = v;
                finite.push(v);
                column += v.abs();
                wm[row as usize] += v.abs();
            }
            *w = column;
        }
        // S and D copied, and their terms of the row sums added after B's
        // (the order `norm_inf` added them in).
        let mut take = |v: &mut f64, p: usize, w: &mut f64| {
            *v = values[p];
            finite.push(*v);
            *w += v.abs();
        };
        if self.diagonal {
            for ((v, &p), w) in self.s_values.iter_mut().zip(&self.diag_s).zip(wp) {
                take(v, p, w);
            }
        } else {
            let entries = self.s_entries.iter().zip(&self.s_global);
            for (v, (e, &(i, _))) in self.s_values.iter_mut().zip(entries) {
                take(v, e.pos(), &mut wp[i as usize]);
            }
        }
        for (v, &(p, r, _)) in self.d_values.iter_mut().zip(&self.d_all) {
            take(v, p, &mut wm[r]);
        }
        if finite.all() {
            Ok(())
        } else {
            Err(KktError::NonFinite)
        }
    }

    /// [`factor_matrix`](Self::factor_matrix) for a diagonal `S` and `C` in its envelope
    /// (a chain in the constraints' own order, a closed loop in the reverse
    /// Cuthill–McKee order), in one pass over the columns:
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
        let (mut finite, mut wp_max) = (Finite::new(), 0.0f64);
        let mut zero_pivot = None;
        for j in 0..n {
            let s = values[self.diag_s[j]];
            self.s_values[j] = s;
            finite.push(s);
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
                finite.push(v);
                column += v.abs();
                wm[self.b_rows[q] as usize] += v.abs();
            }
            let w = column + s.abs();
            wp_max = if w > wp_max { w } else { wp_max };
            // The lower triangle of b bᵀ / S_jj (a column's rows ascend in
            // the constraints' own order, not always in C's).
            let (rows, bv) = (&self.b_rows[col.clone()], &self.b_values[col]);
            for (a, (&r, &br)) in rows.iter().zip(bv).enumerate() {
                for (&s_row, &bs) in rows[..=a].iter().zip(bv) {
                    let (hi, lo) = if r >= s_row { (r, s_row) } else { (s_row, r) };
                    env.add(hi as usize, lo as usize, br * inv * bs);
                }
            }
        }
        for (v, &(p, r, _)) in self.d_values.iter_mut().zip(&self.d_all) {
            *v = values[p];
            finite.push(*v);
            wm[r] += v.abs();
        }
        if !finite.all() {
            return Err(KktError::NonFinite);
        }
        if let Some(j) = zero_pivot {
            return Err(KktError::Singular { unknown: Some(j) });
        }
        // Finite values: finite row sums.
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

    /// General blocks: dense `S_K⁻¹`, `W = B_K S_K⁻¹`, `C += W B_Kᵀ`
    /// ([`blocks::factor_block`], fixed-size for small blocks).
    fn factor_blocks(&mut self, values: &[f64]) -> Result<(), KktError> {
        let c_values = self.cf.values_mut();
        let mut scratch = blocks::Scratch {
            block: &mut self.block,
            bk: &mut self.bk,
            w: &mut self.w,
        };
        for b in &self.blocks {
            let size = b.coords.len();
            let lists = blocks::Lists {
                s_entries: &self.s_entries[b.s_entries.clone()],
                b_entries: &self.b_entries[b.b_entries.clone()],
                pairs: &self.pairs[b.pairs.clone()],
                n_rows: b.n_rows,
            };
            let inv = &mut self.inverse[b.inverse..b.inverse + size * size];
            let sizes = (b.k, size);
            blocks::factor_block(sizes, &lists, values, inv, &mut scratch, c_values).map_err(
                |l| KktError::Singular {
                    unknown: Some(self.coords[b.coords.start + l]),
                },
            )?;
        }
        Ok(())
    }

    /// `y = A x` for the last factored matrix, from the compact copies of
    /// `S`, `B` and `D` (`A = [[S, Bᵀ], [B, D]]`).
    fn product(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n_primal;
        y.fill(0.0);
        let (yp, ym) = y.split_at_mut(n);
        let (xp, xm) = x.split_at(n);
        if self.diagonal {
            for ((yj, &s), &xj) in yp.iter_mut().zip(&self.s_values).zip(xp) {
                *yj = s * xj;
            }
        } else {
            for (&(i, j), &v) in self.s_global.iter().zip(&self.s_values) {
                yp[i as usize] += v * xp[j as usize];
            }
        }
        let rows = if self.natural {
            &self.b_rows
        } else {
            &self.b_orig
        };
        for (j, (yj, &xj)) in yp.iter_mut().zip(xp).enumerate() {
            let col = range(&self.b_col_ptr, j);
            let mut acc = *yj;
            for (&row, &b) in rows[col.clone()].iter().zip(&self.b_values[col]) {
                acc += b * xm[row as usize];
                ym[row as usize] += b * xj;
            }
            *yj = acc;
        }
        for (&(_, r, s), &v) in self.d_all.iter().zip(&self.d_values) {
            ym[r] += v * xm[s];
        }
    }

    /// `‖A‖∞`, the largest absolute row sum of the last factored matrix
    /// (the row sums of [`gather`](Self::gather)).
    fn norm_inf(&mut self) -> f64 {
        if let Some(norm) = self.norm {
            return norm;
        }
        // The row sums are complete after `gather` (finite and ≥ 0: their
        // largest as `f64::max` folds it, in vectorizable lanes).
        max_abs(&self.row_sums)
    }

    /// Solves in place with the last factorization; returns `‖x‖∞` (as
    /// [`max_abs`] would).
    fn solve(&mut self, rhs: &mut [f64]) -> f64 {
        if self.refine {
            return self.solve_refined(rhs).0;
        }
        if self.diagonal {
            return self.solve_diagonal(rhs, false).0;
        }
        self.solve_general(rhs)
    }

    /// Whether [`solve_checked`](Self::solve_checked) forms the residual on
    /// the way (`S` diagonal, or a refined solve, which forms it anyway).
    pub(crate) fn checks_in_solve(&self) -> bool {
        self.refine || self.diagonal
    }

    /// [`solve`](Self::solve) that also returns
    /// `‖A x − b‖∞`, formed in the solve's own sweeps instead of a product
    /// with the matrix afterwards (the check of the first solve after each
    /// factorization); for [`checks_in_solve`](Self::checks_in_solve) only.
    /// Returns `(‖x‖∞, ‖A x − b‖∞)`.
    pub(crate) fn solve_checked(&mut self, rhs: &mut [f64]) -> (f64, f64) {
        debug_assert!(self.checks_in_solve());
        if self.refine {
            return self.solve_refined(rhs);
        }
        self.solve_diagonal(rhs, true)
    }

    /// The solve for a diagonal `S`, its multipliers' part in `C`'s order
    /// ([`solve_diagonal_in_order`](Self::solve_diagonal_in_order), on a
    /// copy in that order when it is not the constraints' own).
    fn solve_diagonal(&mut self, rhs: &mut [f64], check: bool) -> (f64, f64) {
        let n = self.n_primal;
        let (f, g) = rhs.split_at_mut(n);
        if self.natural {
            return self.solve_diagonal_in_order(f, g, check);
        }
        let mut ordered = std::mem::take(&mut self.g_ordered);
        for (r, &gr) in g.iter().enumerate() {
            ordered[self.c_inv[r]] = gr;
        }
        let out = self.solve_diagonal_in_order(f, &mut ordered, check);
        for (r, gr) in g.iter_mut().enumerate() {
            *gr = ordered[self.c_inv[r]];
        }
        self.g_ordered = ordered;
        out
    }

    /// The solve for a diagonal `S`, `g` in `C`'s order:
    /// the steps of the general path in two sweeps over `B` and no scratch
    /// (on a long chain each pass over `B` streams it from memory):
    /// `g ← B S⁻¹ f − g`, `g ← C⁻¹ g`, `f ← S⁻¹ (f − Bᵀ g)`. With `check`, the
    /// second sweep also forms the residual `A x − b`: for a primal row `j`,
    /// `S_jj x_j − s_j` (`s_j = f_j − (Bᵀ y)_j`, formed anyway), for a
    /// constraint row `(B x + D y − g)_r`, accumulated in the scratch `y`
    /// from `−g` and the `x_j` as they come. Returns
    /// `(‖x‖∞, ‖A x − b‖∞)` (the residual 0 without `check`).
    fn solve_diagonal_in_order(&mut self, f: &mut [f64], g: &mut [f64], check: bool) -> (f64, f64) {
        if check {
            // The constraint rows' residual starts at D y − g.
            for (r, &gr) in self.y.iter_mut().zip(g.iter()) {
                *r = -gr;
            }
        }
        let g_norm = self.diagonal_multipliers(f, g);
        if check {
            // D's entries are indexed in the constraints' own order.
            for (&(_, r, c), &v) in self.d_all.iter().zip(&self.d_values) {
                self.y[self.c_inv[r]] += v * g[self.c_inv[c]];
            }
        }
        let (f_max, primal_res) = self.diagonal_primal(f, g, check);
        let residual = if check {
            primal_res.max(max_abs(&self.y))
        } else {
            0.0
        };
        let x_norm = if f_max.is_finite() {
            f_max.finite_max().max(g_norm)
        } else {
            // A NaN or an infinity: max_abs tells which (a rare path;
            // `f64::max` would drop a NaN).
            let (a, b) = (max_abs(f), max_abs(g));
            if a.is_infinite() || b.is_infinite() {
                f64::INFINITY
            } else if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        };
        (x_norm, residual)
    }

    /// First sweep and `C` solve of [`solve_diagonal`](Self::solve_diagonal):
    /// `g ← C⁻¹ (B S⁻¹ f − g)`, the multipliers; returns `‖g‖∞`.
    fn diagonal_multipliers(&mut self, f: &[f64], g: &mut [f64]) -> f64 {
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
        let columns = self.b_col_ptr.windows(2).zip(f.iter().zip(&self.inverse));
        for (w, (&fj, &inv)) in columns {
            let xj = sign * (inv * fj);
            let col = w[0] as usize..w[1] as usize;
            for (&r, &b) in self.b_rows[col.clone()].iter().zip(&self.b_values[col]) {
                g[r as usize] += b * xj;
            }
        }
        match &mut self.cf {
            CFactor::Envelope(e) => e.solve(g, true),
            CFactor::EnvelopeLu(e) => e.solve(g),
            cf => {
                cf.solve_in_place(g);
                max_abs(g)
            }
        }
    }

    /// Second sweep of [`solve_diagonal`](Self::solve_diagonal):
    /// `f ← S⁻¹ (f − Bᵀ g)`, with `‖f‖∞` on the way and, with `check`, the
    /// primal rows' residual (returned) and the constraint rows' (added into
    /// the scratch `y`).
    fn diagonal_primal(&mut self, f: &mut [f64], g: &[f64], check: bool) -> (MaxAbs, f64) {
        let (mut f_max, mut primal_res) = (MaxAbs::new(), MaxAbs::new());
        let columns = self
            .b_col_ptr
            .windows(2)
            .zip(f.iter_mut().zip(&self.inverse));
        for (j, (w, (fj, &inv))) in columns.enumerate() {
            let col = w[0] as usize..w[1] as usize;
            let (rows, values) = (&self.b_rows[col.clone()], &self.b_values[col]);
            let mut s = *fj;
            for (&r, &b) in rows.iter().zip(values) {
                s -= b * g[r as usize];
            }
            let x = inv * s;
            *fj = x;
            f_max.push(x);
            if check {
                primal_res.push(self.s_values[j] * x - s);
                for (&r, &b) in rows.iter().zip(values) {
                    self.y[r as usize] += b * x;
                }
            }
        }
        (f_max, primal_res.value())
    }

    /// The solve for block-diagonal `S` or `C` in another order. Each
    /// block's unknowns include the multipliers of its local rows, so a
    /// block's inverse reads and writes both parts of `rhs`.
    fn solve_general(&mut self, rhs: &mut [f64]) -> f64 {
        let n = self.n_primal;
        // y = −g in C's order, x = S⁻¹ f, then y += B x: C y = B S⁻¹ f − g.
        if self.natural {
            for (y, &gr) in self.y.iter_mut().zip(&rhs[n..]) {
                *y = -gr;
            }
        } else {
            for (r, &gr) in rhs[n..].iter().enumerate() {
                self.y[self.c_inv[r]] = -gr;
            }
        }
        self.apply_inverse(rhs);
        for (j, &xj) in self.x[..n].iter().enumerate() {
            let col = range(&self.b_col_ptr, j);
            for (&row, &b) in self.b_rows[col.clone()].iter().zip(&self.b_values[col]) {
                self.y[row as usize] += b * xj;
            }
        }
        // The local rows (after C's) take no part in C y = …, nor in Bᵀ y.
        let m_c = self.m_c;
        self.y[m_c..].fill(0.0);
        self.cf.solve_in_place(&mut self.y[..m_c]);
        // x = S⁻¹ (f − Bᵀ y), with the local rows' g as it came.
        for (j, fj) in rhs[..n].iter_mut().enumerate() {
            let col = range(&self.b_col_ptr, j);
            let mut s = *fj;
            for (&row, &b) in self.b_rows[col.clone()].iter().zip(&self.b_values[col]) {
                s -= b * self.y[row as usize];
            }
            *fj = s;
        }
        self.apply_inverse(rhs);
        let (f, g) = rhs.split_at_mut(n);
        f.copy_from_slice(&self.x[..n]);
        if self.natural {
            // Local rows, if any, are the last ones (after C's), in order.
            g[..m_c].copy_from_slice(&self.y[..m_c]);
            g[m_c..].copy_from_slice(&self.x[n + m_c..]);
        } else {
            for (r, gr) in g.iter_mut().enumerate() {
                let k = self.c_inv[r];
                *gr = if k < m_c { self.y[k] } else { self.x[n + r] };
            }
        }
        max_abs(rhs)
    }

    /// `self.x = S⁻¹ rhs` block by block (a block with local rows reads and
    /// writes their multipliers too).
    fn apply_inverse(&mut self, rhs: &[f64]) {
        if self.diagonal {
            for ((x, &fi), &d) in self.x.iter_mut().zip(rhs).zip(&self.inverse) {
                *x = d * fi;
            }
            return;
        }
        for b in &self.blocks {
            let k = b.coords.len();
            let inv = &self.inverse[b.inverse..b.inverse + k * k];
            blocks::apply_block(&self.coords[b.coords.clone()], inv, rhs, &mut self.x);
        }
    }
}

impl KktBackend for Schur {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        self.factor_matrix(values)?;
        Ok(self.norm_inf())
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        self.solve(rhs)
    }

    fn solve_in_place_unrefined(&mut self, rhs: &mut [f64]) -> f64 {
        if self.refine {
            return self.solve_general(rhs);
        }
        self.solve(rhs)
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.product(x, y);
    }

    /// A chain (`S` diagonal, `C` in the constraints' order) forms the
    /// residual inside its solve: no copy of `rhs`, no product afterwards.
    fn solve_with_residual(&mut self, rhs: &mut [f64]) -> Option<(f64, f64)> {
        self.checks_in_solve().then(|| self.solve_checked(rhs))
    }

    /// `schur-lu` without its refinement step has no residual on the way
    /// (the caller multiplies); the others as `solve_with_residual`.
    fn solve_unrefined_with_residual(&mut self, rhs: &mut [f64]) -> Option<(f64, f64)> {
        if self.refine {
            return None;
        }
        self.solve_with_residual(rhs)
    }

    fn fork(&self) -> Option<Box<dyn KktBackend>> {
        Some(Box::new(self.clone()))
    }
}

/// The positions `ptr[j]..ptr[j + 1]` (column `j`'s `B` entries in `b_rows`,
/// `b_pos`, `b_values`).
#[inline]
fn range(ptr: &[u32], j: usize) -> std::ops::Range<usize> {
    ptr[j] as usize..ptr[j + 1] as usize
}

/// `C` and how it is factored.
#[derive(Clone)]
enum CFactor {
    /// By its lower envelope, in the constraints' own order.
    Envelope(EnvelopeLdlt),
    /// By LU on its whole envelope, in the constraints' own order (`S` not
    /// symmetric).
    EnvelopeLu(EnvelopeLu),
    /// faer's sparse LDLᵀ of the triangle it reads, after AMD.
    Sparse { c: Csc, ldlt: Box<SparseLdlt> },
}

impl CFactor {
    /// Whether entry `(r, s)` (in `C`'s order) is stored and read.
    fn reads(&self, r: usize, s: usize) -> bool {
        match self {
            Self::Envelope(_) => r >= s,
            Self::EnvelopeLu(_) => true,
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
    ///
    /// # Errors
    /// [`KktError::Structure`] when `(r, s)` is not stored. The analysis asks
    /// only for entries of `C`'s own pattern, so this is a broken invariant
    /// of the analysis, reported instead of writing into another entry's slot.
    fn slot(&self, r: usize, s: usize) -> Result<usize, KktError> {
        let slot = match self {
            Self::Envelope(e) => e.checked_slot(r, s),
            Self::EnvelopeLu(e) => e.checked_slot(r, s),
            Self::Sparse { c, .. } => c.position(r, s),
        };
        slot.ok_or_else(|| {
            KktError::Structure(format!(
                "the Schur analysis asked for entry ({r}, {s}) of C, which its pattern does not hold"
            ))
        })
    }

    fn values_mut(&mut self) -> &mut [f64] {
        match self {
            Self::Envelope(e) => e.values_mut(),
            Self::EnvelopeLu(e) => e.values_mut(),
            Self::Sparse { c, .. } => &mut c.values,
        }
    }

    /// Factors; a zero pivot names its row of `C` (in `C`'s order).
    fn factor(&mut self) -> Result<(), KktError> {
        match self {
            Self::Envelope(e) => e
                .factor()
                .map_err(|k| KktError::Singular { unknown: Some(k) }),
            Self::EnvelopeLu(e) => e
                .factor()
                .map_err(|k| KktError::Singular { unknown: Some(k) }),
            Self::Sparse { c, ldlt } => ldlt.factor(c),
        }
    }

    fn solve_in_place(&mut self, y: &mut [f64]) {
        match self {
            Self::Envelope(e) => e.solve_in_place(y),
            Self::EnvelopeLu(e) => e.solve_in_place(y),
            Self::Sparse { ldlt, .. } => ldlt.solve_in_place(y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::analyse::csc_of;
    use super::*;

    /// The analysis asks for slots of `C`'s own entries only; an entry
    /// outside the pattern is an error, not some other entry's slot.
    #[test]
    fn an_entry_outside_the_pattern_of_c_has_no_slot() {
        let envelope = CFactor::Envelope(EnvelopeLdlt::new(&[0, 0, 1]).expect("small"));
        assert_eq!(envelope.slot(2, 1), Ok(3)); // rows hold 1, 2 and 2 values
        assert!(matches!(envelope.slot(2, 0), Err(KktError::Structure(_))));
        assert!(matches!(envelope.slot(3, 3), Err(KktError::Structure(_))));
        let mut entries = vec![(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)];
        let c = csc_of(3, &mut entries);
        let ldlt = Box::new(SparseLdlt::preordered(&c).expect("symmetric"));
        let sparse = CFactor::Sparse { c, ldlt };
        assert_eq!(sparse.slot(1, 0), Ok(1));
        assert!(matches!(sparse.slot(2, 0), Err(KktError::Structure(_))));
    }
}
