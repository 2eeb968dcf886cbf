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
//! **Distributed** (more than one MPI rank, [`crate::ranks`]): the model is on every rank, and
//! the blocks are partitioned among the ranks by a recursive coordinate bisection of their
//! centroids weighted by their kernels' cost ([`crate::ranks::rcb`]; recomputed at a new
//! pattern, and by [`Assembler::rebalance`] when the points' moves unbalance it beyond
//! [`REBALANCE_THRESHOLD`]). Step 1 evaluates the kernels of this rank's blocks (the domains
//! are told theirs, [`Domain::own_blocks`]); step 2 gathers them and sums the residual over
//! the ranks (every rank then holds the whole residual), step 3 gathers this rank's blocks of
//! the matrix, which PETSc adds across the ranks before its solve, and the whole correction
//! comes back to every rank. A kernel's failure on one rank fails the assembly on every rank.
//!
//! Residual and correction norms are also reported per block (soil, interface, structure)
//! of the monolithic system, from the node roles of the DOF map.
//!
//! **Pressure equations** (mixed u–p domains) are equilibrated with the displacement ones:
//! with `s = μ/h` per pressure DOF (the material's shear modulus over the cell size, given
//! by the model), the solve works on `D K D x̂ = D (−R)`, `δ = D x̂`, `D = diag(1, …, s, …)`,
//! so that a pressure equation `∫ q (ln J − p/K) dV` (a volume) weighs as a force and a
//! pressure correction (Pa) as a length: the residual and correction norms of the
//! convergence criteria and of the Newton log stay meaningful, and the pivots of the
//! saddle-point matrix are of one magnitude. The element blocks, the residual and the
//! correction keep their physical units.

use crate::assembly::{scale_values, AssemblyPattern, BlockLayout};
use crate::convergence::BlockNorms;
use crate::dofs::{Block, DofMap, DofTie, NodeRole, CONSTRAINED};
use crate::domain::{AssemblyInput, Domain, DomainError};
use crate::friction::NodalFriction;
use crate::linear_solver::{
    CholeskyFactorisation, LinearSolver, LinearSolverError, LinearSolverKind, PetscOptions, SolverTimings,
};
use crate::ranks::{rcb, with_stats, BlockOwners, RankShare, Ranks};
use crate::slip::{axis_slips, Slip, SlipRotations};

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
    /// Node of each pressure DOF (the `k`-th is DOF `roles.len()·dim + k`).
    pub pressure_nodes: &'a [usize],
    /// Equilibration scale `s = μ/h` (Pa/m) of each pressure DOF (see the module doc).
    pub pressure_scales: &'a [f64],
    /// Linear solver.
    pub solver: LinearSolverKind,
    /// How its Cholesky-type factorisations are organised.
    pub cholesky: CholeskyFactorisation,
    /// Extra options of the `petsc` solver.
    pub petsc_options: &'a PetscOptions,
    /// The ranks of a distributed run ([`crate::ranks`]; one process: [`Ranks::single`]).
    pub ranks: Ranks,
    /// Node positions (the centroids of the blocks for the partition of a distributed run).
    pub positions: &'a [[f64; 3]],
}

/// Largest kernel cost of a rank over the mean above which [`Assembler::rebalance`]
/// recomputes the partition (10 %).
pub const REBALANCE_THRESHOLD: f64 = 1.1;

/// Weight of a block beside its kernel cost (in integration points) in the partition: blocks
/// without points (the rings of an MPM pattern, walls, interface blocks) are spread too.
const BLOCK_WEIGHT_FLOOR: f64 = 1e-3;

