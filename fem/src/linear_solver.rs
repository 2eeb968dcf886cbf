//! Sparse direct solvers (faer) with the symbolic factorisation kept across Newton
//! iterations and steps while the sparsity pattern holds.
//!
//! `auto` (the default) checks the assembled tangent's symmetry (one pass over the
//! nonzeros through the precomputed transpose map) and uses the Cholesky factorisation
//! `A = L Lᵀ` when it is symmetric and positive definite, sparse LU otherwise. On this
//! project's FEM/MPM matrices Cholesky with AMD ordering was up to 10× faster than faer's LU
//! `P A Q = L U` (partial pivoting: its structure is bounded by the Cholesky factor of `AᵀA`
//! under COLAMD), see `../shared/STACK.md`. So every LU but the one `lu` asks for is first
//! tried on the matrix's symmetric pattern ([`crate::pattern_lu`]: the Cholesky structure
//! under AMD, pivoting restricted to the supernodes, 2× faster than faer's LU on the Bui
//! collapse's Mohr–Coulomb tangents); a pivot below its tolerance or a solve not accurate to
//! `1e-8` after refinement hands the pattern to faer's LU.
//!
//! **Saddle-point systems** (mixed u–p domains: `[K_uu K_up; K_pu K_pp]`, symmetric and
//! indefinite for the hyperelastic laws and the pressure-independent plasticity) break
//! Cholesky. The assembler equilibrates them (pressure rows and columns scaled by `μ/h`) and
//! declares the expected pivot signs (`+` displacement, `−` pressure); then `auto` takes the
//! sparse `L B Lᵀ` factorisation with Bunch–Kaufman pivoting inside the supernodes (faer's
//! intranode factorisation, on the same symbolic AMD analysis as Cholesky; Bunch & Kaufman
//! 1977, "Some stable methods for calculating inertia and solving symmetric linear systems",
//! Math. Comp. 31:163–179, doi:10.1090/S0025-5718-1977-0428694-0) when the matrix is
//! symmetric, LU when it is not (Mohr–Coulomb or Drucker–Prager with φ > 0, whose deviatoric
//! stress depends on the pressure). Each symmetric solve is followed by up to
//! [`LDLT_REFINEMENTS`] steps of iterative refinement while its residual is above round-off;
//! one left above `1e-8` relative goes to LU, which then takes the next few solves
//! ([`LDLT_BACKOFF`]). `ldlt` asks for `L D Lᵀ` without pivoting and with signed regularisation
//! of the pivots (a pivot of the wrong sign or below `1e-13·max|a_ii|` replaced; stable for
//! quasi-definite matrices, Vanderbei 1995, "Symmetric quasidefinite matrices", SIAM J.
//! Optim. 5:100–113, doi:10.1137/0805005): 25 % cheaper than `L B Lᵀ`, but perfect plasticity
//! makes `K_uu` indefinite in a collapse mechanism and it then fails. Measured on the u–p
//! footing and Cook's membrane (LU 4× slower than `L B Lᵀ`): `docs/performance.md`, section
//! "Mixed u–p".
//!
//! `symmetric_part_gmres` solves an unsymmetric tangent by GMRES ([`crate::krylov`])
//! preconditioned with the Cholesky factors of its symmetric part, to [`KRYLOV_TOLERANCE`]
//! within [`KRYLOV_MAX_ITERATIONS`], and falls back to LU for the rest of the pattern when that
//! fails. (Reusing an earlier iteration's factors as the preconditioner was tried and gave no
//! gain on the MPM cantilever or the Bui column, so every solve factorises.)

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, IntranodeLbltRef, LdltRef, LltRef,
    SymbolicCholesky, SymbolicCholeskyRaw,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Side};
use serde::Deserialize;

use crate::assembly::AssemblyPattern;
use crate::krylov::Gmres;
use crate::pattern_lu::PatternLu;
use crate::permuted_lower::PermutedLower;

/// Relative residual `‖b − A x‖/‖b‖` a GMRES solve must reach: far below the
/// Newton tolerances, so that Newton takes the same path as with exact solves.
pub const KRYLOV_TOLERANCE: f64 = 1e-9;
/// Steps of iterative refinement at most after a symmetric indefinite (`L B Lᵀ`, `L D Lᵀ`)
/// solve whose residual is not at round-off.
pub const LDLT_REFINEMENTS: usize = 3;
/// Longest run of LU solves after failures of the symmetric indefinite factorisation (a
/// factorisation, or a solve not accurate to 1e-8): after each failure LU takes the next
/// `2k + 1` solves (`k` the previous run), up to this many, before it is tried again.
pub const LDLT_BACKOFF: u32 = 7;
/// Arnoldi steps before GMRES is given up for LU.
pub const KRYLOV_MAX_ITERATIONS: usize = 12;

