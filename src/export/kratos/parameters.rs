//! Kratos' `ProjectParameters.json` of an MPM analysis from a Loam case: the inverse of
//! [`crate::import::kratos::parameters`].
//!
//! `problem_data` and `solver_settings` (Kratos' `MPMSolver`: solver type, time step, scheme,
//! convergence criterion and tolerances, the direct `sparse_lu` linear solver) from `analysis`
//! and `solver`; `processes` from the grid conditions ([`Condition`], the importer's type),
//! gravity and the points whose displacement Kratos writes (`json_output_process`).
//!
//! Kratos steps while `t < end_time`, adding Δt to t: `end_time` is written as (n − ½) Δt for
//! n steps, which no rounding of the sum turns into n ± 1 steps.

use serde_json::{json, Value};

use super::ExportError;
use crate::case::{AnalysisType, Case};
use crate::import::kratos::parameters::{Condition, CRITERIA, SOLVER_TYPES};
use loam_fem::convergence::ConvergenceCriterion;
use loam_fem::scheme::TimeScheme;

/// The grid's model part in Kratos (`Background_Grid.<part>` in processes).
const GRID: &str = "Background_Grid";

/// What the solver settings need beside the case.
pub struct Files<'a> {
    /// Body sub model parts (`Parts_<domain>`) and the grid's (`Parts_Grid`).
    pub parts: &'a [String],
    /// Grid sub model parts that processes use.
    pub process_parts: &'a [String],
    /// Whether the bodies carry pressure unknowns (`mixed_up`).
    pub pressure_dofs: bool,
}

/// `ProjectParameters.json` of `case` with the grid `conditions`, `gravity` and one
/// `json_output_process` per `(sub model part, file)` of `outputs`; notes collect what is
/// approximated.
pub fn project(
    case: &Case,
    files: &Files,
    conditions: &[Condition],
    gravity: Option<[f64; 3]>,
    outputs: &[(String, String)],
    notes: &mut Vec<String>,
) -> Result<Value, ExportError> {
    let a = &case.analysis;
    let dt = a.time_step;
    let steps = (a.end_time / dt - 1e-9).ceil().max(1.0);
    if (steps * dt - a.end_time).abs() > 1e-9 * dt {
        notes.push(format!(
            "analysis.end_time: {} approximated by {steps} steps of {dt} (Kratos has no shorter last step): ends at {}",
            a.end_time,
            steps * dt
        ));
    }
    let dim = case.formulation.dim();
    let mut solver = json!({
        "solver_type": kratos_name(&SOLVER_TYPES.map(|(k, l)| (k[0], l)), a.kind.as_str()),
        "model_part_name": "MPM_Material",
        "domain_size": dim,
        "echo_level": 0,
        "analysis_type": "non_linear",
        "time_integration_method": "implicit",
        "model_import_settings": { "input_type": "mdpa", "input_filename": "Body" },
        "grid_model_import_settings": { "input_type": "mdpa", "input_filename": "Grid" },
        "material_import_settings": { "materials_filename": "ParticleMaterials.json" },
        "time_stepping": { "time_step": dt },
        "pressure_dofs": files.pressure_dofs,
        "axis_symmetric_flag": case.formulation == loam_fem::formulation::Formulation::Axisymmetric,
        // Loam's MPM grid mass is lumped
        "consistent_mass_matrix": false,
        "problem_domain_sub_model_part_list": files.parts,
        "processes_sub_model_part_list": files.process_parts,
        "linear_solver_settings": { "solver_type": "LinearSolversApplication.sparse_lu" },
    });
    if conditions.iter().any(|c| matches!(c, Condition::Slip { .. })) {
        // the slip process computes the nodal normals into NORMAL, which must be allocated
        solver["auxiliary_variables_list"] = json!(["NORMAL"]);
    }
    newton(case, &mut solver, notes);
    if a.kind == AnalysisType::Dynamic {
        scheme(a.scheme.unwrap_or(TimeScheme::Newmark { beta: 0.25, gamma: 0.5 }), &mut solver)?;
    }
    let mut constraints = Vec::new();
    let mut loads = Vec::new();
    for c in conditions {
        match c {
            Condition::Displacement { part, value } => constraints.push(json!({
                "python_module": "assign_vector_variable_process",
                "kratos_module": "KratosMultiphysics",
                "Parameters": {
                    "model_part_name": format!("{GRID}.{part}"),
                    "variable_name": "DISPLACEMENT",
                    "constrained": value.map(|v| v.is_some()),
                    "value": value.map(|v| v.unwrap_or(0.0)),
                    "interval": [0.0, "End"]
                }
            })),
            Condition::Slip { part } => constraints.push(json!({
                "python_module": "apply_mpm_slip_boundary_process",
                "kratos_module": "KratosMultiphysics.MPMApplication",
                "Parameters": { "model_part_name": format!("{GRID}.{part}") }
            })),
            Condition::LineLoad { part, load: v } | Condition::PointLoad { part, force: v } => {
                let variable = if matches!(c, Condition::LineLoad { .. }) { "LINE_LOAD" } else { "POINT_LOAD" };
                let modulus = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                let direction = if modulus > 0.0 { v.map(|x| x / modulus) } else { [1.0, 0.0, 0.0] };
                loads.push(json!({
                    "python_module": "assign_vector_by_direction_to_condition_process",
                    "kratos_module": "KratosMultiphysics",
                    "Parameters": {
                        "model_part_name": format!("{GRID}.{part}"),
                        "variable_name": variable,
                        "modulus": modulus,
                        "direction": direction,
                        "interval": [0.0, "End"]
                    }
                }));
            }
            Condition::Penalty { part, .. } => {
                return Err(ExportError(format!("penalty condition on {part}: not exported")));
            }
        }
    }
    let mut processes = json!({ "constraints_process_list": constraints, "loads_process_list": loads });
    if let Some(g) = gravity {
        let modulus = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        if modulus > 0.0 {
            processes["gravity"] = json!([{
                "python_module": "assign_gravity_to_material_point_process",
                "kratos_module": "KratosMultiphysics.MPMApplication",
                "process_name": "AssignGravityToMaterialPointProcess",
                "Parameters": { "model_part_name": "MPM_Material", "modulus": modulus, "direction": g.map(|x| x / modulus) }
            }]);
        }
    }
    if !outputs.is_empty() {
        processes["list_other_processes"] = outputs
            .iter()
            .map(|(part, file)| {
                json!({
                    "python_module": "json_output_process",
                    "kratos_module": "KratosMultiphysics",
                    "process_name": "JsonOutputProcess",
                    "Parameters": {
                        "output_variables": ["DISPLACEMENT"],
                        "output_file_name": file,
                        "model_part_name": format!("{GRID}.{part}"),
                        "time_frequency": 0.0
                    }
                })
            })
            .collect();
    }
    Ok(json!({
        "problem_data": {
            "problem_name": case.name,
            "parallel_type": "OpenMP",
            "start_time": 0.0,
            "end_time": (steps - 0.5) * dt,
            "echo_level": 0
        },
        "solver_settings": solver,
        "processes": processes
    }))
}