/// The global system of one sparsity pattern (see the module doc).
pub struct Assembler {
    dofs: DofMap,
    /// The whole matrix's pattern and gathers (one process); in a distributed run empty: a
    /// rank gathers its blocks on its share's pattern, and PETSc preallocates its rows from
    /// the layout ([`OwnedRows::of`](crate::ranks::OwnedRows::of)).
    pattern: AssemblyPattern,
    /// Nonzeros of the whole matrix (in a distributed run summed over the ranks' rows).
    whole_nnz: usize,
    /// The element blocks (the global DOF of every entry of the vector buffer).
    layout: BlockLayout,
    /// Start of each domain's blocks (`len = domains + 1`).
    domain_blocks: Vec<usize>,
    /// Which rank evaluates each block (a distributed run).
    owners: Option<BlockOwners>,
    /// Start of each domain's part of the matrix and vector buffers.
    domain_matrix: Vec<usize>,
    domain_vector: Vec<usize>,
    matrices: Vec<f64>,
    vectors: Vec<f64>,
    values: Vec<f64>,
    /// Scratch of the matrix gather: the values in row order ([`AssemblyPattern::gather_matrix`]).
    values_by_rows: Vec<f64>,
    /// Residual `R = f_int − f_body + M ã − f_ext` per DOF (local frames at slip nodes).
    residual: Vec<f64>,
    /// `−R` per equation before a solve, the correction per equation after it.
    rhs: Vec<f64>,
    /// Correction `δu` per DOF (global frame).
    delta: Vec<f64>,
    /// Equilibration `D` per equation (empty without pressure equations).
    scale: Vec<f64>,
    /// The equilibration's factors `D_ii D_jj` and `1/(D_ii D_jj)` per nonzero of the
    /// solved pattern, made at its first solve ([`AssemblyPattern::symmetric_scale_factors`]).
    entry_scales: (Vec<f64>, Vec<f64>),
    /// `1/s` per pressure DOF (the weights of [`Assembler::dof_norm`]).
    pressure_weights: Vec<f64>,
    /// Whether `rhs` holds the correction of the last solve (else the residual).
    solved: bool,
    rotations: SlipRotations,
    friction: NodalFriction,
    solver: LinearSolver,
    /// The step length Δt of the Newton tangent whose factors the solver keeps (set by
    /// [`Assembler::keep_factors_for`]; `None` after any other solve).
    factors_for: Option<f64>,
    /// This rank's share of a distributed run (`None` on one process): its blocks are
    /// gathered, the residual summed over the ranks, the matrix assembled and solved by PETSc
    /// across them ([`crate::ranks`]).
    share: Option<RankShare>,
    /// Wall-clock seconds each domain's kernels took in [`Assembler::assemble`], summed over
    /// the calls (domain order).
    kernel_seconds: Vec<f64>,
}

