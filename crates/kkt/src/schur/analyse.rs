//! The Schur backend's symbolic analysis, step by step: the blocks of `S`
//! (connected components of its pattern), the pattern of `C = B S⁻¹ Bᵀ − D`,
//! how `C` is factored (envelope or AMD), the slots every block writes in `C`,
//! and `B` by primal column.

use super::blocks::Entry;
use super::{Block, CFactor, FILL_SLACK, MAX_BLOCK, Schur, Symmetry};
use crate::envelope::EnvelopeLdlt;
use crate::envelope_lu::EnvelopeLu;
use crate::sparse_ldlt::{SparseLdlt, is_symmetric_structure, kkt_ordering};
use crate::{Csc, KktError};

/// The block structure of `S` and each block's rows of `B`.
pub(super) struct Parts {
    pub(super) blocks: Vec<Block>,
    /// Unknowns of all blocks, block after block.
    pub(super) coords: Vec<usize>,
    /// Every block's `S` entries (local `i`, `j`).
    pub(super) s_entries: Vec<Entry>,
    /// Every block's `B` entries (local row, local column).
    pub(super) b_entries: Vec<Entry>,
    /// Each block's rows (original constraint indices), block after block:
    /// the rows that stay in `C` (those of other blocks too).
    pub(super) rows: Vec<usize>,
    /// Whether each constraint row is local to a block (absorbed into it:
    /// see [`local_candidates`]) rather than a row of `C`.
    pub(super) local: Vec<bool>,
    /// Total size of the blocks' dense inverses, the largest block and the
    /// most rows a block touches (scratch sizes).
    pub(super) inverse_len: usize,
    pub(super) max_k: usize,
    pub(super) max_rows: usize,
}

/// [`Parts::gather`]'s buffers, reused block after block (one allocation
/// for all blocks, not one each).
struct Scratch {
    /// Each constraint row's local row in the block being gathered, or
    /// `usize::MAX`.
    row_local: Vec<usize>,
    /// The rows local to the block being gathered.
    own: Vec<usize>,
}

/// `B` by primal column (column `j`'s entries are `col_ptr[j]..col_ptr[j + 1]`):
/// each entry's row in `C`'s order and its position in the KKT values, on 32
/// bits and apart (the solve reads the rows only).
pub(super) struct BColumns {
    pub(super) col_ptr: Vec<u32>,
    pub(super) rows: Vec<u32>,
    pub(super) pos: Vec<u32>,
    /// Each entry's row in the constraints' own order.
    pub(super) orig: Vec<u32>,
}

/// How `C` is factored and its order: `fwd[k]` is the constraint in position
/// `k`, `inv` the inverse.
pub(super) struct COrder {
    pub(super) fwd: Vec<usize>,
    pub(super) inv: Vec<usize>,
    pub(super) factor: CFactor,
}

impl Schur {
    /// Analyses `a` (values ignored) whose first `n_primal` unknowns are primal.
    ///
    /// # Errors
    /// [`KktError::Structure`] when a diagonal block of `S` has more than
    /// [`MAX_BLOCK`] unknowns, touches more than `u16::MAX` rows, or the
    /// structure is too large for 32-bit indices.
    pub(crate) fn new(a: &Csc, n_primal: usize) -> Result<Self, KktError> {
        Self::with_symmetry(a, n_primal, Symmetry::Symmetric)
    }

