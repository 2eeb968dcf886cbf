//! The Newton–Raphson strategy of one implicit step (Kratos' residual-based Newton strategy).
//!
//! From the predictor `u = u_n` (prescribed values at `t_{n+1}`), iteration `k`:
//!
//! 1. the time scheme gives `v`, `a` and the inertial acceleration `ã` from `u`;
//! 2. the assembler forms `R(u) = f_int − f_body + M ã − f_ext` (and the tangent
//!    `K_t + c_M M` unless the step has most likely converged: then the residual alone first,
//!    [`crate::convergence::Convergence::likely`]);
//! 3. with a line search, a residual that grew (or is not finite) takes back half of the
//!    last correction, up to `line_search_max_cuts` times;
//! 4. the convergence criteria decide; if not converged, `K δu = −R` is solved and
//!    `u ← u + δu`.
//!
//! **Modified Newton** ([`TangentReuse::Auto`], `solver.tangent_reuse`): the factors of the
//! last tangent of the pattern and step length are kept, also into the next step; an
//! iteration solves with them instead of assembling and factorising a new tangent while the
//! residual contracts by [`REUSE_CONTRACTION`] or better per iteration (the first iteration
//! of a step tries them unconditionally), in the first half of the iteration budget. A kept
//! factor's correction that does not reduce the residual is taken back whole, and a new
//! tangent is factorised at the previous iterate. The converged state meets the same
//! criteria as with full Newton (the residual is always exact); only the path differs
//! (linear instead of quadratic convergence in the reused iterations).
//!
//! **Finishing with kept factors** ([`TangentReuse::Finish`]): under the `and` criterion a step
//! often meets the residual tolerance an iteration or two before its last correction is small
//! enough (the displacement criterion): in the default Bui collapse's first 0.1 s (on a step
//! tolerance of 2e-6 m), 159 of 509 corrections came after the residual had converged. Those
//! iterations solve with the factors of the step's last tangent and assemble the residual
//! alone, once the last correction is within [`FINISH_REACH`] of the displacement tolerance
//! and while the residual stays below its tolerance and falls by [`FINISH_CONTRACTION`] or
//! better per iteration; a correction that does not reduce it is taken back and a new tangent
//! factorised, as above. Kept factors do not cross steps here. The converged state meets the
//! same criteria.
//!
//! The residual and correction norms of every iteration, per block of the monolithic system,
//! go into the [`StepReport`]; with [`NewtonSettings::trace`] (`loam run --trace-newton`)
//! every iteration also prints them on stderr.

use std::time::Instant;

use serde::Deserialize;

use crate::assembler::Assembler;
use crate::convergence::{Convergence, ConvergenceCriterion};
use crate::domain::{AssemblyInput, Domain, NodalState};
use crate::linear_solver::{CholeskyFactorisation, LinearSolverKind};
use crate::model::{StepError, StepReport};
use crate::ranks::Ranks;
use crate::scheme::TimeScheme;

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
    /// Backtracking line search: halve the correction while the residual grows (default
    /// off; helps Newton through the kinks of plasticity in flowing granular bodies).
    pub line_search: bool,
    /// Halvings tried per iteration by the line search (default 4).
    pub line_search_max_cuts: u32,
    /// How the Cholesky-type factorisations (`L Lᵀ`, `L D Lᵀ`, `L B Lᵀ`) are organised
    /// (default supernodal).
    pub cholesky_factorisation: CholeskyFactorisation,
    /// Rings of inactive cells an MPM grid keeps in the sparsity pattern around its active
    /// ones (default [`DEFAULT_MPM_PATTERN_RINGS`]): the pattern, its symbolic factorisation
    /// included, is rebuilt only when the material leaves them; 0 rebuilds it at every
    /// change of the active cells.
    pub mpm_pattern_rings: usize,
    /// Whether an iteration may solve with the factors of an earlier tangent (modified
    /// Newton) while the residual contracts fast enough (default `off`; see
    /// [`TangentReuse`]).
    pub tangent_reuse: TangentReuse,
    /// Whether a grid node's projected velocity and acceleration are set to rest where a
    /// boundary holds it, after the projection of every step (default `true`; see
    /// `Model::hold_grid_boundaries`). `false` keeps the projected values, as Kratos' MPM
    /// does: `loam import kratos` sets it so that imported dynamic cases reproduce Kratos.
    pub hold_grid_boundaries: bool,
    /// The first iterate of a dynamic step (default `constant_displacement`; see
    /// [`Predictor`]).
    pub predictor: Predictor,
    /// Print every iteration's residual and correction norms on stderr (not a case key:
    /// `loam run --trace-newton` sets it).
    #[serde(skip)]
    pub trace: bool,
    /// The ranks of a distributed run (not a case key: `loam run` under `mpirun` sets it;
    /// one process by default), see [`crate::ranks`].
    #[serde(skip)]
    pub ranks: Ranks,
}