impl Assembler {
    /// The system of `domains` under `system`: nodes that no block touches carry no equation.
    pub fn new(system: &SystemLayout<'_>, domains: &[Box<dyn Domain>]) -> Self {
        let dim = system.dim;
        let num_dofs = system.prescribed.len();
        let mut layout = BlockLayout::default();
        let mut domain_matrix = vec![0];
        let mut domain_vector = vec![0];
        let mut domain_blocks = vec![0];
        for d in domains {
            d.blocks(&mut layout);
            domain_matrix.push(layout.matrix_len());
            domain_vector.push(layout.vector_len());
            domain_blocks.push(layout.num_blocks());
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
        // slip nodes with a Dirichlet component: unrotated, the normal's axis held, friction on
        // the free components
        let axis = axis_slips(dim, system.slips, |d| dirichlet[d]);
        let mut frictional = rotations.frictional_nodes();
        for a in &axis {
            constrained[a.dof(dim)] = true;
            if let Some(frame) = a.friction_frame() {
                frictional.retain(|f| f.0 != a.node);
                frictional.push((a.node, a.friction, frame));
            }
        }
        frictional.sort_by_key(|f| f.0);
        let friction = NodalFriction::new(dim, &frictional, &layout);
        let dofs = DofMap::with_roles(dim, &constrained, system.roles, system.pressure_nodes, system.ties);
        let n_eq = dofs.num_equations();
        let mut scale = Vec::new();
        if !system.pressure_nodes.is_empty() {
            scale = vec![1.0; n_eq];
            let first = dofs.displacement_dofs();
            for (k, &s) in system.pressure_scales.iter().enumerate() {
                let e = dofs.equation(first + k);
                if e != CONSTRAINED {
                    scale[e] = s;
                }
            }
        }
        let mut solver = LinearSolver::new(system.solver, system.cholesky);
        if system.solver == LinearSolverKind::Petsc {
            solver.set_petsc_options(system.petsc_options.clone());
        }
        let owners = system.ranks.is_distributed().then(|| {
            partition(system.ranks, &layout, dim, dofs.displacement_dofs(), system.positions, &block_costs(domains))
        });
        let (pattern, share, whole_nnz) = match &owners {
            None => {
                let pattern = AssemblyPattern::new(&dofs, &layout);
                let nnz = pattern.nnz();
                (pattern, None, nnz)
            }
            Some(o) => {
                let (share, rows) = RankShare::new(o, &dofs, &layout);
                let mut nnz = [rows.cols.len() as f64];
                system.ranks.sum_identically(&mut nnz);
                solver.distribute(rows);
                (AssemblyPattern::of_blocks(&dofs, &layout, |_| false), Some(share), nnz[0] as usize)
            }
        };
        if !scale.is_empty() {
            let mut signs = vec![1i8; n_eq];
            for (g, &e) in dofs.equations().iter().enumerate() {
                if e != CONSTRAINED && dofs.is_pressure(g) {
                    signs[e] = -1;
                }
            }
            solver.set_saddle_point(signs);
        }
        Self {
            matrices: vec![0.0; layout.matrix_len()],
            vectors: vec![0.0; layout.vector_len()],
            values: vec![0.0; pattern.nnz()],
            values_by_rows: Vec::new(),
            residual: vec![0.0; num_dofs],
            rhs: vec![0.0; n_eq],
            delta: vec![0.0; num_dofs],
            scale,
            entry_scales: Default::default(),
            pressure_weights: system.pressure_scales.iter().map(|s| 1.0 / s).collect(),
            solved: false,
            layout,
            domain_blocks,
            owners,
            rotations,
            friction,
            solver,
            factors_for: None,
            share,
            kernel_seconds: vec![0.0; domains.len()],
            dofs,
            pattern,
            whole_nnz,
            domain_matrix,
            domain_vector,
        }
    }

    /// The DOF map.
    pub fn dofs(&self) -> &DofMap {
        &self.dofs
    }

    /// Number of stored nonzeros of the matrix (of the whole matrix in a distributed run).
    pub fn nnz(&self) -> usize {
        self.whole_nnz
    }

    /// What the linear solver has learnt about this pattern's matrices.
    pub fn solver_memory(&self) -> crate::linear_solver::SolverMemory {
        self.solver.memory()
    }

    /// Starts the linear solver from what a solver of the same pattern had learnt.
    pub fn remember(&mut self, memory: crate::linear_solver::SolverMemory) {
        self.solver.remember(memory);
    }

    /// Entries of the solver's last Cholesky-type factor ([`LinearSolver::factor_entries`]).
    pub fn factor_entries(&self) -> Option<usize> {
        self.solver.factor_entries()
    }

    /// Accumulated linear-solver timings of this pattern.
    pub fn solver_timings(&self) -> SolverTimings {
        self.solver.timings
    }

    /// Seconds each domain's element kernels have taken in this pattern's assemblies, in
    /// domain order (the kernel part of [`PhaseTimings::assembly`](crate::model::PhaseTimings);
    /// the rest is the gather).
    pub fn kernel_seconds(&self) -> &[f64] {
        &self.kernel_seconds
    }

    /// The rigid-body motions of the nodes at `positions`, written per equation (local frames
    /// at slip nodes, pressure equations 0): the `dim` translations and the rotations (one in
    /// 2D, three in 3D) about the centroid of the nodes that carry an equation, scaled by their
    /// RMS distance from it. The near null space of PETSc's smoothed-aggregation AMG
    /// ([`Assembler::set_near_null_space`]).
    pub fn rigid_body_modes(&self, positions: &[[f64; 3]]) -> Vec<Vec<f64>> {
        let dim = self.dofs.dim();
        let nodes = self.dofs.displacement_dofs() / dim;
        let carries = |k: usize| (0..dim).any(|i| self.dofs.equation(k * dim + i) != CONSTRAINED);
        let free: Vec<usize> = (0..nodes.min(positions.len())).filter(|&k| carries(k)).collect();
        if free.is_empty() {
            return Vec::new();
        }
        let mut c = [0.0; 3];
        for &k in &free {
            for i in 0..dim {
                c[i] += positions[k][i] / free.len() as f64;
            }
        }
        let r2: f64 = free.iter().map(|&k| (0..dim).map(|i| (positions[k][i] - c[i]).powi(2)).sum::<f64>()).sum();
        let r = (r2 / free.len() as f64).sqrt().max(f64::MIN_POSITIVE);
        let planes: &[(usize, usize)] = if dim == 2 { &[(0, 1)] } else { &[(1, 2), (2, 0), (0, 1)] };
        let mut fulls: Vec<Vec<f64>> = Vec::with_capacity(dim + planes.len());
        for t in 0..dim {
            let mut full = vec![0.0; self.residual.len()];
            for &k in &free {
                full[k * dim + t] = 1.0;
            }
            fulls.push(full);
        }
        for &(a, b) in planes {
            let mut full = vec![0.0; self.residual.len()];
            for &k in &free {
                full[k * dim + a] = -(positions[k][b] - c[b]) / r;
                full[k * dim + b] = (positions[k][a] - c[a]) / r;
            }
            fulls.push(full);
        }
        fulls
            .into_iter()
            .map(|mut full| {
                self.rotations.to_local(&mut full);
                let mut v = vec![0.0; self.dofs.num_equations()];
                for (g, &e) in self.dofs.equations().iter().enumerate().take(nodes * dim) {
                    if e != CONSTRAINED {
                        v[e] = full[g];
                    }
                }
                v
            })
            .collect()
    }

    /// Gives the linear solver the near null space of its matrices (PETSc's GAMG; the other
    /// solvers ignore it), e.g. [`Assembler::rigid_body_modes`].
    pub fn set_near_null_space(&mut self, vectors: Vec<Vec<f64>>) {
        self.solver.set_near_null_space(vectors);
    }

    /// Rotates a full DOF vector to the local frames of the slip nodes.
    pub fn to_local(&self, full: &mut [f64]) {
        self.rotations.to_local(full);
    }

    /// Tells every domain which of its blocks this rank evaluates (a distributed run; `None`
    /// on one process): call after building the assembler and after a
    /// [`Assembler::rebalance`].
    pub fn distribute_kernels(&self, domains: &mut [Box<dyn Domain>]) {
        for (k, d) in domains.iter_mut().enumerate() {
            d.own_blocks(self.owners.as_ref().map(|o| o.part(self.domain_blocks[k]..self.domain_blocks[k + 1])));
        }
    }

    /// In a distributed run, recomputes the partition of the blocks if the kernel costs of
    /// the ranks' blocks (the domains' [`Domain::block_costs`], e.g. after material points
    /// moved between cells) differ from their mean by more than [`REBALANCE_THRESHOLD`], and
    /// tells the domains ([`Assembler::distribute_kernels`]); the PETSc matrix keeps its rows,
    /// this rank's contribution to it is set up again. Returns whether it did. Every rank
    /// computes the same partition from the same replicated data (no communication).
    pub fn rebalance(&mut self, domains: &mut [Box<dyn Domain>], positions: &[[f64; 3]]) -> bool {
        let Some(owners) = &self.owners else { return false };
        let costs = block_costs(domains);
        if owners.imbalance(&costs) <= REBALANCE_THRESHOLD {
            return false;
        }
        let dim = self.dofs.dim();
        let owners = partition(owners.ranks(), &self.layout, dim, self.dofs.displacement_dofs(), positions, &costs);
        with_stats(|s| s.rebalances += 1);
        let (share, rows) = RankShare::new(&owners, &self.dofs, &self.layout);
        self.solver.distribute(rows);
        self.share = Some(share);
        self.owners = Some(owners);
        self.factors_for = None;
        self.distribute_kernels(domains);
        true
    }

    /// Step 1: every domain fills its part of the element buffers (in a distributed run, the
    /// kernels of this rank's blocks); blocks are rotated to the local frames of slip nodes;
    /// frictional slip nodes take their slip in the step.
    pub fn assemble(&mut self, domains: &mut [Box<dyn Domain>], input: &AssemblyInput<'_>) -> Result<(), DomainError> {
        let t = std::time::Instant::now();
        let mut mats = self.matrices.as_mut_slice();
        let mut vecs = self.vectors.as_mut_slice();
        let mut result = Ok(());
        for (k, d) in domains.iter_mut().enumerate() {
            let (m, rest_m) = mats.split_at_mut(self.domain_matrix[k + 1] - self.domain_matrix[k]);
            let (v, rest_v) = vecs.split_at_mut(self.domain_vector[k + 1] - self.domain_vector[k]);
            let kernels = std::time::Instant::now();
            result = d.assemble(input, m, v);
            self.kernel_seconds[k] += kernels.elapsed().as_secs_f64();
            if result.is_err() {
                break;
            }
            mats = rest_m;
            vecs = rest_v;
        }
        if let Some(owners) = &self.owners {
            with_stats(|s| s.kernel_seconds += t.elapsed().as_secs_f64());
            // collective: a kernel that failed on one rank fails the assembly on every rank
            if !owners.ranks().all(result.is_ok()) {
                result = result.and(Err(DomainError {
                    domain: "(another rank)".into(),
                    element: 0,
                    message: "an element kernel failed on another MPI rank".into(),
                }));
            }
        }
        result?;
        self.rotations.rotate_blocks(&mut self.matrices, &mut self.vectors);
        if !self.friction.is_empty() {
            let matrices = input.with_tangent.then_some(self.matrices.as_slice());
            self.friction.after_assembly(
                (&input.state.u, &input.committed.u),
                (input.time, input.time_step),
                matrices,
                input.stiffness,
                self.owners.as_ref(),
            );
        }
        Ok(())
    }

    /// Step 2: `R = gather(r_e) − f_ext` per DOF (`f_ext` in local frames), the friction of
    /// frictional slip nodes ([`crate::friction`]) and the right-hand side `−R` per
    /// equation; returns `‖R‖` over the equations (pressure equations equilibrated, see the
    /// module doc).
    pub fn residual(&mut self, f_ext: &[f64]) -> f64 {
        match &mut self.share {
            None => self.pattern.gather_vector(&self.vectors, &mut self.residual),
            Some(share) => {
                share.pattern.gather_vector(&self.vectors, &mut self.residual);
                share.sum_over_ranks(&mut self.residual);
            }
        }
        for (r, f) in self.residual.iter_mut().zip(f_ext) {
            *r -= f;
        }
        self.friction.apply_to_residual(&mut self.residual);
        self.rhs.fill(0.0);
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            if e != CONSTRAINED {
                self.rhs[e] -= self.residual[g];
            }
        }
        self.solved = false;
        self.weighted_norm()
    }

