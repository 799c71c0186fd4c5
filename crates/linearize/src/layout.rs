//! The KKT structure of a system, built once: the system's patterns checked,
//! their union in compressed sparse columns, and the slot of every term's
//! entries in its values (eq. 16-17).

use mstar_kkt::{Csc, Structure};
use mstar_model::{Pattern, System};

use crate::LinearizeError;
use crate::csc::{Slot, from_terms};

/// A system's declared patterns, checked against its dimensions.
#[derive(Clone, Debug)]
pub(crate) struct Patterns {
    pub(crate) n: usize,
    pub(crate) m: usize,
    pub(crate) mass: Pattern,
    pub(crate) b: Pattern,
    pub(crate) hessian: Pattern,
    pub(crate) g_u: Pattern,
    pub(crate) g_v: Pattern,
    pub(crate) mass_du: Pattern,
}

impl Patterns {
    /// Reads and checks every pattern of `sys`.
    pub(crate) fn read<S: System + ?Sized>(sys: &S) -> Result<Self, LinearizeError> {
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        Ok(Self {
            n,
            m,
            mass: checked(sys.mass_pattern(), "mass", n, n)?,
            b: checked(sys.b_pattern(), "B", m, n)?,
            hessian: checked(sys.hessian_pattern(), "constraint Hessian", n, n)?,
            g_u: checked(sys.forces_du_pattern(), "∂g/∂u", n, n)?,
            g_v: checked(sys.forces_dv_pattern(), "∂g/∂u̇", n, n)?,
            mass_du: checked(sys.mass_du_pattern(), "∂(Mü)/∂u", n, n)?,
        })
    }

    /// Whether `M`'s pattern is its diagonal in order (`M ü = m ⊙ ü`).
    pub(crate) fn mass_is_diagonal(&self) -> bool {
        self.mass.len() == self.n
            && self
                .mass
                .entries
                .iter()
                .enumerate()
                .all(|(k, &(i, j))| i == k && j == k)
    }

    /// `BᵀB`: for every constraint row, all pairs `(p, q)` of its entries
    /// (positions in `B`'s values).
    pub(crate) fn bb_pairs(&self) -> Vec<(usize, usize)> {
        bb_pairs(self.m, &self.b)
    }
}

/// `BᵀB` of the `m`-row pattern `b`: for every constraint row, all pairs
/// `(p, q)` of its entries (positions in `b`'s entries), in their order
/// within the row.
/// (The entries grouped by row with a counting sort rather than a vector per
/// row: 3·10⁵ of them at 10⁵ bodies.)
pub(crate) fn bb_pairs(m: usize, b: &Pattern) -> Vec<(usize, usize)> {
    let mut start = vec![0usize; m + 1];
    for &(i, _) in &b.entries {
        start[i + 1] += 1;
    }
    for i in 0..m {
        start[i + 1] += start[i];
    }
    let mut by_row = vec![0usize; b.entries.len()];
    let mut next = start.clone();
    for (k, &(i, _)) in b.entries.iter().enumerate() {
        by_row[next[i]] = k;
        next[i] += 1;
    }
    let len = (0..m).map(|i| (start[i + 1] - start[i]).pow(2)).sum();
    let mut pairs = Vec::with_capacity(len);
    for i in 0..m {
        let row = &by_row[start[i]..start[i + 1]];
        pairs.extend(row.iter().flat_map(|&p| row.iter().map(move |&q| (p, q))));
    }
    pairs
}

/// The `(row, column)` entries of `BᵀB` for `pairs` of positions in `b`'s
/// entries.
fn bb_entries(b: &Pattern, pairs: &[(usize, usize)]) -> Vec<(usize, usize)> {
    pairs
        .iter()
        .map(|&(p, q)| (b.entries[p].1, b.entries[q].1))
        .collect()
}

fn checked(
    p: Pattern,
    matrix: &'static str,
    rows: usize,
    cols: usize,
) -> Result<Pattern, LinearizeError> {
    if p.nrows != rows || p.ncols != cols {
        return Err(LinearizeError::PatternShape {
            matrix,
            got_rows: p.nrows,
            got_cols: p.ncols,
            want_rows: rows,
            want_cols: cols,
        });
    }
    if let Some((row, col)) = p.out_of_bounds() {
        return Err(LinearizeError::PatternEntry { matrix, row, col });
    }
    Ok(p)
}

