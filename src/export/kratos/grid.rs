//! The background grid of the export: the grid as a mesh, its model part, the sub model parts
//! of the conditions (a region's nodes, and its boundary facets where Kratos applies a
//! condition on facets) and of the outputs.

use std::collections::{BTreeMap, BTreeSet};

use loam_fem::formulation::Formulation;
use loam_fem::mesh::Mesh;
use loam_mpm::basis::Basis;
use serde_json::Value;

use super::mdpa::{block, entity_suffix};
use super::{ExportError, GRID_PART};
use crate::case::{Case, LoadSpec, MonitorSpec};
use crate::import::kratos::mdpa::{Mdpa, SubModelPart};
use crate::import::kratos::parameters::Condition;
use crate::model_builder::{build_mesh, line_tolerance, nearest_node, select_region, structured_grid};

/// The background grid shared by every body, as a mesh (a structured `grid` rotated as given).
pub(super) fn grid_mesh(case: &Case, raw: &Value) -> Result<Mesh, ExportError> {
    let key = |k: usize| {
        let d = &raw["domains"][k];
        if d.get("grid").is_some() {
            ("grid", d["grid"].clone())
        } else {
            ("grid_mesh", d["grid_mesh"].clone())
        }
    };
    let first = key(0);
    if let Some(k) = (1..case.domains.len()).find(|&k| key(k) != first) {
        return Err(ExportError(format!(
            "domains[{k}].{}: Kratos has one background grid: every body must be on the grid of domains[0]",
            key(k).0
        )));
    }
    let d = &case.domains[0];
    let mesh = match (&d.grid, &d.grid_mesh) {
        (Some(g), _) => {
            if g.basis != Basis::Linear {
                return Err(ExportError(format!(
                    "domains[0].grid.basis: \"{}\": Kratos' implicit MPM has the cells' linear functions",
                    g.basis.name()
                )));
            }
            structured_grid(case, "domains[0]", g)?.mesh
        }
        (None, Some(spec)) => build_mesh(case, "domains[0].grid_mesh", spec)?,
        (None, None) => unreachable!("checked by build_model"),
    };
    Ok(mesh)
}

/// The grid's model part: its nodes (Kratos ids from 1) and cells (`Element2D4N` …), sub
/// model part [`GRID_PART`].
pub(super) fn grid_model_part(grid: &Mesh, dim: usize) -> Mdpa {
    let mut m = Mdpa { nodes: grid.coords.iter().enumerate().map(|(n, x)| (n + 1, *x)).collect(), ..Mdpa::default() };
    let kind = format!("Element{}", entity_suffix(dim, grid.element.num_nodes()));
    m.elements.push(block(&kind, (0..grid.num_cells()).map(|e| grid.cell(e).to_vec()), 0));
    m.sub_model_parts.push(SubModelPart {
        name: GRID_PART.into(),
        nodes: (1..=grid.coords.len()).collect(),
        elements: (1..=grid.num_cells()).collect(),
        conditions: Vec::new(),
    });
    m
}

/// The boundary conditions and loads of the case on the grid, their sub model parts added to
/// `grid_parts` (with the grid's boundary facets in the region as conditions where Kratos
/// applies them on facets).
pub(super) fn grid_conditions(
    case: &Case,
    grid: &Mesh,
    grid_parts: &mut GridParts,
) -> Result<Vec<Condition>, ExportError> {
    let dim = case.formulation.dim();
    let tol = line_tolerance(&grid.coords);
    let region = |name: &str, loc: String| -> Result<Vec<usize>, ExportError> {
        let spec =
            case.regions.get(name).ok_or_else(|| ExportError(format!("{loc}: no region named '{name}' in regions")))?;
        Ok(select_region(name, spec, &grid.coords, dim, &grid.node_groups, tol)?)
    };
    let facets = grid.boundary_facets();
    let part_name = part_names(case);
    let mut conditions = Vec::new();
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        let loc = format!("boundary_conditions[{k}]");
        let nodes = region(&bc.region, format!("{loc}.region"))?;
        if bc.slip.is_some() {
            let part = part_name("SLIP", &bc.region);
            let kind = if dim == 2 { "LineCondition2D2N" } else { "SurfaceCondition3D" };
            grid_parts.add(&part, &nodes, &facets, Some(kind), &loc)?;
            conditions.push(Condition::Slip { part });
        } else {
            let part = part_name("DISPLACEMENT", &bc.region);
            grid_parts.add(&part, &nodes, &facets, None, &loc)?;
            // in 2D, DISPLACEMENT_Z held at 0 as in Kratos' own 2D cases
            let mut value = [None, None, Some(0.0)];
            for (d, v) in bc.displacement.iter().enumerate().take(dim) {
                value[d] = *v;
            }
            conditions.push(Condition::Displacement { part, value });
        }
    }
    let axisymmetric = case.formulation == Formulation::Axisymmetric;
    for (k, load) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        match load {
            LoadSpec::Traction { region: r, traction, .. } => {
                let nodes = region(r, format!("{loc}.region"))?;
                let part = part_name("LINE_LOAD", r);
                let kind =
                    if axisymmetric { "MPMGridAxisymLineLoadCondition2D2N" } else { "MPMGridLineLoadCondition2D2N" };
                grid_parts.add(&part, &nodes, &facets, Some(kind), &loc)?;
                let t = if axisymmetric { 1.0 } else { case.thickness };
                conditions.push(Condition::LineLoad { part, load: [traction[0] * t, traction[1] * t, 0.0] });
            }
            LoadSpec::NodalForce { region: r, force, .. } => {
                let nodes = region(r, format!("{loc}.region"))?;
                let part = part_name("POINT_LOAD", r);
                let kind = format!("MPMGridPointLoadCondition{dim}D1N");
                grid_parts.points(&part, &nodes, &kind);
                let mut f = [0.0; 3];
                f[..dim].copy_from_slice(&force[..dim]);
                conditions.push(Condition::PointLoad { part, force: f });
            }
            LoadSpec::Pressure { .. } | LoadSpec::MaterialPointForce { .. } => unreachable!("refused above"),
        }
    }
    Ok(conditions)
}