    /// [`new`](Self::new) for symmetric `S` and `D` ([`Symmetry::Symmetric`],
    /// `C` by LDLᵀ) or any values on `a`'s pattern ([`Symmetry::General`],
    /// `C` by LU on its envelope in the constraints' own order).
    ///
    /// # Errors
    /// As [`new`](Self::new); with [`Symmetry::General`] also when `C`'s
    /// envelope in the constraints' own order is wider than `FILL_SLACK`
    /// times the factor AMD gives (the LU has no sparse fallback).
    pub(crate) fn with_symmetry(
        a: &Csc,
        n_primal: usize,
        symmetry: Symmetry,
    ) -> Result<Self, KktError> {
        let n = n_primal;
        let m = a.n - n;
        // Every entry of the multiplier block D: (KKT value position, row, column).
        let d_all: Vec<(usize, usize, usize)> = (n..a.n)
            .flat_map(|j| (a.col_ptr[j]..a.col_ptr[j + 1]).map(move |p| (p, j)))
            .filter(|&(p, _)| a.row_idx[p] >= n)
            .map(|(p, j)| (p, a.row_idx[p] - n, j - n))
            .collect();
        let members = components(a, n);
        let candidates = local_candidates(a, n, &members, &d_all);
        let mut parts = Parts::gather(a, n, &members, &candidates)?;
        let order = COrder::choose(&parts, &d_all, m, symmetry)?;
        let pairs = pair_slots(&mut parts, &order)?;
        let b = BColumns::new(a, n, &order.inv)?;
        let mut schur = Self::from_parts(a.n, parts, order, pairs, d_all, b)?;
        if symmetry == Symmetry::General {
            schur.refine = true;
            (schur.refine_b, schur.refine_r) = (vec![0.0; a.n], vec![0.0; a.n]);
        }
        Ok(schur)
    }

    /// The backend from its analysed parts, with its buffers.
    fn from_parts(
        dim: usize,
        parts: Parts,
        order: COrder,
        pairs: Vec<(u16, u16, u32)>,
        d_all: Vec<(usize, usize, usize)>,
        b: BColumns,
    ) -> Result<Self, KktError> {
        let n = parts.blocks.iter().map(|b| b.k).sum::<usize>();
        let m = dim - n;
        let m_c = parts.local.iter().filter(|&&l| !l).count();
        // Index in `d_all` of each entry of D in the read triangle, and its slot.
        let d_entries = d_all
            .iter()
            .enumerate()
            .filter(|&(_, &(_, r, s))| order.factor.reads(order.inv[r], order.inv[s]))
            .map(|(k, &(_, r, s))| Ok((k, order.factor.slot(order.inv[r], order.inv[s])?)))
            .collect::<Result<_, KktError>>()?;
        // S diagonal: every block one unknown, in order, with one S entry.
        let diagonal = parts.coords.iter().enumerate().all(|(i, &c)| i == c)
            && parts
                .blocks
                .iter()
                .all(|b| b.coords.len() == 1 && b.s_entries.len() == 1);
        let natural = order.fwd.iter().enumerate().all(|(k, &r)| k == r);
        let banded = diagonal && matches!(order.factor, CFactor::Envelope(_));
        // The one-pass factorization of a chain (or of a closed loop in the
        // reverse Cuthill–McKee order) computes C's slots from the envelope:
        // no table of pairs (8 bytes a pair, about 20 pairs a bar).
        let (diag_s, pair_ptr, pairs) = match (diagonal, banded) {
            (false, _) => (Vec::new(), Vec::new(), pairs),
            (true, banded) => (
                parts
                    .blocks
                    .iter()
                    .map(|b| parts.s_entries[b.s_entries.start].pos())
                    .collect(),
                if banded {
                    Vec::new()
                } else {
                    std::iter::once(0)
                        .chain(parts.blocks.iter().map(|b| b.pairs.end))
                        .collect()
                },
                if banded { Vec::new() } else { pairs },
            ),
        };
        let s_global = if diagonal {
            Vec::new()
        } else {
            global_s(&parts.blocks, &parts.coords, &parts.s_entries)?
        };
        Ok(Self {
            banded,
            norm: None,
            n_primal: n,
            diagonal,
            diag_s,
            pair_ptr,
            pairs,
            d_entries,
            s_values: vec![0.0; parts.s_entries.len()],
            d_values: vec![0.0; d_all.len()],
            d_all,
            inverse: vec![0.0; parts.inverse_len],
            cf: order.factor,
            c_inv: order.inv,
            c_fwd: order.fwd,
            block: vec![0.0; parts.max_k * parts.max_k],
            bk: vec![0.0; parts.max_rows * parts.max_k],
            w: vec![0.0; parts.max_rows * parts.max_k],
            x: vec![0.0; dim],
            y: vec![0.0; m],
            g_ordered: if diagonal && !natural {
                vec![0.0; m]
            } else {
                Vec::new()
            },
            m_c,
            b_values: vec![0.0; b.rows.len()],
            natural,
            row_sums: vec![0.0; dim],
            b_col_ptr: b.col_ptr,
            b_orig: if natural { Vec::new() } else { b.orig },
            b_rows: b.rows,
            b_pos: b.pos,
            refine: false,
            refine_b: Vec::new(),
            refine_r: Vec::new(),
            blocks: parts.blocks,
            coords: parts.coords,
            s_global,
            s_entries: parts.s_entries,
            b_entries: parts.b_entries,
        })
    }
}

