//! Ghost-penalty stabilisation of the cells at the edge of the material.
//!
//! A cell that the material only grazes (a few points near one of its corners) joins its far
//! nodes to the system through tiny shape-function values and gradients: their stiffness is
//! a small fraction of the material's, and under the geometric stiffness of a stressed body
//! it can vanish or turn negative. Newton's correction there is then unbounded, and the
//! iteration that had nearly converged jumps away (measured on the static MPM cantilever of
//! benchmark 12 at grid h = 0.1: a residual of 0.14 N followed by a correction of 176 m at
//! the node diagonally beyond the tip's corner point). This is the small-cut-cell problem of
//! unfitted finite elements, which implicit MPM shares.
//!
//! The cure of those methods is the face ghost penalty (Burman 2010, *Ghost penalty*, C. R.
//! Acad. Sci. Paris, Ser. I 348, 1217–1220), brought to implicit MPM by Coombs 2023 (*Ghost
//! stabilisation of the material point method for stable quasi-static and dynamic analysis
//! of large deformation problems*, Int. J. Numer. Methods Eng. 124, 4841–4875): across every
//! face `F` that a cut cell (below) shares with another cell holding material, the
//! jump of the normal derivative of the step's displacement increment is penalised,
//!
//! $$ G(Δu, δu) = \sum_F γ\, h_F \int_F [\![∂_n Δu]\!] \cdot [\![∂_n δu]\!] \, dΓ, \qquad
//!    γ = α E, $$
//!
//! with `E` the Young's modulus of the stiffest body in the two cells, `h_F` the face size and
//! the dimensionless `α` of the case (`ghost_penalty` of an MPM domain). The term is linear
//! in `Δu` (residual `G Δu`, tangent `G`, symmetric positive semi-definite) and vanishes for
//! every displacement increment that is linear across the face, so it only acts on the
//! kinks of the grid interpolation that carry the poorly supported nodes. The penalised
//! faces are those of the *cut cells*: cells that hold points filling less than
//! [`CUT_FRACTION`] of their volume (the sum of their points' volumes against the cell's).
//! A material that fills its cells, as a body whose points sit at the Gauss positions of the
//! grid's cells does, has none, and its results are those of the unstabilised method (the
//! MPM cantilever of benchmark 1 keeps FEM's strain energy to 1e-9).
//!
//! **On a smooth basis** ([`crate::basis`]) the penalty acts on the grid's nodal values, the
//! control net, i.e. on the kinks of the net rather than of the field: for quadratic
//! B-splines the net's second difference at a node is `h²` times the field's second
//! derivative there, so the term penalises `α E h² |∂²Δu|²` near the material's edge, a
//! higher-order ghost penalty that still vanishes for linear increments. There a node is
//! in the system when a point's function reaches it, even in a cell without points, and at
//! a ragged surface a node can be in it while every cell around it has a node that is not,
//! so the face term, which needs both cells' nodes, leaves it unheld. The smooth bases
//! therefore add the face term lumped node by node for such nodes
//! ([`GhostPenalty::add_lattice_lines`], [`GhostPenalty::mark_lines`]): every line of three
//! lattice nodes in the system one of which the material barely covers (its weight
//! `Σ_p N_I w_p` below [`CUT_FRACTION`] of a cell) while no ghost face holds it penalises
//! the net's second divided difference along the line, with the face term's weight. Measured on the smooth footing of issue 23 at h = B/10 (contact wall,
//! u–p): without a ghost penalty Newton's converged increments moved nodes the material
//! barely reaches by up to 2.9 m in steps of 3 mm of footing travel; with the face form at
//! α = 0.1 by at most 0.05 m; at B/40 the face form left a node above the footing's corner
//! unheld (a correction of 15 m, and the run stopped), which the lines hold.
//!
//! On the linear basis, each face between two cells of the sparsity pattern near a cut cell (the cut cells grown by
//! one ring when the blocks were last declared) is a block over the union of the two cells'
//! nodes (6 for quads, 4 for triangles, 12 for hexahedra, 5 for tetrahedra); faces that are
//! not ghost faces in a step write zeros, and a cut cell outside that zone declares the
//! blocks anew; on a smooth basis each line of three nodes is a block, declared around the
//! edge cells the same way. A material that fills its cells declares none and keeps its
//! sparsity.