/// Choice of direct solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKind {
    /// Cholesky when the matrix is symmetric positive definite, LU otherwise; on a saddle
    /// point (mixed u–p) `L B Lᵀ` when symmetric, LU otherwise.
    #[default]
    Auto,
    /// faer's sparse LU with partial pivoting (any matrix), not the LU on the symmetric
    /// pattern that the other kinds try first.
    Lu,
    /// Sparse Cholesky (symmetric positive definite matrices only).
    Cholesky,
    /// Sparse `L D Lᵀ` without pivoting, with the pivot signs of a saddle point (symmetric
    /// matrices; LU if the matrix is unsymmetric or the factorisation fails).
    Ldlt,
    /// Sparse `L B Lᵀ` with Bunch–Kaufman pivoting inside the supernodes (symmetric
    /// matrices; LU if the matrix is unsymmetric or the solve is not accurate).
    Lblt,
    /// As `auto` for symmetric matrices; an unsymmetric one (non-associated plasticity) by
    /// GMRES preconditioned with the Cholesky factors of its symmetric part, LU if that part
    /// is not positive definite or GMRES does not converge. Pays in mass-dominated steps
    /// (small Δt), where the skew part is small beside `M/(βΔt²)`.
    SymmetricPartGmres,
    /// PETSc's Krylov solvers with algebraic multigrid (issue 26, docs/distributed.md): CG or
    /// GMRES with GAMG by default, tuned by [`PetscOptions`] (`crate::petsc_solver`). Only a
    /// build with the `petsc` Cargo feature has it; the case loader refuses it otherwise, and
    /// [`LinearSolver::solve`] returns an error.
    Petsc,
}

/// How the sparse factorisations (`L Lᵀ`, `L D Lᵀ`, `L B Lᵀ`, and since issue 30 the LU too)
/// are organised: the case file's `solver.cholesky_factorisation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CholeskyFactorisation {
    /// Supernodal (dense blocks of columns with the same structure): 1.4–2.3× faster than
    /// the simplicial one on these 2D FEM/MPM matrices from about 1 000 equations on, and
    /// the LU of the Bui collapse's unsymmetric Mohr–Coulomb tangent 3.4× faster
    /// (docs/performance.md).
    #[default]
    Supernodal,
    /// Simplicial (column by column).
    Simplicial,
    /// faer's flop-ratio heuristic, which picks the simplicial one for these matrices.
    Auto,
}

impl CholeskyFactorisation {
    /// faer's threshold that forces (or leaves to its heuristic) this choice.
    fn threshold(self) -> SupernodalThreshold {
        match self {
            CholeskyFactorisation::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
            CholeskyFactorisation::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
            CholeskyFactorisation::Auto => SupernodalThreshold::AUTO,
        }
    }
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
    /// An iterative solve (`petsc`) stopped without reaching its tolerance.
    #[error("linear solver: the Krylov iterations did not converge ({reason} after {iterations} iterations)")]
    NotConverged {
        /// Krylov iterations done.
        iterations: usize,
        /// Why they stopped (PETSc's `KSPConvergedReason`, e.g. `DIVERGED_ITS`).
        reason: String,
    },
}

/// Extra PETSc options of `linear_solver: "petsc"` (the case file's `solver.petsc_options`):
/// each an option name with its leading `-` (`-ksp_type`) and its value, or
/// `None` for a flag. Kept beside [`crate::newton::NewtonSettings`] (which is `Copy`), and
/// used only by a build with the `petsc` feature (`crate::petsc_solver`'s module doc lists
/// the defaults they override).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PetscOptions {
    /// `(name, value)` pairs.
    pub options: Vec<(String, Option<String>)>,
}

/// Seconds spent in the solver phases, accumulated.
#[derive(Debug, Clone, Copy, Default)]
pub struct SolverTimings {
    /// Symbolic analyses.
    pub symbolic: f64,
    /// Numeric factorisations.
    pub factorisation: f64,
    /// Triangular solves (and GMRES iterations).
    pub solve: f64,
    /// Numeric factorisations done.
    pub factorisations: usize,
    /// Solves done by GMRES.
    pub krylov_solves: usize,
    /// GMRES iterations of those solves (failed attempts included).
    pub krylov_iterations: usize,
    /// Saddle-point systems whose symmetric indefinite factorisation (`L B Lᵀ`, `L D Lᵀ`)
    /// failed (then solved by LU).
    pub ldlt_failures: usize,
    /// Saddle-point systems solved by LU (after a failure of `L B Lᵀ` / `L D Lᵀ`, or
    /// unsymmetric).
    pub saddle_point_lu: usize,
    /// Solves with the factors of an earlier tangent ([`LinearSolver::solve_with_kept_factors`]).
    pub reused_factors: usize,
    /// Patterns on which the LU on the symmetric pattern failed (then the general LU).
    pub pattern_lu_failures: usize,
    /// PETSc solves in which GAMG did not converge, after which MUMPS's LU took over
    /// ([`crate::petsc_solver`]).
    pub gamg_failures: usize,
}

impl std::ops::AddAssign for SolverTimings {
    fn add_assign(&mut self, o: Self) {
        self.symbolic += o.symbolic;
        self.factorisation += o.factorisation;
        self.solve += o.solve;
        self.factorisations += o.factorisations;
        self.krylov_solves += o.krylov_solves;
        self.krylov_iterations += o.krylov_iterations;
        self.ldlt_failures += o.ldlt_failures;
        self.saddle_point_lu += o.saddle_point_lu;
        self.reused_factors += o.reused_factors;
        self.pattern_lu_failures += o.pattern_lu_failures;
        self.gamg_failures += o.gamg_failures;
    }
}

/// Which factorisation the last successful [`LinearSolver::solve`] left numeric, for
/// [`LinearSolver::solve_with_kept_factors`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum KeptFactors {
    /// None (no solve yet, a new pattern, a failure, or a GMRES solve).
    #[default]
    None,
    /// `P A Q = L U`.
    Lu,
    /// `P A Pᵀ = L U` on the symmetric pattern ([`PatternLu`]).
    PatternLu,
    /// `A = L Lᵀ`.
    Llt,
    /// `L B Lᵀ` (Bunch–Kaufman, `pivoting`) or `L D Lᵀ`.
    Ldlt { pivoting: bool },
}

