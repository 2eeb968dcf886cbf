//! Analysis, solver and output settings: ranges and combinations, and the time scheme.

use loam_fem::scheme::TimeScheme;

use super::check_positive;
use crate::case::{AnalysisType, Case, CaseError};

/// Most halvings of a failed step (`analysis.max_step_cuts`) or of a Newton correction
/// (`solver.line_search_max_cuts`): 2^-50 of a step is at the round-off of its time.
pub(super) const MAX_STEP_CUTS: u32 = 50;

/// Most Newton iterations per step (`solver.max_iterations`): a Newton iteration that has
/// not converged in a thousand iterations will not.
pub(super) const MAX_NEWTON_ITERATIONS: usize = 1000;

/// Most rings of inactive cells in an MPM grid's sparsity pattern
/// (`solver.mpm_pattern_rings`): each ring is a pass over the grid's cells at every rebuild
/// of the pattern, and a few rings already hold a flow for many steps.
pub(super) const MAX_MPM_PATTERN_RINGS: usize = 100;

/// Checks the case's scalar settings and returns its time scheme.
pub(super) fn check(case: &Case) -> Result<TimeScheme, CaseError> {
    check_positive("thickness", case.thickness)?;
    check_positive("analysis.end_time", case.analysis.end_time)?;
    let dt = case.analysis.time_step;
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(CaseError::new(
            "analysis.time_step",
            format!("must be > 0 (s), e.g. {} (end_time / 100), got {dt}", case.analysis.end_time / 100.0),
        ));
    }
    if case.analysis.time_step > case.analysis.end_time * (1.0 + 1e-12) {
        return Err(CaseError::new("analysis.time_step", "is longer than analysis.end_time"));
    }
    check_positive("solver.residual_relative_tolerance", case.solver.residual_relative_tolerance)?;
    check_positive("solver.residual_absolute_tolerance", case.solver.residual_absolute_tolerance)?;
    check_positive("solver.displacement_relative_tolerance", case.solver.displacement_relative_tolerance)?;
    check_positive("solver.displacement_absolute_tolerance", case.solver.displacement_absolute_tolerance)?;
    if case.analysis.max_step_cuts > MAX_STEP_CUTS {
        return Err(CaseError::new(
            "analysis.max_step_cuts",
            format!(
                "must be at most {MAX_STEP_CUTS} (2^-{MAX_STEP_CUTS} of a step is below round-off), got {}",
                case.analysis.max_step_cuts
            ),
        ));
    }
    if case.solver.line_search_max_cuts > MAX_STEP_CUTS {
        return Err(CaseError::new(
            "solver.line_search_max_cuts",
            format!("must be at most {MAX_STEP_CUTS}, got {}", case.solver.line_search_max_cuts),
        ));
    }
    if case.solver.max_iterations > MAX_NEWTON_ITERATIONS {
        return Err(CaseError::new(
            "solver.max_iterations",
            format!("must be at most {MAX_NEWTON_ITERATIONS}, got {}", case.solver.max_iterations),
        ));
    }
    if case.solver.mpm_pattern_rings > MAX_MPM_PATTERN_RINGS {
        return Err(CaseError::new(
            "solver.mpm_pattern_rings",
            format!(
                "must be at most {MAX_MPM_PATTERN_RINGS} (rings of inactive grid cells, e.g. 1), got {}",
                case.solver.mpm_pattern_rings
            ),
        ));
    }
    let petsc = case.solver.linear_solver == loam_fem::linear_solver::LinearSolverKind::Petsc;
    if !petsc && !case.petsc_options.options.is_empty() {
        return Err(CaseError::new(
            "solver.petsc_options",
            "applies only to solver.linear_solver \"petsc\" (PETSc's Krylov solvers)",
        ));
    }
    if petsc && cfg!(not(feature = "petsc")) {
        return Err(CaseError::new(
            "solver.linear_solver",
            "`petsc` (Krylov + AMG, issue 26) is not in this build: it needs the `petsc` Cargo feature \
             (scripts/install_petsc.sh, docs/distributed.md); use `auto` here",
        ));
    }
    check_limits(case)?;
    if let Some(a) = &case.analysis.adaptive {
        check_positive("analysis.adaptive.min_time_step", a.min_time_step)?;
        check_positive("analysis.adaptive.max_time_step", a.max_time_step)?;
        if a.min_time_step > case.analysis.time_step || a.max_time_step < case.analysis.time_step {
            return Err(CaseError::new(
                "analysis.adaptive",
                format!(
                    "time_step {} must lie in [min_time_step, max_time_step] = [{}, {}]",
                    case.analysis.time_step, a.min_time_step, a.max_time_step
                ),
            ));
        }
        if a.target_iterations == 0 {
            return Err(CaseError::new("analysis.adaptive.target_iterations", "must be at least 1"));
        }
        if !(a.growth >= 1.0 && a.growth.is_finite()) {
            return Err(CaseError::new("analysis.adaptive.growth", format!("must be ≥ 1, got {}", a.growth)));
        }
        if let Some(tolerance) = a.error_tolerance {
            check_positive("analysis.adaptive.error_tolerance", tolerance)?;
        }
    }
    if let Some(c) = &case.analysis.checkpoint {
        if c.every_steps.is_none() && c.every_seconds.is_none() {
            return Err(CaseError::new("analysis.checkpoint", "give every_steps and/or every_seconds"));
        }
        if c.every_steps == Some(0) {
            return Err(CaseError::new("analysis.checkpoint.every_steps", "must be at least 1"));
        }
        if let Some(s) = c.every_seconds {
            check_positive("analysis.checkpoint.every_seconds", s)?;
        }
        if c.keep == 0 {
            return Err(CaseError::new("analysis.checkpoint.keep", "must be at least 1"));
        }
    }
    if let Some(r) = &case.analysis.stop_at_rest {
        check_positive("analysis.stop_at_rest.kinetic_energy_ratio", r.kinetic_energy_ratio)?;
        if !(r.duration >= 0.0 && r.min_time >= 0.0) {
            return Err(CaseError::new("analysis.stop_at_rest", "duration and min_time must be ≥ 0"));
        }
    }
    if let Some(t) = case.output.time_interval {
        check_positive("output.time_interval", t)?;
    }
    for (k, &t) in case.output.times.iter().enumerate() {
        check_positive(&format!("output.times[{k}]"), t)?;
        if k > 0 && t <= case.output.times[k - 1] {
            return Err(CaseError::new(format!("output.times[{k}]"), "times must increase"));
        }
        if t > case.analysis.end_time * (1.0 + 1e-12) {
            return Err(CaseError::new(
                format!("output.times[{k}]"),
                format!("{t} s lies after analysis.end_time = {} s", case.analysis.end_time),
            ));
        }
    }
    check_step_count(case)?;
    if case.solver.max_iterations == 0 {
        return Err(CaseError::new("solver.max_iterations", "must be at least 1"));
    }
    let scheme = match (case.analysis.kind, case.analysis.scheme) {
        (AnalysisType::Dynamic, None) => TimeScheme::Newmark { beta: 0.25, gamma: 0.5 },
        (AnalysisType::Dynamic, Some(TimeScheme::Static)) => {
            return Err(CaseError::new("analysis.scheme", "a dynamic analysis needs newmark or bossak"));
        }
        (AnalysisType::Dynamic, Some(s)) => s,
        (_, None) => TimeScheme::Static,
        (_, Some(TimeScheme::Static)) => TimeScheme::Static,
        (_, Some(_)) => return Err(CaseError::new("analysis.scheme", "only dynamic analyses take a time scheme")),
    };
    scheme.check().map_err(|(k, m)| CaseError::new(format!("analysis.scheme.{k}"), m))?;
    Ok(scheme)
}

