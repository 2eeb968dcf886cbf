//! Kratos' `ProjectParameters.json` of an MPM analysis (`MpmAnalysis` stage) to Loam's
//! analysis, solver, gravity, boundary conditions and loads.
//!
//! `problem_data` gives the time span, `solver_settings` the solver (Kratos' `MPMSolver`:
//! static, quasi-static or implicit dynamic with a Newmark or Bossak scheme, Newton with a
//! residual or displacement criterion) and the file names, `processes` the processes by list.
//! The processes read are: `assign_vector_variable_process` on `DISPLACEMENT` (grid Dirichlet
//! conditions), `assign_gravity_to_material_point_process`,
//! `assign_vector_by_direction_to_condition_process` on `LINE_LOAD` and `POINT_LOAD` (grid
//! conditions), `apply_mpm_slip_boundary_process` and
//! `apply_mpm_particle_dirichlet_condition_process` (penalty, Chandra et al. 2021). Kratos'
//! result checks and output processes are reported and left out; any other process is
//! refused if it is a constraint or load, otherwise reported as ignored.

use serde_json::{json, Map, Value};

use super::json::{ImportError, Section};

/// A condition on a sub model part of the grid (the name without `Background_Grid.`).
#[derive(Debug, Clone, PartialEq)]
pub enum Condition {
    /// Prescribed displacement.
    Displacement {
        /// Grid sub model part.
        part: String,
        /// Value per component, `None` where not constrained.
        value: [Option<f64>; 3],
    },
    /// Frictionless slip on the grid nodes.
    Slip {
        /// Grid sub model part.
        part: String,
    },
    /// Force per unit length on the condition lines (`LINE_LOAD`).
    LineLoad {
        /// Grid sub model part.
        part: String,
        /// N/m.
        load: [f64; 3],
    },
    /// Force on every node (`POINT_LOAD`).
    PointLoad {
        /// Grid sub model part.
        part: String,
        /// N.
        force: [f64; 3],
    },
    /// Penalty Dirichlet condition on boundary particles along the condition lines.
    Penalty {
        /// Grid sub model part holding the condition lines.
        part: String,
        /// `material_points_per_condition`.
        points_per_condition: usize,
        /// `penalty_coefficient`.
        penalty: f64,
    },
}

/// What `ProjectParameters.json` says, in Loam's terms.
#[derive(Debug, Clone)]
pub struct Project {
    /// `problem_data.problem_name`.
    pub name: String,
    /// Body, grid and materials file names (as Kratos resolves them: `.mdpa` appended).
    pub body_file: String,
    /// Grid `.mdpa`.
    pub grid_file: String,
    /// Materials JSON.
    pub materials_file: String,
    /// 2 or 3.
    pub domain_size: usize,
    /// `axis_symmetric_flag`.
    pub axisymmetric: bool,
    /// `pressure_dofs` (mixed u–p elements).
    pub pressure_dofs: bool,
    /// Loam `analysis`.
    pub analysis: Value,
    /// Loam `solver`.
    pub solver: Value,
    /// Gravity acceleration vector, if any.
    pub gravity: Option<[f64; 3]>,
    /// Grid conditions in file order.
    pub conditions: Vec<Condition>,
}

/// Kratos' MPM solver types (the names its solver wrapper accepts; the first is the one
/// `loam export kratos` writes) and Loam's `analysis.type`.
pub const SOLVER_TYPES: [(&[&str], &str); 3] = [
    (&["Static", "static"], "static"),
    (&["Quasi-static", "quasi_static", "QuasiStatic"], "quasi_static"),
    (&["Dynamic", "dynamic"], "dynamic"),
];

/// Kratos' convergence criteria and Loam's `solver.convergence_criterion` (Kratos' MPM solver
/// builds the first two; the combined ones are StructuralMechanics' names).
pub const CRITERIA: [(&str, &str); 4] = [
    ("residual_criterion", "residual"),
    ("displacement_criterion", "displacement"),
    ("and_criterion", "and"),
    ("or_criterion", "or"),
];

