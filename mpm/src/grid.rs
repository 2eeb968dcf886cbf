//! MPM background grids: structured (quad4 / tri3 in 2D, hex8 in 3D, optionally rotated) with
//! O(1) point location by lattice arithmetic, or any mesh (e.g. from Gmsh: tri3, quad4, tet4,
//! hex8) with the bin-based search of Kratos' MPM application: a uniform bin lattice over the
//! bounding box lists the cells whose bounding boxes overlap each bin, and a point is tested
//! only against the cells of its bin.
//!
//! The grid keeps its node coordinates as data (a [`Mesh`]) in two configurations: the
//! **reference** positions, where the grid returns at the start of every step, and the
//! **current** positions of the step, which differ from them only where the grid is attached
//! to a structure (interface nodes move with it, a band of nodes around by a mesh-motion
//! rule: [`Grid::move_nodes`]). Location first asks the reference locator (lattice or bins)
//! for the cell, which is exact for cells that did not move; cells that moved are searched in
//! bins over their current positions, rebuilt when the grid moves. Cells inside a structure
//! are removed ([`Grid::without_cells`]); a structured lattice keeps its arithmetic through an
//! index from lattice cells to the remaining ones.
//!
//! Local coordinates come from the element's inverse map (Newton), or, in simplex cells
//! (tri3, tet4), whose isoparametric map is affine, from that map's inverse
//! `ξ = J⁻¹(x − x₀)`, kept per cell with `det J` (recomputed for cells that move): one 3×3
//! product per located point, and the shape-function gradients of every point in the cell
//! from the same `J⁻¹`. Parallelogram quads and parallelepiped hexes (every cell of a
//! structured grid, rotated or not, until it moves) are affine too and take the same path.

use loam_fem::element::{ElementType, GaussPoint, MAX_ELEMENT_NODES, MAX_NODES};
use loam_fem::formulation::Formulation;
use loam_fem::kernel::{point_geometry_into, CellMap, KernelError, PointGeometry};
use loam_fem::mesh::Mesh;
use loam_fem::mixed_kernel::CellProjection;

use crate::basis::{Basis, SmoothLattice, SupportValues};
use nalgebra::Vector3;

/// An empty integration point (storage for a cell's or support's Gauss rule).
pub const NO_GEOMETRY: PointGeometry =
    PointGeometry { shape: [0.0; MAX_NODES], gradient: [[0.0; 3]; MAX_NODES], weight: 0.0, radius: 0.0 };

/// Newton iterations that invert the map of a moved smooth lattice (it converges in 2–4
/// where the motion is smooth; one where the cells are parallelograms).
const MAP_INVERSION_ITERATIONS: usize = 12;

/// Marker of a lattice cell without a grid cell (removed: inside a structure).
const NO_CELL: u32 = u32::MAX;

/// Uniform bins over a box, each listing the cells whose bounding boxes overlap it (CSR).
#[derive(Debug, Clone)]
struct Bins {
    lower: [f64; 3],
    size: [f64; 3],
    bins: [usize; 3],
    start: Vec<usize>,
    cells: Vec<u32>,
}

impl Bins {
    /// Bins about one cell in size over the bounding box of `cells` of `mesh`.
    fn new(mesh: &Mesh, cells: &[usize]) -> Self {
        let dim = mesh.element.dim();
        let (mut lower, mut upper) = ([0.0; 3], [0.0; 3]);
        for d in 0..dim {
            let coords = || cells.iter().flat_map(|&c| mesh.cell(c)).map(|&a| mesh.coords[a][d]);
            lower[d] = coords().fold(f64::MAX, f64::min);
            upper[d] = coords().fold(f64::MIN, f64::max);
        }
        let extent: Vec<f64> = (0..dim).map(|d| (upper[d] - lower[d]).max(1e-300)).collect();
        let volume: f64 = extent.iter().product();
        let ncells = cells.len().max(1) as f64;
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
        for &c in cells {
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
        Self { lower, size, bins, start, cells }
    }

    /// The cells listed in the bin holding `x` (none outside the box).
    fn candidates(&self, x: &[f64; 3], dim: usize) -> &[u32] {
        let mut b = [0usize; 3];
        for d in 0..dim {
            let s = (x[d] - self.lower[d]) / self.size[d];
            if !(s >= -1e-9 && s <= self.bins[d] as f64 * (1.0 + 1e-12) + 1e-9) {
                return &[];
            }
            b[d] = (s.floor().max(0.0) as usize).min(self.bins[d] - 1);
        }
        let bin = (b[2] * self.bins[1] + b[1]) * self.bins[0] + b[0];
        &self.cells[self.start[bin]..self.start[bin + 1]]
    }
}

/// How a grid finds the cell that holds a point in its reference configuration.
#[derive(Debug, Clone)]
enum Locator {
    /// Structured lattice: cell index by arithmetic.
    Lattice {
        origin: [f64; 3],
        spacing: [f64; 3],
        cells: [usize; 3],
        /// `(cos θ, sin θ)` of the grid's rotation about `origin` (2D).
        rotation: (f64, f64),
        /// Grid cell of each cell of the full lattice (tri3: two per lattice cell), or
        /// [`NO_CELL`]; `None` while no cell has been removed (the identity).
        cell_index: Option<Vec<u32>>,
    },
    /// Bins over the reference positions.
    Bins(Bins),
}

/// A grid function at a point in 2D: value, gradient and second derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GridFunction {
    /// `N_I(x)`.
    pub value: f64,
    /// `∇N_I(x)`.
    pub gradient: [f64; 2],
    /// `[∂xx, ∂xy, ∂yy] N_I(x)`.
    pub hessian: [f64; 3],
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
    /// The grid as a mesh: node coordinates in the current configuration of the step, and
    /// the cells.
    pub mesh: Mesh,
    /// Node coordinates in the reference configuration.
    reference: Vec<[f64; 3]>,
    locator: Locator,
    /// Per cell, its affine map in the current configuration (`None` where the map is not
    /// affine).
    affine: Vec<Option<AffineCell>>,
    /// Per cell, whether a node of it is away from its reference position.
    moved: Vec<bool>,
    /// Bins over the moved cells in their current positions (`None` if none moved).
    moved_bins: Option<Bins>,
    /// The supports of a smooth basis (`None`: the cells' linear functions).
    smooth: Option<SmoothLattice>,
    /// The cells' [`ElementType::gauss_points_mixed`].
    mixed_rule: Vec<GaussPoint>,
}

/// Why a grid cannot carry a smooth basis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum BasisError {
    /// The grid is not a structured lattice of quad4 (2D) or hex8 (3D) cells.
    #[error("a smooth basis needs a structured grid of quad4 (2D) or hex8 (3D) cells (tri3, tet4 and unstructured grids keep \"linear\")")]
    NotQuadLattice,
    /// The lattice is rotated.
    #[error("a smooth basis needs a grid whose cell edges follow x and y (not rotated)")]
    Rotated,
    /// Cells were removed before the basis was set.
    #[error("a smooth basis is set on the whole lattice, before the cells inside a structure are removed")]
    Holes,
    /// Fewer than two cells in a direction.
    #[error("a smooth basis needs two or more cells in each direction")]
    TooFewCells,
}