/// The bounds of `limits` themselves must be positive.
fn check_limits(case: &Case) -> Result<(), CaseError> {
    let l = &case.limits;
    for (key, v) in [("cells", l.cells), ("material_points", l.material_points), ("steps", l.steps)] {
        if v == 0 {
            return Err(CaseError::new(format!("limits.{key}"), "must be at least 1"));
        }
    }
    Ok(())
}

/// A run may take at most `limits.steps` steps: `end_time / time_step` with fixed steps,
/// `end_time / max_time_step` (the fewest possible) with adaptive ones, plus one step per
/// `output.times` entry (steps are shortened to land on them).
fn check_step_count(case: &Case) -> Result<(), CaseError> {
    let a = &case.analysis;
    let (step, key) = match &a.adaptive {
        Some(adaptive) => (adaptive.max_time_step, "analysis.adaptive.max_time_step"),
        None => (a.time_step, "analysis.time_step"),
    };
    let steps = (a.end_time / step * (1.0 - 1e-12)).ceil() + case.output.times.len() as f64;
    let limit = case.limits.steps;
    if !super::within(steps, limit) {
        return Err(CaseError::new(
            key,
            format!(
                "{step} s steps to analysis.end_time = {} s take {} steps, more than limits.steps = {limit} \
                 (raise it in the case's \"limits\" if the run is meant to be that long)",
                a.end_time,
                super::meshes::count(steps)
            ),
        ));
    }
    Ok(())
}
