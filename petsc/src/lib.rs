//! Thin bindings to PETSc (the system library, found by pkg-config; bindgen over
//! `petscksp.h` in `build.rs`, allowlisted to what Loam calls) and a small safe layer: one
//! AIJ matrix with a fixed nonzero pattern, its two vectors and a Krylov solver (issue 26,
//! `docs/distributed.md`), sequential (`MATSEQAIJ`, values written in place) or distributed
//! over the ranks of `PETSC_COMM_WORLD` (`MATMPIAIJ`, rows split in contiguous ranges, each
//! rank adding its contribution with `ADD_VALUES` through PETSc's stash, the solution
//! gathered to every rank by `VecScatterCreateToAll`); and [`VectorSum`], the sum over the
//! ranks of a vector that each rank holds a part of.
//!
//! **Process-wide state.** PETSc (and the MPI it initialises) is initialised once per process,
//! lazily, by the first [`KrylovSolver::new`], with `MPI_THREAD_SERIALIZED`, PETSc's signal
//! handlers off (`-no_signal_handler`: Loam's own SIGINT/SIGTERM handling checkpoints) and
//! PETSc's error handler replaced by the returning one (an error is a [`Error`], not a
//! traceback on stderr). If MPI is already running (an `mpi` build initialises it with rsmpi
//! before PETSc), it is left to its owner: [`finalize`] then ends PETSc only. PETSc built without thread safety must not be entered by two threads
//! at once: every call of this crate holds one process-wide lock, which is what makes
//! [`KrylovSolver`] `Send`. [`finalize`] ends PETSc and MPI; a process that never calls it
//! exits without (Open MPI's singleton mode does not complain).
//!
//! **Options.** Each solver has its own options prefix (`loam<k>_`), so the options of one
//! solver (`-ksp_type`, `-pc_type`, …, given without the prefix) go into PETSc's options
//! database under that prefix and reach its KSP, PC and their inner solvers (multigrid
//! levels) without touching another solver's.

pub mod sys;
mod vector_sum;

pub use vector_sum::VectorSum;

use std::ffi::{c_char, CStr, CString};
use std::ops::Range;
use std::ptr;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, OnceLock};

/// An error reported by PETSc or MPI.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    /// The PETSc function that failed.
    pub call: &'static str,
    /// PETSc's error code (MPI's for an MPI call).
    pub code: i32,
    /// PETSc's text for the code.
    pub message: String,
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PETSc {} failed (error {}: {})", self.call, self.code, self.message)
    }
}

impl std::error::Error for Error {}

/// The lock every PETSc call of this crate holds (module doc).
static LOCK: Mutex<()> = Mutex::new(());
/// The outcome of the one initialisation.
static INIT: OnceLock<Result<(), Error>> = OnceLock::new();
/// Solvers created: the next options prefix.
static PREFIXES: AtomicUsize = AtomicUsize::new(0);
/// Whether [`initialize`] started MPI (else its owner, e.g. rsmpi's `Universe`, ends it).
static STARTED_MPI: AtomicBool = AtomicBool::new(false);

pub(crate) fn lock() -> MutexGuard<'static, ()> {
    // a panic while the lock was held leaves PETSc as consistent as the panic left it; the
    // caller's error handling decides, not the poisoning
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// `Ok` for PETSc's success code, the [`Error`] with PETSc's message otherwise (call with
/// the lock held).
pub(crate) fn check(call: &'static str, code: sys::PetscErrorCode) -> Result<(), Error> {
    if code == 0 {
        return Ok(());
    }
    let mut text: *const c_char = ptr::null();
    // SAFETY: PetscErrorMessage only writes a pointer to a static string of PETSc's table
    // (or leaves it null for an unknown code); the third argument may be null.
    let known = unsafe { sys::PetscErrorMessage(code, &mut text, ptr::null_mut()) } == 0 && !text.is_null();
    let message = if known {
        // SAFETY: a non-null pointer from PetscErrorMessage is a NUL-terminated static string.
        unsafe { CStr::from_ptr(text) }.to_string_lossy().into_owned()
    } else {
        "unknown error".to_string()
    };
    Err(Error { call, code, message })
}

/// A C string of Loam's own text (no NUL inside: the texts are option names and values).
fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("no NUL left")
}