/// A cell that the motion of the grid would invert.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvertedCell {
    /// Cell index.
    pub cell: usize,
    /// Its centre in the reference configuration.
    pub centre: [f64; 3],
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
        Self::with_locator(mesh, Locator::Lattice { origin, spacing, cells, rotation: (1.0, 0.0), cell_index: None })
    }

    /// A grid on any mesh, located by bins about one cell in size.
    pub fn unstructured(mesh: Mesh) -> Self {
        let all: Vec<usize> = (0..mesh.num_cells()).collect();
        let bins = Bins::new(&mesh, &all);
        Self::with_locator(mesh, Locator::Bins(bins))
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
        let moved = vec![false; mesh.num_cells()];
        let mixed_rule = mesh.element.gauss_points_mixed();
        Self {
            reference: mesh.coords.clone(),
            mesh,
            locator,
            affine,
            moved,
            moved_bins: None,
            smooth: None,
            mixed_rule,
        }
    }

    /// Gives the grid the shape functions `basis` ([`crate::basis`]): a smooth one needs a
    /// structured, unrotated, fixed lattice of quad4 (2D) or hex8 (3D) cells with two or more
    /// cells per direction.
    pub fn set_basis(&mut self, basis: Basis) -> Result<(), BasisError> {
        if !basis.is_smooth() {
            self.smooth = None;
            return Ok(());
        }
        let Locator::Lattice { origin, spacing, cells, rotation, cell_index } = &self.locator else {
            return Err(BasisError::NotQuadLattice);
        };
        if !matches!(self.mesh.element, ElementType::Quad4 | ElementType::Hex8) {
            return Err(BasisError::NotQuadLattice);
        }
        if *rotation != (1.0, 0.0) {
            return Err(BasisError::Rotated);
        }
        if cell_index.is_some() {
            return Err(BasisError::Holes);
        }
        let dim = self.mesh.element.dim();
        if cells[..dim].iter().any(|&n| n < 2) {
            return Err(BasisError::TooFewCells);
        }
        let lattice = SmoothLattice::new(basis, dim, *origin, *spacing, *cells);
        self.smooth = Some(lattice);
        Ok(())
    }

    /// The spacing of a smooth basis's lattice (its reference cells' sides), `None` on the
    /// linear basis.
    pub fn lattice_spacing(&self) -> Option<[f64; 3]> {
        self.smooth.as_ref().map(|lattice| lattice.spacing())
    }

    /// The grid's shape functions.
    pub fn basis(&self) -> Basis {
        self.smooth.as_ref().map_or(Basis::Linear, SmoothLattice::basis)
    }

    /// Number of supports: the blocks that group the material points whose functions reach
    /// the same nodes (the cells on the linear basis; 3 × 3 or 3 × 3 × 3-node windows on a
    /// smooth one).
    pub fn num_supports(&self) -> usize {
        self.smooth.as_ref().map_or_else(|| self.mesh.num_cells(), SmoothLattice::num_supports)
    }

    /// The grid nodes of support `s`.
    pub fn support(&self, s: usize) -> &[usize] {
        match &self.smooth {
            Some(lattice) => lattice.support(s),
            None => self.mesh.cell(s),
        }
    }

    /// Nodes per support.
    pub fn support_len(&self) -> usize {
        match &self.smooth {
            Some(lattice) => lattice.support_len(),
            None => self.mesh.element.num_nodes(),
        }
    }

    /// Supports sharing a node with any of `supports` (ascending, included); on a smooth
    /// basis with `narrow`, only those whose windows are one node row from one of `supports`
    /// ([`SmoothLattice::dilate`]: the ring half as wide).
    pub fn dilate_supports(&self, supports: &[usize], narrow: bool) -> Vec<usize> {
        match &self.smooth {
            Some(lattice) => lattice.dilate(supports, if narrow { 1 } else { 2 }),
            None => self.dilate(supports),
        }
    }

    /// The support of a material point at `x` whose domain has the half lengths `half_size`
    /// along the axes (GIMP's `l_p,d`) and its shape functions and gradients in the grid's
    /// current configuration (weight: the caller's), or `None` outside the grid.
    pub fn point_functions(
        &self,
        x: &[f64; 3],
        half_size: [f64; 3],
        formulation: Formulation,
        thickness: f64,
    ) -> Option<(usize, PointGeometry)> {
        let mut g = PointGeometry::default();
        self.point_functions_into(x, half_size, formulation, thickness, &mut g).map(|support| (support, g))
    }

    /// [`Grid::point_functions`] written into `g` (its support's entries; on the linear basis
    /// without a copy of the whole record, which point location does for every point of a
    /// step), returning the support.
    pub fn point_functions_into(
        &self,
        x: &[f64; 3],
        half_size: [f64; 3],
        formulation: Formulation,
        thickness: f64,
        g: &mut PointGeometry,
    ) -> Option<usize> {
        if let Some(lattice) = &self.smooth {
            let (support, geometry) = if self.has_moved() {
                let s = self.moved_lattice_coordinates(lattice, x)?;
                let (support, geometry, _) =
                    self.moved_lattice_functions(lattice, s, lattice.in_cells(half_size), formulation);
                (support, geometry)
            } else {
                lattice.evaluate(x, half_size, formulation)?
            };
            *g = geometry;
            return Some(support);
        }
        let (cell, xi) = self.locate(x)?;
        let element = self.mesh.element;
        let coords = self.cell_coords(cell);
        point_geometry_into(
            g,
            element,
            formulation,
            thickness,
            &coords[..element.num_nodes()],
            &xi,
            1.0,
            self.cell_map(cell),
        )
        .expect("located points lie in cells that are not inverted");
        Some(cell)
    }

    /// The grid functions at `x` (2D) with their first and second derivatives, per node
    /// (grid numbering) of the support holding `x`, in the grid's current configuration;
    /// `None` outside the grid, in 3D, and for a smooth basis on a lattice that moved or lost
    /// cells. A smooth basis is evaluated as at a point without a domain (GIMP: `l = 0`, the
    /// hat, whose kinks carry no second derivative).
    ///
    /// On a linear cell the second derivatives follow from differentiating `∇_ξ N = Jᵀ ∇_x N`
    /// once more (`J = ∂x/∂ξ`): `∂²N/∂ξ_k∂ξ_l = (Jᵀ ∇²_x N J)_kl + ∇_x N · ∂²x/∂ξ_k∂ξ_l`, so
    ///
    /// ```text
    /// ∇²_x N = J⁻ᵀ (∇²_ξ N − Σ_m ∂_m N ∇²_ξ x_m) J⁻¹,
    /// ```
    ///
    /// where quad4 has only the mixed local derivatives `∂²N_a/∂ξ∂η = ¼ ξ_a η_a` and
    /// `∂²x/∂ξ∂η = Σ_a x_a ∂²N_a/∂ξ∂η` (zero on a parallelogram: then `∂_xy N` is the
    /// bilinear function's only second derivative), and tri3 none.
    pub fn functions_with_hessian(&self, x: &[f64; 3]) -> Option<Vec<(usize, GridFunction)>> {
        let element = self.mesh.element;
        if element.dim() != 2 {
            return None;
        }
        if let Some(lattice) = &self.smooth {
            if self.has_moved() {
                return None;
            }
            let s = lattice.lattice_coordinates(x)?;
            let (support, values) = lattice.functions_with_hessian(s, [0.0; 3])?;
            let h = lattice.spacing();
            let nodes = lattice.support(support);
            return Some(
                nodes
                    .iter()
                    .zip(values)
                    .map(|(&a, v)| {
                        let f = GridFunction {
                            value: v[0],
                            gradient: [v[1] / h[0], v[2] / h[1]],
                            hessian: [v[3] / (h[0] * h[0]), v[4] / (h[0] * h[1]), v[5] / (h[1] * h[1])],
                        };
                        (a, f)
                    })
                    .collect(),
            );
        }
        let (cell, xi) = self.locate(x)?;
        let coords = self.cell_coords(cell);
        let nn = element.num_nodes();
        let mut n = [0.0; MAX_NODES];
        let mut dn = [[0.0; 3]; MAX_NODES];
        element.shape_functions(&xi, &mut n);
        element.shape_gradients(&xi, &mut dn);
        // ∂²N_a/∂ξ∂η: dN/dξ is linear in η on quad4
        let mut mixed = [0.0; MAX_NODES];
        if element == ElementType::Quad4 {
            let (mut up, mut down) = ([[0.0; 3]; MAX_NODES], [[0.0; 3]; MAX_NODES]);
            element.shape_gradients(&[xi[0], 1.0, 0.0], &mut up);
            element.shape_gradients(&[xi[0], -1.0, 0.0], &mut down);
            for a in 0..nn {
                mixed[a] = 0.5 * (up[a][0] - down[a][0]);
            }
        }
        let (mut j, mut d) = ([[0.0; 2]; 2], [0.0; 2]);
        for a in 0..nn {
            for m in 0..2 {
                for k in 0..2 {
                    j[m][k] += coords[a][m] * dn[a][k];
                }
                d[m] += coords[a][m] * mixed[a];
            }
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        // J⁻¹ (ξ_k per x_i)
        let inv = [[j[1][1] / det, -j[0][1] / det], [-j[1][0] / det, j[0][0] / det]];
        Some(
            (0..nn)
                .map(|a| {
                    let gradient: [f64; 2] = std::array::from_fn(|i| inv[0][i] * dn[a][0] + inv[1][i] * dn[a][1]);
                    // ∇²_ξ N − Σ_m ∂_m N ∇²_ξ x_m: only the mixed entry
                    let c = mixed[a] - gradient[0] * d[0] - gradient[1] * d[1];
                    // (J⁻ᵀ A J⁻¹)_ij with A = [[0, c], [c, 0]]
                    let entry = |i: usize, k: usize| c * (inv[0][i] * inv[1][k] + inv[1][i] * inv[0][k]);
                    let f = GridFunction { value: n[a], gradient, hessian: [entry(0, 0), entry(0, 1), entry(1, 1)] };
                    (self.mesh.cell(cell)[a], f)
                })
                .collect(),
        )
    }

    /// On a smooth basis (fixed lattice without holes), the functions at `x` (GIMP: `l = 0`)
    /// per node with those of the nodes for which `absent` holds folded into the others by
    /// the extrapolation of a linear field ([`SmoothLattice::functions_without`]); `None`
    /// outside the lattice, on the linear basis, or if the support keeps no node.
    pub fn functions_without(&self, x: &[f64; 3], absent: impl Fn(usize) -> bool) -> Option<Vec<(usize, f64)>> {
        let lattice = self.smooth.as_ref().filter(|_| !self.has_moved())?;
        let s = lattice.lattice_coordinates(x)?;
        let (support, values) = lattice.functions_without(s, [0.0; 3], absent)?;
        Some(lattice.support(support).iter().zip(values).map(|(&a, v)| (a, v[0])).collect())
    }

    /// The linear functions of `cell` at `x`, also outside the cell (the cell's map
    /// extrapolated: exact for linear fields), per node (grid numbering); `None` if the map
    /// is singular.
    pub fn cell_functions_at(&self, cell: usize, x: &[f64; 3]) -> Option<Vec<(usize, f64)>> {
        let xi = self.local_coordinates(cell, x)?;
        let mut n = [0.0; MAX_NODES];
        self.mesh.element.shape_functions(&xi, &mut n);
        Some(self.mesh.cell(cell).iter().zip(n).map(|(&a, v)| (a, v)).collect())
    }

    /// The Gauss rule of support `s` in the step's configuration on which a u–p support
    /// integrates its pressure projection ([`loam_fem::mixed_kernel`]): the cell's
    /// [`ElementType::gauss_points_mixed`], or a 3 × 3 (× 3) rule over a smooth support's region.
    /// Writes its points into `rule` and returns how many.
    pub fn projection_rule(
        &self,
        s: usize,
        formulation: Formulation,
        thickness: f64,
        rule: &mut [PointGeometry; MAX_NODES],
    ) -> Result<usize, KernelError> {
        if let Some(lattice) = &self.smooth {
            if !self.has_moved() {
                lattice.projection_rule(s, formulation, thickness, rule);
            } else {
                for (g, (point, weight)) in
                    rule.iter_mut().zip(lattice.projection_points(s)).take(lattice.support_len())
                {
                    let (_, mut geometry, det) = self.moved_lattice_functions(lattice, point, [0.0; 3], formulation);
                    geometry.weight = weight * det * formulation.measure_factor(thickness, geometry.radius);
                    *g = geometry;
                }
            }
            return Ok(lattice.support_len());
        }
        self.cell_rule(s, formulation, thickness, rule)
    }

    /// The integrals of support (or cell) `s`'s functions over its region in the step's
    /// configuration, with which a u–p support integrates its pressure projection
    /// ([`CellProjection`]): in closed form on a fixed smooth lattice
    /// ([`SmoothLattice::projection_moments`]), else on the region's Gauss rule
    /// ([`Grid::projection_rule`], written into `rule`).
    pub fn projection_moments(
        &self,
        s: usize,
        formulation: Formulation,
        thickness: f64,
        rule: &mut [PointGeometry; MAX_NODES],
        out: &mut CellProjection,
    ) -> Result<(), KernelError> {
        if let Some(lattice) = self.smooth.as_ref().filter(|_| !self.has_moved()) {
            if lattice.projection_moments(s, formulation, thickness, out) {
                return Ok(());
            }
        }
        let len = self.projection_rule(s, formulation, thickness, rule)?;
        out.integrate(self.support_len(), &rule[..len]);
        Ok(())
    }

    /// The map of a smooth lattice in the step's configuration, `x(s) = Σ_I M_I(s) x_I`, at
    /// lattice coordinates `s`, with `∂x/∂s` (`[i][d] = ∂x_i/∂s_d`, per lattice cell): `M_I`
    /// are the basis's own functions (GIMP's with `l = 0`, the cells' bilinear map), so that
    /// a moved grid stays isoparametric (module doc of [`crate::basis`]).
    fn lattice_map(&self, lattice: &SmoothLattice, s: [f64; 3]) -> ([f64; 2], [[f64; 2]; 2]) {
        let (support, values) = lattice.functions_at(s, [0.0; 3]);
        self.map_from(lattice, support, &values)
    }

    /// [`Grid::lattice_map`] from the map's functions `values` on `support`, already evaluated.
    fn map_from(&self, lattice: &SmoothLattice, support: usize, values: &SupportValues) -> ([f64; 2], [[f64; 2]; 2]) {
        let mut x = [0.0; 2];
        let mut jacobian = [[0.0; 2]; 2];
        for (v, &a) in values.iter().zip(lattice.support(support)) {
            let xa = self.mesh.coords[a];
            for i in 0..2 {
                x[i] += v[0] * xa[i];
                jacobian[i][0] += v[1] * xa[i];
                jacobian[i][1] += v[2] * xa[i];
            }
        }
        (x, jacobian)
    }

    /// Lattice coordinates of `x` on a smooth lattice that has moved: the inverse of
    /// [`Grid::lattice_map`] by Newton's method, started from the reference position of `x`'s
    /// local coordinates in the (bilinear) cell that holds it. `None` outside the grid.
    fn moved_lattice_coordinates(&self, lattice: &SmoothLattice, x: &[f64; 3]) -> Option<[f64; 3]> {
        let (cell, xi) = self.locate(x)?;
        let element = self.mesh.element;
        let mut n = [0.0; MAX_NODES];
        element.shape_functions(&xi, &mut n);
        let mut reference = [0.0; 3];
        for (k, &a) in self.mesh.cell(cell).iter().enumerate() {
            for d in 0..2 {
                reference[d] += n[k] * self.reference[a][d];
            }
        }
        let mut s = lattice.clamped_coordinates(reference);
        for _ in 0..MAP_INVERSION_ITERATIONS {
            let (mapped, j) = self.lattice_map(lattice, s);
            let r = [x[0] - mapped[0], x[1] - mapped[1]];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det.is_nan() || det <= 0.0 {
                break;
            }
            let ds = [(j[1][1] * r[0] - j[0][1] * r[1]) / det, (j[0][0] * r[1] - j[1][0] * r[0]) / det];
            s = lattice.clamp([s[0] + ds[0], s[1] + ds[1], 0.0]);
            if ds[0].abs().max(ds[1].abs()) < 1e-13 {
                break;
            }
        }
        Some(s)
    }

    /// The functions of a moved smooth lattice at lattice coordinates `s`: shape values,
    /// gradients `∂N/∂x = (∂x/∂s)⁻ᵀ ∂N/∂s`, and the radius `Σ N_I x_I`; with `det ∂x/∂s`.
    fn moved_lattice_functions(
        &self,
        lattice: &SmoothLattice,
        s: [f64; 3],
        half_cells: [f64; 3],
        formulation: Formulation,
    ) -> (usize, PointGeometry, f64) {
        let (support, values) = lattice.functions_at(s, half_cells);
        // the map's functions are these unless they depend on the point's domain (GIMP)
        let (_, j) = if lattice.basis() == Basis::Gimp && half_cells != [0.0; 3] {
            self.lattice_map(lattice, s)
        } else {
            self.map_from(lattice, support, &values)
        };
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        // ∂s/∂x = (∂x/∂s)⁻¹
        let inverse = [[j[1][1] / det, -j[0][1] / det], [-j[1][0] / det, j[0][0] / det]];
        let mut g =
            PointGeometry { shape: [0.0; MAX_NODES], gradient: [[0.0; 3]; MAX_NODES], weight: 0.0, radius: 0.0 };
        for (a, (v, &node)) in values.iter().zip(lattice.support(support)).enumerate() {
            g.shape[a] = v[0];
            for i in 0..2 {
                g.gradient[a][i] = v[1] * inverse[0][i] + v[2] * inverse[1][i];
            }
            if formulation == Formulation::Axisymmetric {
                g.radius += v[0] * self.mesh.coords[node][0];
            }
        }
        (support, g, det)
    }

    /// The Gauss rule [`ElementType::gauss_points_mixed`] of `cell` in the step's
    /// configuration (weights: its share of the cell's volume, with the thickness or `2πR`).
    /// Writes its points into `rule` and returns how many.
    pub fn cell_rule(
        &self,
        cell: usize,
        formulation: Formulation,
        thickness: f64,
        rule: &mut [PointGeometry; MAX_NODES],
    ) -> Result<usize, KernelError> {
        let element = self.mesh.element;
        let coords = self.cell_coords(cell);
        let gauss = &self.mixed_rule;
        for (g, gp) in rule.iter_mut().zip(gauss) {
            point_geometry_into(
                g,
                element,
                formulation,
                thickness,
                &coords[..element.num_nodes()],
                &gp.xi,
                gp.weight,
                self.cell_map(cell),
            )?;
        }
        Ok(gauss.len())
    }

    /// The grid without the cells marked in `remove` (e.g. those inside a structure) and
    /// without the nodes only they used; returns it with, for each of its nodes, the index of
    /// that node in `self`. The reference configuration is kept (a grid that has moved
    /// returns to it).
    pub fn without_cells(&self, remove: &[bool]) -> (Grid, Vec<usize>) {
        if !remove.iter().any(|&r| r) && !self.has_moved() {
            // nothing to remove: the same grid (its basis included)
            return (self.clone(), (0..self.reference.len()).collect());
        }
        let element = self.mesh.element;
        let nn = element.num_nodes();
        let mut new_cell = vec![NO_CELL; self.mesh.num_cells()];
        let mut new_node = vec![usize::MAX; self.reference.len()];
        let mut kept_nodes = Vec::new();
        let mut connectivity = Vec::new();
        let mut kept = 0u32;
        for c in 0..self.mesh.num_cells() {
            if remove[c] {
                continue;
            }
            new_cell[c] = kept;
            kept += 1;
            for &a in self.mesh.cell(c) {
                if new_node[a] == usize::MAX {
                    new_node[a] = kept_nodes.len();
                    kept_nodes.push(a);
                }
                connectivity.push(new_node[a]);
            }
        }
        let mut node_groups = std::collections::BTreeMap::new();
        for (g, nodes) in &self.mesh.node_groups {
            let n: Vec<usize> = nodes.iter().map(|&a| new_node[a]).filter(|&a| a != usize::MAX).collect();
            node_groups.insert(g.clone(), n);
        }
        debug_assert_eq!(connectivity.len(), kept as usize * nn);
        let mesh = Mesh {
            element,
            coords: kept_nodes.iter().map(|&a| self.reference[a]).collect(),
            connectivity,
            node_groups,
        };
        let locator = match &self.locator {
            Locator::Lattice { origin, spacing, cells, rotation, cell_index } => {
                let index = match cell_index {
                    Some(index) => {
                        index.iter().map(|&c| if c == NO_CELL { NO_CELL } else { new_cell[c as usize] }).collect()
                    }
                    None => new_cell,
                };
                Locator::Lattice {
                    origin: *origin,
                    spacing: *spacing,
                    cells: *cells,
                    rotation: *rotation,
                    cell_index: Some(index),
                }
            }
            Locator::Bins(_) => {
                let all: Vec<usize> = (0..mesh.num_cells()).collect();
                Locator::Bins(Bins::new(&mesh, &all))
            }
        };
        let mut grid = Self::with_locator(mesh, locator);
        grid.smooth = self.smooth.as_ref().map(|lattice| lattice.holed(&new_node));
        (grid, kept_nodes)
    }

    /// Node coordinates in the reference configuration.
    pub fn reference_coords(&self) -> &[[f64; 3]] {
        &self.reference
    }

    /// Whether any node is away from its reference position.
    pub fn has_moved(&self) -> bool {
        self.moved_bins.is_some()
    }

    /// Places every node at its reference position plus `displacement` (one entry per
    /// node; zero for a grid at rest) for the coming step: the cells that move get their
    /// maps and bins anew, the others return to the reference configuration. Returns the
    /// worst quality of the moved cells (1 where none moved): the smallest corner `det J`
    /// of a cell over its reference value. Fails with the first cell that the motion inverts
    /// (`det J ≤ 0` at a corner); the grid is then left in the inverted configuration and must
    /// be moved again before use.
    pub fn move_nodes(&mut self, displacement: &[[f64; 3]]) -> Result<f64, InvertedCell> {
        let was_moved = self.has_moved();
        let mut node_moved = vec![false; self.reference.len()];
        let mut any = false;
        for ((x, x0), (w, m)) in
            self.mesh.coords.iter_mut().zip(&self.reference).zip(displacement.iter().zip(&mut node_moved))
        {
            *m = w.iter().any(|v| *v != 0.0);
            any |= *m;
            *x = [x0[0] + w[0], x0[1] + w[1], x0[2] + w[2]];
        }
        if !any && !was_moved {
            return Ok(1.0);
        }
        let element = self.mesh.element;
        let nn = element.num_nodes();
        let mut moved_cells = Vec::new();
        let mut quality = 1.0f64;
        for c in 0..self.mesh.num_cells() {
            let now = self.mesh.cell(c).iter().any(|&a| node_moved[a]);
            if now {
                let coords = self.cell_coords(c);
                let det_j = element.min_corner_det_j(&coords[..nn]);
                if det_j <= 0.0 {
                    return Err(InvertedCell { cell: c, centre: self.reference_centre(c) });
                }
                let mut reference = [[0.0; 3]; MAX_NODES];
                for (x, &a) in reference.iter_mut().zip(self.mesh.cell(c)) {
                    *x = self.reference[a];
                }
                quality = quality.min(det_j / element.min_corner_det_j(&reference[..nn]));
                moved_cells.push(c);
            }
            if now || self.moved[c] {
                self.affine[c] = affine_cell(&self.mesh, c);
            }
            self.moved[c] = now;
        }
        self.moved_bins = (!moved_cells.is_empty()).then(|| Bins::new(&self.mesh, &moved_cells));
        Ok(quality)
    }

    /// Sides of the axis-aligned bounding box of `cell` in the step's configuration (0 beyond
    /// the grid's dimension).
    pub fn cell_extent(&self, cell: usize) -> [f64; 3] {
        let coords = self.cell_coords(cell);
        let nodes = &coords[..self.mesh.element.num_nodes()];
        std::array::from_fn(|d| {
            let (lo, hi) = nodes.iter().fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x[d]), h.max(x[d])));
            hi - lo
        })
    }

    /// Centre of `cell` in the reference configuration (mean of its nodes).
    pub fn reference_centre(&self, cell: usize) -> [f64; 3] {
        let nodes = self.mesh.cell(cell);
        let mut c = [0.0; 3];
        for &a in nodes {
            for d in 0..3 {
                c[d] += self.reference[a][d] / nodes.len() as f64;
            }
        }
        c
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

    /// Node coordinates of `cell` in the current configuration (the first `num_nodes`
    /// entries), without allocating.
    pub fn cell_coords(&self, cell: usize) -> [[f64; 3]; MAX_ELEMENT_NODES] {
        let mut coords = [[0.0; 3]; MAX_ELEMENT_NODES];
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
        let still = |cell: &usize| !self.moved[*cell];
        let found = match &self.locator {
            Locator::Bins(bins) => bins.candidates(x, dim).iter().map(|&c| c as usize).filter(still).find_map(test),
            Locator::Lattice { origin, spacing, cells, rotation, cell_index } => {
                let (c, s) = *rotation;
                let (dx, dy) = (x[0] - origin[0], x[1] - origin[1]);
                let lattice_x = [origin[0] + c * dx + s * dy, origin[1] - s * dx + c * dy, x[2]];
                let mut ijk = [0usize; 3];
                let mut inside = true;
                for d in 0..dim {
                    let s = (lattice_x[d] - origin[d]) / spacing[d];
                    if !(s >= -1e-9 && s <= cells[d] as f64 * (1.0 + 1e-12) + 1e-9) {
                        inside = false;
                        break;
                    }
                    ijk[d] = (s.floor().max(0.0) as usize).min(cells[d] - 1);
                }
                let lattice = (ijk[2] * cells[1] + ijk[1]) * cells[0] + ijk[0];
                let structured: &[usize] = match element {
                    ElementType::Tri3 => &[2 * lattice, 2 * lattice + 1],
                    _ => &[lattice],
                };
                let cell_of = |k: usize| match cell_index {
                    Some(index) => (index[k] != NO_CELL).then_some(index[k] as usize),
                    None => Some(k),
                };
                if inside {
                    structured.iter().filter_map(|&k| cell_of(k)).filter(still).find_map(test)
                } else {
                    None
                }
            }
        };
        found.or_else(|| {
            let bins = self.moved_bins.as_ref()?;
            bins.candidates(x, dim).iter().find_map(|&c| test(c as usize))
        })
    }
}

