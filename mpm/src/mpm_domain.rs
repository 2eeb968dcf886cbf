//! The implicit MPM domain: one background grid, whose nodes are global, with the bodies of
//! material points on it and the penalty walls that cut it.
//!
//! One grid is one object: every body (material) on it is located and projected once per
//! step, the walls read the bodies' nodal masses and points, and a grid attached to a
//! structure ([`GridAttachment`]) moves once for all of them. A step is the seed's three
//! phases, each a named function here:
//!
//! 1. **initialisation** ([`Domain::begin_step`]): [`MpmDomain::move_grid`] (reset the grid
//!    to its reference position, or to where the attached structure and the mesh motion put
//!    it), [`MpmDomain::locate_points`], [`MpmDomain::update_pattern`] (active cells and the
//!    blocks kept in the sparsity pattern), [`MpmDomain::project_to_grid`] (p2g and the reset
//!    of the grid's velocities and accelerations), [`MpmDomain::place_walls`];
//! 2. **updated-Lagrangian phase** ([`Domain::assemble`]): [`MpmDomain::compute_internal_forces`]
//!    over the cells of the pattern, then the walls' penalty blocks;
//! 3. **convective phase** ([`Domain::commit`]): [`MpmDomain::interpolate_to_points`]
//!    (g2p: the bodies' points move and commit), the walls record their forces.
//!
//! A grid in the **mixed u–p formulation** ([`MpmDomain::set_pressure_dofs`]) carries a
//! pressure DOF at every node: its bodies' cells go through
//! [`loam_fem::mixed_kernel::mixed_element`] with the material points as integration points
//! (the pressure projection acts on the points of each body in each cell), and the
//! initialisation phase starts the nodal pressures from the mass-weighted projection of the
//! points' mean Kirchhoff stress, `p_I = Σ_p N_I m_p p_p / Σ_p N_I m_p` (as the velocities).
//! Like the displacements, the pressures of nodes that no active cell touches keep their
//! start value (`r = (p − p_n)/s²`: a unit diagonal after the assembler's equilibration by
//! `s = μ/h`).
//!
//! In a **distributed run** (docs/distributed.md) a domain holds, on each rank, only the
//! points of the supports whose blocks the rank owns ([`Domain::own_blocks`]): the counts of points per support and the projection's nodal
//! sums are summed over the ranks in the initialisation phase, and points that moved into
//! another rank's supports migrate to it (`MpmDomain::migrate`).

use std::ops::Range;
use std::sync::{Arc, RwLock};

use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{
    AssemblyInput, Domain, DomainError, DomainOutput, Field, NamedOutput, NodalState, PointExtent, PointLoad,
    PointQuantity, PointTensor,
};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;
use loam_fem::kernel::{KernelContext, PointGeometry};
use loam_fem::mixed_kernel::CellProjection;
use loam_fem::newton::DEFAULT_MPM_PATTERN_RINGS;
use loam_fem::ranks::Ranks;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::attachment::{GridAttachment, GridNodeKind, MIN_CELL_QUALITY};
use crate::body::{Body, GridSums};
use crate::ghost_penalty::{GhostPenalty, CUT_FRACTION};
use crate::grid::{Grid, NO_GEOMETRY};
use crate::penalty_boundary::{GridNodes, PenaltyBoundary};
use crate::quadrature::{cell_volume, normalise_filled_cells, PointQuadrature};

/// Marker of a block without an occupying body.
const NONE: u8 = u8::MAX;

/// Per worker of the assembly, storage that a block needs only sometimes, made once per
/// worker rather than zeroed per block (a 3D smooth support's rule, projection integrals and
/// block are 24 kB, 6 kB and 93 kB): a u–p support's projection rule and integrals (the rule
/// only where they are not in closed form, [`Grid::projection_moments`]), and the block of a
/// second body in a support.
struct BlockScratch {
    rule: [PointGeometry; MAX_NODES],
    projection: CellProjection,
    disp: [[f64; 3]; MAX_NODES],
    inertia: [[f64; 3]; MAX_NODES],
    pressure: [f64; MAX_NODES],
    later: LaterBody,
}

impl Default for BlockScratch {
    fn default() -> Self {
        Self {
            rule: [NO_GEOMETRY; MAX_NODES],
            projection: CellProjection::default(),
            disp: [[0.0; 3]; MAX_NODES],
            inertia: [[0.0; 3]; MAX_NODES],
            pressure: [0.0; MAX_NODES],
            later: LaterBody::default(),
        }
    }
}

/// Residual and tangent of a second body's points in a block, before they are added.
#[derive(Default)]
struct LaterBody {
    residual: Vec<f64>,
    tangent: Vec<f64>,
}

impl LaterBody {
    /// Storage for a block of `nd` DOFs (contents unspecified: the kernels overwrite them).
    fn block(&mut self, nd: usize) -> (&mut [f64], &mut [f64]) {
        self.residual.resize(nd, 0.0);
        self.tangent.resize(nd * nd, 0.0);
        (&mut self.residual[..nd], &mut self.tangent[..nd * nd])
    }
}

/// Young's modulus `E = μ (3λ + 2μ)/(λ + μ)` of small-strain constants `(λ, μ)` (`3μ` for
/// an incompressible material, `λ = ∞`).
pub fn young_modulus((lambda, mu): (f64, f64)) -> f64 {
    if lambda.is_finite() {
        mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu)
    } else {
        3.0 * mu
    }
}

/// The grid's cells in the system: the active cells and the blocks of the pattern.
#[derive(Debug, Clone, Default)]
struct CellBlocks {
    /// Cells holding points of any body (ascending).
    active: Vec<usize>,
    /// Cells declared as element blocks (ascending): the active cells grown by
    /// `rings` rings when the pattern was last built. The sparsity pattern and the
    /// symbolic factorisation are kept while the active cells stay inside this set.
    pattern: Vec<usize>,
    /// Whether each grid cell is in `pattern`.
    in_pattern: Vec<bool>,
    /// For each block: the first body with points in its cell, or [`NONE`].
    first_body: Vec<u8>,
    /// For each block: bit `a` set if it carries the equation `Δu = 0` of its node `a`, which
    /// no active cell touches (residual `Δu`, unit diagonal).
    orphans: Vec<u32>,
    /// As `orphans` for the pressure DOFs (u–p grids): also at interface nodes, whose
    /// pressure only the soil has.
    pressure_orphans: Vec<u32>,
    /// Rings of cells around the active ones in the pattern (0: the pattern is the active
    /// set and is rebuilt whenever it changes).
    rings: usize,
}

/// Per grid node (grid numbering), whether a material point's function reaches it at the
/// current step, so that the soil's own terms give it an equation (the others keep their
/// place by an identity row, or are outside the system): written by
/// [`MpmDomain::update_pattern`], read by the coupling terms that act on the grid from
/// outside (a non-conforming tie, `loam_coupling::interface_points`), whose `begin_step` runs
/// after this domain's.
pub type SoilNodes = Arc<RwLock<Vec<bool>>>;

/// The material points of an MPM domain at the start of the step as the soil's surface
/// (positions and sizes, [`PointExtent`]), shared with the non-conforming contacts on its grid
/// (`loam_coupling::interface_points`), which measure an open point's distance to the soil
/// from them; refreshed at every step only while a contact holds a handle.
pub type SoilPoints = Arc<RwLock<Vec<PointExtent>>>;

/// What an MPM domain carries from step to step beside the nodal unknowns.
#[derive(serde::Serialize, serde::Deserialize)]
struct MpmState {
    bodies: Vec<crate::body::BodyState>,
    walls: Vec<crate::penalty_boundary::WallState>,
    pattern: Vec<usize>,
    /// Worst cell quality of an attached grid so far and the mesh motion's widenings (a
    /// resumed run widens it as often, so that it places the grid as the first run did).
    worst_cell_quality: f64,
    widenings: Vec<String>,
}

