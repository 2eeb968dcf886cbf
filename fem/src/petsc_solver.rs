//! `linear_solver: "petsc"` (issue 26, `docs/distributed.md`): PETSc's Krylov solvers with
//! algebraic multigrid on one process or distributed over MPI ranks, through the safe layer of `loam-petsc`. Built only with
//! the `petsc` Cargo feature.
//!
//! **Defaults.** CG when the assembled tangent is symmetric (the check `auto` makes, to
//! `1e-10` relative), GMRES (restart 100, right preconditioning) otherwise; the
//! preconditioner is PETSc's smoothed-aggregation AMG `gamg`, with the rigid-body modes of
//! the nodes as its near null space (`Assembler::rigid_body_modes`); the relative tolerance
//! [`PETSC_RELATIVE_TOLERANCE`] on the unpreconditioned residual `‖b − A x‖/‖b‖`, so that
//! Newton takes the direct solver's path; at most [`PETSC_MAX_ITERATIONS`] iterations.
//! A CG solve that fails (GAMG's Chebyshev smoothers can make the preconditioner indefinite:
//! `DIVERGED_INDEFINITE_PC`) is repeated by GMRES, which then serves the rest of the pattern.
//! Where GMRES with GAMG does not converge either and the options name no preconditioner (a
//! penalty wall's 10¹³ N/m³ against the mass matrix of the initial acceleration, a nearly
//! incompressible soil under a contact), the solve is repeated with MUMPS's LU, which then
//! serves the rest of the pattern (`gamg_failures` in `summary.json`); a new pattern tries
//! GAMG again.
//! [`PetscOptions`] (the case file's `solver.petsc_options`) override any of it
//! (`-ksp_type`, `-pc_type`, `-ksp_rtol`, …); `-pc_type hypre` is BoomerAMG and the value
//! `mumps` of `-pc_type` stands for `-pc_type lu -pc_factor_mat_solver_type mumps` (MUMPS's
//! sparse direct LU).
//!
//! **Pattern.** One PETSc `SeqAIJ` matrix per sparsity pattern (the assembler, and so this
//! solver, lives while the pattern holds): the preallocation is the pattern's, each solve
//! only writes the values in place. The assembly pattern is column-compressed and
//! structurally symmetric, so its column pointers and row indices are the row pointers and
//! column indices of the compressed-row matrix, and row `i`'s entry `(i, j)` is the stored
//! entry at the transpose position of `(j, i)`.
//!
//! **Distributed** (a run on several MPI ranks, [`crate::ranks`]): one `MPIAIJ` matrix per
//! pattern, each rank owning a contiguous range of PETSc rows — the equations renumbered so
//! that a rank's rows are those its blocks mostly reach ([`crate::ranks::Ownership`]; the
//! right-hand side, the solution and the near null space are permuted to and from that order
//! here) — preallocated exactly with the owned rows of the whole pattern, which every rank
//! builds from the replicated block layout ([`crate::ranks::OwnedRows::of`]); each rank adds its part
//! (the blocks it evaluates, on the same transposed positions) with `ADD_VALUES`, gives its
//! owned entries of the (replicated) right-hand side and receives the whole solution; CG or GMRES is chosen when every rank's
//! part is symmetric (one `MPI_Allreduce`), so that every rank takes the same path.
//!
//! **Failure.** A Krylov solve that PETSc reports as diverged (iteration limit, breakdown,
//! an indefinite preconditioner) is [`LinearSolverError::NotConverged`] with the iterations
//! and PETSc's reason: the step fails and is retried with a shorter one, as after a failed
//! factorisation.

use std::time::Instant;

use loam_petsc::{reason_name, KrylovSettings, KrylovSolver, RowPattern};

use crate::assembly::AssemblyPattern;
use crate::linear_solver::{LinearSolverError, PetscOptions, SolverTimings};
use crate::ranks::{OwnedRows, Ranks};

