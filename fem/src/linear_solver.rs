//! Sparse direct solvers (faer) with the symbolic factorisation kept across Newton
//! iterations and steps while the sparsity pattern holds.
//!
//! `auto` (the default) checks the assembled tangent's symmetry (one pass over the
//! nonzeros through the precomputed transpose map) and uses the Cholesky factorisation
//! `A = L Lᵀ` when it is symmetric and positive definite, sparse LU `P A Q = L U`
//! otherwise. On this project's FEM/MPM matrices Cholesky with AMD ordering was up to 10×
//! faster than LU (whose column ordering fills in more), see `../shared/STACK.md`.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::{MatMut, Side};
use serde::Deserialize;

use crate::assembly::AssemblyPattern;

/// Choice of direct solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKind {
    /// Cholesky when the matrix is symmetric positive definite, LU otherwise.
    #[default]
    Auto,
    /// Sparse LU with partial pivoting (any matrix).
    Lu,
    /// Sparse Cholesky (symmetric positive definite matrices only).
    Cholesky,
}

/// Failure of the linear solve.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum LinearSolverError {
    /// Factorisation failed (singular matrix: a rigid-body mode left free, or a
    /// mechanism; or not positive definite for Cholesky).
    #[error("linear solver: {0}")]
    Factorisation(String),
    /// The solution contains NaN or infinity.
    #[error("linear solver: singular system (non-finite solution)")]
    NonFinite,
}

/// Seconds spent in the solver phases, accumulated.
#[derive(Debug, Clone, Copy, Default)]
pub struct SolverTimings {
    /// Symbolic analyses.
    pub symbolic: f64,
    /// Numeric factorisations.
    pub factorisation: f64,
    /// Triangular solves.
    pub solve: f64,
}

/// A direct solver bound to one sparsity pattern.
#[derive(Debug)]
pub struct LinearSolver {
    kind: LinearSolverKind,
    lu: Option<SymbolicLu<usize>>,
    llt: Option<SymbolicLlt<usize>>,
    /// Set once Cholesky failed on this pattern (indefinite tangent): use LU from then on.
    llt_failed: bool,
    /// Accumulated timings.
    pub timings: SolverTimings,
}

impl LinearSolver {
    /// A solver of the given kind; symbolic analyses happen at the first solve.
    pub fn new(kind: LinearSolverKind) -> Self {
        Self { kind, lu: None, llt: None, llt_failed: false, timings: SolverTimings::default() }
    }

    /// Forgets the symbolic factorisations (call when the pattern changes).
    pub fn reset_pattern(&mut self) {
        self.lu = None;
        self.llt = None;
        self.llt_failed = false;
    }

    /// Solves `A x = b` in place (`rhs` holds `b` on entry and `x` on exit).
    pub fn solve(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), LinearSolverError> {
        let n = pattern.num_equations();
        if n == 0 {
            return Ok(());
        }
        let a = pattern.matrix(values);
        let use_llt = match self.kind {
            LinearSolverKind::Cholesky => true,
            LinearSolverKind::Lu => false,
            LinearSolverKind::Auto => !self.llt_failed && pattern.asymmetry(values) < 1e-10,
        };
        if use_llt {
            if self.llt.is_none() {
                let t = Instant::now();
                self.llt = Some(
                    SymbolicLlt::try_new(a.symbolic(), Side::Lower)
                        .map_err(|e| LinearSolverError::Factorisation(format!("{e:?}")))?,
                );
                self.timings.symbolic += t.elapsed().as_secs_f64();
            }
            let t = Instant::now();
            let sym = self.llt.clone().expect("symbolic Cholesky present");
            match Llt::try_new_with_symbolic(sym, a, Side::Lower) {
                Ok(llt) => {
                    self.timings.factorisation += t.elapsed().as_secs_f64();
                    let t = Instant::now();
                    llt.solve_in_place(MatMut::from_column_major_slice_mut(rhs, n, 1));
                    self.timings.solve += t.elapsed().as_secs_f64();
                    return check_finite(rhs);
                }
                Err(e) if self.kind == LinearSolverKind::Cholesky => {
                    return Err(LinearSolverError::Factorisation(format!(
                        "Cholesky failed ({e}): matrix not positive definite"
                    )));
                }
                Err(_) => {
                    self.timings.factorisation += t.elapsed().as_secs_f64();
                    self.llt_failed = true;
                }
            }
        }
        if self.lu.is_none() {
            let t = Instant::now();
            self.lu = Some(
                SymbolicLu::try_new(a.symbolic()).map_err(|e| LinearSolverError::Factorisation(format!("{e:?}")))?,
            );
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let t = Instant::now();
        let sym = self.lu.clone().expect("symbolic LU present");
        let lu = Lu::try_new_with_symbolic(sym, a)
            .map_err(|e| LinearSolverError::Factorisation(format!("LU failed: {e}")))?;
        self.timings.factorisation += t.elapsed().as_secs_f64();
        let t = Instant::now();
        lu.solve_in_place(MatMut::from_column_major_slice_mut(rhs, n, 1));
        self.timings.solve += t.elapsed().as_secs_f64();
        check_finite(rhs)
    }
}

fn check_finite(x: &[f64]) -> Result<(), LinearSolverError> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LinearSolverError::NonFinite)
    }
}
