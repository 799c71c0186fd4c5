//! Analysed backends kept for reuse: the runs of a sweep, or any program
//! that builds solvers for one structure again and again, analyse it once.
//!
//! Sharing is on while a [`SharedAnalyses`] guard lives (a sweep holds one
//! for its runs); without one nothing is kept, so that a single large run
//! does not pay for a copy of its analysis. A template is a backend that has been analysed and never factored, with
//! the structure and options it was analysed for. [`KktSolver::new`]
//! (crate::KktSolver::new) asks for a [`fork`](crate::KktBackend::fork) of a
//! template whose structure and options match exactly (the whole pattern is
//! compared, not a hash), and otherwise analyses and keeps a template of the
//! result. The newest [`KEPT`] templates are kept; [`forget_analyses`] frees
//! them. A fork is the backend the analysis would give, so a run's values do
//! not depend on whether its analysis was shared.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::{Backend, Csc, KktBackend, KktOptions};

/// Templates kept (a run makes up to three structures: the start's
/// solvers and the iteration matrix).
const KEPT: usize = 4;

/// One analysed backend and what it was analysed for.
struct Template {
    backend: Backend,
    options: KktOptions,
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    analysed: Box<dyn KktBackend>,
}

impl Template {
    fn matches(&self, backend: Backend, a: &Csc, options: &KktOptions) -> bool {
        self.backend == backend
            && self.options == *options
            && self.n == a.n
            && self.col_ptr == a.col_ptr
            && self.row_idx == a.row_idx
    }
}

/// The number of live [`SharedAnalyses`] guards.
static SHARING: AtomicUsize = AtomicUsize::new(0);

/// While one lives, [`KktSolver::new`](crate::KktSolver::new) keeps the
/// analyses it makes and reuses them for identical structures and options;
/// when the last one is dropped they are freed.
///
/// ```
/// let sweep = mstar_kkt::SharedAnalyses::begin();
/// // … build the runs' solvers: one analysis per distinct structure …
/// drop(sweep);
/// ```
#[derive(Debug)]
#[must_use = "analyses are shared only while the guard lives"]
pub struct SharedAnalyses(());

impl SharedAnalyses {
    /// Turns sharing on until the guard is dropped.
    pub fn begin() -> Self {
        SHARING.fetch_add(1, Ordering::SeqCst);
        Self(())
    }
}

impl Drop for SharedAnalyses {
    fn drop(&mut self) {
        if SHARING.fetch_sub(1, Ordering::SeqCst) == 1 {
            forget_analyses();
        }
    }
}

fn sharing() -> bool {
    SHARING.load(Ordering::SeqCst) > 0
}

/// Newest first.
static TEMPLATES: Mutex<Vec<Template>> = Mutex::new(Vec::new());

/// A fork of the template analysed for `backend` on `a`'s structure with
/// `options`, if one is kept.
pub(crate) fn fork(backend: Backend, a: &Csc, options: &KktOptions) -> Option<Box<dyn KktBackend>> {
    if !sharing() {
        return None;
    }
    // A poisoned lock (a panic elsewhere while holding it) only loses the reuse.
    let mut kept = TEMPLATES.lock().ok()?;
    let k = kept.iter().position(|t| t.matches(backend, a, options))?;
    let fork = kept[k].analysed.fork()?;
    // The most recently used first.
    let template = kept.remove(k);
    kept.insert(0, template);
    Some(fork)
}

/// Keeps a fork of `analysed` (just analysed, not factored) as the template
/// for `backend` on `a`'s structure with `options`, if the backend can fork.
pub(crate) fn keep(backend: Backend, a: &Csc, options: &KktOptions, analysed: &dyn KktBackend) {
    if !sharing() {
        return;
    }
    let Some(copy) = analysed.fork() else {
        return;
    };
    let Ok(mut kept) = TEMPLATES.lock() else {
        return;
    };
    kept.retain(|t| !t.matches(backend, a, options));
    kept.insert(
        0,
        Template {
            backend,
            options: *options,
            n: a.n,
            col_ptr: a.col_ptr.clone(),
            row_idx: a.row_idx.clone(),
            analysed: copy,
        },
    );
    kept.truncate(KEPT);
}

/// Frees the analyses kept for reuse (the next solver for any structure is
/// analysed afresh).
fn forget_analyses() {
    if let Ok(mut kept) = TEMPLATES.lock() {
        kept.clear();
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::chain_with;
    use crate::{Backend, KktOptions, KktSolver, SharedAnalyses};

    /// Solves `a x = b` (b = 1, 2, 3, …) with a new solver; returns `x` and
    /// whether the solver reused an analysis.
    fn solve(a: &crate::Csc, options: &KktOptions) -> (Vec<f64>, bool) {
        let mut solver = KktSolver::new(a, options).expect("analysis");
        solver.factor(&a.values).expect("factorization");
        let mut x: Vec<f64> = (0..a.n).map(|i| (i + 1) as f64).collect();
        solver.solve_in_place(&mut x).expect("solve");
        (x, solver.reused_analysis())
    }

    #[test]
    fn a_shared_analysis_solves_as_a_fresh_one_to_the_bit() {
        let cases = [
            (Backend::SPARSE_LU, true),
            (Backend::SPARSE_LDLT, true),
            (Backend::SCHUR, false),
            (Backend::SCHUR_LU, false),
        ];
        for (backend, augmented) in cases {
            // Two matrices with one structure (a chain's depends on its length only).
            let (first, second) = (
                chain_with(30, 7, None, augmented),
                chain_with(30, 8, None, augmented),
            );
            assert_eq!(first.row_idx, second.row_idx);
            assert_ne!(first.values, second.values);
            let options = KktOptions {
                backend,
                n_primal: Some(90),
                ..KktOptions::default()
            };
            let (fresh, reused) = solve(&second, &options);
            assert!(!reused, "{backend}: no guard, no reuse");
            let guard = SharedAnalyses::begin();
            let (_, reused_first) = solve(&first, &options);
            let (forked, reused_second) = solve(&second, &options);
            drop(guard);
            assert!(
                !reused_first && reused_second,
                "{backend}: the second solver reuses"
            );
            assert_eq!(forked, fresh, "{backend}");
            // And it is the solution: ‖A x − b‖∞ at the rounding level.
            let mut ax = vec![0.0; second.n];
            second.mul(&forked, &mut ax);
            assert!(ax.iter().all(|v| v.is_finite()), "{backend}: {ax:?}");
            let scale = crate::max_abs(&second.values) * crate::max_abs(&forked) + second.n as f64;
            for (i, v) in ax.iter().enumerate() {
                let r = (v - (i + 1) as f64).abs();
                assert!(r <= 1e-12 * scale, "{backend}: row {i}: residual {r}");
            }
        }
    }
}