/// Default relative tolerance of the Krylov iterations (`-ksp_rtol` overrides it): below
/// the Newton tolerances by orders of magnitude, so Newton's path does not depend on the
/// solver.
pub const PETSC_RELATIVE_TOLERANCE: f64 = 1e-10;
/// Default largest number of Krylov iterations of one solve (`-ksp_max_it`).
pub const PETSC_MAX_ITERATIONS: usize = 1000;
/// GMRES restart length (`-ksp_gmres_restart`).
pub const PETSC_GMRES_RESTART: usize = 100;

/// PETSc's Krylov solver bound to one sparsity pattern.
#[derive(Debug)]
pub(crate) struct PetscSolver {
    krylov: KrylovSolver,
    /// The settings before the options (KSP type from the symmetry unless given).
    settings: KrylovSettings,
    /// Whether the options fix the KSP type (then the symmetry is not checked).
    ksp_given: bool,
    /// Whether the KSP was configured for a symmetric matrix (`None`: not yet configured).
    configured_symmetric: Option<bool>,
    /// Set once CG failed on this pattern (e.g. an indefinite preconditioner): GMRES from
    /// then on, as the direct solver turns to LU after a failed Cholesky.
    cg_failed: bool,
    /// Whether the options fix the preconditioner (then GAMG has no fallback).
    pc_given: bool,
    /// Set once GMRES with GAMG did not converge: MUMPS's LU from then on.
    gamg_failed: bool,
    /// The ranks of a distributed solve (one process: [`Ranks::single`]).
    ranks: Ranks,
    /// Distributed: this rank's matrix entries per assembly, and those in other ranks' rows
    /// (through PETSc's stash), for the run's statistics ([`crate::ranks::DistributedStats`]).
    entries: (u64, u64),
    /// Distributed: the PETSc row of each equation ([`crate::ranks::Ownership`]; empty: the
    /// equation's number).
    row_of: Vec<usize>,
}

/// A vector per equation in PETSc's order of the rows (`row_of` empty: as it is).
fn to_rows(row_of: &[usize], v: &[f64]) -> Vec<f64> {
    if row_of.is_empty() {
        return v.to_vec();
    }
    let mut out = vec![0.0; v.len()];
    for (e, &r) in row_of.iter().enumerate() {
        out[r] = v[e];
    }
    out
}

fn petsc_error(e: loam_petsc::Error) -> LinearSolverError {
    LinearSolverError::Factorisation(e.to_string())
}

