//! MPM background grids: structured (quad4 / tri3 in 2D, hex8 in 3D, optionally rotated) with
//! O(1) point location by lattice arithmetic, or any mesh (e.g. from Gmsh: tri3, quad4, tet4,
//! hex8) with the bin-based search of Kratos' MPM application: a uniform bin lattice over the
//! bounding box lists the cells whose bounding boxes overlap each bin, and a point is tested
//! only against the cells of its bin.
//!
//! The grid keeps its node coordinates as data (a [`Mesh`]); local coordinates come from the
//! element's inverse map (Newton), or, in simplex cells (tri3, tet4), whose isoparametric map
//! is affine, from that map's inverse `ξ = J⁻¹(x − x₀)`, kept per cell with `det J` when the
//! grid is built (the cells do not move afterwards): one 3×3 product per located point, and
//! the shape-function gradients of every point in the cell from the same `J⁻¹`. (Rectangular
//! quad cells are affine too, but there the Newton path is kept: the affine local coordinates
//! differ from it by round-off only, and the MPM Cam Clay localisation run,
//! `biaxial_mcc_mpm`, is sensitive enough to that to stop at 0.08 m of platen travel instead
//! of 0.13 m.)

use loam_fem::element::{ElementType, MAX_NODES};
use loam_fem::kernel::CellMap;
use loam_fem::mesh::Mesh;
use nalgebra::Vector3;

/// How a grid finds the cell that holds a point.
#[derive(Debug, Clone)]
enum Locator {
    /// Structured lattice: cell index by arithmetic.
    Lattice {
        origin: [f64; 3],
        spacing: [f64; 3],
        cells: [usize; 3],
        /// `(cos θ, sin θ)` of the grid's rotation about `origin` (2D).
        rotation: (f64, f64),
    },
    /// Uniform bins over the bounding box, each listing the cells overlapping it (CSR).
    Bins { lower: [f64; 3], size: [f64; 3], bins: [usize; 3], start: Vec<usize>, cells: Vec<u32> },
}

/// The isoparametric map of an affine cell, `x = x₀ + J ξ`.
#[derive(Debug, Clone, Copy)]
struct AffineCell {
    /// `x₀ = x(ξ = 0)`.
    origin: [f64; 3],
    map: CellMap,
}

/// An MPM background grid.
#[derive(Debug, Clone)]
pub struct Grid {
    /// The grid as a mesh (node coordinates and cells).
    pub mesh: Mesh,
    locator: Locator,
    /// Per cell, its affine map (`None` where the map is not affine).
    affine: Vec<Option<AffineCell>>,
}

impl Grid {
    /// A grid of `cells` cells over the box `origin + [0, size]` (2D: first two entries).
    pub fn new(origin: [f64; 3], size: [f64; 3], cells: [usize; 3], element: ElementType) -> Self {
        let mesh = match element.dim() {
            2 => Mesh::rectangle([origin[0], origin[1]], [size[0], size[1]], [cells[0], cells[1]], element),
            _ => Mesh::cuboid(origin, size, cells, element),
        };
        let cells = if element.dim() == 2 { [cells[0], cells[1], 1] } else { cells };
        let spacing = [size[0] / cells[0] as f64, size[1] / cells[1] as f64, size[2] / cells[2] as f64];
        Self::with_locator(mesh, Locator::Lattice { origin, spacing, cells, rotation: (1.0, 0.0) })
    }

    /// A grid on any mesh, located by bins about one cell in size.
    pub fn unstructured(mesh: Mesh) -> Self {
        let dim = mesh.element.dim();
        let (mut lower, mut upper) = ([0.0; 3], [0.0; 3]);
        for d in 0..dim {
            lower[d] = mesh.coords.iter().map(|c| c[d]).fold(f64::MAX, f64::min);
            upper[d] = mesh.coords.iter().map(|c| c[d]).fold(f64::MIN, f64::max);
        }
        let extent: Vec<f64> = (0..dim).map(|d| (upper[d] - lower[d]).max(1e-300)).collect();
        let volume: f64 = extent.iter().product();
        let ncells = mesh.num_cells().max(1) as f64;
        let h = (volume / ncells).powf(1.0 / dim as f64);
        let mut bins = [1usize; 3];
        let mut size = [1.0; 3];
        for d in 0..dim {
            bins[d] = ((extent[d] / h).ceil() as usize).clamp(1, 1 << 16);
            size[d] = extent[d] / bins[d] as f64;
        }
        let nbins = bins[0] * bins[1] * bins[2];
        let bin_range = |lo: f64, hi: f64, d: usize| {
            let a = (((lo - lower[d]) / size[d]).floor().max(0.0) as usize).min(bins[d] - 1);
            let b = (((hi - lower[d]) / size[d]).floor().max(0.0) as usize).min(bins[d] - 1);
            a..=b
        };
        let mut lists: Vec<(usize, u32)> = Vec::new();
        for c in 0..mesh.num_cells() {
            let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
            for d in 0..dim {
                lo[d] = mesh.cell(c).iter().map(|&a| mesh.coords[a][d]).fold(f64::MAX, f64::min);
                hi[d] = mesh.cell(c).iter().map(|&a| mesh.coords[a][d]).fold(f64::MIN, f64::max);
            }
            let ks = if dim == 3 { bin_range(lo[2], hi[2], 2) } else { 0..=0 };
            for k in ks {
                for j in bin_range(lo[1], hi[1], 1) {
                    for i in bin_range(lo[0], hi[0], 0) {
                        lists.push(((k * bins[1] + j) * bins[0] + i, c as u32));
                    }
                }
            }
        }
        lists.sort_unstable();
        let mut start = vec![0usize; nbins + 1];
        for &(b, _) in &lists {
            start[b + 1] += 1;
        }
        for b in 0..nbins {
            start[b + 1] += start[b];
        }
        let cells = lists.into_iter().map(|(_, c)| c).collect();
        Self::with_locator(mesh, Locator::Bins { lower, size, bins, start, cells })
    }

