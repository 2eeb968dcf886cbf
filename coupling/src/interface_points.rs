//! A non-conforming interface between the facets of a structure and the soil of a fixed
//! background grid (issue 25: tie, frictionless and Coulomb contact): a [`Domain`] of
//! interface quadrature points.
//!
//! The structure's interface facets (2-node, 2D) carry two Gauss points each, of weight
//! `w = ½ L₀ t` (Gauss weight on `[0, 1]` × reference facet length × the formulation's
//! thickness, `2πr` in axisymmetry). The grid is fixed and need not conform: it keeps its
//! cells inside and around the structure, and the structure's nodes are never grid nodes.
//!
//! **Kinematics.** The soil's grid is reset at every step (updated Lagrangian: the grid
//! nodes' displacements are the step's increments `Δu_I`, measured from the grid's
//! reference position) and a material point moves by `Σ_I N_I(x_p^n) Δu_I`, its functions
//! taken where it was at the start of the step. The tie is written the same way: point `p`
//! of a facet, at `x_p^n = Σ_a φ_a (X_a + u_a^n)` at the start of the step, is located there
//! once ([`Domain::begin_step`]), and its gap is
//!
//! ```text
//! g = g_n + Σ_I N_I(x_p^n) Δu_I − Σ_a φ_a Δu_a,      Δu = u − u_n,
//! ```
//!
//! the soil material that was at the point at `t_n` moved by the grid's field there, the
//! structure's point by its own increment; `g_n` is the gap committed at the end of the
//! last step (the penalty's elastic offset that carries the interface force). The point's
//! law ([`InterfaceLaw`]: tie, or contact with Coulomb friction in the frame of the facet's
//! outward normal `n` at the start of the step) gives the traction on the structure `T(g)`
//! and `C = ∂T/∂g`; with `∂g/∂u_I = N_I I`, `∂g/∂u_a = −φ_a I` the point's residual is
//! `w N_I T` on the grid nodes and `−w φ_a T` on the facet nodes, and its exact tangent
//! `w (∂g/∂u)ᵀ C (∂g/∂u)` (for the tie `T = β g`: the gradient and Hessian of the penalty
//! energy `½ β w |g|²`, [`crate::tie::tie_point_block`] with the functions frozen; for
//! contact unsymmetric while sliding). Because
//! `N_I` is taken at `x_p^n`, the point does not move in the grid within the step and the
//! tangent needs no `∂N/∂x`: this is the MPM's own convention, not a simplification of it.
//! The normal is frozen the same way: a facet that turns by `Δθ` in a step mixes normal and
//! tangential gap by `Δθ |g|` (the carried gap is kept in global components), a penalty gap
//! of micrometres against rotations of milliradians per step.
//! (Evaluating `N_I` at the current position `x_p^n + Δu_S` instead would tie the soil
//! that started where the structure ends, a different material point, off by
//! `∇Δu · Δu_S` per step; the moving-point tangent of [`crate::tie`], which needs the
//! second derivatives of the grid functions, is for a grid whose field is total.)
//!
//! **Empty grid nodes.** The MPM domain gives equations only to the grid nodes its points'
//! functions reach (others keep their place by identity rows or are out of the system), and
//! the tie must not give a grid node its only equation. A point whose non-zero functions
//! all reach soil nodes ([`loam_mpm::mpm_domain::SoilNodes`]) uses them. Where the soil ends
//! at the structure inside a cell (or a smooth support), the nodes on the structure's side
//! are empty, and the soil's field is extrapolated to the point from the nodes it reaches:
//! on the linear basis the point takes the functions of the nearest cell around its own
//! (one ring, nearest centre) whose nodes the soil all reaches, the cell's map inverted
//! outside it; on a smooth basis the empty nodes' functions are folded into the support's
//! other nodes as those of a hole's removed nodes ([`loam_mpm::basis`]). Both reproduce
//! linear fields and keep the partition of unity. Otherwise (no such cell; a support
//! without soil) the point is skipped for the step and its carried gap reset to zero: there
//! is no soil there to tie to. A contact point whose soil does not press (`g_N ≥ 0`) is open
//! and carries no gap either: separation is measured within the step, not remembered (unless
//! the contact holds the soil's points, which track it: below). The set of active points and their
//! nodes is the domain's sparsity pattern: `begin_step` reports a change.
//!
//! **Open points** (contact). The grid's field reaches a cell beyond the soil's material, so
//! a contact point whose gap started at zero when the soil's nodes first reached it closed up
//! to a cell before the structure met the soil (measured: a disk dropped on soil met it 9.3 mm,
//! 0.93 of a cell, early; a cylinder pressed on a half-space had a contact 65 % wider than
//! Hertz's). A contact therefore holds the soil's material points at the start of each step
//! ([`loam_mpm::mpm_domain::SoilPoints`]: their positions and the squares of their sizes, as
//! the surface monitors see them) and gives an open point the normal gap
//! `g_n = d n`, `d` its distance along its facet's outward normal to the nearest square the
//! normal crosses ([`soil_distance`]; 0 inside the soil's squares, two cells if none is
//! crossed): when the soil's nodes first reach the point, and at every later step the smaller
//! of `d` and the separation it carried (an open point keeps its normal gap `max(g_N, 0) n`
//! at the end of a step), so that material arriving beside it is seen and a point that has
//! just opened does not need to travel back. A closed point carries its penetration as
//! before. The tie starts at zero (its soil is bonded where it is).
//!
//! **Penalty.** `β` (Pa/m, β_N of contact) is the case's `interfaces[].penalty`, by default
//! `DEFAULT_TIE_PENALTY_FACTOR · E_soil / h` (the stiffest body's Young's modulus over the
//! grid's cell size; see the model builder); contact's tangential `β_T` is
//! `interfaces[].tangential_penalty`, by default
//! `DEFAULT_TANGENTIAL_PENALTY_FACTOR · E_soil / h`.
//!
//! **Newton.** The stick/slip and open/closed states are those of the iterate (a semi-smooth
//! Newton method on the exact residual, with the exact tangent of the branch taken). A point
//! that slides has no tangential stiffness, so a body whose points all slide is held along
//! the interface only by its inertia, and a Newton correction of a sticking body lands in the
//! stick band `|t_T^tr| ≤ μ t_N` (of width `μ t_N / β_T` in slip) only if β_T is not orders of
//! magnitude stiffer than the body: hence the tangential default of `E_soil / h`, a hundredth
//! of the normal one, with which the sticking block of `cases/block_on_incline_stick.json`
//! converges (at `β_T = 100 E/h` its iterates cycle between sliding up and down the slope).
//!
//! Output: the points as a point cloud named after the interface (`gap`, `traction`,
//! `normal_gap`, `normal_traction`, `tangential_traction`, `state`: [`Domain::outputs`]).
//!
//! The domain's residual at the structure's facet nodes is the force the soil exerts on the
//! structure (`−r`), so it reports itself as soil ([`Domain::is_soil`]): the model's
//! `soil_forces`, and the `interface_force` monitor over the facet nodes, include it.