/// When a Newton iteration solves with the factors of an earlier tangent instead of
/// assembling and factorising a new one: the case file's `solver.tangent_reuse`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TangentReuse {
    /// Full Newton: a new tangent at every iteration.
    #[default]
    Off,
    /// Modified Newton decided per iteration from the measured contraction (module doc):
    /// the kept factors of the last tangent of this pattern and step length serve while
    /// `‖R_k‖/‖R_{k−1}‖ ≤` [`REUSE_CONTRACTION`], in the first half of the iteration budget.
    Auto,
    /// Full Newton until the residual criterion holds; the iterations after it, while only
    /// the displacement criterion is pending, solve with the factors of the step's last
    /// tangent and assemble the residual alone (module doc).
    Finish,
}

/// The first iterate of a dynamic step: the case file's `solver.predictor`. Prescribed
/// DOFs take their prescribed values either way, and a static step always starts from
/// `u_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Predictor {
    /// `u = u_n`: the step starts where the last one ended (a grid node: where the grid was
    /// placed), with the time scheme's `v`, `a` for no motion.
    #[default]
    ConstantDisplacement,
    /// `u = u_n + Δt v_n + ½ Δt² a_n`: the motion continues with the last acceleration
    /// (the time scheme then gives `a = a_n`, `v = v_n + Δt a_n` at the predictor), as
    /// Kratos' Newmark and Bossak schemes predict. Newton starts `β Δt² |a_{n+1} − a_n|`
    /// from the solution instead of the step's whole motion `|Δu|`.
    ConstantAcceleration,
}

/// Largest contraction `‖R_k‖/‖R_{k−1}‖` of the last iteration under which the next one may
/// reuse kept factors ([`TangentReuse::Auto`]): a modified-Newton iteration then costs a
/// residual assembly and two triangular solves instead of a tangent assembly and a
/// factorisation, and four of them still gain 2.4 decades on the residual.
pub const REUSE_CONTRACTION: f64 = 0.25;

/// How far from converged a step may be for [`TangentReuse::Finish`] to solve with kept
/// factors: its last correction within this factor of the displacement tolerance (kept
/// factors contract the correction by 10–100 per iteration near the solution; farther out
/// a new tangent's quadratic rate needs fewer iterations).
pub const FINISH_REACH: f64 = 100.0;

/// Largest contraction `‖R_k‖/‖R_{k−1}‖` of a kept-factor iteration under [`TangentReuse::Finish`]
/// after which the step goes on with kept factors; a slower one ends their use in the step.
pub const FINISH_CONTRACTION: f64 = 0.5;

/// Default of [`NewtonSettings::mpm_pattern_rings`].
pub const DEFAULT_MPM_PATTERN_RINGS: usize = 1;

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
            cholesky_factorisation: CholeskyFactorisation::Supernodal,
            mpm_pattern_rings: DEFAULT_MPM_PATTERN_RINGS,
            tangent_reuse: TangentReuse::Off,
            hold_grid_boundaries: true,
            predictor: Predictor::ConstantDisplacement,
            trace: false,
            ranks: Ranks::single(),
        }
    }
}

impl NewtonSettings {
    /// The convergence criteria of these settings.
    pub fn convergence(&self) -> Convergence {
        Convergence::new(
            self.convergence_criterion,
            self.residual_relative_tolerance,
            self.residual_absolute_tolerance,
            self.displacement_relative_tolerance,
            self.displacement_absolute_tolerance,
        )
    }
}

