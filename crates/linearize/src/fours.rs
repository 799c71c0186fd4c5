//! A pattern's entries in fours, for products with fewer index loads.
//!
//! The Jacobians of bodies in Euler parameters are dense in each body's four
//! parameters: a pattern's entries, in the order its values are written,
//! mostly come in fours on one row and consecutive columns (a row of a
//! 4 × 4 block of `M` or `∂(M ü)/∂u`, the Euler-parameter part of a joint's
//! row of `B`). Such a four is one `(row, col)`, four contiguous values and
//! four contiguous entries of `x`: its product reads one pair of indices
//! and makes three bounds checks, where entry by entry it reads four pairs
//! and makes eight. The other entries stay entry by entry.

use mstar_model::Pattern;

/// Values `start..start + 4` on row `row`, columns `col..col + 4`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Four {
    row: u32,
    col: u32,
    start: u32,
}

/// A [`Pattern`]'s entries as fours and single entries (the same matrix:
/// the products sum the same terms, a four's terms first).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Fours {
    nrows: usize,
    ncols: usize,
    len: usize,
    fours: Vec<Four>,
    /// `(row, col, position in the values)` of the entries in no four.
    singles: Vec<(u32, u32, u32)>,
}

/// Four values from `values[start..]`.
#[inline]
fn four(values: &[f64], start: usize) -> [f64; 4] {
    let v = &values[start..start + 4];
    [v[0], v[1], v[2], v[3]]
}

impl Fours {
    /// The fours of `p` (runs of consecutive entries on one row and
    /// consecutive columns, split into fours from their start); `None` when
    /// an index does not fit in 32 bits or fewer than half the entries
    /// are in fours (then the pattern's own product is cheaper).
    pub(crate) fn new(p: &Pattern) -> Option<Self> {
        let mut fours = Vec::new();
        let mut singles = Vec::new();
        let e = &p.entries;
        let mut k = 0;
        while k < e.len() {
            let (i, j) = e[k];
            let run = (1..4)
                .take_while(|&d| e.get(k + d) == Some(&(i, j + d)))
                .count()
                + 1;
            let (row, col, start) = (
                u32::try_from(i).ok()?,
                u32::try_from(j).ok()?,
                u32::try_from(k).ok()?,
            );
            if run == 4 {
                fours.push(Four { row, col, start });
            } else {
                singles.push((row, col, start));
                k += 1;
                continue;
            }
            k += 4;
        }
        (4 * fours.len() >= singles.len()).then_some(Self {
            nrows: p.nrows,
            ncols: p.ncols,
            len: e.len(),
            fours,
            singles,
        })
    }

    /// `y ± A x` (`A` or, with `TRANSPOSE`, `Aᵀ`; subtracting with `SUB`)
    /// for the matrix `A` with these `values`.
    ///
    /// # Panics
    /// If `values`, `x` or `y` do not match the pattern's dimensions.
    pub(crate) fn product<const TRANSPOSE: bool, const SUB: bool>(
        &self,
        values: &[f64],
        x: &[f64],
        y: &mut [f64],
    ) {
        let (rows, cols) = if TRANSPOSE {
            (self.ncols, self.nrows)
        } else {
            (self.nrows, self.ncols)
        };
        assert_eq!(values.len(), self.len);
        assert_eq!(x.len(), cols);
        assert_eq!(y.len(), rows);
        let sign = if SUB { -1.0 } else { 1.0 };
        for f in &self.fours {
            let (row, col) = (f.row as usize, f.col as usize);
            let v = four(values, f.start as usize);
            if TRANSPOSE {
                let x_row = sign * x[row];
                let y = &mut y[col..col + 4];
                for (y, a) in y.iter_mut().zip(v) {
                    *y += a * x_row;
                }
            } else {
                let x = four(x, col);
                let dot = v[0] * x[0] + v[1] * x[1] + v[2] * x[2] + v[3] * x[3];
                y[row] += sign * dot;
            }
        }
        for &(i, j, k) in &self.singles {
            let (i, j) = (i as usize, j as usize);
            let (to, from) = if TRANSPOSE { (j, i) } else { (i, j) };
            y[to] += sign * (values[k as usize] * x[from]);
        }
    }