use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{AssemblyInput, Domain, DomainError, DomainOutput, Field, NamedOutput, NodalState, PointExtent};
use loam_fem::formulation::Formulation;
use loam_fem::rigid_body::RigidFrame;
use loam_mpm::grid::Grid;
use loam_mpm::mpm_domain::{SoilNodes, SoilPoints};

use crate::interface::{InterfaceError, Structure};
use crate::interface_law::{InterfaceLaw, LawResponse, PointState};

/// Penalty `β = factor · E_soil / h` of a tie when the case gives none (see the module doc;
/// the tip of benchmark 12 changes by less than 0.1 % between factors 10 and 1000, see
/// docs/coupling.md).
pub const DEFAULT_TIE_PENALTY_FACTOR: f64 = 100.0;

/// Tangential (stick) penalty `β_T = factor · E_soil / h` of a contact when the case gives
/// none (module doc, "Newton"): the elastic slip while sticking, `t_T / β_T`, is then that of a
/// soil layer one cell thick under the same shear stress.
pub const DEFAULT_TANGENTIAL_PENALTY_FACTOR: f64 = 1.0;

/// Functions smaller than this at a point do not tie it to their node.
const NEGLIGIBLE_FUNCTION: f64 = 1e-12;

/// The functions of `functions` that are not negligible.
fn significant(functions: Vec<(usize, f64)>) -> Vec<(usize, f64)> {
    functions.into_iter().filter(|(_, v)| v.abs() > NEGLIGIBLE_FUNCTION).collect()
}

/// How the structure's facets move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FacetMotion {
    /// Every facet node has its own displacement DOFs (an FEM structure); the facets' `nodes`
    /// are global node ids.
    Nodal,
    /// The facets belong to a rigid body ([`loam_fem::rigid_body`]): a facet point at `X` is at
    /// `X_c + u_c + R(θ)(X − X_c)`, its block's structure DOFs are the body's `[u_cx, u_cy, θ]`
    /// (the facets' `nodes` are the body mesh's own, unused).
    Rigid(RigidFrame),
}

/// A 2-node interface facet of the structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceFacet {
    /// Global node ids (the body mesh's own for a rigid body, [`FacetMotion::Rigid`]).
    pub nodes: [usize; 2],
    /// Reference coordinates of the nodes.
    pub reference: [[f64; 2]; 2],
}

/// An interface quadrature point: its facet, facet functions `φ_a` and weight `w`.
#[derive(Debug, Clone, Copy)]
struct TiePoint {
    facet: usize,
    phi: [f64; 2],
    weight: f64,
}

/// A point active at this step: the grid nodes (grid numbering) whose functions are non-zero
/// at its position at the start of the step, those functions' values, and its facet's
/// outward unit normal at the start of the step.
#[derive(Debug, Clone, PartialEq)]
struct ActivePoint {
    point: usize,
    nodes: Vec<usize>,
    values: Vec<f64>,
    normal: [f64; 2],
}

/// The committed state beyond the nodal unknowns.
#[derive(serde::Serialize, serde::Deserialize)]
struct TieState {
    gaps: Vec<[f64; 2]>,
    multipliers: Vec<f64>,
    tractions: Vec<[f64; 2]>,
    states: Vec<PointState>,
    force: [f64; 2],
    energy: f64,
    /// Per point, whether its gap is tracked from the soil's surface (contact with the soil's
    /// points; absent in older checkpoints).
    #[serde(default)]
    tracked: Vec<bool>,
}

/// A penalty tie or contact between a structure's facets and a fixed grid (see the module
/// doc).
pub struct InterfacePoints {
    name: String,
    formulation: Formulation,
    thickness: f64,
    grid: Grid,
    grid_ids: Vec<usize>,
    soil_nodes: SoilNodes,
    facets: Vec<InterfaceFacet>,
    /// How the facets move (an FEM structure's nodes, or a rigid body).
    motion: FacetMotion,
    points: Vec<TiePoint>,
    law: InterfaceLaw,
    /// Per point, the gap `g_n` committed at the end of the last step.
    gaps: Vec<[f64; 2]>,
    /// Per point, the augmented-Lagrangian multiplier λ_N (Pa) of the contact pressure
    /// committed at the end of the last step (0 without augmentation).
    multipliers: Vec<f64>,
    /// Per point, λ_N within the step (updated by [`Domain::augment`]).
    trial_multipliers: Vec<f64>,
    /// The penetration (m) above which a converged step updates the multipliers and is
    /// solved again (augmented Lagrangian, Uzawa); `None`: pure penalty.
    gap_tolerance: Option<f64>,
    /// Per point, the traction on the structure (Pa) and the state at the end of the last
    /// step (output).
    tractions: Vec<[f64; 2]>,
    states: Vec<PointState>,
    /// The points active at this step, in block order.
    active: Vec<ActivePoint>,
    /// Force (N) the soil exerted on the structure through the interface in the last
    /// converged step, `Σ_p w_p T_p`.
    force: [f64; 2],
    /// Penalty energy `Σ_p w_p ψ_p` at the last converged step ([`LawResponse::energy`]).
    energy: f64,
    /// The soil's material points at the start of the step (contact): a point's gap starts
    /// at its distance to them when the soil first reaches it ([`soil_distance`]).
    soil_points: Option<SoilPoints>,
    /// Per point, whether its gap is tracked: set from the soil's surface when the soil's
    /// nodes first reached it, carried since (open or closed) while they reach it.
    tracked: Vec<bool>,
    /// The grid's largest cell extent ([`InterfacePoints::largest_cell`]).
    largest_cell: f64,
    /// The cells around each grid node (CSR: `node_cells[node_cell_ptr[a]..node_cell_ptr[a + 1]]`),
    /// for the ring of cells around a point's ([`InterfacePoints::extrapolated`]).
    node_cell_ptr: Vec<usize>,
    node_cells: Vec<usize>,
}

