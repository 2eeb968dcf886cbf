//! Mesh motion of a background grid attached to a structure: harmonic extension of the
//! interface displacement into a band of grid nodes, once per step.
//!
//! Each component `w_i` of the grid-node displacement solves the discrete Laplace equation
//! of the grid's edge graph (unit weights on the cell edges),
//!
//! $$ \sum_{b \in N(a)} (w_a - w_b) = 0 \quad \text{at every free node } a, $$
//!
//! with Dirichlet values at the fixed nodes: the structure's displacement at the interface
//! nodes, 0 at the nodes farther than the band width from every interface node, and 0 in
//! every component a boundary condition prescribes (a wall or base of the grid stays where
//! it is). Elsewhere the grid's outer boundary is free (the natural condition): where the
//! structure meets the edge of the grid, as a beam's end does, the edge turns with it; held
//! along the edge, the cells at the structure's corner shear by the structure's rotation
//! times the band width over one cell and fold (observed: the beam of benchmark 12 split
//! with the clamped half as material points, at 0.18 m of deflection). Material is not
//! lost by this: a free edge of the grid has no material on it, and it moves only within
//! the band by less than the structure does. The graph Laplacian is an M-matrix, so the
//! discrete maximum principle holds: every free node moves by a convex combination of its
//! neighbours' motions, no more than the largest interface displacement, and the motion
//! decays smoothly across the band (the harmonic extension of mesh-moving ALE methods, e.g.
//! Löhner & Yang 1996, *Improved ALE mesh velocities for moving bodies*, Commun. Numer.
//! Methods Eng. 12, 599–608, doi:10.1002/(SICI)1099-0887(199610)12:10<599::AID-CNM1>3.0.CO;2-Q).
//! The matrices depend only on the reference grid: each component's is factorised once
//! (Cholesky) and every step costs one forward and back substitution per component.
//!
//! The rule does not by itself exclude inverted cells: a structure that moves by more than
//! about half the band width relative to its surroundings can fold the cells next to it.
//! The grid checks every moved cell ([`loam_mpm::grid::Grid::move_nodes`]) and the step
//! stops with a message naming the interface.

use loam_fem::assembly::{AssemblyPattern, BlockLayout};
use loam_fem::dofs::DofMap;
use loam_fem::linear_solver::CholeskyFactor;
use loam_mpm::attachment::GridMotion;
use loam_mpm::grid::Grid;

/// One component's Laplace problem: free nodes, their equations and the factor.
struct ComponentProblem {
    /// Equation of each grid node (`usize::MAX` if fixed).
    equation: Vec<usize>,
    factor: Option<CholeskyFactor>,
}

/// The harmonic extension of a grid's interface displacement (see the module doc).
pub struct HarmonicExtension {
    dim: usize,
    /// Cell edges `(a, b)`, `a < b`, each once.
    edges: Vec<(usize, usize)>,
    components: Vec<ComponentProblem>,
    rhs: Vec<f64>,
    /// Reference coordinates of the grid nodes.
    coords: Vec<[f64; 3]>,
    /// The constraints, kept to widen the band.
    anchored: Vec<bool>,
    prescribed: Vec<[bool; 3]>,
    /// Width of the band (m).
    band: f64,
    /// Largest distance of a grid node from the anchored nodes (m): a wider band moves the
    /// same nodes.
    reach: f64,
}

/// Which components of which grid nodes the motion must not change, and the band.
pub struct MotionConstraints<'a> {
    /// Interface nodes: their displacement is given.
    pub anchored: &'a [bool],
    /// Per node and component: prescribed by a boundary condition (held at 0).
    pub prescribed: &'a [[bool; 3]],
    /// Width of the band (m): nodes farther from every anchored node stay in place.
    pub band: f64,
}

