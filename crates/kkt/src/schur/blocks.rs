//! One diagonal block's share of the Schur factorization: `S_K⁻¹` (dense,
//! Gauss-Jordan with partial pivoting), `W = B_K S_K⁻¹` and `C += W B_Kᵀ`
//! over the block's pairs of rows.
//!
//! Blocks of up to 4 unknowns take a path whose size is a
//! compile-time constant (the loops unroll, the block lives on the stack):
//! bodies in Euler parameters give blocks of 1 (`x`, `y`, `z`) and 4 (`p`)
//! unknowns, thousands of them per factorization. Both paths do the same
//! arithmetic in the same order, so they give the same values to the bit.

/// The largest block taking the fixed-size path ([`factor_block`]'s match).
#[cfg(test)]
const MAX_FIXED: usize = 4;

/// One entry of a block's `S` or `B`: its position in the KKT values and
/// its local row and column (for `B`, the local row of `B_K` and the local
/// unknown), in 8 bytes: a factorization reads every entry of every block,
/// and at 10³ bodies the lists are a large share of what it reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Entry {
    pos: u32,
    i: u16,
    j: u16,
}

impl Entry {
    /// The entry at KKT value position `pos`, local `(i, j)`; `None` when
    /// they do not fit in 32 and 16 bits.
    pub(super) fn new(pos: usize, i: usize, j: usize) -> Option<Self> {
        Some(Self {
            pos: u32::try_from(pos).ok()?,
            i: u16::try_from(i).ok()?,
            j: u16::try_from(j).ok()?,
        })
    }

    /// The position in the KKT values.
    #[inline]
    pub(super) fn pos(self) -> usize {
        self.pos as usize
    }

    /// The local row.
    #[inline]
    pub(super) fn i(self) -> usize {
        usize::from(self.i)
    }

    /// The local column.
    #[inline]
    pub(super) fn j(self) -> usize {
        usize::from(self.j)
    }
}

/// A block's analysed entry lists, each already cut to the block.
pub(super) struct Lists<'a> {
    /// Its `S` entries (local `i`, `j`).
    pub(super) s_entries: &'a [Entry],
    /// Its `B` entries (local row, local column).
    pub(super) b_entries: &'a [Entry],
    /// `(local row r, local row s, slot of C[r, s])`.
    pub(super) pairs: &'a [(u16, u16, u32)],
    /// Number of rows of `B` touching the block.
    pub(super) n_rows: usize,
}

/// The most rows of `B` whose `B_K` and `W` [`factor_fixed`] keeps on the
/// stack.
const STACK_ROWS: usize = 8;

/// Reused buffers: `B_K` and `W` (at least `n_rows × k` each) and, for the
/// generic path, the block (`k × k`).
pub(super) struct Scratch<'a> {
    pub(super) block: &'a mut [f64],
    pub(super) bk: &'a mut [f64],
    pub(super) w: &'a mut [f64],
}

/// Factors one block of `sizes = (k, size)`: `k` primal unknowns and
/// `size − k` local rows (their `B` entries are those of `lists.b_entries`
/// with a local row `≥ n_rows`). Writes the inverse of the saddle point
/// `[[S_K, B_lᵀ], [B_l, 0]]` (`size × size`, row-major; `S_K⁻¹` without
/// local rows) into `inverse` and adds `W B_Kᵀ` into `c_values`, `W = B_K P`
/// with `P` the inverse's leading `k × k` block (the local rows' columns of
/// `B_K` are zero).
///
/// # Errors
/// The local column without a pivot when the block is singular.
#[inline(always)]
pub(super) fn factor_block(
    sizes: (usize, usize),
    lists: &Lists<'_>,
    values: &[f64],
    inverse: &mut [f64],
    scratch: &mut Scratch<'_>,
    c_values: &mut [f64],
) -> Result<(), usize> {
    match sizes {
        (1, 1) => factor_scalar(lists, values, inverse, scratch, c_values),
        (2, 2) => factor_fixed::<2, 2>(lists, values, inverse, scratch, c_values),
        (3, 3) => factor_fixed::<3, 3>(lists, values, inverse, scratch, c_values),
        (4, 4) => factor_fixed::<4, 4>(lists, values, inverse, scratch, c_values),
        // A planar body with one, two or three rows of a joint to the
        // ground folded in (a distance; a revolute or prismatic; a weld).
        (3, 4) => factor_fixed::<3, 4>(lists, values, inverse, scratch, c_values),
        (3, 5) => factor_fixed::<3, 5>(lists, values, inverse, scratch, c_values),
        (3, 6) => factor_fixed::<3, 6>(lists, values, inverse, scratch, c_values),
        // A body in Euler parameters with its normalization row.
        (4, 5) => factor_fixed::<4, 5>(lists, values, inverse, scratch, c_values),
        (k, size) => factor_dynamic((k, size), lists, values, inverse, scratch, c_values),
    }
}