impl InterfacePoints {
    /// An interface named `name` of the structure's `facets` to the soil on `grid` (fixed,
    /// not attached to any structure), whose node `a` is global node `grid_ids[a]` and whose
    /// reached nodes `soil_nodes` reports, with the point law `law`. 2D only.
    pub fn new(
        name: &str,
        formulation: Formulation,
        thickness: f64,
        grid: Grid,
        grid_ids: Vec<usize>,
        soil_nodes: SoilNodes,
        facets: Vec<InterfaceFacet>,
        law: InterfaceLaw,
    ) -> Self {
        debug_assert_eq!(grid.mesh.element.dim(), 2, "a tie is 2D");
        let a = 0.5 / 3f64.sqrt();
        let mut points = Vec::with_capacity(2 * facets.len());
        for (f, facet) in facets.iter().enumerate() {
            let [x0, x1] = facet.reference;
            let length = (x1[0] - x0[0]).hypot(x1[1] - x0[1]);
            for xi in [0.5 - a, 0.5 + a] {
                let radius = (1.0 - xi) * x0[0] + xi * x1[0];
                let weight = 0.5 * length * formulation.measure_factor(thickness, radius);
                points.push(TiePoint { facet: f, phi: [1.0 - xi, xi], weight });
            }
        }
        let n = points.len();
        let largest_cell = Self::largest_cell(&grid);
        let (node_cell_ptr, node_cells) = Self::cells_around_nodes(&grid);
        Self {
            name: name.to_string(),
            formulation,
            thickness,
            grid,
            grid_ids,
            soil_nodes,
            facets,
            motion: FacetMotion::Nodal,
            points,
            law,
            gaps: vec![[0.0; 2]; n],
            multipliers: vec![0.0; n],
            trial_multipliers: vec![0.0; n],
            gap_tolerance: None,
            tractions: vec![[0.0; 2]; n],
            states: vec![PointState::Open; n],
            active: Vec::new(),
            force: [0.0; 2],
            energy: 0.0,
            soil_points: None,
            tracked: vec![false; n],
            largest_cell,
            node_cell_ptr,
            node_cells,
        }
    }

    /// The cells around each node of `grid`, CSR (see the fields).
    fn cells_around_nodes(grid: &Grid) -> (Vec<usize>, Vec<usize>) {
        let mesh = &grid.mesh;
        let mut count = vec![0usize; mesh.coords.len() + 1];
        for c in 0..mesh.num_cells() {
            for &a in mesh.cell(c) {
                count[a + 1] += 1;
            }
        }
        for a in 0..mesh.coords.len() {
            count[a + 1] += count[a];
        }
        let mut cells = vec![0; count[mesh.coords.len()]];
        let mut next = count.clone();
        for c in 0..mesh.num_cells() {
            for &a in mesh.cell(c) {
                cells[next[a]] = c;
                next[a] += 1;
            }
        }
        (count, cells)
    }

    /// The cells sharing a node with `cell` (itself included), ascending.
    fn ring(&self, cell: usize) -> Vec<usize> {
        let mut ring: Vec<usize> = self
            .grid
            .mesh
            .cell(cell)
            .iter()
            .flat_map(|&a| self.node_cells[self.node_cell_ptr[a]..self.node_cell_ptr[a + 1]].iter().copied())
            .collect();
        ring.sort_unstable();
        ring.dedup();
        ring
    }

    /// The same contact with the soil's material points (module doc, "Open points"): a point
    /// that the soil's nodes reach for the first time starts at its distance from the soil's
    /// surface, and its gap is tracked from there while they reach it, so that it closes where
    /// the structure meets the points' material, not where it enters the cells next to them.
    pub fn with_soil_points(mut self, soil_points: SoilPoints) -> Self {
        self.soil_points = Some(soil_points);
        self
    }

    /// The same interface with the augmented Lagrangian: a converged step whose largest
    /// penetration `−g_N` exceeds `gap_tolerance` (m) updates every point's multiplier to its
    /// contact pressure, `λ_N ← max(0, λ_N − β_N g_N)`, and is solved again (Uzawa's
    /// iteration; Laursen 2002, §6.4), so the penetration falls below the tolerance whatever
    /// the penalty. Contact only (a tie keeps its penalty gap).
    pub fn with_gap_tolerance(mut self, gap_tolerance: f64) -> Self {
        self.gap_tolerance = Some(gap_tolerance);
        self
    }

    /// The same interface on the facets of a rigid body whose unknowns are at `frame`
    /// ([`FacetMotion::Rigid`]; module doc, "Rigid structures").
    pub fn on_rigid_body(mut self, frame: RigidFrame) -> Self {
        self.motion = FacetMotion::Rigid(frame);
        self
    }

    /// The penalty `β` (Pa/m; β_N of contact).
    pub fn penalty(&self) -> f64 {
        self.law.penalty()
    }

    /// The points' law.
    pub fn law(&self) -> InterfaceLaw {
        self.law
    }

    /// Number of interface quadrature points, and of those active at this step.
    pub fn num_points(&self) -> (usize, usize) {
        (self.points.len(), self.active.len())
    }

    /// Force (N) the soil exerted on the structure through the interface in the last
    /// converged step.
    pub fn force(&self) -> [f64; 2] {
        self.force
    }

    /// The global DOFs of an active point's block: its grid nodes, then its facet's nodes
    /// (a rigid body's `[u_cx, u_cy, θ]`).
    fn block_dofs(&self, p: &ActivePoint) -> Vec<usize> {
        let grid = p.nodes.iter().map(|&a| self.grid_ids[a]).flat_map(|g| [2 * g, 2 * g + 1]);
        match self.motion {
            FacetMotion::Nodal => {
                let facet = &self.facets[self.points[p.point].facet];
                grid.chain(facet.nodes.iter().flat_map(|&g| [2 * g, 2 * g + 1])).collect()
            }
            FacetMotion::Rigid(frame) => grid.chain(frame.dofs()).collect(),
        }
    }