/// Initialises MPI and PETSc once per process (module doc); later calls return the first
/// outcome.
pub fn initialize() -> Result<(), Error> {
    INIT.get_or_init(|| {
        let _guard = lock();
        let mut mpi_up = 0;
        // SAFETY: MPI_Initialized may be called at any time, before MPI_Init too.
        check("MPI_Initialized", unsafe { sys::MPI_Initialized(&mut mpi_up) })?;
        if mpi_up == 0 {
            let mut provided = 0;
            // SAFETY: null argc/argv are allowed by MPI-2 and later; MPI is not initialised
            // yet (checked above) and this runs once (OnceLock). SERIALIZED: PETSc is entered
            // from whichever thread runs a solve, one at a time (the lock).
            let code = unsafe {
                sys::MPI_Init_thread(ptr::null_mut(), ptr::null_mut(), sys::MPI_THREAD_SERIALIZED as i32, &mut provided)
            };
            check("MPI_Init_thread", code)?;
            STARTED_MPI.store(true, Ordering::Relaxed);
        }
        let no_signals = c_string("-no_signal_handler");
        // SAFETY: PETSc documents PetscOptionsSetValue before PetscInitialize (the options
        // are then read by it); the strings outlive the call (copied by PETSc).
        check("PetscOptionsSetValue", unsafe {
            sys::PetscOptionsSetValue(ptr::null_mut(), no_signals.as_ptr(), ptr::null())
        })?;
        // SAFETY: called once, with MPI initialised; PETSc does not finalise an MPI it did
        // not initialise (that is [`finalize`]'s job).
        check("PetscInitializeNoArguments", unsafe { sys::PetscInitializeNoArguments() })?;
        // SAFETY: PetscReturnErrorHandler is PETSc's own handler with the signature
        // PetscPushErrorHandler expects; no context is needed.
        check("PetscPushErrorHandler", unsafe {
            sys::PetscPushErrorHandler(Some(sys::PetscReturnErrorHandler), ptr::null_mut())
        })?;
        Ok(())
    })
    .clone()
}

/// Ends PETSc if [`initialize`] started it, and MPI if it started that too (call at the end of
/// the process, after every [`KrylovSolver`] and [`VectorSum`] has been dropped; none can be
/// created afterwards; an MPI started by rsmpi is ended by its `Universe`, after this).
pub fn finalize() -> Result<(), Error> {
    if !matches!(INIT.get(), Some(Ok(()))) {
        return Ok(());
    }
    let _guard = lock();
    let mut done = sys::PetscBool::PETSC_FALSE;
    // SAFETY: PetscFinalized may be called at any time.
    check("PetscFinalized", unsafe { sys::PetscFinalized(&mut done) })?;
    if done == sys::PetscBool::PETSC_FALSE {
        // SAFETY: PETSc was initialised by `initialize` and not finalised (checked above).
        check("PetscFinalize", unsafe { sys::PetscFinalize() })?;
    }
    if !STARTED_MPI.load(Ordering::Relaxed) {
        return Ok(());
    }
    let mut mpi_done = 0;
    // SAFETY: MPI_Finalized may be called at any time.
    check("MPI_Finalized", unsafe { sys::MPI_Finalized(&mut mpi_done) })?;
    if mpi_done == 0 {
        // SAFETY: MPI was initialised (PETSc's initialisation needs it) and is not finalised.
        check("MPI_Finalize", unsafe { sys::MPI_Finalize() })?;
    }
    Ok(())
}

/// The outcome of one [`KrylovSolver::solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// Krylov iterations.
    pub iterations: usize,
    /// Whether PETSc reports convergence (a positive `KSPConvergedReason`).
    pub converged: bool,
    /// PETSc's `KSPConvergedReason` (negative: diverged).
    pub reason: i32,
    /// The residual norm PETSc's test saw last (unpreconditioned unless changed by options).
    pub residual_norm: f64,
    /// Seconds in the preconditioner's set-up (`KSPSetUp`: AMG hierarchy, factorisation).
    pub setup_seconds: f64,
    /// Seconds in the Krylov iterations (`KSPSolve`).
    pub solve_seconds: f64,
}

/// PETSc's name of a `KSPConvergedReason`.
pub fn reason_name(reason: i32) -> &'static str {
    match reason {
        1 => "CONVERGED_RTOL_NORMAL",
        2 => "CONVERGED_RTOL",
        3 => "CONVERGED_ATOL",
        4 => "CONVERGED_ITS",
        5 => "CONVERGED_CG_NEG_CURVE",
        6 => "CONVERGED_CG_CONSTRAINED",
        7 => "CONVERGED_STEP_LENGTH",
        8 => "CONVERGED_HAPPY_BREAKDOWN",
        9 => "CONVERGED_ATOL_NORMAL",
        -2 => "DIVERGED_NULL",
        -3 => "DIVERGED_ITS",
        -4 => "DIVERGED_DTOL",
        -5 => "DIVERGED_BREAKDOWN",
        -6 => "DIVERGED_BREAKDOWN_BICG",
        -7 => "DIVERGED_NONSYMMETRIC",
        -8 => "DIVERGED_INDEFINITE_PC",
        -9 => "DIVERGED_NANORINF",
        -10 => "DIVERGED_INDEFINITE_MAT",
        -11 => "DIVERGED_PC_FAILED",
        0 => "ITERATING",
        _ => "unknown reason",
    }
}

