//! The structure's `ProjectParameters` of a co-simulation (Kratos' StructuralMechanicsApplication,
//! `StructuralMechanicsAnalysis`) to a Loam FEM domain's supports and loads.
//!
//! `problem_data` and `solver_settings` are read as for an MPM case
//! ([`super::parameters::analysis_and_solver`]: `Static` or `Dynamic`, time step, Newton
//! criterion); `model_import_settings` names the structure's `.mdpa`,
//! `material_import_settings` its materials file. The processes read are
//! `assign_vector_variable_process` on `DISPLACEMENT` (supports) and
//! `assign_vector_by_direction_process` on `VOLUME_ACCELERATION` (self-weight); result checks
//! and output are reported and left out, any other constraint or load is refused.

use serde_json::Value;

use super::json::{ImportError, Section};
use super::parameters::{by_direction, mdpa_file, prescribed_displacement, whole_interval};

/// What the structure's parameters say, in Loam's terms.
#[derive(Debug, Clone)]
pub struct Structure {
    /// `solver_settings.model_part_name` (`Structure`), the prefix of its sub model parts.
    pub model_part: String,
    /// The structure's `.mdpa`.
    pub mesh_file: String,
    /// Materials JSON.
    pub materials_file: String,
    /// 2 or 3.
    pub domain_size: usize,
    /// Loam `analysis`.
    pub analysis: Value,
    /// Loam `solver`.
    pub solver: Value,
    /// Prescribed displacements: sub model part (without the prefix), value per constrained component.
    pub supports: Vec<(String, [Option<f64>; 3])>,
    /// Volume accelerations (self-weight): sub model part, acceleration vector.
    pub volume_accelerations: Vec<(String, [f64; 3])>,
}

/// Reads the structure's parameters (text `text`, named `file`); notes collect what is not taken over.
pub fn read(text: &str, file: &str, notes: &mut Vec<String>) -> Result<Structure, ImportError> {
    let root = super::json::parse_json(text, file)?;
    let top = Section::root(&root, file)?;

    let pd = top.object("problem_data")?;
    pd.take("problem_name");
    let start = pd.optional_number("start_time")?.unwrap_or(0.0);
    let end = pd.number("end_time")?;
    pd.ignore("parallel_type", "Loam picks its threads with loam run --threads", notes);
    pd.ignore("echo_level", "verbosity", notes);
    pd.finish(notes);

    let s = top.object("solver_settings")?;
    let model_part = s.optional_string("model_part_name")?.unwrap_or_else(|| "Structure".into());
    let domain_size = s.optional_number("domain_size")?.unwrap_or(2.0) as usize;
    if domain_size != 2 {
        return Err(s.error("domain_size", format!("{domain_size}: the tie of an MPM–FEM import is 2D")));
    }
    s.ignore("echo_level", "verbosity", notes);
    if let Some(a) = s.optional_string("analysis_type")? {
        if a == "linear" {
            notes.push(s.note("analysis_type", "\"linear\" approximated: Loam solves the nonlinear problem by Newton"));
        }
    }
    let mesh_file = mdpa_file(&s, "model_import_settings", notes)?;
    let materials_file = s.object("material_import_settings")?.string("materials_filename")?;
    let (analysis, solver) = super::parameters::analysis_and_solver(&pd, &s, start, end, notes)?;
    if s.optional_bool("rotation_dofs")? == Some(true) {
        return Err(s.error("rotation_dofs", "rotation degrees of freedom (shells, beams) are not imported"));
    }
    if s.optional_bool("line_search")? == Some(true) {
        notes.push(s.note("line_search", "ignored: Loam's Newton has no line search"));
    }
    s.ignore("auxiliary_variables_list", "Loam computes what it needs", notes);
    s.ignore("linear_solver_settings", "Loam's direct solvers: solver.linear_solver auto", notes);
    s.ignore("compute_reactions", "Loam always computes reactions", notes);
    s.finish(notes);

    let mut supports = Vec::new();
    let mut volume_accelerations = Vec::new();
    if let Some(procs) = top.optional_object("processes")? {
        let lists: Vec<String> = root["processes"].as_object().map(|m| m.keys().cloned().collect()).unwrap_or_default();
        for list in lists {
            for (k, item) in procs.array(&list)?.iter().enumerate() {
                let p = procs.child_at(item, &format!("{list}[{k}]"))?;
                let module = p.optional_string("python_module")?.unwrap_or_default();
                p.take("kratos_module");
                p.take("process_name");
                p.take("help");
                p.take("check");
                let part = |q: &Section| -> Result<String, ImportError> {
                    let name = q.string("model_part_name")?;
                    name.strip_prefix(&format!("{model_part}.")).map(str::to_string).ok_or_else(|| {
                        q.error("model_part_name", format!("\"{name}\": expected a sub model part of {model_part}"))
                    })
                };
                match module.as_str() {
                    "from_json_check_result_process"
                    | "json_output_process"
                    | "vtk_output_process"
                    | "gid_output_process" => {
                        p.take("Parameters");
                        notes.push(p.note(
                            "",
                            format!(
                                "{module}: ignored (Kratos output or result check; Loam writes monitors.csv and VTK)"
                            ),
                        ));
                    }
                    "assign_vector_variable_process" => {
                        let q = p.object("Parameters")?;
                        let value = prescribed_displacement(&q)?;
                        supports.push((part(&q)?, value));
                        q.finish(notes);
                    }
                    "assign_vector_by_direction_process" => {
                        let q = p.object("Parameters")?;
                        let var = q.string("variable_name")?;
                        if var != "VOLUME_ACCELERATION" {
                            return Err(
                                q.error("variable_name", format!("\"{var}\": only VOLUME_ACCELERATION is imported"))
                            );
                        }
                        let name = part(&q)?;
                        if q.optional_bool("constrained")? == Some(true) {
                            return Err(q.error("constrained", "a constrained VOLUME_ACCELERATION is not a load"));
                        }
                        let g = by_direction(&q)?;
                        whole_interval(&q)?;
                        volume_accelerations.push((name, g));
                        q.finish(notes);
                    }
                    other if list == "constraints_process_list" || list == "loads_process_list" => {
                        return Err(p.error(
                            "python_module",
                            format!("\"{other}\": this Kratos process has no Loam counterpart in the importer"),
                        ));
                    }
                    other => {
                        p.take("Parameters");
                        notes.push(p.note(
                            "",
                            format!("{other}: ignored (unknown process; whatever it does is missing from the case)"),
                        ));
                    }
                }
                p.finish(notes);
            }
        }
        procs.finish(notes);
    }
    for key in ["output_processes", "print_output_process", "analysis_stage", "modelers"] {
        top.ignore(key, "Loam writes its own output (docs/cli.md)", notes);
    }
    top.finish(notes);
    Ok(Structure {
        model_part,
        mesh_file,
        materials_file,
        domain_size,
        analysis,
        solver,
        supports,
        volume_accelerations,
    })
}