    /// Weight of equation `e` in the norms: `D` on a residual, `D⁻¹` on a correction.
    #[inline]
    fn weight(&self, e: usize) -> f64 {
        match self.scale.get(e) {
            Some(&s) if self.solved => 1.0 / s,
            Some(&s) => s,
            None => 1.0,
        }
    }

    /// `‖W rhs‖` with the weights of [`Assembler::weight`].
    fn weighted_norm(&self) -> f64 {
        if self.scale.is_empty() {
            return norm(&self.rhs);
        }
        self.rhs.iter().enumerate().map(|(e, v)| (v * self.weight(e)).powi(2)).sum::<f64>().sqrt()
    }

    /// Norm of a correction given per DOF (full vector, e.g. the step's increment `Δu`), with
    /// the pressure DOFs weighted as the corrections of [`Assembler::solve`] (`δp/s`).
    pub fn dof_norm(&self, full: &[f64]) -> f64 {
        let first = self.dofs.displacement_dofs();
        let (u, p) = full.split_at(first.min(full.len()));
        let sq: f64 = u.iter().map(|v| v * v).sum::<f64>()
            + p.iter().zip(&self.pressure_weights).map(|(v, w)| (v * w).powi(2)).sum::<f64>();
        sq.sqrt()
    }

    /// Norms of the right-hand side per block (before a solve: the residual; after it: the
    /// correction; pressure equations equilibrated).
    pub fn block_norms(&self) -> BlockNorms {
        let mut sq = [0.0; 3];
        for (e, v) in self.rhs.iter().enumerate() {
            sq[self.dofs.block(e) as usize] += (v * self.weight(e)).powi(2);
        }
        BlockNorms { soil: sq[0].sqrt(), interface: sq[1].sqrt(), structure: sq[2].sqrt() }
    }

