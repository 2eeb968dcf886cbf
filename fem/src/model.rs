//! A model: nodes, domains, constraints and loads on one DOF map, and the implicit step.
//!
//! One step from `t_n` to `t_{n+1} = t_n + Δt` ([`Model::solve_step`]) is the seed's three
//! phases, each in one place:
//!
//! 1. **initialisation** ([`Model::begin_step`]): every domain prepares the step; particle
//!    domains move their grid with any structure attached to it, locate their material
//!    points, project them to the grid and reset its nodes (the node roles of the DOF map
//!    say which nodes are reset); a changed set of element blocks rebuilds the
//!    [`Assembler`];
//! 2. **updated-Lagrangian phase**: the predictor `u = u_n` with prescribed values at
//!    `t_{n+1}` and the time scheme's `v`, `a`; then the [`NewtonStrategy`] iterates with the
//!    assembler and the convergence criteria until `R(u) = 0`;
//! 3. **convective phase** ([`Model::commit_step`]): reactions and the soil's forces on the
//!    structure are recorded and every domain commits its histories (material points move).
//!
//! A failed step leaves the committed state as it was.

use std::time::Instant;

use crate::amplitude::Amplitude;
use crate::assembler::{Assembler, SystemLayout};
use crate::convergence::BlockNorms;
pub use crate::convergence::ConvergenceCriterion;
use crate::dofs::{DofTie, NodeRole};
use crate::domain::{AssemblyInput, Domain, DomainError, NamedOutput, NodalState};
use crate::linear_solver::{LinearSolverError, PetscOptions, SolverMemory, SolverTimings};
pub use crate::newton::NewtonSettings;
use crate::newton::{assembly_input, NewtonStrategy, Predictor, StepProblem};
use crate::rigid_modes::{free_rigid_motion, short, FreeMotion};
use crate::scheme::TimeScheme;
use crate::slip::Slip;

/// Prescribed displacements `u = value · amplitude(t)` on a set of DOFs.
#[derive(Debug, Clone, PartialEq)]
pub struct Constraint {
    /// Global DOF ids.
    pub dofs: Vec<usize>,
    /// Prescribed value per DOF (m).
    pub values: Vec<f64>,
    /// Time function.
    pub amplitude: Amplitude,
}

impl Constraint {
    /// A constraint on no DOF yet, following `amplitude`: the slot of a boundary condition
    /// enforced by other means (a penalty wall, slip nodes), so that every boundary condition
    /// owns an amplitude slot that an input can drive.
    pub fn without_dofs(amplitude: Amplitude) -> Self {
        Constraint { dofs: Vec::new(), values: Vec::new(), amplitude }
    }
}

/// External nodal forces `f = forces · amplitude(t)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    /// (global DOF, force in N) pairs.
    pub forces: Vec<(usize, f64)>,
    /// Time function.
    pub amplitude: Amplitude,
}

impl StepError {
    /// Whether a shorter step may succeed where this one failed.
    pub fn is_retryable(&self) -> bool {
        !matches!(self, StepError::StepStart(_))
    }
}

/// Why a step failed.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum StepError {
    /// Newton did not converge in the allowed iterations.
    #[error("Newton did not converge in {iterations} iterations (residual {residual:.3e}{})", peak_note(.largest))]
    NoConvergence {
        /// Iterations spent.
        iterations: usize,
        /// Last residual norm.
        residual: f64,
        /// Where the last residual is largest (filled in by [`Model::solve_step`]).
        largest: Option<Box<ResidualPeak>>,
    },
    /// A static model with a rigid-body motion that nothing holds: the stiffness matrix is
    /// singular ([`crate::rigid_modes`]).
    #[error(
        "the static model is not supported: the stiffness matrix is singular ({0}); add supports \
         (boundary_conditions that hold it) or make the analysis dynamic"
    )]
    Unsupported(Box<Unsupported>),
    /// An element failed (e.g. inverted).
    #[error(transparent)]
    Domain(#[from] DomainError),
    /// The initialisation phase failed (e.g. the motion of a grid attached to a structure
    /// inverts a cell): a shorter step does not help, the committed state decides it.
    #[error("at the start of the step: {0}")]
    StepStart(DomainError),
    /// The linear solve failed.
    #[error(transparent)]
    LinearSolver(#[from] LinearSolverError),
}

/// Where the residual of a step that did not converge is largest (issue 31): the node, where
/// it is and who owns it.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualPeak {
    /// Global node id.
    pub node: usize,
    /// Its position at the start of the step (m): reference coordinates plus the committed
    /// displacement (for a grid node, where the grid was placed).
    pub position: Vec<f64>,
    /// Norm of the residual over its free components (N).
    pub force: f64,
    /// `the soil block` (coupled models: soil, interface or structure) or `domain 'beam'`.
    pub owner: String,
}

impl std::fmt::Display for ResidualPeak {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at: Vec<String> = self.position.iter().map(|&x| short(x)).collect();
        write!(f, "largest in {}: node {} at ({}), {:.2e} N", self.owner, self.node, at.join(", "), self.force)
    }
}

/// `; <peak>` or nothing.
fn peak_note(peak: &Option<Box<ResidualPeak>>) -> String {
    peak.as_ref().map_or(String::new(), |p| format!("; {p}"))
}

/// The domains of a static model that can move as a rigid body, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Unsupported {
    /// Names of the domains of the free component.
    pub domains: Vec<String>,
    /// The motion ([`crate::rigid_modes::FreeMotion`]).
    pub motion: FreeMotion,
}

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self.domains.iter().map(|d| format!("'{d}'")).collect();
        let who = match names.len() {
            1 => format!("domain {}", names[0]),
            _ => format!("domains {}", names.join(", ")),
        };
        let m = &self.motion;
        if m.free >= m.all {
            write!(f, "{who} is free in every rigid-body motion: nothing holds it")
        } else if m.free > 1 {
            write!(f, "{who} is free in {} rigid-body motions, e.g. {}", m.free, m.motion)
        } else {
            write!(f, "{who} is free to move as a rigid body: {}", m.motion)
        }
    }
}