use std::collections::HashMap;

use loam_fem::domain::{AssemblyInput, DomainError};
use loam_fem::formulation::Formulation;
use loam_fem::kernel::point_geometry;

use crate::grid::Grid;

/// A cell holding points is a cut cell (its faces are penalised) while its points fill less
/// than this share of it: one or two of a 2 × 2 set of points.
pub const CUT_FRACTION: f64 = 0.5;

/// Most nodes of a face block: two hexahedra sharing a face (the faces are the grid cells',
/// also on a smooth basis).
const MAX_FACE_NODES: usize = 16;

/// A face shared by two cells of the pattern.
#[derive(Debug, Clone)]
struct Face {
    /// The two cells.
    cells: [usize; 2],
    /// Local indices (in `cells[0]`) of the face's nodes, in the order of the element's facet.
    facet: Vec<usize>,
    /// The union of the two cells' nodes: `cells[0]`'s, then those of `cells[1]` not in it.
    nodes: Vec<usize>,
}

/// The ghost penalty of one grid (see the module doc).
#[derive(Debug, Clone)]
pub struct GhostPenalty {
    /// Dimensionless factor α of `γ = α E`.
    alpha: f64,
    /// Faces between two cells of the pattern.
    faces: Vec<Face>,
    /// Lines of three lattice nodes (smooth bases, [`GhostPenalty::add_lattice_lines`]).
    stencils: Vec<Stencil>,
    /// Per face or stencil: `γ` if it acts in this step, else 0.
    gamma: Vec<f64>,
    /// Per grid cell: whether blocks of it were declared at the last rebuild.
    zone: Vec<bool>,
    /// Per grid node, per lattice direction: its neighbours on the minus and plus side
    /// (`usize::MAX` where there is none); built with the first lattice rebuild.
    neighbours: Vec<[[usize; 2]; 3]>,
}

/// Three consecutive nodes `a, b, c` of a lattice line along `direction`.
#[derive(Debug, Clone, Copy)]
struct Stencil {
    nodes: [usize; 3],
    direction: usize,
}

/// No neighbour on that side.
const NONE: usize = usize::MAX;

/// A facet's global nodes, ascending, padded with `usize::MAX`.
type FacetKey = [usize; 4];

/// The key of facet `facet` (local node indices) of a cell with nodes `cell`.
fn facet_key(cell: &[usize], facet: &[usize]) -> FacetKey {
    let mut key = [usize::MAX; 4];
    for (k, &a) in key.iter_mut().zip(facet) {
        *k = cell[a];
    }
    key.sort_unstable();
    key
}

impl GhostPenalty {
    /// A ghost penalty of factor `alpha` (no faces until [`GhostPenalty::rebuild`]).
    pub fn new(alpha: f64) -> Self {
        Self {
            alpha,
            faces: Vec::new(),
            stencils: Vec::new(),
            gamma: Vec::new(),
            zone: Vec::new(),
            neighbours: Vec::new(),
        }
    }

    /// Nodes per face block on `grid` (a stencil has three).
    fn face_nodes(grid: &Grid) -> usize {
        let element = grid.mesh.element;
        2 * element.num_nodes() - element.facets()[0].len()
    }

    /// Per node and lattice direction, the neighbours along the cells' edges (the cells are
    /// lattice cells: two nodes of a cell are neighbours along `d` where their local
    /// coordinates differ in `d` alone).
    fn lattice_neighbours(grid: &Grid) -> Vec<[[usize; 2]; 3]> {
        let mesh = &grid.mesh;
        let element = mesh.element;
        let mut neighbours = vec![[[NONE; 2]; 3]; mesh.coords.len()];
        for c in 0..mesh.num_cells() {
            let cell = mesh.cell(c);
            for (i, &a) in cell.iter().enumerate() {
                let xa = element.node_local(i);
                for (j, &b) in cell.iter().enumerate() {
                    let xb = element.node_local(j);
                    let differ: Vec<usize> = (0..3).filter(|&d| xa[d] != xb[d]).collect();
                    if let [d] = differ[..] {
                        if xb[d] > xa[d] {
                            neighbours[a][d][1] = b;
                            neighbours[b][d][0] = a;
                        }
                    }
                }
            }
        }
        neighbours
    }