/// The connected components of the pattern of `S` (entries `(i, j)` with
/// `i, j < n`), each sorted, in the order of their smallest unknown.
fn components(a: &Csc, n: usize) -> Vec<Vec<usize>> {
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut parent: Vec<usize> = (0..n).collect();
    for j in 0..n {
        for &i in a.column(j) {
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
    members.retain(|g| !g.is_empty());
    members
}

/// The constraint rows that may join a block of `S` (`candidates[r]`): every
/// `B` entry of row `r` lies in one block, and `D` has no entry in its row or
/// column. Such a row (a body's normalization `pᵀp = 1`) is eliminated with
/// its block: the block becomes the saddle point `[[S_K, B_rᵀ], [B_r, 0]]`,
/// inverted densely, and `C` keeps only the rows that join blocks.
fn local_candidates(
    a: &Csc,
    n: usize,
    members: &[Vec<usize>],
    d_all: &[(usize, usize, usize)],
) -> Vec<bool> {
    const NONE: usize = usize::MAX;
    const MANY: usize = usize::MAX - 1;
    let m = a.n - n;
    let mut block_of = vec![0usize; n];
    for (b, group) in members.iter().enumerate() {
        for &i in group {
            block_of[i] = b;
        }
    }
    // The block of each row's B entries: NONE yet, MANY when they differ.
    let mut row_block = vec![NONE; m];
    for j in 0..n {
        for &i in a.column(j) {
            if i >= n {
                let rb = &mut row_block[i - n];
                *rb = match *rb {
                    NONE => block_of[j],
                    b if b == block_of[j] => b,
                    _ => MANY,
                };
            }
        }
    }
    for &(_, r, s) in d_all {
        row_block[r] = MANY;
        row_block[s] = MANY;
    }
    row_block.iter().map(|&b| b < MANY).collect()
}

impl Parts {
    /// The blocks of the given components with their `S` entries and rows of
    /// `B` (rows ascending, then local indices: for one unknown, the order of
    /// its column's `B` entries). A block takes the rows local to it
    /// (`candidates`) as long as it stays within [`MAX_BLOCK`] unknowns.
    fn gather(
        a: &Csc,
        n: usize,
        members: &[Vec<usize>],
        candidates: &[bool],
    ) -> Result<Self, KktError> {
        let m = a.n - n;
        let mut local = vec![0usize; n];
        let mut scratch = Scratch {
            row_local: vec![usize::MAX; m],
            own: Vec::new(),
        };
        let mut this = Self {
            blocks: Vec::new(),
            coords: Vec::with_capacity(n),
            s_entries: Vec::new(),
            b_entries: Vec::new(),
            rows: Vec::new(),
            local: vec![false; m],
            inverse_len: 0,
            max_k: 0,
            max_rows: 0,
        };
        for group in members {
            let k = group.len();
            if k > MAX_BLOCK {
                return Err(KktError::Structure(format!(
                    "the Schur backend needs a block-diagonal S with blocks of at most {MAX_BLOCK} unknowns; unknowns {}, {}, … form a block of {k}",
                    group[0], group[1]
                )));
            }
            for (l, &i) in group.iter().enumerate() {
                local[i] = l;
            }
            this.push_block(a, n, group, &local, candidates, &mut scratch)?;
        }
        if this.max_rows > usize::from(u16::MAX) {
            return Err(KktError::Structure(format!(
                "a block of S touches {} constraint rows; the Schur backend takes at most {}",
                this.max_rows,
                u16::MAX
            )));
        }
        Ok(this)
    }

    /// Appends the block of the unknowns `group` (`local` their local
    /// indices; `scratch.row_local` is `usize::MAX` everywhere on entry and
    /// exit):
    /// its rows of `C` get local rows `0..n_rows`, its own rows (`candidates`,
    /// while the block stays within [`MAX_BLOCK`]) the local rows after them
    /// and the block's unknowns `n + r` after its primal ones.
    fn push_block(
        &mut self,
        a: &Csc,
        n: usize,
        group: &[usize],
        local: &[usize],
        candidates: &[bool],
        scratch: &mut Scratch,
    ) -> Result<(), KktError> {
        let Scratch { row_local, own } = scratch;
        own.clear();
        let (c0, s0, b0, r0) = (
            self.coords.len(),
            self.s_entries.len(),
            self.b_entries.len(),
            self.rows.len(),
        );
        self.coords.extend_from_slice(group);
        for &j in group {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i < n {
                    self.s_entries.push(entry(p, local[i], local[j])?);
                } else if row_local[i - n] == usize::MAX {
                    row_local[i - n] = 0;
                    if candidates[i - n] {
                        own.push(i - n);
                    } else {
                        self.rows.push(i - n);
                    }
                }
            }
        }
        self.rows[r0..].sort_unstable();
        own.sort_unstable();
        // Rows beyond MAX_BLOCK unknowns stay rows of C, and so do the rows
        // of a single unknown (which keeps a diagonal S on its fast paths).
        let keep = if group.len() < 2 {
            0
        } else {
            own.len().min(MAX_BLOCK - group.len())
        };
        self.rows.extend_from_slice(&own[keep..]);
        own.truncate(keep);
        self.rows[r0..].sort_unstable();
        let n_rows = self.rows.len() - r0;
        for (l, &r) in self.rows[r0..].iter().chain(own.iter()).enumerate() {
            row_local[r] = l;
        }
        for &r in own.iter() {
            self.local[r] = true;
            self.coords.push(n + r);
        }
        for &j in group {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i >= n {
                    self.b_entries.push(entry(p, row_local[i - n], local[j])?);
                }
            }
        }
        for &r in self.rows[r0..].iter().chain(own.iter()) {
            row_local[r] = usize::MAX;
        }
        let size = self.coords.len() - c0;
        self.blocks.push(Block {
            coords: c0..self.coords.len(),
            k: group.len(),
            s_entries: s0..self.s_entries.len(),
            b_entries: b0..self.b_entries.len(),
            rows: r0..self.rows.len(),
            n_rows,
            inverse: self.inverse_len,
            pairs: 0..0,
        });
        self.inverse_len += size * size;
        self.max_k = self.max_k.max(size);
        self.max_rows = self.max_rows.max(n_rows);
        Ok(())
    }
}