/// Reads `ProjectParameters.json` (text `text`, named `file`); notes collect what is not taken over.
pub fn read(text: &str, file: &str, notes: &mut Vec<String>) -> Result<Project, ImportError> {
    let root = super::json::parse_json(text, file)?;
    let top = Section::root(&root, file)?;

    let pd = top.object("problem_data")?;
    let name = pd.optional_string("problem_name")?.unwrap_or_else(|| "kratos".into());
    let start = pd.optional_number("start_time")?.unwrap_or(0.0);
    let end = pd.number("end_time")?;
    pd.ignore("parallel_type", "Loam picks its threads with loam run --threads", notes);
    pd.ignore("echo_level", "verbosity", notes);
    pd.finish(notes);

    let s = top.object("solver_settings")?;
    s.take("model_part_name");
    let domain_size = s.optional_number("domain_size")?.unwrap_or(2.0) as usize;
    if domain_size != 2 && domain_size != 3 {
        return Err(s.error("domain_size", format!("{domain_size}: Kratos MPM cases are 2 or 3")));
    }
    s.ignore("echo_level", "verbosity", notes);
    if let Some(a) = s.optional_string("analysis_type")? {
        if a == "linear" {
            notes.push(s.note("analysis_type", "\"linear\" approximated: Loam solves the nonlinear problem by Newton"));
        }
    }
    let body_file = mdpa_file(&s, "model_import_settings", notes)?;
    let grid_file = mdpa_file(&s, "grid_model_import_settings", notes)?;
    let materials_file = s.object("material_import_settings")?.string("materials_filename")?;
    let (analysis, solver) = analysis_and_solver(&pd, &s, start, end, notes)?;
    s.take("problem_domain_sub_model_part_list");
    s.take("processes_sub_model_part_list");
    let pressure_dofs = s.optional_bool("pressure_dofs")?.unwrap_or(false);
    if s.optional_bool("consistent_mass_matrix")? == Some(true) {
        notes.push(s.note(
            "consistent_mass_matrix",
            "true approximated by a lumped grid mass (Loam's MPM lumps it: mass_matrix \"lumped\")",
        ));
    }
    let axisymmetric = s.optional_bool("axis_symmetric_flag")?.unwrap_or(false);
    s.ignore("auxiliary_variables_list", "Loam computes what it needs", notes);
    s.ignore("linear_solver_settings", "Loam's direct solvers: solver.linear_solver auto", notes);
    s.ignore("compute_reactions", "Loam always computes reactions", notes);
    s.finish(notes);

    let mut gravity = None;
    let mut conditions = Vec::new();
    if let Some(procs) = top.optional_object("processes")? {
        let lists: Vec<String> = procs_keys(&root);
        for list in lists {
            let items = procs.array(&list)?;
            for (k, item) in items.iter().enumerate() {
                let p = procs.child_at(item, &format!("{list}[{k}]"))?;
                process(&p, &list, &mut gravity, &mut conditions, notes)?;
            }
        }
        procs.finish(notes);
    }
    for key in ["output_processes", "print_output_process", "analysis_stage", "modelers"] {
        top.ignore(key, "Loam writes its own output (docs/cli.md)", notes);
    }
    top.finish(notes);
    Ok(Project {
        name,
        body_file,
        grid_file,
        materials_file,
        domain_size,
        axisymmetric,
        pressure_dofs,
        analysis,
        solver,
        gravity,
        conditions,
    })
}