    /// Declares the line blocks of a smooth basis, after the faces ([`GhostPenalty::rebuild`]):
    /// every line of three lattice nodes `a, b, c` whose middle node `b` is a node of a cell
    /// of the zone and whose nodes are all unknowns of the pattern (`in_pattern`). See
    /// [`GhostPenalty::mark_lines`] for the nodes they hold.
    pub fn add_lattice_lines(&mut self, grid: &Grid, in_pattern: &[bool]) {
        if self.neighbours.len() != grid.mesh.coords.len() {
            self.neighbours = Self::lattice_neighbours(grid);
        }
        let dim = grid.mesh.element.dim();
        let mut in_zone = vec![false; grid.mesh.coords.len()];
        for c in (0..grid.mesh.num_cells()).filter(|&c| self.zone[c]) {
            for &a in grid.mesh.cell(c) {
                in_zone[a] = true;
            }
        }
        self.stencils.clear();
        for b in (0..in_zone.len()).filter(|&b| in_zone[b] && in_pattern[b]) {
            for direction in 0..dim {
                let [a, c] = self.neighbours[b][direction];
                if a != NONE && c != NONE && in_pattern[a] && in_pattern[c] {
                    self.stencils.push(Stencil { nodes: [a, b, c], direction });
                }
            }
        }
        self.gamma.resize(self.faces.len() + self.stencils.len(), 0.0);
    }

    /// Marks the lines of a step on a smooth basis, after the faces ([`GhostPenalty::mark`]):
    /// those whose nodes are all unknowns (`reached`: a point's function reaches them) and one
    /// of which the material barely covers (`weak`: its weight `Σ_p N_I w_p` below
    /// [`CUT_FRACTION`] of a cell) while no ghost face of the step holds it, with `γ = α E`,
    /// `E` the largest modulus (`modulus`, per cell) of the cells around the three nodes, or
    /// `fallback` where none of them holds points. A line penalises the control net's second
    /// divided difference along it with the face term's weight (`stencil_matrix`).
    ///
    /// A smooth function reaches nodes one and a half cells from its point: at a ragged
    /// surface a node can be an unknown while every cell around it has a node that is not
    /// (a node above a heave, reached by the tail of one point's function). The faces need
    /// both cells' nodes, so none holds such a node and nothing but that tail's tiny
    /// stiffness does. Measured on the B/40 B-spline footing (`loam run --trace-newton`, its
    /// `dpeak`): at 0.10 m of settlement the first Newton correction of a step moved the node
    /// at (0.5, 5.0) m, above the footing's corner and beside the soil that had left its side,
    /// by 15 m at every step size down to an eighth, and the run stopped with an inverted
    /// point; with the lines the same step from the same checkpoint converges (its largest
    /// nodal increment 4 mm) and the run reaches 0.15 m. A line of three nodes always exists
    /// for an unknown node (the 3 × 3 block of the support that reached it). Only the nodes
    /// the faces leave are held this way: lines through every weak node would penalise a bent
    /// beam's curvature along its surface (they took the GIMP cantilever's tip error at
    /// h = 0.25 m from −1.96 % to −7.7 %, where the faces move the tip by 0.03 %).
    pub fn mark_lines(&mut self, grid: &Grid, reached: &[bool], weak: &[bool], modulus: &[f64], fallback: f64) {
        let mesh = &grid.mesh;
        let mut node_modulus = vec![0.0f64; mesh.coords.len()];
        for c in 0..mesh.num_cells() {
            for &a in mesh.cell(c) {
                node_modulus[a] = node_modulus[a].max(modulus[c]);
            }
        }
        let mut held = vec![false; mesh.coords.len()];
        for (face, &gamma) in self.faces.iter().zip(&self.gamma) {
            if gamma > 0.0 {
                face.nodes.iter().for_each(|&a| held[a] = true);
            }
        }
        let faces = self.faces.len();
        for (stencil, gamma) in self.stencils.iter().zip(self.gamma[faces..].iter_mut()) {
            let nodes = stencil.nodes;
            *gamma = if nodes.iter().all(|&n| reached[n]) && nodes.iter().any(|&n| weak[n] && !held[n]) {
                let e = nodes.iter().map(|&n| node_modulus[n]).fold(0.0, f64::max);
                self.alpha * if e > 0.0 { e } else { fallback }
            } else {
                0.0
            };
        }
    }

