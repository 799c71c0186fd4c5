//! Residual, constraints and the KKT iteration matrix of a [`System`] on a
//! pattern computed once (`algorithm.md` §2-4, the paper's eqs. 3-17).

use mstar_model::{Pattern, System};

use mstar_kkt::{Csc, max_abs};

use crate::csc::{Slot, from_terms, scatter};

/// Errors in a system's declared structure.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinearizeError {
    /// A declared pattern has the wrong dimensions.
    #[error("the {matrix} pattern is {got_rows}×{got_cols}, expected {want_rows}×{want_cols}")]
    PatternShape {
        /// Which matrix.
        matrix: &'static str,
        /// Declared rows.
        got_rows: usize,
        /// Declared columns.
        got_cols: usize,
        /// Expected rows.
        want_rows: usize,
        /// Expected columns.
        want_cols: usize,
    },
    /// A declared pattern has an entry outside its bounds.
    #[error("the {matrix} pattern has the entry ({row}, {col}) outside the matrix")]
    PatternEntry {
        /// Which matrix.
        matrix: &'static str,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// The KKT matrix has more entries than 32-bit positions address.
    #[error("the KKT matrix has {nnz} entries, more than 2³² − 1")]
    TooLarge {
        /// Number of entries.
        nnz: usize,
    },
}

/// The coefficients that turn the linearized equations (8)-(9) into one KKT
/// matrix (16):
///
/// ```text
/// top-left = scale·(c_u K_T + c_v C_T + c_a M + c_bb BᵀB) + c_identity I
/// [ top-left  Bᵀ ]
/// [ B         0  ]
/// ```
///
/// For the paper's Newmark scheme `c_u = 1`, `c_v = γ/(βh)`, `c_a = c_bb = 1/(βh²)`
/// (so that `c_a M + c_bb BᵀB = M*/(βh²)`, eqs. 11 and 17) and `scale = 1`.
/// `scale = 1/c_a` multiplies the equilibrium rows and divides the multipliers
/// so that the matrix's conditioning does not grow as `h → 0` (Bottasso,
/// Bauchau & Cardona 2007).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// Factor of the tangent stiffness `K_T` (eq. 6).
    pub c_u: f64,
    /// Factor of the tangent damping `C_T` (eq. 7).
    pub c_v: f64,
    /// Factor of the mass matrix `M`.
    pub c_a: f64,
    /// Factor of `BᵀB`, the augmentation `M* = M + BᵀB` (eq. 11).
    pub c_bb: f64,
    /// Factor of the identity (used by the minimum-norm position projection).
    pub c_identity: f64,
    /// Row scaling of the equilibrium equations (and inverse scaling of `Δλ`).
    pub scale: f64,
}

impl Coefficients {
    /// Only the mass matrix: `[M Bᵀ; B 0]`, the acceleration-level KKT matrix.
    #[must_use]
    pub fn acceleration() -> Self {
        Self {
            c_u: 0.0,
            c_v: 0.0,
            c_a: 1.0,
            c_bb: 0.0,
            c_identity: 0.0,
            scale: 1.0,
        }
    }

    /// Only the identity: `[I Bᵀ; B 0]`, for minimum-norm projections.
    #[must_use]
    pub fn projection() -> Self {
        Self {
            c_u: 0.0,
            c_v: 0.0,
            c_a: 0.0,
            c_bb: 0.0,
            c_identity: 1.0,
            scale: 1.0,
        }
    }
}

/// `B`'s entries by column, for `(Bᵀλ)_j = Σ_q b[pos_q] λ[row_q]` in one
/// pass that also forms the residual. In each column the entries keep the
/// order of `B`'s values, so the sums are those of a scatter over the values.
#[derive(Clone, Debug)]
struct BtGather {
    /// Column `j`'s entries are `col_ptr[j]..col_ptr[j + 1]`.
    col_ptr: Vec<u32>,
    /// `(position in B's values, row)`.
    entries: Vec<(u32, u32)>,
}