/// Wall-clock seconds per phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseTimings {
    /// Domains' per-step preparation (initialisation phase of particle domains: point
    /// search, sort, shape functions, projection to the grid, grid reset).
    pub search: f64,
    /// Building sparsity patterns, DOF maps and gather lists (when they changed).
    pub pattern: f64,
    /// Element kernels and gather of matrix and residual.
    pub assembly: f64,
    /// Symbolic and numeric factorisation.
    pub factorisation: f64,
    /// Of `factorisation`: symbolic analyses (when the pattern changed).
    pub symbolic: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Domains' commit of the converged step (convective phase of particle domains).
    pub commit: f64,
    /// Steps in which the sparsity pattern was rebuilt.
    pub pattern_builds: usize,
}

impl std::ops::AddAssign for PhaseTimings {
    fn add_assign(&mut self, o: Self) {
        self.search += o.search;
        self.pattern += o.pattern;
        self.assembly += o.assembly;
        self.factorisation += o.factorisation;
        self.symbolic += o.symbolic;
        self.solve += o.solve;
        self.commit += o.commit;
        self.pattern_builds += o.pattern_builds;
    }
}

impl std::ops::Sub for PhaseTimings {
    type Output = Self;

    /// The timings accumulated between two snapshots (`later − earlier`).
    fn sub(self, o: Self) -> Self {
        Self {
            search: self.search - o.search,
            pattern: self.pattern - o.pattern,
            assembly: self.assembly - o.assembly,
            factorisation: self.factorisation - o.factorisation,
            symbolic: self.symbolic - o.symbolic,
            solve: self.solve - o.solve,
            commit: self.commit - o.commit,
            pattern_builds: self.pattern_builds - o.pattern_builds,
        }
    }
}

/// Most augmented-Lagrangian updates per step ([`Domain::augment`]): Uzawa's iteration
/// contracts the penetration by about `β / (β + k)` per update (`k` the soil's stiffness at
/// the interface), so a penalty of tens of times `k` needs a few.
pub const MAX_AUGMENTATIONS: usize = 20;

/// What one converged step did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations (linear solves).
    pub iterations: usize,
    /// Of `iterations`: those that assembled and factorised a new tangent (all of them
    /// unless `solver.tangent_reuse` is `auto` or `finish`).
    pub tangents: usize,
    /// Free-DOF residual norm at each iteration, the last one converged.
    pub residuals: Vec<f64>,
    /// Residual norms per block (soil, interface, structure) at each iteration.
    pub block_residuals: Vec<BlockNorms>,
    /// Correction norms `‖δu‖` per block at each solve.
    pub block_corrections: Vec<BlockNorms>,
    /// Phase timings of this step.
    pub timings: PhaseTimings,
    /// Augmented-Lagrangian updates (each followed by a further Newton solve of the step).
    pub augmentations: usize,
    /// The converged step's local time-integration error ([`Model::local_time_error`]; zero
    /// for a static scheme).
    pub time_error: TimeError,
}

/// The local error of a Newmark step, estimated as Zienkiewicz & Xie (1991), "A simple error
/// estimator and adaptive time stepping procedure for dynamic analysis", Earthquake Eng.
/// Struct. Dyn. 20:871–887: the step's displacement differs from the exact one of the same
/// start by `e = Δt² (β − 1/6)(a_{n+1} − a_n)` to leading order (the third-order term of
/// Taylor's series that Newmark's update does not reproduce), per displacement DOF (m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TimeError {
    /// The largest `|e|` over the displacement DOFs (constrained ones have `a = 0` and add none).
    pub max: f64,
    /// The root mean square of `e` over the displacement DOFs that carry an acceleration
    /// (`a_n` or `a_{n+1}` non-zero: the grid nodes reached by material points, the
    /// structures' nodes).
    pub rms: f64,
}

/// Seconds of one [`Model::assemble_only`], by half.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AssemblyTimings {
    /// Element kernels writing the element buffers.
    pub kernels: f64,
    /// Gather of the element buffers into the residual and the matrix values.
    pub gather: f64,
}

/// Nodes, domains, constraints, loads and the solution state.
pub struct Model {
    /// Components per node (2 or 3).
    pub dim: usize,
    /// Reference coordinates of the global nodes.
    pub coords: Vec<[f64; 3]>,
    /// Role of every node (grid, structure, interface).
    pub roles: Vec<NodeRole>,
    /// Domains on the shared node set.
    pub domains: Vec<Box<dyn Domain>>,
    /// Prescribed displacements.
    pub constraints: Vec<Constraint>,
    /// External nodal forces.
    pub loads: Vec<Load>,
    /// Frictionless slip conditions (local rotation of the nodal DOFs).
    pub slips: Vec<Slip>,
    /// Local frames without constraint (the nodes of slip interfaces).
    pub frames: Vec<Slip>,
    /// DOFs that share one equation (the normal components of slip-interface pairs).
    pub ties: Vec<DofTie>,
    /// Node of each pressure DOF of the mixed u–p domains: the `k`-th is DOF
    /// `coords.len()·dim + k` ([`crate::dofs`]).
    pub pressure_nodes: Vec<usize>,
    /// Equilibration scale `s = μ/h` (Pa/m) of each pressure DOF ([`crate::assembler`]).
    pub pressure_scales: Vec<f64>,
    /// Gravity (m/s²) and its time function.
    pub gravity: ([f64; 3], Amplitude),
    /// Time scheme.
    pub scheme: TimeScheme,
    /// Newton settings.
    pub settings: NewtonSettings,
    /// Extra PETSc options of `settings.linear_solver == Petsc` (the case's
    /// `solver.petsc_options`; kept apart because [`NewtonSettings`] is `Copy`).
    pub petsc_options: PetscOptions,
    /// Current iterate (equal to `committed` between steps).
    pub state: NodalState,
    /// Last converged state.
    pub committed: NodalState,
    /// Time of the committed state.
    pub time: f64,
    /// Reactions (full DOF vector; nonzero at constrained DOFs) of the committed state.
    pub reactions: Vec<f64>,
    /// Force (N) that the soil domains exert on the nodes they share with a structure, at
    /// the committed state (full DOF vector, global frame; 0 at nodes only the soil has).
    pub soil_forces: Vec<f64>,
    /// Amplitude factor of each constraint at the committed state (0 before the first step).
    applied_factors: Vec<f64>,
    /// What the linear solver of the current pattern had learnt, from a checkpoint, for the
    /// assembler built at the next step if that step keeps the pattern.
    restored_solver_memory: Option<SolverMemory>,
    assembler: Option<Assembler>,
    /// The solver counters of the patterns dropped so far ([`Model::solver_timings`]).
    retired_solver_timings: SolverTimings,
    /// The kernel seconds per domain of the patterns dropped so far
    /// ([`Model::kernel_seconds_by_domain`]).
    retired_kernel_seconds: Vec<f64>,
    /// Phase timings of the failed step attempts not yet taken by
    /// [`Model::take_failed_step_timings`] (a failed attempt returns no [`StepReport`]).
    failed_step_timings: PhaseTimings,
}

