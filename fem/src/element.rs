//! Linear Lagrange elements: tri3, quad4, tet4, hex8.
//!
//! Shape functions `N_a(ξ)`, their local gradients `∂N_a/∂ξ`, Gauss rules, boundary facets
//! and the inverse isoparametric map `x ↦ ξ` (needed to place material points and monitor
//! points inside cells). Node orderings follow VTK/Gmsh (counter-clockwise in 2D).

use serde::Deserialize;

/// Largest number of nodes of an element block: 8 for the elements here (hex8), 9 and 27 for
/// the 3 × 3 and 3 × 3 × 3-node supports of a point on a smooth MPM basis in 2D and 3D (GIMP,
/// quadratic B-splines: `loam_mpm::basis`), whose blocks go through the same kernels. The
/// kernels size their scratch by the block they are given (`SMALL_BLOCK_DOFS`), so the
/// capacity costs the elements and 2D supports nothing but the size of [`crate::kernel::PointGeometry`].
pub const MAX_NODES: usize = 27;

/// Most nodes of an element here (hex8).
pub const MAX_ELEMENT_NODES: usize = 8;

/// The element shapes Loam knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementType {
    /// 3-node triangle, local coordinates (ξ, η) ≥ 0, ξ + η ≤ 1.
    Tri3,
    /// 4-node quadrilateral on [−1, 1]².
    Quad4,
    /// 4-node tetrahedron, local coordinates ≥ 0 with sum ≤ 1.
    Tet4,
    /// 8-node hexahedron on [−1, 1]³.
    Hex8,
}

/// One Gauss point: local coordinates (unused trailing entries are 0) and weight.
#[derive(Debug, Clone, Copy)]
pub struct GaussPoint {
    /// Local coordinates ξ.
    pub xi: [f64; 3],
    /// Quadrature weight (on the reference element).
    pub weight: f64,
}

const QUAD_NODES: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
const HEX_NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

impl ElementType {
    /// Number of nodes.
    pub const fn num_nodes(self) -> usize {
        match self {
            ElementType::Tri3 => 3,
            ElementType::Quad4 | ElementType::Tet4 => 4,
            ElementType::Hex8 => 8,
        }
    }

    /// Spatial dimension of the element (2 or 3).
    pub const fn dim(self) -> usize {
        match self {
            ElementType::Tri3 | ElementType::Quad4 => 2,
            ElementType::Tet4 | ElementType::Hex8 => 3,
        }
    }