    /// A 2D grid as [`Grid::new`], rotated counter-clockwise by `angle` (radians)
    /// about `origin`: its cell edges, and so its boundaries, are inclined.
    pub fn rotated(origin: [f64; 3], size: [f64; 3], cells: [usize; 3], element: ElementType, angle: f64) -> Self {
        let mut g = Self::new(origin, size, cells, element);
        let (c, s) = (angle.cos(), angle.sin());
        for x in &mut g.mesh.coords {
            let (dx, dy) = (x[0] - origin[0], x[1] - origin[1]);
            x[0] = origin[0] + c * dx - s * dy;
            x[1] = origin[1] + s * dx + c * dy;
        }
        if let Locator::Lattice { rotation, .. } = &mut g.locator {
            *rotation = (c, s);
        }
        Self::with_locator(g.mesh, g.locator)
    }

    fn with_locator(mesh: Mesh, locator: Locator) -> Self {
        let affine = (0..mesh.num_cells()).map(|c| affine_cell(&mesh, c)).collect();
        Self { mesh, locator, affine }
    }

    /// Local coordinates of `x` in `cell` (possibly outside the reference element), or `None`
    /// if the cell's map is singular.
    pub fn local_coordinates(&self, cell: usize, x: &[f64; 3]) -> Option<[f64; 3]> {
        match &self.affine[cell] {
            Some(a) => {
                let d = Vector3::new(x[0] - a.origin[0], x[1] - a.origin[1], x[2] - a.origin[2]);
                let xi = a.map.jacobian_inverse * d;
                let mut out = [0.0; 3];
                out[..self.mesh.element.dim()].copy_from_slice(&xi.as_slice()[..self.mesh.element.dim()]);
                Some(out)
            }
            None => {
                let coords = self.cell_coords(cell);
                self.mesh.element.inverse_map(&coords[..self.mesh.element.num_nodes()], x)
            }
        }
    }

    /// The constant map of `cell` if it is affine (see the module doc).
    pub fn cell_map(&self, cell: usize) -> Option<&CellMap> {
        self.affine[cell].as_ref().map(|a| &a.map)
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
        let test = |cell: usize| {
            self.local_coordinates(cell, x).filter(|xi| element.contains_local(xi, 1e-9)).map(|xi| (cell, xi))
        };
        let (origin, spacing, cells, rotation) = match &self.locator {
            Locator::Lattice { origin, spacing, cells, rotation } => (origin, spacing, cells, rotation),
            Locator::Bins { lower, size, bins, start, cells } => {
                let mut b = [0usize; 3];
                for d in 0..dim {
                    let s = (x[d] - lower[d]) / size[d];
                    if !(s >= -1e-9 && s <= bins[d] as f64 * (1.0 + 1e-12) + 1e-9) {
                        return None;
                    }
                    b[d] = (s.floor().max(0.0) as usize).min(bins[d] - 1);
                }
                let bin = (b[2] * bins[1] + b[1]) * bins[0] + b[0];
                return cells[start[bin]..start[bin + 1]].iter().find_map(|&c| test(c as usize));
            }
        };
        let (c, s) = *rotation;
        let (dx, dy) = (x[0] - origin[0], x[1] - origin[1]);
        let lattice_x = [origin[0] + c * dx + s * dy, origin[1] - s * dx + c * dy, x[2]];
        let mut ijk = [0usize; 3];
        for d in 0..dim {
            let s = (lattice_x[d] - origin[d]) / spacing[d];
            if !(s >= -1e-9 && s <= cells[d] as f64 * (1.0 + 1e-12) + 1e-9) {
                return None;
            }
            ijk[d] = (s.floor().max(0.0) as usize).min(cells[d] - 1);
        }
        let lattice = (ijk[2] * cells[1] + ijk[1]) * cells[0] + ijk[0];
        let candidates: &[usize] = match element {
            ElementType::Tri3 => &[2 * lattice, 2 * lattice + 1],
            _ => &[lattice],
        };
        candidates.iter().find_map(|&cell| test(cell))
    }
}