impl COrder {
    /// `C`'s pattern is every block's row pairs, `D`'s entries and the
    /// diagonal. It is factored by its envelope when that is at most
    /// `FILL_SLACK` times the factor AMD gives, in the constraints' own order
    /// (a chain's joints in order: a band of width 3, factored and solved in
    /// sequential passes) or else in the reverse Cuthill–McKee order (a
    /// closed loop's rows brought together: the N-four-bar's `C` in a band),
    /// else by faer's sparse LDLᵀ after AMD, on the one triangle it reads
    /// (faer then factors it in place). With [`Symmetry::General`] the
    /// envelope is factored by LU on both triangles, and there is no
    /// fallback: a wider envelope is an error.
    ///
    /// Rows local to a block ([`Parts::local`]) are not rows of `C`: `C`'s
    /// rows are the others in their own order, and the local rows follow
    /// them in the multipliers' order (`inv[r] ≥ C`'s dimension).
    fn choose(
        parts: &Parts,
        d_all: &[(usize, usize, usize)],
        m: usize,
        symmetry: Symmetry,
    ) -> Result<Self, KktError> {
        // compact[r]: row r's index among the rows of C (MAX for a local row).
        let mut compact = vec![usize::MAX; m];
        let mut m_c = 0;
        for (c, _) in compact.iter_mut().zip(&parts.local).filter(|(_, l)| !**l) {
            *c = m_c;
            m_c += 1;
        }
        let c_order = Self::choose_compact(parts, d_all, &compact, m_c, symmetry)?;
        let mut inv = vec![0; m];
        let mut next_local = m_c;
        for (r, slot) in inv.iter_mut().enumerate() {
            *slot = if parts.local[r] {
                next_local += 1;
                next_local - 1
            } else {
                c_order.inv[compact[r]]
            };
        }
        let mut fwd = vec![0; m];
        for (r, &k) in inv.iter().enumerate() {
            fwd[k] = r;
        }
        Ok(Self {
            fwd,
            inv,
            factor: c_order.factor,
        })
    }