impl BtGather {
    /// `None` when the indices do not fit in 32 bits.
    fn new(b: &Pattern) -> Option<Self> {
        let mut counts = vec![0usize; b.ncols + 1];
        for &(_, j) in &b.entries {
            counts[j + 1] += 1;
        }
        for j in 0..b.ncols {
            counts[j + 1] += counts[j];
        }
        let col_ptr = counts
            .into_iter()
            .map(|c| u32::try_from(c).ok())
            .collect::<Option<Vec<u32>>>()?;
        let mut next: Vec<u32> = col_ptr[..b.ncols].to_vec();
        let mut entries = vec![(0u32, 0u32); b.entries.len()];
        for (p, &(i, j)) in b.entries.iter().enumerate() {
            entries[next[j] as usize] = (u32::try_from(p).ok()?, u32::try_from(i).ok()?);
            next[j] += 1;
        }
        Some(Self { col_ptr, entries })
    }

    /// `(Bᵀλ)_j`.
    #[inline]
    fn column(&self, j: usize, b: &[f64], lambda: &[f64]) -> f64 {
        let range = self.col_ptr[j] as usize..self.col_ptr[j + 1] as usize;
        self.entries[range]
            .iter()
            .fold(0.0, |s, &(p, i)| s + b[p as usize] * lambda[i as usize])
    }
}

/// Residual, constraints, Jacobians and the KKT matrix of one [`System`], with
/// every buffer allocated once in [`Linearization::new`].
///
/// Call [`eval_residual`](Self::eval_residual) at every Newton iteration,
/// [`eval_jacobians`](Self::eval_jacobians) and [`assemble`](Self::assemble)
/// only when the iteration matrix is to be refreshed.
#[derive(Clone, Debug)]
pub struct Linearization {
    n: usize,
    m: usize,
    augmented: bool,
    /// Whether [`assemble`](Self::assemble) fills the `Bᵀ` block.
    fill_transpose: bool,
    /// Whether `mass` holds a constant `M` already.
    mass_ready: bool,
    /// Whether `g` holds constant forces already.
    forces_ready: bool,
    /// `B`'s entries by column on 32 bits, for `Bᵀλ` (`None` if they do not
    /// fit).
    bt_gather: Option<BtGather>,
    /// Whether `M`'s pattern is its diagonal in order (`M ü = m ⊙ ü`).
    mass_diagonal: bool,
    mass_pattern: Pattern,
    b_pattern: Pattern,
    /// Values of `M` on the system's mass pattern. A constant `M`
    /// ([`System::mass_is_constant`]) is evaluated by the first
    /// [`eval_residual`](Self::eval_residual) only: pass the system the
    /// linearization was built for, and do not overwrite these values.
    pub mass: Vec<f64>,
    /// Values of `B` on the system's B pattern.
    pub b: Vec<f64>,
    /// Values of `Σ λᵢ ∂²Φᵢ/∂u²` on the system's Hessian pattern.
    pub hessian: Vec<f64>,
    /// Values of `∂g/∂u`.
    pub g_u: Vec<f64>,
    /// Values of `∂g/∂u̇`.
    pub g_v: Vec<f64>,
    /// Values of `∂(M ü)/∂u`.
    pub mass_du: Vec<f64>,
    /// Forces `g` (eq. 3). Constant forces ([`System::forces_are_constant`])
    /// are evaluated by the first [`eval_residual`](Self::eval_residual) only,
    /// like a constant `M`.
    pub g: Vec<f64>,
    /// Constraint force `Bᵀλ` (eq. 1), stored only when `B`'s indices do not
    /// fit in 32 bits (else formed in the residual's own pass).
    bt_lambda: Vec<f64>,
    /// Inertia force `M ü` for a non-diagonal `M`; empty for a diagonal one,
    /// whose `M ü` is formed in the residual's own pass and not stored.
    pub m_a: Vec<f64>,
    /// Residual `r = g − Bᵀλ − M ü` (the paper's γ, eq. 3), as the last
    /// [`eval_residual`](Self::eval_residual) formed it
    /// ([`eval_kkt_rhs`](Self::eval_kkt_rhs) writes `r` into the KKT
    /// right-hand side instead).
    pub r: Vec<f64>,
    /// Constraints `Φ` (eq. 4).
    pub phi: Vec<f64>,
    /// `max(‖g‖∞, ‖Bᵀλ‖∞, ‖M ü‖∞, ‖λ‖∞)` of the last residual evaluation.
    force_scale: f64,
    /// `‖r‖∞` of the last residual evaluation (NaN if `r` has a NaN).
    r_max: f64,
    /// `‖Φ‖∞` of the last residual evaluation.
    phi_max: f64,
    kkt: Csc,
    slots: KktSlots,
    /// The slots of every term of `S_T` (sorted, once each), and whether
    /// every slot of the `B` block has exactly one entry of `B`: then
    /// [`assemble`](Self::assemble) of the structure without `BᵀB` and `Bᵀ`
    /// zeroes these slots and assigns `B` instead of zeroing the matrix.
    s_slots: Vec<Slot>,
    b_slots_unique: bool,
    bb_pairs: Vec<(usize, usize)>,
    m_star: Csc,
    m_star_mass: Vec<Slot>,
    m_star_bb: Vec<Slot>,
    bb_values: Vec<f64>,
}