/// The nonlinear problem of one step: what the strategy iterates on.
pub struct StepProblem<'a> {
    /// The domains (element blocks).
    pub domains: &'a mut [Box<dyn Domain>],
    /// The global system of the current pattern.
    pub assembler: &'a mut Assembler,
    /// The iterate at `t_{n+1}`, starting from the predictor.
    pub state: &'a mut NodalState,
    /// The converged state at `t_n`.
    pub committed: &'a NodalState,
    /// Time scheme.
    pub scheme: TimeScheme,
    /// Step length Δt.
    pub dt: f64,
    /// `t_{n+1}`.
    pub time: f64,
    /// Gravity at `t_{n+1}`.
    pub gravity: [f64; 3],
    /// External nodal forces at `t_{n+1}` (local frames at slip nodes).
    pub f_ext: &'a [f64],
    /// Number of displacement DOFs (the DOFs with velocity and acceleration).
    pub kinematic_dofs: usize,
    /// Reference coordinates of the nodes (for the trace's residual peak: where it is).
    pub coords: &'a [[f64; 3]],
}

impl StepProblem<'_> {
    /// ` peak=<node>@(<x>, <y>[, <z>]):<force>`: the node whose displacement equations carry
    /// the largest residual ([`Assembler::largest_nodal_residual`]), where it was at the start
    /// of the step, or nothing.
    fn residual_peak(&self) -> String {
        let Some((node, force, _)) = self.assembler.largest_nodal_residual() else { return String::new() };
        format!(" peak={node}@({}):{force:.3e}", self.node_position(node))
    }

    /// ` dpeak=<node>@(<x>, <y>[, <z>]):<norm>`: the node whose displacement moved most in the
    /// step so far (`‖Δu‖` over its components), or nothing before the first correction.
    fn increment_peak(&self, du_step: &[f64]) -> String {
        let dim = self.kinematic_dofs / self.coords.len().max(1);
        let norm = |n: usize| du_step[n * dim..(n + 1) * dim].iter().map(|d| d * d).sum::<f64>().sqrt();
        let peak = (0..self.coords.len()).max_by(|&a, &b| norm(a).total_cmp(&norm(b)));
        match peak.filter(|&n| norm(n) > 0.0) {
            Some(n) => format!(" dpeak={n}@({}):{:.3e}", self.node_position(n), norm(n)),
            None => String::new(),
        }
    }

    /// `x, y[, z]` of node `n` at the start of the step.
    fn node_position(&self, n: usize) -> String {
        let dim = self.kinematic_dofs / self.coords.len().max(1);
        let at: Vec<String> =
            (0..dim.min(3)).map(|i| format!("{:.4}", self.coords[n][i] + self.committed.u[n * dim + i])).collect();
        at.join(", ")
    }

    /// `u ← u + s δu` for the last correction, with the step's increment `Δu` and the
    /// kinematics following.
    fn apply_correction(&mut self, s: f64, du_step: &mut [f64]) {
        for ((u, du), d) in self.state.u.iter_mut().zip(du_step.iter_mut()).zip(self.assembler.correction()) {
            *u += s * d;
            *du += s * d;
        }
        self.scheme.update_kinematics(self.dt, self.state, self.committed, self.kinematic_dofs);
    }
}

/// The assembly input of a step at the iterate `state`, with inertia at `inertial`.
#[allow(clippy::too_many_arguments)]
pub fn assembly_input<'b>(
    scheme: TimeScheme,
    state: &'b NodalState,
    committed: &'b NodalState,
    inertial: &'b [f64],
    dt: f64,
    time: f64,
    gravity: [f64; 3],
    with_tangent: bool,
) -> AssemblyInput<'b> {
    AssemblyInput {
        state,
        committed,
        inertial_acceleration: scheme.is_dynamic().then_some(inertial),
        mass_coefficient: scheme.mass_coefficient(dt),
        gravity,
        time_step: dt,
        gamma: scheme.gamma(),
        time,
        with_tangent,
        stiffness: true,
    }
}

/// Newton–Raphson with optional line search (see the module doc).
pub struct NewtonStrategy {
    /// Settings from the case file.
    pub settings: NewtonSettings,
    /// The first residual of an earlier solve of the same step, as the reference of the
    /// relative residual criterion (a step solved again after an augmented-Lagrangian update
    /// converges to the step's tolerance, not to a fraction of the update's small residual).
    pub reference_residual: Option<f64>,
}

