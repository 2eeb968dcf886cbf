//! What Kratos' MPM cannot express is refused (one line naming the JSON path), what it only
//! approximates or leaves out is noted, one line per key.

use serde_json::Value;

use super::ExportError;
use crate::case::{Case, DomainKind, LoadSpec, MonitorSpec, Quadrature, DEFAULT_GHOST_PENALTY};
use loam_fem::formulation::Formulation;

/// A name that becomes part of a Kratos sub model part name (`Begin SubModelPart NAME`, and
/// `Background_Grid.NAME` in processes) must be one word of letters, digits and `_`.
fn check_kratos_name(loc: &str, name: &str) -> Result<(), ExportError> {
    if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        Ok(())
    } else {
        Err(ExportError(format!("{loc}: \"{name}\" names a Kratos sub model part: use letters, digits and _ only")))
    }
}

/// Refuses what Kratos' MPM cannot express and notes what it only approximates or leaves
/// out, one line per key with its JSON path: the model (domains, regions, monitors' names),
/// the conditions and loads, the analysis and solver settings.
pub(super) fn refuse_unexpressed(case: &Case, raw: &Value, notes: &mut Vec<String>) -> Result<(), ExportError> {
    model(case, raw, notes)?;
    conditions(case, raw, notes)?;
    settings(raw, notes)
}

/// An error at `loc`.
fn refuse(loc: String, why: &str) -> Result<(), ExportError> {
    Err(ExportError(format!("{loc}: {why}")))
}

/// Interfaces, names, and the domains' keys.
fn model(case: &Case, raw: &Value, notes: &mut Vec<String>) -> Result<(), ExportError> {
    if !case.interfaces.is_empty() {
        return refuse(
            "interfaces".into(),
            "soil–structure interfaces are not exported (Kratos' MPM case has no structure)",
        );
    }
    for name in case.regions.keys() {
        check_kratos_name(&format!("regions.{name}"), name)?;
    }
    for (k, m) in case.monitors.iter().enumerate() {
        if matches!(m, MonitorSpec::Displacement { .. }) {
            check_kratos_name(&format!("monitors[{k}].name"), m.name())?;
        }
    }
    for (k, d) in case.domains.iter().enumerate() {
        let loc = format!("domains[{k}]");
        check_kratos_name(&format!("{loc}.name"), &d.name)?;
        if d.kind != DomainKind::Mpm {
            return refuse(
                format!("{loc}.type"),
                &format!(
                    "{} domains are not exported (a Kratos MPM case holds material points and a grid)",
                    d.kind.as_str()
                ),
            );
        }
        let given = |key: &str| raw["domains"][k].get(key).is_some();
        if given("initial_velocity") {
            return refuse(format!("{loc}.initial_velocity"), "initial velocities are not exported");
        }
        if given("initial_stress") {
            return refuse(format!("{loc}.initial_stress"), "initial stresses are not exported");
        }
        if d.pic_fraction != 0.0 || d.pic_relaxation_time.is_some() {
            return refuse(
                format!("{loc}.pic_fraction"),
                "Kratos' implicit MPM has no PIC blend of the point velocities",
            );
        }
        if d.quadrature != Quadrature::MaterialPoints {
            return refuse(
                format!("{loc}.quadrature"),
                "Kratos integrates over the material points' volumes (material_points)",
            );
        }
        if d.element_formulation != case.domains[0].element_formulation {
            return refuse(
                format!("{loc}.element_formulation"),
                "the bodies' element_formulation must be one (Kratos' solver settings)",
            );
        }
        let alpha = d.ghost_penalty.unwrap_or(match case.analysis.kind {
            crate::case::AnalysisType::Dynamic => 0.0,
            _ => DEFAULT_GHOST_PENALTY,
        });
        if alpha > 0.0 {
            notes.push(format!(
                "{loc}.ghost_penalty: {alpha} left out (Kratos has no ghost penalty; it acts only on cells the material cuts)"
            ));
        }
    }
    Ok(())
}

/// Boundary conditions and loads.
fn conditions(case: &Case, raw: &Value, notes: &mut Vec<String>) -> Result<(), ExportError> {
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        let loc = format!("boundary_conditions[{k}]");
        let given = |key: &str| raw["boundary_conditions"][k].get(key).is_some();
        if bc.penalty.is_some() {
            return refuse(
                format!("{loc}.penalty"),
                "penalty walls are not exported (Kratos places its boundary particles on grid condition lines)",
            );
        }
        if given("amplitude") {
            return refuse(
                format!("{loc}.amplitude"),
                "time functions are not exported (Kratos processes over [0, End])",
            );
        }
        if let Some(s) = &bc.slip {
            if s.friction != 0.0 {
                return refuse(format!("{loc}.slip.friction"), "friction on slip boundaries is not exported");
            }
            if s.normal.is_some() {
                notes.push(format!(
                    "{loc}.slip.normal: approximated by the normals Kratos computes from the region's boundary facets"
                ));
            }
        }
    }
    for (k, l) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        if raw["loads"][k].get("amplitude").is_some() {
            return refuse(
                format!("{loc}.amplitude"),
                "time functions are not exported (Kratos processes over [0, End])",
            );
        }
        match l {
            LoadSpec::Pressure { .. } => {
                return refuse(
                    format!("{loc}.type"),
                    "pressure loads are not exported (Kratos' LINE_LOAD is a fixed vector)",
                )
            }
            LoadSpec::MaterialPointForce { .. } => {
                return refuse(format!("{loc}.type"), "material point forces are not exported")
            }
            LoadSpec::Traction { .. } if case.formulation.dim() == 3 => {
                return refuse(
                    format!("{loc}.type"),
                    "tractions on 3D grids are not exported (SURFACE_LOAD is not imported back)",
                )
            }
            LoadSpec::NodalForce { .. } if case.formulation == Formulation::Axisymmetric => {
                return refuse(format!("{loc}.type"), "nodal forces in axisymmetric cases are not exported")
            }
            _ => {}
        }
    }
    Ok(())
}

/// Gravity, analysis, solver and the case's own settings.
fn settings(raw: &Value, notes: &mut Vec<String>) -> Result<(), ExportError> {
    if let Some(g) = raw.get("gravity") {
        if g.get("amplitude").is_some() {
            return refuse("gravity.amplitude".into(), "time functions are not exported (Kratos' gravity is constant)");
        }
    }
    let analysis = &raw["analysis"];
    for key in ["adaptive", "stop_at_rest"] {
        if analysis.get(key).is_some() {
            return refuse(format!("analysis.{key}"), "Kratos steps with a fixed time step to the end");
        }
    }
    for key in ["max_step_cuts", "checkpoint"] {
        if analysis.get(key).is_some() {
            notes.push(format!("analysis.{key}: left out (no Kratos counterpart)"));
        }
    }
    let taken = [
        "convergence_criterion",
        "residual_relative_tolerance",
        "residual_absolute_tolerance",
        "displacement_relative_tolerance",
        "displacement_absolute_tolerance",
        "max_iterations",
    ];
    if let Some(s) = raw.get("solver").and_then(Value::as_object) {
        for key in s.keys().filter(|k| !taken.contains(&k.as_str())) {
            notes.push(format!("solver.{key}: left out (Kratos: Newton with the sparse_lu direct solver)"));
        }
    }
    for key in ["output", "fmu", "limits"] {
        if raw.get(key).is_some() {
            notes.push(format!("{key}: left out (Loam's own settings)"));
        }
    }
    Ok(())
}
