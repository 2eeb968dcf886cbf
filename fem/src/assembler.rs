//! The assembler: from the domains' element blocks to the global system `K δu = −R` and
//! back (Kratos' builder-and-solver).
//!
//! Built once per sparsity pattern (the DOF map with its node roles and ties, the element
//! buffers, the gather lists, the local frames of slip nodes and the linear solver with its
//! symbolic factorisation), it then serves every Newton iteration of the steps that keep the
//! pattern:
//!
//! 1. [`Assembler::assemble`]: every domain fills its slice of the element buffers
//!    (`r_e = f_int − f_body + M ã`, `K_e = K_t + c_M M`), blocks touching slip nodes are
//!    rotated to their local frames;
//! 2. [`Assembler::residual`]: the gather sums them per DOF, subtracts `f_ext` and forms
//!    `rhs_e = −Σ_{g→e} R_g` per equation (tied DOFs add into one equation);
//! 3. [`Assembler::tangent`] and [`Assembler::solve`]: the gather of the matrix and the
//!    sparse direct (or Krylov) solve, whose solution goes back to every DOF of its
//!    equation and to the global frame as the correction `δu`.
//!
//! Residual and correction norms are also reported per block (soil, interface, structure)
//! of the monolithic system, from the node roles of the DOF map.

use crate::assembly::{AssemblyPattern, BlockLayout};
use crate::convergence::BlockNorms;
use crate::dofs::{DofMap, DofTie, NodeRole, CONSTRAINED};
use crate::domain::{AssemblyInput, Domain, DomainError};
use crate::linear_solver::{LinearSolver, LinearSolverError, LinearSolverKind, SolverTimings};
use crate::slip::{Slip, SlipRotations};

/// What decides the equations of a model: nodes, roles, constraints and ties.
pub struct SystemLayout<'a> {
    /// Components per node.
    pub dim: usize,
    /// Role of each node.
    pub roles: &'a [NodeRole],
    /// Whether each DOF is prescribed (Dirichlet).
    pub prescribed: &'a [bool],
    /// Slip boundaries (normal DOF constrained in the local frame).
    pub slips: &'a [Slip],
    /// Local frames without constraint (slip interfaces).
    pub frames: &'a [Slip],
    /// DOFs that share one equation.
    pub ties: &'a [DofTie],
    /// Linear solver.
    pub solver: LinearSolverKind,
}

/// The global system of one sparsity pattern (see the module doc).
pub struct Assembler {
    dofs: DofMap,
    pattern: AssemblyPattern,
    /// Global DOF of every entry of the vector buffer.
    buffer_dofs: Vec<usize>,
    /// Start of each domain's part of the matrix and vector buffers.
    domain_matrix: Vec<usize>,
    domain_vector: Vec<usize>,
    matrices: Vec<f64>,
    vectors: Vec<f64>,
    values: Vec<f64>,
    /// Residual `R = f_int − f_body + M ã − f_ext` per DOF (local frames at slip nodes).
    residual: Vec<f64>,
    /// `−R` per equation before a solve, the correction per equation after it.
    rhs: Vec<f64>,
    /// Correction `δu` per DOF (global frame).
    delta: Vec<f64>,
    rotations: SlipRotations,
    solver: LinearSolver,
}

impl Assembler {
    /// The system of `domains` under `system`: nodes that no block touches carry no equation.
    pub fn new(system: &SystemLayout<'_>, domains: &[Box<dyn Domain>]) -> Self {
        let dim = system.dim;
        let num_dofs = system.prescribed.len();
        let mut layout = BlockLayout::default();
        let mut domain_matrix = vec![0];
        let mut domain_vector = vec![0];
        for d in domains {
            d.blocks(&mut layout);
            domain_matrix.push(layout.matrix_len());
            domain_vector.push(layout.vector_len());
        }
        let mut touched = vec![false; num_dofs];
        for &g in &layout.dofs {
            touched[g] = true;
        }
        let mut constrained: Vec<bool> = system.prescribed.iter().zip(&touched).map(|(&p, &t)| p || !t).collect();
        let dirichlet = constrained.clone();
        let rotations =
            SlipRotations::new(dim, system.slips, system.frames, &layout, |n| (0..dim).any(|i| dirichlet[n * dim + i]));
        for d in rotations.normal_dofs() {
            constrained[d] = true;
        }
        let dofs = DofMap::with_roles(dim, &constrained, system.roles, system.ties);
        let pattern = AssemblyPattern::new(&dofs, &layout);
        let n_eq = dofs.num_equations();
        Self {
            matrices: vec![0.0; layout.matrix_len()],
            vectors: vec![0.0; layout.vector_len()],
            values: vec![0.0; pattern.nnz()],
            residual: vec![0.0; num_dofs],
            rhs: vec![0.0; n_eq],
            delta: vec![0.0; num_dofs],
            buffer_dofs: layout.dofs,
            rotations,
            solver: LinearSolver::new(system.solver),
            dofs,
            pattern,
            domain_matrix,
            domain_vector,
        }
    }

    /// The DOF map.
    pub fn dofs(&self) -> &DofMap {
        &self.dofs
    }

    /// Number of stored nonzeros of the matrix.
    pub fn nnz(&self) -> usize {
        self.pattern.nnz()
    }

    /// What the linear solver has learnt about this pattern's matrices.
    pub fn solver_memory(&self) -> crate::linear_solver::SolverMemory {
        self.solver.memory()
    }

    /// Starts the linear solver from what a solver of the same pattern had learnt.
    pub fn remember(&mut self, memory: crate::linear_solver::SolverMemory) {
        self.solver.remember(memory);
    }

