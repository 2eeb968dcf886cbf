//! How a grid cell integrates over its material points: the points' own volumes as weights
//! (standard MPM), or those weights normalised to the cell's volume in the cells the
//! material fills.
//!
//! **Why.** MPM integrates the internal force of a cell, `f_I = Σ_p V_p σ_p ∇N_I(x_p)`, with
//! the points in the cell as quadrature points. When points cross a cell boundary the
//! weights in a cell no longer add up to the volume of material in it: in a filled cell
//! that has lost one row of its 2 × 2 points to its neighbour the rule integrates half the
//! cell, the neighbour one and a half. Steffen, Kirby & Berzins (2008), *Analysis and
//! reduction of quadrature errors in the material point method (MPM)*, Int. J. Numer.
//! Meth. Engng 76:922–948, doi:10.1002/nme.2360, show this is the leading quadrature error
//! of MPM (the rule is not even exact for a constant stress). A row of half-weighted cells
//! is a soft layer: under an incompressible, perfectly plastic soil it concentrates the
//! strain, yields early and starts a spurious mechanism. Observed on the rigid footing of
//! benchmark 11 at h = B/20: points crossing the row of cells under the footing at 1 m
//! depth (2 points in a cell, 6 in the one below) at 0.016 m settlement, a pressure
//! oscillation in that row a step later, a spurious plastic zone under the rigid wedge,
//! and a load that levels off at q/s_u ≈ 2.9 instead of rising to 2 + π.
//!
//! **What [`PointQuadrature::FilledCells`] does.** In a cell the material fills, the
//! weights are scaled so that they add up to the cell's volume,
//!
//! `w_p = V_p · V_cell / Σ_{q ∈ cell} V_q`,
//!
//! which restores the zeroth-moment condition `Σ_p w_p = ∫_cell dV` whatever the points'
//! distribution (the cell integrates its own volume; the nodal forces of a constant stress,
//! `σ Σ_p w_p ∇N_I(x_p)`, would also need the first moments on a quad, which the points'
//! positions give only approximately), and leaves the points' positions, masses and states
//! alone (mass, gravity and inertia still come from the points). Fitting the first moments
//! too (weights exact for linear functions, the least change from these) was tried on the
//! footing and made it softer (q/s_u 4.78 against 5.03 at 0.129 m, h = B/20), and a quarter
//! of the cells could not be fitted with positive weights; the remedy that worked there is
//! more points per cell (the footing cases' 3 × 3). It is the
//! idea of Beuth, Więckowski & Vermeer (2011), *Solution of quasi-static large-strain
//! problems by the material point method*, Int. J. Numer. Anal. Meth. Geomech.
//! 35:1451–1465, doi:10.1002/nag.904, whose "mixed integration" integrates filled elements
//! over their whole volume and partially filled ones by their points, kept with the points'
//! positions as the quadrature points. A cell counts as filled when it holds points and every
//! cell sharing a node with it holds points too (cells missing from the grid, beyond its
//! outer boundary or inside an attached structure, do not count against it): at a free
//! surface or beside an empty cell the material may fill only part of the cell, and the
//! points' own volumes are kept there.

use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;

use crate::body::Body;
use crate::grid::{Grid, NO_GEOMETRY};

/// How a grid cell integrates over its material points (`domains[k].quadrature`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PointQuadrature {
    /// The points' current volumes as the weights (standard MPM).
    #[default]
    MaterialPoints,
    /// The points' volumes scaled to add up to the cell's volume in every filled cell (see
    /// the module doc).
    FilledCells,
}

