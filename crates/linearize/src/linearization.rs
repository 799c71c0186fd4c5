//! Residual, constraints and the KKT iteration matrix of a [`System`] on a
//! pattern computed once (`algorithm.md` §2-4, the paper's eqs. 3-17).

use mstar_model::{Pattern, StateRef, System};

use mstar_kkt::{Csc, MaxAbs, Structure, max_abs};

use crate::csc::scatter;
use crate::fours::Fours;
use crate::layout::{Layout, MStar, Patterns, bb_pairs};

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

/// The patterns of `M`, `B` and the tangent's four terms as [`Fours`]
/// (`None` where few entries come in fours: the pattern's own product).
#[derive(Clone, Debug)]
struct PatternFours {
    mass: Option<Fours>,
    b: Option<Fours>,
    tangent: [Option<Fours>; 4],
    /// Whether `∂g/∂u`, `∂g/∂u̇` and `∂(M ü)/∂u` have one pattern (bodies
    /// in Euler parameters): their products are made in one pass.
    velocity_terms_fused: bool,
}

impl PatternFours {
    fn new(mass: &Pattern, b: &Pattern, tangent: [&Pattern; 4]) -> Self {
        Self {
            mass: Fours::new(mass),
            b: Fours::new(b),
            tangent: tangent.map(Fours::new),
            velocity_terms_fused: !tangent[1].is_empty()
                && tangent[1] == tangent[2]
                && tangent[1] == tangent[3],
        }
    }
}

/// `y ± A x` (`Aᵀ` with `TRANSPOSE`, subtracting with `SUB`) for the
/// matrix of `pattern` with `values`: by its `fours` when there are.
fn product<const TRANSPOSE: bool, const SUB: bool>(
    fours: Option<&Fours>,
    pattern: &Pattern,
    values: &[f64],
    x: &[f64],
    y: &mut [f64],
) {
    match (fours, TRANSPOSE, SUB) {
        (Some(fours), ..) => fours.product::<TRANSPOSE, SUB>(values, x, y),
        (None, false, false) => pattern.mul_add(values, x, y),
        (None, false, true) => pattern.mul_sub(values, x, y),
        (None, true, false) => pattern.mul_transpose_add(values, x, y),
        (None, true, true) => pattern.mul_transpose_sub(values, x, y),
    }
}

/// Residual, constraints, Jacobians and the KKT matrix of one [`System`], with
/// every buffer allocated once in [`Linearization::new`].
///
/// Call [`eval_residual`](Self::eval_residual) (or
/// [`eval_kkt_rhs`](Self::eval_kkt_rhs)) at every Newton iteration,
/// [`eval_jacobians`](Self::eval_jacobians) and [`assemble`](Self::assemble)
/// only when the iteration matrix is to be refreshed. The evaluated
/// quantities are read through accessors ([`mass`](Self::mass), [`b`](Self::b),
/// [`g`](Self::g), [`phi`](Self::phi), [`r`](Self::r), …): a constant `M` or
/// constant forces are evaluated once and kept.
#[derive(Clone, Debug)]
pub struct Linearization {
    n: usize,
    m: usize,
    structure: Structure,
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
    /// The patterns of `Σ λᵢ ∂²Φᵢ/∂u²`, `∂g/∂u`, `∂g/∂u̇`, `∂(M ü)/∂u`, for
    /// [`tangent_mul_add`](Self::tangent_mul_add).
    tangent_patterns: [Pattern; 4],
    /// `M`'s, `B`'s and the tangent's patterns (in `tangent_patterns`'
    /// order) in fours, for their products.
    fours: PatternFours,
    /// Values of `M`, `B`, `Σ λᵢ ∂²Φᵢ/∂u²`, `∂g/∂u`, `∂g/∂u̇`, `∂(M ü)/∂u` on
    /// the system's patterns.
    mass: Vec<f64>,
    b: Vec<f64>,
    hessian: Vec<f64>,
    g_u: Vec<f64>,
    g_v: Vec<f64>,
    mass_du: Vec<f64>,
    /// Forces `g` (eq. 3).
    g: Vec<f64>,
    /// Constraint force `Bᵀλ` (eq. 1), stored only when `B`'s indices do not
    /// fit in 32 bits (else formed in the residual's own pass).
    bt_lambda: Vec<f64>,
    /// Inertia force `M ü` for a non-diagonal `M`; empty for a diagonal one,
    /// whose `M ü` is formed in the residual's own pass and not stored.
    m_a: Vec<f64>,
    /// Residual `r = g − Bᵀλ − M ü` (the paper's γ, eq. 3), as the last
    /// [`eval_residual`](Self::eval_residual) formed it.
    r: Vec<f64>,
    /// Constraints `Φ` (eq. 4).
    phi: Vec<f64>,
    /// The system's scratch for [`System::phi_b_into`].
    work: Vec<f64>,
    /// The `(t, u)` at which [`System::phi_b_into`] last wrote `work`
    /// (`u` empty: none, or a workspace of no values): the Jacobians at the
    /// same state may read it ([`System::hessian_after_phi_b`]).
    work_t: f64,
    work_u: Vec<f64>,
    /// `max(‖g‖∞, ‖Bᵀλ‖∞, ‖M ü‖∞, ‖λ‖∞)` of the last residual evaluation.
    force_scale: f64,
    /// `‖r‖∞` of the last residual evaluation (NaN if `r` has a NaN).
    r_max: f64,
    /// `‖Φ‖∞` of the last residual evaluation.
    phi_max: f64,
    /// The KKT structure and slot maps.
    layout: Layout,
    bb_values: Vec<f64>,
}