impl Model {
    /// A model over `coords` with `dim` DOFs per node, all structure nodes, and no domains yet.
    pub fn new(dim: usize, coords: Vec<[f64; 3]>, scheme: TimeScheme, settings: NewtonSettings) -> Self {
        let n = coords.len() * dim;
        Self {
            dim,
            roles: vec![NodeRole::Structure; coords.len()],
            coords,
            domains: Vec::new(),
            constraints: Vec::new(),
            loads: Vec::new(),
            slips: Vec::new(),
            frames: Vec::new(),
            ties: Vec::new(),
            pressure_nodes: Vec::new(),
            pressure_scales: Vec::new(),
            gravity: ([0.0; 3], Amplitude::default()),
            scheme,
            settings,
            petsc_options: PetscOptions::default(),
            state: NodalState::zeros(n),
            committed: NodalState::zeros(n),
            time: 0.0,
            reactions: vec![0.0; n],
            soil_forces: vec![0.0; n],
            applied_factors: Vec::new(),
            restored_solver_memory: None,
            assembler: None,
            retired_solver_timings: SolverTimings::default(),
            retired_kernel_seconds: Vec::new(),
            failed_step_timings: PhaseTimings::default(),
        }
    }

    /// Number of DOFs (constrained included): the displacements, then the pressures.
    pub fn num_dofs(&self) -> usize {
        self.coords.len() * self.dim + self.pressure_nodes.len()
    }

    /// Number of displacement DOFs, `coords.len() · dim` (pressure DOFs follow).
    pub fn displacement_dofs(&self) -> usize {
        self.coords.len() * self.dim
    }

    /// Gives `nodes` a pressure DOF each (a mixed u–p domain's nodes), reusing the one a node
    /// already has (its scale becomes the larger of the two), and returns their DOF ids.
    /// `scale` is the domain's `μ/h` (Pa/m, see [`crate::assembler`]). Call before the first
    /// step.
    pub fn add_pressure_dofs(&mut self, nodes: &[usize], scale: f64) -> Vec<usize> {
        let first = self.displacement_dofs();
        let mut of_node: std::collections::HashMap<usize, usize> =
            self.pressure_nodes.iter().enumerate().map(|(k, &n)| (n, k)).collect();
        let dofs = nodes
            .iter()
            .map(|&n| {
                let k = *of_node.entry(n).or_insert_with(|| {
                    self.pressure_nodes.push(n);
                    self.pressure_scales.push(0.0);
                    self.pressure_nodes.len() - 1
                });
                self.pressure_scales[k] = self.pressure_scales[k].max(scale);
                first + k
            })
            .collect();
        let n = self.num_dofs();
        for v in [&mut self.state, &mut self.committed] {
            v.u.resize(n, 0.0);
            v.v.resize(n, 0.0);
            v.a.resize(n, 0.0);
        }
        self.reactions.resize(n, 0.0);
        self.soil_forces.resize(n, 0.0);
        self.invalidate_pattern();
        dofs
    }

    /// The node of DOF `dof` (displacement or pressure).
    pub fn node_of_dof(&self, dof: usize) -> usize {
        let first = self.displacement_dofs();
        if dof < first {
            dof / self.dim
        } else {
            self.pressure_nodes[dof - first]
        }
    }

    /// Number of equations (after [`Model::prepare`]).
    pub fn num_equations(&self) -> usize {
        self.assembler.as_ref().map_or(0, |a| a.dofs().num_equations())
    }

    /// Number of nonzeros of the global matrix (after [`Model::prepare`]).
    pub fn nnz(&self) -> usize {
        self.assembler.as_ref().map_or(0, |a| a.nnz())
    }

    /// Frictional slip nodes that stick and that slide at the last residual (0, 0 before
    /// [`Model::prepare`]).
    pub fn friction_counts(&self) -> (usize, usize) {
        self.assembler.as_ref().map_or((0, 0), |a| a.friction_counts())
    }

    /// Forgets the sparsity pattern (after a change of domains or constraints).
    pub fn invalidate_pattern(&mut self) {
        self.retire_assembler();
    }

    /// Drops the assembler of the current pattern, keeping its solver's counters.
    fn retire_assembler(&mut self) {
        if let Some(a) = self.assembler.take() {
            self.retired_solver_timings += a.solver_timings();
            add_elementwise(&mut self.retired_kernel_seconds, a.kernel_seconds());
        }
    }

    /// Builds the assembler (DOF map, element-buffer layout, sparsity pattern), if needed.
    pub fn prepare(&mut self) {
        if self.assembler.is_some() {
            return;
        }
        let mut prescribed = vec![false; self.num_dofs()];
        for c in &self.constraints {
            for &d in &c.dofs {
                prescribed[d] = true;
            }
        }
        let positions = self.positions();
        let system = SystemLayout {
            dim: self.dim,
            roles: &self.roles,
            prescribed: &prescribed,
            slips: &self.slips,
            frames: &self.frames,
            ties: &self.ties,
            pressure_nodes: &self.pressure_nodes,
            pressure_scales: &self.pressure_scales,
            solver: self.settings.linear_solver,
            cholesky: self.settings.cholesky_factorisation,
            petsc_options: &self.petsc_options,
            ranks: self.settings.ranks,
            positions: &positions,
        };
        let mut assembler = Assembler::new(&system, &self.domains);
        assembler.distribute_kernels(&mut self.domains);
        if self.settings.linear_solver == crate::linear_solver::LinearSolverKind::Petsc {
            // the near null space of PETSc's AMG: rigid-body modes at the step's start
            let modes = assembler.rigid_body_modes(&positions);
            assembler.set_near_null_space(modes);
        }
        if let Some(memory) = self.restored_solver_memory.take() {
            assembler.remember(memory);
        }
        self.assembler = Some(assembler);
    }