/// How [`KrylovSolver::configure`] sets the solver up before the options of the solver's
/// prefix are applied (which override it).
#[derive(Debug, Clone, PartialEq)]
pub struct KrylovSettings {
    /// PETSc's KSP type, e.g. `gmres`, `cg`.
    pub ksp_type: String,
    /// PETSc's PC type, e.g. `gamg`, `hypre`, `lu`.
    pub pc_type: String,
    /// The factorisation package of a factorising PC (`mumps`), if any.
    pub factor_package: Option<String>,
    /// Relative tolerance of the Krylov iterations.
    pub relative_tolerance: f64,
    /// Largest number of Krylov iterations.
    pub max_iterations: usize,
    /// GMRES restart length.
    pub gmres_restart: usize,
    /// Right preconditioning: the convergence test then sees the true residual `‖b − A x‖`
    /// under GMRES (CG tests the unpreconditioned norm either way).
    pub right_preconditioning: bool,
}

/// Rows of a matrix in compressed-row form: row `rows[i]` (a global equation) has the
/// columns `cols[row_ptr[i]..row_ptr[i + 1]]` (global, sorted within the row).
#[derive(Debug, Clone, Copy)]
pub struct RowPattern<'a> {
    /// Global index of each row.
    pub rows: &'a [usize],
    /// Start of each row in `cols`; `rows.len() + 1` entries.
    pub row_ptr: &'a [usize],
    /// Global column indices.
    pub cols: &'a [usize],
}

/// How the matrix is stored across the ranks.
enum Layout {
    /// `MATSEQAIJ` on one process: the values are written in place, in the order of the
    /// compressed-row pattern it was preallocated with.
    Sequential,
    /// `MATMPIAIJ` over the ranks of `PETSC_COMM_WORLD`: this rank's contribution (rows of
    /// any rank) is added with `ADD_VALUES`; the solution is gathered to every rank.
    Distributed {
        /// The rows this rank contributes to, as PETSc indices.
        rows: Vec<sys::PetscInt>,
        /// Start of each contributed row in `cols` and in the values.
        row_ptr: Vec<usize>,
        /// Columns of the contributed entries, as PETSc indices.
        cols: Vec<sys::PetscInt>,
        /// The contributed values of the current matrix.
        values: Vec<f64>,
        /// `VecScatterCreateToAll` from the solution to `x_all`.
        gather: sys::VecScatter,
        /// The whole solution on this rank (a sequential vector of `n` entries).
        x_all: sys::Vec,
    },
}

/// An AIJ matrix with a fixed nonzero pattern, its vectors and a KSP: sequential
/// ([`KrylovSolver::new`]) or distributed over the ranks ([`KrylovSolver::distributed`]).
pub struct KrylovSolver {
    mat: sys::Mat,
    x: sys::Vec,
    b: sys::Vec,
    ksp: sys::KSP,
    /// Number of equations (global).
    n: usize,
    /// The equations whose rows (and vector entries) this rank owns (`0..n` on one process).
    owned: Range<usize>,
    /// Stored entries of the sequential matrix, or of this rank's contribution.
    nnz: usize,
    layout: Layout,
    /// Options prefix `loam<k>_`.
    prefix: String,
    /// Full names of the options this solver put into PETSc's database (cleared on drop).
    options: Vec<CString>,
}

// SAFETY: the PETSc objects are owned by this value alone and every PETSc call that touches
// them holds the process-wide lock (module doc), so moving the value to another thread
// cannot race; MPI is initialised with MPI_THREAD_SERIALIZED for that.
unsafe impl Send for KrylovSolver {}

impl std::fmt::Debug for KrylovSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KrylovSolver")
            .field("n", &self.n)
            .field("owned", &self.owned)
            .field("nnz", &self.nnz)
            .field("prefix", &self.prefix)
            .finish()
    }
}

/// The indices as PETSc's (32-bit) integers, or the error naming `what` if one does not fit.
pub(crate) fn petsc_indices(values: &[usize], what: &str) -> Result<Vec<sys::PetscInt>, Error> {
    values.iter().map(|&v| sys::PetscInt::try_from(v)).collect::<Result<_, _>>().map_err(|_| Error {
        call: "KrylovSolver",
        code: 0,
        message: format!("{what} exceed PETSc's 32-bit indices"),
    })
}