/// Symbolic Cholesky factorisation with the numeric factor and the workspace kept between
/// refactorisations (faer's low-level API: no allocation or zeroing of the factor per
/// Newton iteration).
struct CholeskyState {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    scratch: MemBuffer,
    /// The matrix's lower triangle in the analysis' order, gathered for the supernodal
    /// factorisation (`None`: simplicial, or no permutation; faer permutes then).
    lower: Option<PermutedLower>,
}

/// Symbolic `L D Lᵀ` factorisation (the Cholesky analysis) with the factor, the expected
/// pivot signs and the workspace kept.
struct LdltState {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    scratch: MemBuffer,
    /// Bunch–Kaufman (`L B Lᵀ`): the subdiagonal of `B` and the pivoting permutation.
    subdiag: Vec<f64>,
    perm_forward: Vec<usize>,
    perm_inverse: Vec<usize>,
    /// The matrix's lower triangle in the analysis' order, for the supernodal `L B Lᵀ`
    /// (see [`CholeskyState::lower`]).
    lower: Option<PermutedLower>,
}

impl LdltState {
    /// Overwrites `x` with `A⁻¹ x` from the factor: `L B Lᵀ` with the Bunch–Kaufman
    /// permutation if `pivoting`, else `L D Lᵀ`.
    fn solve_in_place(&mut self, x: &mut [f64], pivoting: bool, par: faer::Par) {
        let n = x.len();
        let x = MatMut::from_column_major_slice_mut(x, n, 1);
        let stack = MemStack::new(&mut self.scratch);
        if pivoting {
            let perm = PermRef::new_checked(&self.perm_forward, &self.perm_inverse, n);
            IntranodeLbltRef::new(&self.symbolic, &self.values, &self.subdiag, perm).solve_in_place_with_conj(
                Conj::No,
                x,
                par,
                stack,
            );
        } else {
            LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(Conj::No, x, par, stack);
        }
    }
}

impl std::fmt::Debug for LdltState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LdltState").field("len_val", &self.values.len()).finish_non_exhaustive()
    }
}

/// Symbolic LU factorisation with the numeric factor and the workspace kept.
struct LuState {
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    scratch: MemBuffer,
}

impl CholeskyState {
    /// Overwrites `x` with `L⁻ᵀ L⁻¹ x` (the factor must be numeric).
    fn solve_in_place(&mut self, x: &mut [f64]) {
        let n = x.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            faer::get_global_parallelism(),
            MemStack::new(&mut self.scratch),
        );
    }
}

impl std::fmt::Debug for CholeskyState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskyState").field("len_val", &self.values.len()).finish_non_exhaustive()
    }
}

impl std::fmt::Debug for LuState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LuState").finish_non_exhaustive()
    }
}

/// Solves `A x = b` in place (`rhs`: `b` on entry) with an approximate inverse `solve`
/// (factors of `A`, or of a nearby matrix), followed by up to [`LDLT_REFINEMENTS`] steps of
/// iterative refinement `x ← x + solve(b − A x)` while the residual is above `1e-12 ‖b‖`;
/// `true` (and `x` in `rhs`) if it ends below `1e-8 ‖b‖`, else `false` and `rhs` unchanged.
fn refined_solve(
    pattern: &AssemblyPattern,
    values: &[f64],
    rhs: &mut [f64],
    work: &mut RefinementWork,
    mut solve: impl FnMut(&mut [f64]),
) -> bool {
    let RefinementWork { b, x, r } = work;
    b.clear();
    b.extend_from_slice(rhs);
    x.clear();
    x.extend_from_slice(rhs);
    r.resize(rhs.len(), 0.0);
    solve(x);
    let residual = |x: &[f64], r: &mut [f64]| {
        pattern.multiply(values, x, r);
        r.iter_mut().zip(b.iter()).for_each(|(ri, bi)| *ri = bi - *ri);
        norm2(r)
    };
    let bn = norm2(b);
    let mut rn = residual(x, r);
    for _ in 0..LDLT_REFINEMENTS {
        if rn <= 1e-12 * bn {
            break;
        }
        solve(r);
        x.iter_mut().zip(r.iter()).for_each(|(xi, di)| *xi += di);
        rn = residual(x, r);
    }
    let accurate = rn <= 1e-8 * bn;
    if accurate {
        rhs.copy_from_slice(x);
    }
    accurate
}

/// The vectors of [`refined_solve`] (right-hand side, solution, residual), kept between
/// solves so that a Newton iteration allocates nothing.
#[derive(Debug, Default)]
struct RefinementWork {
    b: Vec<f64>,
    x: Vec<f64>,
    r: Vec<f64>,
}

fn factorisation_error(e: impl std::fmt::Debug) -> LinearSolverError {
    LinearSolverError::Factorisation(format!("{e:?}"))
}

fn buffer(req: StackReq) -> Result<MemBuffer, LinearSolverError> {
    MemBuffer::try_new(req).map_err(|_| LinearSolverError::Factorisation("out of memory".into()))
}