    /// [`choose`](Self::choose) on the `m_c` rows of `C` (row `r`'s index
    /// among them `compact[r]`): the order and factor of `C` alone.
    fn choose_compact(
        parts: &Parts,
        d_all: &[(usize, usize, usize)],
        compact: &[usize],
        m: usize,
        symmetry: Symmetry,
    ) -> Result<Self, KktError> {
        // Sized at once: grown pair by pair, its copies took a tenth of
        // the analysis at 10⁵ bodies.
        let pairs: usize = parts.blocks.iter().map(|b| b.rows.len().pow(2)).sum();
        let mut pattern: Vec<(usize, usize)> = Vec::with_capacity(pairs + d_all.len() + m);
        for b in &parts.blocks {
            let rows = &parts.rows[b.rows.clone()];
            for &r in rows {
                for &s in rows {
                    pattern.push((compact[s], compact[r]));
                }
            }
        }
        // D's rows are never local (`local_candidates`).
        pattern.extend(d_all.iter().map(|&(_, r, s)| (compact[s], compact[r])));
        pattern.extend((0..m).map(|r| (r, r)));
        // csc_of sorts and deduplicates `pattern`: it is C's entry list.
        let c_orig = csc_of(m, &mut pattern);
        // Every factor of C in any order stores at least C's lower triangle
        // (fill only adds entries, and for a symmetric pattern the
        // triangle's size does not depend on the order): an envelope within
        // FILL_SLACK of it is within FILL_SLACK of AMD's factor, and the
        // AMD analysis would only confirm the envelope. (On a chain of 10⁵
        // bodies that analysis was two thirds of the Schur set-up.)
        let mut envelopes = Envelopes::new(&c_orig);
        let surely = if is_symmetric_structure(&c_orig) {
            FILL_SLACK * lower_len(&c_orig) as f64
        } else {
            0.0
        };
        if let Some(this) = envelopes
            .within(surely)
            .and_then(|o| Self::envelope(o, symmetry))
        {
            return Ok(this);
        }
        let (fwd, inv) = kkt_ordering(&c_orig, m, Default::default())?;
        let mut permuted: Vec<(usize, usize)> =
            pattern.iter().map(|&(s, r)| (inv[s], inv[r])).collect();
        let c_amd = csc_of(m, &mut permuted);
        let amd = SparseLdlt::preordered(&c_amd)?;
        let limit = FILL_SLACK * amd.factor_len() as f64;
        if let Some(this) = envelopes
            .within(limit)
            .and_then(|o| Self::envelope(o, symmetry))
        {
            return Ok(this);
        }
        if symmetry == Symmetry::General {
            return Err(KktError::Structure(
                "the schur-lu backend factors C = B S⁻¹ Bᵀ by its envelope, in the constraints' own \
                 order or the reverse Cuthill–McKee order, and both are too wide (use lu)"
                    .to_string(),
            ));
        }
        Ok(Self {
            fwd,
            inv,
            factor: sparse_c_factor(c_amd, amd)?,
        })
    }

    /// `C` factored on its envelope in `order`, by LDLᵀ or LU as `symmetry`
    /// says; `None` beyond 32-bit row pointers.
    fn envelope(order: EnvelopeOrder, symmetry: Symmetry) -> Option<Self> {
        let factor = match symmetry {
            Symmetry::Symmetric => CFactor::Envelope(EnvelopeLdlt::new(&order.first)?),
            Symmetry::General => CFactor::EnvelopeLu(EnvelopeLu::new(&order.first)?),
        };
        Some(Self {
            fwd: order.fwd,
            inv: order.inv,
            factor,
        })
    }
}

/// The number of entries of `c` on or below the diagonal.
fn lower_len(c: &Csc) -> usize {
    (0..c.n)
        .map(|j| {
            let col = c.column(j);
            col.len() - col.partition_point(|&i| i < j)
        })
        .sum()
}

/// An order of `C` and the first stored column of each of its rows there.
#[derive(Clone)]
struct EnvelopeOrder {
    fwd: Vec<usize>,
    inv: Vec<usize>,
    first: Vec<usize>,
}