impl KrylovSolver {
    /// A solver on one process for `n × n` matrices with the compressed-row pattern
    /// `row_ptr` (`n + 1` entries), `col_idx` (sorted within each row), and the extra PETSc
    /// `options` (name with its leading `-`, value or `None` for a flag) under its own prefix.
    pub fn new(row_ptr: &[usize], col_idx: &[usize], options: &[(String, Option<String>)]) -> Result<Self, Error> {
        initialize()?;
        let n = row_ptr.len().saturating_sub(1);
        let ia = petsc_indices(row_ptr, "the nonzeros")?;
        let ja = petsc_indices(col_idx, "the equations")?;
        let mut solver = Self::unset(n, 0..n, col_idx.len(), Layout::Sequential);
        // SAFETY (every call of this block): PETSc is initialised; the matrix handle is
        // written by MatCreate before use and owned by `solver` (destroyed by its Drop, also
        // on an early return); the CSR arrays outlive the preallocation call, which copies
        // them (values null: zeros); the type name outlives its call.
        unsafe {
            let _guard = lock();
            check("MatCreate", sys::MatCreate(sys::PETSC_COMM_WORLD, &mut solver.mat))?;
            let size = n as sys::PetscInt;
            check("MatSetSizes", sys::MatSetSizes(solver.mat, size, size, size, size))?;
            let seqaij = c_string("seqaij");
            check("MatSetType", sys::MatSetType(solver.mat, seqaij.as_ptr()))?;
            check(
                "MatSeqAIJSetPreallocationCSR",
                sys::MatSeqAIJSetPreallocationCSR(solver.mat, ia.as_ptr(), ja.as_ptr(), ptr::null()),
            )?;
        }
        solver.finish_creation(options)?;
        Ok(solver)
    }

    /// A solver distributed over the ranks of `PETSC_COMM_WORLD` (collective: every rank
    /// calls it, with its own arguments) for `n × n` matrices: this rank owns the equations
    /// `owned` (contiguous, in rank order, together `0..n`), whose rows have the pattern
    /// `owned_pattern` (its `rows` are `owned`: PETSc's exact preallocation), and contributes
    /// the entries of `contribution` (rows of any rank) to every matrix
    /// ([`KrylovSolver::set_values`]); `options` as for [`KrylovSolver::new`].
    pub fn distributed(
        n: usize,
        owned: Range<usize>,
        owned_pattern: RowPattern<'_>,
        contribution: RowPattern<'_>,
        options: &[(String, Option<String>)],
    ) -> Result<Self, Error> {
        initialize()?;
        assert!(owned.end <= n && owned_pattern.rows.len() == owned.len(), "owned rows within the equations");
        let first = owned_pattern.row_ptr.first().copied().unwrap_or(0);
        let ia: Vec<sys::PetscInt> = petsc_indices(owned_pattern.row_ptr, "the nonzeros")?
            .into_iter()
            .map(|k| k - first as sys::PetscInt)
            .collect();
        let ja = petsc_indices(
            &owned_pattern.cols[first..*owned_pattern.row_ptr.last().unwrap_or(&first)],
            "the equations",
        )?;
        let layout = Layout::Distributed {
            rows: petsc_indices(contribution.rows, "the equations")?,
            row_ptr: contribution.row_ptr.to_vec(),
            cols: petsc_indices(contribution.cols, "the equations")?,
            values: vec![0.0; contribution.cols.len()],
            gather: ptr::null_mut(),
            x_all: ptr::null_mut(),
        };
        let mut solver = Self::unset(n, owned.clone(), contribution.cols.len(), layout);
        petsc_indices(&[n], "the equations")?;
        // SAFETY (every call of this block): PETSc is initialised; the matrix handle is
        // written by MatCreate before use and owned by `solver` (destroyed by its Drop);
        // the local CSR arrays (local row pointers from 0, global sorted columns) outlive
        // the preallocation call, which copies them (values null: zeros) and assembles;
        // the type name outlives its call.
        unsafe {
            let _guard = lock();
            check("MatCreate", sys::MatCreate(sys::PETSC_COMM_WORLD, &mut solver.mat))?;
            let (local, global) = (owned.len() as sys::PetscInt, n as sys::PetscInt);
            check("MatSetSizes", sys::MatSetSizes(solver.mat, local, local, global, global))?;
            let mpiaij = c_string("mpiaij");
            check("MatSetType", sys::MatSetType(solver.mat, mpiaij.as_ptr()))?;
            check(
                "MatMPIAIJSetPreallocationCSR",
                sys::MatMPIAIJSetPreallocationCSR(solver.mat, ia.as_ptr(), ja.as_ptr(), ptr::null()),
            )?;
        }
        solver.finish_creation(options)?;
        let _guard = lock();
        if let Layout::Distributed { gather, x_all, .. } = &mut solver.layout {
            // SAFETY: `solver.x` is the live parallel vector of the matrix's layout; the
            // scatter and the sequential vector it creates are owned by the layout and
            // destroyed by Drop.
            check("VecScatterCreateToAll", unsafe { sys::VecScatterCreateToAll(solver.x, gather, x_all) })?;
        }
        Ok(solver)
    }