/// The slot in the KKT values of every entry of every term.
#[derive(Clone, Debug)]
pub(crate) struct KktSlots {
    pub(crate) mass: Vec<Slot>,
    pub(crate) hessian: Vec<Slot>,
    pub(crate) g_u: Vec<Slot>,
    pub(crate) g_v: Vec<Slot>,
    pub(crate) mass_du: Vec<Slot>,
    pub(crate) bb: Vec<Slot>,
    pub(crate) identity: Vec<Slot>,
    pub(crate) b: Vec<Slot>,
    pub(crate) bt: Vec<Slot>,
}

/// The KKT matrix's structure and slot maps.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    pub(crate) kkt: Csc,
    pub(crate) slots: KktSlots,
    /// The slots of every term of `S_T` (sorted, once each).
    pub(crate) s_slots: Vec<Slot>,
    /// Whether every slot of the `B` block has exactly one entry of `B`.
    pub(crate) b_slots_unique: bool,
    /// Whether every slot of `S_T` has exactly one entry of `M` (bodies in
    /// Euler parameters: the other terms fall on `M`'s blocks).
    pub(crate) mass_covers_s: bool,
    /// Whether `∂g/∂u`, `∂(M ü)/∂u` and `∂g/∂u̇` have the same slots, in
    /// the same order (assembled in one pass).
    pub(crate) velocity_terms_share_slots: bool,
    /// `BᵀB` as pairs of positions in `B`'s values: with the augmented
    /// structure from the start, else empty until [`MStar`] needs them.
    pub(crate) bb_pairs: Vec<(usize, usize)>,
    /// `M* = M + BᵀB`, built on first use (only the paper's start solves
    /// with it).
    pub(crate) m_star: Option<MStar>,
}

/// The structure of `M* = M + BᵀB` (eq. 11) and the slots of its terms.
#[derive(Clone, Debug)]
pub(crate) struct MStar {
    pub(crate) csc: Csc,
    /// The slot of each entry of `M`'s pattern.
    pub(crate) mass: Vec<usize>,
    /// The slot of each pair of [`Layout::bb_pairs`].
    pub(crate) bb: Vec<usize>,
}

impl MStar {
    /// The structure of `M + BᵀB` for `M`'s pattern `mass` and `BᵀB`'s
    /// `pairs` of positions in `b`'s entries. (Slots as `usize`: built
    /// outside the KKT structure's checks, it needs no size limit.)
    pub(crate) fn new(mass: &Pattern, b: &Pattern, pairs: &[(usize, usize)]) -> Self {
        let bb = bb_entries(b, pairs);
        let (csc, Ok(mut slots)) = from_terms::<usize>(mass.nrows, &[&mass.entries, &bb]);
        let bb_slots = slots.pop().unwrap_or_default();
        Self {
            csc,
            mass: slots.pop().unwrap_or_default(),
            bb: bb_slots,
        }
    }
}

impl Layout {
    /// The union of the patterns of `M`, the constraint Hessian, `∂g/∂u`,
    /// `∂g/∂u̇`, `∂(Mü)/∂u`, the primal diagonal, `B`, and as `structure`
    /// says `BᵀB`, `Bᵀ` and the multiplier diagonal.
    /// (`BᵀB`'s pairs only with the augmented structure, and `M*` not yet:
    /// at 10⁵ spatial bodies `BᵀB` has 6·10⁷ pairs, and building them with
    /// `M*` for every structure was half of a run's set-up and most of its
    /// memory.)
    pub(crate) fn new(p: &Patterns, structure: Structure) -> Result<Self, LinearizeError> {
        let (n, m) = (p.n, p.m);
        let bb_pairs = if structure.augmented {
            p.bb_pairs()
        } else {
            Vec::new()
        };
        let bb_entries = bb_entries(&p.b, &bb_pairs);
        let identity: Vec<(usize, usize)> = (0..n + m).map(|i| (i, i)).collect();
        let b_entries: Vec<(usize, usize)> = p.b.entries.iter().map(|&(i, j)| (n + i, j)).collect();
        let bt_entries: Vec<(usize, usize)> =
            p.b.entries.iter().map(|&(i, j)| (j, n + i)).collect();
        let (kkt, slots) = from_terms::<Slot>(
            n + m,
            &[
                &p.mass.entries,
                &p.hessian.entries,
                &p.g_u.entries,
                &p.g_v.entries,
                &p.mass_du.entries,
                &bb_entries,
                &identity[..n],
                &b_entries,
                when(structure.transpose, &bt_entries),
                // The multiplier block is zero. LDLᵀ of the augmented matrix
                // wants its diagonal in the pattern; the Schur backend forms
                // the diagonal of C itself and would only read these zeros.
                when(structure.augmented, &identity[n..]),
            ],
        );
        drop((bb_entries, identity, b_entries, bt_entries));
        let nnz = kkt.nnz();
        let slots = slots.map_err(|_| LinearizeError::TooLarge { nnz })?;
        let slots = KktSlots::from(slots);
        Ok(Self {
            kkt,
            s_slots: slots.s_terms(nnz),
            b_slots_unique: slots.b_unique(nnz),
            mass_covers_s: slots.mass_covers_s(nnz),
            velocity_terms_share_slots: slots.velocity_terms_share_slots(nnz),
            slots,
            bb_pairs,
            m_star: None,
        })
    }
}

