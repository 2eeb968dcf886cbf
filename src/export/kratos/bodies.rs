//! The bodies of the export: their cells as `MPMUpdatedLagrangian…` elements of the body model
//! part, and their materials.

use std::collections::BTreeMap;

use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::mesh::Mesh;
use loam_mpm::grid::Grid;
use serde_json::Value;

use super::materials;
use super::mdpa::{block, entity_suffix};
use super::ExportError;
use crate::case::{BodySpec, Case, ElementFormulation};
use crate::import::kratos::mdpa::{Mdpa, SubModelPart};
use crate::model_builder::{body_points, build_mesh};

/// The bodies' model part (one sub model part `Parts_<domain>` each, `MPMUpdatedLagrangian…`
/// elements), their materials' `properties` and the sub model part names.
pub(super) fn bodies(
    case: &Case,
    raw: &Value,
    grid: &Mesh,
    notes: &mut Vec<String>,
) -> Result<(Mdpa, Vec<Value>, Vec<String>), ExportError> {
    let dim = case.formulation.dim();
    let axisymmetric = case.formulation == Formulation::Axisymmetric;
    let mut body_mdpa = Mdpa::default();
    let mut properties = Vec::new();
    let mut parts = Vec::new();
    for (k, d) in case.domains.iter().enumerate() {
        let (m, points_per_cell) = body_mesh(case, k, grid, notes)?;
        let part = format!("Parts_{}", d.name);
        let (node0, element0) =
            (body_mdpa.nodes.len(), body_mdpa.elements.iter().map(|b| b.entities.len()).sum::<usize>());
        body_mdpa.nodes.extend(m.coords.iter().enumerate().map(|(n, x)| (node0 + n + 1, *x)));
        let up = if d.element_formulation == ElementFormulation::MixedUp { "UP" } else { "" };
        let kind = format!("MPMUpdatedLagrangian{up}{}", entity_suffix(dim, m.element.num_nodes()));
        let cells = (0..m.num_cells()).map(|e| m.cell(e).iter().map(|n| n + node0).collect::<Vec<_>>());
        let b = block(&kind, cells, element0);
        body_mdpa.sub_model_parts.push(SubModelPart {
            name: part.clone(),
            nodes: (node0 + 1..=node0 + m.coords.len()).collect(),
            elements: b.entities.iter().map(|e| e.0).collect(),
            conditions: Vec::new(),
        });
        body_mdpa.elements.push(b);
        let kin = materials::BodyKinematics {
            part: &part,
            formulation: case.formulation.name(),
            mixed_up: !up.is_empty(),
            // Kratos' 2D elements need THICKNESS, also in axisymmetry (where it is not used)
            thickness: (dim == 2).then_some(if axisymmetric { 1.0 } else { case.thickness }),
            points_per_cell,
        };
        let id = properties.len() + 1;
        properties.push(materials::properties(&d.material, &raw["materials"][&d.material], id, &kin)?);
        parts.push(part);
    }
    Ok((body_mdpa, properties, parts))
}

/// The body mesh of MPM domain `k` and its points per cell. A `cells` body as given; a lattice
/// body (`disk`, `polygon`) as one square cell of side `spacing` centred on each of its
/// lattice points with one point per cell, which Kratos (as Loam) places at the cell's centre
/// with the square's area as its volume: Loam's lattice point, position and volume.
fn body_mesh(case: &Case, k: usize, grid: &Mesh, notes: &mut Vec<String>) -> Result<(Mesh, usize), ExportError> {
    let loc = format!("domains[{k}].material_points");
    let spacing = match case.domains[k].material_points.as_ref().expect("an mpm domain has points") {
        BodySpec::Cells { mesh, points_per_cell } => {
            return Ok((build_mesh(case, &format!("{loc}.cells.mesh"), mesh)?, *points_per_cell));
        }
        BodySpec::Disk { spacing, .. } | BodySpec::Polygon { spacing, .. } => *spacing,
    };
    let points = body_points(case, k, &Grid::unstructured(grid.clone()))?;
    let mut ids: BTreeMap<(i64, i64), usize> = BTreeMap::new();
    let mut coords = Vec::new();
    let mut connectivity = Vec::new();
    for x in &points.position {
        for (di, dj) in [(-1, -1), (1, -1), (1, 1), (-1, 1)] {
            // corners on the lattice of half spacings, so that neighbours share them
            let key = ((2.0 * x[0] / spacing).round() as i64 + di, (2.0 * x[1] / spacing).round() as i64 + dj);
            let id = *ids.entry(key).or_insert_with(|| {
                coords.push([x[0] + 0.5 * spacing * di as f64, x[1] + 0.5 * spacing * dj as f64, 0.0]);
                coords.len() - 1
            });
            connectivity.push(id);
        }
    }
    notes.push(format!(
        "{loc}: the lattice of {} points written as one {spacing} m square cell per point, 1 point per cell (the same points and volumes)",
        points.len()
    ));
    Ok((Mesh { element: ElementType::Quad4, coords, connectivity, node_groups: BTreeMap::new() }, 1))
}