/// What a solver has learnt about the matrices of its pattern, which decides how it solves
/// the next ones (kept in checkpoints: a resumed run solves as the uninterrupted one would).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SolverMemory {
    /// Cholesky failed (an indefinite tangent): LU from then on.
    pub cholesky_failed: bool,
    /// GMRES on the symmetric part's factors failed: LU from then on.
    pub symmetric_part_failed: bool,
    /// The LU on the symmetric pattern met a small pivot or an inaccurate solve: the
    /// general LU from then on.
    #[serde(default)]
    pub pattern_lu_failed: bool,
    /// Length of the last run of LU solves after an `L B Lᵀ` / `L D Lᵀ` failure
    /// ([`LDLT_BACKOFF`]).
    #[serde(default)]
    pub ldlt_backoff: u32,
    /// Solves left to LU before `L B Lᵀ` / `L D Lᵀ` is tried again.
    #[serde(default)]
    pub ldlt_skip: u32,
    /// PETSc's GAMG did not converge on this pattern: MUMPS's LU from then on (the `petsc`
    /// kind without a preconditioner in its options).
    #[serde(default)]
    pub gamg_failed: bool,
}

/// A direct solver bound to one sparsity pattern.
#[derive(Debug)]
pub struct LinearSolver {
    kind: LinearSolverKind,
    factorisation: CholeskyFactorisation,
    lu: Option<LuState>,
    pattern_lu: Option<PatternLu>,
    /// Set once the LU on the symmetric pattern failed on this pattern: the general LU from
    /// then on.
    pattern_lu_failed: bool,
    llt: Option<CholeskyState>,
    ldlt: Option<LdltState>,
    /// Expected pivot sign of each equation of a saddle-point system (`+1` displacement,
    /// `−1` pressure); empty otherwise.
    signs: Vec<i8>,
    /// Set once Cholesky failed on this pattern (indefinite tangent): use LU from then on.
    llt_failed: bool,
    /// Length of the last run of LU solves after an `L D Lᵀ` failure ([`LDLT_BACKOFF`]).
    ldlt_backoff: u32,
    /// Solves left to LU before `L D Lᵀ` is tried again.
    ldlt_skip: u32,
    /// Set once GMRES on the symmetric part's factors failed on this pattern: LU from then on.
    symmetric_part_failed: bool,
    /// Set once PETSc's GAMG did not converge on this pattern: MUMPS's LU from then on (a
    /// new pattern tries GAMG again; a checkpoint keeps the flag, [`SolverMemory`]).
    gamg_failed: bool,
    /// `(A + Aᵀ)/2` for its factorisation.
    symmetric_values: Vec<f64>,
    gmres: Gmres,
    /// The factors the last successful solve left.
    kept: KeptFactors,
    /// Work vectors of the refined solves.
    refinement: RefinementWork,
    /// Options of the `petsc` kind.
    petsc_options: PetscOptions,
    /// Near null space of the matrices (the `petsc` kind's GAMG), one vector per mode.
    near_null_space: Vec<Vec<f64>>,
    /// The PETSc solver of this pattern (`petsc` kind, after the first solve).
    #[cfg(feature = "petsc")]
    petsc: Option<crate::petsc_solver::PetscSolver>,
    /// In a distributed run, this rank's rows of the matrix ([`LinearSolver::distribute`]).
    owned_rows: Option<crate::ranks::OwnedRows>,
    /// Accumulated timings.
    pub timings: SolverTimings,
}

impl LinearSolver {
    /// A solver of the given kind whose Cholesky-type factorisations are organised as
    /// `factorisation`; symbolic analyses happen at the first solve.
    pub fn new(kind: LinearSolverKind, factorisation: CholeskyFactorisation) -> Self {
        Self {
            kind,
            factorisation,
            lu: None,
            pattern_lu: None,
            pattern_lu_failed: false,
            llt: None,
            ldlt: None,
            signs: Vec::new(),
            llt_failed: false,
            ldlt_backoff: 0,
            ldlt_skip: 0,
            symmetric_part_failed: false,
            gamg_failed: false,
            symmetric_values: Vec::new(),
            gmres: Gmres::default(),
            kept: KeptFactors::None,
            refinement: RefinementWork::default(),
            petsc_options: PetscOptions::default(),
            near_null_space: Vec::new(),
            #[cfg(feature = "petsc")]
            petsc: None,
            owned_rows: None,
            timings: SolverTimings::default(),
        }
    }

    /// Sets the near null space of this pattern's matrices (vectors per equation, e.g. the
    /// rigid-body modes), which the `petsc` kind gives its GAMG preconditioner (before the
    /// first solve); the direct solvers do not use it.
    pub fn set_near_null_space(&mut self, vectors: Vec<Vec<f64>>) {
        self.near_null_space = vectors;
    }

    /// Sets the extra PETSc options of the `petsc` kind (before the first solve).
    pub fn set_petsc_options(&mut self, options: PetscOptions) {
        self.petsc_options = options;
    }

    /// Makes the solves distributed over the ranks (before the first solve; the `petsc` kind
    /// only): this rank owns `rows` of the matrix, each solve receives this rank's part of
    /// the matrix (the blocks it assembles) and the whole right-hand side, and returns the
    /// whole solution on every rank ([`crate::ranks`]). Called again (a new partition of the
    /// blocks, [`crate::assembler::Assembler::rebalance`]), the PETSc solver is set up again
    /// at the next solve, with this rank's new contribution.
    pub fn distribute(&mut self, rows: crate::ranks::OwnedRows) {
        self.owned_rows = Some(rows);
        #[cfg(feature = "petsc")]
        {
            self.petsc = None;
        }
        self.kept = KeptFactors::None;
    }

