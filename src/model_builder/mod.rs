//! From a parsed [`Case`] to a solvable [`Model`], with every consistency check that needs
//! more than the JSON schema (empty regions, missing materials, inverted elements, wrong
//! vector lengths, grids that do not conform to an interface). One concern per module, in
//! the order [`build_model`] takes them:
//!
//! 1. `settings`: analysis, solver and output settings, the time scheme;
//! 2. `meshes`: FEM meshes, background grids with their bodies of material points, the
//!    interfaces that attach grids to structures, and the one global node set with its node
//!    roles;
//! 3. `regions`: named node sets;
//! 4. `conditions`: boundary conditions, penalty walls, the grids' attachment to their
//!    structures (`interfaces`), loads and gravity;
//! 5. `monitors` and `fmu_variables`.

mod conditions;
mod fmu_variables;
mod interfaces;
mod meshes;
mod monitors;
mod regions;
mod settings;
mod walls;

use std::collections::BTreeMap;
use std::sync::Arc;

use loam_coupling::interface::InterfaceSummary;
use loam_fem::model::Model;
use loam_laws::ConstitutiveLaw;

use crate::case::{Case, CaseError, Component};
use crate::monitor::Monitor;

pub use meshes::RigidSummary;
pub(crate) use meshes::{body_points, build_mesh, structured_grid};
pub use monitors::monitor_unit;
pub use regions::nearest_node;
pub(crate) use regions::{line_tolerance, select_region};

/// A model ready to run, with the monitors resolved to nodes and regions.
pub struct BuiltModel {
    /// The model.
    pub model: Model,
    /// Monitors in case-file order.
    pub monitors: Vec<Monitor>,
    /// Node sets of the regions (global ids).
    pub regions: BTreeMap<String, Vec<usize>>,
    /// Named inputs (`fmu.inputs`), resolved to their targets in the model.
    pub inputs: Vec<ModelInput>,
    /// Named outputs (`fmu.outputs`, or every monitor), resolved to monitors.
    pub outputs: Vec<ModelOutput>,
    /// The interfaces between soil and structures, as `loam check` reports them.
    pub interfaces: Vec<InterfaceSummary>,
    /// The rigid domains, as `loam check` reports them.
    pub rigid_bodies: Vec<RigidSummary>,
}

/// Where an input acts in the [`Model`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputSlot {
    /// `model.loads[i]`.
    Load(usize),
    /// `model.constraints[i]`.
    Constraint(usize),
    /// `model.gravity`.
    Gravity,
}

/// A named input resolved to its target.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInput {
    /// Variable name.
    pub name: String,
    /// The amplitude it replaces.
    pub slot: InputSlot,
    /// Unit (`1` for a factor).
    pub unit: String,
    /// Start value (FMI `start`).
    pub start: f64,
    /// Description.
    pub description: String,
}

/// A named output resolved to a monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelOutput {
    /// Variable name.
    pub name: String,
    /// Index into the monitors.
    pub monitor: usize,
    /// Unit.
    pub unit: String,
    /// Description.
    pub description: String,
}