    /// Entries of the last Cholesky-type factor of the current pattern (None after an LU or
    /// before a factorisation).
    pub fn factor_entries(&self) -> Option<usize> {
        self.assembler.as_ref().and_then(|a| a.factor_entries())
    }

    /// Accumulated times and counters of the linear solver (symbolic analyses, numeric
    /// factorisations, solves) over every pattern of the run.
    pub fn solver_timings(&self) -> SolverTimings {
        let mut t = self.retired_solver_timings;
        if let Some(a) = &self.assembler {
            t += a.solver_timings();
        }
        t
    }

    /// Seconds each domain's element kernels have taken over the run, in domain order (the
    /// kernel part of [`PhaseTimings::assembly`]; the rest is the gather into the system).
    pub fn kernel_seconds_by_domain(&self) -> Vec<f64> {
        let mut seconds = self.retired_kernel_seconds.clone();
        if let Some(a) = &self.assembler {
            add_elementwise(&mut seconds, a.kernel_seconds());
        }
        seconds.resize(self.domains.len(), 0.0);
        seconds
    }

    /// Gravity at time `t`.
    fn gravity_at(&self, t: f64) -> [f64; 3] {
        let f = self.gravity.1.at(t);
        self.gravity.0.map(|g| g * f)
    }

    /// External nodal forces at time `t` (full DOF vector, global frame).
    fn external_forces(&self, t: f64) -> Vec<f64> {
        let mut f_ext = vec![0.0; self.num_dofs()];
        for l in &self.loads {
            let f = l.amplitude.at(t);
            for &(d, v) in &l.forces {
                f_ext[d] += v * f;
            }
        }
        f_ext
    }

    /// Phase 1, initialisation: every domain prepares the step on the committed state
    /// (particle domains: grid motion, location, projection, grid reset); the assembler is
    /// rebuilt if a domain's element blocks changed.
    pub fn begin_step(&mut self) -> Result<(), StepError> {
        let mut changed = false;
        for d in self.domains.iter_mut() {
            changed |= d.begin_step(&mut self.committed).map_err(StepError::StepStart)?;
        }
        if changed {
            self.invalidate_pattern();
            self.restored_solver_memory = None;
        } else if self.settings.ranks.is_distributed() {
            // the points moved: the blocks' kernel costs changed (docs/distributed.md)
            if let Some(mut assembler) = self.assembler.take() {
                let positions = self.positions();
                assembler.rebalance(&mut self.domains, &positions);
                self.assembler = Some(assembler);
            }
        }
        if self.settings.hold_grid_boundaries {
            self.hold_grid_boundaries();
        }
        Ok(())
    }

    /// The boundary conditions on a grid's start-of-step kinematics: a grid node's velocity
    /// and acceleration are projected from the material points each step, and where the
    /// boundary holds the node they are set to rest in the held directions — the fixed
    /// components (prescribed 0) and the normal of slip nodes — as explicit and implicit MPM
    /// codes apply the grid's boundary conditions after the projection (e.g. Sulsky, Zhou &
    /// Schreyer 1995, CPC 87, §3; Guilkey & Weiss 2003, IJNME 57). Otherwise the Newmark
    /// kinematics of a held node carry the projected normal velocity `v_n` of the points
    /// beside it: a spurious inertia `M v_n/(β Δt)` in the node's reaction (the normal force
    /// of a frictional boundary), and a reversed nodal velocity `−v_n` in the points' update.
    fn hold_grid_boundaries(&mut self) {
        let dim = self.dim;
        for c in &self.constraints {
            for (&d, &v) in c.dofs.iter().zip(&c.values) {
                if v == 0.0 && self.roles[d / dim] == NodeRole::Grid {
                    self.committed.v[d] = 0.0;
                    self.committed.a[d] = 0.0;
                }
            }
        }
        for s in &self.slips {
            if self.roles[s.node] != NodeRole::Grid {
                continue;
            }
            let len = s.normal[..dim].iter().map(|x| x * x).sum::<f64>().sqrt();
            let n = s.normal.map(|x| x / len);
            for field in [&mut self.committed.v, &mut self.committed.a] {
                let x = &mut field[s.node * dim..s.node * dim + dim];
                let along: f64 = (0..dim).map(|i| x[i] * n[i]).sum();
                for i in 0..dim {
                    x[i] -= along * n[i];
                }
            }
        }
    }

    /// The committed state of the model and of every domain, for a checkpoint: with the
    /// case, it determines every later step bit for bit.
    pub fn save_state(&self) -> ModelState {
        ModelState {
            time: self.time,
            committed: self.committed.clone(),
            reactions: self.reactions.clone(),
            soil_forces: self.soil_forces.clone(),
            applied_factors: self.applied_factors.clone(),
            solver_memory: self.assembler.as_ref().map(Assembler::solver_memory).or(self.restored_solver_memory),
            domains: self.domains.iter().map(|d| d.save_state()).collect(),
        }
    }

    /// Restores a state of [`Model::save_state`] into a model built from the same case.
    pub fn restore_state(&mut self, state: ModelState) -> Result<(), String> {
        let n = self.num_dofs();
        let c = &state.committed;
        if c.u.len() != n || c.v.len() != n || c.a.len() != n || state.domains.len() != self.domains.len() {
            return Err(format!(
                "the saved model has {} DOFs and {} domains, this case {n} and {}",
                c.u.len(),
                state.domains.len(),
                self.domains.len()
            ));
        }
        for (d, bytes) in self.domains.iter_mut().zip(&state.domains) {
            d.restore_state(bytes)?;
        }
        self.time = state.time;
        self.state.clone_from(&state.committed);
        self.committed = state.committed;
        self.reactions = state.reactions;
        self.soil_forces = state.soil_forces;
        self.applied_factors = state.applied_factors;
        self.restored_solver_memory = state.solver_memory;
        self.retire_assembler();
        Ok(())
    }

