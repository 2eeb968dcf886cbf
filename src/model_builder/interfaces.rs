//! Attaching grids to structures once the boundary conditions are known: the mesh motion
//! of each coupled grid, the node kinds its initialisation phase needs, and, on slip
//! interfaces, the local frames and tied normal DOFs of each soil–structure node pair.

use std::collections::HashSet;

use loam_coupling::mesh_motion::{HarmonicExtension, MotionConstraints};
use loam_fem::dofs::DofTie;
use loam_fem::model::{Constraint, Model};
use loam_fem::slip::Slip;
use loam_mpm::attachment::{GridAttachment, GridNodeKind};

use super::meshes::Part;
use crate::case::{Case, CaseError};

/// Default width of the mesh-motion band, in grid cells.
const DEFAULT_BAND_CELLS: f64 = 20.0;

/// Attaches every coupled grid of `parts` to its structures (see the module doc).
pub(super) fn attach(case: &Case, model: &mut Model, parts: &mut [Part]) -> Result<(), CaseError> {
    let dim = model.dim;
    let prescribed_dofs: HashSet<usize> = model.constraints.iter().flat_map(|c| c.dofs.iter().copied()).collect();
    let slip_nodes: HashSet<usize> = model.slips.iter().map(|s| s.node).collect();
    for part in parts.iter_mut() {
        let Part::Grid(grid_part) = part else { continue };
        let Some(coupling) = &grid_part.coupling else { continue };
        let domain = &grid_part.domain;
        let grid = domain.grid();
        let node_ids = domain.node_ids().to_vec();
        let held = |g: usize, i: usize| prescribed_dofs.contains(&(g * dim + i)) || slip_nodes.contains(&g);
        let prescribed: Vec<[bool; 3]> =
            node_ids.iter().map(|&g| std::array::from_fn(|i| i < dim && held(g, i))).collect();
        let anchored: Vec<bool> = coupling.on_interface.iter().map(Option::is_some).collect();
        // the narrowest band asked for by the grid's interfaces, 20 cells where none asks
        let band = coupling
            .interfaces
            .iter()
            .filter_map(|&k| case.interfaces[k].band)
            .reduce(f64::min)
            .unwrap_or(DEFAULT_BAND_CELLS * mean_cell_size(grid));
        let motion =
            HarmonicExtension::new(grid, &MotionConstraints { anchored: &anchored, prescribed: &prescribed, band });
        let mut kind = vec![GridNodeKind::Free; node_ids.len()];
        let mut anchor = vec![None; node_ids.len()];
        for (a, on) in coupling.on_interface.iter().enumerate() {
            let Some((node, structure)) = on else { continue };
            let slip = case.interfaces[coupling.interfaces[node.interface]].slip;
            if !slip {
                kind[a] = GridNodeKind::Tied;
                anchor[a] = Some(*structure);
                continue;
            }
            let soil = node_ids[a];
            kind[a] = GridNodeKind::Slip { source: *structure, normal: node.normal };
            anchor[a] = Some(*structure);
            // the normal along a coordinate axis: its global components are tied directly
            // (no local frames; boundary conditions on the other components stay); inclined:
            // both nodes in the local frame of the normal, unless a boundary condition holds
            // one of them (then the soil node takes the structure node's conditions)
            let axis = (0..dim).find(|&k| node.normal[k].abs() > 1.0 - 1e-12);
            match axis {
                Some(k) if !held(*structure, k) && !held(soil, k) => {
                    model.ties.push(DofTie { leader: structure * dim + k, follower: soil * dim + k });
                }
                Some(k) if held(*structure, k) => {
                    model
                        .constraints
                        .extend(copy_constraints(model, *structure, soil, dim, |i| i == k && !held(soil, i)));
                }
                Some(_) => {} // the soil node's own condition holds its normal component
                None if (0..dim).any(|i| held(*structure, i) || held(soil, i)) => {
                    model.constraints.extend(copy_constraints(model, *structure, soil, dim, |i| !held(soil, i)));
                }
                None => {
                    model.frames.push(Slip { node: soil, normal: node.normal, friction: 0.0 });
                    model.frames.push(Slip { node: *structure, normal: node.normal, friction: 0.0 });
                    model.ties.push(DofTie { leader: structure * dim, follower: soil * dim });
                }
            }
        }
        let names: Vec<String> =
            coupling.interfaces.iter().map(|&k| format!("'{}'", case.interfaces[k].name)).collect();
        grid_part.domain.attach(GridAttachment {
            interfaces: names.join(", "),
            kind,
            anchor,
            motion: Box::new(motion),
        });
    }
    Ok(())
}

/// The constraints of `structure`'s components `i` with `which(i)`, copied onto `soil` (the
/// soil node of a slip pair follows what holds its structure node).
fn copy_constraints(
    model: &Model,
    structure: usize,
    soil: usize,
    dim: usize,
    which: impl Fn(usize) -> bool,
) -> Vec<Constraint> {
    model
        .constraints
        .iter()
        .map(|c| {
            let mut copy = Constraint::without_dofs(c.amplitude.clone());
            for (&d, &v) in c.dofs.iter().zip(&c.values) {
                if d / dim == structure && which(d % dim) {
                    copy.dofs.push(soil * dim + d % dim);
                    copy.values.push(v);
                }
            }
            copy
        })
        .filter(|c| !c.dofs.is_empty())
        .collect()
}

/// Mean cell size of a grid: the square (cube) root of its mean cell measure.
fn mean_cell_size(grid: &loam_mpm::grid::Grid) -> f64 {
    let mesh = &grid.mesh;
    let dim = mesh.element.dim();
    let coords = grid.reference_coords();
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for x in coords {
        for d in 0..dim {
            lo[d] = lo[d].min(x[d]);
            hi[d] = hi[d].max(x[d]);
        }
    }
    let volume: f64 = (0..dim).map(|d| hi[d] - lo[d]).product();
    (volume / mesh.num_cells().max(1) as f64).powf(1.0 / dim as f64)
}
