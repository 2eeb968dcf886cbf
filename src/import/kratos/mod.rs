//! `loam import kratos DIR`: a Kratos Multiphysics MPM case folder as a Loam case.
//!
//! A Kratos MPM case (the `MpmAnalysis` stage of Kratos' MPMApplication) is a folder with
//! `ProjectParameters.json` ([`parameters`]), the body and background-grid model parts as
//! `.mdpa` files ([`mdpa`]) and a materials file ([`materials`]). The import writes beside the
//! case JSON one Gmsh MSH 4.1 file per body (its elements: the material points at their Gauss
//! positions, `material_points.cells`) and one for the grid (`grid_mesh`, with the grid's sub
//! model parts as physical groups, i.e. regions) ([`msh`]). What is not taken over, or only
//! approximately, is returned as notes, one line per key or block; what cannot be expressed
//! is refused with an [`ImportError`]. A CoSimulation folder of one MPM and one structural
//! solver is imported as one case, the structure an FEM domain tied to the grid ([`cosim`]).
//! The mapping of names: `docs/kratos.md`.

pub mod cosim;
pub mod json;
pub mod materials;
pub mod mdpa;
pub mod msh;
pub mod parameters;
pub mod structural;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

pub use json::ImportError;
use parameters::Condition;

/// What an import produced.
#[derive(Debug, Clone)]
pub struct Import {
    /// Files written, the case first.
    pub files: Vec<PathBuf>,
    /// One line per key or block not taken over as is (ignored or approximated).
    pub notes: Vec<String>,
}

/// Imports the Kratos case folder `dir` and writes the Loam case `out` (meshes beside it).
///
/// A folder holding a CoSimulation parameters file (`cosim_*_parameters.json`) is imported as
/// one monolithic case ([`cosim`]); any other folder as an MPM case (`ProjectParameters.json`).
pub fn import(dir: &Path, out: &Path) -> Result<Import, ImportError> {
    if let Some(params) = cosim::find(dir)? {
        return cosim::import(dir, &params, out);
    }
    let mut notes = Vec::new();
    let (case, files) = mpm_case(dir, "ProjectParameters.json", out, &mut notes)?;
    write_case(out, case)?;
    Ok(Import { files, notes })
}

/// Writes the case `case` to `out`.
fn write_case(out: &Path, case: Map<String, Value>) -> Result<(), ImportError> {
    let text = serde_json::to_string_pretty(&Value::Object(case)).expect("JSON values serialise") + "\n";
    std::fs::write(out, text).map_err(|e| ImportError(format!("{}: cannot write: {e}", out.display())))
}

/// The file `name` of the case folder `dir`. Kratos resolves file names from its working
/// directory, which co-simulations put one level up (`mpm_fem_beam/particle_Body`): a name not
/// found in `dir` is looked up by its last component.
fn locate(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    if path.exists() {
        return path;
    }
    match Path::new(name).file_name() {
        Some(f) if dir.join(f).exists() => dir.join(f),
        _ => path,
    }
}

/// Reads the text of `path`, returning it and the path as a string for messages.
fn read_text(path: &Path) -> Result<(String, String), ImportError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ImportError(format!("{file}: cannot read: {e}")))?;
    Ok((text, file))
}