#[derive(Clone, Debug)]
struct KktSlots {
    mass: Vec<Slot>,
    hessian: Vec<Slot>,
    g_u: Vec<Slot>,
    g_v: Vec<Slot>,
    mass_du: Vec<Slot>,
    bb: Vec<Slot>,
    identity: Vec<Slot>,
    b: Vec<Slot>,
    bt: Vec<Slot>,
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

impl Linearization {
    /// Reads the system's patterns, checks them, and builds the KKT structure
    /// `[S_T Bᵀ; B 0]` (eq. 16) once: the union of the patterns of `M`, `BᵀB`,
    /// the constraint Hessian, `∂g/∂u`, `∂g/∂u̇`, `∂(Mü)/∂u`, the diagonal, `B`
    /// and `Bᵀ`.
    ///
    /// # Errors
    /// [`LinearizeError`] when a declared pattern has the wrong shape or an
    /// entry out of bounds.
    pub fn new<S: System + ?Sized>(sys: &S) -> Result<Self, LinearizeError> {
        Self::with_augmentation(sys, true)
    }

    /// As [`new`](Self::new), with (`augmented`) or without the `BᵀB` term
    /// in the KKT structure. Without it, [`assemble`](Self::assemble) ignores
    /// [`Coefficients::c_bb`] and `S_T = c_u K_T + c_v C_T + c_a M`: for bodies
    /// that interact only through constraints `S_T` is then block-diagonal,
    /// which the Schur backend of mstar-kkt exploits. Both matrices give the
    /// same `Δu`; the augmented one returns the multiplier part `Δλ + c_bb Φ`
    /// (with `scale`), the plain one `Δλ`: from the constraint rows `B Δu = −Φ`,
    /// `c_bb BᵀB Δu = −c_bb Bᵀ Φ` moves into the multipliers. Without it the
    /// multiplier block has no entries at all (it is zero): the structure is
    /// meant for mstar-kkt's Schur backend.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_augmentation<S: System + ?Sized>(
        sys: &S,
        augmented: bool,
    ) -> Result<Self, LinearizeError> {
        let n = sys.n_coords();
        let m = sys.n_constraints();
        let mass_pattern = checked(sys.mass_pattern(), "mass", n, n)?;
        let b_pattern = checked(sys.b_pattern(), "B", m, n)?;
        let hessian_pattern = checked(sys.hessian_pattern(), "constraint Hessian", n, n)?;
        let g_u_pattern = checked(sys.forces_du_pattern(), "∂g/∂u", n, n)?;
        let g_v_pattern = checked(sys.forces_dv_pattern(), "∂g/∂u̇", n, n)?;
        let mass_du_pattern = checked(sys.mass_du_pattern(), "∂(Mü)/∂u", n, n)?;

        // BᵀB: for every constraint row, all pairs of its entries.
        let mut rows: Vec<Vec<usize>> = vec![Vec::new(); m];
        for (k, &(i, _)) in b_pattern.entries.iter().enumerate() {
            rows[i].push(k);
        }
        let mut bb_pairs = Vec::new();
        for row in &rows {
            for &p in row {
                for &q in row {
                    bb_pairs.push((p, q));
                }
            }
        }
        let bb_entries: Vec<(usize, usize)> = bb_pairs
            .iter()
            .map(|&(p, q)| (b_pattern.entries[p].1, b_pattern.entries[q].1))
            .collect();
        let identity: Vec<(usize, usize)> = (0..n + m).map(|i| (i, i)).collect();
        let b_entries: Vec<(usize, usize)> =
            b_pattern.entries.iter().map(|&(i, j)| (n + i, j)).collect();
        let bt_entries: Vec<(usize, usize)> =
            b_pattern.entries.iter().map(|&(i, j)| (j, n + i)).collect();
        let no_entries = Vec::new();
        let (kkt, slots) = from_terms(
            n + m,
            &[
                &mass_pattern.entries,
                &hessian_pattern.entries,
                &g_u_pattern.entries,
                &g_v_pattern.entries,
                &mass_du_pattern.entries,
                if augmented { &bb_entries } else { &no_entries },
                &identity[..n],
                &b_entries,
                &bt_entries,
                // The multiplier block is zero. LDLᵀ of the augmented matrix
                // wants its diagonal in the pattern; the Schur backend forms
                // the diagonal of C itself and would only read these zeros
                // (at 10⁵ bodies, a pass through memory per factorization).
                if augmented {
                    &identity[n..]
                } else {
                    &no_entries
                },
            ],
        )
        .map_err(|nnz| LinearizeError::TooLarge { nnz })?;
        let mut it = slots.into_iter();
        let mut next = || it.next().unwrap_or_default();
        let mut slots = KktSlots {
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
        let mut s_slots: Vec<Slot> = [
            &slots.mass,
            &slots.hessian,
            &slots.g_u,
            &slots.g_v,
            &slots.mass_du,
            &slots.bb,
            &slots.identity,
        ]
        .into_iter()
        .flatten()
        .copied()
        .collect();
        s_slots.sort_unstable();
        s_slots.dedup();
        let mut b_sorted = slots.b.clone();
        b_sorted.sort_unstable();
        b_sorted.dedup();
        let b_slots_unique = b_sorted.len() == slots.b.len();
        slots.b.shrink_to_fit();
        let (m_star, ms) = from_terms(n, &[&mass_pattern.entries, &bb_entries])
            .map_err(|nnz| LinearizeError::TooLarge { nnz })?;
        let mut ms = ms.into_iter();
        let m_star_mass = ms.next().unwrap_or_default();
        let m_star_bb = ms.next().unwrap_or_default();
        let bt_gather = BtGather::new(&b_pattern);
        let mass_diagonal = mass_pattern.len() == n
            && mass_pattern
                .entries
                .iter()
                .enumerate()
                .all(|(k, &(i, j))| i == k && j == k);
        Ok(Self {
            n,
            m,
            augmented,
            fill_transpose: true,
            mass_ready: false,
            forces_ready: false,
            bt_lambda: if bt_gather.is_some() {
                Vec::new()
            } else {
                vec![0.0; n]
            },
            bt_gather,
            mass_diagonal,
            mass: vec![0.0; mass_pattern.len()],
            b: vec![0.0; b_pattern.len()],
            hessian: vec![0.0; hessian_pattern.len()],
            g_u: vec![0.0; g_u_pattern.len()],
            g_v: vec![0.0; g_v_pattern.len()],
            mass_du: vec![0.0; mass_du_pattern.len()],
            g: vec![0.0; n],
            m_a: if mass_diagonal {
                Vec::new()
            } else {
                vec![0.0; n]
            },
            r: vec![0.0; n],
            phi: vec![0.0; m],
            force_scale: 0.0,
            r_max: 0.0,
            phi_max: 0.0,
            bb_values: vec![0.0; bb_pairs.len()],
            mass_pattern,
            b_pattern,
            kkt,
            slots,
            s_slots,
            b_slots_unique,
            bb_pairs,
            m_star,
            m_star_mass,
            m_star_bb,
        })
    }

    /// Whether [`assemble`](Self::assemble) fills the `Bᵀ` block of the KKT
    /// matrix (default: yes). A solver that reads only `S`, `B` and the
    /// multiplier block (mstar-kkt's Schur backend) does not need it; the
    /// block then stays zero and [`kkt`](Self::kkt) is not the whole matrix.
    pub fn set_fill_transpose(&mut self, fill: bool) {
        self.fill_transpose = fill;
        if !fill {
            for &k in &self.slots.bt {
                self.kkt.values[k as usize] = 0.0;
            }
        }
    }

    /// Whether the KKT matrix carries the `BᵀB` term (see
    /// [`with_augmentation`](Self::with_augmentation)).
    #[must_use]
    pub fn augmented(&self) -> bool {
        self.augmented
    }

    /// Whether every diagonal entry of `M`, as last evaluated, is positive
    /// (necessary for a positive definite `M`).
    #[must_use]
    pub fn mass_diagonal_positive(&self) -> bool {
        let mut diag = vec![0.0; self.n];
        for (&(i, j), &v) in self.mass_pattern.entries.iter().zip(&self.mass) {
            if i == j {
                diag[i] += v;
            }
        }
        diag.iter().all(|&d| d > 0.0)
    }

    /// Number of coordinates `n`.
    #[must_use]
    pub fn n_coords(&self) -> usize {
        self.n
    }

    /// Number of constraints `m`.
    #[must_use]
    pub fn n_constraints(&self) -> usize {
        self.m
    }

    /// The system's mass pattern (for energies and products with `M`).
    #[must_use]
    pub fn mass_pattern(&self) -> &Pattern {
        &self.mass_pattern
    }

    /// The system's `B` pattern.
    #[must_use]
    pub fn b_pattern(&self) -> &Pattern {
        &self.b_pattern
    }

    /// Evaluates `M`, `B`, `g`, `Φ` and the residual `r = g − Bᵀλ − M ü` (eq. 3)
    /// at the given state.
    #[allow(clippy::too_many_arguments)]
    pub fn eval_residual<S: System + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &[f64],
        lambda: &[f64],
    ) {
        let mut r = std::mem::take(&mut self.r);
        self.residual_into(sys, t, u, v, a, lambda, 1.0, &mut r);
        self.r = r;
        self.phi_max = max_abs(&self.phi);
    }