    /// Name as written in case files.
    pub const fn name(self) -> &'static str {
        match self {
            ElementType::Tri3 => "tri3",
            ElementType::Quad4 => "quad4",
            ElementType::Tet4 => "tet4",
            ElementType::Hex8 => "hex8",
        }
    }

    /// Shape functions `N_a(ξ)` into `n[..num_nodes]`.
    pub fn shape_functions(self, xi: &[f64; 3], n: &mut [f64]) {
        match self {
            ElementType::Tri3 => {
                n[0] = 1.0 - xi[0] - xi[1];
                n[1] = xi[0];
                n[2] = xi[1];
            }
            ElementType::Quad4 => {
                for (a, c) in QUAD_NODES.iter().enumerate() {
                    n[a] = 0.25 * (1.0 + c[0] * xi[0]) * (1.0 + c[1] * xi[1]);
                }
            }
            ElementType::Tet4 => {
                n[0] = 1.0 - xi[0] - xi[1] - xi[2];
                n[1] = xi[0];
                n[2] = xi[1];
                n[3] = xi[2];
            }
            ElementType::Hex8 => {
                for (a, c) in HEX_NODES.iter().enumerate() {
                    n[a] = 0.125 * (1.0 + c[0] * xi[0]) * (1.0 + c[1] * xi[1]) * (1.0 + c[2] * xi[2]);
                }
            }
        }
    }

    /// Local gradients `dn[a][d] = ∂N_a/∂ξ_d`.
    pub fn shape_gradients(self, xi: &[f64; 3], dn: &mut [[f64; 3]]) {
        match self {
            ElementType::Tri3 => {
                dn[0] = [-1.0, -1.0, 0.0];
                dn[1] = [1.0, 0.0, 0.0];
                dn[2] = [0.0, 1.0, 0.0];
            }
            ElementType::Quad4 => {
                for (a, c) in QUAD_NODES.iter().enumerate() {
                    dn[a] = [0.25 * c[0] * (1.0 + c[1] * xi[1]), 0.25 * c[1] * (1.0 + c[0] * xi[0]), 0.0];
                }
            }
            ElementType::Tet4 => {
                dn[0] = [-1.0, -1.0, -1.0];
                dn[1] = [1.0, 0.0, 0.0];
                dn[2] = [0.0, 1.0, 0.0];
                dn[3] = [0.0, 0.0, 1.0];
            }
            ElementType::Hex8 => {
                for (a, c) in HEX_NODES.iter().enumerate() {
                    let (p0, p1, p2) = (1.0 + c[0] * xi[0], 1.0 + c[1] * xi[1], 1.0 + c[2] * xi[2]);
                    dn[a] = [0.125 * c[0] * p1 * p2, 0.125 * c[1] * p0 * p2, 0.125 * c[2] * p0 * p1];
                }
            }
        }
    }

    /// Gauss rule that integrates the element's stiffness exactly on an affine element:
    /// 1 point for simplices (constant strain), 2×2 / 2×2×2 for quads and hexes.
    pub fn gauss_points(self) -> Vec<GaussPoint> {
        let g = 1.0 / 3f64.sqrt();
        match self {
            ElementType::Tri3 => vec![GaussPoint { xi: [1.0 / 3.0, 1.0 / 3.0, 0.0], weight: 0.5 }],
            ElementType::Quad4 => {
                QUAD_NODES.iter().map(|c| GaussPoint { xi: [c[0] * g, c[1] * g, 0.0], weight: 1.0 }).collect()
            }
            ElementType::Tet4 => vec![GaussPoint { xi: [0.25, 0.25, 0.25], weight: 1.0 / 6.0 }],
            ElementType::Hex8 => {
                HEX_NODES.iter().map(|c| GaussPoint { xi: [c[0] * g, c[1] * g, c[2] * g], weight: 1.0 }).collect()
            }
        }
    }

    /// The rule of the mixed u–p element ([`crate::mixed_kernel`]), exact for the pressure mass
    /// `N_a N_b` on which its stabilisation acts: [`Self::gauss_points_high`] on simplices (3
    /// or 4 points), [`Self::gauss_points`] (2×2(×2)) on quads and hexes.
    pub fn gauss_points_mixed(self) -> Vec<GaussPoint> {
        match self {
            ElementType::Tri3 | ElementType::Tet4 => self.gauss_points_high(),
            ElementType::Quad4 | ElementType::Hex8 => self.gauss_points(),
        }
    }

    /// A higher-order rule (3-point triangle, 4-point tetrahedron, 3×3(×3) for quads and
    /// hexes) used for consistent mass matrices and axisymmetric elements, where the
    /// integrand is not polynomial of the stiffness' degree.
    pub fn gauss_points_high(self) -> Vec<GaussPoint> {
        match self {
            ElementType::Tri3 => [[1.0 / 6.0, 1.0 / 6.0], [2.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 2.0 / 3.0]]
                .iter()
                .map(|c| GaussPoint { xi: [c[0], c[1], 0.0], weight: 1.0 / 6.0 })
                .collect(),
            ElementType::Tet4 => {
                let (a, b) = (0.585_410_196_624_968_5, 0.138_196_601_125_010_5);
                [[b, b, b], [a, b, b], [b, a, b], [b, b, a]]
                    .iter()
                    .map(|c| GaussPoint { xi: *c, weight: 1.0 / 24.0 })
                    .collect()
            }
            ElementType::Quad4 | ElementType::Hex8 => {
                let p = [-(0.6f64.sqrt()), 0.0, 0.6f64.sqrt()];
                let w = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
                let mut out = Vec::new();
                let nz = if self == ElementType::Hex8 { 3 } else { 1 };
                for k in 0..nz {
                    for j in 0..3 {
                        for i in 0..3 {
                            let (z, wz) = if nz == 3 { (p[k], w[k]) } else { (0.0, 1.0) };
                            out.push(GaussPoint { xi: [p[i], p[j], z], weight: w[i] * w[j] * wz });
                        }
                    }
                }
                out
            }
        }
    }

    /// Local node lists of the element's boundary facets (edges in 2D, faces in 3D), ordered
    /// so that the facet normal computed from them points out of the element.
    pub fn facets(self) -> &'static [&'static [usize]] {
        match self {
            ElementType::Tri3 => &[&[0, 1], &[1, 2], &[2, 0]],
            ElementType::Quad4 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            ElementType::Tet4 => &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[0, 3, 2]],
            ElementType::Hex8 => {
                &[&[0, 3, 2, 1], &[4, 5, 6, 7], &[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[3, 0, 4, 7]]
            }
        }
    }

    /// Whether local coordinates `xi` lie inside the element (with tolerance `tol`).
    pub fn contains_local(self, xi: &[f64; 3], tol: f64) -> bool {
        match self {
            ElementType::Tri3 => xi[0] >= -tol && xi[1] >= -tol && xi[0] + xi[1] <= 1.0 + tol,
            ElementType::Tet4 => xi[0] >= -tol && xi[1] >= -tol && xi[2] >= -tol && xi[0] + xi[1] + xi[2] <= 1.0 + tol,
            ElementType::Quad4 => xi[0].abs() <= 1.0 + tol && xi[1].abs() <= 1.0 + tol,
            ElementType::Hex8 => xi.iter().all(|c| c.abs() <= 1.0 + tol),
        }
    }

    /// Jacobian `J_de = Σ_a x_a,d ∂N_a/∂ξ_e` of the isoparametric map of an element with
    /// node coordinates `coords`, from the local gradients `dn` at a point
    /// ([`ElementType::shape_gradients`]); 1 on the unused diagonal entry of 2D elements.
    pub fn jacobian(self, coords: &[[f64; 3]], dn: &[[f64; 3]]) -> nalgebra::Matrix3<f64> {
        let dim = self.dim();
        let mut jac = nalgebra::Matrix3::<f64>::identity();
        for d in 0..dim {
            jac[(d, d)] = 0.0;
        }
        for a in 0..self.num_nodes() {
            for d in 0..dim {
                for e in 0..dim {
                    jac[(d, e)] += coords[a][d] * dn[a][e];
                }
            }
        }
        jac
    }

    /// Local coordinates of node `a` of the reference element.
    pub fn node_local(self, a: usize) -> [f64; 3] {
        match self {
            ElementType::Tri3 => [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]][a],
            ElementType::Tet4 => [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]][a],
            ElementType::Quad4 => [QUAD_NODES[a][0], QUAD_NODES[a][1], 0.0],
            ElementType::Hex8 => HEX_NODES[a],
        }
    }

    /// The smallest `det J` of the isoparametric map at the element's nodes: positive for a
    /// cell that is not inverted (for the multilinear quad and hex, positive at the corners
    /// means positive throughout the 2D cell, and is the usual practical test in 3D).
    pub fn min_corner_det_j(self, coords: &[[f64; 3]]) -> f64 {
        let mut dn = [[0.0; 3]; MAX_NODES];
        (0..self.num_nodes())
            .map(|a| {
                self.shape_gradients(&self.node_local(a), &mut dn);
                self.jacobian(coords, &dn).determinant()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Centre of the reference element.
    pub fn centroid_local(self) -> [f64; 3] {
        match self {
            ElementType::Tri3 => [1.0 / 3.0, 1.0 / 3.0, 0.0],
            ElementType::Tet4 => [0.25, 0.25, 0.25],
            ElementType::Quad4 | ElementType::Hex8 => [0.0; 3],
        }
    }

    /// Inverse isoparametric map: local coordinates of the physical point `x` in the element
    /// with node coordinates `coords`, by Newton iteration on `Σ N_a(ξ) x_a = x`
    /// (exact in one step for simplices). Returns `None` if the iteration fails.
    pub fn inverse_map(self, coords: &[[f64; 3]], x: &[f64; 3]) -> Option<[f64; 3]> {
        let dim = self.dim();
        let nn = self.num_nodes();
        let mut xi = self.centroid_local();
        let mut n = [0.0; MAX_NODES];
        let mut dn = [[0.0; 3]; MAX_NODES];
        let mut last = f64::INFINITY;
        for _ in 0..30 {
            self.shape_functions(&xi, &mut n);
            self.shape_gradients(&xi, &mut dn);
            let mut r = [0.0; 3];
            r[..dim].copy_from_slice(&x[..dim]);
            for a in 0..nn {
                for d in 0..dim {
                    r[d] -= n[a] * coords[a][d];
                }
            }
            let inv = self.jacobian(coords, &dn).try_inverse()?;
            let step = inv * nalgebra::Vector3::new(r[0], r[1], r[2]);
            let mut norm = 0.0f64;
            for d in 0..dim {
                xi[d] += step[d];
                norm = norm.max(step[d].abs());
            }
            // affine elements: one step is exact; otherwise converged, or at the round-off
            // floor (small cells far from the origin: the steps stop shrinking at |x|·ε / h)
            if matches!(self, ElementType::Tri3 | ElementType::Tet4) || norm < 1e-13 || (norm < 1e-9 && norm >= last) {
                return Some(xi);
            }
            last = norm;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [ElementType; 4] = [ElementType::Tri3, ElementType::Quad4, ElementType::Tet4, ElementType::Hex8];

    #[test]
    fn partition_of_unity_and_gradients_sum_to_zero() {
        for et in ALL {
            let mut n = [0.0; MAX_NODES];
            let mut dn = [[0.0; 3]; MAX_NODES];
            let xi = [0.21, 0.17, 0.08];
            et.shape_functions(&xi, &mut n);
            et.shape_gradients(&xi, &mut dn);
            let s: f64 = n[..et.num_nodes()].iter().sum();
            assert!((s - 1.0).abs() < 1e-14, "{et:?}");
            for d in 0..et.dim() {
                let g: f64 = dn[..et.num_nodes()].iter().map(|v| v[d]).sum();
                assert!(g.abs() < 1e-14, "{et:?}");
            }
        }
    }

    #[test]
    fn gauss_weights_sum_to_reference_measure() {
        for et in ALL {
            let measure = match et {
                ElementType::Tri3 => 0.5,
                ElementType::Quad4 => 4.0,
                ElementType::Tet4 => 1.0 / 6.0,
                ElementType::Hex8 => 8.0,
            };
            for rule in [et.gauss_points(), et.gauss_points_high()] {
                let w: f64 = rule.iter().map(|g| g.weight).sum();
                assert!((w - measure).abs() < 1e-12, "{et:?}");
            }
        }
    }

    #[test]
    fn inverse_map_recovers_local_coordinates() {
        let quad = [[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [2.2, 1.5, 0.0], [-0.1, 1.2, 0.0]];
        let xi = [0.3, -0.4, 0.0];
        let mut n = [0.0; MAX_NODES];
        ElementType::Quad4.shape_functions(&xi, &mut n);
        let mut x = [0.0; 3];
        for a in 0..4 {
            for d in 0..2 {
                x[d] += n[a] * quad[a][d];
            }
        }
        let back = ElementType::Quad4.inverse_map(&quad, &x).unwrap();
        assert!((back[0] - xi[0]).abs() < 1e-12 && (back[1] - xi[1]).abs() < 1e-12);
    }
}