    /// Declares the face blocks: the faces shared by two cells of `pattern` (ascending cell
    /// list) of which one lies in `zone` (per grid cell: the cut cells grown by a ring, so
    /// that the blocks last while the cut cells move by less than a cell; a cut cell outside
    /// it makes the caller rebuild, [`GhostPenalty::covers`]).
    pub fn rebuild(&mut self, grid: &Grid, pattern: &[usize], zone: Vec<bool>) {
        let mesh = &grid.mesh;
        let element = mesh.element;
        let mut open: HashMap<FacetKey, (usize, usize)> = HashMap::new();
        self.faces.clear();
        self.stencils.clear();
        for &c in pattern {
            let cell = mesh.cell(c);
            for (f, facet) in element.facets().iter().enumerate() {
                let key = facet_key(cell, facet);
                match open.remove(&key) {
                    Some((first, first_facet)) if zone[first] || zone[c] => {
                        let first_cell = mesh.cell(first);
                        let mut nodes = first_cell.to_vec();
                        nodes.extend(cell.iter().filter(|a| !first_cell.contains(a)));
                        self.faces.push(Face {
                            cells: [first, c],
                            facet: element.facets()[first_facet].to_vec(),
                            nodes,
                        });
                    }
                    Some(_) => {}
                    None => {
                        open.insert(key, (c, f));
                    }
                }
            }
        }
        self.faces.sort_by_key(|f| f.cells);
        self.gamma = vec![0.0; self.faces.len()];
        self.zone = zone;
    }

    /// Whether the blocks declared at the last rebuild hold every face (or stencil) of the
    /// cells `cut`; never before the first rebuild (a domain restored from a checkpoint keeps
    /// its pattern, so only this declares its blocks).
    pub fn covers(&self, cut: &[bool]) -> bool {
        self.zone.len() == cut.len() && cut.iter().zip(&self.zone).all(|(&e, &z)| !e || z)
    }

    /// Marks the ghost faces of a step: faces between two cells holding points (`active`)
    /// of which at least one is a cut cell (`cut`: less than [`CUT_FRACTION`] of it filled),
    /// with `γ = α E` of the stiffer cell (`modulus[c]`: Young's modulus of the stiffest body
    /// in cell `c`).
    pub fn mark(&mut self, active: &[bool], cut: &[bool], modulus: &[f64]) {
        for (face, gamma) in self.faces.iter().zip(self.gamma.iter_mut()) {
            let [a, b] = face.cells;
            *gamma = if active[a] && active[b] && (cut[a] || cut[b]) {
                self.alpha * modulus[a].max(modulus[b])
            } else {
                0.0
            };
        }
    }

    /// Number of blocks (faces or stencils).
    pub fn num_blocks(&self) -> usize {
        self.faces.len() + self.stencils.len()
    }

    /// The grid nodes of block `k`.
    fn block(&self, k: usize) -> &[usize] {
        match self.faces.get(k) {
            Some(face) => &face.nodes,
            None => &self.stencils[k - self.faces.len()].nodes,
        }
    }

    /// Global displacement DOFs of each block, in block order.
    pub fn blocks(&self, grid: &Grid, node_ids: &[usize], layout: &mut loam_fem::assembly::BlockLayout) {
        let dim = grid.mesh.element.dim();
        for k in 0..self.num_blocks() {
            layout.push(self.block(k).iter().flat_map(|&a| (0..dim).map(move |i| node_ids[a] * dim + i)));
        }
    }

