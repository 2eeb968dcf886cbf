//! A model: nodes, domains, constraints and loads on one DOF map, and the implicit step.
//!
//! One step from `t_n` to `t_{n+1} = t_n + Δt` (Newton–Raphson, as in Kratos' residual-based
//! Newton strategy): displacement predictor `u = u_n` with prescribed values at `t_{n+1}`;
//! then repeat — every domain fills its element blocks, the gather forms
//! `R = f_int − f_body + M ã − f_ext` and the tangent `K_t + c_M M`, the sparse system
//! `K δu = −R` is solved, `u ← u + δu` and the scheme updates `v`, `a` — until the
//! convergence criterion holds. Only then do domains commit their histories.

use std::time::Instant;

use serde::Deserialize;

use crate::amplitude::Amplitude;
use crate::assembly::{AssemblyPattern, BlockLayout};
use crate::dofs::{DofMap, CONSTRAINED};
use crate::domain::{AssemblyInput, Domain, DomainError, NodalState, Projection};
use crate::linear_solver::{LinearSolver, LinearSolverError, LinearSolverKind, SolverTimings};
use crate::scheme::TimeScheme;
use crate::slip::{Slip, SlipRotations};

/// Which norms decide convergence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConvergenceCriterion {
    /// Residual only.
    Residual,
    /// Displacement increment only.
    Displacement,
    /// Both (the default).
    #[default]
    And,
    /// Either.
    Or,
}

/// Newton–Raphson settings, as in the case file's `solver` object.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NewtonSettings {
    /// Largest number of iterations per step (default 20).
    pub max_iterations: usize,
    /// `‖R_k‖ / ‖R_0‖` below which the residual has converged (default 1e-6).
    pub residual_relative_tolerance: f64,
    /// `‖R_k‖` (N) below which the residual has converged (default 1e-9).
    pub residual_absolute_tolerance: f64,
    /// `‖δu‖ / ‖Δu‖` (increment of this iteration vs of the step) (default 1e-6).
    pub displacement_relative_tolerance: f64,
    /// `‖δu‖` (m) below which the displacement has converged (default 1e-12).
    pub displacement_absolute_tolerance: f64,
    /// Combination of the two criteria (default `and`).
    pub convergence_criterion: ConvergenceCriterion,
    /// Direct solver (default `auto`: Cholesky if symmetric, else LU).
    pub linear_solver: LinearSolverKind,
    /// Backtracking line search (default off): when an iteration raises the residual norm
    /// above the previous one, the Newton correction is halved, up to
    /// `line_search_max_cuts` times, until the residual falls (Armijo-type backtracking on
    /// `‖R‖`, e.g. Wriggers, *Nonlinear Finite Element Methods*, §5.1.3). Cures the
    /// two-state cycling of non-smooth returns (Mohr–Coulomb edges and apex).
    pub line_search: bool,
    /// Halvings tried per iteration by the line search (default 4).
    pub line_search_max_cuts: u32,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            max_iterations: 20,
            residual_relative_tolerance: 1e-6,
            residual_absolute_tolerance: 1e-9,
            displacement_relative_tolerance: 1e-6,
            displacement_absolute_tolerance: 1e-12,
            convergence_criterion: ConvergenceCriterion::And,
            linear_solver: LinearSolverKind::Auto,
            line_search: false,
            line_search_max_cuts: 4,
        }
    }
}

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

/// Why a step failed.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum StepError {
    /// Newton did not converge in the allowed iterations.
    #[error("Newton did not converge in {iterations} iterations (residual {residual:.3e})")]
    NoConvergence {
        /// Iterations spent.
        iterations: usize,
        /// Last residual norm.
        residual: f64,
    },
    /// An element failed (e.g. inverted).
    #[error(transparent)]
    Domain(#[from] DomainError),
    /// The linear solve failed.
    #[error(transparent)]
    LinearSolver(#[from] LinearSolverError),
}

/// Wall-clock seconds per phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
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

/// What one converged step did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations (linear solves).
    pub iterations: usize,
    /// Free-DOF residual norm at each iteration, the last one converged.
    pub residuals: Vec<f64>,
    /// Phase timings of this step.
    pub timings: PhaseTimings,
}