impl PetscSolver {
    /// The solver of `pattern` with the case's extra `options` and the near null space of
    /// its matrices (the rigid-body modes per equation, for GAMG; may be empty). Distributed
    /// (`owned_rows` given, collective): `pattern` is this rank's part of the matrix (the
    /// blocks it assembles, global equation numbers), `owned_rows` the rows PETSc keeps here.
    /// With `direct` (GAMG already failed on this pattern: before a rebalance rebuilt the
    /// solver, or in the run a checkpoint resumes, [`crate::linear_solver::SolverMemory`]) and
    /// no preconditioner in the options, it starts with MUMPS's LU.
    pub(crate) fn new(
        pattern: &AssemblyPattern,
        options: &PetscOptions,
        near_null_space: &[Vec<f64>],
        owned_rows: Option<&OwnedRows>,
        direct: bool,
    ) -> Result<Self, LinearSolverError> {
        let mut settings = KrylovSettings {
            ksp_type: "gmres".into(),
            pc_type: "gamg".into(),
            factor_package: None,
            relative_tolerance: PETSC_RELATIVE_TOLERANCE,
            max_iterations: PETSC_MAX_ITERATIONS,
            gmres_restart: PETSC_GMRES_RESTART,
            right_preconditioning: true,
        };
        let mut ksp_given = false;
        let mut pc_given = false;
        let mut passed = Vec::with_capacity(options.options.len());
        for (name, value) in &options.options {
            match (name.as_str(), value.as_deref()) {
                ("-pc_type", Some("mumps")) => {
                    settings.pc_type = "lu".into();
                    settings.factor_package = Some("mumps".into());
                    pc_given = true;
                    continue;
                }
                ("-pc_type", Some(pc)) => {
                    settings.pc_type = pc.to_string();
                    pc_given = true;
                }
                ("-ksp_type", Some(ksp)) => {
                    settings.ksp_type = ksp.to_string();
                    ksp_given = true;
                }
                _ => {}
            }
            passed.push((name.clone(), value.clone()));
        }
        let symbolic = pattern.symbolic();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        let n = pattern.num_equations();
        let mut entries = (0, 0);
        let mut row_of = Vec::new();
        let (krylov, ranks) = match owned_rows {
            None => (KrylovSolver::new(col_ptr, row_idx, &passed), Ranks::single()),
            Some(owned) => {
                // this rank's contribution: the non-empty rows of its part (column c of the
                // structurally symmetric pattern is row c)
                // this rank's contribution: the non-empty rows of its part (column c of the
                // structurally symmetric pattern is row c), in PETSc's numbering of the rows
                let ownership = &owned.ownership;
                let rows: Vec<usize> = (0..n).filter(|&c| col_ptr[c + 1] > col_ptr[c]).collect();
                let first = rows.first().map_or(0, |&c| col_ptr[c]);
                let row_ptr: Vec<usize> = std::iter::once(first).chain(rows.iter().map(|&c| col_ptr[c + 1])).collect();
                let petsc_rows: Vec<usize> = rows.iter().map(|&c| ownership.row(c)).collect();
                let petsc_cols: Vec<usize> = row_idx.iter().map(|&c| ownership.row(c)).collect();
                let owned_list: Vec<usize> = ownership.rows().collect();
                let mine = ownership.rows();
                let count = |c: &usize| (col_ptr[c + 1] - col_ptr[*c]) as u64;
                entries = (
                    rows.iter().map(count).sum(),
                    rows.iter().filter(|&&c| !mine.contains(&ownership.row(c))).map(count).sum(),
                );
                let solver = KrylovSolver::distributed(
                    n,
                    ownership.rows(),
                    RowPattern { rows: &owned_list, row_ptr: &owned.row_ptr, cols: &owned.cols },
                    RowPattern { rows: &petsc_rows, row_ptr: &row_ptr, cols: &petsc_cols },
                    &passed,
                );
                row_of = ownership.rows_of_equations().to_vec();
                (solver, owned.ownership.ranks())
            }
        };
        let mut krylov = krylov.map_err(petsc_error)?;
        if settings.pc_type == "gamg" && near_null_space.iter().all(|v| v.len() == pattern.num_equations()) {
            let modes: Vec<Vec<f64>> = near_null_space.iter().map(|v| to_rows(&row_of, v)).collect();
            krylov.set_near_null_space(&modes).map_err(petsc_error)?;
        }
        let mut solver = Self {
            krylov,
            settings,
            ksp_given,
            configured_symmetric: None,
            cg_failed: false,
            pc_given,
            gamg_failed: false,
            ranks,
            entries,
            row_of,
        };
        if direct && !pc_given {
            solver.use_mumps();
        }
        Ok(solver)
    }

    /// Whether GAMG did not converge on this pattern (MUMPS's LU took over).
    pub(crate) fn gamg_failed(&self) -> bool {
        self.gamg_failed
    }

    /// MUMPS's LU as the preconditioner from now on (CG or GMRES then converges in one
    /// iteration).
    fn use_mumps(&mut self) {
        self.settings.pc_type = "lu".into();
        self.settings.factor_package = Some("mumps".into());
        self.gamg_failed = true;
        self.configured_symmetric = None;
    }