    /// Lengths of the matrix and vector buffers of the blocks.
    pub fn buffer_lengths(&self, grid: &Grid) -> (usize, usize) {
        let dim = grid.mesh.element.dim();
        let (face, line) = (Self::face_nodes(grid) * dim, 3 * dim);
        (
            self.faces.len() * face * face + self.stencils.len() * line * line,
            self.faces.len() * face + self.stencils.len() * line,
        )
    }

    /// Residual `G Δu` and tangent `G` of every face block (see the module doc); `Δu` is the
    /// grid nodes' displacement since the start of the step.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &self,
        grid: &Grid,
        node_ids: &[usize],
        formulation: Formulation,
        thickness: f64,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        use rayon::prelude::*;
        let dim = grid.mesh.element.dim();
        let faces = self.faces.len();
        let nd_face = Self::face_nodes(grid) * dim;
        let (face_matrices, line_matrices) = matrices.split_at_mut(faces * nd_face * nd_face);
        let (face_vectors, line_vectors) = vectors.split_at_mut(faces * nd_face);
        let add = |nodes: &[usize], g: &[f64], km: &mut [f64], fv: &mut [f64]| {
            let (nf, nd) = (nodes.len(), nodes.len() * dim);
            let mut du = [[0.0; 3]; MAX_FACE_NODES];
            for (d, &a) in du.iter_mut().zip(nodes) {
                let dof = node_ids[a] * dim;
                for i in 0..dim {
                    d[i] = input.state.u[dof + i] - input.committed.u[dof + i];
                }
            }
            for a in 0..nf {
                for b in 0..nf {
                    let gab = g[a * nf + b];
                    if gab == 0.0 {
                        continue;
                    }
                    for i in 0..dim {
                        fv[a * dim + i] += gab * du[b][i];
                        if input.with_tangent {
                            km[(a * dim + i) * nd + b * dim + i] += gab;
                        }
                    }
                }
            }
        };
        let clear = |km: &mut [f64], fv: &mut [f64]| {
            fv.fill(0.0);
            if input.with_tangent {
                km.fill(0.0);
            }
        };
        face_matrices
            .par_chunks_mut(nd_face * nd_face)
            .zip(face_vectors.par_chunks_mut(nd_face))
            .zip(self.faces.par_iter())
            .zip(&self.gamma[..faces])
            .try_for_each(|(((km, fv), face), &gamma)| {
                clear(km, fv);
                if gamma > 0.0 {
                    let g = face_matrix(grid, formulation, thickness, face, gamma).map_err(|message| DomainError {
                        domain: String::new(),
                        element: face.cells[0],
                        message,
                    })?;
                    add(&face.nodes, &g, km, fv);
                }
                Ok::<(), DomainError>(())
            })?;
        let nd_line = 3 * dim;
        line_matrices
            .par_chunks_mut(nd_line * nd_line)
            .zip(line_vectors.par_chunks_mut(nd_line))
            .zip(self.stencils.par_iter())
            .zip(&self.gamma[faces..])
            .for_each(|(((km, fv), &stencil), &gamma)| {
                clear(km, fv);
                if gamma > 0.0 {
                    let g = stencil_matrix(grid, formulation, thickness, stencil, gamma);
                    add(&stencil.nodes, &g, km, fv);
                }
            });
        Ok(())
    }
}