/// Scales the quadrature weights of the points of `bodies` in every filled cell of `grid`
/// (the grid's configuration of the step, the points located in it) so that they add up to
/// the cell's volume (see the module doc); `occupied[c]`: whether cell `c` holds points of
/// any body (of any rank, where the points are distributed over ranks and `bodies` hold only
/// this rank's). Returns the number of cells scaled.
pub fn normalise_filled_cells(
    grid: &Grid,
    formulation: Formulation,
    thickness: f64,
    bodies: &mut [Body],
    occupied: &[bool],
) -> usize {
    let mesh = &grid.mesh;
    let num_cells = mesh.num_cells();
    // a node is inside the material if no cell around it is empty
    let mut inside = vec![true; mesh.coords.len()];
    for c in 0..num_cells {
        if !occupied[c] {
            for &a in mesh.cell(c) {
                inside[a] = false;
            }
        }
    }
    let mut scaled = 0;
    for c in 0..num_cells {
        if !mesh.cell(c).iter().all(|&a| inside[a]) {
            continue;
        }
        let weights: f64 = bodies.iter().map(|b| b.cell_weight(c)).sum();
        if weights <= 0.0 {
            continue;
        }
        let volume = cell_volume(grid, formulation, thickness, c);
        for body in bodies.iter_mut() {
            body.scale_cell_weights(c, volume / weights);
        }
        scaled += 1;
    }
    scaled
}

/// Volume of grid cell `c` in its current position, as the points' weights count it
/// (thickness, or `2πR` of an axisymmetric model): the element's Gauss rule.
pub fn cell_volume(grid: &Grid, formulation: Formulation, thickness: f64, c: usize) -> f64 {
    let mut rule = [NO_GEOMETRY; MAX_NODES];
    let points = grid.cell_rule(c, formulation, thickness, &mut rule).unwrap_or(0);
    rule[..points].iter().map(|g| g.weight).sum()
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use loam_fem::element::ElementType;
    use loam_laws::linear_elastic::LinearElastic;

    use super::*;
    use crate::material_points::MaterialPoints;

    /// A 4 × 3 grid of unit cells, its lower two rows filled with 2 × 2 points (volume 1/4),
    /// one point of cell (1, 0) moved up into cell (1, 1): the bottom row is filled (its
    /// upper neighbours hold points, below is the grid's edge) and is scaled to the cell
    /// volume, the half-emptied cell (1, 0) included; the row under the empty top row is
    /// not filled and keeps the points' volumes, the crossed point's extra weight included.
    #[test]
    fn filled_cells_integrate_their_volume_and_surface_cells_their_points() {
        let grid = Grid::new([0.0; 3], [4.0, 3.0, 0.0], [4, 3, 1], ElementType::Quad4);
        let mut points = MaterialPoints::default();
        for j in 0..4 {
            for i in 0..8 {
                let (x, mut y) = (0.25 + 0.5 * i as f64, 0.25 + 0.5 * j as f64);
                if i == 2 && j == 1 {
                    y = 1.05; // crossed from cell (1, 0) into cell (1, 1)
                }
                points.push([x, y, 0.0], 0.25, 1.0);
            }
        }
        let law = Arc::new(LinearElastic::new(1.0, 1.0e6, 0.3));
        let mut bodies = vec![Body::new("soil", law, points, 0)];
        bodies[0].locate(&grid, Formulation::PlaneStrain, 1.0);
        let weight = |bodies: &[Body], i: usize, j: usize| bodies[0].cell_weight(j * 4 + i);
        assert_eq!(weight(&bodies, 1, 0), 0.75, "cell (1, 0) lost a point");
        assert_eq!(weight(&bodies, 1, 1), 1.25, "cell (1, 1) gained it");
        let occupied: Vec<bool> = (0..grid.mesh.num_cells()).map(|c| bodies.iter().any(|b| b.occupies(c))).collect();
        let scaled = normalise_filled_cells(&grid, Formulation::PlaneStrain, 1.0, &mut bodies, &occupied);
        assert_eq!(scaled, 4, "the bottom row");
        for i in 0..4 {
            assert!((weight(&bodies, i, 0) - 1.0).abs() < 1e-14, "filled cell ({i}, 0): {}", weight(&bodies, i, 0));
        }
        assert_eq!(weight(&bodies, 1, 1), 1.25, "beside the empty row: the points' volumes");
        assert_eq!(weight(&bodies, 0, 1), 1.0);
    }
}