    /// The predictor of a step to `t`: `u = u_n` (or, with [`Predictor::ConstantAcceleration`]
    /// in a dynamic step, the last motion continued) with the prescribed values at `t`, and
    /// the time scheme's `v`, `a` for it. A structure node's prescribed displacement is its total
    /// displacement `ū(t)`; a grid node starts every step where the grid was placed, so its
    /// prescribed displacement moves it by the increment `ū(t) − ū(t_n)` from there (a
    /// boundary of the grid follows the prescribed trajectory; `ū(t_n)` is what the committed
    /// state applied, 0 at the start, so a constant value is applied in the first step).
    fn predict(&mut self, t: f64, dt: f64) {
        self.state.clone_from(&self.committed);
        if self.settings.predictor == Predictor::ConstantAcceleration && self.scheme.is_dynamic() {
            self.predict_constant_acceleration(dt);
        }
        self.applied_factors.resize(self.constraints.len(), 0.0);
        for (c, &f_n) in self.constraints.iter().zip(&self.applied_factors) {
            let f = c.amplitude.at(t);
            for (&d, &v) in c.dofs.iter().zip(&c.values) {
                let role = self.roles[self.node_of_dof(d)];
                self.state.u[d] = match role {
                    NodeRole::Grid => self.committed.u[d] + v * (f - f_n),
                    NodeRole::Structure | NodeRole::Interface => v * f,
                };
            }
        }
        let dofs = self.displacement_dofs();
        self.scheme.update_kinematics(dt, &mut self.state, &self.committed, dofs);
    }

    /// [`Predictor::ConstantAcceleration`]: `u = u_n + Δt v_n + ½ Δt² a_n` on the free
    /// displacement DOFs. A slip node's increment loses its normal component (the
    /// constraint `ũ_n = 0` holds corrections only), and the nodes of a tie start at `u_n`
    /// (their shared equation carries one correction for two nodes whose `v_n` differ).
    fn predict_constant_acceleration(&mut self, dt: f64) {
        let dim = self.dim;
        let dofs = self.displacement_dofs();
        let (c, u) = (&self.committed, &mut self.state.u);
        for g in 0..dofs {
            u[g] = c.u[g] + dt * c.v[g] + 0.5 * dt * dt * c.a[g];
        }
        for s in &self.slips {
            let len = s.normal[..dim].iter().map(|x| x * x).sum::<f64>().sqrt();
            let n = s.normal.map(|x| x / len);
            let first = s.node * dim;
            let along: f64 = (0..dim).map(|i| (u[first + i] - c.u[first + i]) * n[i]).sum();
            for i in 0..dim {
                u[first + i] -= along * n[i];
            }
        }
        for tie in &self.ties {
            for d in [tie.leader, tie.follower] {
                let first = d / dim * dim;
                u[first..first + dim].copy_from_slice(&c.u[first..first + dim]);
            }
        }
    }

    /// Consistent initial acceleration for a dynamic analysis: solves
    /// `M a₀ = f_ext(t) + f_body − f_int(u)` at the committed state (prescribed DOFs keep
    /// `a = 0`) and hands `a₀` to the domains. Without it, a load applied suddenly at
    /// `t = 0` loses `Δt/2 · a₀` of velocity in the first step. No-op for static schemes.
    pub fn initialise_acceleration(&mut self) -> Result<(), StepError> {
        if !self.scheme.is_dynamic() {
            return Ok(());
        }
        self.begin_step()?;
        self.prepare();
        self.state.clone_from(&self.committed);
        let mut f_ext = self.external_forces(self.time);
        let mut assembler = self.assembler.take().expect("prepared");
        assembler.to_local(&mut f_ext);
        let input = AssemblyInput {
            state: &self.state,
            committed: &self.committed,
            inertial_acceleration: None,
            mass_coefficient: 1.0,
            gravity: self.gravity_at(self.time),
            time_step: 0.0,
            gamma: 0.5,
            time: self.time,
            with_tangent: true,
            stiffness: false,
        };
        let result = (|| {
            assembler.assemble(&mut self.domains, &input)?;
            assembler.residual(&f_ext);
            assembler.tangent();
            assembler.solve()?;
            Ok::<(), StepError>(())
        })();
        let a0 = assembler.correction();
        self.committed.a.copy_from_slice(a0);
        self.state.a.copy_from_slice(a0);
        for d in self.domains.iter_mut() {
            d.accept_initial_acceleration(a0);
        }
        self.assembler = Some(assembler);
        result
    }

    /// Assembles once at the current iterate, as the first Newton iteration of a static
    /// step of length 0 would (element kernels, then gather of residual and tangent), and
    /// discards the result. For benchmarks and profiling (`benches/fem_newton.rs`); the
    /// committed state and the domains' histories are not changed.
    pub fn assemble_only(&mut self) -> Result<AssemblyTimings, StepError> {
        self.prepare();
        let gravity = self.gravity_at(self.time);
        let f_ext = vec![0.0; self.num_dofs()];
        let assembler = self.assembler.as_mut().expect("prepared");
        let input =
            assembly_input(TimeScheme::Static, &self.state, &self.committed, &[], 0.0, self.time, gravity, true);
        let t = Instant::now();
        assembler.assemble(&mut self.domains, &input)?;
        let kernels = t.elapsed().as_secs_f64();
        let t = Instant::now();
        assembler.residual(&f_ext);
        assembler.tangent();
        Ok(AssemblyTimings { kernels, gather: t.elapsed().as_secs_f64() })
    }