/// `G_ab = γ h_F ∫_F j_a j_b dΓ` of one face, row-major over the face's nodes, with
/// `j_a = n·∇N_a` of the first cell minus that of the second, at the grid's current position.
fn face_matrix(
    grid: &Grid,
    formulation: Formulation,
    thickness: f64,
    face: &Face,
    gamma: f64,
) -> Result<[f64; MAX_FACE_NODES * MAX_FACE_NODES], String> {
    let mesh = &grid.mesh;
    let element = mesh.element;
    let dim = element.dim();
    let nn = element.num_nodes();
    let nf = face.nodes.len();
    let cells = [mesh.cell(face.cells[0]), mesh.cell(face.cells[1])];
    let coords = [grid.cell_coords(face.cells[0]), grid.cell_coords(face.cells[1])];
    // the face's corners: global nodes and physical positions (the face is straight or planar:
    // one normal and one measure for all its points)
    let n_corners = face.facet.len();
    let mut corners = [0usize; 4];
    let mut positions = [[0.0; 3]; 4];
    for (k, &a) in face.facet.iter().enumerate() {
        corners[k] = cells[0][a];
        positions[k] = mesh.coords[corners[k]];
    }
    let corners = &corners[..n_corners];
    let (normal, measure) = face_normal(&positions[..n_corners], dim);
    let size = if dim == 2 { measure } else { measure.sqrt() };
    let mut g = [0.0; MAX_FACE_NODES * MAX_FACE_NODES];
    // the face's Gauss rule in its own parameters, with the corner weights of each point
    for (weights, w) in face_rule(n_corners, dim) {
        let mut jump = [0.0; MAX_FACE_NODES];
        let mut radius = 0.0;
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            // the point's local coordinates in this cell: the corners' local coordinates
            // combined with the same weights
            let mut xi = [0.0; 3];
            for (k, &a) in corners.iter().enumerate() {
                let local = cells[side].iter().position(|&b| b == a).ok_or("ghost face: corner not in its cell")?;
                let node_xi = element.node_local(local);
                for i in 0..3 {
                    xi[i] += weights[k] * node_xi[i];
                }
            }
            let geometry = point_geometry(element, formulation, thickness, &coords[side][..nn], &xi, 1.0, None)
                .map_err(|e| e.to_string())?;
            radius = geometry.radius;
            for (a, &node) in cells[side].iter().enumerate() {
                let k = face.nodes.iter().position(|&b| b == node).expect("a cell's node is in its face block");
                let dn: f64 = (0..dim).map(|i| geometry.gradient[a][i] * normal[i]).sum();
                jump[k] += sign * dn;
            }
        }
        let out_of_plane = match formulation {
            Formulation::Axisymmetric => 2.0 * std::f64::consts::PI * radius,
            _ if dim == 2 => thickness,
            _ => 1.0,
        };
        let scale = gamma * size * w * measure * out_of_plane;
        for a in 0..nf {
            for b in 0..nf {
                g[a * nf + b] += scale * jump[a] * jump[b];
            }
        }
    }
    Ok(g)
}

/// `G_ab = w k_a k_b` of one stencil `a, b, c` (row-major over its three nodes): the
/// control net's second divided difference along the line, `s = k · Δu` with
/// `k = (1/l_ab, −1/l_ab − 1/l_bc, 1/l_bc)` (`l`: the nodes' distances at the grid's current
/// position), weighted `w = γ h_F A_⊥` with `A_⊥` the lattice's cross-section per line (the
/// product of the other directions' spacings; in 2D times the thickness, or `2πr` at `b`
/// in axisymmetry) and `h_F = A_⊥^{1/(dim−1)}` of the grid's own cross-section: the lumped
/// form of the face term, `γ h_F ∫_F [∂_n Δu]²`, which for a kink `κ` along a lattice plane
/// gives `γ h_F κ²` per unit of its measure in both. Zero for a displacement linear along
/// straight lattice lines (a lattice that the mesh motion bends by `δθ` between two
/// segments sees `|A δθ|²` of a linear field `A x`, on the edge cells only).
fn stencil_matrix(
    grid: &Grid,
    formulation: Formulation,
    thickness: f64,
    stencil: Stencil,
    gamma: f64,
) -> [f64; MAX_FACE_NODES * MAX_FACE_NODES] {
    let dim = grid.mesh.element.dim();
    let [a, b, c] = stencil.nodes.map(|n| grid.mesh.coords[n]);
    let distance = |p: [f64; 3], q: [f64; 3]| (0..dim).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt();
    let (l_ab, l_bc) = (distance(a, b), distance(b, c));
    let k = [1.0 / l_ab, -1.0 / l_ab - 1.0 / l_bc, 1.0 / l_bc];
    // the cross-section of one lattice line: the spacings along the other directions
    let spacing = grid.lattice_spacing().unwrap_or([l_ab.max(l_bc); 3]);
    let cross: f64 = (0..dim).filter(|&d| d != stencil.direction).map(|d| spacing[d]).product();
    let h_f = if dim == 2 { cross } else { cross.sqrt() };
    let out_of_plane = match formulation {
        Formulation::Axisymmetric => 2.0 * std::f64::consts::PI * b[0],
        _ if dim == 2 => thickness,
        _ => 1.0,
    };
    let w = gamma * h_f * cross * out_of_plane;
    let mut g = [0.0; MAX_FACE_NODES * MAX_FACE_NODES];
    for i in 0..3 {
        for j in 0..3 {
            g[i * 3 + j] = w * k[i] * k[j];
        }
    }
    g
}