struct Workspace {
    dofs: DofMap,
    pattern: AssemblyPattern,
    domain_matrix: Vec<usize>,
    domain_vector: Vec<usize>,
    matrices: Vec<f64>,
    vectors: Vec<f64>,
    values: Vec<f64>,
    residual: Vec<f64>,
    rhs: Vec<f64>,
    delta: Vec<f64>,
    slip: SlipRotations,
    solver: LinearSolver,
}

impl Workspace {
    /// Every domain fills its part of the element buffers.
    fn assemble_domains(
        &mut self,
        domains: &mut [Box<dyn Domain>],
        input: &AssemblyInput<'_>,
    ) -> Result<(), DomainError> {
        let mut mats = self.matrices.as_mut_slice();
        let mut vecs = self.vectors.as_mut_slice();
        for (k, d) in domains.iter_mut().enumerate() {
            let (m, rest_m) = mats.split_at_mut(self.domain_matrix[k + 1] - self.domain_matrix[k]);
            let (v, rest_v) = vecs.split_at_mut(self.domain_vector[k + 1] - self.domain_vector[k]);
            d.assemble(input, m, v)?;
            mats = rest_m;
            vecs = rest_v;
        }
        self.slip.rotate_blocks(&mut self.matrices, &mut self.vectors);
        Ok(())
    }
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
    /// Domains on the shared node set.
    pub domains: Vec<Box<dyn Domain>>,
    /// Prescribed displacements.
    pub constraints: Vec<Constraint>,
    /// External nodal forces.
    pub loads: Vec<Load>,
    /// Frictionless slip conditions (local rotation of the nodal DOFs).
    pub slips: Vec<Slip>,
    /// Gravity (m/s²) and its time function.
    pub gravity: ([f64; 3], Amplitude),
    /// Time scheme.
    pub scheme: TimeScheme,
    /// Newton settings.
    pub settings: NewtonSettings,
    /// Current iterate (equal to `committed` between steps).
    pub state: NodalState,
    /// Last converged state.
    pub committed: NodalState,
    /// Time of the committed state.
    pub time: f64,
    /// Reactions (full DOF vector; nonzero at constrained DOFs) of the committed state.
    pub reactions: Vec<f64>,
    workspace: Option<Workspace>,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl Model {
    /// A model over `coords` with `dim` DOFs per node and no domains yet.
    pub fn new(dim: usize, coords: Vec<[f64; 3]>, scheme: TimeScheme, settings: NewtonSettings) -> Self {
        let n = coords.len() * dim;
        Self {
            dim,
            coords,
            domains: Vec::new(),
            constraints: Vec::new(),
            loads: Vec::new(),
            slips: Vec::new(),
            gravity: ([0.0; 3], Amplitude::default()),
            scheme,
            settings,
            state: NodalState::zeros(n),
            committed: NodalState::zeros(n),
            time: 0.0,
            reactions: vec![0.0; n],
            workspace: None,
        }
    }

    /// Number of DOFs (constrained included).
    pub fn num_dofs(&self) -> usize {
        self.coords.len() * self.dim
    }

    /// Number of equations (after [`Model::prepare`]).
    pub fn num_equations(&self) -> usize {
        self.workspace.as_ref().map_or(0, |w| w.dofs.num_equations())
    }

    /// Number of nonzeros of the global matrix (after [`Model::prepare`]).
    pub fn nnz(&self) -> usize {
        self.workspace.as_ref().map_or(0, |w| w.pattern.nnz())
    }

    /// Forgets the sparsity pattern (after a change of domains or constraints).
    pub fn invalidate_pattern(&mut self) {
        self.workspace = None;
    }

    /// Builds the DOF map, the element-buffer layout and the sparsity pattern, if needed.
    pub fn prepare(&mut self) {
        if self.workspace.is_some() {
            return;
        }
        let mut constrained = vec![false; self.num_dofs()];
        for c in &self.constraints {
            for &d in &c.dofs {
                constrained[d] = true;
            }
        }
        let mut layout = BlockLayout::default();
        let mut domain_matrix = vec![0];
        let mut domain_vector = vec![0];
        for d in &self.domains {
            d.blocks(&mut layout);
            domain_matrix.push(layout.matrix_len());
            domain_vector.push(layout.vector_len());
        }
        // nodes no block touches carry no equation
        let mut touched = vec![false; self.num_dofs()];
        for &g in &layout.dofs {
            touched[g] = true;
        }
        for (c, t) in constrained.iter_mut().zip(&touched) {
            *c |= !t;
        }
        let dirichlet = constrained.clone();
        let dim = self.dim;
        let slip = SlipRotations::new(dim, &self.slips, &layout, |n| (0..dim).any(|i| dirichlet[n * dim + i]));
        for d in slip.normal_dofs() {
            constrained[d] = true;
        }
        let dofs = DofMap::new(self.dim, &constrained);
        let pattern = AssemblyPattern::new(&dofs, &layout);
        let n_eq = dofs.num_equations();
        self.workspace = Some(Workspace {
            matrices: vec![0.0; layout.matrix_len()],
            vectors: vec![0.0; layout.vector_len()],
            values: vec![0.0; pattern.nnz()],
            residual: vec![0.0; self.num_dofs()],
            rhs: vec![0.0; n_eq],
            delta: vec![0.0; self.num_dofs()],
            slip,
            solver: LinearSolver::new(self.settings.linear_solver),
            dofs,
            pattern,
            domain_matrix,
            domain_vector,
        });
    }

    /// Accumulated times of the linear solver (symbolic analyses, numeric factorisations,
    /// solves) since the pattern was built.
    pub fn solver_timings(&self) -> SolverTimings {
        self.workspace.as_ref().map_or_else(SolverTimings::default, |w| w.solver.timings)
    }

    /// Consistent initial acceleration for a dynamic analysis: solves
    /// `M a₀ = f_ext(t) + f_body − f_int(u)` at the committed state (prescribed DOFs keep
    /// `a = 0`) and hands `a₀` to the domains. Without it, a load applied suddenly at
    /// `t = 0` loses `Δt/2 · a₀` of velocity in the first step. No-op for static schemes.
    pub fn initialise_acceleration(&mut self) -> Result<(), StepError> {
        if self.scheme.coefficients().is_none() {
            return Ok(());
        }
        let mut projection = Projection::new(self.coords.len(), self.dim);
        let mut changed = false;
        for d in self.domains.iter_mut() {
            changed |= d.begin_step(&mut projection);
        }
        for d in self.domains.iter_mut() {
            d.end_projection(&projection);
        }
        projection.apply(&mut self.committed);
        if changed {
            self.invalidate_pattern();
        }
        self.prepare();
        self.state.clone_from(&self.committed);
        let n = self.num_dofs();
        let mut f_ext = vec![0.0; n];
        for l in &self.loads {
            let f = l.amplitude.at(self.time);
            for &(d, v) in &l.forces {
                f_ext[d] += v * f;
            }
        }
        let mut ws = self.workspace.take().expect("prepared");
        ws.slip.to_local(&mut f_ext);
        let gf = self.gravity.1.at(self.time);
        let input = AssemblyInput {
            state: &self.state,
            committed: &self.committed,
            inertial_acceleration: None,
            mass_coefficient: 1.0,
            gravity: self.gravity.0.map(|g| g * gf),
            time_step: 0.0,
            gamma: 0.5,
            time: self.time,
            with_tangent: true,
            stiffness: false,
        };
        let result = (|| {
            ws.assemble_domains(&mut self.domains, &input)?;
            ws.pattern.gather_vector(&ws.vectors, &mut ws.residual);
            ws.pattern.gather_matrix(&ws.matrices, &mut ws.values);
            for (g, &e) in ws.dofs.equations().iter().enumerate() {
                if e != CONSTRAINED {
                    ws.rhs[e] = f_ext[g] - ws.residual[g];
                }
            }
            ws.solver.solve(&ws.pattern, &ws.values, &mut ws.rhs)?;
            for (g, &e) in ws.dofs.equations().iter().enumerate() {
                ws.delta[g] = if e != CONSTRAINED { ws.rhs[e] } else { 0.0 };
            }
            ws.slip.to_global(&mut ws.delta);
            Ok::<(), StepError>(())
        })();
        self.committed.a.copy_from_slice(&ws.delta);
        self.state.a.copy_from_slice(&ws.delta);
        for d in self.domains.iter_mut() {
            d.accept_initial_acceleration(&ws.delta);
        }
        self.workspace = Some(ws);
        result
    }

    /// Assembles once at the current iterate, as the first Newton iteration of a static
    /// step of length 0 would (element kernels, then gather of residual and tangent), and
    /// discards the result. For benchmarks and profiling (`benches/fem_newton.rs`); the
    /// committed state and the domains' histories are not changed.
    pub fn assemble_only(&mut self) -> Result<AssemblyTimings, StepError> {
        self.prepare();
        let gf = self.gravity.1.at(self.time);
        let input = AssemblyInput {
            state: &self.state,
            committed: &self.committed,
            inertial_acceleration: None,
            mass_coefficient: 0.0,
            gravity: self.gravity.0.map(|g| g * gf),
            time_step: 0.0,
            gamma: 0.5,
            time: self.time,
            with_tangent: true,
            stiffness: true,
        };
        let ws = self.workspace.as_mut().expect("prepared");
        let t = Instant::now();
        ws.assemble_domains(&mut self.domains, &input)?;
        let kernels = t.elapsed().as_secs_f64();
        let t = Instant::now();
        ws.pattern.gather_vector(&ws.vectors, &mut ws.residual);
        ws.pattern.gather_matrix(&ws.matrices, &mut ws.values);
        Ok(AssemblyTimings { kernels, gather: t.elapsed().as_secs_f64() })
    }

    /// Advances from the committed state by `dt`. On success the new state is committed
    /// and `time` advanced; on failure nothing committed changes (call again with a
    /// smaller step).
    pub fn solve_step(&mut self, dt: f64) -> Result<StepReport, StepError> {
        let mut report = StepReport::default();
        let t0 = Instant::now();
        // initialisation phase of particle domains (locate, project); a changed set of
        // element blocks invalidates the sparsity pattern
        let mut topology_changed = false;
        let mut projection = Projection::new(self.coords.len(), self.dim);
        for d in self.domains.iter_mut() {
            topology_changed |= d.begin_step(&mut projection);
        }
        for d in self.domains.iter_mut() {
            d.end_projection(&projection);
        }
        projection.apply(&mut self.committed);
        if topology_changed {
            self.invalidate_pattern();
        }
        report.timings.search += t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        if self.workspace.is_none() {
            report.timings.pattern_builds += 1;
        }
        self.prepare();
        report.timings.pattern += t0.elapsed().as_secs_f64();
        let t_new = self.time + dt;
        let scheme = self.scheme;
        let settings = self.settings;
        let n = self.num_dofs();
        self.state.clone_from(&self.committed);
        for c in &self.constraints {
            let f = c.amplitude.at(t_new);
            for (&d, &v) in c.dofs.iter().zip(&c.values) {
                self.state.u[d] = v * f;
            }
        }
        self.update_kinematics(dt);
        let mut f_ext = vec![0.0; n];
        for l in &self.loads {
            let f = l.amplitude.at(t_new);
            for &(d, v) in &l.forces {
                f_ext[d] += v * f;
            }
        }
        if let Some(ws) = &self.workspace {
            ws.slip.to_local(&mut f_ext);
        }
        let gf = self.gravity.1.at(t_new);
        let gravity = self.gravity.0.map(|g| g * gf);
        let mut inertial = vec![0.0; n];
        let mut r0 = 0.0;
        let mut du_step = vec![0.0; n];
        let mut last_du = f64::INFINITY;
        let mut previous_du = f64::INFINITY;
        let mut ws = self.workspace.take().expect("prepared");
        let result = (|| {
            for it in 0..=settings.max_iterations {
                if scheme.coefficients().is_some() {
                    for ((m, &a), &an) in inertial.iter_mut().zip(&self.state.a).zip(&self.committed.a) {
                        *m = scheme.inertial_acceleration(a, an);
                    }
                }
                // when the step has most likely converged, assemble the residual alone first
                // and the tangent only if the residual says otherwise: the displacement
                // criterion is known before assembling, and Newton's quadratic convergence
                // predicts the residual after the last correction δu_k from the one before,
                // r_k ≈ r_{k−1} (|δu_k| / |δu_{k−1}|)² (trusted with a factor 2 to spare; a
                // wrong guess costs one residual-only assembly)
                let du_norm = norm(&du_step);
                let disp_ok = it > 0
                    && (last_du <= settings.displacement_absolute_tolerance
                        || last_du <= settings.displacement_relative_tolerance * du_norm);
                let residual_likely_ok = it > 1 && {
                    let predicted = report.residuals[it - 1] * (last_du / previous_du).powi(2);
                    predicted
                        <= 0.5 * settings.residual_absolute_tolerance.max(settings.residual_relative_tolerance * r0)
                };
                let likely_converged = match settings.convergence_criterion {
                    ConvergenceCriterion::Residual => residual_likely_ok,
                    ConvergenceCriterion::Displacement | ConvergenceCriterion::And => disp_ok,
                    ConvergenceCriterion::Or => disp_ok || residual_likely_ok,
                };
                let mut with_tangent = !likely_converged;
                let mut first_pass = true;
                // fraction of the last correction `ws.delta` currently applied
                let mut step_length = 1.0;
                let mut backtracks = 0;
                loop {
                    let t = Instant::now();
                    let input = AssemblyInput {
                        state: &self.state,
                        committed: &self.committed,
                        inertial_acceleration: scheme.coefficients().map(|_| inertial.as_slice()),
                        mass_coefficient: scheme.mass_coefficient(dt),
                        gravity,
                        time_step: dt,
                        gamma: scheme.coefficients().map_or(0.5, |c| c.2),
                        time: t_new,
                        with_tangent,
                        stiffness: true,
                    };
                    ws.assemble_domains(&mut self.domains, &input)?;
                    ws.pattern.gather_vector(&ws.vectors, &mut ws.residual);
                    for (r, f) in ws.residual.iter_mut().zip(&f_ext) {
                        *r -= f;
                    }
                    for (g, &e) in ws.dofs.equations().iter().enumerate() {
                        if e != CONSTRAINED {
                            ws.rhs[e] = -ws.residual[g];
                        }
                    }
                    let r_norm = norm(&ws.rhs);
                    report.timings.assembly += t.elapsed().as_secs_f64();
                    if !first_pass {
                        break;
                    }
                    let r_prev = report.residuals.last().copied().unwrap_or(f64::INFINITY);
                    if settings.line_search
                        && it > 1
                        && backtracks < settings.line_search_max_cuts
                        && (r_norm >= r_prev || r_norm.is_nan())
                    {
                        // take back half of the applied part of the correction
                        let shorter = 0.5 * step_length;
                        let back = step_length - shorter;
                        for ((u, du), d) in self.state.u.iter_mut().zip(du_step.iter_mut()).zip(&ws.delta) {
                            *u -= back * d;
                            *du -= back * d;
                        }
                        last_du *= shorter / step_length;
                        step_length = shorter;
                        backtracks += 1;
                        self.update_kinematics(dt);
                        continue;
                    }
                    first_pass = false;
                    report.residuals.push(r_norm);
                    if trace_newton() {
                        eprintln!("newton t={t_new:.6e} dt={dt:.3e} it={it} |r|={r_norm:.3e} |du|={last_du:.3e} |Du|={du_norm:.3e} backtracks={backtracks} tangent={with_tangent}");
                    }
                    if it == 0 {
                        r0 = r_norm;
                    }
                    let res_ok = r_norm <= settings.residual_absolute_tolerance
                        || r_norm <= settings.residual_relative_tolerance * r0;
                    let converged = (it == 0 && r_norm <= settings.residual_absolute_tolerance)
                        || (it > 0
                            && match settings.convergence_criterion {
                                ConvergenceCriterion::Residual => res_ok,
                                ConvergenceCriterion::Displacement => disp_ok,
                                ConvergenceCriterion::And => res_ok && disp_ok,
                                ConvergenceCriterion::Or => res_ok || disp_ok,
                            });
                    if !r_norm.is_finite() {
                        return Err(StepError::NoConvergence { iterations: it, residual: r_norm });
                    }
                    if converged {
                        report.iterations = it;
                        for (g, &e) in ws.dofs.equations().iter().enumerate() {
                            self.reactions[g] = if e == CONSTRAINED { ws.residual[g] } else { 0.0 };
                        }
                        ws.slip.to_global(&mut self.reactions);
                        let t = Instant::now();
                        for d in self.domains.iter_mut() {
                            d.commit(&input);
                        }
                        report.timings.commit += t.elapsed().as_secs_f64();
                        return Ok(());
                    }
                    if with_tangent || it == settings.max_iterations {
                        break;
                    }
                    with_tangent = true;
                }
                if it == settings.max_iterations {
                    break;
                }
                let t = Instant::now();
                ws.pattern.gather_matrix(&ws.matrices, &mut ws.values);
                report.timings.assembly += t.elapsed().as_secs_f64();
                let before = ws.solver.timings;
                ws.solver.solve(&ws.pattern, &ws.values, &mut ws.rhs)?;
                report.timings.factorisation += ws.solver.timings.factorisation - before.factorisation
                    + ws.solver.timings.symbolic
                    - before.symbolic;
                report.timings.symbolic += ws.solver.timings.symbolic - before.symbolic;
                report.timings.solve += ws.solver.timings.solve - before.solve;
                for (g, &e) in ws.dofs.equations().iter().enumerate() {
                    ws.delta[g] = if e != CONSTRAINED { ws.rhs[e] } else { 0.0 };
                }
                ws.slip.to_global(&mut ws.delta);
                for ((u, du), d) in self.state.u.iter_mut().zip(du_step.iter_mut()).zip(&ws.delta) {
                    *u += d;
                    *du += d;
                }
                previous_du = last_du;
                last_du = norm(&ws.rhs);
                self.update_kinematics(dt);
            }
            Err(StepError::NoConvergence {
                iterations: settings.max_iterations,
                residual: report.residuals.last().copied().unwrap_or(f64::NAN),
            })
        })();
        self.workspace = Some(ws);
        match result {
            Ok(()) => {
                self.committed.clone_from(&self.state);
                self.time = t_new;
                Ok(report)
            }
            Err(e) => {
                self.state.clone_from(&self.committed);
                Err(e)
            }
        }
    }

    fn update_kinematics(&mut self, dt: f64) {
        let scheme = self.scheme;
        let s = &mut self.state;
        let c = &self.committed;
        for g in 0..s.u.len() {
            let (v, a) = scheme.kinematics(dt, s.u[g], c.u[g], c.v[g], c.a[g]);
            s.v[g] = v;
            s.a[g] = a;
        }
    }

    /// Total kinetic energy of the committed state.
    pub fn kinetic_energy(&self) -> f64 {
        self.domains.iter().map(|d| d.kinetic_energy(&self.committed.v)).sum()
    }

    /// Total stored work of internal forces of the committed state.
    pub fn strain_energy(&self) -> f64 {
        self.domains.iter().map(|d| d.strain_energy()).sum()
    }
}

/// Whether `LOAM_NEWTON_TRACE` asks for every Newton iteration's norms on stderr.
fn trace_newton() -> bool {
    static TRACE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *TRACE.get_or_init(|| std::env::var_os("LOAM_NEWTON_TRACE").is_some())
}