/// The MPM case of `dir` whose parameters are the file `params` (Kratos' `MpmAnalysis`), with
/// its meshes written beside `out`: the case as a JSON object (not yet written) and the files,
/// `out` first.
pub(crate) fn mpm_case(
    dir: &Path,
    params: &str,
    out: &Path,
    notes: &mut Vec<String>,
) -> Result<(Map<String, Value>, Vec<PathBuf>), ImportError> {
    let (text, file) = read_text(&locate(dir, params))?;
    let project = parameters::read(&text, &file, notes)?;
    let (text, mat_file) = read_text(&locate(dir, &project.materials_file))?;
    let bodies = materials::read(&text, &mat_file, notes)?;
    let body_path = locate(dir, &project.body_file);
    let body = mdpa::read(&body_path)?;
    let grid_path = locate(dir, &project.grid_file);
    let grid = mdpa::read(&grid_path)?;
    notes.extend(body.notes.iter().cloned());
    notes.extend(grid.notes.iter().cloned());
    let (body_name, grid_name) = (body_path.display().to_string(), grid_path.display().to_string());

    // formulation: one for all bodies, as the laws say
    let first = bodies.first().ok_or_else(|| ImportError(format!("{mat_file}: properties: no material")))?;
    let formulation = first.formulation;
    if let Some(b) = bodies.iter().find(|b| b.formulation != formulation) {
        return Err(ImportError(format!(
            "{mat_file}: the laws mix {formulation} and {} (a Loam case has one formulation)",
            b.formulation
        )));
    }
    if project.axisymmetric != (formulation == "axisymmetric") {
        return Err(ImportError(format!(
            "{file}: solver_settings.axis_symmetric_flag is {} but the laws of {mat_file} are {formulation}",
            project.axisymmetric
        )));
    }
    let dim = project.domain_size;
    if (dim == 3) != (formulation == "3d") {
        return Err(ImportError(format!(
            "{file}: solver_settings.domain_size is {dim} but the laws of {mat_file} are {formulation}"
        )));
    }
    let thickness = first.thickness.unwrap_or(1.0);
    let mixed_up = project.pressure_dofs || bodies.iter().any(|b| b.mixed_up);
    if project.pressure_dofs != bodies.iter().all(|b| b.mixed_up) {
        return Err(ImportError(format!(
            "{file}: solver_settings.pressure_dofs is {} but the laws of {mat_file} are {}",
            project.pressure_dofs,
            if mixed_up && !project.pressure_dofs { "UP laws" } else { "not all UP laws" }
        )));
    }

    let out_dir = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf();
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "kratos".into());
    std::fs::create_dir_all(&out_dir).map_err(|e| ImportError(format!("{}: cannot create: {e}", out_dir.display())))?;
    let mut files = vec![out.to_path_buf()];
    let write = |name: &str, text: &str, files: &mut Vec<PathBuf>| -> Result<(), ImportError> {
        let path = out_dir.join(name);
        std::fs::write(&path, text).map_err(|e| ImportError(format!("{}: cannot write: {e}", path.display())))?;
        files.push(path);
        Ok(())
    };

    // the grid: every element of the grid file, the sub model parts the conditions use as groups
    let grid_cells =
        cells_of(&grid, &grid_name, grid.elements.iter().flat_map(|b| b.entities.iter().map(|e| e.0)), "Element", dim)?;
    let mut groups: Vec<(String, BTreeSet<usize>)> = Vec::new();
    let part_of = |c: &Condition| match c {
        Condition::Displacement { part, .. }
        | Condition::Slip { part }
        | Condition::LineLoad { part, .. }
        | Condition::PointLoad { part, .. }
        | Condition::Penalty { part, .. } => part.clone(),
    };
    for c in &project.conditions {
        let part = part_of(c);
        if matches!(c, Condition::Penalty { .. }) || groups.iter().any(|g| g.0 == part) {
            continue;
        }
        let smp = grid
            .sub_model_part(&part)
            .ok_or_else(|| ImportError(format!("{grid_name}: no sub model part '{part}' (named by {file})")))?;
        let mut nodes: BTreeSet<usize> = smp.nodes.iter().copied().collect();
        for id in &smp.conditions {
            let (_, n) = grid.condition(*id).ok_or_else(|| {
                ImportError(format!(
                    "{grid_name}: sub model part '{part}' lists condition {id}, which no Conditions block defines"
                ))
            })?;
            nodes.extend(n);
        }
        if let Some(n) = nodes.iter().find(|n| !grid.nodes.contains_key(n)) {
            return Err(ImportError(format!(
                "{grid_name}: sub model part '{part}' lists node {n}, which `Begin Nodes` does not define"
            )));
        }
        groups.push((part, nodes));
    }
    let grid_file = format!("{stem}_grid.msh");
    write(&grid_file, &msh::write(&grid.nodes, &grid_cells, dim, &groups), &mut files)?;

    // the bodies
    let mut materials = Map::new();
    let mut domains = Vec::new();
    for (k, b) in bodies.iter().enumerate() {
        let smp = body
            .sub_model_part(&b.part)
            .ok_or_else(|| ImportError(format!("{body_name}: no sub model part '{}' (named by {mat_file})", b.part)))?;
        let cells = cells_of(&body, &body_name, smp.elements.iter().copied(), "MPMUpdatedLagrangian", dim)?;
        let ppc = b.points_per_cell.unwrap_or(1);
        let (allowed, shape): (&[usize], _) = match (dim, cells[0].len()) {
            (2, 4) => (&[1, 4, 9, 16], "quadrilateral"),
            (2, _) => (&[1, 3], "triangular"),
            (_, 8) => (&[1, 8, 27, 64], "hexahedral"),
            _ => (&[1, 4], "tetrahedral"),
        };
        if !allowed.contains(&ppc) {
            return Err(ImportError(format!(
                "{mat_file}: properties[{k}].Material.Variables.MATERIAL_POINTS_PER_ELEMENT: {ppc} on {shape} cells: Loam places {allowed:?}"
            )));
        }
        let name = if bodies.len() == 1 { "body".to_string() } else { format!("body_{}", k + 1) };
        let mesh_file = format!("{stem}_{name}.msh");
        write(&mesh_file, &msh::write(&body.nodes, &cells, dim, &[]), &mut files)?;
        materials.insert(name.clone(), b.material.clone());
        let mut d = json!({
            "name": name, "type": "mpm", "material": name,
            "grid_mesh": { "gmsh": grid_file },
            "material_points": { "cells": { "mesh": { "gmsh": mesh_file }, "points_per_cell": ppc } }
        });
        if mixed_up {
            d["element_formulation"] = json!("mixed_up");
        }
        // Kratos' default and Loam's only MPM grid mass
        d["mass_matrix"] = json!("lumped");
        domains.push(d);
    }

    // what the body file holds beyond the bodies' elements
    let assigned: BTreeSet<usize> =
        bodies.iter().filter_map(|b| body.sub_model_part(&b.part)).flat_map(|p| p.elements.iter().copied()).collect();
    for b in &body.elements {
        let left = b.entities.iter().filter(|e| !assigned.contains(&e.0)).count();
        if left > 0 {
            notes.push(format!(
                "{body_name}:{}: {left} {} elements in no sub model part of {mat_file}: ignored (no material)",
                b.line, b.kind
            ));
        }
    }
    for b in &body.conditions {
        notes.push(format!(
            "{body_name}:{}: {} {} conditions on the body: ignored (material point conditions are not imported)",
            b.line,
            b.entities.len(),
            b.kind
        ));
    }

    // regions, boundary conditions and loads
    let mut regions = Map::new();
    for (g, _) in &groups {
        regions.insert(g.clone(), json!({ "group": g }));
    }
    let mut bcs = Vec::new();
    let mut loads = Vec::new();
    for c in &project.conditions {
        match c {
            Condition::Displacement { part, value } => {
                bcs.push(json!({ "region": part, "displacement": value[..dim] }));
            }
            Condition::Slip { part } => bcs.push(json!({ "region": part, "slip": {} })),
            Condition::LineLoad { part, .. } if dim == 3 => {
                return Err(ImportError(format!(
                    "{file}: LINE_LOAD on {part} in a 3D case: line loads on 3D grids are not imported (POINT_LOAD is)"
                )));
            }
            Condition::LineLoad { part, load } => {
                if thickness != 1.0 {
                    notes.push(format!(
                        "{file}: LINE_LOAD on {part}: taken as traction LINE_LOAD / THICKNESS ({thickness})"
                    ));
                }
                loads.push(json!({ "type": "traction", "region": part, "traction": [load[0] / thickness, load[1] / thickness] }));
            }
            Condition::PointLoad { part, force } => {
                loads.push(json!({ "type": "nodal_force", "region": part, "force": force[..dim] }));
            }
            Condition::Penalty { part, .. } if dim == 3 => {
                return Err(ImportError(format!(
                    "{file}: apply_mpm_particle_dirichlet_condition_process on {part} in a 3D case: Loam's penalty walls are 2D polylines"
                )));
            }
            Condition::Penalty { part, points_per_condition, penalty } => {
                let (lines, spacing) = penalty_lines(&grid, &grid_name, part, &body, *points_per_condition)?;
                notes.push(format!(
                    "{file}: penalty on {part}: {points_per_condition} boundary particles per condition approximated by one every {spacing:.6} m along {} polyline(s) of its condition lines",
                    lines.len()
                ));
                for (k, polyline) in lines.into_iter().enumerate() {
                    let name = if k == 0 { part.clone() } else { format!("{part}_{}", k + 1) };
                    bcs.push(json!({ "name": name, "penalty": {
                        "polyline": polyline, "spacing": spacing, "penalty_factor": penalty } }));
                }
            }
        }
    }

    let mut case = Map::new();
    case.insert(
        "description".into(),
        json!(format!("Kratos MPM case '{}' imported by `loam import kratos {}`", project.name, dir.display())),
    );
    case.insert("formulation".into(), json!(formulation));
    if formulation != "axisymmetric" && dim == 2 {
        case.insert("thickness".into(), json!(thickness));
    }
    case.insert("materials".into(), Value::Object(materials));
    case.insert("domains".into(), Value::Array(domains));
    if !regions.is_empty() {
        case.insert("regions".into(), Value::Object(regions));
    }
    if !bcs.is_empty() {
        case.insert("boundary_conditions".into(), Value::Array(bcs));
    }
    if !loads.is_empty() {
        case.insert("loads".into(), Value::Array(loads));
    }
    if let Some(g) = project.gravity {
        case.insert("gravity".into(), json!({ "acceleration": g[..dim] }));
    }
    case.insert("analysis".into(), project.analysis.clone());
    case.insert("solver".into(), project.solver.clone());
    case.insert("output".into(), json!({ "grid": true }));
    Ok((case, files))
}