/// Builds the model of `case` (see the module doc for the order of the steps).
pub fn build_model(case: &Case) -> Result<BuiltModel, CaseError> {
    // contact walls are rigid structures from here on
    let with_walls = walls::as_rigid_structures(case)?;
    let case = with_walls.as_ref().unwrap_or(case);
    let dim = case.formulation.dim();
    let scheme = settings::check(case)?;
    check_output_names(case)?;
    let laws = materials(case)?;
    let discretisation = meshes::discretise(case, &laws)?;
    let mut model = Model::new(dim, discretisation.coords.clone(), scheme, case.solver);
    model.petsc_options = case.petsc_options.clone();
    model.roles.clone_from(&discretisation.roles);
    let regions = regions::select_all(case, &model.coords, &discretisation.groups)?;
    let mut parts = discretisation.parts;
    let ties = discretisation.ties;
    meshes::assign_pressure_dofs(case, &mut model, &mut parts);
    let bcs = conditions::boundary_conditions(case, &mut model, &regions, &mut parts)?;
    conditions::check_supported(case, &model)?;
    interfaces::attach(case, &mut model, &mut parts)?;
    let motions = meshes::place_domains(case, &mut model, parts)?;
    model.domains.extend(ties.into_iter().map(|t| Box::new(t) as Box<dyn loam_fem::domain::Domain>));
    let load_of_load = conditions::loads(case, &mut model, &regions)?;
    conditions::gravity(case, &mut model)?;
    let monitors = monitors::build(case, &model, &regions, &discretisation.interfaces, &discretisation.rigid_frames)?;
    let (inputs, outputs) = fmu_variables::resolve(case, &bcs, &load_of_load, &motions, &monitors)?;
    let interfaces = discretisation.interfaces.iter().map(|i| i.summary.clone()).collect();
    let rigid_bodies = discretisation.rigid_bodies.clone();
    Ok(BuiltModel { model, monitors, regions, inputs, outputs, interfaces, rigid_bodies })
}

/// The laws of the case's materials, checked.
fn materials(case: &Case) -> Result<BTreeMap<&str, Arc<dyn ConstitutiveLaw>>, CaseError> {
    let mut laws: BTreeMap<&str, Arc<dyn ConstitutiveLaw>> = BTreeMap::new();
    for (name, spec) in &case.materials {
        let law = spec.build().map_err(|e| {
            // a sign error gets an example of the parameter, as check_positive gives
            let example = crate::hints::example_value(e.parameter);
            let problem = match (e.problem.strip_prefix("must be > 0, got "), example) {
                (Some(got), Some(example)) => format!("must be > 0, e.g. {example}, got {got}"),
                _ => e.problem,
            };
            CaseError::new(format!("materials.{name}.{}", e.parameter), problem)
        })?;
        laws.insert(name, Arc::from(law));
    }
    Ok(laws)
}

/// Longest name that becomes a file name, in bytes (file systems allow 255; the step
/// number and suffix take up to 18).
const MAX_FILE_NAME_BYTES: usize = 100;

/// A name that becomes an output file name (`<name>.pvd`, `<name>_<step>.vtu`): domains,
/// bodies, penalty walls. Refused (issue 16) if it could write outside the output directory
/// or hide its files: empty, starting with `.`, ending with `.` or a space, longer than
/// [`MAX_FILE_NAME_BYTES`], with a path separator, control character or one of
/// `<>:"|?*` (not allowed in Windows file names), or ending in `_grid` (the suffix of the
/// background grids' output, which `loam plot` recognises).
fn check_file_name(location: &str, name: &str) -> Result<(), CaseError> {
    let problem = if name.is_empty() {
        Some("must not be empty")
    } else if name.starts_with('.') {
        Some("must not start with '.'")
    } else if name.ends_with('.') || name.ends_with(' ') || name.starts_with(' ') {
        Some("must not start with a space or end with '.' or a space")
    } else if name.len() > MAX_FILE_NAME_BYTES {
        Some("is too long (at most 100 bytes)")
    } else if name.chars().any(|c| c.is_control() || "/\\<>:\"|?*".contains(c)) {
        Some("must not contain / \\ < > : \" | ? * or control characters")
    } else if name.ends_with("_grid") {
        Some("must not end in '_grid' (the suffix of the background grids' output)")
    } else {
        None
    };
    match problem {
        Some(p) => Err(CaseError::new(location, format!("{name:?} names output files ({name}.pvd): it {p}"))),
        None => Ok(()),
    }
}

