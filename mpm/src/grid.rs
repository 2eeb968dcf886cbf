//! Structured background grids (quad4 / tri3 in 2D, hex8 in 3D) with O(1) point location.
//!
//! The grid keeps its node coordinates as data (a [`Mesh`]), so a later coupling can move
//! interface nodes; point location uses the lattice arithmetic for the cell and the
//! element's inverse map for the local coordinates.

use loam_fem::element::{ElementType, MAX_NODES};
use loam_fem::mesh::Mesh;

/// A structured background grid.
#[derive(Debug, Clone)]
pub struct StructuredGrid {
    /// The grid as a mesh (node coordinates and cells).
    pub mesh: Mesh,
    origin: [f64; 3],
    spacing: [f64; 3],
    cells: [usize; 3],
    /// `(cos θ, sin θ)` of the grid's rotation about `origin` (2D).
    rotation: (f64, f64),
}

impl StructuredGrid {
    /// A grid of `cells` cells over the box `origin + [0, size]` (2D: first two entries).
    pub fn new(origin: [f64; 3], size: [f64; 3], cells: [usize; 3], element: ElementType) -> Self {
        let mesh = match element.dim() {
            2 => Mesh::rectangle([origin[0], origin[1]], [size[0], size[1]], [cells[0], cells[1]], element),
            _ => Mesh::cuboid(origin, size, cells, element),
        };
        let cells = if element.dim() == 2 { [cells[0], cells[1], 1] } else { cells };
        let spacing = [size[0] / cells[0] as f64, size[1] / cells[1] as f64, size[2] / cells[2] as f64];
        Self { mesh, origin, spacing, cells, rotation: (1.0, 0.0) }
    }

    /// A 2D grid as [`StructuredGrid::new`], rotated counter-clockwise by `angle` (radians)
    /// about `origin`: its cell edges, and so its boundaries, are inclined.
    pub fn rotated(origin: [f64; 3], size: [f64; 3], cells: [usize; 3], element: ElementType, angle: f64) -> Self {
        let mut g = Self::new(origin, size, cells, element);
        let (c, s) = (angle.cos(), angle.sin());
        for x in &mut g.mesh.coords {
            let (dx, dy) = (x[0] - origin[0], x[1] - origin[1]);
            x[0] = origin[0] + c * dx - s * dy;
            x[1] = origin[1] + s * dx + c * dy;
        }
        g.rotation = (c, s);
        g
    }

    /// Cell size along each axis.
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
    }

    /// Node coordinates of `cell` (the first `num_nodes` entries), without allocating.
    pub fn cell_coords(&self, cell: usize) -> [[f64; 3]; MAX_NODES] {
        let mut coords = [[0.0; 3]; MAX_NODES];
        for (c, &a) in coords.iter_mut().zip(self.mesh.cell(cell)) {
            *c = self.mesh.coords[a];
        }
        coords
    }

    /// Cells sharing a node with any cell of `cells` (`cells` included), ascending: the
    /// set grown by one ring. `cells` must be ascending.
    pub fn dilate(&self, cells: &[usize]) -> Vec<usize> {
        let mesh = &self.mesh;
        let mut node_mark = vec![false; mesh.coords.len()];
        for &c in cells {
            for &a in mesh.cell(c) {
                node_mark[a] = true;
            }
        }
        (0..mesh.num_cells()).filter(|&c| mesh.cell(c).iter().any(|&a| node_mark[a])).collect()
    }

    /// Cell containing `x` and the local coordinates of `x` in it, or `None` outside.
    pub fn locate(&self, x: &[f64; 3]) -> Option<(usize, [f64; 3])> {
        let element = self.mesh.element;
        let dim = element.dim();
        let (c, s) = self.rotation;
        let (dx, dy) = (x[0] - self.origin[0], x[1] - self.origin[1]);
        let lattice_x = [self.origin[0] + c * dx + s * dy, self.origin[1] - s * dx + c * dy, x[2]];
        let mut ijk = [0usize; 3];
        for d in 0..dim {
            let s = (lattice_x[d] - self.origin[d]) / self.spacing[d];
            if !(s >= -1e-9 && s <= self.cells[d] as f64 * (1.0 + 1e-12) + 1e-9) {
                return None;
            }
            ijk[d] = (s.floor().max(0.0) as usize).min(self.cells[d] - 1);
        }
        let lattice = (ijk[2] * self.cells[1] + ijk[1]) * self.cells[0] + ijk[0];
        let candidates: &[usize] = match element {
            ElementType::Tri3 => &[2 * lattice, 2 * lattice + 1],
            _ => &[lattice],
        };
        let nn = element.num_nodes();
        for &cell in candidates {
            let coords = self.cell_coords(cell);
            if let Some(xi) = element.inverse_map(&coords[..nn], x) {
                if element.contains_local(&xi, 1e-9) {
                    return Some((cell, xi));
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_points_in_quads_triangles_and_hexes() {
        for element in [ElementType::Quad4, ElementType::Tri3] {
            let g = StructuredGrid::new([0.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], element);
            let (cell, xi) = g.locate(&[1.3, 0.7, 0.0]).unwrap();
            let coords: Vec<[f64; 3]> = g.mesh.cell(cell).iter().map(|&a| g.mesh.coords[a]).collect();
            let mut n = [0.0; 8];
            element.shape_functions(&xi, &mut n);
            let x: f64 = (0..element.num_nodes()).map(|a| n[a] * coords[a][0]).sum();
            assert!((x - 1.3).abs() < 1e-12);
            assert!(g.locate(&[2.5, 0.5, 0.0]).is_none());
            assert!(g.locate(&[2.0, 1.0, 0.0]).is_some(), "upper corner belongs to the grid");
        }
        let r = StructuredGrid::rotated([1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4, 0.5);
        let x = [1.0 + 1.25 * 0.5f64.cos() - 0.75 * 0.5f64.sin(), 1.25 * 0.5f64.sin() + 0.75 * 0.5f64.cos(), 0.0];
        let (cell, xi) = r.locate(&x).unwrap();
        assert_eq!(cell, 4 + 2);
        assert!(xi[0].abs() < 1e-12 && xi[1].abs() < 1e-12, "{xi:?}");
        let g = StructuredGrid::new([0.0; 3], [1.0, 1.0, 1.0], [2, 2, 2], ElementType::Hex8);
        let (cell, xi) = g.locate(&[0.75, 0.25, 0.6]).unwrap();
        assert_eq!(cell, 4 + 1);
        assert!((xi[0] - 0.0).abs() < 1e-12 && (xi[2] + 0.6).abs() < 1e-12);
    }
}