    /// A solver without PETSc objects yet (every handle null: Drop accepts that).
    fn unset(n: usize, owned: Range<usize>, nnz: usize, layout: Layout) -> Self {
        let prefix = format!("loam{}_", PREFIXES.fetch_add(1, Ordering::Relaxed));
        Self {
            mat: ptr::null_mut(),
            x: ptr::null_mut(),
            b: ptr::null_mut(),
            ksp: ptr::null_mut(),
            n,
            owned,
            nnz,
            layout,
            prefix,
            options: Vec::new(),
        }
    }

    /// After the matrix is created and preallocated: its fixed pattern, its vectors, the KSP
    /// with this solver's prefix and `options` in PETSc's database under it.
    fn finish_creation(&mut self, options: &[(String, Option<String>)]) -> Result<(), Error> {
        let _guard = lock();
        // SAFETY (every call of this block): the matrix is live and preallocated; the vector
        // and KSP handles are written by their Create calls and owned by self; the strings
        // outlive their calls (PETSc copies them).
        unsafe {
            // the pattern is fixed: a value outside it is an error, not a reallocation
            check(
                "MatSetOption",
                sys::MatSetOption(self.mat, sys::MatOption::MAT_NEW_NONZERO_LOCATION_ERR, sys::PetscBool::PETSC_TRUE),
            )?;
            check("MatCreateVecs", sys::MatCreateVecs(self.mat, &mut self.x, &mut self.b))?;
            check("KSPCreate", sys::KSPCreate(sys::PETSC_COMM_WORLD, &mut self.ksp))?;
            let prefix = c_string(&self.prefix);
            check("KSPSetOptionsPrefix", sys::KSPSetOptionsPrefix(self.ksp, prefix.as_ptr()))?;
            for (name, value) in options {
                let name = name.trim_start_matches('-');
                let full = c_string(&format!("-{}{name}", self.prefix));
                let value = value.as_deref().map(c_string);
                check(
                    "PetscOptionsSetValue",
                    sys::PetscOptionsSetValue(
                        ptr::null_mut(),
                        full.as_ptr(),
                        value.as_ref().map_or(ptr::null(), |v| v.as_ptr()),
                    ),
                )?;
                self.options.push(full);
            }
        }
        Ok(())
    }

    /// Number of equations.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the system has no equation.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Gives the matrix a near null space (for PCGAMG: the rigid-body modes of elasticity),
    /// `vectors` of the solver's (global) size, the same on every rank; they are
    /// orthonormalised here (modified Gram–Schmidt), and a vector that depends on the others
    /// is dropped.
    pub fn set_near_null_space(&mut self, vectors: &[Vec<f64>]) -> Result<(), Error> {
        let mut basis: Vec<Vec<f64>> = Vec::with_capacity(vectors.len());
        for v in vectors {
            assert_eq!(v.len(), self.n, "near-null-space vector of the solver's size");
            let mut w = v.clone();
            for _ in 0..2 {
                for b in &basis {
                    let d: f64 = w.iter().zip(b).map(|(x, y)| x * y).sum();
                    w.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
                }
            }
            let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
            let scale = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm > 1e-8 * scale && norm > 0.0 {
                w.iter_mut().for_each(|x| *x /= norm);
                basis.push(w);
            }
        }
        if basis.is_empty() {
            return Ok(());
        }
        let _guard = lock();
        let mut vecs: Vec<sys::Vec> = Vec::with_capacity(basis.len());
        let owned = self.owned.clone();
        // SAFETY: the matrix and `self.x` are live; each duplicate is written through the
        // array PETSc lends (the owned entries, valid until the restore); MatNullSpaceCreate takes its
        // own references to the vectors and MatSetNearNullSpace its own to the null space, so
        // ours are destroyed here (also on an error, by the closure's caller below).
        let result = (|| unsafe {
            for b in &basis {
                let mut v: sys::Vec = ptr::null_mut();
                check("VecDuplicate", sys::VecDuplicate(self.x, &mut v))?;
                vecs.push(v);
                let mut a: *mut f64 = ptr::null_mut();
                check("VecGetArray", sys::VecGetArray(v, &mut a))?;
                if !owned.is_empty() {
                    std::slice::from_raw_parts_mut(a, owned.len()).copy_from_slice(&b[owned.clone()]);
                }
                check("VecRestoreArray", sys::VecRestoreArray(v, &mut a))?;
            }
            let mut space: sys::MatNullSpace = ptr::null_mut();
            check(
                "MatNullSpaceCreate",
                sys::MatNullSpaceCreate(
                    sys::PETSC_COMM_WORLD,
                    sys::PetscBool::PETSC_FALSE,
                    vecs.len() as sys::PetscInt,
                    vecs.as_ptr(),
                    &mut space,
                ),
            )?;
            let set = check("MatSetNearNullSpace", sys::MatSetNearNullSpace(self.mat, space));
            sys::MatNullSpaceDestroy(&mut space);
            set
        })();
        for v in &mut vecs {
            // SAFETY: each is a live vector created above, destroyed once.
            unsafe { sys::VecDestroy(v) };
        }
        result
    }