    /// `y ± (A x − C w)` with `A = m_du − g_u` and `C = g_v` on this
    /// pattern (`∂(M ü)/∂u`, `∂g/∂u` and `∂g/∂u̇` of bodies in Euler
    /// parameters, which share it), in one pass (subtracting with `SUB`).
    ///
    /// # Panics
    /// If the values, `x`, `w` or `y` do not match the pattern.
    pub(crate) fn velocity_product<const SUB: bool>(
        &self,
        [m_du, g_u, g_v]: [&[f64]; 3],
        x: &[f64],
        w: &[f64],
        y: &mut [f64],
    ) {
        for values in [m_du, g_u, g_v] {
            assert_eq!(values.len(), self.len);
        }
        assert_eq!((x.len(), w.len()), (self.ncols, self.ncols));
        assert_eq!(y.len(), self.nrows);
        let sign = if SUB { -1.0 } else { 1.0 };
        for f in &self.fours {
            let (row, col, start) = (f.row as usize, f.col as usize, f.start as usize);
            let (m, g, c) = (four(m_du, start), four(g_u, start), four(g_v, start));
            let (x, w) = (four(x, col), four(w, col));
            let mut t = 0.0;
            for k in 0..4 {
                t += (m[k] - g[k]) * x[k] - c[k] * w[k];
            }
            y[row] += sign * t;
        }
        for &(i, j, k) in &self.singles {
            let (i, j, k) = (i as usize, j as usize, k as usize);
            y[i] += sign * ((m_du[k] - g_u[k]) * x[j] - g_v[k] * w[j]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 4 block by rows, then entries in no four: a repeated one, a
    /// run of three, a row whose columns go backwards.
    fn pattern() -> Pattern {
        let mut entries: Vec<(usize, usize)> = (0..2)
            .flat_map(|i| (0..4).map(move |j| (i + 1, j + 1)))
            .collect();
        entries.extend([(1, 2), (0, 0), (0, 1), (0, 2), (4, 3), (4, 2)]);
        Pattern::from_entries(5, 5, entries)
    }

    /// `y ± A x` from the dense matrix, summed in `f64` by a loop of its own.
    fn dense_product(p: &Pattern, values: &[f64], transpose: bool, x: &[f64], y: &mut [f64]) {
        let a = p.to_dense(values);
        for (i, row) in a.iter().enumerate() {
            for (j, &a_ij) in row.iter().enumerate() {
                if transpose {
                    y[j] += a_ij * x[i];
                } else {
                    y[i] += a_ij * x[j];
                }
            }
        }
    }

    /// The fours' products are the dense matrix's, duplicates and all (the
    /// values small integers: every sum is exact).
    #[test]
    fn fours_multiply_as_their_pattern() {
        let p = pattern();
        let fours = Fours::new(&p).expect("two fours");
        assert_eq!((fours.fours.len(), fours.singles.len()), (2, 6));
        let values: Vec<f64> = (1..=14).map(f64::from).collect();
        let x = [0.5, -1.0, 2.0, 3.0, -4.0];
        for transpose in [false, true] {
            let mut expected = [0.0; 5];
            dense_product(&p, &values, transpose, &x, &mut expected);
            let (mut added, mut subtracted) = ([0.0; 5], [0.0; 5]);
            if transpose {
                fours.product::<true, false>(&values, &x, &mut added);
                fours.product::<true, true>(&values, &x, &mut subtracted);
            } else {
                fours.product::<false, false>(&values, &x, &mut added);
                fours.product::<false, true>(&values, &x, &mut subtracted);
            }
            assert_eq!(added, expected, "transposed: {transpose}");
            assert_eq!(subtracted, expected.map(|v| -v), "transposed: {transpose}");
        }
    }

    #[test]
    fn the_velocity_terms_in_one_pass() {
        let p = pattern();
        let fours = Fours::new(&p).expect("two fours");
        let m_du: Vec<f64> = (1..=14).map(f64::from).collect();
        let g_u: Vec<f64> = m_du.iter().map(|v| 2.0 * v - 3.0).collect();
        let g_v: Vec<f64> = m_du.iter().map(|v| 5.0 - v).collect();
        let (x, w) = ([0.5, -1.0, 2.0, 3.0, -4.0], [1.0, 0.25, -2.0, 0.5, 3.0]);
        let mut expected = [0.0; 5];
        let a: Vec<f64> = m_du.iter().zip(&g_u).map(|(m, g)| m - g).collect();
        let c: Vec<f64> = g_v.iter().map(|v| -v).collect();
        dense_product(&p, &a, false, &x, &mut expected);
        dense_product(&p, &c, false, &w, &mut expected);
        let mut y = [0.0; 5];
        fours.velocity_product::<false>([&m_du, &g_u, &g_v], &x, &w, &mut y);
        assert_eq!(y, expected);
        fours.velocity_product::<true>([&m_du, &g_u, &g_v], &x, &w, &mut y);
        assert_eq!(y, [0.0; 5]);
    }

    /// Mostly single entries: the pattern's own product.
    #[test]
    fn scattered_patterns_have_no_fours() {
        let p = Pattern::from_entries(3, 3, vec![(0, 0), (1, 1), (2, 2), (0, 2)]);
        assert!(Fours::new(&p).is_none());
    }
}
