//! Meshes of one element type: node coordinates, connectivity and named groups, plus the
//! structured generators used by case files (rectangles and boxes).

use std::collections::BTreeMap;

use crate::element::ElementType;

/// A mesh of a single element type. Coordinates are 3D (`z = 0` in 2D).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Element type of every cell.
    pub element: ElementType,
    /// Node coordinates.
    pub coords: Vec<[f64; 3]>,
    /// Connectivity, `element.num_nodes()` local node ids per cell, back to back.
    pub connectivity: Vec<usize>,
    /// Named node sets (e.g. Gmsh physical groups), sorted node ids.
    pub node_groups: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        self.connectivity.len() / self.element.num_nodes()
    }

    /// Nodes of cell `e`.
    pub fn cell(&self, e: usize) -> &[usize] {
        let nn = self.element.num_nodes();
        &self.connectivity[e * nn..(e + 1) * nn]
    }

    /// Boundary facets (edges in 2D, faces in 3D): facets that belong to exactly one cell,
    /// with outward orientation, as node lists.
    pub fn boundary_facets(&self) -> Vec<Vec<usize>> {
        let mut count: BTreeMap<Vec<usize>, (usize, Vec<usize>)> = BTreeMap::new();
        for e in 0..self.num_cells() {
            let cell = self.cell(e);
            for f in self.element.facets() {
                let nodes: Vec<usize> = f.iter().map(|&a| cell[a]).collect();
                let mut key = nodes.clone();
                key.sort_unstable();
                count.entry(key).and_modify(|c| c.0 += 1).or_insert((1, nodes));
            }
        }
        count.into_values().filter(|(n, _)| *n == 1).map(|(_, f)| f).collect()
    }

    /// Structured mesh of the rectangle `[x0, x0+lx] × [y0, y0+ly]` with `nx × ny` cells,
    /// as quad4 or tri3 (each quad split along alternating diagonals, which keeps the mesh
    /// free of a preferred direction).
    pub fn rectangle(origin: [f64; 2], size: [f64; 2], cells: [usize; 2], element: ElementType) -> Mesh {
        let [nx, ny] = cells;
        let mut coords = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                coords.push([
                    origin[0] + size[0] * i as f64 / nx as f64,
                    origin[1] + size[1] * j as f64 / ny as f64,
                    0.0,
                ]);
            }
        }
        let node = |i: usize, j: usize| j * (nx + 1) + i;
        let mut connectivity = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
                match element {
                    ElementType::Quad4 => connectivity.extend_from_slice(&[a, b, c, d]),
                    _ if (i + j) % 2 == 0 => connectivity.extend_from_slice(&[a, b, c, a, c, d]),
                    _ => connectivity.extend_from_slice(&[a, b, d, b, c, d]),
                }
            }
        }
        Mesh { element, coords, connectivity, node_groups: BTreeMap::new() }
    }

    /// Structured mesh of a box with `nx × ny × nz` cells, as hex8 or tet4 (each hexahedron
    /// split into six tetrahedra around its main diagonal, conforming between neighbours).
    pub fn cuboid(origin: [f64; 3], size: [f64; 3], cells: [usize; 3], element: ElementType) -> Mesh {
        let [nx, ny, nz] = cells;
        let mut coords = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    coords.push([
                        origin[0] + size[0] * i as f64 / nx as f64,
                        origin[1] + size[1] * j as f64 / ny as f64,
                        origin[2] + size[2] * k as f64 / nz as f64,
                    ]);
                }
            }
        }
        let node = |i: usize, j: usize, k: usize| (k * (ny + 1) + j) * (nx + 1) + i;
        let mut connectivity = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let h = [
                        node(i, j, k),
                        node(i + 1, j, k),
                        node(i + 1, j + 1, k),
                        node(i, j + 1, k),
                        node(i, j, k + 1),
                        node(i + 1, j, k + 1),
                        node(i + 1, j + 1, k + 1),
                        node(i, j + 1, k + 1),
                    ];
                    match element {
                        ElementType::Hex8 => connectivity.extend_from_slice(&h),
                        _ => {
                            // six positive tetrahedra sharing the diagonal h0–h6
                            for t in
                                [[0, 1, 2, 6], [0, 2, 3, 6], [0, 3, 7, 6], [0, 7, 4, 6], [0, 4, 5, 6], [0, 5, 1, 6]]
                            {
                                connectivity.extend(t.iter().map(|&a| h[a]));
                            }
                        }
                    }
                }
            }
        }
        Mesh { element, coords, connectivity, node_groups: BTreeMap::new() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signed_measure(mesh: &Mesh, e: usize) -> f64 {
        let c = mesh.cell(e);
        let x = |a: usize| nalgebra::Vector3::from(mesh.coords[c[a]]);
        match mesh.element {
            ElementType::Tri3 => (x(1) - x(0)).cross(&(x(2) - x(0))).z / 2.0,
            ElementType::Tet4 => (x(1) - x(0)).cross(&(x(2) - x(0))).dot(&(x(3) - x(0))) / 6.0,
            _ => unreachable!(),
        }
    }

    #[test]
    fn generated_simplices_are_positive_and_fill_the_domain() {
        let tri = Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [4, 3], ElementType::Tri3);
        let area: f64 = (0..tri.num_cells()).map(|e| signed_measure(&tri, e)).inspect(|a| assert!(*a > 0.0)).sum();
        assert!((area - 2.0).abs() < 1e-12);
        let tet = Mesh::cuboid([0.0; 3], [1.0, 2.0, 3.0], [2, 2, 2], ElementType::Tet4);
        let vol: f64 = (0..tet.num_cells()).map(|e| signed_measure(&tet, e)).inspect(|v| assert!(*v > 0.0)).sum();
        assert!((vol - 6.0).abs() < 1e-12);
        assert_eq!(tet.boundary_facets().len(), 6 * 4 * 2);
    }
}