/// The map `x = x₀ + J ξ` of `cell` where it is affine: a simplex, or a quad4 / hex8 cell that
/// is a parallelogram / parallelepiped (opposite edges equal to round-off: the bilinear /
/// trilinear map then has no `ξη` terms). `x₀` is the image of `ξ = 0`: node 0 of a simplex,
/// the centroid of a quad or hex.
fn affine_cell(mesh: &Mesh, cell: usize) -> Option<AffineCell> {
    let element = mesh.element;
    let coords: Vec<[f64; 3]> = mesh.cell(cell).iter().map(|&a| mesh.coords[a]).collect();
    let origin = match element {
        ElementType::Tri3 | ElementType::Tet4 => coords[0],
        ElementType::Quad4 | ElementType::Hex8 => {
            if !is_parallelotope(element, &coords) {
                return None;
            }
            let n = coords.len() as f64;
            std::array::from_fn(|i| coords.iter().map(|x| x[i]).sum::<f64>() / n)
        }
    };
    let mut dn = [[0.0; 3]; MAX_NODES];
    element.shape_gradients(&element.centroid_local(), &mut dn);
    let map = CellMap::at(element, &coords, &dn).ok()?;
    Some(AffineCell { origin, map })
}

/// Whether a quad4 (nodes counter-clockwise) is a parallelogram, `x₀ + x₂ = x₁ + x₃`, or a
/// hex8 (two such faces, `z` layers 0–3 and 4–7) a parallelepiped, to a relative round-off.
fn is_parallelotope(element: ElementType, coords: &[[f64; 3]]) -> bool {
    let size = coords.iter().flat_map(|x| x.iter()).fold(0.0f64, |m, v| m.max(v.abs())).max(1.0);
    let closes = |a: usize, b: usize, c: usize, d: usize| {
        (0..3).all(|i| (coords[a][i] + coords[c][i] - coords[b][i] - coords[d][i]).abs() <= 1e-12 * size)
    };
    match element {
        ElementType::Quad4 => closes(0, 1, 2, 3),
        // bottom and top faces parallelograms, the vertical edges equal
        ElementType::Hex8 => closes(0, 1, 2, 3) && closes(4, 5, 6, 7) && closes(0, 1, 5, 4) && closes(0, 3, 7, 4),
        _ => false,
    }
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

    /// A grid without the cells of a hole still locates by lattice arithmetic around it,
    /// finds nothing in the hole, and after moving some nodes locates points in the moved
    /// cells by their current positions.
    #[test]
    fn holes_and_moved_cells_are_located() {
        for element in [ElementType::Quad4, ElementType::Tri3] {
            let full = Grid::new([0.0; 3], [4.0, 2.0, 0.0], [4, 2, 1], element);
            let remove: Vec<bool> = (0..full.mesh.num_cells())
                .map(|c| {
                    let x = full.reference_centre(c);
                    x[0] < 1.0 && x[1] < 1.0
                })
                .collect();
            let (mut g, kept) = full.without_cells(&remove);
            assert_eq!(kept.len(), 15 - 1, "the corner node (0, 0) is dropped");
            assert!(g.locate(&[0.5, 0.5, 0.0]).is_none());
            let (cell, _) = g.locate(&[2.5, 1.5, 0.0]).unwrap();
            assert!(g.reference_centre(cell)[0] > 2.0);
            // move the node at (1, 1) by (0.3, 0.2)
            let node = g.reference_coords().iter().position(|x| x[0] == 1.0 && x[1] == 1.0).unwrap();
            let mut w = vec![[0.0; 3]; g.mesh.coords.len()];
            w[node] = [0.3, 0.2, 0.0];
            g.move_nodes(&w).unwrap();
            assert!(g.has_moved());
            // a point that the moved node's cells now cover
            let x = [1.4, 1.3, 0.0];
            let (cell, xi) = g.locate(&x).expect("inside a moved cell");
            let coords = g.cell_coords(cell);
            let mut n = [0.0; 8];
            element.shape_functions(&xi, &mut n);
            for d in 0..2 {
                let v: f64 = (0..element.num_nodes()).map(|a| n[a] * coords[a][d]).sum();
                assert!((v - x[d]).abs() < 1e-12);
            }
            // an inverting motion is refused with the cell
            w[node] = [-1.5, -0.2, 0.0];
            assert!(g.move_nodes(&w).is_err());
            w[node] = [0.0; 3];
            g.move_nodes(&w).unwrap();
            assert!(!g.has_moved());
        }
    }

    /// The per-cell affine maps (simplices, parallelogram quads, parallelepiped hexes) give the
    /// local coordinates of the Newton inverse map; a distorted quad keeps the Newton path.
    #[test]
    fn affine_cells_match_the_inverse_map() {
        // a distorted quad: not affine, the Newton path
        let mut distorted = Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [2, 1], ElementType::Quad4);
        distorted.coords[1][1] += 0.2;
        let g = Grid::unstructured(distorted);
        assert!(g.cell_map(0).is_none() && g.cell_map(1).is_none());
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
                assert!(g.cell_map(cell).is_some(), "{element:?} cell {cell}: every cell is affine");
            }
        }
    }

    /// Asserts that a point's smooth functions are a partition of unity reproducing the
    /// grid's current linear fields: `Σ N_I = 1`, `Σ N_I x_I = x`, `Σ x_I ⊗ ∇N_I = 1`.
    fn assert_reproduces_linear_fields(
        g: &Grid,
        lattice: &SmoothLattice,
        support: usize,
        f: &PointGeometry,
        x: &[f64; 3],
        what: &str,
    ) {
        let (mut sum, mut xs, mut grad) = (0.0, [0.0; 2], [[0.0; 2]; 2]);
        for (a, &node) in lattice.support(support).iter().enumerate() {
            let xa = g.mesh.coords[node];
            sum += f.shape[a];
            for i in 0..2 {
                xs[i] += f.shape[a] * xa[i];
                for j in 0..2 {
                    grad[i][j] += xa[i] * f.gradient[a][j];
                }
            }
        }
        assert!((sum - 1.0).abs() < 1e-12, "{what}: Σ N = {sum} at {x:?}");
        assert!((xs[0] - x[0]).abs() < 1e-10 && (xs[1] - x[1]).abs() < 1e-10, "{what}: Σ N x = {xs:?} at {x:?}");
        for (i, row) in grad.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let identity = if i == j { 1.0 } else { 0.0 };
                assert!((v - identity).abs() < 1e-9, "{what}: Σ x ⊗ ∇N = {grad:?} at {x:?}");
            }
        }
    }

    /// A smooth lattice that moves with a structure (issue 23, coupled grids): the inverse of
    /// its map recovers the lattice coordinates, the functions are a partition of unity that
    /// reproduces the linear fields of the moved configuration exactly (`Σ N_I x_I = x`,
    /// `Σ x_I ⊗ ∇N_I = 1`: the map is isoparametric), their gradients match central
    /// differences of the shape values, and an affine motion gives the fixed lattice's
    /// functions with the gradients mapped.
    #[test]
    fn a_moved_smooth_lattice_stays_isoparametric() {
        for basis in [Basis::Bspline2, Basis::Gimp] {
            let mut g = Grid::new([0.0; 3], [2.0, 1.0, 0.0], [8, 4, 1], ElementType::Quad4);
            g.set_basis(basis).unwrap();
            let fixed = g.clone();
            // a bending-like motion of the edge x = 0 decaying into the grid, as the mesh
            // motion of an interface on that edge gives
            let motion: Vec<[f64; 3]> = g
                .reference_coords()
                .iter()
                .map(|x| {
                    let decay = (1.0 - x[0] / 2.0).powi(2);
                    [-0.04 * (x[1] - 0.5) * decay, -0.06 * decay + 0.01 * x[0] * x[1], 0.0]
                })
                .collect();
            g.move_nodes(&motion).unwrap();
            let lattice = g.smooth.clone().unwrap();
            for k in 0..200 {
                let s = [8.0 * ((k as f64 * 0.618_034).fract()), 4.0 * ((k as f64 * 0.381_966 + 0.1).fract()), 0.0];
                let (x2, _) = g.lattice_map(&lattice, s);
                let x = [x2[0], x2[1], 0.0];
                let recovered = g.moved_lattice_coordinates(&lattice, &x).expect("inside the moved grid");
                assert!(
                    (recovered[0] - s[0]).abs() < 1e-10 && (recovered[1] - s[1]).abs() < 1e-10,
                    "{s:?} → {recovered:?}"
                );
                let (support, f) = g.point_functions(&x, [0.0; 3], Formulation::PlaneStrain, 1.0).unwrap();
                assert_reproduces_linear_fields(&g, &lattice, support, &f, &x, &format!("{basis:?}"));
                // gradients against central differences of the shape values (same support)
                let h = 1e-6;
                for i in 0..2 {
                    let (mut p, mut m) = (x, x);
                    p[i] += h;
                    m[i] -= h;
                    let (Some((sp, fp)), Some((sm, fm))) = (
                        g.point_functions(&p, [0.0; 3], Formulation::PlaneStrain, 1.0),
                        g.point_functions(&m, [0.0; 3], Formulation::PlaneStrain, 1.0),
                    ) else {
                        continue;
                    };
                    if sp != support || sm != support {
                        continue;
                    }
                    for a in 0..9 {
                        let fd = (fp.shape[a] - fm.shape[a]) / (2.0 * h);
                        assert!(
                            (fd - f.gradient[a][i]).abs() < 1e-5,
                            "{basis:?}: ∂N_{a}/∂x_{i} {} vs FD {fd}",
                            f.gradient[a][i]
                        );
                    }
                }
            }
            // an affine motion: the fixed lattice's functions, gradients through the map
            let stretch = [[1.1, 0.2], [-0.05, 0.9]];
            let affine: Vec<[f64; 3]> = fixed
                .reference_coords()
                .iter()
                .map(|x| {
                    [
                        (stretch[0][0] - 1.0) * x[0] + stretch[0][1] * x[1],
                        stretch[1][0] * x[0] + (stretch[1][1] - 1.0) * x[1],
                        0.0,
                    ]
                })
                .collect();
            let mut a = fixed.clone();
            a.move_nodes(&affine).unwrap();
            for reference in [[0.13, 0.07], [1.0, 0.5], [1.93, 0.99], [0.62, 0.31]] {
                let x = [
                    stretch[0][0] * reference[0] + stretch[0][1] * reference[1],
                    stretch[1][0] * reference[0] + stretch[1][1] * reference[1],
                    0.0,
                ];
                let (s_moved, f_moved) = a.point_functions(&x, [0.0; 3], Formulation::PlaneStrain, 1.0).unwrap();
                let (s_fixed, f_fixed) = fixed
                    .point_functions(&[reference[0], reference[1], 0.0], [0.0; 3], Formulation::PlaneStrain, 1.0)
                    .unwrap();
                assert_eq!(s_moved, s_fixed);
                let det = stretch[0][0] * stretch[1][1] - stretch[0][1] * stretch[1][0];
                for k in 0..9 {
                    assert!((f_moved.shape[k] - f_fixed.shape[k]).abs() < 1e-12);
                    // ∇_x N = F⁻ᵀ ∇_X N
                    let gx = [
                        (stretch[1][1] * f_fixed.gradient[k][0] - stretch[1][0] * f_fixed.gradient[k][1]) / det,
                        (-stretch[0][1] * f_fixed.gradient[k][0] + stretch[0][0] * f_fixed.gradient[k][1]) / det,
                    ];
                    for i in 0..2 {
                        assert!(
                            (f_moved.gradient[k][i] - gx[i]).abs() < 1e-10,
                            "{basis:?}: {:?} vs {gx:?}",
                            f_moved.gradient[k]
                        );
                    }
                }
            }
        }
    }

    /// A smooth lattice holed by a structure (cells removed inside it, its boundary nodes
    /// kept): for points around the hole, fixed and moved, the folded functions are a
    /// partition of unity reproducing linear fields (`Σ N_I x_I = x`, `Σ x_I ⊗ ∇N_I = 1`),
    /// their gradients match central differences, and along lines past the hole's corners no
    /// function jumps by more than 1/64 (the fold's switch beside a corner).
    #[test]
    fn a_holed_smooth_lattice_folds_the_removed_nodes() {
        for basis in [Basis::Bspline2, Basis::Gimp] {
            let mut whole = Grid::new([0.0; 3], [3.0, 2.0, 0.0], [12, 8, 1], ElementType::Quad4);
            whole.set_basis(basis).unwrap();
            // the hole: lattice cells 4..8 × 2..5, i.e. [1, 2] × [0.5, 1.25]
            let remove: Vec<bool> =
                (0..whole.mesh.num_cells()).map(|c| (4..8).contains(&(c % 12)) && (2..5).contains(&(c / 12))).collect();
            let (holed, _) = whole.without_cells(&remove);
            assert_eq!(holed.basis(), basis);
            let in_hole =
                |x: &[f64; 3]| x[0] > 1.0 + 1e-9 && x[0] < 2.0 - 1e-9 && x[1] > 0.5 + 1e-9 && x[1] < 1.25 - 1e-9;
            let mut moved = holed.clone();
            let motion: Vec<[f64; 3]> = moved
                .reference_coords()
                .iter()
                .map(|x| {
                    let d = ((x[0] - 1.5).powi(2) + (x[1] - 0.9).powi(2)).sqrt();
                    let decay = (1.0 - d / 1.5).max(0.0).powi(2);
                    [0.03 * decay, -0.05 * decay, 0.0]
                })
                .collect();
            moved.move_nodes(&motion).unwrap();
            for (label, g) in [("fixed", &holed), ("moved", &moved)] {
                let lattice = g.smooth.clone().unwrap();
                // GIMP's domain averages over the lattice coordinates, exact for linear fields
                // where the map is affine: on the moved grid checked with l = 0
                let half = if basis == Basis::Gimp && label == "moved" { 0.0 } else { 0.05 };
                let functions = |x: &[f64; 3]| g.point_functions(x, [half, half, 0.0], Formulation::PlaneStrain, 1.0);
                // reference points around the hole, carried by the motion where the grid moved
                let place = |r: [f64; 2]| {
                    if label == "fixed" {
                        [r[0], r[1], 0.0]
                    } else {
                        let d = ((r[0] - 1.5).powi(2) + (r[1] - 0.9).powi(2)).sqrt();
                        let decay = (1.0 - d / 1.5).max(0.0).powi(2);
                        [r[0] + 0.03 * decay, r[1] - 0.05 * decay, 0.0]
                    }
                };
                let mut checked = 0;
                for k in 0..600 {
                    let r = [
                        0.6 + 1.8 * ((k as f64 * 0.618_034).fract()),
                        0.2 + 1.4 * ((k as f64 * 0.381_966 + 0.05).fract()),
                    ];
                    if in_hole(&[r[0], r[1], 0.0]) {
                        continue;
                    }
                    let x = place(r);
                    let Some((support, f)) = functions(&x) else { continue };
                    checked += 1;
                    assert_reproduces_linear_fields(g, &lattice, support, &f, &x, &format!("{basis:?} {label}"));
                    let h = 1e-7;
                    for i in 0..2 {
                        let (mut p, mut m) = (x, x);
                        p[i] += h;
                        m[i] -= h;
                        let (Some((sp, fp)), Some((sm, fm))) = (functions(&p), functions(&m)) else { continue };
                        if sp != support || sm != support {
                            continue;
                        }
                        for a in 0..9 {
                            let fd = (fp.shape[a] - fm.shape[a]) / (2.0 * h);
                            // off the fold's switch lines the functions are smooth
                            if (fd - f.gradient[a][i]).abs() > 1e-4 && (fp.shape[a] - fm.shape[a]).abs() > 1e-3 {
                                continue;
                            }
                            assert!(
                                (fd - f.gradient[a][i]).abs() < 1e-4,
                                "{basis:?} {label}: ∂N/∂x {} vs FD {fd}",
                                f.gradient[a][i]
                            );
                        }
                    }
                }
                assert!(checked > 300, "{checked} points checked");
                // continuity: walk lines past the hole's corners, the functions per grid node
                let mut largest_jump = 0.0f64;
                for (from, to) in [
                    ([0.7, 1.45], [2.3, 1.45]),
                    ([0.8, 0.3], [0.8, 1.6]),
                    ([0.7, 1.6], [1.3, 1.0]),
                    ([2.2, 0.2], [1.9, 0.45]),
                ] {
                    let mut previous: Option<Vec<f64>> = None;
                    for k in 0..=4000 {
                        let t = k as f64 / 4000.0;
                        let r = [from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])];
                        if in_hole(&[r[0], r[1], 0.0]) {
                            previous = None;
                            continue;
                        }
                        let Some((support, f)) = functions(&place(r)) else { continue };
                        let mut full = vec![0.0; g.mesh.coords.len()];
                        for (a, &node) in lattice.support(support).iter().enumerate() {
                            full[node] += f.shape[a];
                        }
                        if let Some(prev) = &previous {
                            for (a, b) in full.iter().zip(prev) {
                                largest_jump = largest_jump.max((a - b).abs());
                            }
                        }
                        previous = Some(full);
                    }
                }
                println!(
                    "{basis:?} {label}: largest change of a function between neighbouring samples {largest_jump:.4}"
                );
                assert!(largest_jump < 1.0 / 64.0 + 2e-3, "{basis:?} {label}: a function jumps by {largest_jump}");
            }
        }
    }

    /// The second derivatives of [`Grid::functions_with_hessian`] against central
    /// differences of its gradients (and the gradients against differences of the values),
    /// relative to the largest entry: the bilinear lattice (`∂xy N ≠ 0`), a rotated lattice,
    /// a distorted quad4 mesh (not a parallelogram: `∂xx N`, `∂yy N ≠ 0`), tri3, GIMP (the
    /// hat) and B-splines, at points off the kinks.
    #[test]
    fn hessian_matches_central_differences_of_the_gradient() {
        let mut distorted = Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [2, 1], ElementType::Quad4);
        distorted.coords[1] = [1.15, -0.1, 0.0];
        distorted.coords[4] = [0.9, 1.2, 0.0];
        let mut grids = vec![
            ("bilinear lattice", Grid::new([0.0; 3], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4)),
            ("rotated lattice", Grid::rotated([0.0; 3], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4, 0.4)),
            ("distorted quad4", Grid::unstructured(distorted)),
            ("tri3 lattice", Grid::new([0.0; 3], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Tri3)),
        ];
        for basis in [Basis::Gimp, Basis::Bspline2] {
            let mut g = Grid::new([0.0; 3], [2.0, 1.0, 0.0], [4, 2, 1], ElementType::Quad4);
            g.set_basis(basis).unwrap();
            grids.push((basis.name(), g));
        }
        let points = [[0.61, 0.33, 0.0], [1.12, 0.71, 0.0], [0.21, 0.12, 0.0]];
        for (label, grid) in &grids {
            let mut worst = (0.0f64, 0.0f64);
            let mut mixed = 0.0f64;
            for x in points {
                let f = grid.functions_with_hessian(&x).expect("inside");
                let step = 1e-6;
                let at = |dx: [f64; 2]| {
                    let xs = [x[0] + dx[0], x[1] + dx[1], 0.0];
                    let g = grid.functions_with_hessian(&xs).expect("inside");
                    f.iter()
                        .map(|(a, _)| g.iter().find(|(b, _)| b == a).map_or(GridFunction::default(), |(_, v)| *v))
                        .collect::<Vec<_>>()
                };
                let (xp, xm, yp, ym) = (at([step, 0.0]), at([-step, 0.0]), at([0.0, step]), at([0.0, -step]));
                let scale_g = f.iter().fold(0.0f64, |m, (_, v)| m.max(v.gradient[0].abs()).max(v.gradient[1].abs()));
                // (floor: the gradients per cell size, for tri3 whose second derivatives vanish)
                let scale_h = f.iter().fold(scale_g / 0.5, |m, (_, v)| v.hessian.iter().fold(m, |m, h| m.max(h.abs())));
                for (k, (_, v)) in f.iter().enumerate() {
                    let dx = |p: &[GridFunction], m: &[GridFunction], get: &dyn Fn(&GridFunction) -> f64| {
                        (get(&p[k]) - get(&m[k])) / (2.0 * step)
                    };
                    let fd_gradient = [dx(&xp, &xm, &|g| g.value), dx(&yp, &ym, &|g| g.value)];
                    let fd_hessian = [
                        dx(&xp, &xm, &|g| g.gradient[0]),
                        0.5 * (dx(&yp, &ym, &|g| g.gradient[0]) + dx(&xp, &xm, &|g| g.gradient[1])),
                        dx(&yp, &ym, &|g| g.gradient[1]),
                    ];
                    for i in 0..2 {
                        worst.0 = worst.0.max((fd_gradient[i] - v.gradient[i]).abs() / scale_g);
                    }
                    for i in 0..3 {
                        worst.1 = worst.1.max((fd_hessian[i] - v.hessian[i]).abs() / scale_h);
                    }
                    mixed = mixed.max(v.hessian[1].abs());
                }
            }
            println!("{label}: gradient vs FD {:.2e}, hessian vs FD of the gradient {:.2e}", worst.0, worst.1);
            assert!(worst.0 < 1e-6 && worst.1 < 1e-5, "{label}: {worst:?}");
            if !label.starts_with("tri3") {
                assert!(mixed > 0.1, "{label}: the mixed derivative must not vanish ({mixed})");
            }
        }
    }
}