/// Gauss rule over a face with `corners` corners: per point the corners' interpolation
/// weights and the point's weight in the face's parameter space (which sums to 1).
fn face_rule(corners: usize, dim: usize) -> Vec<([f64; 4], f64)> {
    let s = 0.5 - 0.5 / 3f64.sqrt();
    match (dim, corners) {
        // an edge: two points
        (2, 2) => vec![([1.0 - s, s, 0.0, 0.0], 0.5), ([s, 1.0 - s, 0.0, 0.0], 0.5)],
        // a triangle: the jump of linear shape functions is constant, one point
        (3, 3) => vec![([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0], 1.0)],
        // a quadrilateral in cyclic order: 2 × 2 points of the bilinear face map
        _ => {
            let t = [s, 1.0 - s];
            let mut rule = Vec::with_capacity(4);
            for &u in &t {
                for &v in &t {
                    rule.push(([(1.0 - u) * (1.0 - v), u * (1.0 - v), u * v, (1.0 - u) * v], 0.25));
                }
            }
            rule
        }
    }
}

/// Unit normal and measure (length or area) of a straight edge or a planar face.
fn face_normal(corners: &[[f64; 3]], dim: usize) -> ([f64; 3], f64) {
    if dim == 2 {
        let t = [corners[1][0] - corners[0][0], corners[1][1] - corners[0][1]];
        let length = (t[0] * t[0] + t[1] * t[1]).sqrt();
        return ([t[1] / length, -t[0] / length, 0.0], length);
    }
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let n = if corners.len() == 3 {
        cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]))
    } else {
        cross(sub(corners[2], corners[0]), sub(corners[3], corners[1]))
    };
    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    // a triangle's area, or a planar quadrilateral's from its diagonals: both ½ |n|
    ([n[0] / norm, n[1] / norm, n[2] / norm], 0.5 * norm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_fem::element::ElementType;

    /// `Δuᵀ G Δu` of the one face between two unit cells of `element` for the nodal field
    /// `field(x)` (one component).
    fn face_energy(element: ElementType, field: impl Fn(&[f64; 3]) -> f64) -> f64 {
        let grid = Grid::new([0.0; 3], [2.0, 1.0, 1.0], [2, 1, 1], element);
        let mut ghost = GhostPenalty::new(1.0);
        let cells: Vec<usize> = (0..grid.mesh.num_cells()).collect();
        ghost.rebuild(&grid, &cells, vec![true; cells.len()]);
        let mut energy = 0.0;
        for face in &ghost.faces {
            let g = face_matrix(&grid, Formulation::PlaneStrain, 1.0, face, 1.0).unwrap();
            let u: Vec<f64> = face.nodes.iter().map(|&a| field(&grid.mesh.coords[a])).collect();
            let nf = face.nodes.len();
            for a in 0..nf {
                for b in 0..nf {
                    energy += u[a] * g[a * nf + b] * u[b];
                }
            }
        }
        energy
    }

    /// The smooth bases' lines of three nodes: none acts on a displacement linear in x and y;
    /// a kink `u = κ (x − 1)⁺` gives each line through a node of x = 1 along x the energy
    /// `γ h_F h κ²` (h = 0.5), the face term's `γ h_F κ²` per unit length of the kink, and
    /// the lines along y nothing; every node with two neighbours along a direction has its
    /// line.
    #[test]
    fn lattice_lines_vanish_on_linear_fields_and_measure_a_kink_as_the_faces_do() {
        let mut grid = Grid::new([0.0; 3], [2.0, 1.0, 1.0], [4, 2, 1], ElementType::Quad4);
        grid.set_basis(crate::basis::Basis::Bspline2).unwrap();
        let mut ghost = GhostPenalty::new(1.0);
        let nodes = grid.mesh.coords.len();
        ghost.rebuild(&grid, &[], vec![true; grid.mesh.num_cells()]);
        ghost.add_lattice_lines(&grid, &vec![true; nodes]);
        // 5 × 3 nodes: 3 × 3 middles along x, 5 × 1 along y
        assert_eq!(ghost.stencils.len(), 9 + 5);
        let energy = |stencil: Stencil, field: &dyn Fn(&[f64; 3]) -> f64| {
            let g = stencil_matrix(&grid, Formulation::PlaneStrain, 1.0, stencil, 1.0);
            let u = stencil.nodes.map(|a| field(&grid.mesh.coords[a]));
            (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| u[i] * g[i * 3 + j] * u[j]).sum::<f64>()
        };
        let linear = |x: &[f64; 3]| 0.3 + 2.0 * x[0] - 1.5 * x[1];
        let kink = |x: &[f64; 3]| 0.7 * (x[0] - 1.0).max(0.0);
        for &stencil in &ghost.stencils {
            assert!(energy(stencil, &linear).abs() < 1e-12, "linear field on {:?}", stencil.nodes);
            let middle = grid.mesh.coords[stencil.nodes[1]];
            let expected =
                if stencil.direction == 0 && (middle[0] - 1.0).abs() < 1e-12 { 0.5 * 0.5 * 0.49 } else { 0.0 };
            let measured = energy(stencil, &kink);
            assert!(
                (measured - expected).abs() < 1e-12,
                "kink on {:?}: {measured} (expected {expected})",
                stencil.nodes
            );
        }
    }

    /// A displacement linear across the faces has no jump: the penalty does not act on it
    /// (consistency); a kink across the face x = 1, `u = (x − 1)⁺`, has the jump 1 of its
    /// normal derivative along the unit face: `γ h ∫ 1 dΓ = γ` with γ = 1, h = 1.
    #[test]
    fn penalty_vanishes_on_linear_fields_and_measures_a_kink() {
        let linear = face_energy(ElementType::Quad4, |x| 0.3 + 2.0 * x[0] - 1.5 * x[1]);
        assert!(linear.abs() < 1e-12, "linear field: {linear}");
        let kink = face_energy(ElementType::Quad4, |x| (x[0] - 1.0).max(0.0));
        println!("quad4: kink energy {kink} (exact 1)");
        assert!((kink - 1.0).abs() < 1e-12);
        // triangles: the linear field again, through the faces inside and between the cells
        let linear = face_energy(ElementType::Tri3, |x| 0.3 + 2.0 * x[0] - 1.5 * x[1]);
        assert!(linear.abs() < 1e-12, "tri3 linear field: {linear}");
    }

    /// Hexahedra: the linear field gives nothing, the kink across x = 1 gives `γ h A = 1`
    /// over the unit square face.
    #[test]
    fn hexahedral_faces() {
        let grid = Grid::new([0.0; 3], [2.0, 1.0, 1.0], [2, 1, 1], ElementType::Hex8);
        let mut ghost = GhostPenalty::new(1.0);
        ghost.rebuild(&grid, &[0, 1], vec![true; 2]);
        assert_eq!(ghost.faces.len(), 1);
        let face = &ghost.faces[0];
        let g = face_matrix(&grid, Formulation::ThreeD, 1.0, face, 1.0).unwrap();
        let energy = |field: &dyn Fn(&[f64; 3]) -> f64| {
            let u: Vec<f64> = face.nodes.iter().map(|&a| field(&grid.mesh.coords[a])).collect();
            let nf = face.nodes.len();
            (0..nf).flat_map(|a| (0..nf).map(move |b| (a, b))).map(|(a, b)| u[a] * g[a * nf + b] * u[b]).sum::<f64>()
        };
        assert!(energy(&|x| 1.0 + x[0] - 2.0 * x[1] + 0.5 * x[2]).abs() < 1e-12);
        let kink = energy(&|x| (x[0] - 1.0).max(0.0));
        assert!((kink - 1.0).abs() < 1e-12, "hex8 kink energy {kink}");
    }
}