    /// Residual, tangent and law response of an active point at the iterate of `input`:
    /// `r_j = w (∂g/∂q_j) · T`, `K_ij = w (∂g/∂q_i)ᵀ C (∂g/∂q_j) + w (∂²g/∂q_i∂q_j) · T`, block
    /// DOFs as in [`InterfacePoints::block_dofs`] ([`InterfacePoints::gap_columns`]; the second
    /// derivative is that of a rigid body's rotation, `∂²g/∂θ² = R(θ) r_p`).
    fn point_block(&self, p: &ActivePoint, input: &AssemblyInput<'_>) -> (Vec<f64>, Vec<f64>, LawResponse) {
        let point = &self.points[p.point];
        let columns = self.gap_columns(p, &input.state.u);
        let gap = self.point_gap(p, input);
        let response = self.law.response(gap, p.normal, self.trial_multipliers[p.point]);
        let nd = columns.len();
        let w = point.weight;
        let t = response.traction;
        let residual: Vec<f64> = columns.iter().map(|c| w * (c[0] * t[0] + c[1] * t[1])).collect();
        let mut tangent = vec![0.0; nd * nd];
        let c = &response.tangent;
        for (i, ci) in columns.iter().enumerate() {
            let cci = [ci[0] * c[0][0] + ci[1] * c[1][0], ci[0] * c[0][1] + ci[1] * c[1][1]];
            for (j, cj) in columns.iter().enumerate() {
                tangent[i * nd + j] = w * (cci[0] * cj[0] + cci[1] * cj[1]);
            }
        }
        if let FacetMotion::Rigid(frame) = self.motion {
            let (_, theta) = frame.unknowns(&input.state.u);
            let r = RigidFrame::rotate(theta, self.rigid_arm(p.point, frame));
            tangent[nd * nd - 1] += w * (r[0] * t[0] + r[1] * t[1]);
        }
        (residual, tangent, response)
    }

    /// The columns `∂g/∂q_j` of an active point's block at displacements `u` (one per block
    /// DOF): `N_I e_k` on its grid nodes; `−φ_a e_k` on its facet's nodes, or for a rigid body
    /// `−e_x`, `−e_y` and `−R′(θ) r_p` (module doc).
    fn gap_columns(&self, p: &ActivePoint, u: &[f64]) -> Vec<[f64; 2]> {
        let point = &self.points[p.point];
        let grid = p.values.iter().flat_map(|&n| [[n, 0.0], [0.0, n]]);
        match self.motion {
            FacetMotion::Nodal => grid.chain(point.phi.iter().flat_map(|&phi| [[-phi, 0.0], [0.0, -phi]])).collect(),
            FacetMotion::Rigid(frame) => {
                let (_, theta) = frame.unknowns(u);
                let r = self.rigid_arm(p.point, frame);
                let (s, c) = theta.sin_cos();
                grid.chain([[-1.0, 0.0], [0.0, -1.0], [s * r[0] + c * r[1], s * r[1] - c * r[0]]]).collect()
            }
        }
    }

    /// The arm `r_p = Σ_a φ_a (X_a − X_c)` of point `p` on a rigid body.
    fn rigid_arm(&self, p: usize, frame: RigidFrame) -> [f64; 2] {
        let point = &self.points[p];
        let facet = &self.facets[point.facet];
        let x = |k: usize| point.phi[0] * facet.reference[0][k] + point.phi[1] * facet.reference[1][k];
        frame.arm([x(0), x(1)])
    }

    /// The gap `g = g_n + Σ_I N_I Δu_I − Δx_p` of an active point at the iterate, `Δx_p` the
    /// structure point's motion in the step (`Σ_a φ_a Δu_a`, or a rigid body's).
    fn point_gap(&self, p: &ActivePoint, input: &AssemblyInput<'_>) -> [f64; 2] {
        let (u, un) = (&input.state.u, &input.committed.u);
        let mut gap = self.gaps[p.point];
        for (&a, &n) in p.nodes.iter().zip(&p.values) {
            let g = self.grid_ids[a];
            for k in 0..2 {
                gap[k] += n * (u[2 * g + k] - un[2 * g + k]);
            }
        }
        match self.motion {
            FacetMotion::Nodal => {
                let point = &self.points[p.point];
                for (&g, phi) in self.facets[point.facet].nodes.iter().zip(point.phi) {
                    for k in 0..2 {
                        gap[k] -= phi * (u[2 * g + k] - un[2 * g + k]);
                    }
                }
            }
            FacetMotion::Rigid(frame) => {
                let r = self.rigid_arm(p.point, frame);
                let ((uc, theta), (uc_n, theta_n)) = (frame.unknowns(u), frame.unknowns(un));
                let (x, x_n) = (RigidFrame::rotate(theta, r), RigidFrame::rotate(theta_n, r));
                for k in 0..2 {
                    gap[k] -= uc[k] - uc_n[k] + x[k] - x_n[k];
                }
            }
        }
        gap
    }

    /// Current position of node `a` (0 or 1) of `facet` at displacements `u`.
    fn facet_node_position(&self, facet: &InterfaceFacet, a: usize, u: &[f64]) -> [f64; 2] {
        let reference = facet.reference[a];
        match self.motion {
            FacetMotion::Nodal => {
                let g = facet.nodes[a];
                [reference[0] + u[2 * g], reference[1] + u[2 * g + 1]]
            }
            FacetMotion::Rigid(frame) => frame.position(reference, u),
        }
    }

    /// Outward unit normal of point `p`'s facet at the committed state (the facet's nodes run
    /// counter-clockwise around their element, as [`loam_fem::mesh::Mesh::boundary_facets`]
    /// gives them).
    fn committed_normal(&self, p: usize, committed: &NodalState) -> [f64; 2] {
        let facet = &self.facets[self.points[p].facet];
        let x = [0, 1].map(|a| self.facet_node_position(facet, a, &committed.u));
        let (dx, dy) = (x[1][0] - x[0][0], x[1][1] - x[0][1]);
        let length = dx.hypot(dy);
        [dy / length, -dx / length]
    }