/// The map `x = x₀ + J ξ` of a simplex `cell` (see the module doc for quads).
fn affine_cell(mesh: &Mesh, cell: usize) -> Option<AffineCell> {
    let element = mesh.element;
    if !matches!(element, ElementType::Tri3 | ElementType::Tet4) {
        return None;
    }
    let coords: Vec<[f64; 3]> = mesh.cell(cell).iter().map(|&a| mesh.coords[a]).collect();
    let mut dn = [[0.0; 3]; MAX_NODES];
    element.shape_gradients(&element.centroid_local(), &mut dn);
    let map = CellMap::at(element, &coords, &dn).ok()?;
    // ξ = 0 is node 0 of a simplex
    let origin = coords[0];
    Some(AffineCell { origin, map })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_points_in_quads_triangles_and_hexes() {
        for element in [ElementType::Quad4, ElementType::Tri3] {
            let g = Grid::new([0.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], element);
            let (cell, xi) = g.locate(&[1.3, 0.7, 0.0]).unwrap();
            let coords: Vec<[f64; 3]> = g.mesh.cell(cell).iter().map(|&a| g.mesh.coords[a]).collect();
            let mut n = [0.0; 8];
            element.shape_functions(&xi, &mut n);
            let x: f64 = (0..element.num_nodes()).map(|a| n[a] * coords[a][0]).sum();
            assert!((x - 1.3).abs() < 1e-12);
            assert!(g.locate(&[2.5, 0.5, 0.0]).is_none());
            assert!(g.locate(&[2.0, 1.0, 0.0]).is_some(), "upper corner belongs to the grid");
        }
        let r = Grid::rotated([1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4, 0.5);
        let x = [1.0 + 1.25 * 0.5f64.cos() - 0.75 * 0.5f64.sin(), 1.25 * 0.5f64.sin() + 0.75 * 0.5f64.cos(), 0.0];
        let (cell, xi) = r.locate(&x).unwrap();
        assert_eq!(cell, 4 + 2);
        assert!(xi[0].abs() < 1e-12 && xi[1].abs() < 1e-12, "{xi:?}");
        // the same points found by the bin search on the same meshes (unstructured path)
        for (mesh, x) in [
            (Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [4, 2], ElementType::Tri3), [1.3, 0.7, 0.0]),
            (Mesh::cuboid([0.0; 3], [1.0; 3], [3, 2, 2], ElementType::Tet4), [0.71, 0.33, 0.52]),
        ] {
            let structured_cells = mesh.num_cells();
            let g = Grid::unstructured(mesh);
            let (cell, xi) = g.locate(&x).expect("inside");
            assert!(cell < structured_cells);
            let mut n = [0.0; 8];
            g.mesh.element.shape_functions(&xi, &mut n);
            let coords = g.cell_coords(cell);
            for d in 0..g.mesh.element.dim() {
                let v: f64 = (0..g.mesh.element.num_nodes()).map(|a| n[a] * coords[a][d]).sum();
                assert!((v - x[d]).abs() < 1e-12);
            }
            assert!(g.locate(&[5.0, 0.5, 0.5]).is_none());
        }
        let g = Grid::new([0.0; 3], [1.0, 1.0, 1.0], [2, 2, 2], ElementType::Hex8);
        let (cell, xi) = g.locate(&[0.75, 0.25, 0.6]).unwrap();
        assert_eq!(cell, 4 + 1);
        assert!((xi[0] - 0.0).abs() < 1e-12 && (xi[2] + 0.6).abs() < 1e-12);
    }

    /// The per-cell affine maps of simplices give the local coordinates of the Newton inverse
    /// map; quad and hex cells keep the Newton path.
    #[test]
    fn affine_cells_match_the_inverse_map() {
        let grids = [
            Grid::rotated([1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4, 0.5),
            Grid::rotated([1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Tri3, 0.5),
            Grid::new([0.0; 3], [1.0, 1.0, 1.0], [2, 2, 2], ElementType::Hex8),
            Grid::unstructured(Mesh::cuboid([0.0; 3], [1.0; 3], [3, 2, 2], ElementType::Tet4)),
        ];
        let x = [0.93, 0.41, 0.37];
        for g in &grids {
            let element = g.mesh.element;
            for cell in 0..g.mesh.num_cells() {
                let coords = g.cell_coords(cell);
                let newton = element.inverse_map(&coords[..element.num_nodes()], &x).unwrap();
                let local = g.local_coordinates(cell, &x).unwrap();
                for d in 0..element.dim() {
                    assert!((local[d] - newton[d]).abs() < 1e-12, "{element:?} cell {cell}: {local:?} vs {newton:?}");
                }
                let simplex = matches!(element, ElementType::Tri3 | ElementType::Tet4);
                assert_eq!(g.cell_map(cell).is_some(), simplex, "{element:?} cell {cell}");
            }
        }
    }
}