    /// Step 3a: gathers the element matrices into the global matrix (with the friction's
    /// tangent, written into the blocks: call once per assembly, after the residual); in a
    /// distributed run this rank's blocks only (PETSc adds the ranks' parts at the solve).
    pub fn tangent(&mut self) {
        self.friction.apply_to_matrices(&mut self.matrices);
        match &mut self.share {
            None => self.pattern.gather_matrix(&self.matrices, &mut self.values, &mut self.values_by_rows),
            Some(share) => share.pattern.gather_matrix(&self.matrices, &mut share.values, &mut self.values_by_rows),
        }
    }

    /// Step 3a with every block: the whole matrix for [`Assembler::tangent_matrix`] and the
    /// diagnosis of a failed step ([`crate::rigid_modes`]); not for a solve. One process only
    /// (a rank holds neither the other ranks' blocks nor the whole pattern).
    pub fn whole_tangent(&mut self) {
        self.friction.apply_to_matrices(&mut self.matrices);
        self.pattern.gather_matrix(&self.matrices, &mut self.values, &mut self.values_by_rows);
    }

    /// Frictional slip nodes that stick and that slide at the last residual.
    pub fn friction_counts(&self) -> (usize, usize) {
        self.friction.counts()
    }

    /// Step 3b: solves `K δu = −R`; the correction per DOF is then [`Assembler::correction`]
    /// and `‖δu‖` over the equations is returned.
    pub fn solve(&mut self) -> Result<f64, LinearSolverError> {
        self.factors_for = None;
        let (pattern, values) = match &mut self.share {
            None => (&self.pattern, &mut self.values),
            Some(share) => (&share.pattern, &mut share.values),
        };
        let solver = &mut self.solver;
        if self.scale.is_empty() {
            solver.solve(pattern, values, &mut self.rhs)?;
        } else {
            // D K D x̂ = D (−R), δ = D x̂ (module doc); the values are restored after
            if self.entry_scales.0.len() != values.len() {
                let inverse: Vec<f64> = self.scale.iter().map(|d| 1.0 / d).collect();
                self.entry_scales =
                    (pattern.symmetric_scale_factors(&self.scale), pattern.symmetric_scale_factors(&inverse));
            }
            scale_values(values, &self.entry_scales.0);
            for (r, d) in self.rhs.iter_mut().zip(&self.scale) {
                *r *= d;
            }
            let solved = solver.solve(pattern, values, &mut self.rhs);
            scale_values(values, &self.entry_scales.1);
            solved?;
            for (r, d) in self.rhs.iter_mut().zip(&self.scale) {
                *r *= d;
            }
        }
        Ok(self.take_correction())
    }