/// The material points of a domain held by the ranks that own their supports (a distributed
/// run, docs/distributed.md, stage 3): each rank holds the points of the supports whose
/// blocks it evaluates; the grid, the pattern and the nodal sums stay whole on every rank.
#[derive(Debug, Clone)]
struct DistributedPoints {
    ranks: Ranks,
    /// Points of each body in each support, summed over the ranks at the last
    /// [`MpmDomain::update_pattern`].
    counts: Vec<Vec<u32>>,
    /// Points this rank holds (in every body).
    held: usize,
}

impl DistributedPoints {
    /// Every rank's count of its points per body and support, summed (collective).
    fn count(&mut self, bodies: &[Body], supports: usize) {
        let mut mine = Vec::new();
        for (k, body) in bodies.iter().enumerate() {
            for s in 0..supports {
                let n = body.points_in_support(s).len();
                if n > 0 {
                    mine.extend_from_slice(&[(k * supports + s) as f64, n as f64]);
                }
            }
        }
        let all = self.ranks.exchange(&mine);
        self.counts.resize(bodies.len(), Vec::new());
        for c in &mut self.counts {
            c.clear();
            c.resize(supports, 0);
        }
        for rec in all.iter().flat_map(|part| part.chunks_exact(2)) {
            let i = rec[0] as usize;
            self.counts[i / supports][i % supports] += rec[1] as u32;
        }
    }
}

/// The state of `body` with the points of every rank (collective): each rank's records
/// ([`crate::material_points::MaterialPoints::pack`]) gathered in rank order, the points
/// erased on every rank summed.
fn every_rank_state(body: &Body, ranks: Ranks) -> crate::body::BodyState {
    let sl = body.law().state_len();
    let mut mine = vec![body.erased() as f64];
    for p in 0..body.points.len() {
        body.points.pack(p, sl, &mut mine);
    }
    let mut state = crate::body::BodyState { points: Default::default(), erased: 0 };
    let len = crate::material_points::MaterialPoints::RECORD_LEN + sl;
    for part in ranks.all_gather_varcount(&mine) {
        state.erased += part[0] as usize;
        for rec in part[1..].chunks_exact(len) {
            state.points.push_record(rec, sl);
        }
    }
    state
}

/// Material points on a background grid (see the module doc).
pub struct MpmDomain {
    name: String,
    formulation: Formulation,
    thickness: f64,
    grid: Grid,
    node_ids: Vec<usize>,
    bodies: Vec<Body>,
    walls: Vec<PenaltyBoundary>,
    attachment: Option<GridAttachment>,
    /// Displacement of every grid node from its reference position at the start of the step.
    start: Vec<[f64; 3]>,
    sums: GridSums,
    blocks: CellBlocks,
    /// Global pressure DOF of every grid node (u–p grids).
    pressure_dofs: Option<Vec<usize>>,
    /// Diagonal `1/s²` of an orphan node's pressure equation, `s` the assembler's
    /// equilibration scale of the grid's pressures ([`MpmDomain::set_pressure_dofs`]).
    orphan_pressure_weight: f64,
    /// How a cell integrates over its points ([`crate::quadrature`]).
    quadrature: PointQuadrature,
    /// Ghost penalty on the faces of the cut cells ([`crate::ghost_penalty`]).
    ghost: Option<GhostPenalty>,
    /// Worst quality of the attached grid's cells over the steps so far (1: undistorted).
    worst_cell_quality: f64,
    /// The mesh motion's reach after each time it was widened.
    widenings: Vec<String>,
    /// The nodes the soil's points reach at the current step.
    soil_nodes: SoilNodes,
    /// The soil's points at the start of the step, for the contacts on the grid.
    soil_points: SoilPoints,
    /// In a distributed run, the rank that evaluates each block ([`Domain::own_blocks`]).
    owners: Option<loam_fem::ranks::BlockOwners>,
    /// In a distributed run whose points are distributed: see [`DistributedPoints`].
    distributed: Option<DistributedPoints>,
}

/// The grid nodes that the bodies' points reach (`reached`) but barely cover: a node's
/// weight `Σ_p N_I w_p` below [`CUT_FRACTION`] of its smallest cell's measure (`volume`,
/// per cell); an interior node's is about one cell's. With `ranks` (distributed points), the
/// weights of every rank's points.
fn weak_nodes(grid: &Grid, bodies: &[Body], reached: &[bool], volume: &[f64], ranks: Option<Ranks>) -> Vec<bool> {
    let nodes = grid.mesh.coords.len();
    let mut weight = vec![0.0f64; nodes];
    for body in bodies {
        body.add_node_weights(grid, &mut weight);
    }
    if let Some(ranks) = ranks {
        ranks.sum_rows_identically(&mut weight, 1);
    }
    let mut full = vec![f64::INFINITY; nodes];
    for (c, &v) in volume.iter().enumerate() {
        for &a in grid.mesh.cell(c) {
            full[a] = full[a].min(v);
        }
    }
    (0..nodes).map(|a| reached[a] && weight[a] < CUT_FRACTION * full[a]).collect()
}

impl MpmDomain {
    /// A domain on `grid`, whose local node `a` is global node `node_ids[a]`, with its first
    /// body; the domain takes the body's name.
    pub fn new(grid: Grid, node_ids: Vec<usize>, formulation: Formulation, thickness: f64, body: Body) -> Self {
        let nodes = grid.mesh.coords.len();
        Self {
            name: body.name.clone(),
            formulation,
            thickness,
            grid,
            node_ids,
            bodies: vec![body],
            walls: Vec::new(),
            attachment: None,
            start: vec![[0.0; 3]; nodes],
            sums: GridSums::default(),
            blocks: CellBlocks { rings: DEFAULT_MPM_PATTERN_RINGS, ..Default::default() },
            pressure_dofs: None,
            orphan_pressure_weight: 1.0,
            quadrature: PointQuadrature::MaterialPoints,
            ghost: None,
            worst_cell_quality: 1.0,
            widenings: Vec::new(),
            soil_nodes: Arc::new(RwLock::new(vec![false; nodes])),
            soil_points: Arc::new(RwLock::new(Vec::new())),
            owners: None,
            distributed: None,
        }
    }

    /// The grid nodes the soil's points reach at the current step (see [`SoilNodes`]).
    pub fn soil_nodes(&self) -> SoilNodes {
        Arc::clone(&self.soil_nodes)
    }

    /// The soil's material points at the start of the step (see [`SoilPoints`]).
    pub fn soil_points(&self) -> SoilPoints {
        Arc::clone(&self.soil_points)
    }

    /// Worst quality (smallest corner `det J` over its reference value) of the grid's cells
    /// over the steps so far, and the mesh motion's reach after each time it was widened;
    /// `None` for a grid not attached to a structure.
    pub fn grid_motion_report(&self) -> Option<(f64, &[String])> {
        self.attachment.as_ref().map(|_| (self.worst_cell_quality, self.widenings.as_slice()))
    }

    /// Stabilises the cut cells by the ghost penalty of factor `alpha`
    /// ([`crate::ghost_penalty`]; 0 switches it off).
    pub fn set_ghost_penalty(&mut self, alpha: f64) {
        self.ghost = (alpha > 0.0).then(|| GhostPenalty::new(alpha));
    }

    /// Rings of inactive cells kept in the sparsity pattern around the active ones (default
    /// [`DEFAULT_MPM_PATTERN_RINGS`], the case file's `solver.mpm_pattern_rings`; 0 rebuilds
    /// the pattern at every change of the active cells).
    pub fn set_pattern_rings(&mut self, rings: usize) {
        self.blocks.rings = rings;
    }

    /// How the grid's cells integrate over their points ([`crate::quadrature`]).
    pub fn set_quadrature(&mut self, quadrature: PointQuadrature) {
        self.quadrature = quadrature;
    }