/// The Newton settings: Kratos' MPM solver has a residual and a displacement criterion; Loam's
/// `and` and `or` are approximated by the residual one.
fn newton(case: &Case, solver: &mut Value, notes: &mut Vec<String>) {
    let s = &case.solver;
    let criterion = match s.convergence_criterion {
        ConvergenceCriterion::Residual => kratos_name(&CRITERIA, "residual"),
        ConvergenceCriterion::Displacement => kratos_name(&CRITERIA, "displacement"),
        ConvergenceCriterion::And | ConvergenceCriterion::Or => {
            let which = if s.convergence_criterion == ConvergenceCriterion::And { "and" } else { "or" };
            notes.push(format!(
                "solver.convergence_criterion: \"{which}\" approximated by Kratos' residual_criterion (its MPM solver has residual_criterion and displacement_criterion)"
            ));
            kratos_name(&CRITERIA, "residual")
        }
    };
    solver["convergence_criterion"] = json!(criterion);
    solver["residual_relative_tolerance"] = json!(s.residual_relative_tolerance);
    solver["residual_absolute_tolerance"] = json!(s.residual_absolute_tolerance);
    solver["displacement_relative_tolerance"] = json!(s.displacement_relative_tolerance);
    solver["displacement_absolute_tolerance"] = json!(s.displacement_absolute_tolerance);
    solver["max_iteration"] = json!(s.max_iterations);
    if s.hold_grid_boundaries && case.analysis.kind == AnalysisType::Dynamic {
        notes.push(
            "solver.hold_grid_boundaries: true has no Kratos counterpart: Kratos keeps the projected velocity and acceleration of fixed grid nodes (Loam's false), so dynamic answers differ by design".into(),
        );
    }
}

/// The Kratos name of Loam's `loam` in the importer's `table` of (Kratos, Loam) names.
fn kratos_name(table: &[(&'static str, &str)], loam: &str) -> &'static str {
    table.iter().find(|t| t.1 == loam).map(|t| t.0).expect("every Loam name has its Kratos name in the table")
}

/// The dynamic scheme. Kratos' MPM schemes are its Bossak scheme (`ResidualBasedBossakDisplacementScheme`)
/// with β = (1 − α)² β_N, γ = ½ − α from `damp_factor_m` α and `newmark_beta` β_N, which it
/// admits as 0.25 only among implicit values (0.167 is not 1/6): Newmark is α = 0, so Loam's
/// Newmark must be the average acceleration (β = ¼, γ = ½), and Loam's Bossak (β = (1 − α)²/4,
/// γ = ½ − α) is written with β_N = 0.25.
fn scheme(scheme: TimeScheme, solver: &mut Value) -> Result<(), ExportError> {
    match scheme {
        TimeScheme::Newmark { beta, gamma } => {
            if (beta - 0.25).abs() > 1e-12 || (gamma - 0.5).abs() > 1e-12 {
                return Err(ExportError(format!(
                    "analysis.scheme.newmark: beta {beta}, gamma {gamma}: Kratos' implicit MPM Newmark is the average acceleration scheme (beta 0.25, gamma 0.5)"
                )));
            }
            solver["scheme_type"] = json!("newmark");
            solver["newmark_beta"] = json!(0.25);
        }
        TimeScheme::Bossak { alpha } => {
            solver["scheme_type"] = json!("bossak");
            solver["damp_factor_m"] = json!(alpha);
            solver["newmark_beta"] = json!(0.25);
        }
        TimeScheme::Static => {}
    }
    Ok(())
}