    /// The functions at `x` extrapolated from the nodes the soil reaches (module doc): on
    /// the linear basis those of the cell nearest to `x` (by its centre) among those sharing
    /// a node with the cell holding `x` whose nodes the soil all reaches; on a smooth basis
    /// the point's own with the empty nodes' functions folded into the others. `None`
    /// without such a cell, or a support without soil.
    fn extrapolated(&self, x: &[f64; 3], reached: &[bool]) -> Option<Vec<(usize, f64)>> {
        if self.grid.basis().is_smooth() {
            return self.grid.functions_without(x, |a| !reached[a]).map(significant);
        }
        let (cell, _) = self.grid.locate(x)?;
        let distance = |c: usize| {
            let centre = self.grid.reference_centre(c);
            (centre[0] - x[0]).hypot(centre[1] - x[1])
        };
        let nearest = self
            .ring(cell)
            .into_iter()
            .filter(|&c| self.grid.mesh.cell(c).iter().all(|&a| reached[a]))
            .min_by(|&a, &b| distance(a).total_cmp(&distance(b)))?;
        self.grid.cell_functions_at(nearest, x).map(significant)
    }

    /// The grid's largest cell extent along x or y (the reach of an open point's search for
    /// the soil's points: two of them).
    fn largest_cell(grid: &Grid) -> f64 {
        (0..grid.mesh.num_cells()).flat_map(|c| grid.cell_extent(c)).fold(0.0, f64::max)
    }

    /// Position of point `p` at the committed state `x_p^n = Σ_a φ_a (X_a + u_a^n)`.
    fn committed_position(&self, p: usize, committed: &NodalState) -> [f64; 3] {
        let point = &self.points[p];
        let facet = &self.facets[point.facet];
        let mut x = [0.0; 3];
        for a in 0..2 {
            let xa = self.facet_node_position(facet, a, &committed.u);
            for k in 0..2 {
                x[k] += point.phi[a] * xa[k];
            }
        }
        x
    }
}

/// The soil points within `reach` of any of `positions` (a box test), as `(x, y, half size)`
/// with the half size `min(s, s₀)/2` of the surface monitors ([`PointExtent::half_height`]).
fn points_near(soil: &[PointExtent], positions: impl Iterator<Item = [f64; 3]>, reach: f64) -> Vec<[f64; 3]> {
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for x in positions {
        for d in 0..2 {
            lo[d] = lo[d].min(x[d] - reach);
            hi[d] = hi[d].max(x[d] + reach);
        }
    }
    soil.iter()
        .filter(|p| (0..2).all(|d| p.position[d] >= lo[d] && p.position[d] <= hi[d]))
        .map(|p| [p.position[0], p.position[1], p.half_height()])
        .collect()
}