    /// Makes the grid a mixed u–p one: grid node `a` carries the global pressure DOF
    /// `dofs[a]` (see the module doc), equilibrated by the assembler with the scale `scale`
    /// (`μ/h`, [`loam_fem::assembler`]). An orphan node's pressure equation is written as
    /// `r = (p − p_n)/s²` with the diagonal `1/s²`, so that after the equilibration it is a unit
    /// row like an orphan displacement's, not one of `s²` (about 10¹⁵ on the Bui column)
    /// beside the unit rows, which no pivot test relative to its block survives.
    pub fn set_pressure_dofs(&mut self, dofs: Vec<usize>, scale: f64) {
        self.pressure_dofs = Some(dofs);
        self.orphan_pressure_weight = if scale > 0.0 { 1.0 / (scale * scale) } else { 1.0 };
    }

    /// Global pressure DOF of every grid node, if the grid is a u–p one.
    pub fn pressure_dofs(&self) -> Option<&[usize]> {
        self.pressure_dofs.as_deref()
    }

    /// DOFs of a support's block: `nn·dim` displacements, then `nn` pressures on a u–p grid.
    fn block_len(&self) -> usize {
        let nn = self.grid.support_len();
        nn * self.dim() + if self.pressure_dofs.is_some() { nn } else { 0 }
    }

    /// Adds another body (material) on the same grid.
    ///
    /// # Panics
    /// With more than 254 bodies on one grid.
    pub fn add_body(&mut self, body: Body) {
        assert!(self.bodies.len() < NONE as usize, "at most 254 bodies on one grid");
        self.bodies.push(body);
    }

    /// Adds a penalty wall cutting the grid.
    pub fn add_wall(&mut self, wall: PenaltyBoundary) {
        self.walls.push(wall);
    }

    /// Attaches the grid to structures (see [`GridAttachment`]).
    pub fn attach(&mut self, attachment: GridAttachment) {
        self.attachment = Some(attachment);
    }

    /// The bodies on the grid.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The bodies on the grid, mutably (initial stress and velocity, PIC blend).
    pub fn bodies_mut(&mut self) -> &mut [Body] {
        &mut self.bodies
    }

    /// The next free point id (ids of a new body start here).
    pub fn next_point_id(&self) -> usize {
        self.bodies.last().map_or(0, |b| b.id_range().end)
    }

    /// The background grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Global id of each grid node.
    pub fn node_ids(&self) -> &[usize] {
        &self.node_ids
    }

    /// Material points erased so far because they left the grid.
    pub fn erased(&self) -> usize {
        self.bodies.iter().map(Body::erased).sum()
    }

    fn dim(&self) -> usize {
        self.grid.mesh.element.dim()
    }

    fn kind(&self, a: usize) -> GridNodeKind {
        self.attachment.as_ref().map_or(GridNodeKind::Free, |att| att.kind[a])
    }

    fn body_of(&self, id: usize) -> Option<(&Body, usize)> {
        self.bodies.iter().find_map(|b| b.index_of(id).map(|k| (b, k)))
    }

    /// Phase 1a: places the grid for the step. A free grid returns to its reference
    /// position; an attached one goes where its interface nodes' structure nodes are
    /// (`X + u_n`), with the band between them and the far field moved by the mesh motion.
    /// The displacement of every grid node that is not a structure node is reset to that
    /// position (`u_n = w`: the increments of the step are measured from there).
    pub fn move_grid(&mut self, committed: &mut NodalState) -> Result<(), DomainError> {
        let dim = self.dim();
        if let Some(att) = &mut self.attachment {
            loop {
                for (a, w) in self.start.iter_mut().enumerate() {
                    *w = [0.0; 3];
                    if let Some(g) = att.anchor[a] {
                        w[..dim].copy_from_slice(&committed.u[g * dim..(g + 1) * dim]);
                    }
                }
                att.motion.extend(&mut self.start);
                let placed = self.grid.move_nodes(&self.start);
                // a cell distorted past MIN_CELL_QUALITY, or inverted: the motion spreads wider
                let poor = placed.as_ref().map_or(true, |&q| q < MIN_CELL_QUALITY);
                if poor {
                    if let Some(reach) = att.motion.widen() {
                        self.widenings.push(reach);
                        continue;
                    }
                }
                match placed {
                    Ok(quality) => {
                        self.worst_cell_quality = self.worst_cell_quality.min(quality);
                        break;
                    }
                    Err(inverted) => {
                        return Err(DomainError {
                            domain: self.name.clone(),
                            element: inverted.cell,
                            message: format!(
                                "the grid attached to the structure by interface {} would invert its cell at ({}) at the start of the step, although the mesh motion already spreads over the whole grid: the structure has moved too far against the grid's fixed boundaries (enlarge the grid, or refine it there)",
                                att.interfaces,
                                inverted.centre[..dim].iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(", ")
                            ),
                        })
                    }
                }
            }
        }
        for (a, &g) in self.node_ids.iter().enumerate() {
            if self.kind(a) == GridNodeKind::Tied {
                continue;
            }
            committed.u[g * dim..(g + 1) * dim].copy_from_slice(&self.start[a][..dim]);
        }
        Ok(())
    }

    /// Phase 1b: every body locates its points in the grid's configuration of the step;
    /// with [`PointQuadrature::FilledCells`] the points' weights in filled cells are scaled
    /// to the cell's volume.
    pub fn locate_points(&mut self) {
        for body in &mut self.bodies {
            body.locate(&self.grid, self.formulation, self.thickness);
        }
        // distributed points: once the points per cell of every rank are counted
        if self.distributed.is_none() {
            self.fill_cells();
        }
    }

    /// With [`PointQuadrature::FilledCells`], the points' weights in the cells the material
    /// fills scaled to the cell's volume ([`normalise_filled_cells`]); a cell counts as
    /// occupied if it holds points of any body (of any rank where the points are distributed:
    /// on the linear basis, the only one `filled_cells` serves, a cell's points are all held
    /// by the rank that owns its block).
    fn fill_cells(&mut self) {
        if self.quadrature != PointQuadrature::FilledCells {
            return;
        }
        let occupied: Vec<bool> = (0..self.grid.num_supports())
            .map(|c| match &self.distributed {
                Some(d) => d.counts.iter().any(|n| n[c] > 0),
                None => self.bodies.iter().any(|b| b.occupies(c)),
            })
            .collect();
        normalise_filled_cells(&self.grid, self.formulation, self.thickness, &mut self.bodies, &occupied);
    }