/// [`factor_block`] for one unknown (a body's `x`, `y` or `z`): `1 / s` and
/// `C += b_r (1 / s) b_s`, the arithmetic of [`factor_fixed`] for `K = 1`
/// (whose sums from `−0.0` add one term: the same values to the bit) without
/// its buffers. Inlined into the loop over the blocks with the dispatch
/// (a closed loop of planar bodies is mostly such blocks, and a call a
/// block cost about as much as its pairs, docs/performance.md).
#[inline(always)]
fn factor_scalar(
    lists: &Lists<'_>,
    values: &[f64],
    inverse: &mut [f64],
    scratch: &mut Scratch<'_>,
    c_values: &mut [f64],
) -> Result<(), usize> {
    let mut s = 0.0;
    for e in lists.s_entries {
        s += values[e.pos()];
    }
    // Gauss-Jordan's test for one unknown (`invert_fixed`).
    if s.abs() <= f64::EPSILON * s.abs() || s == 0.0 {
        return Err(0);
    }
    let inv = 1.0 / s;
    inverse[0] = inv;
    let nr = lists.n_rows;
    let mut b_stack = [0.0; STACK_ROWS];
    let b = if nr <= STACK_ROWS {
        &mut b_stack[..nr]
    } else {
        let b = &mut scratch.bk[..nr];
        b.fill(0.0);
        b
    };
    for e in lists.b_entries {
        b[e.i()] += values[e.pos()];
    }
    for &(r, s, slot) in lists.pairs {
        c_values[slot as usize] += b[usize::from(r)] * inv * b[usize::from(s)];
    }
    Ok(())
}

/// [`factor_block`] for `K` primal unknowns and `A − K` local rows.
#[inline(never)]
fn factor_fixed<const K: usize, const A: usize>(
    lists: &Lists<'_>,
    values: &[f64],
    inverse: &mut [f64],
    scratch: &mut Scratch<'_>,
    c_values: &mut [f64],
) -> Result<(), usize> {
    let nr = lists.n_rows;
    let mut a = [[0.0; A]; A];
    for e in lists.s_entries {
        a[e.i()][e.j()] += values[e.pos()];
    }
    // B_K and W on the stack when they fit (a body's blocks: 2 and 6 rows),
    // else in the scratch: no call to zero a few values.
    let (mut bk_stack, mut w_stack) = ([[0.0; K]; STACK_ROWS], [[0.0; K]; STACK_ROWS]);
    let (bk, w): (&mut [f64], &mut [f64]) = if nr <= STACK_ROWS {
        (
            &mut bk_stack.as_flattened_mut()[..nr * K],
            &mut w_stack.as_flattened_mut()[..nr * K],
        )
    } else {
        let bk = &mut scratch.bk[..nr * K];
        bk.fill(0.0);
        (bk, &mut scratch.w[..nr * K])
    };
    for e in lists.b_entries {
        let (r, j, v) = (e.i(), e.j(), values[e.pos()]);
        if r < nr {
            bk[r * K + j] += v;
        } else {
            // A local row: B_l below S_K and its mirror Bᵀ beside it.
            let l = K + r - nr;
            a[l][j] += v;
            a[j][l] += v;
        }
    }
    let mut inv = [[0.0; A]; A];
    invert_fixed(&mut a, &mut inv)?;
    for (out, row) in inverse.chunks_exact_mut(A).zip(&inv) {
        out.copy_from_slice(row);
    }
    for (wr, br) in w.chunks_exact_mut(K).zip(bk.chunks_exact(K)) {
        for l in 0..K {
            // As `Iterator::sum`: from −0.0, term by term.
            let mut acc = -0.0;
            for j in 0..K {
                acc += br[j] * inv[j][l];
            }
            wr[l] = acc;
        }
    }
    let bk: &[f64] = bk;
    for &(r, s, slot) in lists.pairs {
        let (r, s) = (usize::from(r) * K, usize::from(s) * K);
        let (wr, bs) = (&w[r..r + K], &bk[s..s + K]);
        let mut v = -0.0;
        for l in 0..K {
            v += wr[l] * bs[l];
        }
        c_values[slot as usize] += v;
    }
    Ok(())
}