/// The `json_output_process` outputs `(sub model part, file)`: one per `displacement`
/// monitor, of the grid node nearest to its point (`OUTPUT_<monitor>`, `<monitor>.json`);
/// other monitors are noted as left out.
pub(super) fn outputs(
    case: &Case,
    raw: &Value,
    grid: &Mesh,
    grid_parts: &mut GridParts,
    notes: &mut Vec<String>,
) -> Result<Vec<(String, String)>, ExportError> {
    let mut outputs = Vec::new();
    for (k, m) in case.monitors.iter().enumerate() {
        match m {
            MonitorSpec::Displacement { name, point, .. } => {
                let node = nearest_node(&grid.coords, point)
                    .ok_or_else(|| ExportError(format!("monitors[{k}].point: no grid node")))?;
                let part = format!("OUTPUT_{name}");
                if grid_parts.mdpa.sub_model_part(&part).is_some() {
                    return Err(ExportError(format!(
                        "monitors[{k}].name: \"{name}\": its sub model part {part} is a region's name"
                    )));
                }
                grid_parts.add(&part, &[node], &[], None, &format!("monitors[{k}]"))?;
                outputs.push((part, format!("{name}.json")));
            }
            other => notes.push(format!(
                "monitors[{k}]: the {} monitor '{}' left out (exported: displacement monitors, as Kratos' json_output_process of a grid node)",
                monitor_type(raw, k),
                other.name()
            )),
        }
    }
    Ok(outputs)
}

/// The grid sub model part of the conditions of kind `KIND` (`DISPLACEMENT`, `SLIP`,
/// `LINE_LOAD`, `POINT_LOAD`) on a region: the region's name where only one kind uses it (a
/// re-import gives the region back by its name), else `KIND_<region>` (Kratos puts the
/// conditions of a sub model part under one process).
fn part_names(case: &Case) -> impl Fn(&str, &str) -> String {
    let mut kinds: BTreeMap<String, BTreeSet<&'static str>> = BTreeMap::new();
    for bc in &case.boundary_conditions {
        kinds.entry(bc.region.clone()).or_default().insert(if bc.slip.is_some() { "SLIP" } else { "DISPLACEMENT" });
    }
    for l in &case.loads {
        match l {
            LoadSpec::Traction { region, .. } => kinds.entry(region.clone()).or_default().insert("LINE_LOAD"),
            LoadSpec::NodalForce { region, .. } => kinds.entry(region.clone()).or_default().insert("POINT_LOAD"),
            _ => false,
        };
    }
    move |kind, region| {
        if kinds.get(region).is_some_and(|k| k.len() == 1) && region != GRID_PART {
            region.to_string()
        } else {
            format!("{kind}_{region}")
        }
    }
}

/// The `type` of monitor `k` as written in the case.
fn monitor_type(raw: &Value, k: usize) -> String {
    raw["monitors"][k]["type"].as_str().unwrap_or("?").to_string()
}

/// The grid's sub model parts as they are added.
pub(super) struct GridParts<'a> {
    pub(super) mdpa: &'a mut Mdpa,
    pub(super) next_condition: usize,
}

impl GridParts<'_> {
    /// Adds sub model part `name` (if new) of `nodes` (0-based); with `condition`, the
    /// `facets` whose nodes all lie in it become conditions of that kind (refused if none).
    fn add(
        &mut self,
        name: &str,
        nodes: &[usize],
        facets: &[Vec<usize>],
        condition: Option<&str>,
        loc: &str,
    ) -> Result<(), ExportError> {
        if self.mdpa.sub_model_part(name).is_some() {
            return Ok(());
        }
        let mut conditions = Vec::new();
        if let Some(kind) = condition {
            let inside: BTreeSet<usize> = nodes.iter().copied().collect();
            let on: Vec<Vec<usize>> = facets.iter().filter(|f| f.iter().all(|n| inside.contains(n))).cloned().collect();
            if on.is_empty() {
                return Err(ExportError(format!(
                    "{loc}.region: no boundary facet of the grid has all its nodes in the region (Kratos applies this condition on facets)"
                )));
            }
            let kind =
                if kind.starts_with("SurfaceCondition") { format!("{kind}{}N", on[0].len()) } else { kind.into() };
            let b = block(&kind, on.into_iter(), self.next_condition - 1);
            self.next_condition += b.entities.len();
            conditions = b.entities.iter().map(|e| e.0).collect();
            self.mdpa.conditions.push(b);
        }
        self.mdpa.sub_model_parts.push(SubModelPart {
            name: name.into(),
            nodes: nodes.iter().map(|n| n + 1).collect(),
            elements: Vec::new(),
            conditions,
        });
        Ok(())
    }

    /// Adds sub model part `name` of `nodes` with one point condition of `kind` on each.
    fn points(&mut self, name: &str, nodes: &[usize], kind: &str) {
        if self.mdpa.sub_model_part(name).is_some() {
            return;
        }
        let b = block(kind, nodes.iter().map(|&n| vec![n]), self.next_condition - 1);
        self.next_condition += b.entities.len();
        self.mdpa.sub_model_parts.push(SubModelPart {
            name: name.into(),
            nodes: nodes.iter().map(|n| n + 1).collect(),
            elements: Vec::new(),
            conditions: b.entities.iter().map(|e| e.0).collect(),
        });
        self.mdpa.conditions.push(b);
    }
}