    /// Phase 1c: the active cells (holding points of any body), the blocks of the pattern
    /// (rebuilt only when an active cell leaves it), the first body of each block and the
    /// identity rows of pattern nodes that no active cell touches. Returns whether the
    /// blocks changed.
    pub fn update_pattern(&mut self) -> bool {
        let num_cells = self.grid.num_supports();
        if let Some(d) = &mut self.distributed {
            d.count(&self.bodies, num_cells);
            self.fill_cells();
        }
        // the first body with points in each support (of every rank's points where they are
        // distributed)
        let first_body = |c: usize| -> Option<usize> {
            match &self.distributed {
                Some(d) => d.counts.iter().position(|n| n[c] > 0),
                None => self.bodies.iter().position(|b| b.occupies(c)),
            }
        };
        let active: Vec<usize> = (0..num_cells).filter(|&c| first_body(c).is_some()).collect();
        let cb = &mut self.blocks;
        let changed = if cb.rings == 0 {
            active != cb.active || cb.pattern != active
        } else {
            cb.pattern.is_empty() || active.iter().any(|&c| !cb.in_pattern[c])
        };
        if changed {
            // a smooth basis's ring is half as wide where only the points act on the grid: its
            // supports span three node rows, so a full ring (supports sharing a node) adds two
            // rows on each side and its zero blocks cost fill in every factorisation; the price
            // is more frequent rebuilds of the pattern. A ghost penalty, a penalty wall, an
            // attached structure or a contact acts on nodes beside the points, which the full
            // ring gives a place (an identity row for a direction they do not hold)
            let narrow = self.ghost.is_none()
                && self.walls.is_empty()
                && self.attachment.is_none()
                && Arc::strong_count(&self.soil_nodes) == 1
                && Arc::strong_count(&self.soil_points) == 1;
            let mut cells = active.clone();
            for _ in 0..cb.rings {
                cells = self.grid.dilate_supports(&cells, narrow);
            }
            cb.in_pattern = vec![false; num_cells];
            for &c in &cells {
                cb.in_pattern[c] = true;
            }
            cb.pattern = cells;
        }
        cb.active = active;
        // live nodes: those of the active cells (linear basis), or those that a point's
        // function reaches (smooth basis: a support also holds nodes whose functions vanish at
        // all its points, which would leave empty rows)
        let mut live = vec![false; self.grid.mesh.coords.len()];
        if self.grid.basis().is_smooth() {
            for body in &self.bodies {
                body.mark_reached_nodes(&self.grid, &mut live);
            }
            if let Some(d) = &self.distributed {
                // reached by a point of any rank
                let mut flags: Vec<f64> = live.iter().map(|&l| f64::from(u8::from(l))).collect();
                d.ranks.sum_rows_identically(&mut flags, 1);
                live.iter_mut().zip(&flags).for_each(|(l, &f)| *l = f > 0.0);
            }
        } else {
            for &c in &cb.active {
                for &a in self.grid.support(c) {
                    live[a] = true;
                }
            }
        }
        let reached = live.clone();
        self.soil_nodes.write().expect("no writer panicked").clone_from(&reached);
        if Arc::strong_count(&self.soil_points) > 1 {
            // the contacts measure their gaps to every rank's points
            let (formulation, thickness) = (self.formulation, self.thickness);
            let extents = self.bodies.iter().flat_map(|b| b.point_extents(formulation, thickness)).collect();
            *self.soil_points.write().expect("no writer panicked") = match &self.distributed {
                Some(d) => PointExtent::gathered(d.ranks, extents),
                None => extents,
            };
        }
        let mut live_pressure = live.clone();
        cb.first_body.clear();
        cb.orphans.clear();
        cb.pressure_orphans.clear();
        for &c in &cb.pattern {
            let first = first_body(c);
            cb.first_body.push(first.map_or(NONE, |k| k as u8));
            // a node not live is owned by the first block that holds it (on the linear basis
            // always a block without points; on a smooth one possibly one with points)
            let (mut mask, mut pressure_mask) = (0u32, 0u32);
            for (a, &node) in self.grid.support(c).iter().enumerate() {
                let tied = self.attachment.as_ref().is_some_and(|att| att.kind[node] == GridNodeKind::Tied);
                if !live[node] && !tied {
                    live[node] = true;
                    mask |= 1 << a;
                }
                if !live_pressure[node] {
                    live_pressure[node] = true;
                    pressure_mask |= 1 << a;
                }
            }
            cb.orphans.push(mask);
            cb.pressure_orphans.push(pressure_mask);
        }
        let mut changed = changed;
        if let Some(ghost) = &mut self.ghost {
            // per grid cell: the points' weights (a smooth basis groups its points by support:
            // their cells from their positions) and the stiffest body's modulus
            let num_cells = self.grid.mesh.num_cells();
            let mut fill = vec![0.0f64; num_cells];
            let mut modulus = vec![0.0f64; num_cells];
            let mut body_fill = vec![0.0f64; num_cells];
            for body in &self.bodies {
                let e = young_modulus(body.law().elastic_lame());
                body_fill.iter_mut().for_each(|w| *w = 0.0);
                body.add_cell_weights(&self.grid, &mut body_fill);
                if let Some(d) = &self.distributed {
                    d.ranks.sum_rows_identically(&mut body_fill, 1);
                }
                for c in 0..num_cells {
                    if body_fill[c] > 0.0 {
                        fill[c] += body_fill[c];
                        modulus[c] = modulus[c].max(e);
                    }
                }
            }
            // cells in the system: those holding points (linear basis), or those whose nodes a
            // point's function reaches (smooth basis: their nodes are unknowns even without
            // points in them, and the faces to them hold those nodes)
            let smooth = self.grid.basis().is_smooth();
            let active: Vec<bool> = if smooth {
                (0..num_cells).map(|c| self.grid.mesh.cell(c).iter().all(|&a| reached[a])).collect()
            } else {
                fill.iter().map(|&w| w > 0.0).collect()
            };
            let volume: Vec<f64> =
                (0..num_cells).map(|c| cell_volume(&self.grid, self.formulation, self.thickness, c)).collect();
            let cut: Vec<bool> = (0..num_cells).map(|c| active[c] && fill[c] < CUT_FRACTION * volume[c]).collect();
            // smooth basis: the nodes that the material barely covers (a node's weight
            // `Σ_p N_I w_p` below CUT_FRACTION of a cell), which the lines of the ghost
            // penalty hold where no face does; their cells join the zone of the blocks
            let ranks = self.distributed.as_ref().map(|d| d.ranks);
            let weak = if smooth { weak_nodes(&self.grid, &self.bodies, &reached, &volume, ranks) } else { Vec::new() };
            let edge: Vec<bool> = if smooth {
                (0..num_cells).map(|c| cut[c] || self.grid.mesh.cell(c).iter().any(|&a| weak[a])).collect()
            } else {
                cut.clone()
            };
            if changed || !ghost.covers(&edge) {
                // faces declared around the cut cells
                let edge_cells: Vec<usize> = (0..num_cells).filter(|&c| edge[c]).collect();
                let zone_cells = self.grid.dilate(&edge_cells);
                let mut zone = vec![false; num_cells];
                for &c in &zone_cells {
                    zone[c] = true;
                }
                if smooth {
                    // the faces' cells: those around the zone whose nodes are all unknowns of
                    // the pattern's supports (a node outside them would be an equation
                    // without a row), and the lines of such nodes
                    let mut in_pattern = vec![false; self.grid.mesh.coords.len()];
                    for &s in &cb.pattern {
                        for &a in self.grid.support(s) {
                            in_pattern[a] = true;
                        }
                    }
                    let mut cells = self.grid.dilate(&zone_cells);
                    cells.retain(|&c| self.grid.mesh.cell(c).iter().all(|&a| in_pattern[a]));
                    ghost.rebuild(&self.grid, &cells, zone);
                    ghost.add_lattice_lines(&self.grid, &in_pattern);
                } else {
                    ghost.rebuild(&self.grid, &cb.pattern, zone);
                }
                changed = true;
            }
            ghost.mark(&active, &cut, &modulus);
            if smooth {
                let stiffest = modulus.iter().copied().fold(0.0, f64::max);
                ghost.mark_lines(&self.grid, &reached, &weak, &modulus, stiffest);
            }
        }
        changed
    }