#[inline(never)]
fn factor_dynamic(
    (k, size): (usize, usize),
    lists: &Lists<'_>,
    values: &[f64],
    inverse: &mut [f64],
    scratch: &mut Scratch<'_>,
    c_values: &mut [f64],
) -> Result<(), usize> {
    let nr = lists.n_rows;
    let blk = &mut scratch.block[..size * size];
    blk.fill(0.0);
    for e in lists.s_entries {
        blk[e.i() * size + e.j()] += values[e.pos()];
    }
    let bk = &mut scratch.bk[..nr * k];
    bk.fill(0.0);
    for e in lists.b_entries {
        let (r, j, v) = (e.i(), e.j(), values[e.pos()]);
        if r < nr {
            bk[r * k + j] += v;
        } else {
            let l = k + r - nr;
            blk[l * size + j] += v;
            blk[j * size + l] += v;
        }
    }
    match size {
        1..=8 => invert_padded::<8>(blk, size, inverse)?,
        9..=12 => invert_padded::<12>(blk, size, inverse)?,
        13..=16 => invert_padded::<16>(blk, size, inverse)?,
        _ => invert(blk, inverse, size)?,
    }
    let w = &mut scratch.w[..nr * k];
    // The fixed path's sums (each from −0.0, `j` ascending), row by row of
    // the inverse: contiguous slices, no index checks inside.
    for (w_row, b_row) in w.chunks_exact_mut(k).zip(bk.chunks_exact(k)) {
        w_row.fill(-0.0);
        for (b, inv_row) in b_row.iter().zip(inverse.chunks_exact(size)) {
            for (x, p) in w_row.iter_mut().zip(&inv_row[..k]) {
                *x += b * p;
            }
        }
    }
    for &(r, s, slot) in lists.pairs {
        let (r, s) = (usize::from(r) * k, usize::from(s) * k);
        let v: f64 = w[r..r + k]
            .iter()
            .zip(&bk[s..s + k])
            .map(|(x, y)| x * y)
            .sum();
        c_values[slot as usize] += v;
    }
    Ok(())
}

/// `x = S_K⁻¹ f` on the block's unknowns `coords` (`inverse` row-major;
/// with local rows, `f` and `x` include their multipliers).
#[inline]
pub(super) fn apply_block(coords: &[usize], inverse: &[f64], f: &[f64], x: &mut [f64]) {
    match coords.len() {
        1 => apply_fixed::<1>(coords, inverse, f, x),
        4 => apply_fixed::<4>(coords, inverse, f, x),
        5 => apply_fixed::<5>(coords, inverse, f, x),
        6 => apply_fixed::<6>(coords, inverse, f, x),
        k => {
            for (i, &ci) in coords.iter().enumerate() {
                let row = &inverse[i * k..(i + 1) * k];
                x[ci] = row.iter().zip(coords).map(|(a, &cj)| a * f[cj]).sum();
            }
        }
    }
}

fn apply_fixed<const K: usize>(coords: &[usize], inverse: &[f64], f: &[f64], x: &mut [f64]) {
    let fl: [f64; K] = std::array::from_fn(|j| f[coords[j]]);
    for (row, &ci) in inverse.chunks_exact(K).zip(coords) {
        let mut acc = -0.0;
        for j in 0..K {
            acc += row[j] * fl[j];
        }
        x[ci] = acc;
    }
}