impl HarmonicExtension {
    /// The extension on `grid` (reference configuration) under `constraints`.
    pub fn new(grid: &Grid, constraints: &MotionConstraints<'_>) -> Self {
        let mesh = &grid.mesh;
        let element = mesh.element;
        let dim = element.dim();
        let coords = grid.reference_coords().to_vec();
        let n = coords.len();
        // edges of the cells (from the facets: each facet's consecutive nodes)
        let mut edges = Vec::new();
        for c in 0..mesh.num_cells() {
            let cell = mesh.cell(c);
            for facet in element.facets() {
                let k = facet.len();
                for i in 0..if k == 2 { 1 } else { k } {
                    let (a, b) = (cell[facet[i]], cell[facet[(i + 1) % k]]);
                    edges.push((a.min(b), a.max(b)));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let anchors: Vec<[f64; 3]> = (0..n).filter(|&a| constraints.anchored[a]).map(|a| coords[a]).collect();
        let distance: Vec<f64> = coords
            .iter()
            .map(|x| {
                anchors
                    .iter()
                    .map(|y| (0..dim).map(|i| (x[i] - y[i]).powi(2)).sum::<f64>())
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .collect();
        let reach = distance.iter().copied().filter(|d| d.is_finite()).fold(0.0, f64::max);
        let mut extension = Self {
            dim,
            edges,
            components: Vec::new(),
            rhs: Vec::new(),
            coords,
            anchored: constraints.anchored.to_vec(),
            prescribed: constraints.prescribed.to_vec(),
            band: constraints.band,
            reach,
        };
        extension.factorise();
        extension
    }

    /// Width of the band (m).
    pub fn band(&self) -> f64 {
        self.band
    }

    /// The Laplace problem of every component for the present band.
    fn factorise(&mut self) {
        let n = self.coords.len();
        let dim = self.dim;
        let anchors: Vec<[f64; 3]> = (0..n).filter(|&a| self.anchored[a]).map(|a| self.coords[a]).collect();
        // the band: distance to the nearest anchored node
        let far: Vec<bool> = self
            .coords
            .iter()
            .map(|x| {
                let d2 = anchors
                    .iter()
                    .map(|y| (0..dim).map(|i| (x[i] - y[i]).powi(2)).sum::<f64>())
                    .fold(f64::INFINITY, f64::min);
                d2 > self.band * self.band
            })
            .collect();
        self.components.clear();
        for i in 0..dim {
            let fixed: Vec<bool> = (0..n).map(|a| self.anchored[a] || far[a] || self.prescribed[a][i]).collect();
            let fixed = hold_unanchored_islands(n, &self.edges, fixed);
            self.components.push(ComponentProblem::new(&self.edges, fixed));
        }
    }

    /// Number of grid nodes the motion may move in at least one component.
    pub fn moving_nodes(&self) -> usize {
        let n = self.components.first().map_or(0, |c| c.equation.len());
        (0..n).filter(|&a| self.components.iter().any(|c| c.equation[a] != usize::MAX)).count()
    }
}

impl ComponentProblem {
    fn new(edges: &[(usize, usize)], fixed: Vec<bool>) -> Self {
        let dofs = DofMap::new(1, &fixed);
        let equation = dofs.equations().to_vec();
        if dofs.num_equations() == 0 {
            return Self { equation, factor: None };
        }
        let mut layout = BlockLayout::default();
        for &(a, b) in edges {
            layout.push([a, b]);
        }
        let pattern = AssemblyPattern::new(&dofs, &layout);
        let blocks: Vec<f64> = edges.iter().flat_map(|_| [1.0, -1.0, -1.0, 1.0]).collect();
        let mut values = vec![0.0; pattern.nnz()];
        pattern.gather_matrix(&blocks, &mut values, &mut Vec::new());
        // every free node is joined to a fixed one (hold_unanchored_islands): L_FF is SPD
        let factor =
            CholeskyFactor::new(&pattern, &values).expect("the Laplacian of a connected band is positive definite");
        Self { equation, factor: Some(factor) }
    }
}

/// Fixes the free nodes of every connected set of free nodes that no edge joins to a fixed
/// node (its Laplace problem would be singular): they stay in place.
fn hold_unanchored_islands(n: usize, edges: &[(usize, usize)], mut fixed: Vec<bool>) -> Vec<bool> {
    let mut neighbours = vec![Vec::new(); n];
    for &(a, b) in edges {
        neighbours[a].push(b);
        neighbours[b].push(a);
    }
    let mut seen = vec![false; n];
    for start in 0..n {
        if fixed[start] || seen[start] {
            continue;
        }
        let mut island = vec![start];
        let mut stack = vec![start];
        seen[start] = true;
        let mut touches_fixed = false;
        while let Some(a) = stack.pop() {
            for &b in &neighbours[a] {
                if fixed[b] {
                    touches_fixed = true;
                } else if !seen[b] {
                    seen[b] = true;
                    island.push(b);
                    stack.push(b);
                }
            }
        }
        if !touches_fixed {
            for a in island {
                fixed[a] = true;
            }
        }
    }
    fixed
}

impl GridMotion for HarmonicExtension {
    /// Doubles the band (up to the farthest grid node) and factorises the Laplace problems
    /// anew.
    fn widen(&mut self) -> Option<String> {
        if self.band >= self.reach {
            return None;
        }
        self.band = (2.0 * self.band).min(self.reach * (1.0 + 1e-9));
        self.factorise();
        Some(format!("band {:.3} m", self.band))
    }

    fn extend(&mut self, w: &mut [[f64; 3]]) {
        for i in 0..self.dim {
            let c = &mut self.components[i];
            let Some(factor) = c.factor.as_mut() else { continue };
            let n_eq = c.equation.iter().filter(|&&e| e != usize::MAX).count();
            self.rhs.clear();
            self.rhs.resize(n_eq, 0.0);
            // Σ_b (w_a − w_b) = 0 → deg(a) w_a − Σ_free w_b = Σ_fixed w_b
            for &(a, b) in &self.edges {
                let (ea, eb) = (c.equation[a], c.equation[b]);
                if ea != usize::MAX && eb == usize::MAX {
                    self.rhs[ea] += w[b][i];
                }
                if eb != usize::MAX && ea == usize::MAX {
                    self.rhs[eb] += w[a][i];
                }
            }
            factor.solve_in_place(&mut self.rhs);
            for (a, &e) in c.equation.iter().enumerate() {
                if e != usize::MAX {
                    w[a][i] = self.rhs[e];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use loam_fem::element::ElementType;

    use super::*;

    /// A strip: the interface (left column) moves along the strip by 1, the far column
    /// (beyond the band) stays; the motion in between is linear in x (harmonic in a strip
    /// with free top and bottom), and a boundary condition holds its component.
    #[test]
    fn motion_decays_linearly_across_a_strip() {
        let grid = Grid::new([0.0; 3], [4.0, 1.0, 0.0], [4, 1, 1], ElementType::Quad4);
        let coords = grid.reference_coords().to_vec();
        let anchored: Vec<bool> = coords.iter().map(|x| x[0] == 0.0).collect();
        // the interface moved by 1 along x, extended with the nodes held by `prescribed`
        let extended = |prescribed: &[[bool; 3]]| {
            let mut motion =
                HarmonicExtension::new(&grid, &MotionConstraints { anchored: &anchored, prescribed, band: 3.5 });
            let mut w: Vec<[f64; 3]> = anchored.iter().map(|&a| if a { [1.0, 0.0, 0.0] } else { [0.0; 3] }).collect();
            motion.extend(&mut w);
            w
        };
        let w = extended(&vec![[false; 3]; coords.len()]);
        for (x, w) in coords.iter().zip(&w) {
            // x = 4 is beyond the band: fixed; in between w_x = 1 − x/4
            let expected = 1.0 - x[0] / 4.0;
            assert!((w[0] - expected).abs() < 1e-12, "at {x:?}: {w:?} vs {expected}");
            assert_eq!(w[1], 0.0, "the interface moves along x only");
        }
        // the bottom held in x by a boundary condition: those nodes stay
        let prescribed: Vec<[bool; 3]> = coords.iter().map(|x| [x[1] == 0.0, false, false]).collect();
        let w = extended(&prescribed);
        for (x, w) in coords.iter().zip(&w) {
            if x[1] == 0.0 && x[0] > 0.0 {
                assert_eq!(w[0], 0.0, "held at {x:?}");
            }
            assert!(w[0] >= 0.0 && w[0] <= 1.0, "maximum principle at {x:?}: {w:?}");
        }
    }
}