    /// Phase 1d: p2g, `m_I = Σ_p N_I m_p`, `(m v)_I`, `(m a)_I` over every body, and the reset
    /// of the grid nodes: `v = (m v)/m`, `a = (m a)/m` (0 where no mass was projected); a tied
    /// interface node keeps the structure's state; the soil node of a slip pair takes the
    /// structure node's normal components.
    pub fn project_to_grid(&mut self, committed: &mut NodalState) {
        let dim = self.dim();
        self.sums.reset(self.grid.mesh.coords.len());
        for body in &self.bodies {
            body.project(&self.grid, dim, &mut self.sums);
        }
        if let Some(d) = &self.distributed {
            self.sums.sum_over(d.ranks);
        }
        for (a, &g) in self.node_ids.iter().enumerate() {
            let kind = self.kind(a);
            if kind == GridNodeKind::Tied {
                continue;
            }
            let m = self.sums.mass[a];
            let mut v = [0.0; 3];
            let mut acc = [0.0; 3];
            if m > 0.0 {
                for i in 0..dim {
                    v[i] = self.sums.momentum[a][i] / m;
                    acc[i] = self.sums.inertia[a][i] / m;
                }
            }
            if let GridNodeKind::Slip { source, normal } = kind {
                let s = source * dim;
                let (vn, an): (f64, f64) = (0..dim)
                    .map(|i| (normal[i] * (committed.v[s + i] - v[i]), normal[i] * (committed.a[s + i] - acc[i])))
                    .fold((0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
                for i in 0..dim {
                    v[i] += vn * normal[i];
                    acc[i] += an * normal[i];
                }
            }
            committed.v[g * dim..(g + 1) * dim].copy_from_slice(&v[..dim]);
            committed.a[g * dim..(g + 1) * dim].copy_from_slice(&acc[..dim]);
        }
        if let Some(pressure_dofs) = &self.pressure_dofs {
            let mut sums = vec![0.0; self.grid.mesh.coords.len()];
            for body in &self.bodies {
                body.project_pressure(&self.grid, &mut sums);
            }
            if let Some(d) = &self.distributed {
                d.ranks.sum_rows_identically(&mut sums, 1);
            }
            for (a, &dof) in pressure_dofs.iter().enumerate() {
                let m = self.sums.mass[a];
                committed.u[dof] = if m > 0.0 { sums[a] / m } else { 0.0 };
            }
        }
    }

    /// Phase 1e: the walls place their penalty points where the bodies' mass is. Returns
    /// whether their blocks changed.
    pub fn place_walls(&mut self) -> bool {
        if self.walls.is_empty() {
            return false;
        }
        let mut changed = false;
        for wall in &mut self.walls {
            changed |= wall.begin_step(&self.grid, &self.sums.mass);
        }
        changed
    }

    /// Phase 2: the points of each body in each cell of the pattern are the kernel's
    /// integration points (weight `V_p^n`, `F0 = F_p^n`), with their lumped mass; blocks
    /// without points carry the identity rows of their orphan nodes. The first body of a
    /// block writes it, the others add to it.
    pub fn compute_internal_forces(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let element = self.grid.mesh.element;
        let nn = self.grid.support_len();
        let dim = self.dim();
        let nd = self.block_len();
        let pressure_dofs = self.pressure_dofs.as_deref();
        let orphan_pressure_weight = self.orphan_pressure_weight;
        let (formulation, thickness) = (self.formulation, self.thickness);
        let (grid, node_ids, name, blocks) = (&self.grid, &self.node_ids, &self.name, &self.blocks);
        let attachment = self.attachment.as_ref();
        let owners = self.owners.as_ref();
        // the orphan nodes' equations `r = Δu` (`K = I`: they keep their place; at the soil
        // node of a slip pair only the tangential part, `r = (I − n⊗n) Δu`, its normal
        // component belongs to the structure's equation), added to block `b`
        let orphan_rows = |b: usize, km: &mut [f64], fv: &mut [f64]| {
            for (a, &node) in grid.support(blocks.pattern[b]).iter().enumerate() {
                if blocks.orphans[b] & (1 << a) == 0 {
                    continue;
                }
                let normal = match attachment.map(|att| att.kind[node]) {
                    Some(GridNodeKind::Slip { normal, .. }) => Some(normal),
                    _ => None,
                };
                let dof = node_ids[node] * dim;
                for i in 0..dim {
                    for j in 0..dim {
                        let p = if i == j { 1.0 } else { 0.0 } - normal.map_or(0.0, |n| n[i] * n[j]);
                        fv[a * dim + i] += p * (input.state.u[dof + j] - input.committed.u[dof + j]);
                        if input.with_tangent {
                            km[(a * dim + i) * nd + a * dim + j] += p;
                        }
                    }
                }
            }
            if let Some(pressure_dofs) = pressure_dofs {
                let nu = nn * dim;
                for (a, &node) in grid.support(blocks.pattern[b]).iter().enumerate() {
                    if blocks.pressure_orphans[b] & (1 << a) != 0 {
                        let dof = pressure_dofs[node];
                        fv[nu + a] += orphan_pressure_weight * (input.state.u[dof] - input.committed.u[dof]);
                        if input.with_tangent {
                            km[(nu + a) * nd + nu + a] += orphan_pressure_weight;
                        }
                    }
                }
            }
        };
        // blocks without points: zero, but for the orphan nodes' equations
        matrices
            .par_chunks_mut(nd * nd)
            .zip(vectors.par_chunks_mut(nd))
            .enumerate()
            .with_min_len(64)
            .filter(|(b, _)| blocks.first_body[*b] == NONE)
            .for_each(|(b, (km, fv))| {
                fv.fill(0.0);
                if input.with_tangent {
                    km.fill(0.0);
                }
                orphan_rows(b, km, fv);
            });
        for (k, body) in self.bodies.iter_mut().enumerate() {
            let mut trial = body.take_trial();
            let views = trial.views(body.support_start(), body.law().state_len(), &blocks.pattern);
            let body_ref = &*body;
            let ctx = KernelContext {
                element,
                formulation: self.formulation,
                law: body_ref.law(),
                time_step: input.time_step,
            };
            let result = matrices
                .par_chunks_mut(nd * nd)
                .zip(vectors.par_chunks_mut(nd))
                .zip(views.into_par_iter())
                .enumerate()
                .with_min_len(16)
                .try_for_each_init(BlockScratch::default, |scratch, (b, ((km, fv), view))| {
                    let Some((trial, out)) = view else { return Ok(()) };
                    if owners.is_some_and(|o| !o.owns(b)) {
                        return Ok(()); // another rank's support
                    }
                    let cell = blocks.pattern[b];
                    let nodes = grid.support(cell);
                    // every entry read below is written here (the z components stay 0 in 2D)
                    let BlockScratch { rule, projection, disp, inertia, pressure, later } = scratch;
                    for (a, &local) in nodes.iter().enumerate() {
                        let dof = node_ids[local] * dim;
                        for i in 0..dim {
                            disp[a][i] = input.state.u[dof + i] - input.committed.u[dof + i];
                            if let Some(acc) = input.inertial_acceleration {
                                inertia[a][i] = acc[dof + i];
                            }
                        }
                        if let Some(p) = pressure_dofs {
                            pressure[a] = input.state.u[p[local]];
                        }
                    }
                    // the integrals over the support's region in the step's configuration, for
                    // the projection
                    if pressure_dofs.is_some() {
                        grid.projection_moments(cell, formulation, thickness, rule, projection).map_err(|err| {
                            DomainError { domain: name.clone(), element: cell, message: err.to_string() }
                        })?;
                    }
                    let pressure = pressure_dofs.map(|_| (&pressure[..nn], &*projection));
                    let fail = |err: loam_fem::kernel::KernelError| DomainError {
                        domain: name.clone(),
                        element: cell,
                        message: err.to_string(),
                    };
                    let body = body_ref;
                    let mut contribute = |f: &mut [f64], k: Option<&mut [f64]>| {
                        body.cell_contribution(
                            &ctx,
                            cell,
                            &disp[..nn],
                            pressure,
                            &inertia[..nn],
                            input,
                            trial,
                            out,
                            f,
                            k,
                        )
                        .map_err(fail)
                    };
                    if blocks.first_body[b] as usize == k {
                        return contribute(fv, input.with_tangent.then_some(&mut *km));
                    }
                    // a later body of the block: into scratch, then added
                    let (f_scratch, k_scratch) = later.block(nd);
                    contribute(f_scratch, input.with_tangent.then_some(&mut *k_scratch))?;
                    for (f, s) in fv.iter_mut().zip(&*f_scratch) {
                        *f += s;
                    }
                    if input.with_tangent {
                        for (m, s) in km.iter_mut().zip(&*k_scratch) {
                            *m += s;
                        }
                    }
                    Ok(())
                });
            body.restore_trial(trial);
            result?;
        }
        // blocks with points: a smooth basis's nodes that no point's function reaches
        matrices
            .par_chunks_mut(nd * nd)
            .zip(vectors.par_chunks_mut(nd))
            .enumerate()
            .filter(|(b, _)| blocks.first_body[*b] != NONE && (blocks.orphans[*b] | blocks.pressure_orphans[*b]) != 0)
            .for_each(|(b, (km, fv))| orphan_rows(b, km, fv));
        let block_of_support =
            |s: usize| blocks.pattern.binary_search(&s).expect("the support of a material point is in the pattern");
        for body in &self.bodies {
            body.add_point_loads(input.time, (nn, dim, nd), block_of_support, vectors);
        }
        Ok(())
    }

    /// Sends every point held here whose support's block another rank owns to that rank and
    /// takes the points the other ranks send here (collective: one exchange of the points'
    /// records per body, [`crate::material_points::MaterialPoints::pack`]), then locates the
    /// points held again. With `first` every rank holds every point (the first partition, or
    /// a restored checkpoint): each keeps its own and nothing is sent.
    fn migrate(&mut self, first: bool) {
        let (Some(owners), Some(d)) = (&self.owners, &mut self.distributed) else { return };
        let (ranks, me) = (d.ranks, d.ranks.rank());
        let pattern = &self.blocks.pattern;
        let (mut sent, mut received, mut held) = (0u64, 0u64, 0usize);
        let mut relocated = false;
        for body in &mut self.bodies {
            let sl = body.law().state_len();
            let n = body.points.len();
            let mut keep = Vec::with_capacity(n);
            let mut outgoing = Vec::new();
            for p in 0..n {
                let s = body.support_of(p);
                let b = pattern.binary_search(&s).expect("a located point's support is in the pattern");
                let r = owners.owner(b);
                if r == me {
                    keep.push(p);
                } else if !first {
                    outgoing.push(r as f64);
                    body.points.pack(p, sl, &mut outgoing);
                    sent += 1;
                }
            }
            let all = if first { Vec::new() } else { ranks.exchange(&outgoing) };
            let leaving = keep.len() != n;
            if leaving {
                body.points.reorder(&keep, sl);
            }
            let before = body.points.len();
            let len = 1 + crate::material_points::MaterialPoints::RECORD_LEN + sl;
            for (r, part) in all.iter().enumerate() {
                if r == me {
                    continue;
                }
                for rec in part.chunks_exact(len).filter(|rec| rec[0] as usize == me) {
                    body.points.push_record(&rec[1..], sl);
                    received += 1;
                }
            }
            // located at the step's start already unless points left or arrived
            if leaving || body.points.len() != before {
                body.locate(&self.grid, self.formulation, self.thickness);
                relocated = true;
            }
            held += body.points.len();
        }
        let before = std::mem::replace(&mut d.held, held);
        loam_fem::ranks::with_stats(|s| {
            s.points_held = s.points_held + held as u64 - before as u64;
            s.points_sent += sent;
            s.points_received += received;
            if !first {
                s.migrations += 1;
            }
        });
        if first {
            // the points per support of every rank, now that each holds its own; the room the
            // other ranks' points took is given back
            d.count(&self.bodies, self.grid.num_supports());
            self.bodies.iter_mut().for_each(Body::shrink_to_fit);
        }
        if relocated {
            self.fill_cells();
        }
    }

    /// In a distributed run, before phase 3: the kernel output and law history of the points
    /// of other ranks' supports reach this rank (docs/distributed.md), so that every rank
    /// convects every point.
    fn replicate_trials(&mut self) {
        let Some(o) = &self.owners else { return };
        for body in &mut self.bodies {
            let start = body.support_start();
            let mut owner = vec![0usize; body.points.len()];
            for (b, &cell) in self.blocks.pattern.iter().enumerate() {
                owner[start[cell]..start[cell + 1]].fill(o.owner(b));
            }
            let sl = body.law().state_len();
            let mut trial = body.take_trial();
            o.ranks().replicate_points(&owner, &mut trial.out, &mut trial.state, sl);
            body.restore_trial(trial);
        }
    }

    /// Phase 3: g2p for every body (the points move and commit their state).
    pub fn interpolate_to_points(&mut self, input: &AssemblyInput<'_>) {
        for body in &mut self.bodies {
            body.convect(&self.grid, &self.node_ids, input);
        }
    }

    /// The background grid at the start of the last step with nodal `mass` (`Σ_p N_I m_p`
    /// of the bodies' points in the last step), `displacement_increment` (`Δu` of the last
    /// step: the grid returns to its start position at each step), `velocity`,
    /// `acceleration` and `active` (1 on nodes of cells holding points in the last step).
    fn grid_output(&self, committed: &NodalState) -> DomainOutput {
        let mesh = &self.grid.mesh;
        let dim = self.dim();
        let nodal = |src: &[f64], offset: Option<&[[f64; 3]]>| -> Vec<f64> {
            self.node_ids
                .iter()
                .enumerate()
                .flat_map(|(a, &g)| {
                    (0..3).map(move |i| if i < dim { src[g * dim + i] - offset.map_or(0.0, |w| w[a][i]) } else { 0.0 })
                })
                .collect()
        };
        let mut mass = vec![0.0; mesh.coords.len()];
        if self.distributed.is_some() {
            // the step's projection, summed over the ranks: the same points and functions
            mass.copy_from_slice(&self.sums.mass);
        } else {
            for body in &self.bodies {
                body.nodal_mass(&self.grid, &mut mass);
            }
        }
        let mut active = vec![0.0; mesh.coords.len()];
        for &c in &self.blocks.active {
            for &node in self.grid.support(c) {
                active[node] = 1.0;
            }
        }
        let point_fields = vec![
            Field { name: "mass".into(), components: 1, values: mass },
            Field {
                name: "displacement_increment".into(),
                components: 3,
                values: nodal(&committed.u, Some(&self.start)),
            },
            Field { name: "velocity".into(), components: 3, values: nodal(&committed.v, None) },
            Field { name: "acceleration".into(), components: 3, values: nodal(&committed.a, None) },
            Field { name: "active".into(), components: 1, values: active },
        ];
        let mut point_fields = point_fields;
        if let Some(p) = &self.pressure_dofs {
            point_fields.push(Field {
                name: "pressure".into(),
                components: 1,
                values: p.iter().map(|&d| committed.u[d]).collect(),
            });
        }
        DomainOutput {
            points: mesh.coords.clone(),
            cells: Some((mesh.element, mesh.connectivity.clone())),
            point_fields,
            cell_fields: Vec::new(),
        }
    }

    /// The points `range` of `body` (all of them for the output, a rank's share for its
    /// piece) with their fields and the law's state variables.
    fn body_output(&self, body: &Body, range: std::ops::Range<usize>) -> DomainOutput {
        let pts = &body.points;
        let n = range.len();
        let vec3 = |v: &[[f64; 3]]| v[range.clone()].iter().flatten().copied().collect::<Vec<f64>>();
        let tensor = |v: &[Matrix3<f64>]| {
            v[range.clone()].iter().flat_map(|m| m.transpose().iter().copied().collect::<Vec<_>>()).collect()
        };
        let law = body.law();
        let names = law.state_variables();
        let sl = law.state_len();
        let mut states = vec![vec![0.0; n]; names.len()];
        let mut tmp = vec![0.0; names.len()];
        for (q, p) in range.clone().enumerate() {
            law.state_output(&pts.state[p * sl..(p + 1) * sl], &mut tmp);
            for (k, v) in tmp.iter().enumerate() {
                states[k][q] = *v;
            }
        }
        let cauchy = &pts.cauchy[range.clone()];
        let mut point_fields = vec![
            Field { name: "displacement".into(), components: 3, values: vec3(&pts.displacement) },
            Field { name: "velocity".into(), components: 3, values: vec3(&pts.velocity) },
            Field { name: "acceleration".into(), components: 3, values: vec3(&pts.acceleration) },
            Field { name: "mass".into(), components: 1, values: pts.mass[range.clone()].to_vec() },
            Field { name: "volume".into(), components: 1, values: pts.volume[range.clone()].to_vec() },
            Field { name: "cauchy_stress".into(), components: 9, values: tensor(&pts.cauchy) },
            Field { name: "deformation_gradient".into(), components: 9, values: tensor(&pts.deformation_gradient) },
            Field {
                name: "von_mises_stress".into(),
                components: 1,
                values: cauchy.iter().map(loam_fem::von_mises).collect(),
            },
            Field {
                name: "id".into(),
                components: 1,
                values: pts.id[range.clone()].iter().map(|&i| (i + body.id_offset) as f64).collect(),
            },
        ];
        for (k, name) in names.iter().enumerate() {
            point_fields.push(Field { name: name.to_string(), components: 1, values: std::mem::take(&mut states[k]) });
        }
        if self.pressure_dofs.is_some() {
            // the mean Kirchhoff stress interpolated from the nodal pressures at convergence
            let values = cauchy
                .iter()
                .zip(&pts.deformation_gradient[range.clone()])
                .map(|(s, f)| f.determinant() * s.trace() / 3.0);
            point_fields.push(Field { name: "pressure".into(), components: 1, values: values.collect() });
        }
        DomainOutput { points: pts.position[range].to_vec(), cells: None, point_fields, cell_fields: Vec::new() }
    }

    /// The outputs ([`Domain::outputs`]): each body's points `range(body)`, then the walls
    /// and, with `with_grid`, the grid.
    fn outputs_of(
        &self,
        committed: &NodalState,
        with_grid: bool,
        range: impl Fn(&Body) -> std::ops::Range<usize>,
    ) -> Vec<NamedOutput> {
        let mut out: Vec<NamedOutput> = self
            .bodies
            .iter()
            .map(|b| NamedOutput { name: b.name.clone(), output: self.body_output(b, range(b)) })
            .collect();
        out.extend(self.walls.iter().map(|w| NamedOutput { name: w.name().to_string(), output: w.output() }));
        if with_grid {
            out.push(NamedOutput { name: format!("{}_grid", self.name), output: self.grid_output(committed) });
        }
        out
    }

    fn at(&self) -> GridNodes<'_> {
        GridNodes { grid: &self.grid, node_ids: &self.node_ids }
    }
}

impl Domain for MpmDomain {
    fn name(&self) -> &str {
        &self.name
    }