/// The node lists of the elements `ids` of `m`, all of one linear kind of dimension `dim`
/// whose name starts with `prefix` (2D: 3 or 4 nodes; 3D: 4 or 8 nodes).
fn cells_of(
    m: &mdpa::Mdpa,
    file: &str,
    ids: impl Iterator<Item = usize>,
    prefix: &str,
    dim: usize,
) -> Result<Vec<Vec<usize>>, ImportError> {
    let kinds_taken: [&str; 2] = if dim == 3 { ["3D4N", "3D8N"] } else { ["2D3N", "2D4N"] };
    let mut cells = Vec::new();
    let mut kinds = BTreeSet::new();
    for id in ids {
        let (kind, nodes) = m
            .element(id)
            .ok_or_else(|| ImportError(format!("{file}: element {id} is listed but no Elements block defines it")))?;
        if !kind.starts_with(prefix) || !kinds_taken.iter().any(|k| kind.ends_with(k)) {
            return Err(ImportError(format!(
                "{file}: element {id} is a {kind}: in a {dim}D case the importer takes {prefix}…{} and …{}",
                kinds_taken[0], kinds_taken[1]
            )));
        }
        kinds.insert(nodes.len());
        cells.push(nodes.to_vec());
    }
    if cells.is_empty() {
        return Err(ImportError(format!("{file}: no {prefix}… elements")));
    }
    if kinds.len() > 1 {
        return Err(ImportError(format!("{file}: cell shapes mixed (Loam meshes have one cell type)")));
    }
    Ok(cells)
}