/// [`invert`] of the row-major `size × size` block `blk` into `inverse`, on
/// the stack, padded to `CAP × CAP` with the identity ([`invert_leading`]):
/// loops of a constant length, the same values to the bit.
fn invert_padded<const CAP: usize>(
    blk: &[f64],
    size: usize,
    inverse: &mut [f64],
) -> Result<(), usize> {
    let mut a = [[0.0; CAP]; CAP];
    for (row, src) in a.iter_mut().zip(blk.chunks_exact(size)) {
        row[..size].copy_from_slice(src);
    }
    for (i, row) in a.iter_mut().enumerate().skip(size) {
        row[i] = 1.0;
    }
    let mut inv = [[0.0; CAP]; CAP];
    invert_leading(&mut a, &mut inv, size)?;
    for (out, row) in inverse[..size * size].chunks_exact_mut(size).zip(&inv) {
        out.copy_from_slice(&row[..size]);
    }
    Ok(())
}

/// [`invert`] for a block whose size is a constant: the same operations.
fn invert_fixed<const K: usize>(
    a: &mut [[f64; K]; K],
    inv: &mut [[f64; K]; K],
) -> Result<(), usize> {
    invert_leading(a, inv, K)
}

/// [`invert`] of the leading `n × n` block of `a`, whose rows and columns
/// beyond `n` are those of the identity (a block padded to a constant
/// size): the same values to the bit. A padding row is zero in the leading
/// columns, so it is never a pivot and is never changed; a padding column is
/// zero in the leading rows, so it stays so.
fn invert_leading<const K: usize>(
    a: &mut [[f64; K]; K],
    inv: &mut [[f64; K]; K],
    n: usize,
) -> Result<(), usize> {
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let eps = (n as f64) * f64::EPSILON;
    for col in 0..n {
        let scale = (0..K).fold(0.0f64, |s, i| s.max(a[i][col].abs()));
        let (mut p, mut best) = (col, a[col][col].abs());
        for (i, row) in a.iter().enumerate().skip(col + 1) {
            let v = row[col].abs();
            if v > best {
                (p, best) = (i, v);
            }
        }
        if best <= eps * scale || best == 0.0 {
            return Err(col);
        }
        if p != col {
            a.swap(p, col);
            inv.swap(p, col);
        }
        let d = 1.0 / a[col][col];
        for j in 0..K {
            a[col][j] *= d;
            inv[col][j] *= d;
        }
        let (pivot_a, pivot_inv) = (a[col], inv[col]);
        for i in (0..K).filter(|&i| i != col) {
            let f = a[i][col];
            if f != 0.0 {
                for j in 0..K {
                    a[i][j] -= f * pivot_a[j];
                    inv[i][j] -= f * pivot_inv[j];
                }
            }
        }
    }
    Ok(())
}

/// Inverts the row-major `k × k` matrix `a` (overwritten) into `inv` by
/// Gauss-Jordan elimination with partial pivoting; `Err(column)` when a
/// pivot is zero relative to its column.
pub(super) fn invert(a: &mut [f64], inv: &mut [f64], k: usize) -> Result<(), usize> {
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
        // Columns up to `col` of `a` are not read again (only later
        // columns pick pivots and multipliers): they are left as they are.
        for x in &mut a[col * k + col + 1..(col + 1) * k] {
            *x *= d;
        }
        for x in &mut inv[col * k..(col + 1) * k] {
            *x *= d;
        }
        eliminate(a, inv, k, col);
    }
    Ok(())
}