    fn formulation(&self) -> Formulation {
        self.formulation
    }

    fn thickness(&self) -> f64 {
        self.thickness
    }

    fn is_soil(&self) -> bool {
        true
    }

    /// Initialisation phase (see the module doc).
    fn begin_step(&mut self, committed: &mut NodalState) -> Result<bool, DomainError> {
        self.move_grid(committed)?;
        self.locate_points();
        let cells_changed = self.update_pattern();
        self.project_to_grid(committed);
        let walls_changed = self.place_walls();
        // distributed points that moved into other ranks' supports go there now; with a new
        // pattern they go at its partition ([`Domain::own_blocks`])
        if self.distributed.is_some() && !cells_changed && self.owners.is_some() {
            self.migrate(false);
        }
        Ok(cells_changed || walls_changed)
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        let dim = self.dim();
        for &c in &self.blocks.pattern {
            let cell = self.grid.support(c);
            let pressures = self.pressure_dofs.iter().flat_map(|p| cell.iter().map(move |&a| p[a]));
            layout.push(cell.iter().flat_map(|&a| (0..dim).map(move |i| self.node_ids[a] * dim + i)).chain(pressures));
        }
        if let Some(ghost) = &self.ghost {
            ghost.blocks(&self.grid, &self.node_ids, layout);
        }
        for wall in &self.walls {
            wall.blocks(self.at(), layout);
        }
    }