    /// What this solver has learnt about its pattern's matrices.
    pub fn memory(&self) -> SolverMemory {
        SolverMemory {
            cholesky_failed: self.llt_failed,
            symmetric_part_failed: self.symmetric_part_failed,
            pattern_lu_failed: self.pattern_lu_failed,
            ldlt_backoff: self.ldlt_backoff,
            ldlt_skip: self.ldlt_skip,
            gamg_failed: self.gamg_failed,
        }
    }

    /// Starts from what a solver of the same pattern had learnt ([`LinearSolver::memory`]).
    pub fn remember(&mut self, memory: SolverMemory) {
        self.llt_failed = memory.cholesky_failed;
        self.symmetric_part_failed = memory.symmetric_part_failed;
        self.pattern_lu_failed = memory.pattern_lu_failed;
        self.ldlt_backoff = memory.ldlt_backoff;
        self.ldlt_skip = memory.ldlt_skip;
        self.gamg_failed = memory.gamg_failed;
    }

    /// Entries (values) of the factor the last successful solve left if it is Cholesky-type
    /// (`L Lᵀ`, `L D Lᵀ`, `L B Lᵀ`); `None` after an LU, a GMRES solve or before any solve.
    pub fn factor_entries(&self) -> Option<usize> {
        match self.kept {
            KeptFactors::Llt => self.llt.as_ref().map(|st| st.values.len()),
            KeptFactors::Ldlt { .. } => self.ldlt.as_ref().map(|st| st.values.len()),
            KeptFactors::PatternLu => self.pattern_lu.as_ref().map(PatternLu::factor_entries),
            KeptFactors::Lu | KeptFactors::None => None,
        }
    }

    /// Forgets the symbolic factorisations (call when the pattern changes).
    pub fn reset_pattern(&mut self) {
        self.lu = None;
        self.pattern_lu = None;
        self.pattern_lu_failed = false;
        self.llt = None;
        self.ldlt = None;
        self.kept = KeptFactors::None;
        #[cfg(feature = "petsc")]
        {
            self.petsc = None;
        }
        self.llt_failed = false;
        self.ldlt_backoff = 0;
        self.ldlt_skip = 0;
        self.symmetric_part_failed = false;
    }

    /// Declares a saddle-point system: the expected pivot sign of every equation (`+1` on
    /// displacement equations, `−1` on pressure equations), for `L D Lᵀ`.
    pub fn set_saddle_point(&mut self, signs: Vec<i8>) {
        self.signs = signs;
    }

    /// GMRES on `A x = b` preconditioned by the Cholesky factors held in the Cholesky state
    /// (of the symmetric part); `true` if it converged (then `rhs` holds `x`; otherwise `rhs`
    /// is unchanged).
    fn solve_by_gmres(&mut self, pattern: &AssemblyPattern, values: &[f64], rhs: &mut [f64]) -> bool {
        let st = self.llt.as_mut().expect("Cholesky factor present");
        let precondition = |z: &mut [f64]| st.solve_in_place(z);
        let report = self.gmres.solve(
            rhs,
            KRYLOV_MAX_ITERATIONS,
            KRYLOV_TOLERANCE,
            |x, y| pattern.multiply(values, x, y),
            precondition,
        );
        self.timings.krylov_solves += usize::from(report.converged);
        self.timings.krylov_iterations += report.iterations;
        report.converged
    }

    /// Solves `A x = b` in place (`rhs` holds `b` on entry and `x` on exit): numeric
    /// factorisation (symbolic analysis first if the pattern is new), then the solve: Cholesky and triangular solves for a symmetric `A`; for an unsymmetric one under
    /// `symmetric_part_gmres`, GMRES preconditioned by the Cholesky factors of the symmetric
    /// part `(A + Aᵀ)/2` (far cheaper than LU, whose column ordering fills in more), and LU
    /// with partial pivoting otherwise, or if that part is not positive definite or GMRES
    /// does not converge (then LU for the rest of this pattern). The SIMD state faer's
    /// kernels leave is cleared before returning ([`crate::simd_state`]).
    pub fn solve(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), LinearSolverError> {
        let result = self.solve_any(pattern, values, rhs);
        crate::simd_state::clear_upper_state();
        result
    }