/// Subtracts multiples of pivot row `col` (of `a`, right of column `col`,
/// and of `inv`) from the other rows, in row order: [`invert`]'s
/// elimination, on slices split around the pivot row (no index checks in
/// the loops).
fn eliminate(a: &mut [f64], inv: &mut [f64], k: usize, col: usize) {
    let (a_above, a_rest) = a[..k * k].split_at_mut(col * k);
    let (a_pivot, a_below) = a_rest.split_at_mut(k);
    let (i_above, i_rest) = inv[..k * k].split_at_mut(col * k);
    let (i_pivot, i_below) = i_rest.split_at_mut(k);
    let rows = a_above
        .chunks_exact_mut(k)
        .chain(a_below.chunks_exact_mut(k));
    let inv_rows = i_above
        .chunks_exact_mut(k)
        .chain(i_below.chunks_exact_mut(k));
    for (row, inv_row) in rows.zip(inv_rows) {
        let f = row[col];
        if f != 0.0 {
            for (x, p) in row[col + 1..].iter_mut().zip(&a_pivot[col + 1..]) {
                *x -= f * p;
            }
            for (x, p) in inv_row.iter_mut().zip(i_pivot.iter()) {
                *x -= f * p;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(pos: usize, i: usize, j: usize) -> Entry {
        Entry::new(pos, i, j).unwrap_or_else(|| panic!("({pos}, {i}, {j}) fits"))
    }

    #[test]
    fn an_entry_that_does_not_fit_is_refused() {
        assert_eq!(entry(7, 2, 3).pos(), 7);
        assert_eq!((entry(7, 2, 3).i(), entry(7, 2, 3).j()), (2, 3));
        assert!(Entry::new(1 << 32, 0, 0).is_none());
        assert!(Entry::new(0, 1 << 16, 0).is_none());
        assert!(Entry::new(0, 0, 1 << 16).is_none());
    }

    /// A symmetric positive definite block with a pivot that needs a swap.
    fn sample(k: usize) -> Vec<f64> {
        let mut a = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                a[i * k + j] = 1.0 / (1.0 + (i + j) as f64) + if i == j { 0.5 } else { 0.0 };
            }
        }
        a[0] = 1e-3;
        a
    }

    fn both(k: usize) {
        let a = sample(k);
        let s: Vec<Entry> = (0..k * k).map(|p| entry(p, p / k, p % k)).collect();
        // Two rows of B: row 0 all ones, row 1 = 1, 2, 3, …
        let values_b: Vec<f64> = (0..2 * k)
            .map(|q| if q < k { 1.0 } else { (q - k + 1) as f64 })
            .collect();
        let mut values = a.clone();
        values.extend(&values_b);
        let b: Vec<Entry> = (0..2 * k).map(|q| entry(k * k + q, q / k, q % k)).collect();
        let pairs = [(0u16, 0u16, 0u32), (1, 0, 1), (1, 1, 2)];
        let lists = Lists {
            s_entries: &s,
            b_entries: &b,
            pairs: &pairs,
            n_rows: 2,
        };
        let run = |fixed: bool| {
            let (mut block, mut bk, mut w) = (vec![0.0; k * k], vec![0.0; 2 * k], vec![0.0; 2 * k]);
            let mut scratch = Scratch {
                block: &mut block,
                bk: &mut bk,
                w: &mut w,
            };
            let (mut inv, mut c) = (vec![0.0; k * k], vec![0.0; 3]);
            let r = if fixed {
                factor_block((k, k), &lists, &values, &mut inv, &mut scratch, &mut c)
            } else {
                factor_dynamic((k, k), &lists, &values, &mut inv, &mut scratch, &mut c)
            };
            assert_eq!(r, Ok(()));
            (inv, c)
        };
        let (inv_f, c_f) = run(true);
        let (inv_d, c_d) = run(false);
        assert_eq!(inv_f, inv_d, "k = {k}");
        assert_eq!(c_f, c_d, "k = {k}");
        // S S⁻¹ = I, independently of either path.
        for i in 0..k {
            for j in 0..k {
                let p: f64 = (0..k).map(|l| a[i * k + l] * inv_f[l * k + j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p - want).abs() < 1e-10, "k = {k}: ({i}, {j}) = {p}");
            }
        }
    }

    #[test]
    fn fixed_size_blocks_equal_the_generic_path_to_the_bit() {
        for k in 1..=MAX_FIXED {
            both(k);
        }
    }

    /// Blocks padded to 8, 12 and 16 with the identity give the values of
    /// the generic inverse, and report the same singular column.
    #[test]
    fn padded_inverses_equal_the_generic_path() {
        for n in 1..=16 {
            let a = sample(n);
            let generic = |a: &[f64]| {
                let (mut a, mut inv) = (a.to_vec(), vec![0.0; n * n]);
                invert(&mut a, &mut inv, n).map(|()| inv)
            };
            let padded = |a: &[f64]| {
                let mut inv = vec![0.0; n * n];
                match n {
                    1..=8 => invert_padded::<8>(a, n, &mut inv),
                    9..=12 => invert_padded::<12>(a, n, &mut inv),
                    _ => invert_padded::<16>(a, n, &mut inv),
                }
                .map(|()| inv)
            };
            let want = generic(&a);
            assert!(want.is_ok(), "n = {n}");
            assert_eq!(padded(&a), want, "n = {n}");
            // Row 0 repeated in the last row: singular, the same column.
            let mut singular = a.clone();
            let first: Vec<f64> = singular[..n].to_vec();
            singular[(n - 1) * n..].copy_from_slice(&first);
            let want = generic(&singular);
            assert_eq!(padded(&singular), want, "n = {n}, singular");
            assert!(n == 1 || want.is_err(), "n = {n}: {want:?}");
        }
    }

    /// A block with rows of its own (`local` of them: a body's normalization
    /// `2pᵀ`, a planar joint to the ground folded in): the fixed path gives
    /// the generic path's values to the bit, and the inverse is that of the
    /// saddle point.
    fn with_own_rows(k: usize, local: usize) {
        let size = k + local;
        let a = sample(k);
        let own = |l: usize, j: usize| f64::from(u8::from(j == l)) + 0.1 * (l + 2 * j + 1) as f64;
        let s: Vec<Entry> = (0..k * k).map(|p| entry(p, p / k, p % k)).collect();
        // Rows 0 and 1 of B go to C, rows 2.. are the block's own.
        let mut values = a.clone();
        values.extend((0..2 * k).map(|q| 1.0 + q as f64 * 0.25));
        values.extend((0..local * k).map(|q| own(q / k, q % k)));
        let rows = 2 + local;
        let b: Vec<Entry> = (0..rows * k)
            .map(|q| entry(k * k + q, q / k, q % k))
            .collect();
        let pairs = [(0u16, 0u16, 0u32), (1, 0, 1), (0, 1, 2), (1, 1, 3)];
        let lists = Lists {
            s_entries: &s,
            b_entries: &b,
            pairs: &pairs,
            n_rows: 2,
        };
        let run = |fixed: bool| {
            let mut block = vec![0.0; size * size];
            let (mut bk, mut w) = (vec![0.0; 2 * k], vec![0.0; 2 * k]);
            let mut scratch = Scratch {
                block: &mut block,
                bk: &mut bk,
                w: &mut w,
            };
            let (mut inv, mut c) = (vec![0.0; size * size], vec![0.0; 4]);
            let r = if fixed {
                factor_block((k, size), &lists, &values, &mut inv, &mut scratch, &mut c)
            } else {
                factor_dynamic((k, size), &lists, &values, &mut inv, &mut scratch, &mut c)
            };
            assert_eq!(r, Ok(()), "({k}, {size})");
            (inv, c)
        };
        let (inv_f, c_f) = run(true);
        assert_eq!(
            (&inv_f, &c_f),
            (&run(false).0, &run(false).1),
            "({k}, {size})"
        );
        // [[S, Rᵀ], [R, 0]] times the inverse is I, independently of either path.
        let saddle = |i: usize, j: usize| match (i < k, j < k) {
            (true, true) => a[i * k + j],
            (true, false) => own(j - k, i),
            (false, true) => own(i - k, j),
            (false, false) => 0.0,
        };
        for i in 0..size {
            for j in 0..size {
                let p: f64 = (0..size).map(|l| saddle(i, l) * inv_f[l * size + j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p - want).abs() < 1e-10, "({k}, {size}): ({i}, {j}) = {p}");
            }
        }
    }

    /// The fixed sizes with rows of their own: a body in Euler parameters
    /// with its normalization row, a planar body with one to three rows of
    /// a joint to the ground.
    #[test]
    fn blocks_with_their_own_rows_equal_the_generic_path_to_the_bit() {
        for (k, local) in [(4, 1), (3, 1), (3, 2), (3, 3)] {
            with_own_rows(k, local);
        }
    }

    #[test]
    fn fixed_size_inverse_reports_the_singular_column() {
        let values = [1.0, 2.0, 2.0, 4.0];
        let s = [(0, 0, 0), (1, 0, 1), (2, 1, 0), (3, 1, 1)].map(|(p, i, j)| entry(p, i, j));
        let lists = Lists {
            s_entries: &s,
            b_entries: &[],
            pairs: &[],
            n_rows: 0,
        };
        let (mut block, mut bk, mut w) = (vec![0.0; 4], Vec::new(), Vec::new());
        let mut scratch = Scratch {
            block: &mut block,
            bk: &mut bk,
            w: &mut w,
        };
        let r = factor_block(
            (2, 2),
            &lists,
            &values,
            &mut [0.0; 4],
            &mut scratch,
            &mut [],
        );
        assert_eq!(r, Err(1));
    }
}