/// The Loam `analysis` and `solver` of a Kratos solver's `solver_settings` `s` (`solver_type`,
/// `time_stepping`, scheme, convergence criterion, tolerances, `max_iteration`; the same keys
/// in Kratos' MPM and StructuralMechanics solvers) over `problem_data` `pd` from `start` to `end`.
pub(crate) fn analysis_and_solver(
    pd: &Section,
    s: &Section,
    start: f64,
    end: f64,
    notes: &mut Vec<String>,
) -> Result<(Value, Value), ImportError> {
    let solver_type = s.string("solver_type")?;
    let dt = s.object("time_stepping")?.number("time_step")?;
    if dt <= 0.0 {
        return Err(s.error("time_stepping.time_step", format!("must be positive, got {dt}")));
    }
    // Kratos' loop: while t < end_time: t += Δt
    let (mut t, mut steps) = (start, 0usize);
    while t < end && steps <= 10_000_000 {
        t += dt;
        steps += 1;
    }
    let loam_end = steps as f64 * dt;
    if (loam_end - (end - start)).abs() > 1e-9 * dt {
        notes.push(pd.note(
            "end_time",
            format!("{end} approximated by {steps} steps of {dt}: Kratos steps while t < end_time, so it ends at {loam_end}"),
        ));
    }
    if start != 0.0 {
        notes.push(pd.note("start_time", format!("{start}: Loam's time starts at 0 (times shifted)")));
    }
    let mut analysis = Map::new();
    let kind = SOLVER_TYPES.iter().find(|(kratos, _)| kratos.contains(&solver_type.as_str())).map(|t| t.1).ok_or_else(
        || {
            s.error(
                "solver_type",
                format!("\"{solver_type}\" is not a Kratos solver type Loam imports (Static, Quasi-static, Dynamic)"),
            )
        },
    )?;
    analysis.insert("type".into(), json!(kind));
    analysis.insert("time_step".into(), json!(dt));
    analysis.insert("end_time".into(), json!(loam_end));
    if let Some(m) = s.optional_string("time_integration_method")? {
        if m != "implicit" {
            return Err(s.error("time_integration_method", format!("\"{m}\": Loam is implicit only")));
        }
    }
    let scheme = s.optional_string("scheme_type")?;
    let beta = s.optional_number("newmark_beta")?;
    let gamma = s.optional_number("newmark_gamma")?;
    let alpha = s.optional_number("damp_factor_m")?;
    if kind != "static" {
        let sch = match scheme.as_deref().unwrap_or("newmark") {
            "newmark" => json!({ "newmark": { "beta": beta.unwrap_or(0.25), "gamma": gamma.unwrap_or(0.5) } }),
            "bossak" => json!({ "bossak": { "alpha": alpha.unwrap_or(-0.3) } }),
            other => return Err(s.error("scheme_type", format!("\"{other}\": Loam has newmark and bossak"))),
        };
        if kind == "dynamic" {
            analysis.insert("scheme".into(), sch);
        }
    } else if scheme.is_some() {
        notes.push(s.note("scheme_type", "ignored (static analysis)"));
    }

    let mut solver = Map::new();
    if let Some(c) = s.optional_string("convergence_criterion")? {
        let loam = CRITERIA
            .iter()
            .find(|(kratos, _)| *kratos == c)
            .map(|t| t.1)
            .ok_or_else(|| s.error("convergence_criterion", format!("\"{c}\" has no Loam counterpart")))?;
        solver.insert("convergence_criterion".into(), json!(loam));
    }
    for key in [
        "displacement_relative_tolerance",
        "displacement_absolute_tolerance",
        "residual_relative_tolerance",
        "residual_absolute_tolerance",
    ] {
        if let Some(v) = s.optional_number(key)? {
            solver.insert(key.into(), json!(v));
        }
    }
    if let Some(n) = s.optional_number("max_iteration")? {
        solver.insert("max_iterations".into(), json!(n as usize));
    }
    if kind == "dynamic" {
        // Kratos keeps the projected velocity and acceleration of fixed grid nodes
        solver.insert("hold_grid_boundaries".into(), json!(false));
    }
    Ok((Value::Object(analysis), Value::Object(solver)))
}

