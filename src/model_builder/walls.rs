//! Contact walls as rigid structures (issue 25, item 4): one contact code for walls and
//! structures.
//!
//! A penalty wall in the contact form (`boundary_conditions[k].penalty` with `"contact":
//! true`) is a rigid body pressed against the soil: the model builder writes it as one before
//! anything is built, so that it is served by the non-conforming contact of
//! `loam_coupling::interface_points` on a `rigid` domain (`loam_fem::rigid_body`), as any
//! structure is. The wall becomes
//!
//! - a rigid domain named after the wall: one row of quad4 cells on the wall's right (the
//!   side away from the body), one cell of its grid wide, its polyline clipped to the grid;
//!   its `motion` the wall's `displacement` × `amplitude`, no rotation (its material, for its
//!   mass only, that of the wall's MPM domain: the motion is prescribed);
//! - a contact interface `<wall>_contact` between the wall's MPM domain and that body, on the
//!   wall's face, with the wall's `penalty_factor` as its normal penalty (N/m³ = Pa/m), the
//!   default tangential penalty, and friction μ = 0 for `"slip": true`, the wall's
//!   `friction`, or [`MAX_FRICTION`] for no-slip;
//! - `wall_force` monitors of the wall: `interface_force` of `<wall>_contact` with the sign
//!   turned (the force of the wall on the bodies is minus that of the soil on the structure).
//!
//! The Dirichlet form (`"contact": false`, Chandra et al. 2021) is a bilateral condition on
//! boundary particles, not a structure, and stays in `loam_mpm::penalty_boundary`.

use loam_fem::element::ElementType;
use loam_fem::mesh::Mesh;
use loam_mpm::grid::Grid;

use super::conditions::{check_wall, WallHold, MAX_FRICTION};
use super::meshes::{build_mesh, structured_grid};
use crate::case::{
    Case, CaseError, DomainKind, DomainSpec, ElementFormulation, InterfaceCoupling, InterfaceSpec, MeshSpec,
    MonitorSpec, Quadrature, RegionSpec, RigidMotionSpec,
};