    /// Sets the KSP and PC from `settings`, then applies this solver's options (which
    /// override them).
    pub fn configure(&mut self, settings: &KrylovSettings) -> Result<(), Error> {
        let _guard = lock();
        let ksp_type = c_string(&settings.ksp_type);
        let pc_type = c_string(&settings.pc_type);
        let package = settings.factor_package.as_deref().map(c_string);
        let max_iterations = settings.max_iterations.min(i32::MAX as usize) as sys::PetscInt;
        // SAFETY: the KSP is live (owned by self); the strings outlive the calls (PETSc
        // copies type names); -2 is PETSC_DEFAULT (keep the absolute and divergence
        // tolerances).
        unsafe {
            check("KSPSetType", sys::KSPSetType(self.ksp, ksp_type.as_ptr()))?;
            let mut pc: sys::PC = ptr::null_mut();
            check("KSPGetPC", sys::KSPGetPC(self.ksp, &mut pc))?;
            check("PCSetType", sys::PCSetType(pc, pc_type.as_ptr()))?;
            if let Some(package) = &package {
                check("PCFactorSetMatSolverType", sys::PCFactorSetMatSolverType(pc, package.as_ptr()))?;
            }
            check(
                "KSPSetTolerances",
                sys::KSPSetTolerances(self.ksp, settings.relative_tolerance, -2.0, -2.0, max_iterations),
            )?;
            if settings.ksp_type == "gmres" {
                check(
                    "KSPGMRESSetRestart",
                    sys::KSPGMRESSetRestart(self.ksp, settings.gmres_restart.min(i32::MAX as usize) as sys::PetscInt),
                )?;
            }
            let side = if settings.right_preconditioning { sys::PCSide::PC_RIGHT } else { sys::PCSide::PC_LEFT };
            check("KSPSetPCSide", sys::KSPSetPCSide(self.ksp, side))?;
            check("KSPSetNormType", sys::KSPSetNormType(self.ksp, sys::KSPNormType::KSP_NORM_UNPRECONDITIONED))?;
            check("KSPSetFromOptions", sys::KSPSetFromOptions(self.ksp))?;
        }
        Ok(())
    }

    /// Writes the matrix values: `value(k)` for entry `k` of the compressed-row pattern given
    /// at creation (on one process: the matrix's; distributed: this rank's contribution, added
    /// to the other ranks' with `ADD_VALUES` through PETSc's stash, collective). The pattern
    /// (and PETSc's preallocation) stays; the preconditioner is rebuilt at the next solve.
    pub fn set_values(&mut self, value: impl Fn(usize) -> f64) -> Result<(), Error> {
        let _guard = lock();
        let nnz = self.nnz;
        match &mut self.layout {
            Layout::Sequential => {
                let mut array: *mut f64 = ptr::null_mut();
                // SAFETY: the matrix is a live SeqAIJ of `nnz` stored entries in the order of
                // the CSR pattern it was preallocated with (sorted columns per row, as given);
                // the array PETSc lends is valid until MatSeqAIJRestoreArray, which also marks
                // the values as changed (the PC's next set-up sees a new matrix state).
                unsafe {
                    check("MatSeqAIJGetArray", sys::MatSeqAIJGetArray(self.mat, &mut array))?;
                    if nnz > 0 {
                        let values = std::slice::from_raw_parts_mut(array, nnz);
                        for (k, v) in values.iter_mut().enumerate() {
                            *v = value(k);
                        }
                    }
                    check("MatSeqAIJRestoreArray", sys::MatSeqAIJRestoreArray(self.mat, &mut array))?;
                }
            }
            Layout::Distributed { rows, row_ptr, cols, values, .. } => {
                for (k, v) in values.iter_mut().enumerate() {
                    *v = value(k);
                }
                // SAFETY: the matrix is a live MPIAIJ preallocated with the union of every
                // rank's contribution pattern (so no new nonzero is created); row `i`'s
                // columns and values are the slices `row_ptr[i]..row_ptr[i + 1]` of `cols`
                // and `values`, alive during the call, which copies them (or stashes them
                // for their owner).
                unsafe {
                    check("MatZeroEntries", sys::MatZeroEntries(self.mat))?;
                    for (i, row) in rows.iter().enumerate() {
                        let (a, b) = (row_ptr[i], row_ptr[i + 1]);
                        check(
                            "MatSetValues",
                            sys::MatSetValues(
                                self.mat,
                                1,
                                row,
                                (b - a) as sys::PetscInt,
                                cols[a..b].as_ptr(),
                                values[a..b].as_ptr(),
                                sys::InsertMode::ADD_VALUES,
                            ),
                        )?;
                    }
                }
            }
        }
        // SAFETY: the matrix is live; assembly is collective (every rank calls set_values).
        unsafe {
            check("MatAssemblyBegin", sys::MatAssemblyBegin(self.mat, sys::MatAssemblyType::MAT_FINAL_ASSEMBLY))?;
            check("MatAssemblyEnd", sys::MatAssemblyEnd(self.mat, sys::MatAssemblyType::MAT_FINAL_ASSEMBLY))?;
        }
        Ok(())
    }

