//! Compressed-sparse-column structure built once from pattern entries, with a
//! map from each entry to its slot in the value array.

use mstar_kkt::Csc;

/// Builds the structure of the union of `terms` (each a list of `(row, col)`
/// entries, duplicates allowed) and returns it with, for each term, the slot of
/// each of its entries in the value array, as a `T` (an error when a slot
/// does not fit in a `T`).
pub(crate) fn from_terms<T: TryFrom<usize>>(
    n: usize,
    terms: &[&[(usize, usize)]],
) -> (Csc, Result<Vec<Vec<T>>, T::Error>) {
    // Read from the terms twice (counted, then placed), not copied into
    // one list of pairs first.
    let c = Csc::from_pairs_of(n, || {
        terms.iter().flat_map(|t| t.iter().map(|&(i, j)| (j, i)))
    });
    let slots = terms
        .iter()
        .map(|t| {
            t.iter()
                .map(|&(i, j)| {
                    // The entry is in the union by construction.
                    let col = c.column(j);
                    T::try_from(c.col_ptr[j] + col.partition_point(|&r| r < i))
                })
                .collect::<Result<Vec<T>, _>>()
        })
        .collect::<Result<Vec<_>, _>>();
    (c, slots)
}

/// A position in a value array: 32 bits halve the memory the scatters read.
pub(crate) type Slot = u32;

/// Adds `coef * values[k]` into `out[slots[k]]` for every entry of a term.
#[inline]
pub(crate) fn scatter(out: &mut [f64], slots: &[Slot], values: &[f64], coef: f64) {
    for (&s, &v) in slots.iter().zip(values) {
        out[s as usize] += coef * v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_of_terms_with_slots() {
        let t1 = [(0, 0), (1, 0), (1, 1)];
        let t2 = [(1, 0), (0, 1), (0, 0)];
        let (mut a, slots) = from_terms::<Slot>(2, &[&t1, &t2]);
        let slots = slots.expect("small");
        assert_eq!(a.col_ptr, vec![0, 2, 4]);
        assert_eq!(a.row_idx, vec![0, 1, 0, 1]);
        scatter(&mut a.values, &slots[0], &[1.0, 2.0, 3.0], 1.0);
        scatter(&mut a.values, &slots[1], &[10.0, 20.0, 30.0], 2.0);
        assert_eq!(a.to_dense(), vec![vec![61.0, 40.0], vec![22.0, 3.0]]);
        let mut y = [0.0; 2];
        a.mul(&[1.0, 1.0], &mut y);
        assert_eq!(y, [101.0, 25.0]);
    }
}