/// `case` with its contact walls written as rigid structures (module doc); `None` if it has
/// none.
pub(super) fn as_rigid_structures(case: &Case) -> Result<Option<Case>, CaseError> {
    let walls: Vec<usize> = (0..case.boundary_conditions.len())
        .filter(|&k| case.boundary_conditions[k].penalty.as_ref().is_some_and(|p| p.contact))
        .collect();
    if walls.is_empty() {
        return Ok(None);
    }
    let mut out = case.clone();
    for k in walls {
        let spec = case.boundary_conditions[k].penalty.as_ref().expect("a penalty wall");
        let wall = check_wall(case, k, spec)?;
        let loc = format!("boundary_conditions[{k}].penalty.{}", wall.key);
        let soil = &case.domains[wall.domain];
        let grid = wall_grid(case, wall.domain)?;
        let vertices = clip_to_grid(&wall.vertices, &grid).ok_or_else(|| {
            CaseError::new(
                loc.clone(),
                format!("lies outside the grid of domain '{}' (or crosses it more than once)", soil.name),
            )
        })?;
        let h = smallest_cell(&grid);
        let cells = vertices
            .windows(2)
            .map(|w| ((2.0 * (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / h).ceil() as usize).max(1))
            .collect();
        let bc = &mut out.boundary_conditions[k];
        bc.as_rigid_wall = true;
        let face = format!("{} (the wall's face)", wall.name);
        out.regions.insert(face.clone(), RegionSpec::Polyline(vertices.iter().map(|v| v.to_vec()).collect()));
        out.domains.push(DomainSpec {
            name: wall.name.clone(),
            kind: DomainKind::Rigid,
            mesh: Some(MeshSpec::Strip { vertices, width: h, cells }),
            motion: Some(RigidMotionSpec {
                displacement: vec![Some(wall.displacement[0]), Some(wall.displacement[1])],
                rotation: Some(0.0),
                amplitude: bc.amplitude.clone(),
            }),
            initial_angular_velocity: None,
            grid: None,
            grid_mesh: None,
            material_points: None,
            initial_velocity: None,
            pic_fraction: 0.0,
            pic_relaxation_time: None,
            initial_stress: None,
            material: soil.material.clone(),
            mass_matrix: None,
            element_formulation: ElementFormulation::Displacement,
            quadrature: Quadrature::MaterialPoints,
            ghost_penalty: None,
        });
        let friction = match wall.hold {
            WallHold::Slip => 0.0,
            WallHold::Coulomb(mu) => mu,
            WallHold::NoSlip => MAX_FRICTION,
        };
        let interface = format!("{}_contact", wall.name);
        out.interfaces.push(InterfaceSpec {
            name: interface.clone(),
            soil: soil.name.clone(),
            structure: wall.name.clone(),
            region: face,
            slip: false,
            band: None,
            coupling: InterfaceCoupling::Contact,
            penalty: Some(spec.penalty_factor),
            tangential_penalty: None,
            friction: Some(friction),
            gap_tolerance: None,
        });
        for m in &mut out.monitors {
            if let MonitorSpec::WallForce { name, wall: w, component, scale } = m {
                if *w == wall.name {
                    let (name, component, scale) = (name.clone(), *component, -*scale);
                    *m = MonitorSpec::InterfaceForce { name, interface: interface.clone(), component, scale };
                }
            }
        }
    }
    Ok(Some(out))
}

/// The background grid of MPM domain `d` (as the model builder makes it).
fn wall_grid(case: &Case, d: usize) -> Result<Grid, CaseError> {
    let spec = &case.domains[d];
    let loc = format!("domains[{d}]");
    match (&spec.grid, &spec.grid_mesh) {
        (Some(g), _) => structured_grid(case, &loc, g),
        (None, Some(m)) => Ok(Grid::unstructured(build_mesh(case, &format!("{loc}.grid_mesh"), m)?)),
        (None, None) => Err(CaseError::new(format!("{loc}.grid"), "an mpm domain needs a grid (or a grid_mesh)")),
    }
}

/// The smallest extent of a cell of `grid` along x or y.
fn smallest_cell(grid: &Grid) -> f64 {
    (0..grid.mesh.num_cells()).flat_map(|c| grid.cell_extent(c)).filter(|e| *e > 0.0).fold(f64::MAX, f64::min)
}

/// The part of `vertices` inside `grid`, a millionth of the polyline's length in from the
/// grid's boundary: on each segment the interval of the parameter whose points the grid
/// locates (from 64 samples, its ends refined by bisection), joined into one polyline;
/// `None` if no part of it is inside, or if it leaves the grid and comes back.
fn clip_to_grid(vertices: &[[f64; 2]], grid: &Grid) -> Option<Vec<[f64; 2]>> {
    let length: f64 = vertices.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
    let inset = 1e-6 * length;
    let mut clipped: Vec<[f64; 2]> = Vec::new();
    let mut ended = false; // the polyline has left the grid after being inside
    for w in vertices.windows(2) {
        let at = |t: f64| [w[0][0] + t * (w[1][0] - w[0][0]), w[0][1] + t * (w[1][1] - w[0][1])];
        let inside = |t: f64| {
            let x = at(t);
            grid.locate(&[x[0], x[1], 0.0]).is_some()
        };
        let samples: Vec<f64> = (0..=64).map(|i| i as f64 / 64.0).collect();
        let inner: Vec<f64> = samples.iter().copied().filter(|&t| inside(t)).collect();
        let (Some(&first), Some(&last)) = (inner.first(), inner.last()) else {
            ended |= !clipped.is_empty();
            continue;
        };
        let seg = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        let refine = |mut lo: f64, mut hi: f64| {
            // `lo` inside, `hi` outside (or the reverse): the boundary between them
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if inside(mid) == inside(lo) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let start = if first > 0.0 { refine(first, first - 1.0 / 64.0) + inset / seg } else { 0.0 };
        let end = if last < 1.0 { refine(last, last + 1.0 / 64.0) - inset / seg } else { 1.0 };
        if ended || (!clipped.is_empty() && start > 0.0) {
            return None; // it came back into the grid
        }
        if clipped.is_empty() {
            clipped.push(at(start));
        }
        clipped.push(at(end));
        ended = end < 1.0;
    }
    (clipped.len() >= 2).then_some(clipped)
}

/// One row of quad4 cells along the polyline `vertices`, `width` wide on its right (the side
/// away from a body on its left), `cells[i]` along segment `i`: nodes on the polyline and
/// on its offset (by the segment's normal, and by the mitre of the two normals at an inner
/// vertex), cells counter-clockwise, so that the row's boundary edges on the polyline have
/// their outward normals towards the body.
pub(super) fn strip_mesh(vertices: &[[f64; 2]], width: f64, cells: &[usize]) -> Mesh {
    // the left unit normal of each segment
    let normals: Vec<[f64; 2]> = vertices
        .windows(2)
        .map(|w| {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            let l = dx.hypot(dy);
            [-dy / l, dx / l]
        })
        .collect();
    let mut line: Vec<[f64; 2]> = Vec::new();
    let mut offset: Vec<[f64; 2]> = Vec::new();
    let mut push = |x: [f64; 2], n: [f64; 2], scale: f64| {
        line.push(x);
        offset.push([x[0] - scale * width * n[0], x[1] - scale * width * n[1]]);
    };
    for (i, w) in vertices.windows(2).enumerate() {
        let n = cells[i];
        // the segment's first vertex: its own normal at the polyline's start, the mitre inside
        let (normal, scale) = if i == 0 {
            (normals[0], 1.0)
        } else {
            let m = [normals[i - 1][0] + normals[i][0], normals[i - 1][1] + normals[i][1]];
            let l = m[0].hypot(m[1]);
            let m = [m[0] / l, m[1] / l];
            (m, 1.0 / (m[0] * normals[i][0] + m[1] * normals[i][1]))
        };
        push(w[0], normal, scale);
        for j in 1..n {
            let t = j as f64 / n as f64;
            push([w[0][0] + t * (w[1][0] - w[0][0]), w[0][1] + t * (w[1][1] - w[0][1])], normals[i], 1.0);
        }
    }
    push(*vertices.last().expect("two vertices"), *normals.last().expect("a segment"), 1.0);
    let count = line.len();
    let coords: Vec<[f64; 3]> = line.iter().chain(&offset).map(|x| [x[0], x[1], 0.0]).collect();
    let connectivity = (0..count - 1).flat_map(|a| [count + a, count + a + 1, a + 1, a]).collect();
    Mesh { element: ElementType::Quad4, coords, connectivity, node_groups: Default::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The footing's polyline (side, then base): the row lies inside the footing, its cells
    /// counter-clockwise (positive area), the mitred corner node at `(0.5 − w, 5.0 + w)`, and
    /// the boundary edges on the polyline face the soil (outward normals +x on the side, −y
    /// under the base).
    #[test]
    fn a_strip_lies_on_the_right_of_its_polyline() {
        let vertices = [[0.5, 5.4], [0.5, 5.0], [-0.1, 5.0]];
        let mesh = strip_mesh(&vertices, 0.05, &[8, 12]);
        assert_eq!(mesh.num_cells(), 20);
        for e in 0..mesh.num_cells() {
            let p: Vec<[f64; 3]> = mesh.cell(e).iter().map(|&a| mesh.coords[a]).collect();
            let area: f64 =
                0.5 * (0..4).map(|i| p[i][0] * p[(i + 1) % 4][1] - p[(i + 1) % 4][0] * p[i][1]).sum::<f64>();
            assert!(area > 0.0, "cell {e} is clockwise");
        }
        let corner = mesh.coords[21 + 8];
        assert!((corner[0] - 0.45).abs() < 1e-12 && (corner[1] - 5.05).abs() < 1e-12, "{corner:?}");
        for f in mesh.boundary_facets() {
            let (a, b) = (mesh.coords[f[0]], mesh.coords[f[1]]);
            let normal = [b[1] - a[1], a[0] - b[0]];
            if a[0] == 0.5 && b[0] == 0.5 {
                assert!(normal[0] > 0.0, "the side faces +x");
            }
            if a[1] == 5.0 && b[1] == 5.0 {
                assert!(normal[1] < 0.0, "the base faces −y");
            }
        }
    }
}
