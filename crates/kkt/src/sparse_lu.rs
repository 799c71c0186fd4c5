//! Sparse LU (faer): COLAMD ordering and symbolic analysis once, numeric
//! refactorization into reused buffers.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::LuError;
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

use crate::backend::{Backend, KktBackend, Registration, Structure};
use crate::stored::Stored;
use crate::{Csc, KktError, KktOptions, max_abs};

/// The `lu` backend.
pub(crate) const REGISTRATION: Registration = Registration {
    backend: Backend::SPARSE_LU,
    summary: "faer's sparse LU with partial pivoting, COLAMD order (any square matrix)",
    structure: Structure::AUGMENTED,
    symmetric: false,
    analyse: |a, _: &KktOptions| Ok(Box::new(SparseLu::new(a)?)),
    automatic: Some(100),
    needs_n_primal: false,
};

pub(crate) struct SparseLu {
    stored: Stored,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    mem: MemBuffer,
}

impl SparseLu {
    fn new(a: &Csc) -> Result<Self, KktError> {
        let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.col_ptr, None, &a.row_idx);
        let symbolic = factorize_symbolic_lu(sym, Default::default())
            .map_err(|e| KktError::Backend(format!("{e:?}")))?;
        Self::with_symbolic(Stored::new(a), symbolic)
    }

    /// The numeric buffers around a symbolic analysis of `stored`'s structure.
    fn with_symbolic(stored: Stored, symbolic: SymbolicLu<usize>) -> Result<Self, KktError> {
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| KktError::OutOfMemory)?;
        Ok(Self {
            stored,
            symbolic,
            numeric: NumericLu::new(),
            mem,
        })
    }

    fn factor_numeric(&mut self) -> Result<(), KktError> {
        let a = self.stored.matrix();
        let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.col_ptr, None, &a.row_idx);
        let mat = SparseColMatRef::new(sym, &a.values);
        let stack = MemStack::new(&mut self.mem);
        match self.symbolic.factorize_numeric_lu(
            &mut self.numeric,
            mat,
            Par::Seq,
            stack,
            Default::default(),
        ) {
            Ok(_) => Ok(()),
            Err(LuError::SymbolicSingular { index }) => Err(KktError::Singular {
                unknown: Some(index),
            }),
            Err(LuError::Generic(e)) => Err(KktError::Backend(format!("{e:?}"))),
        }
    }

    fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let lu = LuRef::new_unchecked(&self.symbolic, &self.numeric);
        let stack = MemStack::new(&mut self.mem);
        let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
        lu.solve_in_place_with_conj(Conj::No, x, Par::Seq, stack);
    }
}

impl KktBackend for SparseLu {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        let norm = self.stored.load(values)?;
        self.factor_numeric()?;
        Ok(norm)
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        self.solve(rhs);
        max_abs(rhs)
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.stored.mul(x, y);
    }

    fn fork(&self) -> Option<Box<dyn KktBackend>> {
        // faer's symbolic LU shares its analysis between clones.
        let fork = Self::with_symbolic(self.stored.clone(), self.symbolic.clone()).ok()?;
        Some(Box::new(fork))
    }
}