impl EnvelopeOrder {
    /// `c`'s rows in the order `fwd`.
    fn of(c: &Csc, fwd: Vec<usize>) -> Self {
        let mut inv = vec![0; fwd.len()];
        for (k, &r) in fwd.iter().enumerate() {
            inv[r] = k;
        }
        let first = (0..fwd.len())
            .map(|k| {
                let rows = c.column(fwd[k]).iter().map(|&r| inv[r]);
                rows.min().unwrap_or(k).min(k)
            })
            .collect();
        Self { fwd, inv, first }
    }

    /// The envelope's size: row `k` holds columns `first[k] ..= k`.
    fn size(&self) -> usize {
        self.first.iter().enumerate().map(|(k, &f)| k - f + 1).sum()
    }
}

/// The orders tried for `C`'s envelope, in turn: the constraints' own (a
/// chain's), then the reverse Cuthill–McKee order (a closed loop's rows
/// brought together; `crate::rcm`), made when first asked for.
struct Envelopes<'c> {
    c: &'c Csc,
    own: EnvelopeOrder,
    rcm: Option<EnvelopeOrder>,
}

impl<'c> Envelopes<'c> {
    fn new(c: &'c Csc) -> Self {
        Self {
            c,
            own: EnvelopeOrder::of(c, (0..c.n).collect()),
            rcm: None,
        }
    }

    /// The first order whose envelope holds at most `limit` values.
    fn within(&mut self, limit: f64) -> Option<EnvelopeOrder> {
        if self.own.size() as f64 <= limit {
            return Some(self.own.clone());
        }
        let c = self.c;
        let rcm = self
            .rcm
            .get_or_insert_with(|| EnvelopeOrder::of(c, crate::rcm::reverse_cuthill_mckee(c)));
        (rcm.size() as f64 <= limit).then(|| rcm.clone())
    }
}

/// `C` (stored with both triangles, in AMD order) factored by faer, on the one
/// triangle its kernel reads when faer agrees to take only that one.
fn sparse_c_factor(c_amd: Csc, amd: SparseLdlt) -> Result<CFactor, KktError> {
    let m = c_amd.n;
    let upper = amd.reads_upper();
    // Sized for a symmetric pattern's triangle at once.
    let mut triangle: Vec<(usize, usize)> = Vec::with_capacity(c_amd.nnz().div_ceil(2) + m);
    triangle.extend(
        (0..m)
            .flat_map(|s| c_amd.column(s).iter().map(move |&r| (s, r)))
            .filter(|&(s, r)| if upper { r <= s } else { r >= s }),
    );
    let c_tri = csc_of(m, &mut triangle);
    Ok(match SparseLdlt::preordered_triangle(&c_tri, upper)? {
        Some(ldlt) => CFactor::Sparse {
            c: c_tri,
            ldlt: Box::new(ldlt),
        },
        None => CFactor::Sparse {
            c: c_amd,
            ldlt: Box::new(amd),
        },
    })
}

/// Every block's contributions to `C`: `(local row, local row, slot in C)`
/// for the pairs in the triangle the factorization reads; sets each block's
/// range of pairs.
fn pair_slots(parts: &mut Parts, order: &COrder) -> Result<Vec<(u16, u16, u32)>, KktError> {
    let mut pairs = Vec::new();
    for b in &mut parts.blocks {
        let start = pairs.len();
        let rows = &parts.rows[b.rows.clone()];
        for (lr, &r) in rows.iter().enumerate() {
            for (ls, &s) in rows.iter().enumerate() {
                let (pr, ps) = (order.inv[r], order.inv[s]);
                if order.factor.reads(pr, ps) {
                    let at = u32::try_from(order.factor.slot(pr, ps)?).map_err(|_| {
                        KktError::Structure("C has more than 2³² entries".to_string())
                    })?;
                    // Lossless: both below max_rows ≤ u16::MAX (Parts::gather).
                    pairs.push((lr as u16, ls as u16, at));
                }
            }
        }
        b.pairs = start..pairs.len();
    }
    Ok(pairs)
}