    /// Solves `A x = b` for the current values (`rhs` holds `b` on entry and `x` on exit,
    /// from a zero initial guess; distributed: the whole `b` on every rank, of which each
    /// gives PETSc its owned entries, and the whole `x` gathered back to every rank, so that
    /// every rank holds the same solution). A solve that PETSc reports as diverged returns
    /// `Ok` with `converged == false` and `rhs` unchanged; the caller decides.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<SolveReport, Error> {
        assert_eq!(rhs.len(), self.n, "right-hand side of the solver's size");
        let _guard = lock();
        let mut report = SolveReport {
            iterations: 0,
            converged: false,
            reason: 0,
            residual_norm: f64::NAN,
            setup_seconds: 0.0,
            solve_seconds: 0.0,
        };
        let owned = self.owned.clone();
        // SAFETY: KSP, matrix and vectors are live, of global size n (checked above for rhs)
        // with the owned entries on this rank; the arrays PETSc lends are valid between Get
        // and Restore and hold the owned entries (the gathered vector: all n).
        unsafe {
            let mut b: *mut f64 = ptr::null_mut();
            check("VecGetArray", sys::VecGetArray(self.b, &mut b))?;
            if !owned.is_empty() {
                std::slice::from_raw_parts_mut(b, owned.len()).copy_from_slice(&rhs[owned.clone()]);
            }
            check("VecRestoreArray", sys::VecRestoreArray(self.b, &mut b))?;
            check("KSPSetOperators", sys::KSPSetOperators(self.ksp, self.mat, self.mat))?;
            let t = std::time::Instant::now();
            check("KSPSetUp", sys::KSPSetUp(self.ksp))?;
            report.setup_seconds = t.elapsed().as_secs_f64();
            let t = std::time::Instant::now();
            check("KSPSolve", sys::KSPSolve(self.ksp, self.b, self.x))?;
            report.solve_seconds = t.elapsed().as_secs_f64();
            let mut its: sys::PetscInt = 0;
            check("KSPGetIterationNumber", sys::KSPGetIterationNumber(self.ksp, &mut its))?;
            let mut reason: sys::KSPConvergedReason = 0;
            check("KSPGetConvergedReason", sys::KSPGetConvergedReason(self.ksp, &mut reason))?;
            let mut norm = 0.0;
            check("KSPGetResidualNorm", sys::KSPGetResidualNorm(self.ksp, &mut norm))?;
            report.iterations = its.max(0) as usize;
            report.reason = reason;
            report.converged = reason > 0;
            report.residual_norm = norm;
            if report.converged {
                let whole = match &self.layout {
                    Layout::Sequential => self.x,
                    Layout::Distributed { gather, x_all, .. } => {
                        let (forward, insert) = (sys::ScatterMode::SCATTER_FORWARD, sys::InsertMode::INSERT_VALUES);
                        check("VecScatterBegin", sys::VecScatterBegin(*gather, self.x, *x_all, insert, forward))?;
                        check("VecScatterEnd", sys::VecScatterEnd(*gather, self.x, *x_all, insert, forward))?;
                        *x_all
                    }
                };
                let mut x: *const f64 = ptr::null();
                check("VecGetArrayRead", sys::VecGetArrayRead(whole, &mut x))?;
                if self.n > 0 {
                    rhs.copy_from_slice(std::slice::from_raw_parts(x, self.n));
                }
                check("VecRestoreArrayRead", sys::VecRestoreArrayRead(whole, &mut x))?;
            }
        }
        Ok(report)
    }
}