    /// [`eval_residual`](Self::eval_residual) and [`kkt_rhs`](Self::kkt_rhs)
    /// in one: writes the right-hand side `[scale·r; −Φ]` of (16) into `rhs`
    /// as the residual is formed, without storing `r` (the field
    /// [`r`](Self::r) keeps its last value), and returns `‖rhs‖∞` (see
    /// [`kkt_rhs_norm`](Self::kkt_rhs_norm)). At 10⁵ bodies it saves a pass
    /// writing `r` and one reading it back. The norms are those of
    /// `eval_residual`.
    ///
    /// # Panics
    /// If `rhs` is not of length `n + m`.
    #[allow(clippy::too_many_arguments)]
    pub fn eval_kkt_rhs<S: System + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &[f64],
        lambda: &[f64],
        scale: f64,
        rhs: &mut [f64],
    ) -> f64 {
        assert_eq!(rhs.len(), self.n + self.m);
        let (primal, dual) = rhs.split_at_mut(self.n);
        self.residual_into(sys, t, u, v, a, lambda, scale, primal);
        // −Φ and ‖Φ‖∞ in one pass; `0 · Φᵢ` carries a NaN or an infinity.
        let (mut phi_max, mut nan) = (0.0f64, 0.0f64);
        for (x, &p) in dual.iter_mut().zip(&self.phi) {
            *x = -p;
            phi_max = if p.abs() > phi_max { p.abs() } else { phi_max };
            nan += 0.0 * p;
        }
        self.phi_max = if nan.is_nan() {
            max_abs(&self.phi)
        } else {
            phi_max
        };
        self.kkt_rhs_norm(scale)
    }

    /// `M`, `B`, `g`, `Φ` at the state, then `out = scale·r` with the force
    /// scale and `‖r‖∞` (not `‖Φ‖∞`).
    #[allow(clippy::too_many_arguments)]
    fn residual_into<S: System + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &[f64],
        lambda: &[f64],
        scale_out: f64,
        out: &mut [f64],
    ) {
        // A constant M (System::mass_is_constant) is evaluated once.
        if !(self.mass_ready && sys.mass_is_constant()) {
            sys.mass_into(t, u, &mut self.mass);
            self.mass_ready = true;
        }
        sys.phi_b_into(t, u, &mut self.phi, &mut self.b);
        if !(self.forces_ready && sys.forces_are_constant()) {
            sys.forces_into(t, u, v, &mut self.g);
            self.forces_ready = true;
        }
        if self.bt_gather.is_none() {
            self.bt_lambda.fill(0.0);
            self.b_pattern
                .mul_transpose_add(&self.b, lambda, &mut self.bt_lambda);
        }
        if !self.mass_diagonal {
            self.m_a.fill(0.0);
            self.mass_pattern.mul_add(&self.mass, a, &mut self.m_a);
        }
        // r and, in the same pass, the force scale and ‖r‖∞, with Bᵀλ (32-bit
        // indices) and M ü (diagonal M) formed on the way, not stored: at 10⁵
        // bodies every stored vector is a pass through memory.
        let (mut scale, mut r_max, mut nan) = (0.0f64, 0.0f64, 0.0f64);
        let bigger = |m: f64, x: f64| if x > m { x } else { m };
        let (b, mass, m_a, bt_lambda) = (&self.b, &self.mass, &self.m_a, &self.bt_lambda);
        let gather = self.bt_gather.as_ref();
        let diagonal = self.mass_diagonal;
        for (i, (out, &g)) in out.iter_mut().zip(&self.g).enumerate() {
            let bl = match gather {
                Some(gather) => gather.column(i, b, lambda),
                None => bt_lambda[i],
            };
            let ma = if diagonal { mass[i] * a[i] } else { m_a[i] };
            let r = g - bl - ma;
            *out = scale_out * r;
            // Plain comparisons, one per running maximum: f64::max's NaN
            // rules cost a blend each, in the loop's chain of dependences.
            let local = bigger(bigger(g.abs(), bl.abs()), ma.abs());
            scale = bigger(scale, local);
            r_max = bigger(r_max, r.abs());
            nan += 0.0 * r;
        }
        // `0 · r` is NaN for a NaN or an infinite rᵢ; f64::max drops NaNs.
        if nan.is_nan() && r_max.is_finite() {
            r_max = f64::NAN;
        }
        self.force_scale = scale.max(max_abs(lambda));
        self.r_max = r_max;
    }

    /// Evaluates the parts of `K_T` and `C_T` (eqs. 6-7): the constraint Hessian
    /// contracted with `λ`, `∂g/∂u`, `∂g/∂u̇` and `∂(M ü)/∂u`. `M` and `B` come
    /// from the last [`eval_residual`](Self::eval_residual).
    #[allow(clippy::too_many_arguments)]
    pub fn eval_jacobians<S: System + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &[f64],
        lambda: &[f64],
    ) {
        sys.hessian_into(t, u, lambda, &mut self.hessian);
        sys.forces_du_into(t, u, v, &mut self.g_u);
        sys.forces_dv_into(t, u, v, &mut self.g_v);
        sys.mass_du_into(t, u, a, &mut self.mass_du);
    }

    fn eval_bb(&mut self) {
        for (out, &(p, q)) in self.bb_values.iter_mut().zip(&self.bb_pairs) {
            *out = self.b[p] * self.b[q];
        }
    }

    /// Fills the values of the KKT matrix (16) with the given coefficients from
    /// the last evaluations:
    /// `S_T = c_u K_T + c_v C_T + c_a M + c_bb BᵀB` (eq. 17, `K_T = Σλᵢ∂²Φᵢ/∂u²
    /// − ∂g/∂u + ∂(Mü)/∂u`, `C_T = −∂g/∂u̇`), scaled by `scale`, plus
    /// `c_identity I`.
    pub fn assemble(&mut self, c: &Coefficients) {
        let c_bb = if self.augmented { c.c_bb } else { 0.0 };
        if c_bb != 0.0 {
            self.eval_bb();
        }
        let s = c.scale;
        let vals = &mut self.kkt.values;
        // Without BᵀB and the Bᵀ block (Schur backend) the matrix is the S
        // terms and B: zero the S slots and assign B, each slot of which has
        // one entry, instead of zeroing everything and adding B (fewer
        // instructions; at 10⁵ bodies the same cache lines are written, the
        // S entries sharing them with B). The Bᵀ block stays zero
        // (`set_fill_transpose(false)`).
        let assign_b = !self.fill_transpose && !self.augmented && self.b_slots_unique;
        if assign_b {
            for &k in &self.s_slots {
                vals[k as usize] = 0.0;
            }
        } else {
            vals.fill(0.0);
        }
        let sl = &self.slots;
        scatter(vals, &sl.mass, &self.mass, s * c.c_a);
        if c.c_u != 0.0 {
            scatter(vals, &sl.hessian, &self.hessian, s * c.c_u);
            scatter(vals, &sl.g_u, &self.g_u, -s * c.c_u);
            scatter(vals, &sl.mass_du, &self.mass_du, s * c.c_u);
        }
        if c.c_v != 0.0 {
            scatter(vals, &sl.g_v, &self.g_v, -s * c.c_v);
        }
        if c_bb != 0.0 {
            scatter(vals, &sl.bb, &self.bb_values, s * c_bb);
        }
        if c.c_identity != 0.0 {
            for &k in &sl.identity {
                vals[k as usize] += c.c_identity;
            }
        }
        if assign_b {
            for (&k, &v) in sl.b.iter().zip(&self.b) {
                vals[k as usize] = v;
            }
        } else {
            scatter(vals, &sl.b, &self.b, 1.0);
        }
        if self.fill_transpose {
            scatter(vals, &sl.bt, &self.b, 1.0);
        }
    }

    /// The KKT matrix (16) as last [`assemble`](Self::assemble)d; unknowns are
    /// ordered `[Δu (n); Δλ (m)]`. Its structure never changes.
    #[must_use]
    pub fn kkt(&self) -> &Csc {
        &self.kkt
    }

    /// The right-hand side of (16), `[scale·r; −Φ]`; returns its `‖·‖∞`
    /// (for [`mstar_kkt::KktSolver::solve_in_place_with_norm`]).
    ///
    /// # Panics
    /// If `rhs` is not of length `n + m`.
    pub fn kkt_rhs(&self, scale: f64, rhs: &mut [f64]) -> f64 {
        assert_eq!(rhs.len(), self.n + self.m);
        for (x, &r) in rhs[..self.n].iter_mut().zip(&self.r) {
            *x = scale * r;
        }
        for (x, &p) in rhs[self.n..].iter_mut().zip(&self.phi) {
            *x = -p;
        }
        self.kkt_rhs_norm(scale)
    }

    /// `‖[scale·r; −Φ]‖∞` from the norms of the last evaluation, exactly
    /// `max_abs` of the right-hand side: rounding is monotone, so the largest
    /// `|scale·rᵢ|` is `|scale|·‖r‖∞` rounded. NaN if `r` or `Φ` has a NaN.
    #[must_use]
    pub fn kkt_rhs_norm(&self, scale: f64) -> f64 {
        let r_part = scale.abs() * self.r_max;
        if r_part.is_nan() || self.phi_max.is_nan() {
            f64::NAN
        } else {
            r_part.max(self.phi_max)
        }
    }

    /// Fills and returns the modified mass matrix `M* = M + BᵀB` (eq. 11) from
    /// the last [`eval_residual`](Self::eval_residual).
    pub fn m_star(&mut self) -> &Csc {
        self.eval_bb();
        let vals = &mut self.m_star.values;
        vals.fill(0.0);
        scatter(vals, &self.m_star_mass, &self.mass, 1.0);
        scatter(vals, &self.m_star_bb, &self.bb_values, 1.0);
        &self.m_star
    }

    /// `‖r‖∞`, the residual norm of the last evaluation.
    #[must_use]
    pub fn residual_norm(&self) -> f64 {
        self.r_max
    }

    /// `‖Φ‖∞`, the constraint norm of the last evaluation.
    #[must_use]
    pub fn constraint_norm(&self) -> f64 {
        self.phi_max
    }

    /// The size of the forces and multipliers that balance in eq. (3):
    /// `max(‖g‖∞, ‖Bᵀλ‖∞, ‖M ü‖∞, ‖λ‖∞)`. The residual is judged relative to
    /// it: in a long chain the joint forces `λ` are far larger than their
    /// differences `Bᵀλ`, and the rotational equations cancel terms of size
    /// `|λ|·l`, so round-off and a meaningful tolerance scale with `‖λ‖`.
    #[must_use]
    pub fn force_scale(&self) -> f64 {
        self.force_scale
    }
}

#[cfg(test)]
mod tests {
    use crate::max_abs;

    #[test]
    fn max_abs_finds_the_largest_magnitude_and_non_finite_entries() {
        for len in 0usize..11 {
            let mut x: Vec<f64> = (0..len).map(|i| i as f64 * 0.5 - 2.0).collect();
            let want = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert_eq!(max_abs(&x), want, "len {len}");
            if len > 0 {
                x[len - 1] = -7.5;
                assert_eq!(max_abs(&x), 7.5);
                x[len / 2] = f64::NAN;
                assert!(max_abs(&x).is_nan(), "NaN at {} of {len}", len / 2);
                x[len / 2] = f64::NEG_INFINITY;
                assert_eq!(max_abs(&x), f64::INFINITY);
            }
        }
    }
}
