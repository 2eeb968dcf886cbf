//! `loam export kratos CASE.json -o DIR`: a Loam MPM case as a Kratos Multiphysics MPM case
//! folder, the inverse of [`crate::import::kratos`].
//!
//! The folder holds `ProjectParameters.json` ([`parameters`]), the background grid
//! `Grid.mdpa` (its cells as `Element2D3N` … `Element3D8N`, one sub model part per condition
//! with its nodes and, for loads and slip, the grid's boundary facets in the region as
//! conditions; `grid`), the bodies `Body.mdpa` (their cells as `MPMUpdatedLagrangian…`
//! elements, one sub model part `Parts_<domain>` each; `bodies`), both written by [`mdpa`],
//! and `ParticleMaterials.json` ([`materials`]); `expressible` decides what is refused. Kratos places `MATERIAL_POINTS_PER_ELEMENT` points in each body cell at
//! the positions and with the volumes Loam gives `material_points.cells` (both codes use the
//! cell's Gauss rule); a lattice body (`disk`, `polygon`) is written as one square cell per
//! point with one point each.
//!
//! What Kratos cannot express is refused with one line naming the JSON path; what it expresses
//! only approximately, or what is left out (output settings, monitors other than a point's
//! displacement), is returned as notes, one line per key. A `displacement` monitor becomes a
//! `json_output_process` writing `DISPLACEMENT` of the grid node nearest to its point to
//! `<monitor>.json`, as Kratos' own tests write their results.

mod bodies;
mod expressible;
mod grid;
pub mod materials;
pub mod mdpa;
pub mod parameters;

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::case::{Case, CaseError, ElementFormulation};

/// Why a case could not be exported: one line naming the JSON path and the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ExportError(pub String);

impl From<CaseError> for ExportError {
    fn from(e: CaseError) -> Self {
        ExportError(e.to_string())
    }
}

/// What an export produced.
#[derive(Debug, Clone)]
pub struct Export {
    /// Files written.
    pub files: Vec<PathBuf>,
    /// One line per key approximated or left out.
    pub notes: Vec<String>,
}

/// The grid's own sub model part.
const GRID_PART: &str = "Parts_Grid";

/// Exports the case file `case_path` into the folder `dir`: the case checked (it must build,
/// and Kratos must express it), the grid with its conditions and outputs, the bodies with
/// their materials, the parameters, and the four files written.
pub fn export(case_path: &Path, dir: &Path) -> Result<Export, ExportError> {
    let case = Case::load(case_path)?;
    let raw = crate::input::parse_value(&crate::input::read_json_text(case_path, "case file")?)?;
    // the case must be one Loam runs
    crate::model_builder::build_model(&case)?;
    let mut notes = Vec::new();
    expressible::refuse_unexpressed(&case, &raw, &mut notes)?;

    let grid = grid::grid_mesh(&case, &raw)?;
    let mut grid_mdpa = grid::grid_model_part(&grid, case.formulation.dim());
    let mut grid_parts = grid::GridParts { mdpa: &mut grid_mdpa, next_condition: 1 };
    let conditions = grid::grid_conditions(&case, &grid, &mut grid_parts)?;
    let outputs = grid::outputs(&case, &raw, &grid, &mut grid_parts, &mut notes)?;
    let (body_mdpa, properties, mut parts) = bodies::bodies(&case, &raw, &grid, &mut notes)?;
    parts.push(GRID_PART.into());

    let process_parts: Vec<String> = grid_mdpa.sub_model_parts.iter().skip(1).map(|p| p.name.clone()).collect();
    let dim = case.formulation.dim();
    let gravity = case.gravity.as_ref().map(|g| {
        let mut a = [0.0; 3];
        a[..dim].copy_from_slice(&g.acceleration[..dim]);
        a
    });
    let files = parameters::Files {
        parts: &parts,
        process_parts: &process_parts,
        pressure_dofs: case.domains[0].element_formulation == ElementFormulation::MixedUp,
    };
    let project = parameters::project(&case, &files, &conditions, gravity, &outputs, &mut notes)?;

    let pretty = |v: &Value| serde_json::to_string_pretty(v).expect("JSON values serialise") + "\n";
    let files = write_folder(
        dir,
        [
            ("ProjectParameters.json", pretty(&project)),
            ("ParticleMaterials.json", pretty(&json!({ "properties": properties }))),
            ("Grid.mdpa", mdpa::write(&grid_mdpa)),
            ("Body.mdpa", mdpa::write(&body_mdpa)),
        ],
    )?;
    Ok(Export { files, notes })
}

/// Writes the `files` (name, text) into the folder `dir`; returns their paths.
fn write_folder(dir: &Path, files: [(&str, String); 4]) -> Result<Vec<PathBuf>, ExportError> {
    std::fs::create_dir_all(dir).map_err(|e| ExportError(format!("{}: cannot create: {e}", dir.display())))?;
    let mut written = Vec::new();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| ExportError(format!("{}: cannot write: {e}", path.display())))?;
        written.push(path);
    }
    Ok(written)
}