/// `entries` when `yes`, else none.
fn when(yes: bool, entries: &[(usize, usize)]) -> &[(usize, usize)] {
    if yes { entries } else { &[] }
}

impl From<Vec<Vec<Slot>>> for KktSlots {
    /// The terms' slots in the order [`Layout::new`] lists them.
    fn from(slots: Vec<Vec<Slot>>) -> Self {
        let mut it = slots.into_iter();
        let mut next = || it.next().unwrap_or_default();
        let mut this = Self {
            mass: next(),
            hessian: next(),
            g_u: next(),
            g_v: next(),
            mass_du: next(),
            bb: next(),
            identity: next(),
            b: next(),
            bt: next(),
        };
        this.b.shrink_to_fit();
        this
    }
}

impl KktSlots {
    /// The slots of every term of `S_T`, ascending, once each (marked in
    /// a table of the `nnz` slots: linear, where sorting them took a fifth
    /// of a 10³-body model's set-up).
    fn s_terms(&self, nnz: usize) -> Vec<Slot> {
        let mut used = vec![false; nnz];
        let terms = [
            &self.mass,
            &self.hessian,
            &self.g_u,
            &self.g_v,
            &self.mass_du,
            &self.bb,
            &self.identity,
        ];
        for &s in terms.into_iter().flatten() {
            used[s as usize] = true;
        }
        // Slots fit in a `Slot` (checked when the layout was made).
        (0..nnz).filter(|&k| used[k]).map(|k| k as Slot).collect()
    }

    /// Whether every slot of `S_T`'s terms has exactly one entry of `M`.
    fn mass_covers_s(&self, nnz: usize) -> bool {
        let mut used = vec![false; nnz];
        let unique = self
            .mass
            .iter()
            .all(|&s| !std::mem::replace(&mut used[s as usize], true));
        unique && self.s_terms(nnz).iter().all(|&s| used[s as usize])
    }

    /// Whether `∂g/∂u`, `∂(M ü)/∂u` and `∂g/∂u̇` have the same slots in the
    /// same order, each once (so that one pass adds each slot's terms in
    /// the order of three).
    fn velocity_terms_share_slots(&self, nnz: usize) -> bool {
        let mut used = vec![false; nnz];
        self.g_u == self.mass_du
            && self.g_u == self.g_v
            && self
                .g_u
                .iter()
                .all(|&s| !std::mem::replace(&mut used[s as usize], true))
    }

    /// Whether every slot of the `B` block has exactly one entry of `B`.
    fn b_unique(&self, nnz: usize) -> bool {
        let mut used = vec![false; nnz];
        self.b
            .iter()
            .all(|&s| !std::mem::replace(&mut used[s as usize], true))
    }
}

#[cfg(test)]
mod tests {
    use super::Patterns;
    use mstar_model::Pattern;
    use proptest::prelude::*;

    proptest! {
        /// `BᵀB`'s pairs are, row by row, every pair of the row's entries
        /// in their order in `B`.
        #[test]
        fn bb_pairs_are_the_pairs_of_each_row(
            m in 1usize..6,
            rows in proptest::collection::vec(0usize..100, 0..30),
        ) {
            let mut b = Pattern::new(m, 4);
            b.entries = rows.iter().enumerate().map(|(k, &i)| (i % m, k % 4)).collect();
            let empty = Pattern::new(4, 4);
            let p = Patterns {
                n: 4,
                m,
                mass: empty.clone(),
                b: b.clone(),
                hessian: empty.clone(),
                g_u: empty.clone(),
                g_v: empty.clone(),
                mass_du: empty,
            };
            let mut want = Vec::new();
            for i in 0..m {
                let row: Vec<usize> = (0..b.entries.len()).filter(|&k| b.entries[k].0 == i).collect();
                for &p in &row {
                    want.extend(row.iter().map(|&q| (p, q)));
                }
            }
            prop_assert_eq!(p.bb_pairs(), want);
        }
    }
}