/// The names of the case's output series (domains, bodies, penalty walls, ties; with
/// `output.grid` also `<domain>_grid`) must be valid file names ([`check_file_name`]) and
/// distinct even where case does not count (`Soil` and `soil` are one file on Windows
/// and macOS).
fn check_output_names(case: &Case) -> Result<(), CaseError> {
    let mut seen: BTreeMap<String, String> = BTreeMap::new();
    let mut add = |loc: String, name: &str| -> Result<(), CaseError> {
        check_file_name(&loc, name)?;
        if let Some(first) = seen.insert(name.to_lowercase(), loc.clone()) {
            return Err(CaseError::new(
                loc,
                format!("{name:?} names the same output files as {first} (names must differ in more than case)"),
            ));
        }
        Ok(())
    };
    for (k, d) in case.domains.iter().enumerate() {
        add(format!("domains[{k}].name"), &d.name)?;
    }
    for (k, interface) in case.interfaces.iter().enumerate() {
        if interface.coupling.is_non_conforming() {
            add(format!("interfaces[{k}].name"), &interface.name)?;
        }
    }
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        if bc.penalty.is_some() && !bc.as_rigid_wall {
            match &bc.name {
                Some(name) => add(format!("boundary_conditions[{k}].name"), name)?,
                None => add(format!("boundary_conditions[{k}]"), &format!("penalty_{k}"))?,
            }
        }
    }
    Ok(())
}

/// Whether a count `n` estimated in floating point (possibly infinite or NaN after an
/// overflow) is at most `limit`.
fn within(n: f64, limit: usize) -> bool {
    n.is_finite() && n <= limit as f64
}

/// The last key of the JSON path `location` (`cells` of `domains[0].grid.cells`).
fn last_key(location: &str) -> &str {
    let key = location.rsplit('.').next().unwrap_or(location);
    key.split('[').next().unwrap_or(key)
}

/// `value` must be finite and > 0; the message gives an example where one is known
/// ([`crate::hints::example_value`]).
fn check_positive(location: &str, value: f64) -> Result<(), CaseError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        let example =
            crate::hints::example_value(last_key(location)).map(|e| format!(", e.g. {e}")).unwrap_or_default();
        Err(CaseError::new(location, format!("must be > 0{example}, got {value}")))
    }
}

/// `v` must have one entry per coordinate (`dim`); the message says what the entries are,
/// gives an example and the value found: `expected 2 entries (whole numbers of cells per
/// direction, one per coordinate of this 2D model), e.g. [64, 24], got [64]`.
fn check_len<T: serde::Serialize>(location: &str, v: &[T], dim: usize) -> Result<(), CaseError> {
    if v.len() == dim {
        Ok(())
    } else {
        let (what, example) = crate::hints::example_vector(last_key(location), dim);
        let got = serde_json::to_string(v).unwrap_or_default().replace(',', ", ");
        Err(CaseError::new(
            location,
            format!(
                "expected {dim} entries ({what}, one per coordinate of this {dim}D model), e.g. {example}, got {got}"
            ),
        ))
    }
}

/// The message for a name that `names` (the keys of `section`, e.g. `regions`) lacks: the
/// nearest one if it looks misspelt, and those that exist.
fn unknown_name<'a>(what: &str, name: &str, section: &str, names: impl Iterator<Item = &'a str> + Clone) -> String {
    let listed: Vec<String> = names.clone().map(|n| format!("\"{n}\"")).collect();
    if listed.is_empty() {
        return format!("no {what} named '{name}': the case has no {section}");
    }
    let hint = crate::hints::did_you_mean(name, names);
    format!("no {what} named '{name}' in {section}; {hint}expected one of {}", listed.join(", "))
}

fn component_index(location: &str, c: Component, dim: usize) -> Result<Option<usize>, CaseError> {
    let i = match c {
        Component::X => 0,
        Component::Y => 1,
        Component::Z => 2,
        Component::Magnitude => return Ok(None),
    };
    if i < dim {
        Ok(Some(i))
    } else {
        Err(CaseError::new(location, format!("component z does not exist in a {dim}D model")))
    }
}