    /// Marks the factors of the last [`solve`](Self::solve) as those of the Newton tangent of
    /// a step of length `dt`, for [`solve_with_kept_factors`](Self::solve_with_kept_factors).
    pub fn keep_factors_for(&mut self, dt: f64) {
        self.factors_for = Some(dt);
    }

    /// Whether the solver keeps the factors of a Newton tangent of a step of length `dt`
    /// on this pattern.
    pub fn has_factors_for(&self, dt: f64) -> bool {
        self.factors_for == Some(dt)
    }

    /// Step 3b of a modified Newton iteration: solves `K_k δu = −R` with the kept factors of
    /// an earlier tangent `K_k` ([`keep_factors_for`](Self::keep_factors_for)); `None` if
    /// there are none, else `‖δu‖` as [`solve`](Self::solve).
    pub fn solve_with_kept_factors(&mut self) -> Result<Option<f64>, LinearSolverError> {
        if self.factors_for.is_none() {
            return Ok(None);
        }
        for (r, d) in self.rhs.iter_mut().zip(&self.scale) {
            *r *= d;
        }
        let solved = self.solver.solve_with_kept_factors(&mut self.rhs);
        if !matches!(solved, Ok(true)) {
            self.factors_for = None;
        }
        if !solved? {
            for (r, d) in self.rhs.iter_mut().zip(&self.scale) {
                *r /= d;
            }
            return Ok(None);
        }
        for (r, d) in self.rhs.iter_mut().zip(&self.scale) {
            *r *= d;
        }
        Ok(Some(self.take_correction()))
    }