    /// [`LinearSolver::solve`] before the SIMD state is cleared.
    fn solve_any(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), LinearSolverError> {
        let n = pattern.num_equations();
        self.kept = KeptFactors::None;
        if self.kind == LinearSolverKind::Petsc {
            return self.solve_petsc(pattern, values, rhs);
        }
        if self.owned_rows.is_some() {
            return Err(LinearSolverError::Factorisation(
                "a distributed run (more than one MPI rank) needs the `petsc` linear solver".into(),
            ));
        }
        if n == 0 {
            return Ok(());
        }
        let ldlt = match self.kind {
            LinearSolverKind::Ldlt | LinearSolverKind::Lblt => true,
            LinearSolverKind::Auto => !self.signs.is_empty(),
            _ => false,
        };
        if ldlt {
            if self.ldlt_skip > 0 {
                self.ldlt_skip -= 1;
            } else if pattern.is_symmetric(values, 1e-10) {
                if self.solve_symmetric_indefinite(pattern, values, rhs)? {
                    self.ldlt_backoff = 0;
                    self.kept = KeptFactors::Ldlt { pivoting: self.kind != LinearSolverKind::Ldlt };
                    return check_finite(rhs);
                }
                self.ldlt_backoff = (2 * self.ldlt_backoff + 1).min(LDLT_BACKOFF);
                self.ldlt_skip = self.ldlt_backoff;
                self.timings.ldlt_failures += 1;
            }
            self.timings.saddle_point_lu += 1;
            return self.solve_lu(pattern, values, rhs);
        }
        let symmetric = match self.kind {
            LinearSolverKind::Cholesky => true,
            LinearSolverKind::Lu | LinearSolverKind::Ldlt | LinearSolverKind::Lblt | LinearSolverKind::Petsc => false,
            LinearSolverKind::Auto | LinearSolverKind::SymmetricPartGmres => {
                !self.llt_failed && pattern.is_symmetric(values, 1e-10)
            }
        };
        if symmetric {
            if self.factorise_cholesky(pattern, values)? {
                let t = Instant::now();
                self.llt.as_mut().expect("Cholesky factor present").solve_in_place(rhs);
                self.timings.solve += t.elapsed().as_secs_f64();
                self.kept = KeptFactors::Llt;
                return check_finite(rhs);
            }
            if self.kind == LinearSolverKind::Cholesky {
                return Err(LinearSolverError::Factorisation("Cholesky failed: matrix not positive definite".into()));
            }
            self.llt_failed = true;
        } else if self.kind == LinearSolverKind::SymmetricPartGmres && !self.symmetric_part_failed {
            let mut sym = std::mem::take(&mut self.symmetric_values);
            pattern.symmetric_part(values, &mut sym);
            let factored = self.factorise_cholesky(pattern, &sym);
            self.symmetric_values = sym;
            if factored? {
                let t = Instant::now();
                let converged = self.solve_by_gmres(pattern, values, rhs);
                self.timings.solve += t.elapsed().as_secs_f64();
                if converged {
                    return check_finite(rhs);
                }
            }
            self.symmetric_part_failed = true;
        }
        self.solve_lu(pattern, values, rhs)
    }