    /// One unit per material point of a support's block (of every body); the ghost
    /// penalty's and walls' blocks, which every rank evaluates, 0.
    fn block_costs(&self, costs: &mut Vec<f64>) {
        match &self.distributed {
            Some(d) => {
                costs.extend(self.blocks.pattern.iter().map(|&c| d.counts.iter().map(|n| f64::from(n[c])).sum::<f64>()))
            }
            None => costs.extend(
                self.blocks
                    .pattern
                    .iter()
                    .map(|&c| self.bodies.iter().map(|b| b.points_in_support(c).len() as f64).sum::<f64>()),
            ),
        }
        let mut rest = BlockLayout::default();
        if let Some(ghost) = &self.ghost {
            ghost.blocks(&self.grid, &self.node_ids, &mut rest);
        }
        for wall in &self.walls {
            wall.blocks(self.at(), &mut rest);
        }
        costs.extend(std::iter::repeat_n(0.0, rest.num_blocks()));
    }

    /// The material points' supports of other ranks are not evaluated here (their points'
    /// state is exchanged at the commit); the ghost penalty's and walls' blocks are.
    ///
    /// The first partition leaves each rank only the points of its own supports, and every later
    /// one sends the points whose supports changed owner to their new owners
    /// ([`MpmDomain::migrate`]).
    fn own_blocks(&mut self, owners: Option<loam_fem::ranks::BlockOwners>) {
        self.owners = owners.filter(|o| o.len() >= self.blocks.pattern.len());
        let Some(ranks) = self.owners.as_ref().map(|o| o.ranks()) else { return };
        if self.distributed.is_none() {
            self.distributed = Some(DistributedPoints { ranks, counts: Vec::new(), held: 0 });
            self.migrate(true);
        } else if self.distributed.is_some() {
            self.migrate(false);
        }
    }

    fn points_distributed(&self) -> Option<Ranks> {
        self.distributed.as_ref().map(|d| d.ranks)
    }

    /// Updated-Lagrangian phase: the bodies' cells, then the walls' blocks.
    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let nd = self.block_len();
        let cells = self.blocks.pattern.len();
        let (cell_matrices, mut wall_matrices) = matrices.split_at_mut(cells * nd * nd);
        let (cell_vectors, mut wall_vectors) = vectors.split_at_mut(cells * nd);
        self.compute_internal_forces(input, cell_matrices, cell_vectors)?;
        if let Some(ghost) = &self.ghost {
            let (lm, lv) = ghost.buffer_lengths(&self.grid);
            let (m, rest_m) = std::mem::take(&mut wall_matrices).split_at_mut(lm);
            let (v, rest_v) = std::mem::take(&mut wall_vectors).split_at_mut(lv);
            ghost
                .assemble(&self.grid, &self.node_ids, self.formulation, self.thickness, input, m, v)
                .map_err(|e| DomainError { domain: self.name.clone(), ..e })?;
            wall_matrices = rest_m;
            wall_vectors = rest_v;
        }
        for wall in &self.walls {
            let (lm, lv) = wall.buffer_lengths(&self.grid);
            let (m, rest_m) = std::mem::take(&mut wall_matrices).split_at_mut(lm);
            let (v, rest_v) = std::mem::take(&mut wall_vectors).split_at_mut(lv);
            wall.assemble(self.at(), input, m, v);
            wall_matrices = rest_m;
            wall_vectors = rest_v;
        }
        Ok(())
    }

    /// Convective phase: the bodies' points move and commit; the walls record their forces.
    fn commit(&mut self, input: &AssemblyInput<'_>) {
        if self.distributed.is_none() {
            self.replicate_trials();
        }
        self.interpolate_to_points(input);
        let at = GridNodes { grid: &self.grid, node_ids: &self.node_ids };
        for wall in &mut self.walls {
            wall.commit(at, input);
        }
    }