/// Distance (m, ≥ 0) from an interface point at `x` along its facet's outward normal `n` to
/// the soil's material: each soil point `(x_p, y_p, e_p)` stands for the square of half side
/// `e_p` around it (as the surface monitors see it, [`loam_mpm::surface`]); the ray `x + s n`
/// enters a square at `s = max_k min((x_p,k ∓ e_p − x_k)/n_k)` and leaves it at
/// `max_k`-`min` the other way (the slab test), and the nearest entry of the squares it crosses
/// within `reach` is the gap; `reach` if none is crossed, 0 where the point already lies in
/// the soil's squares. The gap of an open contact point starts a step here (module doc, "Open
/// points"). (The plane through a square's corner nearest along `n`, used before, lies up to
/// `2 e_p sin φ` nearer than the face the ray meets on a surface inclined by `φ` to the facet:
/// the leading side of a disk sliding over soil then closed early and ploughed.)
fn soil_distance(near: &[[f64; 3]], x: [f64; 2], n: [f64; 2], reach: f64) -> f64 {
    let mut d = reach;
    for p in near {
        let e = p[2];
        let (mut entry, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 0..2 {
            let (lo, hi) = (p[k] - e - x[k], p[k] + e - x[k]);
            if n[k].abs() < 1e-300 {
                if lo > 0.0 || hi < 0.0 {
                    (entry, exit) = (f64::INFINITY, f64::NEG_INFINITY); // beside the ray
                }
                continue;
            }
            let (a, b) = (lo / n[k], hi / n[k]);
            entry = entry.max(a.min(b));
            exit = exit.min(a.max(b));
        }
        if entry <= exit && exit >= 0.0 {
            d = d.min(entry);
        }
    }
    d.clamp(0.0, reach)
}

/// The facets of a tie: the boundary edges of the structure's mesh whose nodes all lie in
/// `region` (mesh numbering), and their total reference length. Refused (naming the
/// structure, and a coordinate): a 3D mesh, a region holding no boundary edge, a facet node
/// outside the grid (the soil must surround the interface).
pub fn tie_facets(
    structure: &Structure<'_>,
    region: &[usize],
    grid: &Grid,
) -> Result<(Vec<[usize; 2]>, f64), InterfaceError> {
    let fail = |message: String| InterfaceError { interface: None, message };
    let mesh = structure.mesh;
    if mesh.element.dim() != 2 {
        return Err(fail("a non-conforming interface (tie or contact) is 2D only so far (issue 25)".into()));
    }
    let region: std::collections::HashSet<usize> = region.iter().copied().collect();
    let facets: Vec<[usize; 2]> = mesh
        .boundary_facets()
        .into_iter()
        .filter(|f| f.iter().all(|a| region.contains(a)))
        .map(|f| [f[0], f[1]])
        .collect();
    if facets.is_empty() {
        return Err(fail(format!("its region contains no boundary edge of the mesh of '{}'", structure.name)));
    }
    let mut length = 0.0;
    for f in &facets {
        let [x0, x1] = f.map(|a| mesh.coords[a]);
        length += (x1[0] - x0[0]).hypot(x1[1] - x0[1]);
        if let Some(x) = [x0, x1].into_iter().find(|x| grid.locate(x).is_none()) {
            return Err(fail(format!(
                "the node of '{}' at ({}, {}) lies outside the soil's grid: a non-conforming interface needs the grid around its facets",
                structure.name, x[0], x[1]
            )));
        }
    }
    Ok((facets, length))
}

impl Domain for InterfacePoints {
    fn name(&self) -> &str {
        &self.name
    }

    fn formulation(&self) -> Formulation {
        self.formulation
    }

    fn thickness(&self) -> f64 {
        self.thickness
    }

    /// Locates every point at its committed position and keeps those whose grid nodes the
    /// soil reaches (module doc); `true` if the active points or their nodes changed.
    fn begin_step(&mut self, committed: &mut NodalState) -> Result<bool, DomainError> {
        let reached = self.soil_nodes.read().expect("no writer panicked").clone();
        let mut active = Vec::with_capacity(self.points.len());
        for p in 0..self.points.len() {
            let x = self.committed_position(p, committed);
            let functions: Vec<(usize, f64)> = self
                .grid
                .functions_with_hessian(&x)
                .unwrap_or_default()
                .into_iter()
                .map(|(a, f)| (a, f.value))
                .collect();
            let soil = |f: &[(usize, f64)]| !f.is_empty() && f.iter().all(|&(a, _)| reached[a]);
            let functions = significant(functions);
            // no soil at any of its nodes: none in the ring of cells around either (a cell of
            // the ring shares a node with the point's own), so nothing to extrapolate from
            let near_soil = functions.iter().any(|&(a, _)| reached[a]);
            let functions = match (soil(&functions), near_soil) {
                (true, _) => Some(functions),
                (false, true) => self.extrapolated(&x, &reached),
                (false, false) => None,
            };
            let Some(functions) = functions.filter(|f| soil(f)) else {
                self.gaps[p] = [0.0; 2];
                self.multipliers[p] = 0.0;
                self.tracked[p] = false;
                continue;
            };
            let (nodes, values) = functions.into_iter().unzip();
            let normal = self.committed_normal(p, committed);
            active.push(ActivePoint { point: p, nodes, values, normal });
        }
        let changed = active.len() != self.active.len()
            || active.iter().zip(&self.active).any(|(a, b)| a.point != b.point || a.nodes != b.nodes);
        if let Some(soil_points) = self.soil_points.as_ref().filter(|_| self.law.is_contact()) {
            let soil = soil_points.read().expect("no writer panicked");
            let reach = 2.0 * self.largest_cell;
            let near = points_near(&soil, active.iter().map(|a| self.committed_position(a.point, committed)), reach);
            for a in &active {
                let carried = self.gaps[a.point];
                let carried_normal = carried[0] * a.normal[0] + carried[1] * a.normal[1];
                if self.tracked[a.point] && carried_normal < 0.0 {
                    continue; // closed: it carries its penetration
                }
                // open: its distance to the soil's points, or less if it has closed in on it
                let x = self.committed_position(a.point, committed);
                let mut d = soil_distance(&near, [x[0], x[1]], a.normal, reach);
                if self.tracked[a.point] {
                    d = d.min(carried_normal);
                }
                self.gaps[a.point] = [d * a.normal[0], d * a.normal[1]];
                self.tracked[a.point] = true;
            }
        }
        self.active = active;
        self.trial_multipliers.clone_from(&self.multipliers);
        Ok(changed)
    }

    fn is_soil(&self) -> bool {
        true
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        for p in &self.active {
            layout.push(self.block_dofs(p));
        }
    }

    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let (mut vector_at, mut matrix_at) = (0, 0);
        for p in &self.active {
            let (residual, tangent, _) = self.point_block(p, input);
            let nd = residual.len();
            vectors[vector_at..vector_at + nd].copy_from_slice(&residual);
            if input.with_tangent {
                let km = &mut matrices[matrix_at..matrix_at + nd * nd];
                if input.stiffness {
                    km.copy_from_slice(&tangent);
                } else {
                    km.fill(0.0);
                }
            }
            vector_at += nd;
            matrix_at += nd * nd;
        }
        Ok(())
    }

    fn commit(&mut self, input: &AssemblyInput<'_>) {
        let (mut force, mut energy) = ([0.0; 2], 0.0);
        let n = self.points.len();
        let mut gaps = vec![[0.0; 2]; n];
        let mut tractions = vec![[0.0; 2]; n];
        let mut states = vec![PointState::Open; n];
        for p in &self.active {
            let (_, _, response) = self.point_block(p, input);
            let w = self.points[p.point].weight;
            for k in 0..2 {
                force[k] += w * response.traction[k];
            }
            energy += w * response.energy;
            gaps[p.point] = response.carried;
            if response.state == PointState::Open && self.tracked[p.point] {
                // an open tracked point keeps its separation (normal part), to close it later
                let g = self.point_gap(p, input);
                let gn = (g[0] * p.normal[0] + g[1] * p.normal[1]).max(0.0);
                gaps[p.point] = [gn * p.normal[0], gn * p.normal[1]];
            }
            tractions[p.point] = response.traction;
            states[p.point] = response.state;
        }
        self.gaps = gaps;
        self.tractions = tractions;
        self.states = states;
        self.force = force;
        self.energy = energy;
        // the multipliers of the points the soil reached; the others release
        let mut multipliers = vec![0.0; n];
        for p in &self.active {
            multipliers[p.point] = self.trial_multipliers[p.point];
        }
        self.multipliers = multipliers;
    }

    fn augment(&mut self, input: &AssemblyInput<'_>) -> bool {
        let Some(tolerance) = self.gap_tolerance else { return false };
        if !self.law.is_contact() {
            return false;
        }
        let mut updated = Vec::with_capacity(self.active.len());
        let mut penetration = 0.0f64;
        for p in &self.active {
            let (_, _, response) = self.point_block(p, input);
            let pressure = -(response.traction[0] * p.normal[0] + response.traction[1] * p.normal[1]);
            if response.state != PointState::Open {
                let gn = (pressure - self.trial_multipliers[p.point]) / -self.law.penalty();
                penetration = penetration.max(-gn);
            }
            updated.push((p.point, pressure.max(0.0)));
        }
        if penetration <= tolerance {
            return false;
        }
        for (point, pressure) in updated {
            self.trial_multipliers[point] = pressure;
        }
        true
    }

    fn kinetic_energy(&self, _v: &[f64]) -> f64 {
        0.0
    }

    /// The penalty energy stored in the tie.
    fn strain_energy(&self) -> f64 {
        self.energy
    }

    fn boundary_facets(&self) -> Vec<Vec<usize>> {
        Vec::new()
    }

    fn save_state(&self) -> Vec<u8> {
        let state = TieState {
            gaps: self.gaps.clone(),
            multipliers: self.multipliers.clone(),
            tractions: self.tractions.clone(),
            states: self.states.clone(),
            force: self.force,
            energy: self.energy,
            tracked: self.tracked.clone(),
        };
        bincode::serialize(&state).expect("a tie's state encodes")
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let state: TieState = bincode::deserialize(bytes).map_err(|e| format!("interface '{}': {e}", self.name))?;
        let n = self.points.len();
        if state.gaps.len() != n
            || state.multipliers.len() != n
            || state.tractions.len() != n
            || state.states.len() != n
        {
            return Err(format!(
                "interface '{}': the checkpoint has {} tie points, the case {}",
                self.name,
                state.gaps.len(),
                self.points.len()
            ));
        }
        self.gaps = state.gaps;
        self.multipliers = state.multipliers;
        self.tractions = state.tractions;
        self.states = state.states;
        self.force = state.force;
        self.energy = state.energy;
        self.tracked = if state.tracked.len() == n { state.tracked } else { vec![false; n] };
        Ok(())
    }

    /// The interface points as a point cloud named after the interface, at their committed
    /// positions, with the state of the last converged step: `gap` (m, the carried gap
    /// `g_n`), `traction` on the structure `T` (Pa), `normal_gap` `g_N = g · n` (m, negative
    /// where the soil presses), `normal_traction` (the contact pressure `−T · n`, Pa),
    /// `tangential_traction` `T · τ` (Pa, `τ = (−n_y, n_x)`), `state` (0 open or without
    /// soil, 1 tied or sticking, 2 sliding) and, for a tie, `tied` (1 where the point was
    /// active).
    fn outputs(&self, committed: &NodalState, _with_grid: bool) -> Vec<NamedOutput> {
        let n = self.points.len();
        let points = (0..n).map(|p| self.committed_position(p, committed)).collect();
        let normals: Vec<[f64; 2]> = (0..n).map(|p| self.committed_normal(p, committed)).collect();
        let vector = |v: &[[f64; 2]]| v.iter().flat_map(|g| [g[0], g[1], 0.0]).collect();
        let along = |v: &[[f64; 2]], scale: f64, tangential: bool| {
            v.iter()
                .zip(&normals)
                .map(|(v, n)| {
                    let d = if tangential { [-n[1], n[0]] } else { *n };
                    scale * (v[0] * d[0] + v[1] * d[1])
                })
                .collect()
        };
        let field = |name: &str, components: usize, values: Vec<f64>| Field { name: name.into(), components, values };
        let mut point_fields = vec![
            field("gap", 3, vector(&self.gaps)),
            field("traction", 3, vector(&self.tractions)),
            field("normal_gap", 1, along(&self.gaps, 1.0, false)),
            field("normal_traction", 1, along(&self.tractions, -1.0, false)),
            field("tangential_traction", 1, along(&self.tractions, 1.0, true)),
            field("state", 1, self.states.iter().map(|s| s.code()).collect()),
        ];
        if !self.law.is_contact() {
            let mut tied = vec![0.0; n];
            for p in &self.active {
                tied[p.point] = 1.0;
            }
            point_fields.push(field("tied", 1, tied));
        }
        let output = DomainOutput { points, cells: None, point_fields, cell_fields: Vec::new() };
        vec![NamedOutput { name: self.name.clone(), output }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_fem::element::ElementType;
    use std::sync::{Arc, RwLock};

    /// Dense global residual and tangent of a tie domain at `input` (DOFs `0..n`).
    fn assembled(tie: &mut InterfacePoints, input: &AssemblyInput<'_>, n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut layout = BlockLayout::default();
        tie.blocks(&mut layout);
        let (mut m, mut v) = (vec![0.0; layout.matrix_len()], vec![0.0; layout.vector_len()]);
        tie.assemble(input, &mut m, &mut v).unwrap();
        let (mut r, mut k) = (vec![0.0; n], vec![0.0; n * n]);
        for b in 0..layout.num_blocks() {
            let dofs = &layout.dofs[layout.dof_ptr[b]..layout.dof_ptr[b + 1]];
            let nd = dofs.len();
            for (i, &p) in dofs.iter().enumerate() {
                r[p] += v[layout.dof_ptr[b] + i];
                for (j, &q) in dofs.iter().enumerate() {
                    k[p * n + q] += m[layout.matrix_offset[b] + i * nd + j];
                }
            }
        }
        (r, k)
    }

    fn input<'a>(state: &'a NodalState, committed: &'a NodalState) -> AssemblyInput<'a> {
        AssemblyInput::static_tangent(state, committed)
    }

    /// A bilinear grid of 4 × 2 cells (h = 0.1) and an inclined three-facet structure
    /// boundary across it with the point law `law`, displaced at the start of the step, with
    /// a carried gap from a first step: the assembled tangent of the whole domain against
    /// central differences of its residual (the largest relative error returned); the force
    /// on the structure equal and opposite to the grid's; the points' states at the iterate.
    /// With `rigid`, the facets belong to a rigid body whose unknowns `[u_c, θ]` are the
    /// first DOFs of the two nodes after the grid's, turned by a few milliradians.
    fn check_domain_tangent(law: InterfaceLaw, amplitude: f64, rigid: bool) -> (f64, Vec<PointState>) {
        let grid = Grid::new([0.0; 3], [0.4, 0.2, 0.0], [4, 2, 1], ElementType::Quad4);
        let grid_nodes = grid.mesh.coords.len();
        let ids: Vec<usize> = (0..grid_nodes).collect();
        let soil: SoilNodes = Arc::new(RwLock::new(vec![true; grid_nodes]));
        let s = grid_nodes;
        let reference = [[0.13, 0.02], [0.19, 0.09], [0.27, 0.17], [0.36, 0.11]];
        let facets = (0..3)
            .map(|f| InterfaceFacet { nodes: [s + f, s + f + 1], reference: [reference[f], reference[f + 1]] })
            .collect();
        let tie = InterfacePoints::new("cut", Formulation::PlaneStrain, 1.0, grid, ids, soil, facets, law);
        let frame = RigidFrame { centre: [0.23, 0.06], centre_node: s, rotation_node: s + 1 };
        let mut tie = if rigid { tie.on_rigid_body(frame) } else { tie };
        let n = if rigid { 2 * (grid_nodes + 2) } else { 2 * (grid_nodes + 4) };
        let wave = |k: usize, a: f64| a * ((k * 7 + 3) as f64).sin();
        // step 1 from rest, committed: a gap to carry
        let mut committed = NodalState::zeros(n);
        assert!(tie.begin_step(&mut committed).unwrap(), "the first pattern");
        let mut state = committed.clone();
        state.u.iter_mut().enumerate().for_each(|(k, u)| *u = wave(k, 4.0 * amplitude));
        tie.commit(&input(&state, &committed));
        assert!(tie.gaps.iter().any(|g| g[0].abs() > 1e-2 * amplitude), "a gap is carried");
        // step 2: the structure at its committed place, the grid reset
        committed.u.clone_from(&state.u);
        committed.u[..2 * grid_nodes].fill(0.0);
        tie.begin_step(&mut committed).unwrap();
        assert_eq!(tie.num_points(), (6, 6));
        let mut u = committed.clone();
        u.u.iter_mut().enumerate().for_each(|(k, v)| *v += wave(k + 5, 3.0 * amplitude));
        // the soil moved down by 0.3 amplitudes: it leaves some of the facets (their normals
        // point down)
        for a in 0..grid_nodes {
            u.u[2 * a + 1] -= 0.3 * amplitude;
        }
        let (r, k) = assembled(&mut tie, &input(&u, &committed), n);
        let states = tie.active.iter().map(|p| tie.point_block(p, &input(&u, &committed)).2.state).collect();
        let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        let h = 1e-7 * amplitude / 1e-3;
        for q in 0..n {
            let (mut p, mut m) = (u.clone(), u.clone());
            p.u[q] += h;
            m.u[q] -= h;
            let (rp, _) = assembled(&mut tie, &input(&p, &committed), n);
            let (rm, _) = assembled(&mut tie, &input(&m, &committed), n);
            for i in 0..n {
                worst = worst.max(((rp[i] - rm[i]) / (2.0 * h) - k[i * n + q]).abs() / kmax);
            }
        }
        // the soil's and the structure's forces balance
        for c in 0..2 {
            let grid_sum: f64 = (0..grid_nodes).map(|a| r[2 * a + c]).sum();
            let structure_sum: f64 = match rigid {
                true => r[2 * s + c],
                false => (grid_nodes..grid_nodes + 4).map(|a| r[2 * a + c]).sum(),
            };
            assert!((grid_sum + structure_sum).abs() < 1e-9 * grid_sum.abs().max(1.0), "{grid_sum} vs {structure_sum}");
        }
        (worst, states)
    }

    #[test]
    fn assembled_tangent_matches_central_differences() {
        for rigid in [false, true] {
            let (worst, _) = check_domain_tangent(InterfaceLaw::Tie { penalty: 3.0e9 }, 1e-3, rigid);
            println!(
                "tie domain (rigid {rigid}): assembled tangent vs central differences, relative error {worst:.2e}"
            );
            assert!(worst < 1e-7, "{worst:.2e}");
        }
    }

    /// Frictionless and Coulomb contact on the same blocks, on an elastic structure's facets
    /// and on a rigid body's: the assembled (for friction, unsymmetric) tangent against
    /// central differences, relative error < 1e-6, with points open, sticking and sliding at
    /// the iterate.
    #[test]
    fn contact_tangent_matches_central_differences() {
        for (friction, rigid) in [(0.0, false), (0.3, false), (0.0, true), (0.3, true)] {
            let law = InterfaceLaw::Contact { normal_penalty: 3.0e9, tangential_penalty: 1.0e9, friction };
            let (worst, states) = check_domain_tangent(law, 1e-3, rigid);
            println!(
                "contact μ = {friction} (rigid {rigid}): tangent vs central differences, relative error {worst:.2e}, states {states:?}"
            );
            assert!(worst < 1e-6, "{worst:.2e}");
            let has = |s: PointState| states.contains(&s);
            assert!(has(PointState::Open) && has(PointState::Slip), "{states:?}");
            assert!(friction == 0.0 || has(PointState::Stick), "{states:?}");
        }
    }

    /// A point in a cell with a node the soil does not reach: on the linear basis it takes
    /// the functions of the nearest neighbouring cell that the soil fills, extrapolated; on
    /// B-splines the empty node's function is folded into the others; both a partition of
    /// unity reproducing `x` without the empty node. The pattern changes when the soil
    /// reaches the node; without any soil the points are skipped.
    #[test]
    fn points_beside_empty_nodes_take_the_soil_field_extrapolated() {
        for basis in [loam_mpm::basis::Basis::Linear, loam_mpm::basis::Basis::Bspline2] {
            let mut grid = Grid::new([0.0; 3], [0.4, 0.2, 0.0], [4, 2, 1], ElementType::Quad4);
            grid.set_basis(basis).unwrap();
            let coords = grid.mesh.coords.clone();
            let grid_nodes = coords.len();
            let mut reached = vec![true; grid_nodes];
            reached[grid_nodes - 1] = false; // the top right corner (0.4, 0.2)
            let soil: SoilNodes = Arc::new(RwLock::new(reached));
            let facets =
                vec![InterfaceFacet { nodes: [grid_nodes, grid_nodes + 1], reference: [[0.05, 0.05], [0.39, 0.19]] }];
            let ids = (0..grid_nodes).collect();
            let law = InterfaceLaw::Tie { penalty: 1.0 };
            let mut tie =
                InterfacePoints::new("cut", Formulation::PlaneStrain, 1.0, grid, ids, soil.clone(), facets, law);
            let mut committed = NodalState::zeros(2 * (grid_nodes + 2));
            tie.begin_step(&mut committed).unwrap();
            assert_eq!(tie.num_points(), (2, 2));
            let corner = &tie.active[1];
            assert!(!corner.nodes.contains(&(grid_nodes - 1)), "{:?}", corner.nodes);
            let x = tie.committed_position(corner.point, &committed);
            let sum: f64 = corner.values.iter().sum();
            let xs: Vec<f64> =
                (0..2).map(|k| corner.nodes.iter().zip(&corner.values).map(|(&a, v)| v * coords[a][k]).sum()).collect();
            assert!((sum - 1.0).abs() < 1e-12 && (xs[0] - x[0]).abs() < 1e-12 && (xs[1] - x[1]).abs() < 1e-12);
            assert!(!tie.begin_step(&mut committed).unwrap(), "same pattern");
            soil.write().unwrap()[grid_nodes - 1] = true;
            assert!(tie.begin_step(&mut committed).unwrap(), "the soil reached the corner");
            assert_eq!(tie.num_points(), (2, 2));
            soil.write().unwrap().fill(false);
            assert!(tie.begin_step(&mut committed).unwrap(), "the soil left");
            assert_eq!(tie.num_points(), (2, 0));
        }
    }
}