    /// Advances from the committed state by `dt` (see the module doc). On success the new
    /// state is committed and `time` advanced; on failure nothing committed changes but the
    /// reset of grid nodes (call again with a smaller step, unless the error says a shorter
    /// step cannot help: [`StepError::is_retryable`]).
    pub fn solve_step(&mut self, dt: f64) -> Result<StepReport, StepError> {
        let mut report = StepReport::default();
        // phase 1: initialisation
        let t = Instant::now();
        self.begin_step()?;
        report.timings.search += t.elapsed().as_secs_f64();
        let t = Instant::now();
        if self.assembler.is_none() {
            report.timings.pattern_builds += 1;
        }
        self.prepare();
        report.timings.pattern += t.elapsed().as_secs_f64();
        // phase 2: updated-Lagrangian phase
        let t_new = self.time + dt;
        self.predict(t_new, dt);
        let mut f_ext = self.external_forces(t_new);
        let mut assembler = self.assembler.take().expect("prepared");
        assembler.to_local(&mut f_ext);
        let gravity = self.gravity_at(t_new);
        let mut problem = StepProblem {
            domains: &mut self.domains,
            assembler: &mut assembler,
            state: &mut self.state,
            committed: &self.committed,
            scheme: self.scheme,
            dt,
            time: t_new,
            gravity,
            f_ext: &f_ext,
            kinematic_dofs: self.coords.len() * self.dim,
            coords: &self.coords,
        };
        let mut result =
            NewtonStrategy { settings: self.settings, reference_residual: None }.solve(&mut problem, &mut report);
        let first_residual = report.residuals.first().copied();
        // augmented Lagrangian: domains with multipliers update them at the converged iterate
        // and the step is solved again from there, until none asks for it
        for _ in 0..MAX_AUGMENTATIONS {
            if result.is_err() {
                break;
            }
            let input = assembly_input(self.scheme, problem.state, problem.committed, &[], dt, t_new, gravity, false);
            let mut again = false;
            for d in problem.domains.iter_mut() {
                again |= d.augment(&input);
            }
            if !again {
                break;
            }
            report.augmentations += 1;
            result = NewtonStrategy { settings: self.settings, reference_residual: first_residual }
                .solve(&mut problem, &mut report);
        }
        // phase 3: convective phase
        if result.is_ok() {
            report.time_error = self.local_time_error(dt);
            if self.settings.trace && self.scheme.is_dynamic() {
                eprintln!(
                    "step t={t_new:.6e} dt={dt:.3e} iterations={} time error rms={:.3e} max={:.3e} m",
                    report.iterations, report.time_error.rms, report.time_error.max
                );
            }
            let t = Instant::now();
            self.commit_step(&assembler, dt, t_new, gravity);
            report.timings.commit += t.elapsed().as_secs_f64();
        } else {
            self.state.clone_from(&self.committed);
            self.failed_step_timings += report.timings;
        }
        let result = result.map_err(|e| self.explain_failure(e, &mut assembler, dt, t_new, gravity));
        self.assembler = Some(assembler);
        result.map(|()| report)
    }

    /// [`TimeError`] of the converged iterate against the committed state (before the
    /// commit): `Δt² |β − 1/6| |a_{n+1} − a_n|` over the displacement DOFs, `a_n` the start's
    /// accelerations (for material points, projected to the grid in phase 1). Zero for a
    /// static scheme.
    fn local_time_error(&self, dt: f64) -> TimeError {
        let Some((_, beta, _)) = self.scheme.coefficients() else { return TimeError::default() };
        let c = dt * dt * (beta - 1.0 / 6.0).abs();
        let dofs = self.displacement_dofs();
        let (mut max, mut sum, mut count) = (0.0f64, 0.0, 0usize);
        for (&a, &an) in self.state.a[..dofs].iter().zip(&self.committed.a[..dofs]) {
            if a == 0.0 && an == 0.0 {
                continue;
            }
            let e = c * (a - an);
            max = max.max(e.abs());
            sum += e * e;
            count += 1;
        }
        TimeError { max, rms: if count > 0 { (sum / count as f64).sqrt() } else { 0.0 } }
    }

    /// The phase timings of the failed step attempts since the last call (their search,
    /// assembly, factorisations and solves), so that a run's phases account for them.
    pub fn take_failed_step_timings(&mut self) -> PhaseTimings {
        std::mem::take(&mut self.failed_step_timings)
    }

    /// What a user needs to know of a failed step (issue 31): a Newton iteration that did
    /// not converge says where its last residual is largest; a static model whose tangent at
    /// the step's predictor (assembled once more: the last iterate may be far from it, and
    /// stressed) leaves a rigid-body motion free is [`StepError::Unsupported`], whatever the
    /// symptom. The state is left at the committed one.
    fn explain_failure(
        &mut self,
        error: StepError,
        assembler: &mut Assembler,
        dt: f64,
        t: f64,
        gravity: [f64; 3],
    ) -> StepError {
        let error = self.locate_residual(error, assembler);
        // distributed: a rank holds its blocks' matrices only, not the whole tangent
        if self.scheme.is_dynamic() || !error.is_retryable() || self.settings.ranks.is_distributed() {
            return error;
        }
        self.predict(t, dt);
        let input = assembly_input(self.scheme, &self.state, &self.committed, &[], dt, t, gravity, true);
        let assembled = assembler.assemble(&mut self.domains, &input);
        self.state.clone_from(&self.committed);
        if assembled.is_err() {
            return error;
        }
        assembler.whole_tangent();
        match free_rigid_motion(assembler, &self.positions(), self.dim) {
            Some(motion) => {
                let mut of_component = vec![false; self.num_dofs()];
                for &g in &motion.dofs {
                    of_component[g] = true;
                }
                let domains = assembler
                    .domains_touching(|g| of_component[g])
                    .into_iter()
                    .map(|k| self.domains[k].name().to_string())
                    .collect();
                StepError::Unsupported(Box::new(Unsupported { domains, motion }))
            }
            None => error,
        }
    }

    /// Node positions of the committed state: reference coordinates plus the committed
    /// displacements (a grid node: where the grid was placed).
    fn positions(&self) -> Vec<[f64; 3]> {
        let dim = self.dim;
        self.coords
            .iter()
            .enumerate()
            .map(|(n, x)| {
                let mut p = *x;
                for i in 0..dim {
                    p[i] += self.committed.u[n * dim + i];
                }
                p
            })
            .collect()
    }