    /// After a solve: the correction per DOF (global frame) from the one per equation;
    /// returns `‖δu‖` over the equations.
    fn take_correction(&mut self) -> f64 {
        self.solved = true;
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            self.delta[g] = if e != CONSTRAINED { self.rhs[e] } else { 0.0 };
        }
        self.rotations.to_global(&mut self.delta);
        self.weighted_norm()
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

    /// The node whose free displacement equations carry the largest residual of the last
    /// [`Assembler::residual`]: the Euclidean norm over its equations (N; local frames at
    /// slip nodes; an equation that tied DOFs share counts for each of their nodes), with the
    /// block of its equations. A non-finite norm counts as the largest. `None` after a solve
    /// (the right-hand side then holds the correction) or without free displacement
    /// equations.
    pub fn largest_nodal_residual(&self) -> Option<(usize, f64, Block)> {
        if self.solved {
            return None;
        }
        let dim = self.dofs.dim();
        let mut largest: Option<(usize, f64, Block)> = None;
        for node in 0..self.dofs.displacement_dofs() / dim {
            let mut sq = 0.0;
            let mut block = None;
            for i in 0..dim {
                let e = self.dofs.equation(node * dim + i);
                if e != CONSTRAINED {
                    sq += self.rhs[e] * self.rhs[e];
                    block.get_or_insert(self.dofs.block(e));
                }
            }
            let Some(block) = block else { continue };
            let norm = sq.sqrt();
            let larger = match largest {
                None => true,
                Some((_, l, _)) => l.is_finite() && (!norm.is_finite() || norm > l),
            };
            if larger {
                largest = Some((node, norm, block));
            }
        }
        largest
    }

    /// Indices of the domains whose element blocks touch a DOF for which `touches` holds.
    pub fn domains_touching(&self, touches: impl Fn(usize) -> bool) -> Vec<usize> {
        (0..self.domain_vector.len() - 1)
            .filter(|&k| self.layout.dofs[self.domain_vector[k]..self.domain_vector[k + 1]].iter().any(|&g| touches(g)))
            .collect()
    }

    /// The pattern and the values of the matrix of the last [`Assembler::tangent`] (zeros
    /// before the first).
    pub fn tangent_matrix(&self) -> (&AssemblyPattern, &[f64]) {
        (&self.pattern, &self.values)
    }

    /// A full DOF vector (global frame) as a vector per equation: rotated to the local frames
    /// of slip nodes, each equation taking the value of (one of) its DOFs.
    pub fn to_equations(&self, full: &[f64]) -> Vec<f64> {
        let mut local = full.to_vec();
        self.rotations.to_local(&mut local);
        let mut out = vec![0.0; self.dofs.num_equations()];
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            if e != CONSTRAINED {
                out[e] = local[g];
            }
        }
        out
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