/// The `.mdpa` file named by the import settings at `key`.
pub(crate) fn mdpa_file(s: &Section, key: &str, notes: &mut Vec<String>) -> Result<String, ImportError> {
    let m = s.object(key)?;
    if let Some(t) = m.optional_string("input_type")? {
        if t != "mdpa" {
            return Err(m.error("input_type", format!("\"{t}\": only mdpa input is imported")));
        }
    }
    let f = m.string("input_filename")?;
    m.finish(notes);
    Ok(format!("{f}.mdpa"))
}

fn procs_keys(root: &Value) -> Vec<String> {
    root.get("processes").and_then(Value::as_object).map(|m| m.keys().cloned().collect()).unwrap_or_default()
}

/// The sub model part of a grid process (`Background_Grid.NAME` → `NAME`).
fn grid_part(p: &Section, q: &Section) -> Result<String, ImportError> {
    let name = q.string("model_part_name")?;
    name.strip_prefix("Background_Grid.").map(str::to_string).ok_or_else(|| {
        p.error("Parameters.model_part_name", format!("\"{name}\": expected a sub model part of Background_Grid"))
    })
}

/// A vector of three numbers at `key`.
pub(crate) fn vector(q: &Section, key: &str) -> Result<[f64; 3], ImportError> {
    let v = q.take(key).ok_or_else(|| q.error(key, "missing"))?;
    let a = v.as_array().filter(|a| a.len() == 3).ok_or_else(|| q.error(key, "must be an array of three numbers"))?;
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| q.error(key, "must be an array of three numbers"))?;
    }
    Ok(out)
}

/// The parameters of an `assign_vector_variable_process` on `DISPLACEMENT` (any other
/// variable refused): the prescribed value per component, `None` where not `constrained`,
/// over the whole analysis.
pub(super) fn prescribed_displacement(q: &Section) -> Result<[Option<f64>; 3], ImportError> {
    let var = q.string("variable_name")?;
    if var != "DISPLACEMENT" {
        return Err(q.error("variable_name", format!("\"{var}\": only DISPLACEMENT is imported")));
    }
    let value = vector(q, "value")?;
    let fixed = match q.take("constrained") {
        None => [true; 3],
        Some(v) => {
            let a = v.as_array().filter(|a| a.len() == 3 && a.iter().all(Value::is_boolean));
            let a = a.ok_or_else(|| q.error("constrained", "must be three booleans"))?;
            [a[0] == true, a[1] == true, a[2] == true]
        }
    };
    whole_interval(q)?;
    Ok([0, 1, 2].map(|d| fixed[d].then_some(value[d])))
}

/// `modulus` times the unit vector along `direction`.
pub(crate) fn by_direction(q: &Section) -> Result<[f64; 3], ImportError> {
    let m = q.number("modulus")?;
    let d = vector(q, "direction")?;
    let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n == 0.0 {
        return Err(q.error("direction", "must not be zero"));
    }
    Ok(d.map(|x| m * x / n))
}

/// Only the whole analysis (`[0.0, "End"]`) is imported as a time interval.
pub(crate) fn whole_interval(q: &Section) -> Result<(), ImportError> {
    match q.take("interval") {
        None => Ok(()),
        Some(v) if v.get(0).and_then(Value::as_f64) == Some(0.0) && v.get(1).and_then(Value::as_str) == Some("End") => {
            Ok(())
        }
        Some(v) => Err(q.error(
            "interval",
            format!("{v}: only [0.0, \"End\"] is imported (Loam amplitudes could express it: not yet)"),
        )),
    }
}