impl BColumns {
    /// `B`'s entries of `a` by primal column, rows in `C`'s order (`c_inv`).
    fn new(a: &Csc, n: usize, c_inv: &[usize]) -> Result<Self, KktError> {
        let fits = |x: usize| {
            u32::try_from(x).map_err(|_| {
                KktError::Structure(
                    "the Schur backend indexes the KKT entries with 32 bits".to_string(),
                )
            })
        };
        let (mut col_ptr, mut rows, mut pos) = (vec![0; n + 1], Vec::new(), Vec::new());
        let mut orig = Vec::new();
        for j in 0..n {
            for p in a.col_ptr[j]..a.col_ptr[j + 1] {
                let i = a.row_idx[p];
                if i >= n {
                    rows.push(fits(c_inv[i - n])?);
                    orig.push(fits(i - n)?);
                    pos.push(fits(p)?);
                }
            }
            col_ptr[j + 1] = fits(rows.len())?;
        }
        Ok(Self {
            col_ptr,
            rows,
            pos,
            orig,
        })
    }
}

/// A block's entry (KKT value position, local row, local column), or the
/// error of a structure beyond the 32-bit positions and 16-bit local rows
/// the lists keep.
fn entry(pos: usize, i: usize, j: usize) -> Result<Entry, KktError> {
    Entry::new(pos, i, j).ok_or_else(|| {
        KktError::Structure(format!(
            "a block of S has an entry at KKT position {pos}, local row {i}: the Schur backend takes at most 2³² positions and {} rows a block",
            u16::MAX
        ))
    })
}

/// The `n × n` CSC pattern of the `(column, row)` pairs (sorted and
/// deduplicated in place), values zero.
pub(super) fn csc_of(n: usize, pairs: &mut Vec<(usize, usize)>) -> Csc {
    let c = Csc::from_pairs(n, pairs);
    pairs.clear();
    pairs.extend((0..n).flat_map(|j| c.column(j).iter().map(move |&i| (j, i))));
    c
}

/// Every block's `S` entries as global `(row, column)`, in `s_entries`'
/// order ([`Schur`]'s `s_global`).
///
/// # Errors
/// [`KktError::Structure`] for an unknown beyond `u32` (not reached by a
/// matrix whose pattern fits in memory).
fn global_s(
    blocks: &[Block],
    coords: &[usize],
    s_entries: &[Entry],
) -> Result<Vec<(u32, u32)>, KktError> {
    let wide = || KktError::Structure("more than 2³² unknowns".to_string());
    let mut out = Vec::with_capacity(s_entries.len());
    for b in blocks {
        let local = &coords[b.coords.clone()];
        for e in &s_entries[b.s_entries.clone()] {
            let (i, j) = (u32::try_from(local[e.i()]), u32::try_from(local[e.j()]));
            out.push((i.map_err(|_| wide())?, j.map_err(|_| wide())?));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{csc_of, is_symmetric_structure, kkt_ordering, lower_len};
    use crate::Csc;
    use crate::sparse_ldlt::SparseLdlt;
    use proptest::prelude::*;

    proptest! {
        /// What lets `COrder::choose` keep an envelope without AMD: the
        /// factor AMD gives stores at least the lower triangle of `C`
        /// (counted here by brute force over the pairs).
        #[test]
        fn amd_factor_holds_the_lower_triangle(
            m in 1usize..40,
            offdiag in proptest::collection::vec((0usize..40, 0usize..40), 0..120),
        ) {
            let mut pattern: Vec<(usize, usize)> = (0..m).map(|i| (i, i)).collect();
            for &(i, j) in &offdiag {
                let (i, j) = (i % m, j % m);
                pattern.extend([(i, j), (j, i)]);
            }
            let mut distinct = pattern.clone();
            distinct.sort_unstable();
            distinct.dedup();
            let want_lower = distinct.iter().filter(|&&(j, i)| i >= j).count();
            let c = csc_of(m, &mut pattern);
            prop_assert!(is_symmetric_structure(&c));
            prop_assert_eq!(lower_len(&c), want_lower);
            let (_, inv) = kkt_ordering(&c, m, Default::default()).expect("valid");
            let mut permuted: Vec<(usize, usize)> =
                pattern.iter().map(|&(s, r)| (inv[s], inv[r])).collect();
            let c_amd: Csc = csc_of(m, &mut permuted);
            let amd = SparseLdlt::preordered(&c_amd).expect("symmetric");
            prop_assert!(amd.factor_len() >= want_lower, "{} < {want_lower}", amd.factor_len());
        }
    }
}