    /// The `petsc` kind: PETSc's Krylov solver of this pattern ([`crate::petsc_solver`]),
    /// created at the first solve.
    #[cfg(feature = "petsc")]
    fn solve_petsc(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), LinearSolverError> {
        if pattern.num_equations() == 0 {
            return Ok(());
        }
        if self.petsc.is_none() {
            let t = Instant::now();
            self.petsc = Some(crate::petsc_solver::PetscSolver::new(
                pattern,
                &self.petsc_options,
                &self.near_null_space,
                self.owned_rows.as_ref(),
                self.gamg_failed,
            )?);
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let solver = self.petsc.as_mut().expect("PETSc solver present");
        let solved = solver.solve(pattern, values, rhs, &mut self.timings);
        self.gamg_failed |= solver.gamg_failed();
        solved?;
        check_finite(rhs)
    }

    /// The `petsc` kind in a build without the feature: an error.
    #[cfg(not(feature = "petsc"))]
    fn solve_petsc(&mut self, _: &AssemblyPattern, _: &[f64], _: &mut [f64]) -> Result<(), LinearSolverError> {
        Err(LinearSolverError::Factorisation(
            "`petsc` is not in this build (it needs the `petsc` Cargo feature)".into(),
        ))
    }

    /// Sparse LU: on the symmetric pattern ([`PatternLu`]) unless the kind is `lu` or it
    /// has failed on this pattern, else with partial pivoting (faer's; symbolic analysis
    /// once per pattern).
    fn solve_lu(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), LinearSolverError> {
        if self.kind != LinearSolverKind::Lu && !self.pattern_lu_failed {
            if self.solve_pattern_lu(pattern, values, rhs) {
                self.kept = KeptFactors::PatternLu;
                return check_finite(rhs);
            }
            self.pattern_lu_failed = true;
            self.pattern_lu = None;
            self.timings.pattern_lu_failures += 1;
        }
        let n = pattern.num_equations();
        let par = faer::get_global_parallelism();
        if self.lu.is_none() {
            let t = Instant::now();
            let a = pattern.matrix(values);
            // supernodal unless asked otherwise: faer's flop-ratio heuristic picks the simplicial
            // LU for these 2D MPM matrices, 3.4× slower on the Bui collapse (performance.md)
            let params = LuSymbolicParams {
                supernodal_flop_ratio_threshold: self.factorisation.threshold(),
                ..Default::default()
            };
            let symbolic = factorize_symbolic_lu(a.symbolic(), params).map_err(factorisation_error)?;
            let scratch = buffer(StackReq::any_of(&[
                symbolic.factorize_numeric_lu_scratch::<f64>(par, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, par),
            ]))?;
            self.lu = Some(LuState { symbolic, numeric: NumericLu::new(), scratch });
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let t = Instant::now();
        let st = self.lu.as_mut().expect("symbolic LU present");
        let lu = st
            .symbolic
            .factorize_numeric_lu::<f64>(
                &mut st.numeric,
                pattern.matrix(values),
                par,
                MemStack::new(&mut st.scratch),
                Default::default(),
            )
            .map_err(|e| LinearSolverError::Factorisation(format!("LU failed: {e}")))?;
        crate::simd_state::clear_upper_state();
        self.timings.factorisation += t.elapsed().as_secs_f64();
        self.timings.factorisations += 1;
        let t = Instant::now();
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            par,
            MemStack::new(&mut st.scratch),
        );
        self.timings.solve += t.elapsed().as_secs_f64();
        self.kept = KeptFactors::Lu;
        check_finite(rhs)
    }

    /// LU on the symmetric pattern and a refined solve; `false` (and `rhs` unchanged) if the
    /// analysis, a pivot or the solve's accuracy fails.
    fn solve_pattern_lu(&mut self, pattern: &AssemblyPattern, values: &[f64], rhs: &mut [f64]) -> bool {
        if self.pattern_lu.is_none() {
            let t = Instant::now();
            self.pattern_lu = PatternLu::analyse(pattern.symbolic().as_ref());
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let Some(lu) = self.pattern_lu.as_mut() else { return false };
        let t = Instant::now();
        let factored = lu.factorise(pattern.matrix(values)).is_ok();
        self.timings.factorisation += t.elapsed().as_secs_f64();
        if !factored {
            return false;
        }
        self.timings.factorisations += 1;
        let t = Instant::now();
        let accurate = refined_solve(pattern, values, rhs, &mut self.refinement, |x| lu.solve_in_place(x));
        self.timings.solve += t.elapsed().as_secs_f64();
        accurate
    }

    /// Solves `A_k x = b` in place with the factors that the last successful
    /// [`solve`](Self::solve) left, of an earlier matrix `A_k` of this pattern (modified
    /// Newton, [`crate::newton`]): triangular solves only, without refinement. `Ok(false)`
    /// (and `rhs` unchanged) if there are none.
    pub fn solve_with_kept_factors(&mut self, rhs: &mut [f64]) -> Result<bool, LinearSolverError> {
        let n = rhs.len();
        let par = faer::get_global_parallelism();
        let t = Instant::now();
        match self.kept {
            KeptFactors::None => return Ok(false),
            KeptFactors::Llt => self.llt.as_mut().expect("Cholesky factor kept").solve_in_place(rhs),
            KeptFactors::PatternLu => self.pattern_lu.as_mut().expect("pattern LU kept").solve_in_place(rhs),
            KeptFactors::Lu => {
                let st = self.lu.as_mut().expect("LU factor kept");
                LuRef::new_unchecked(&st.symbolic, &st.numeric).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(rhs, n, 1),
                    par,
                    MemStack::new(&mut st.scratch),
                );
            }
            KeptFactors::Ldlt { pivoting } => {
                let st = self.ldlt.as_mut().expect("L D Lᵀ factor kept");
                st.solve_in_place(rhs, pivoting, par);
            }
        }
        crate::simd_state::clear_upper_state();
        self.timings.solve += t.elapsed().as_secs_f64();
        self.timings.reused_factors += 1;
        check_finite(rhs).map(|()| true)
    }

    /// `L B Lᵀ` (Bunch–Kaufman; `L D Lᵀ` with signed regularisation for the `ldlt` kind) of
    /// the symmetric saddle-point matrix (module doc) and the solve, with up to
    /// [`LDLT_REFINEMENTS`] steps of iterative refinement while the residual is not at
    /// round-off; `false` if the factorisation failed or the solution is not accurate to 1e-8
    /// (then `rhs` is unchanged).
    fn solve_symmetric_indefinite(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
    ) -> Result<bool, LinearSolverError> {
        let a = pattern.matrix(values);
        let par = faer::get_global_parallelism();
        if self.ldlt.is_none() {
            let t = Instant::now();
            let symbolic = symbolic_cholesky(&a, self.factorisation)?;
            let scratch = buffer(StackReq::any_of(&[
                symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
                symbolic.factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, par),
            ]))?;
            let values = vec![0.0; symbolic.len_val()];
            let n = symbolic.nrows();
            let lower = permuted_lower(&symbolic, &a);
            self.ldlt = Some(LdltState {
                symbolic,
                values,
                scratch,
                subdiag: vec![0.0; n],
                perm_forward: vec![0; n],
                perm_inverse: vec![0; n],
                lower,
            });
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let n = rhs.len();
        let signs: Vec<i8> = if self.signs.len() == n { self.signs.clone() } else { vec![1; n] };
        let diag_max = (0..n).fold(0.0f64, |m, c| {
            let (col_ptr, row_idx) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
            (col_ptr[c]..col_ptr[c + 1]).filter(|&k| row_idx[k] == c).fold(m, |m, k| m.max(values[k].abs()))
        });
        let t = Instant::now();
        let st = self.ldlt.as_mut().expect("symbolic LDLT present");
        // `auto` on a saddle point, and `lblt`: Bunch–Kaufman; `ldlt`: signed regularisation
        let pivoting = self.kind != LinearSolverKind::Ldlt;
        if pivoting {
            let stack = MemStack::new(&mut st.scratch);
            if let (Some(lower), SymbolicCholeskyRaw::Supernodal(sn)) = (&mut st.lower, st.symbolic.raw()) {
                supernodal::factorize_supernodal_numeric_intranode_lblt(
                    &mut st.values,
                    &mut st.subdiag,
                    &mut st.perm_forward,
                    &mut st.perm_inverse,
                    lower.matrix(values),
                    sn,
                    par,
                    stack,
                    Default::default(),
                );
            } else {
                st.symbolic.factorize_numeric_intranode_lblt::<f64>(
                    &mut st.values,
                    &mut st.subdiag,
                    &mut st.perm_forward,
                    &mut st.perm_inverse,
                    a,
                    Side::Lower,
                    par,
                    stack,
                    Default::default(),
                );
            }
        } else {
            let regularization = LdltRegularization {
                dynamic_regularization_signs: Some(&signs),
                dynamic_regularization_delta: 1e-8 * diag_max,
                dynamic_regularization_epsilon: 1e-13 * diag_max,
            };
            let factor = st.symbolic.factorize_numeric_ldlt::<f64>(
                &mut st.values,
                a,
                Side::Lower,
                regularization,
                par,
                MemStack::new(&mut st.scratch),
                Default::default(),
            );
            if factor.is_err() {
                self.timings.factorisation += t.elapsed().as_secs_f64();
                return Ok(false);
            }
        }
        crate::simd_state::clear_upper_state();
        self.timings.factorisation += t.elapsed().as_secs_f64();
        self.timings.factorisations += 1;
        let t = Instant::now();
        let accurate = refined_solve(pattern, values, rhs, &mut self.refinement, |x| {
            st.solve_in_place(x, pivoting, par);
            crate::simd_state::clear_upper_state();
        });
        self.timings.solve += t.elapsed().as_secs_f64();
        Ok(accurate)
    }

    /// Cholesky factorisation of the symmetric matrix with nonzeros `values` (its lower
    /// triangle is read) into the Cholesky state; `false` if it is not positive
    /// definite.
    fn factorise_cholesky(&mut self, pattern: &AssemblyPattern, values: &[f64]) -> Result<bool, LinearSolverError> {
        let a = pattern.matrix(values);
        let par = faer::get_global_parallelism();
        if self.llt.is_none() {
            let t = Instant::now();
            let symbolic = symbolic_cholesky(&a, self.factorisation)?;
            let scratch = buffer(StackReq::any_of(&[
                symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, par),
            ]))?;
            let values = vec![0.0; symbolic.len_val()];
            let lower = permuted_lower(&symbolic, &a);
            self.llt = Some(CholeskyState { symbolic, values, scratch, lower });
            self.timings.symbolic += t.elapsed().as_secs_f64();
        }
        let t = Instant::now();
        let st = self.llt.as_mut().expect("symbolic Cholesky present");
        let stack = MemStack::new(&mut st.scratch);
        let factored = match (&mut st.lower, st.symbolic.raw()) {
            (Some(lower), SymbolicCholeskyRaw::Supernodal(supernodal)) => supernodal::factorize_supernodal_numeric_llt(
                &mut st.values,
                lower.matrix(values),
                Default::default(),
                supernodal,
                par,
                stack,
                Default::default(),
            )
            .is_ok(),
            _ => st
                .symbolic
                .factorize_numeric_llt::<f64>(
                    &mut st.values,
                    a,
                    Side::Lower,
                    Default::default(),
                    par,
                    stack,
                    Default::default(),
                )
                .is_ok(),
        };
        crate::simd_state::clear_upper_state();
        self.timings.factorisation += t.elapsed().as_secs_f64();
        self.timings.factorisations += 1;
        Ok(factored)
    }
}