/// Points of a 2D polyline.
type Polyline = Vec<[f64; 2]>;

/// The penalty condition lines of sub model part `part` of the grid as polylines (each
/// chain of connected lines one) with the body on their left, and the boundary-particle
/// spacing (mean line length / `per_line`).
fn penalty_lines(
    grid: &mdpa::Mdpa,
    file: &str,
    part: &str,
    body: &mdpa::Mdpa,
    per_line: usize,
) -> Result<(Vec<Polyline>, f64), ImportError> {
    let smp = grid.sub_model_part(part).ok_or_else(|| ImportError(format!("{file}: no sub model part '{part}'")))?;
    let mut segments: Vec<(usize, usize)> = Vec::new();
    for id in &smp.conditions {
        let (_, n) = grid
            .condition(*id)
            .ok_or_else(|| ImportError(format!("{file}: condition {id} of '{part}' is not defined")))?;
        if n.len() != 2 {
            return Err(ImportError(format!("{file}: condition {id} of '{part}' is not a 2-node line")));
        }
        segments.push((n[0], n[1]));
    }
    if segments.is_empty() {
        return Err(ImportError(format!(
            "{file}: sub model part '{part}' holds no condition lines for the penalty wall"
        )));
    }
    let xy = |n: &usize| [grid.nodes[n][0], grid.nodes[n][1]];
    let len: f64 =
        segments.iter().map(|(a, b)| ((xy(b)[0] - xy(a)[0]).powi(2) + (xy(b)[1] - xy(a)[1]).powi(2)).sqrt()).sum();
    let spacing = len / segments.len() as f64 / per_line as f64;
    // the body's centroid decides the side
    let n = body.nodes.len().max(1) as f64;
    let c = body.nodes.values().fold([0.0; 2], |s, x| [s[0] + x[0] / n, s[1] + x[1] / n]);
    let mut lines = Vec::new();
    let mut left = segments;
    while !left.is_empty() {
        // chains start at a node used once (an open end), else anywhere (a loop)
        let mut count: BTreeMap<usize, usize> = BTreeMap::new();
        left.iter().for_each(|&(a, b)| {
            *count.entry(a).or_default() += 1;
            *count.entry(b).or_default() += 1;
        });
        let start = count.iter().find(|(_, &k)| k == 1).map(|(&n, _)| n).unwrap_or(left[0].0);
        let mut chain = vec![start];
        while let Some(k) = left.iter().position(|&(a, b)| a == chain[chain.len() - 1] || b == chain[chain.len() - 1]) {
            let (a, b) = left.remove(k);
            chain.push(if a == chain[chain.len() - 1] { b } else { a });
        }
        let mut pts: Vec<[f64; 2]> = chain.iter().map(xy).collect();
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0 {
            pts.reverse();
        }
        lines.push(pts);
    }
    Ok((lines, spacing))
}