    /// A [`StepError::NoConvergence`] with where the last residual of `assembler` is largest.
    fn locate_residual(&self, error: StepError, assembler: &Assembler) -> StepError {
        let names = |domains: Vec<usize>| -> Vec<String> {
            domains.into_iter().map(|k| self.domains[k].name().to_string()).collect()
        };
        match error {
            StepError::NoConvergence { iterations, residual, largest: None } => {
                let largest = assembler.largest_nodal_residual().map(|(node, force, block)| {
                    let coupled = self.roles.contains(&NodeRole::Interface) || !self.ties.is_empty();
                    let owner = if coupled {
                        format!("the {} block", block.name())
                    } else {
                        let dim = self.dim;
                        let names: Vec<String> =
                            names(assembler.domains_touching(|g| g < self.displacement_dofs() && g / dim == node))
                                .into_iter()
                                .map(|n| format!("'{n}'"))
                                .collect();
                        match names.len() {
                            1 => format!("domain {}", names[0]),
                            _ => format!("domains {}", names.join(", ")),
                        }
                    };
                    let position = self.positions()[node][..self.dim].to_vec();
                    Box::new(ResidualPeak { node, position, force, owner })
                });
                StepError::NoConvergence { iterations, residual, largest }
            }
            e => e,
        }
    }

    /// Phase 3: records the reactions and the soil's forces on shared nodes from the last
    /// assembly (at the converged state), lets every domain commit (material points convect)
    /// and makes the converged state the committed one at `t`.
    fn commit_step(&mut self, assembler: &Assembler, dt: f64, t: f64, gravity: [f64; 3]) {
        assembler.reactions(&mut self.reactions);
        // shared nodes, slip pairs, or soil terms on structure nodes (a non-conforming tie)
        let soil_on_structure = self.roles.contains(&NodeRole::Structure)
            && self.roles.contains(&NodeRole::Grid)
            && self.domains.iter().any(|d| d.is_soil());
        if self.roles.contains(&NodeRole::Interface) || !self.ties.is_empty() || soil_on_structure {
            assembler.soil_forces(&self.domains, &self.roles, &self.ties, &mut self.soil_forces);
        }
        let mut inertial = vec![0.0; self.num_dofs()];
        if self.scheme.is_dynamic() {
            self.scheme.inertial_accelerations(&self.state, &self.committed, &mut inertial);
        }
        let input = assembly_input(self.scheme, &self.state, &self.committed, &inertial, dt, t, gravity, true);
        for d in self.domains.iter_mut() {
            d.commit(&input);
        }
        self.applied_factors = self.constraints.iter().map(|c| c.amplitude.at(t)).collect();
        self.committed.clone_from(&self.state);
        self.time = t;
    }

    /// Total kinetic energy of the committed state (collective where a domain's points are
    /// distributed: [`Model::sum_over_domains`]).
    pub fn kinetic_energy(&self) -> f64 {
        self.sum_over_domains(|d| d.kinetic_energy(&self.committed.v))
    }

    /// Total stored work of internal forces of the committed state (collective as
    /// [`Model::kinetic_energy`]).
    pub fn strain_energy(&self) -> f64 {
        self.sum_over_domains(|d| d.strain_energy())
    }

    /// Whether a domain's points are distributed over the ranks ([`Domain::points_distributed`]).
    pub fn has_distributed_points(&self) -> bool {
        self.domains.iter().any(|d| d.points_distributed().is_some())
    }

    /// `Σ_d f(d)` over the domains; the parts of domains whose points are distributed
    /// ([`Domain::points_distributed`]) summed over the ranks (collective: every rank must
    /// call it at the same point of the run), the others' taken once.
    pub fn sum_over_domains(&self, f: impl Fn(&dyn Domain) -> f64) -> f64 {
        let Some(ranks) = self.domains.iter().find_map(|d| d.points_distributed()) else {
            return self.domains.iter().map(|d| f(d.as_ref())).sum();
        };
        let mut parts = [0.0, 0.0];
        for d in &self.domains {
            parts[usize::from(d.points_distributed().is_some())] += f(d.as_ref());
        }
        let mut distributed = [parts[1]];
        ranks.sum_identically(&mut distributed);
        parts[0] + distributed[0]
    }

    /// Starts a step of length `dt` as [`Model::solve_step`] does (initialisation phase and
    /// predictor) and returns the step's nonlinear system for evaluation at any correction:
    /// for tests of the consistent tangent against finite differences of the residual. The
    /// committed state is not changed (the domains' trial states are).
    pub fn linearise(&mut self, dt: f64) -> Result<Linearisation<'_>, StepError> {
        self.begin_step()?;
        self.prepare();
        let t = self.time + dt;
        self.predict(t, dt);
        let mut f_ext = self.external_forces(t);
        self.assembler.as_ref().expect("prepared").to_local(&mut f_ext);
        let predictor = self.state.u.clone();
        Ok(Linearisation { gravity: self.gravity_at(t), model: self, dt, time: t, f_ext, predictor })
    }

    /// Every output of every domain at the committed state (see [`Domain::outputs`]).
    pub fn outputs(&self, with_grid: bool) -> Vec<NamedOutput> {
        self.domains.iter().flat_map(|d| d.outputs(&self.committed, with_grid)).collect()
    }

    /// Piece `rank` of `size` of every output ([`Domain::output_pieces`]).
    pub fn output_pieces(&self, with_grid: bool, rank: usize, size: usize) -> Vec<NamedOutput> {
        self.domains.iter().flat_map(|d| d.output_pieces(&self.committed, with_grid, rank, size)).collect()
    }

    /// The output named `name` (a domain, body or wall) at the committed state.
    pub fn output(&self, name: &str) -> Option<crate::domain::DomainOutput> {
        self.outputs(false).into_iter().find(|o| o.name == name).map(|o| o.output)
    }
}

/// The committed state of a [`Model`] ([`Model::save_state`]).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ModelState {
    /// Time of the committed state.
    pub time: f64,
    /// Nodal unknowns.
    pub committed: NodalState,
    /// Reactions.
    pub reactions: Vec<f64>,
    /// Soil forces on shared nodes.
    pub soil_forces: Vec<f64>,
    /// Amplitude factors of the constraints at the committed state.
    pub applied_factors: Vec<f64>,
    /// What the linear solver of the current pattern had learnt.
    pub solver_memory: Option<SolverMemory>,
    /// Each domain's [`Domain::save_state`].
    pub domains: Vec<Vec<u8>>,
}