    fn accept_initial_acceleration(&mut self, a: &[f64]) {
        for body in &mut self.bodies {
            body.interpolate_acceleration(&self.grid, &self.node_ids, a);
        }
    }

    fn kinetic_energy(&self, _v: &[f64]) -> f64 {
        self.bodies.iter().map(Body::kinetic_energy).sum()
    }

    fn strain_energy(&self) -> f64 {
        self.bodies.iter().map(|b| b.points.work.iter().sum::<f64>()).sum()
    }

    fn momentum(&self, name: Option<&str>, _v: &[f64]) -> Option<[f64; 3]> {
        let mut bodies = self.bodies.iter().filter(|b| name.is_none_or(|n| b.name == n)).peekable();
        bodies.peek()?;
        Some(bodies.map(Body::momentum).fold([0.0; 3], |p, q| std::array::from_fn(|i| p[i] + q[i])))
    }

    fn energies(&self, name: &str, _v: &[f64]) -> Option<(f64, f64)> {
        let b = self.bodies.iter().find(|b| b.name == name)?;
        Some((b.kinetic_energy(), b.points.work.iter().sum()))
    }

    fn boundary_facets(&self) -> Vec<Vec<usize>> {
        self.grid
            .mesh
            .boundary_facets()
            .into_iter()
            .map(|f| f.into_iter().map(|a| self.node_ids[a]).collect())
            .collect()
    }

    fn nearest_point(&self, x: &[f64]) -> Option<(usize, f64)> {
        let d2 = |p: &[f64; 3]| x.iter().enumerate().map(|(d, v)| (p[d] - v).powi(2)).sum::<f64>();
        self.bodies
            .iter()
            .flat_map(|b| (0..b.points.len()).map(move |p| (b.id_offset + b.points.id[p], d2(&b.points.position[p]))))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(id, d)| (id, d.sqrt()))
    }

    fn point_set(&self, name: &str) -> Option<Range<usize>> {
        self.bodies.iter().find(|b| b.name == name).map(Body::id_range)
    }

    fn point_extents(&self) -> Vec<PointExtent> {
        self.bodies.iter().flat_map(|b| b.point_extents(self.formulation, self.thickness)).collect()
    }

    fn point_tensor(&self, id: usize, quantity: PointTensor) -> Option<[[f64; 3]; 3]> {
        let (body, k) = self.body_of(id)?;
        let m = match quantity {
            PointTensor::CauchyStress => &body.points.cauchy[k],
            PointTensor::DeformationGradient => &body.points.deformation_gradient[k],
        };
        Some(std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])))
    }

    fn points_in_box(&self, min: &[f64], max: &[f64]) -> Vec<usize> {
        let inside = |x: &[f64; 3]| (0..min.len()).all(|d| x[d] >= min[d] && x[d] <= max[d]);
        let mut ids: Vec<usize> = self
            .bodies
            .iter()
            .flat_map(|b| {
                (0..b.points.len()).filter(|&p| inside(&b.points.position[p])).map(|p| b.id_offset + b.points.id[p])
            })
            .collect();
        ids.sort_unstable();
        ids
    }

    fn points_volume_mass(&self, min: &[f64], max: &[f64]) -> (f64, f64) {
        let inside = |x: &[f64; 3]| (0..min.len()).all(|d| x[d] >= min[d] && x[d] <= max[d]);
        self.bodies.iter().fold((0.0, 0.0), |acc, b| {
            let pts = &b.points;
            (0..pts.len())
                .filter(|&p| inside(&pts.position[p]))
                .fold(acc, |(v, m), p| (v + pts.volume[p], m + pts.mass[p]))
        })
    }

    fn add_point_load(&mut self, load: PointLoad) -> bool {
        for body in &mut self.bodies {
            let range = body.id_range();
            let ids: Vec<usize> = load.ids.iter().copied().filter(|id| range.contains(id)).collect();
            if !ids.is_empty() {
                body.add_point_load(PointLoad { ids, ..load.clone() });
            }
        }
        true
    }

    fn point_quantity(&self, id: usize, quantity: PointQuantity) -> Option<[f64; 3]> {
        let (body, k) = self.body_of(id)?;
        let pts = &body.points;
        Some(match quantity {
            PointQuantity::Position => pts.position[k],
            PointQuantity::Displacement => pts.displacement[k],
            PointQuantity::Velocity => pts.velocity[k],
            PointQuantity::Acceleration => pts.acceleration[k],
        })
    }

    fn grid_motion(&self) -> Option<(f64, Vec<String>)> {
        self.grid_motion_report().map(|(q, w)| (q, w.to_vec()))
    }

    fn wall_force(&self, wall: &str) -> Option<[f64; 3]> {
        self.walls.iter().find(|w| w.name() == wall).map(PenaltyBoundary::total_force)
    }

    /// The bodies' points, the walls' forces and the cells of the sparsity pattern (kept
    /// while the active cells stay inside it: a resumed run assembles the same pattern).
    ///
    /// Where the points are distributed, every rank's points are gathered into the state
    /// (collective: every rank saves at the same step, rank 0 writes it), which then restores
    /// on any number of ranks as a replicated model does.
    fn save_state(&self) -> Vec<u8> {
        let bodies = match &self.distributed {
            None => self.bodies.iter().map(Body::state).collect(),
            Some(d) => self.bodies.iter().map(|b| every_rank_state(b, d.ranks)).collect(),
        };
        let state = MpmState {
            bodies,
            walls: self.walls.iter().map(PenaltyBoundary::state).collect(),
            pattern: self.blocks.pattern.clone(),
            worst_cell_quality: self.worst_cell_quality,
            widenings: self.widenings.clone(),
        };
        bincode::serialize(&state).expect("an MPM domain's state encodes")
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let state: MpmState = bincode::deserialize(bytes).map_err(|e| format!("domain '{}': {e}", self.name))?;
        let cells = self.grid.num_supports();
        if state.bodies.len() != self.bodies.len()
            || state.walls.len() != self.walls.len()
            || state.pattern.iter().any(|&c| c >= cells)
        {
            return Err(format!("domain '{}': the saved state is of another grid, bodies or walls", self.name));
        }
        for (body, s) in self.bodies.iter_mut().zip(state.bodies) {
            body.restore(s)?;
        }
        // every rank holds every point again, until the next partition distributes them
        if let Some(d) = &mut self.distributed {
            loam_fem::ranks::with_stats(|s| s.points_held -= d.held as u64);
        }
        self.distributed = None;
        self.owners = None;
        for (wall, s) in self.walls.iter_mut().zip(state.walls) {
            wall.restore(s);
        }
        self.blocks.in_pattern = vec![false; cells];
        for &c in &state.pattern {
            self.blocks.in_pattern[c] = true;
        }
        self.blocks.pattern = state.pattern;
        self.worst_cell_quality = state.worst_cell_quality;
        if let Some(att) = &mut self.attachment {
            for _ in 0..state.widenings.len().saturating_sub(self.widenings.len()) {
                att.motion.widen();
            }
        }
        self.widenings = state.widenings;
        Ok(())
    }

    fn outputs(&self, committed: &NodalState, with_grid: bool) -> Vec<NamedOutput> {
        self.outputs_of(committed, with_grid, |b| 0..b.points.len())
    }

    /// The bodies' pieces built from the rank's share of their points only; the walls and the
    /// grid (small) built whole and split.
    fn output_pieces(&self, committed: &NodalState, with_grid: bool, rank: usize, size: usize) -> Vec<NamedOutput> {
        let bodies = self.bodies.len();
        let distributed = self.distributed.is_some();
        let mut out = self.outputs_of(committed, with_grid, |b| {
            // distributed points: this rank's own
            if distributed {
                0..b.points.len()
            } else {
                loam_fem::domain::share(b.points.len(), rank, size)
            }
        });
        for o in &mut out[bodies..] {
            o.output = o.output.piece(rank, size);
        }
        out
    }
}