    /// Accumulated linear-solver timings of this pattern.
    pub fn solver_timings(&self) -> SolverTimings {
        self.solver.timings
    }

    /// Rotates a full DOF vector to the local frames of the slip nodes.
    pub fn to_local(&self, full: &mut [f64]) {
        self.rotations.to_local(full);
    }

    /// Step 1: every domain fills its part of the element buffers; blocks are rotated to
    /// the local frames of slip nodes.
    pub fn assemble(&mut self, domains: &mut [Box<dyn Domain>], input: &AssemblyInput<'_>) -> Result<(), DomainError> {
        let mut mats = self.matrices.as_mut_slice();
        let mut vecs = self.vectors.as_mut_slice();
        for (k, d) in domains.iter_mut().enumerate() {
            let (m, rest_m) = mats.split_at_mut(self.domain_matrix[k + 1] - self.domain_matrix[k]);
            let (v, rest_v) = vecs.split_at_mut(self.domain_vector[k + 1] - self.domain_vector[k]);
            d.assemble(input, m, v)?;
            mats = rest_m;
            vecs = rest_v;
        }
        self.rotations.rotate_blocks(&mut self.matrices, &mut self.vectors);
        Ok(())
    }

    /// Step 2: `R = gather(r_e) − f_ext` per DOF (`f_ext` in local frames) and the right-hand
    /// side `−R` per equation; returns `‖R‖` over the equations.
    pub fn residual(&mut self, f_ext: &[f64]) -> f64 {
        self.pattern.gather_vector(&self.vectors, &mut self.residual);
        for (r, f) in self.residual.iter_mut().zip(f_ext) {
            *r -= f;
        }
        self.rhs.fill(0.0);
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            if e != CONSTRAINED {
                self.rhs[e] -= self.residual[g];
            }
        }
        norm(&self.rhs)
    }

    /// Norms of the right-hand side per block (before a solve: the residual; after it: the
    /// correction).
    pub fn block_norms(&self) -> BlockNorms {
        let mut sq = [0.0; 3];
        for (e, v) in self.rhs.iter().enumerate() {
            sq[self.dofs.block(e) as usize] += v * v;
        }
        BlockNorms { soil: sq[0].sqrt(), interface: sq[1].sqrt(), structure: sq[2].sqrt() }
    }

    /// Step 3a: gathers the element matrices into the global matrix.
    pub fn tangent(&mut self) {
        self.pattern.gather_matrix(&self.matrices, &mut self.values);
    }

    /// Step 3b: solves `K δu = −R`; the correction per DOF is then [`Assembler::correction`]
    /// and `‖δu‖` over the equations is returned.
    pub fn solve(&mut self) -> Result<f64, LinearSolverError> {
        self.solver.solve(&self.pattern, &self.values, &mut self.rhs)?;
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            self.delta[g] = if e != CONSTRAINED { self.rhs[e] } else { 0.0 };
        }
        self.rotations.to_global(&mut self.delta);
        Ok(norm(&self.rhs))
    }

    /// The correction `δu` of the last solve (full DOF vector, global frame).
    pub fn correction(&self) -> &[f64] {
        &self.delta
    }

    /// The Newton correction per DOF (global frame) of the correction `delta` per equation.
    pub fn correction_of(&self, delta: &[f64]) -> Vec<f64> {
        let mut full: Vec<f64> =
            self.dofs.equations().iter().map(|&e| if e != CONSTRAINED { delta[e] } else { 0.0 }).collect();
        self.rotations.to_global(&mut full);
        full
    }

    /// The residual `R` per equation of the last [`Assembler::residual`].
    pub fn residual_per_equation(&self) -> Vec<f64> {
        self.rhs.iter().map(|v| -v).collect()
    }

    /// The matrix of the last [`Assembler::tangent`], dense and row-major (small systems:
    /// tests).
    pub fn dense_tangent(&self) -> Vec<f64> {
        let n = self.dofs.num_equations();
        let dense = self.pattern.matrix(&self.values).to_dense();
        (0..n * n).map(|k| dense[(k / n, k % n)]).collect()
    }

    /// Reactions of the last residual: `R` at the constrained DOFs, 0 elsewhere (global frame).
    pub fn reactions(&self, out: &mut [f64]) {
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            out[g] = if e == CONSTRAINED { self.residual[g] } else { 0.0 };
        }
        self.rotations.to_global(out);
    }

    /// The force that the soil domains exert on the nodes they share with others, from the
    /// last assembly: `−Σ r_e` of the soil domains' blocks at every DOF of a node whose role is
    /// not [`NodeRole::Grid`], or that is tied to another DOF (global frame; 0 elsewhere).
    pub fn soil_forces(&self, domains: &[Box<dyn Domain>], roles: &[NodeRole], ties: &[DofTie], out: &mut [f64]) {
        out.fill(0.0);
        let dim = self.dofs.dim();
        let mut shared = vec![false; out.len()];
        for (g, s) in shared.iter_mut().enumerate() {
            *s = roles[g / dim] != NodeRole::Grid;
        }
        for t in ties {
            shared[t.follower] = true;
        }
        for (k, d) in domains.iter().enumerate() {
            if !d.is_soil() {
                continue;
            }
            for i in self.domain_vector[k]..self.domain_vector[k + 1] {
                let g = self.buffer_dofs[i];
                if shared[g] {
                    out[g] -= self.vectors[i];
                }
            }
        }
        self.rotations.to_global(out);
    }
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