impl Drop for KrylovSolver {
    fn drop(&mut self) {
        let _guard = lock();
        // SAFETY: each handle is either null (never created; the Destroy functions accept a
        // pointer to null) or a live object owned by self alone; the option names are
        // NUL-terminated. Errors cannot be reported from Drop and are ignored.
        unsafe {
            sys::KSPDestroy(&mut self.ksp);
            if let Layout::Distributed { gather, x_all, .. } = &mut self.layout {
                sys::VecScatterDestroy(gather);
                sys::VecDestroy(x_all);
            }
            sys::VecDestroy(&mut self.x);
            sys::VecDestroy(&mut self.b);
            sys::MatDestroy(&mut self.mat);
            for name in &self.options {
                sys::PetscOptionsClearValue(ptr::null_mut(), name.as_ptr());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian `tridiag(−1, 2, −1)` in CSR.
    fn laplacian(n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut ptr, mut idx, mut val) = (vec![0], Vec::new(), Vec::new());
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                idx.push(j);
                val.push(if i == j { 2.0 } else { -1.0 });
            }
            ptr.push(idx.len());
        }
        (ptr, idx, val)
    }

    fn settings(ksp: &str, pc: &str, package: Option<&str>) -> KrylovSettings {
        KrylovSettings {
            ksp_type: ksp.into(),
            pc_type: pc.into(),
            factor_package: package.map(Into::into),
            relative_tolerance: 1e-12,
            max_iterations: 1000,
            gmres_restart: 100,
            right_preconditioning: ksp == "gmres",
        }
    }

    /// CG + GAMG, GMRES + BoomerAMG and MUMPS solve the Laplacian to the tolerance; the
    /// solution of `A x = A 1` is 1.
    #[test]
    fn laplacian_solves_with_each_preconditioner() {
        let n = 200;
        let (ptr, idx, val) = laplacian(n);
        for (ksp, pc, package) in [("cg", "gamg", None), ("gmres", "hypre", None), ("gmres", "lu", Some("mumps"))] {
            let mut s = KrylovSolver::new(&ptr, &idx, &[]).expect("solver");
            s.configure(&settings(ksp, pc, package)).expect("configured");
            s.set_values(|k| val[k]).expect("values");
            let mut b: Vec<f64> = (0..n).map(|i| if i == 0 || i == n - 1 { 1.0 } else { 0.0 }).collect();
            let r = s.solve(&mut b).expect("solves");
            assert!(r.converged, "{ksp}+{pc}: {}", reason_name(r.reason));
            let err = b.iter().map(|x| (x - 1.0).abs()).fold(0.0, f64::max);
            assert!(err < 1e-8, "{ksp}+{pc}: error {err}, {} iterations", r.iterations);
        }
    }

    /// An option under the solver's prefix overrides the settings: one Richardson iteration
    /// with Jacobi cannot reach 1e-12, and the report says so.
    #[test]
    fn prefixed_options_override_and_divergence_is_reported() {
        let (ptr, idx, val) = laplacian(50);
        let options =
            [("-ksp_type".to_string(), Some("richardson".to_string())), ("-ksp_max_it".into(), Some("1".into()))];
        let mut s = KrylovSolver::new(&ptr, &idx, &options).expect("solver");
        s.configure(&settings("cg", "jacobi", None)).expect("configured");
        s.set_values(|k| val[k]).expect("values");
        let mut b = vec![1.0; 50];
        let r = s.solve(&mut b).expect("runs");
        assert!(!r.converged);
        assert_eq!(reason_name(r.reason), "DIVERGED_ITS");
        assert_eq!(b, vec![1.0; 50], "rhs unchanged after a failure");
    }

    /// A near null space (the constant, given twice and so once dropped as dependent) is
    /// accepted by GAMG, which then still solves the Laplacian.
    #[test]
    fn near_null_space_is_orthonormalised_and_used() {
        let n = 100;
        let (ptr, idx, val) = laplacian(n);
        let mut s = KrylovSolver::new(&ptr, &idx, &[]).expect("solver");
        s.set_near_null_space(&[vec![1.0; n], vec![2.0; n]]).expect("near null space");
        s.configure(&settings("cg", "gamg", None)).expect("configured");
        s.set_values(|k| val[k]).expect("values");
        let mut b: Vec<f64> = (0..n).map(|i| if i == 0 || i == n - 1 { 1.0 } else { 0.0 }).collect();
        let r = s.solve(&mut b).expect("solves");
        assert!(r.converged, "{}", reason_name(r.reason));
        assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-8));
    }
}