fn process(
    p: &Section,
    list: &str,
    gravity: &mut Option<[f64; 3]>,
    conditions: &mut Vec<Condition>,
    notes: &mut Vec<String>,
) -> Result<(), ImportError> {
    let module = p.optional_string("python_module")?.unwrap_or_default();
    p.take("kratos_module");
    p.take("process_name");
    p.take("help");
    let check_or_output = [
        "from_json_check_result_process",
        "mpm_from_json_check_result_process",
        "json_output_process",
        "mpm_json_output_process",
        "vtk_output_process",
        "mpm_vtk_output_process",
        "gid_output_process",
        "mpm_gid_output_process",
        "particle_mpm_gid_output_process",
        "mpm_point_output_process",
        "mpm_multiple_points_output_process",
        "mpm_grid_conforming_reaction_output_process",
        "compute_nodal_normals_process",
        "particle_from_json_check_result_process",
        "particle_json_output_process",
    ];
    // the MPM side of a partitioned MPM–FEM co-simulation (Kratos' mpm_dirichlet_wrapper and
    // mpm_neumann_wrapper): the structure's displacement imposed on, or its load taken from, an
    // interface of the grid
    let coupling = [
        "apply_mpm_coupling_interface_dirichlet_condition_process",
        "apply_mpm_coupling_interface_neumann_condition_process",
    ];
    if coupling.contains(&module.as_str()) {
        p.take("Parameters");
        notes.push(p.note(
            "",
            format!(
                "{module}: the co-simulation's interface condition, replaced by the monolithic tie \
                 (interfaces[].coupling \"tie\") when the CoSimulation folder is imported; alone: ignored"
            ),
        ));
        p.finish(notes);
        return Ok(());
    }
    if check_or_output.contains(&module.as_str()) {
        p.take("Parameters");
        notes.push(
            p.note("", format!("{module}: ignored (Kratos output or result check; Loam writes monitors.csv and VTK)")),
        );
        p.finish(notes);
        return Ok(());
    }
    let q = p.object("Parameters")?;
    match module.as_str() {
        "assign_vector_variable_process" => {
            let value = prescribed_displacement(&q)?;
            let part = grid_part(p, &q)?;
            conditions.push(Condition::Displacement { part, value });
        }
        // `assign_gravity_to_particle_process`: the name before Kratos 10
        "assign_gravity_to_material_point_process" | "assign_gravity_to_particle_process" => {
            if let Some(v) = q.optional_string("variable_name")? {
                if v != "MP_VOLUME_ACCELERATION" {
                    return Err(q.error("variable_name", format!("\"{v}\": expected MP_VOLUME_ACCELERATION")));
                }
            }
            q.take("model_part_name");
            *gravity = Some(by_direction(&q)?);
        }
        "assign_vector_by_direction_to_condition_process" => {
            let var = q.string("variable_name")?;
            let part = grid_part(p, &q)?;
            let v = by_direction(&q)?;
            whole_interval(&q)?;
            conditions.push(match var.as_str() {
                "LINE_LOAD" => Condition::LineLoad { part, load: v },
                "POINT_LOAD" => Condition::PointLoad { part, force: v },
                other => {
                    return Err(q.error("variable_name", format!("\"{other}\": LINE_LOAD and POINT_LOAD are imported")))
                }
            });
        }
        "apply_mpm_slip_boundary_process" => {
            let part = grid_part(p, &q)?;
            conditions.push(Condition::Slip { part });
        }
        "apply_mpm_particle_dirichlet_condition_process" => {
            let part = grid_part(p, &q)?;
            let n = q.optional_number("material_points_per_condition")?.unwrap_or(1.0) as usize;
            let penalty = q.number("penalty_coefficient")?;
            if let Some(c) = q.optional_string("constrained")? {
                if c != "fixed" {
                    return Err(q.error("constrained", format!("\"{c}\": only \"fixed\" (no-slip) is imported")));
                }
            }
            whole_interval(&q)?;
            conditions.push(Condition::Penalty { part, points_per_condition: n.max(1), penalty });
        }
        other if list == "constraints_process_list" || list == "loads_process_list" || list == "gravity" => {
            return Err(p.error(
                "python_module",
                format!("\"{other}\": this Kratos process has no Loam counterpart in the importer"),
            ));
        }
        other => {
            q.finish(&mut Vec::new());
            notes.push(
                p.note("", format!("{other}: ignored (unknown process; whatever it does is missing from the case)")),
            );
            p.finish(notes);
            return Ok(());
        }
    }
    q.finish(notes);
    p.finish(notes);
    Ok(())
}