/// A Cholesky factorisation kept for repeated solves with one symmetric positive definite
/// matrix (e.g. the graph Laplacian of a grid's mesh motion, factorised once per grid).
pub struct CholeskyFactor {
    state: CholeskyState,
}

impl CholeskyFactor {
    /// Factorises the matrix with nonzeros `values` on `pattern` (its lower triangle is read).
    pub fn new(pattern: &AssemblyPattern, values: &[f64]) -> Result<Self, LinearSolverError> {
        let mut solver = LinearSolver::new(LinearSolverKind::Cholesky, CholeskyFactorisation::default());
        if pattern.num_equations() == 0 {
            return Err(LinearSolverError::Factorisation("no equation".into()));
        }
        if !solver.factorise_cholesky(pattern, values)? {
            return Err(LinearSolverError::Factorisation("Cholesky failed: matrix not positive definite".into()));
        }
        Ok(Self { state: solver.llt.take().expect("factorised") })
    }

    /// Overwrites `x` with `A⁻¹ x`.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        self.state.solve_in_place(x);
    }
}

impl std::fmt::Debug for CholeskyFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskyFactor").finish_non_exhaustive()
    }
}

/// The symbolic Cholesky analysis (AMD ordering, elimination tree, supernodes) of the
/// lower triangle of `a`, shared by the `L Lᵀ`, `L D Lᵀ` and Bunch–Kaufman factorisations.
/// The gather map of `a`'s lower triangle into the order of a supernodal analysis with a
/// fill-reducing permutation (`None` otherwise: faer's permuting path serves).
fn permuted_lower(symbolic: &SymbolicCholesky<usize>, a: &SparseColMatRef<'_, usize, f64>) -> Option<PermutedLower> {
    match (symbolic.raw(), symbolic.perm()) {
        (SymbolicCholeskyRaw::Supernodal(_), Some(perm)) => Some(PermutedLower::new(a.symbolic(), perm.arrays().1)),
        _ => None,
    }
}

fn symbolic_cholesky(
    a: &SparseColMatRef<'_, usize, f64>,
    factorisation: CholeskyFactorisation,
) -> Result<SymbolicCholesky<usize>, LinearSolverError> {
    let params =
        CholeskySymbolicParams { supernodal_flop_ratio_threshold: factorisation.threshold(), ..Default::default() };
    factorize_symbolic_cholesky(a.symbolic(), Side::Lower, Default::default(), params).map_err(factorisation_error)
}

fn norm2(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn check_finite(x: &[f64]) -> Result<(), LinearSolverError> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LinearSolverError::NonFinite)
    }
}