    /// Reactions of the last residual: `R` at the constrained DOFs, the friction forces at
    /// frictional slip nodes, 0 elsewhere (global frame).
    pub fn reactions(&self, out: &mut [f64]) {
        for (g, &e) in self.dofs.equations().iter().enumerate() {
            out[g] = if e == CONSTRAINED { self.residual[g] } else { 0.0 };
        }
        self.friction.write_reactions(out);
        self.rotations.to_global(out);
    }

    /// The force that the soil domains exert on the nodes they share with others, from the
    /// last assembly: `−Σ r_e` of the soil domains' blocks at every DOF of a node whose role is
    /// not [`NodeRole::Grid`], or that is tied to another DOF (global frame; 0 elsewhere).
    pub fn soil_forces(&self, domains: &[Box<dyn Domain>], roles: &[NodeRole], ties: &[DofTie], out: &mut [f64]) {
        out.fill(0.0);
        let dim = self.dofs.dim();
        let mut shared = vec![false; out.len()];
        for (g, s) in shared.iter_mut().enumerate().take(self.dofs.displacement_dofs()) {
            *s = roles[g / dim] != NodeRole::Grid;
        }
        for t in ties {
            shared[t.follower] = true;
        }
        for (k, d) in domains.iter().enumerate() {
            if !d.is_soil() {
                continue;
            }
            for b in self.domain_blocks[k]..self.domain_blocks[k + 1] {
                if self.owners.as_ref().is_some_and(|o| !o.owns(b)) {
                    continue;
                }
                for i in self.layout.dof_ptr[b]..self.layout.dof_ptr[b + 1] {
                    let g = self.layout.dofs[i];
                    if shared[g] {
                        out[g] -= self.vectors[i];
                    }
                }
            }
        }
        if let Some(owners) = &self.owners {
            owners.ranks().sum_identically(out);
        }
        self.rotations.to_global(out);
    }
}

/// The kernel cost of every block of `domains` ([`Domain::block_costs`]).
fn block_costs(domains: &[Box<dyn Domain>]) -> Vec<f64> {
    let mut costs = Vec::new();
    for d in domains {
        d.block_costs(&mut costs);
    }
    costs
}

/// The blocks of `layout` partitioned among `ranks` by a recursive coordinate bisection of
/// their centroids (the mean of their nodes' `positions`) weighted by their kernel `costs`
/// (plus [`BLOCK_WEIGHT_FLOOR`]); the partition's measures go to the run's statistics.
fn partition(
    ranks: Ranks,
    layout: &BlockLayout,
    dim: usize,
    displacement_dofs: usize,
    positions: &[[f64; 3]],
    costs: &[f64],
) -> BlockOwners {
    let centroids: Vec<[f64; 3]> = (0..layout.num_blocks())
        .map(|b| {
            let mut c = [0.0; 3];
            let mut n = 0.0;
            for &g in &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]] {
                if g < displacement_dofs && g % dim == 0 {
                    if let Some(x) = positions.get(g / dim) {
                        for i in 0..3 {
                            c[i] += x[i];
                        }
                        n += 1.0;
                    }
                }
            }
            c.map(|v| if n > 0.0 { v / n } else { 0.0 })
        })
        .collect();
    let weights: Vec<f64> = costs.iter().map(|c| c + BLOCK_WEIGHT_FLOOR).collect();
    let owners = BlockOwners::new(ranks, rcb(&centroids, &weights, ranks.size()));
    let own: f64 = costs.iter().enumerate().filter(|&(b, _)| owners.owns(b)).map(|(_, c)| c).sum();
    let worst = owners.imbalance(costs);
    with_stats(|s| {
        s.own_cost += own;
        s.total_cost += costs.iter().sum::<f64>();
        s.imbalance = worst;
        s.partitions += 1;
    });
    owners
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