/// The nonlinear system `R(u) = 0` of one step, evaluated at corrections of the predictor
/// ([`Model::linearise`]): what the Newton strategy sees, exposed for checks of the
/// consistent tangent.
pub struct Linearisation<'a> {
    model: &'a mut Model,
    dt: f64,
    time: f64,
    gravity: [f64; 3],
    f_ext: Vec<f64>,
    predictor: Vec<f64>,
}

impl Linearisation<'_> {
    /// Number of equations.
    pub fn num_equations(&self) -> usize {
        self.model.num_equations()
    }

    /// The block (soil, interface, structure) of equation `e`.
    pub fn block(&self, e: usize) -> crate::dofs::Block {
        self.model.assembler.as_ref().expect("prepared").dofs().block(e)
    }

    /// Whether each equation is a pressure equation (mixed u–p domains).
    pub fn pressure_equations(&self) -> Vec<bool> {
        let dofs = self.model.assembler.as_ref().expect("prepared").dofs();
        let mut out = vec![false; dofs.num_equations()];
        for (g, &e) in dofs.equations().iter().enumerate() {
            if e != crate::dofs::CONSTRAINED && dofs.is_pressure(g) {
                out[e] = true;
            }
        }
        out
    }

    /// The equation of DOF `dof` (in the local frame at slip nodes: component 0 the normal),
    /// `None` if the DOF is constrained.
    pub fn equation(&self, dof: usize) -> Option<usize> {
        let e = self.model.assembler.as_ref().expect("prepared").dofs().equation(dof);
        (e != crate::dofs::CONSTRAINED).then_some(e)
    }

    /// Frictional slip nodes that stick and that slide at the last evaluation.
    pub fn friction_counts(&self) -> (usize, usize) {
        self.model.friction_counts()
    }

    /// Residual per equation and the tangent (dense, row-major) at `u = u_pred + δu`, where
    /// `δu` is the correction `delta` per equation taken to the DOFs as a Newton correction
    /// is (tied DOFs together, slip frames to the global frame).
    pub fn evaluate(&mut self, delta: &[f64]) -> Result<(Vec<f64>, Vec<f64>), StepError> {
        let model = &mut *self.model;
        let mut assembler = model.assembler.take().expect("prepared");
        let full = assembler.correction_of(delta);
        model.state.u.clone_from(&self.predictor);
        for (u, d) in model.state.u.iter_mut().zip(&full) {
            *u += d;
        }
        let dofs = model.displacement_dofs();
        model.scheme.update_kinematics(self.dt, &mut model.state, &model.committed, dofs);
        let mut inertial = vec![0.0; model.num_dofs()];
        model.scheme.inertial_accelerations(&model.state, &model.committed, &mut inertial);
        let input = crate::newton::assembly_input(
            model.scheme,
            &model.state,
            &model.committed,
            &inertial,
            self.dt,
            self.time,
            self.gravity,
            true,
        );
        let result = assembler.assemble(&mut model.domains, &input);
        let out = result.map(|()| {
            assembler.residual(&self.f_ext);
            assembler.tangent();
            (assembler.residual_per_equation(), assembler.dense_tangent())
        });
        model.assembler = Some(assembler);
        Ok(out?)
    }
}

impl Drop for Linearisation<'_> {
    fn drop(&mut self) {
        self.model.state.clone_from(&self.model.committed);
    }
}

/// `sum[k] += add[k]`, `sum` lengthened with zeros where `add` is longer.
fn add_elementwise(sum: &mut Vec<f64>, add: &[f64]) {
    if sum.len() < add.len() {
        sum.resize(add.len(), 0.0);
    }
    for (s, a) in sum.iter_mut().zip(add) {
        *s += a;
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use loam_laws::neo_hookean::NeoHookean;

    use super::{Model, NewtonSettings};
    use crate::element::ElementType;
    use crate::formulation::Formulation;
    use crate::mesh::Mesh;
    use crate::scheme::TimeScheme;
    use crate::solid_domain::FemDomain;

    /// Issue 26: the rigid-body modes per equation that PETSc's GAMG gets as its near null
    /// space ([`crate::assembler::Assembler::rigid_body_modes`]) are in the null space of the
    /// tangent of a free, unstressed block (`‖K r‖ ≤ 1e-9 max|K_ij| ‖r‖`, 3 modes in 2D, 6 in
    /// 3D), and have one entry per equation.
    #[test]
    fn rigid_body_modes_span_the_null_space_of_a_free_block() {
        for (mesh, dim) in [
            (Mesh::rectangle([0.0, 0.0], [4.0, 1.0], [8, 2], ElementType::Quad4), 2),
            (Mesh::cuboid([0.0; 3], [2.0, 1.0, 1.0], [4, 2, 2], ElementType::Hex8), 3),
        ] {
            let n = mesh.coords.len();
            let formulation = if dim == 2 { Formulation::PlaneStrain } else { Formulation::ThreeD };
            let law = Arc::new(NeoHookean::new(1000.0, 9e7, 0.3));
            let domain = FemDomain::new("block", mesh.clone(), (0..n).collect(), formulation, 1.0, law, false).unwrap();
            let mut model = Model::new(dim, mesh.coords.clone(), TimeScheme::Static, NewtonSettings::default());
            model.domains.push(Box::new(domain));
            let mut lin = model.linearise(1.0).expect("linearises");
            let m = lin.num_equations();
            let (_, k) = lin.evaluate(&vec![0.0; m]).expect("assembles");
            let modes = lin.model.assembler.as_ref().expect("prepared").rigid_body_modes(&mesh.coords);
            assert_eq!(modes.len(), if dim == 2 { 3 } else { 6 });
            let kmax = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (j, r) in modes.iter().enumerate() {
                assert_eq!(r.len(), m);
                let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
                let kr = (0..m).map(|i| (0..m).map(|c| k[i * m + c] * r[c]).sum::<f64>().powi(2)).sum::<f64>().sqrt();
                println!("{dim}D mode {j}: ‖K r‖ / (max|K| ‖r‖) = {:.1e}", kr / (kmax * rn));
                assert!(kr <= 1e-9 * kmax * rn, "{dim}D mode {j} is not rigid");
            }
        }
    }
}