impl NewtonStrategy {
    /// Iterates `problem` to convergence; the iterations and norms go into `report`. On
    /// success `problem.state` is the converged state and the last assembly is at it.
    pub fn solve(&self, problem: &mut StepProblem<'_>, report: &mut StepReport) -> Result<(), StepError> {
        let settings = &self.settings;
        let mut convergence = settings.convergence();
        if let Some(r0) = self.reference_residual {
            convergence.set_reference(r0);
        }
        let n = problem.state.u.len();
        let mut inertial = vec![0.0; n];
        // the step's increment `Δu = u − u_n`: from the predictor's motion where it has one,
        // so that the displacement criterion compares a correction with the step's motion
        let mut du_step = vec![0.0; n];
        if settings.predictor == Predictor::ConstantAcceleration && problem.scheme.is_dynamic() {
            for ((d, u), un) in du_step.iter_mut().zip(&problem.state.u).zip(&problem.committed.u) {
                *d = u - un;
            }
        }
        let mut last_du = f64::INFINITY;
        let mut previous_du = f64::INFINITY;
        let keep_factors = settings.tangent_reuse != TangentReuse::Off;
        // whether the last correction came from kept factors (modified Newton)
        let mut reused_last = false;
        // whether the last iteration could finish the step with kept factors (for `Finish`)
        let mut finishing_last = false;
        // whether a kept-factor iteration of this step contracted too slowly (for `Finish`)
        let mut finish_stalled = false;
        for it in 0..=settings.max_iterations {
            let r_prev = report.residuals.last().copied().unwrap_or(f64::INFINITY);
            let du_step_norm = problem.assembler.dof_norm(&du_step);
            let mut displacement_met = convergence.displacement_met(it, last_du, du_step_norm);
            let likely = convergence.likely(it, r_prev, last_du, previous_du, du_step_norm);
            // (for `Finish`, whether this iteration will most likely solve with kept factors
            // and so needs no tangent)
            let planned_reuse = problem.assembler.has_factors_for(problem.dt)
                && match settings.tangent_reuse {
                    TangentReuse::Off => false,
                    TangentReuse::Auto => it < settings.max_iterations / 2,
                    TangentReuse::Finish => {
                        !finish_stalled
                            && (finishing_last
                                || (convergence.residual_likely(it, r_prev, last_du, previous_du)
                                    && convergence.displacement_within(FINISH_REACH, it, last_du, du_step_norm)))
                    }
                };
            let mut with_tangent = !likely && !planned_reuse;
            // fraction of the last correction currently applied
            let mut step_length = 1.0;
            let mut backtracks = 0;
            let mut taken_back = false;
            let r_norm = loop {
                // the inertia of the iterate as it now stands (a line search or a taken-back
                // correction moved it)
                if problem.scheme.is_dynamic() {
                    problem.scheme.inertial_accelerations(problem.state, problem.committed, &mut inertial);
                }
                let assembled = Self::assemble_residual(problem, &inertial, with_tangent, report);
                let reuse_failed = reused_last
                    && !taken_back
                    && assembled.as_ref().map_or(true, |r| r.partial_cmp(&r_prev) != Some(std::cmp::Ordering::Less));
                if let (Err(e), true) = (&assembled, settings.trace) {
                    eprintln!("newton t={:.6e} dt={:.3e} it={it} refused: {e}", problem.time, problem.dt);
                }
                let r = if reuse_failed { f64::NAN } else { assembled? };
                if reuse_failed {
                    // a correction from kept factors that did not reduce the residual (or that
                    // a domain refused: an inverted point) is taken back whole; a new tangent
                    // at the previous iterate follows
                    problem.apply_correction(-step_length, &mut du_step);
                    taken_back = true;
                    displacement_met = false;
                    last_du = f64::INFINITY;
                    with_tangent = true;
                    continue;
                }
                if settings.line_search
                    && !taken_back
                    && it > 1
                    && backtracks < settings.line_search_max_cuts
                    && (r >= r_prev || r.is_nan())
                {
                    // take back half of the applied part of the correction
                    let shorter = 0.5 * step_length;
                    problem.apply_correction(shorter - step_length, &mut du_step);
                    last_du *= shorter / step_length;
                    step_length = shorter;
                    backtracks += 1;
                    continue;
                }
                break r;
            };
            report.residuals.push(r_norm);
            report.block_residuals.push(problem.assembler.block_norms());
            if settings.trace {
                let b = problem.assembler.block_norms();
                eprintln!(
                    "newton t={:.6e} dt={:.3e} it={it} |r|={r_norm:.3e} (soil {:.3e} interface {:.3e} structure {:.3e}) |du|={last_du:.3e} |Du|={:.3e} backtracks={backtracks} tangent={with_tangent} reused={reused_last}{}{}",
                    problem.time, problem.dt, b.soil, b.interface, b.structure, problem.assembler.dof_norm(&du_step), problem.residual_peak(), problem.increment_peak(&du_step)
                );
            }
            if !r_norm.is_finite() {
                return Err(StepError::NoConvergence { iterations: it, residual: r_norm, largest: None });
            }
            if convergence.converged(it, r_norm, displacement_met) {
                report.iterations += it;
                return Ok(());
            }
            if it == settings.max_iterations {
                break;
            }
            let contraction = if it == 0 { 0.0 } else { r_norm / r_prev };
            let finish = settings.tangent_reuse == TangentReuse::Finish;
            if finish && reused_last && contraction > FINISH_CONTRACTION {
                finish_stalled = true;
            }
            // (for `Finish`) the residual has converged, the correction is nearly small enough
            let finishing = finish
                && convergence.residual_criterion_met(it, r_norm)
                && !finish_stalled
                && convergence.displacement_within(FINISH_REACH, it, last_du, problem.assembler.dof_norm(&du_step));
            let reuse = !taken_back
                && match settings.tangent_reuse {
                    TangentReuse::Off => false,
                    TangentReuse::Auto => planned_reuse && contraction <= REUSE_CONTRACTION,
                    TangentReuse::Finish => finishing && problem.assembler.has_factors_for(problem.dt),
                };
            finishing_last = finishing && !taken_back;
            let before = problem.assembler.solver_timings();
            let correction = if reuse { problem.assembler.solve_with_kept_factors()? } else { None };
            reused_last = correction.is_some();
            let correction = match correction {
                Some(c) => c,
                None => {
                    if !with_tangent {
                        // the prediction failed: the tangent at the same iterate
                        with_tangent = true;
                        Self::assemble_residual(problem, &inertial, with_tangent, report)?;
                    }
                    let t = Instant::now();
                    problem.assembler.tangent();
                    report.timings.assembly += t.elapsed().as_secs_f64();
                    let c = problem.assembler.solve()?;
                    report.tangents += 1;
                    if keep_factors {
                        problem.assembler.keep_factors_for(problem.dt);
                    }
                    c
                }
            };
            let after = problem.assembler.solver_timings();
            report.timings.factorisation +=
                after.factorisation - before.factorisation + after.symbolic - before.symbolic;
            report.timings.symbolic += after.symbolic - before.symbolic;
            report.timings.solve += after.solve - before.solve;
            report.block_corrections.push(problem.assembler.block_norms());
            problem.apply_correction(1.0, &mut du_step);
            previous_du = last_du;
            last_du = correction;
        }
        Err(StepError::NoConvergence {
            iterations: settings.max_iterations,
            residual: report.residuals.last().copied().unwrap_or(f64::NAN),
            largest: None,
        })
    }

    /// Element kernels and residual at the current iterate; returns `‖R‖`.
    fn assemble_residual(
        problem: &mut StepProblem<'_>,
        inertial: &[f64],
        with_tangent: bool,
        report: &mut StepReport,
    ) -> Result<f64, StepError> {
        let t = Instant::now();
        let p = &mut *problem;
        let input = assembly_input(p.scheme, p.state, p.committed, inertial, p.dt, p.time, p.gravity, with_tangent);
        p.assembler.assemble(p.domains, &input)?;
        let r = problem.assembler.residual(problem.f_ext);
        report.timings.assembly += t.elapsed().as_secs_f64();
        Ok(r)
    }
}