impl Linearization {
    /// Reads the system's patterns, checks them, and builds the whole KKT
    /// structure `[S_T Bᵀ; B 0]` (eq. 16) with `S_T` augmented by `BᵀB`
    /// ([`Structure::AUGMENTED`]) once: the union of the patterns of `M`,
    /// `BᵀB`, the constraint Hessian, `∂g/∂u`, `∂g/∂u̇`, `∂(Mü)/∂u`, the
    /// diagonal, `B` and `Bᵀ`.
    ///
    /// # Errors
    /// [`LinearizeError`] when a declared pattern has the wrong shape or an
    /// entry out of bounds.
    pub fn new<S: System + ?Sized>(sys: &S) -> Result<Self, LinearizeError> {
        Self::with_structure(sys, Structure::AUGMENTED)
    }

    /// As [`new`](Self::new), in the structure a KKT backend reads
    /// ([`mstar_kkt::Backend::structure`]). Without the augmentation,
    /// [`assemble`](Self::assemble) ignores [`Coefficients::c_bb`] and
    /// `S_T = c_u K_T + c_v C_T + c_a M`: for bodies that interact only
    /// through constraints `S_T` is then block-diagonal. Both matrices give
    /// the same `Δu`; the augmented one returns the multiplier part
    /// `Δλ + c_bb Φ` (with `scale`), the plain one `Δλ`: from the constraint
    /// rows `B Δu = −Φ`, `c_bb BᵀB Δu = −c_bb Bᵀ Φ` moves into the
    /// multipliers. Without the `Bᵀ` block, [`kkt`](Self::kkt) holds `S`, `B`
    /// and no multiplier block (a symmetric matrix by its lower part).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_structure<S: System + ?Sized>(
        sys: &S,
        structure: Structure,
    ) -> Result<Self, LinearizeError> {
        let p = Patterns::read(sys)?;
        let layout = Layout::new(&p, structure)?;
        let bt_gather = BtGather::new(&p.b);
        let (n, m) = (p.n, p.m);
        let mass_diagonal = p.mass_is_diagonal();
        Ok(Self {
            n,
            m,
            structure,
            mass_ready: false,
            forces_ready: false,
            bt_lambda: if bt_gather.is_some() {
                Vec::new()
            } else {
                vec![0.0; n]
            },
            bt_gather,
            mass_diagonal,
            mass: vec![0.0; p.mass.len()],
            b: vec![0.0; p.b.len()],
            hessian: vec![0.0; p.hessian.len()],
            g_u: vec![0.0; p.g_u.len()],
            g_v: vec![0.0; p.g_v.len()],
            mass_du: vec![0.0; p.mass_du.len()],
            g: vec![0.0; n],
            m_a: if mass_diagonal {
                Vec::new()
            } else {
                vec![0.0; n]
            },
            r: vec![0.0; n],
            phi: vec![0.0; m],
            work: vec![0.0; sys.workspace_len()],
            work_t: 0.0,
            work_u: Vec::new(),
            force_scale: 0.0,
            r_max: 0.0,
            phi_max: 0.0,
            bb_values: vec![0.0; layout.bb_pairs.len()],
            fours: PatternFours::new(&p.mass, &p.b, [&p.hessian, &p.g_u, &p.g_v, &p.mass_du]),
            mass_pattern: p.mass,
            b_pattern: p.b,
            tangent_patterns: [p.hessian, p.g_u, p.g_v, p.mass_du],
            layout,
        })
    }

    /// A linearization of `sys` on this one's KKT structure, without
    /// building the structure again (its layout is most of
    /// [`with_structure`](Self::with_structure)'s cost): for a model that
    /// differs from this one's in values only, such as the model at a
    /// parameter's `p ± h_p`. Nothing evaluated is carried over (a constant
    /// `M` or constant forces are evaluated again). `None` when a pattern of
    /// `sys` differs from the one this linearization was built for, or its
    /// workspace length does.
    #[must_use]
    pub fn like<S: System + ?Sized>(&self, sys: &S) -> Option<Self> {
        let mut lin = self.clone();
        lin.reset_for(sys).then_some(lin)
    }

    /// Makes this linearization one of `sys` (as [`like`](Self::like),
    /// in place) and returns `true`; `false`, and nothing changed, when a
    /// pattern of `sys` or its workspace length differs from this one's.
    pub fn reset_for<S: System + ?Sized>(&mut self, sys: &S) -> bool {
        let Ok(p) = Patterns::read(sys) else {
            return false;
        };
        let [hessian, g_u, g_v, mass_du] = &self.tangent_patterns;
        let same = (p.n, p.m) == (self.n, self.m)
            && p.mass == self.mass_pattern
            && p.b == self.b_pattern
            && (&p.hessian, &p.g_u, &p.g_v, &p.mass_du) == (hessian, g_u, g_v, mass_du)
            && sys.workspace_len() == self.work.len();
        if same {
            self.mass_ready = false;
            self.forces_ready = false;
            // `work` holds the previous system's table.
            self.work_u.clear();
        }
        same
    }

    /// The KKT structure assembled.
    #[must_use]
    pub fn structure(&self) -> Structure {
        self.structure
    }

    /// Whether the KKT matrix carries the `BᵀB` term (see
    /// [`with_structure`](Self::with_structure)).
    #[must_use]
    pub fn augmented(&self) -> bool {
        self.structure.augmented
    }

    /// Values of `M` on the system's mass pattern, as last evaluated.
    #[must_use]
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// Values of `B` on the system's `B` pattern, as last evaluated.
    #[must_use]
    pub fn b(&self) -> &[f64] {
        &self.b
    }

    /// The forces `g` (eq. 3), as last evaluated.
    #[must_use]
    pub fn g(&self) -> &[f64] {
        &self.g
    }

    /// The constraints `Φ` (eq. 4), as last evaluated.
    #[must_use]
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }

    /// The residual `r = g − Bᵀλ − M ü` (eq. 3) of the last
    /// [`eval_residual`](Self::eval_residual) ([`eval_kkt_rhs`](Self::eval_kkt_rhs)
    /// writes `r` into the KKT right-hand side instead and leaves this as it was).
    #[must_use]
    pub fn r(&self) -> &[f64] {
        &self.r
    }

    /// Values of `Σ λᵢ ∂²Φᵢ/∂u²`, `∂g/∂u`, `∂g/∂u̇` and `∂(M ü)/∂u` on the
    /// system's patterns, as last [`eval_jacobians`](Self::eval_jacobians)
    /// evaluated them.
    #[must_use]
    pub fn jacobians(&self) -> [&[f64]; 4] {
        [&self.hessian, &self.g_u, &self.g_v, &self.mass_du]
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
    pub fn eval_residual<S: System + ?Sized>(&mut self, sys: &S, x: &StateRef<'_>) {
        let mut r = std::mem::take(&mut self.r);
        self.residual_into(sys, x, 1.0, &mut r);
        self.r = r;
        self.phi_max = max_abs(&self.phi);
    }

    /// [`eval_residual`](Self::eval_residual) and [`kkt_rhs`](Self::kkt_rhs)
    /// in one: writes the right-hand side `[scale·r; −Φ]` of (16) into `rhs`
    /// as the residual is formed, without storing `r` (the field
    /// [`r`](Self::r) keeps its last value), and returns `‖rhs‖∞` (see
    /// [`kkt_rhs_norm`](Self::kkt_rhs_norm)). On a long chain it saves a
    /// pass writing `r` and one reading it back. The norms are those of
    /// `eval_residual`.
    ///
    /// # Panics
    /// If `rhs` is not of length `n + m`.
    pub fn eval_kkt_rhs<S: System + ?Sized>(
        &mut self,
        sys: &S,
        x: &StateRef<'_>,
        scale: f64,
        rhs: &mut [f64],
    ) -> f64 {
        assert_eq!(rhs.len(), self.n + self.m);
        let (primal, dual) = rhs.split_at_mut(self.n);
        self.residual_into(sys, x, scale, primal);
        // −Φ and ‖Φ‖∞ in one pass.
        let mut phi_max = MaxAbs::new();
        for (x, &p) in dual.iter_mut().zip(&self.phi) {
            *x = -p;
            phi_max.push(p);
        }
        self.phi_max = phi_max.value();
        self.kkt_rhs_norm(scale)
    }

    /// `M`, `B`, `g`, `Φ` at the state, then `out = scale·r` with the force
    /// scale and `‖r‖∞` (not `‖Φ‖∞`).
    fn residual_into<S: System + ?Sized>(
        &mut self,
        sys: &S,
        x: &StateRef<'_>,
        scale_out: f64,
        out: &mut [f64],
    ) {
        self.evaluate(sys, x);
        self.form_residual(x.a, x.lambda, scale_out, out);
    }

    /// `M` (once when constant), `Φ` and `B`, `g` (once when constant), and
    /// where they are stored `Bᵀλ` and `M ü`.
    fn evaluate<S: System + ?Sized>(&mut self, sys: &S, x: &StateRef<'_>) {
        let StateRef { t, u, v, a, lambda } = *x;
        self.eval_matrices(sys, t, u);
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
            let mass = self.fours.mass.as_ref();
            product::<false, false>(mass, &self.mass_pattern, &self.mass, a, &mut self.m_a);
        }
    }

    /// `out = scale_out · r` and, in the same pass, the force scale and
    /// `‖r‖∞`, with `Bᵀλ` (32-bit indices) and `M ü` (diagonal `M`) formed on
    /// the way, not stored: on a long chain every stored vector is a pass
    /// through memory.
    fn form_residual(&mut self, a: &[f64], lambda: &[f64], scale_out: f64, out: &mut [f64]) {
        let (mut scale, mut r_max) = (0.0f64, MaxAbs::new());
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
            r_max.push(r);
        }
        self.force_scale = scale.max(max_abs(lambda));
        self.r_max = r_max.value();
    }

    /// Evaluates `M` (once when constant) and `B` (with `Φ`, which
    /// [`phi`](Self::phi) then holds) at `(t, u)`, without the forces and
    /// the residual: what [`assemble`](Self::assemble) and products with
    /// `B` need besides [`eval_jacobians`](Self::eval_jacobians), e.g. to
    /// refactor the iteration matrix at a state that is already converged
    /// (the backward pass of `mstar_newmark::Integrator::gradient`).
    /// [`r`](Self::r), [`g`](Self::g) and the norms keep their last values.
    pub fn eval_matrices<S: System + ?Sized>(&mut self, sys: &S, t: f64, u: &[f64]) {
        if !(self.mass_ready && sys.mass_is_constant()) {
            sys.mass_into(t, u, &mut self.mass);
            self.mass_ready = true;
        }
        sys.phi_b_into(t, u, &mut self.phi, &mut self.b, &mut self.work);
        if !self.work.is_empty() {
            self.work_t = t;
            self.work_u.clear();
            self.work_u.extend_from_slice(u);
        }
    }

    /// `true` when `work` is what [`System::phi_b_into`] wrote at `(t, u)`
    /// (bit for bit: `−0.0` and `0.0` have different sines).
    fn work_is_at(&self, t: f64, u: &[f64]) -> bool {
        !self.work_u.is_empty()
            && self.work_t.to_bits() == t.to_bits()
            && self.work_u.len() == u.len()
            && self
                .work_u
                .iter()
                .zip(u)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// Evaluates the parts of `K_T` and `C_T` (eqs. 6-7): the constraint Hessian
    /// contracted with `λ`, `∂g/∂u`, `∂g/∂u̇` and `∂(M ü)/∂u`. `M` and `B` come
    /// from the last [`eval_residual`](Self::eval_residual) (or
    /// [`eval_matrices`](Self::eval_matrices)).
    pub fn eval_jacobians<S: System + ?Sized>(&mut self, sys: &S, x: &StateRef<'_>) {
        let StateRef { t, u, v, a, lambda } = *x;
        // (An empty pattern needs no call: the defaults of a constant M or
        // constant forces would evaluate nothing.)
        if !self.hessian.is_empty() {
            if self.work_is_at(t, u) {
                sys.hessian_after_phi_b(t, u, lambda, &mut self.hessian, &mut self.work);
            } else {
                sys.hessian_with_work(t, u, lambda, &mut self.hessian, &mut self.work);
                // `work` is no longer what phi_b_into wrote.
                self.work_u.clear();
            }
        }
        if !self.g_u.is_empty() {
            sys.forces_du_into(t, u, v, &mut self.g_u);
        }
        if !self.g_v.is_empty() {
            sys.forces_dv_into(t, u, v, &mut self.g_v);
        }
        if !self.mass_du.is_empty() {
            sys.mass_du_into(t, u, a, &mut self.mass_du);
        }
    }

    /// `y += K_T x + C_T w` (eqs. 6-7) from the last
    /// [`eval_jacobians`](Self::eval_jacobians): `K_T = Σλᵢ∂²Φᵢ/∂u² − ∂g/∂u
    /// + ∂(M ü)/∂u`, `C_T = −∂g/∂u̇`. The product of the tangent without
    /// assembling it, e.g. for the right-hand side of a sensitivity
    /// (`mstar_newmark::Sensitivities`).
    ///
    /// # Panics
    /// If `x`, `w` or `y` is not of length `n`.
    pub fn tangent_mul_add(&self, x: &[f64], w: &[f64], y: &mut [f64]) {
        self.tangent_product::<false>(x, w, y);
    }

    /// `y −= K_T x + C_T w`: [`tangent_mul_add`](Self::tangent_mul_add)
    /// subtracting, for a residual formed in place (no buffer, no pass).
    ///
    /// # Panics
    /// If `x`, `w` or `y` is not of length `n`.
    pub fn tangent_mul_sub(&self, x: &[f64], w: &[f64], y: &mut [f64]) {
        self.tangent_product::<true>(x, w, y);
    }

    /// `y ± (K_T x + C_T w)`, each matrix's entries added or subtracted in
    /// place (`K_T`'s `−∂g/∂u` and `C_T`'s `−∂g/∂u̇` with the other sign).
    fn tangent_product<const SUB: bool>(&self, x: &[f64], w: &[f64], y: &mut [f64]) {
        let [hessian, g_u, g_v, mass_du] = &self.tangent_patterns;
        let [f_hessian, f_g_u, f_g_v, f_mass_du] =
            self.fours.tangent.each_ref().map(Option::as_ref);
        if !self.hessian.is_empty() {
            product::<false, SUB>(f_hessian, hessian, &self.hessian, x, y);
        }
        if self.fours.velocity_terms_fused {
            self.velocity_product::<SUB>(x, w, y);
            return;
        }
        if !self.mass_du.is_empty() {
            product::<false, SUB>(f_mass_du, mass_du, &self.mass_du, x, y);
        }
        // `−∂g/∂u` and `−∂g/∂u̇`: the other sign.
        if SUB {
            if !self.g_u.is_empty() {
                product::<false, false>(f_g_u, g_u, &self.g_u, x, y);
            }
            if !self.g_v.is_empty() {
                product::<false, false>(f_g_v, g_v, &self.g_v, w, y);
            }
        } else {
            if !self.g_u.is_empty() {
                product::<false, true>(f_g_u, g_u, &self.g_u, x, y);
            }
            if !self.g_v.is_empty() {
                product::<false, true>(f_g_v, g_v, &self.g_v, w, y);
            }
        }
    }

    /// `y ± ((∂(M ü)/∂u − ∂g/∂u) x − ∂g/∂u̇ w)` in one pass, the three on
    /// one pattern (`PatternFours::velocity_terms_fused`).
    fn velocity_product<const SUB: bool>(&self, x: &[f64], w: &[f64], y: &mut [f64]) {
        let values = [&self.mass_du[..], &self.g_u, &self.g_v];
        if let Some(fours) = &self.fours.tangent[1] {
            fours.velocity_product::<SUB>(values, x, w, y);
            return;
        }
        assert_eq!((x.len(), w.len(), y.len()), (self.n, self.n, self.n));
        let sign = if SUB { -1.0 } else { 1.0 };
        let terms = self.tangent_patterns[1].entries.iter().zip(&self.mass_du);
        for ((&(i, j), m_du), (g_u, g_v)) in terms.zip(self.g_u.iter().zip(&self.g_v)) {
            y[i] += sign * ((m_du - g_u) * x[j] - g_v * w[j]);
        }
    }

    /// `y −= B x` with the last evaluated `B`.
    ///
    /// # Panics
    /// If `x` is not of length `n` or `y` of length `m`.
    pub fn b_mul_sub(&self, x: &[f64], y: &mut [f64]) {
        product::<false, true>(self.fours.b.as_ref(), &self.b_pattern, &self.b, x, y);
    }

    /// `y −= Bᵀ x` with the last evaluated `B`.
    ///
    /// # Panics
    /// If `x` is not of length `m` or `y` of length `n`.
    pub fn b_mul_transpose_sub(&self, x: &[f64], y: &mut [f64]) {
        product::<true, true>(self.fours.b.as_ref(), &self.b_pattern, &self.b, x, y);
    }

    /// `y −= M x` with the last evaluated `M`.
    ///
    /// # Panics
    /// If `x` or `y` is not of length `n`.
    pub fn mass_mul_sub(&self, x: &[f64], y: &mut [f64]) {
        product::<false, true>(
            self.fours.mass.as_ref(),
            &self.mass_pattern,
            &self.mass,
            x,
            y,
        );
    }

    /// `y += K_Tᵀ x` and `z += C_Tᵀ x` (the transposes of
    /// [`tangent_mul_add`](Self::tangent_mul_add)'s products) from the last
    /// [`eval_jacobians`](Self::eval_jacobians): the tangent's share of a
    /// transposed KKT product, e.g. for the discrete adjoint
    /// (`mstar_newmark::Integrator::gradient`). `K_T` is not symmetric with
    /// velocity-dependent or follower forces, so `K_Tᵀ x ≠ K_T x` in general.
    ///
    /// # Panics
    /// If `x`, `y` or `z` is not of length `n`.
    pub fn tangent_mul_transpose_add(&self, x: &[f64], y: &mut [f64], z: &mut [f64]) {
        let [hessian, g_u, g_v, mass_du] = &self.tangent_patterns;
        let [f_hessian, f_g_u, f_g_v, f_mass_du] =
            self.fours.tangent.each_ref().map(Option::as_ref);
        if !self.hessian.is_empty() {
            product::<true, false>(f_hessian, hessian, &self.hessian, x, y);
        }
        if !self.mass_du.is_empty() {
            product::<true, false>(f_mass_du, mass_du, &self.mass_du, x, y);
        }
        if !self.g_u.is_empty() {
            product::<true, true>(f_g_u, g_u, &self.g_u, x, y);
        }
        if !self.g_v.is_empty() {
            product::<true, true>(f_g_v, g_v, &self.g_v, x, z);
        }
    }

    fn eval_bb(&mut self) {
        for (out, &(p, q)) in self.bb_values.iter_mut().zip(&self.layout.bb_pairs) {
            *out = self.b[p] * self.b[q];
        }
    }

    /// Fills the values of the KKT matrix (16) with the given coefficients from
    /// the last evaluations:
    /// `S_T = c_u K_T + c_v C_T + c_a M + c_bb BᵀB` (eq. 17, `K_T = Σλᵢ∂²Φᵢ/∂u²
    /// − ∂g/∂u + ∂(Mü)/∂u`, `C_T = −∂g/∂u̇`), scaled by `scale`, plus
    /// `c_identity I`.
    pub fn assemble(&mut self, c: &Coefficients) {
        let c_bb = if self.structure.augmented {
            c.c_bb
        } else {
            0.0
        };
        if c_bb != 0.0 {
            self.eval_bb();
        }
        let s = c.scale;
        let layout = &mut self.layout;
        let vals = &mut layout.kkt.values;
        // Without BᵀB and the Bᵀ block (the Schur backend's structure) the
        // matrix is the S terms and B: zero the S slots and assign B, each
        // slot of which has one entry, instead of zeroing everything and
        // adding B (fewer instructions; the same cache lines are written).
        let assign_b =
            !self.structure.transpose && !self.structure.augmented && layout.b_slots_unique;
        let sl = &layout.slots;
        if assign_b && layout.mass_covers_s {
            // Every S slot takes one entry of M first: assigned, not zeroed
            // and added to (the same values, but for the sign of a zero).
            for (&k, &m) in sl.mass.iter().zip(&self.mass) {
                vals[k as usize] = (s * c.c_a) * m;
            }
        } else {
            if assign_b {
                for &k in &layout.s_slots {
                    vals[k as usize] = 0.0;
                }
            } else {
                vals.fill(0.0);
            }
            scatter(vals, &sl.mass, &self.mass, s * c.c_a);
        }
        if c.c_u != 0.0 {
            scatter(vals, &sl.hessian, &self.hessian, s * c.c_u);
        }
        if c.c_u != 0.0 && c.c_v != 0.0 && layout.velocity_terms_share_slots {
            // `∂g/∂u`, `∂(M ü)/∂u` and `∂g/∂u̇` on the same slots (bodies in
            // Euler parameters): one pass, each slot's terms in the order of
            // the three passes below.
            let terms = sl
                .g_u
                .iter()
                .zip(&self.g_u)
                .zip(&self.mass_du)
                .zip(&self.g_v);
            for (((&k, &gu), &mdu), &gv) in terms {
                let v = &mut vals[k as usize];
                *v += -s * c.c_u * gu;
                *v += s * c.c_u * mdu;
                *v += -s * c.c_v * gv;
            }
        } else {
            if c.c_u != 0.0 {
                scatter(vals, &sl.g_u, &self.g_u, -s * c.c_u);
                scatter(vals, &sl.mass_du, &self.mass_du, s * c.c_u);
            }
            if c.c_v != 0.0 {
                scatter(vals, &sl.g_v, &self.g_v, -s * c.c_v);
            }
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
        // (No Bᵀ slots when the structure has no Bᵀ block.)
        scatter(vals, &sl.bt, &self.b, 1.0);
    }

    /// The KKT matrix (16) as last [`assemble`](Self::assemble)d; unknowns are
    /// ordered `[Δu (n); Δλ (m)]`. Its structure never changes.
    #[must_use]
    pub fn kkt(&self) -> &Csc {
        &self.layout.kkt
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
    /// the last [`eval_residual`](Self::eval_residual). Its structure is built
    /// on the first call (and `BᵀB`'s pairs, unless the KKT structure is
    /// augmented and has them).
    pub fn m_star(&mut self) -> &Csc {
        if self.layout.m_star.is_none() && self.layout.bb_pairs.is_empty() {
            self.layout.bb_pairs = bb_pairs(self.m, &self.b_pattern);
            self.bb_values = vec![0.0; self.layout.bb_pairs.len()];
        }
        self.eval_bb();
        let layout = &mut self.layout;
        let (mass_pattern, b_pattern) = (&self.mass_pattern, &self.b_pattern);
        let ms = layout
            .m_star
            .get_or_insert_with(|| MStar::new(mass_pattern, b_pattern, &layout.bb_pairs));
        let vals = &mut ms.csc.values;
        vals.fill(0.0);
        for (&k, &v) in ms.mass.iter().zip(&self.mass) {
            vals[k] += v;
        }
        for (&k, &v) in ms.bb.iter().zip(&self.bb_values) {
            vals[k] += v;
        }
        &ms.csc
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