    /// Solves `A x = b` in place (`rhs`: `b` on entry, `x` on exit) for the matrix with the
    /// column-compressed `values` on `pattern`; timings and Krylov iterations go to `timings`.
    pub(crate) fn solve(
        &mut self,
        pattern: &AssemblyPattern,
        values: &[f64],
        rhs: &mut [f64],
        timings: &mut SolverTimings,
    ) -> Result<(), LinearSolverError> {
        let t = Instant::now();
        // distributed: symmetric if every rank's part is (the same decision on every rank)
        let symmetric = !self.ksp_given && !self.cg_failed && self.ranks.all(pattern.is_symmetric(values, 1e-10));
        self.configure(symmetric)?;
        let transpose = pattern.transpose_positions();
        let assembly = Instant::now();
        self.krylov.set_values(|k| values[transpose[k] as usize]).map_err(petsc_error)?;
        if self.ranks.is_distributed() {
            let (all, off) = self.entries;
            crate::ranks::with_stats(|s| {
                s.matrix_assembly_seconds += assembly.elapsed().as_secs_f64();
                s.matrix_entries += all;
                s.off_process_entries += off;
                s.matrix_assemblies += 1;
            });
        }
        // the symmetry check and the copy of the values count with the preconditioner's set-up
        timings.factorisation += t.elapsed().as_secs_f64();
        let mut report = self.run(rhs, timings)?;
        if !report.converged && symmetric {
            // CG failed (an indefinite preconditioner, or the limit): GMRES on the same
            // matrix, and from then on for this pattern (`rhs` is unchanged after a failure)
            self.cg_failed = true;
            self.configure(false)?;
            report = self.run(rhs, timings)?;
        }
        if !report.converged && !self.pc_given && !self.gamg_failed {
            // GAMG failed too (a penalty of 10¹³ N/m³ against the mass matrix, a nearly
            // incompressible soil under a contact): MUMPS's LU from then on for this pattern
            timings.gamg_failures += 1;
            self.use_mumps();
            self.configure(false)?;
            report = self.run(rhs, timings)?;
        }
        if !report.converged {
            return Err(LinearSolverError::NotConverged {
                iterations: report.iterations,
                reason: reason_name(report.reason).to_string(),
            });
        }
        timings.krylov_solves += 1;
        Ok(())
    }

    /// Configures the KSP for a symmetric matrix (CG) or not (GMRES) unless it already is (or
    /// the options fix the type).
    fn configure(&mut self, symmetric: bool) -> Result<(), LinearSolverError> {
        if self.configured_symmetric == Some(symmetric) {
            return Ok(());
        }
        let mut settings = self.settings.clone();
        if !self.ksp_given {
            settings.ksp_type = if symmetric { "cg" } else { "gmres" }.into();
        }
        // right preconditioning (the true residual in the test) where the method has it
        settings.right_preconditioning =
            matches!(settings.ksp_type.as_str(), "gmres" | "fgmres" | "lgmres" | "bcgs" | "dgmres");
        self.krylov.configure(&settings).map_err(petsc_error)?;
        self.configured_symmetric = Some(symmetric);
        Ok(())
    }

    /// One Krylov solve with the current matrix, its timings and iterations counted.
    fn run(
        &mut self,
        rhs: &mut [f64],
        timings: &mut SolverTimings,
    ) -> Result<loam_petsc::SolveReport, LinearSolverError> {
        let report = if self.row_of.is_empty() {
            self.krylov.solve(rhs).map_err(petsc_error)?
        } else {
            let mut x = to_rows(&self.row_of, rhs);
            let report = self.krylov.solve(&mut x).map_err(petsc_error)?;
            for (e, &r) in self.row_of.iter().enumerate() {
                rhs[e] = x[r];
            }
            report
        };
        timings.factorisation += report.setup_seconds;
        timings.solve += report.solve_seconds;
        timings.factorisations += 1;
        timings.krylov_iterations += report.iterations;
        Ok(report)
    }
}
