//! The implicit MPM domain: material points on a background grid whose nodes are global.

use std::sync::Arc;

use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{
    AssemblyInput, Domain, DomainError, DomainOutput, Field, NodalState, PointExtent, PointLoad, PointQuantity,
    PointTensor, Projection,
};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;
use loam_fem::kernel::{point_geometry, solid_element, KernelContext, PointGeometry, PointOutput};
use loam_laws::ConstitutiveLaw;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::grid::Grid;
use crate::material_points::MaterialPoints;

/// Material points of one material on a structured background grid.
pub struct MpmDomain {
    name: String,
    formulation: Formulation,
    thickness: f64,
    grid: Grid,
    node_ids: Vec<usize>,
    law: Arc<dyn ConstitutiveLaw>,
    /// The material points (sorted by cell during a step).
    pub points: MaterialPoints,
    index_of_id: Vec<usize>,
    cell_of_point: Vec<usize>,
    geometry: Vec<PointGeometry>,
    active_cells: Vec<usize>,
    cell_ptr: Vec<usize>,
    trial_state: Vec<f64>,
    trial_out: Vec<PointOutput>,
    erased: usize,
    /// Cells declared as element blocks (ascending): the active cells grown by
    /// `pattern_rings` rings when the pattern was last built. The sparsity pattern and the
    /// symbolic factorisation are kept while the active cells stay inside this set.
    pattern_cells: Vec<usize>,
    /// Whether each grid cell is in `pattern_cells`.
    in_pattern: Vec<bool>,
    /// For each block of `pattern_cells`: its index in `active_cells`, or `EMPTY`.
    block_active: Vec<usize>,
    /// For each block: bit `a` set if it carries the unit diagonal of its node `a`, which no
    /// active cell touches (an identity equation, `δu = 0`).
    block_orphans: Vec<u8>,
    /// Rings of cells around the active ones in the pattern (0: the pattern is the active
    /// set and is rebuilt whenever it changes).
    pattern_rings: usize,
    /// Forces carried by material points (particle Neumann conditions).
    point_loads: Vec<PointLoad>,
    /// Share of the PIC velocity in the convective phase (default: pure FLIP-type update).
    velocity_blend: VelocityBlend,
}

/// Share θ of the grid (PIC) velocity in the material points' velocity update of the
/// convective phase, `v_p ← (1 − θ) v_p^FLIP + θ Σ_I N_I v_I^{n+1}` (Brackbill & Ruppel
/// 1986; Nairn 2015 on FLIP/PIC blending). The blend damps the particle-velocity modes the
/// grid does not see by the factor `1 − θ` per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VelocityBlend {
    /// The same θ in every step (θ = 0: FLIP-type Newmark update; θ = 1: PIC); the damping
    /// per unit time then grows as the step shrinks.
    PicFraction(f64),
    /// `θ = 1 − exp(−Δt/τ)`: the modes decay as `exp(−t/τ)` whatever the step sizes, so that
    /// runs with different (or adaptive) steps damp alike.
    RelaxationTime(f64),
}

impl VelocityBlend {
    /// θ for a step of length `dt`.
    pub fn theta(self, dt: f64) -> f64 {
        match self {
            Self::PicFraction(theta) => theta,
            Self::RelaxationTime(tau) => -(-dt / tau).exp_m1(),
        }
    }
}

const EMPTY: usize = usize::MAX;

/// Rings of inactive cells kept in the sparsity pattern around the active ones (default 1;
/// `LOAM_MPM_PATTERN_RINGS=0` rebuilds the pattern at every change of the active set).
fn pattern_rings() -> usize {
    std::env::var("LOAM_MPM_PATTERN_RINGS").ok().and_then(|v| v.parse().ok()).unwrap_or(1)
}

impl MpmDomain {
    /// A domain with `points` on `grid`, whose local node `a` is global node `node_ids[a]`.
    pub fn new(
        name: &str,
        grid: Grid,
        node_ids: Vec<usize>,
        formulation: Formulation,
        thickness: f64,
        law: Arc<dyn ConstitutiveLaw>,
        mut points: MaterialPoints,
    ) -> Self {
        let sl = law.state_len();
        points.state = vec![0.0; points.len() * sl];
        for p in 0..points.len() {
            law.initialise_state(&mut points.state[p * sl..(p + 1) * sl]);
        }
        let index_of_id = (0..points.len()).collect();
        Self {
            name: name.to_string(),
            formulation,
            thickness,
            grid,
            node_ids,
            law,
            points,
            index_of_id,
            cell_of_point: Vec::new(),
            geometry: Vec::new(),
            active_cells: Vec::new(),
            cell_ptr: vec![0],
            trial_state: Vec::new(),
            trial_out: Vec::new(),
            erased: 0,
            pattern_cells: Vec::new(),
            in_pattern: Vec::new(),
            block_active: Vec::new(),
            block_orphans: Vec::new(),
            pattern_rings: pattern_rings(),
            point_loads: Vec::new(),
            velocity_blend: VelocityBlend::PicFraction(0.0),
        }
    }

    /// Blends the particle velocity update with the grid velocity ([`VelocityBlend`]). A
    /// small share damps the particle-velocity noise that the FLIP-type update accumulates in
    /// granular bodies coming to rest.
    pub fn set_velocity_blend(&mut self, blend: VelocityBlend) {
        self.velocity_blend = blend;
    }

    /// Starts every material point from the Cauchy stress `stress(x_p)` (at rest, `F = I`):
    /// the law writes the history that carries it
    /// ([`ConstitutiveLaw::initialise_state_at_stress`]). Fails with the first point whose
    /// stress the law cannot hold (e.g. outside the yield surface).
    pub fn set_initial_stress(
        &mut self,
        stress: impl Fn(&[f64; 3]) -> Matrix3<f64>,
    ) -> Result<(), (usize, loam_laws::LawError)> {
        let sl = self.law.state_len();
        for p in 0..self.points.len() {
            let sigma = stress(&self.points.position[p]);
            self.law
                .initialise_state_at_stress(&sigma, &mut self.points.state[p * sl..(p + 1) * sl])
                .map_err(|e| (p, e))?;
            self.points.cauchy[p] = sigma;
        }
        Ok(())
    }

    /// Material points erased so far because they left the grid.
    pub fn erased(&self) -> usize {
        self.erased
    }

    /// The background grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    fn dim(&self) -> usize {
        self.grid.mesh.element.dim()
    }

    /// Particle Neumann: every loaded point `p` in cell `c` adds `−N_I(ξ_p) F f(t)` to the
    /// residual of the block of `c` (`r = f_int − f_ext + M ã`). The point's natural
    /// coordinates are fixed within a step (the grid moves with the body), so the force
    /// is a follower of the body without a tangent contribution.
    fn add_point_loads(&self, time: f64, vectors: &mut [f64]) {
        let nn = self.grid.mesh.element.num_nodes();
        let dim = self.dim();
        let nd = nn * dim;
        for load in &self.point_loads {
            let f = load.amplitude.at(time);
            for &id in &load.ids {
                let k = self.index_of_id[id];
                if k == usize::MAX {
                    continue; // erased
                }
                let b = self
                    .pattern_cells
                    .binary_search(&self.cell_of_point[k])
                    .expect("the cell of a material point is in the pattern");
                let v = &mut vectors[b * nd..(b + 1) * nd];
                for a in 0..nn {
                    let n = self.geometry[k].shape[a];
                    for i in 0..dim {
                        v[a * dim + i] -= n * load.force[i] * f;
                    }
                }
            }
        }
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

    /// Initialisation phase: locate (erasing points outside the grid), sort by cell,
    /// compute shape functions at the points, mark the grid nodes for reset and project
    /// `m_I = Σ N_I m_p`, `(m v)_I = Σ N_I m_p v_p`, `(m a)_I = Σ N_I m_p a_p`.
    /// A node that another body on the same grid gives mass is not an orphan of this
    /// domain's pattern: its unit diagonal would add to that body's mass and stiffness (and
    /// spoil, e.g., the initial acceleration `M a₀ = f_ext − f_int` of layered bodies).
    fn end_projection(&mut self, projection: &Projection) {
        for (mask, &c) in self.block_orphans.iter_mut().zip(&self.pattern_cells) {
            for (a, &node) in self.grid.mesh.cell(c).iter().enumerate() {
                if *mask & (1 << a) != 0 && projection.mass[self.node_ids[node]] > 0.0 {
                    *mask &= !(1 << a);
                }
            }
        }
    }

    fn begin_step(&mut self, projection: &mut Projection) -> bool {
        let grid = &self.grid;
        let n_before = self.points.len();
        let located: Vec<Option<(usize, [f64; 3])>> =
            self.points.position.par_iter().with_min_len(1024).map(|x| grid.locate(x)).collect();
        // counting sort by cell, each cell's points by id: order (cell, id)
        let num_cells = grid.mesh.num_cells();
        let mut start = vec![0usize; num_cells + 1];
        for (c, _) in located.iter().flatten() {
            start[c + 1] += 1;
        }
        for c in 0..num_cells {
            start[c + 1] += start[c];
        }
        let kept = start[num_cells];
        self.erased += n_before - kept;
        let mut order = vec![0usize; kept];
        {
            let mut fill = start.clone();
            for (p, l) in located.iter().enumerate() {
                if let Some((c, _)) = l {
                    order[fill[*c]] = p;
                    fill[*c] += 1;
                }
            }
        }
        let ids = &self.points.id;
        let mut active = Vec::new();
        let mut ptr = vec![0];
        for c in 0..num_cells {
            let (a, b) = (start[c], start[c + 1]);
            if b > a {
                order[a..b].sort_unstable_by_key(|&p| ids[p]);
                active.push(c);
                ptr.push(b);
            }
        }
        let sl = self.law.state_len();
        if kept != n_before || order.iter().enumerate().any(|(k, &p)| k != p) {
            self.points.reorder(&order, sl);
        }
        self.index_of_id.iter_mut().for_each(|i| *i = usize::MAX);
        for (k, &id) in self.points.id.iter().enumerate() {
            self.index_of_id[id] = k;
        }
        let element = grid.mesh.element;
        let nn = element.num_nodes();
        let (formulation, thickness) = (self.formulation, self.thickness);
        self.cell_of_point.clear();
        self.cell_of_point.extend(order.iter().map(|&p| located[p].expect("kept points are located").0));
        order
            .par_iter()
            .with_min_len(1024)
            .zip(self.points.volume.par_iter())
            .map(|(&p, &volume)| {
                let (cell, xi) = located[p].expect("kept points are located");
                let coords = grid.cell_coords(cell);
                let mut g =
                    point_geometry(element, formulation, thickness, &coords[..nn], &xi, 1.0, grid.cell_map(cell))
                        .expect("located points lie in cells that are not inverted");
                g.weight = volume;
                g
            })
            .collect_into_vec(&mut self.geometry);
        if active.is_empty() {
            ptr = vec![0];
        }
        // keep the pattern while the active cells stay inside it
        let changed = if self.pattern_rings == 0 {
            active != self.active_cells || self.pattern_cells != active
        } else {
            self.pattern_cells.is_empty() || active.iter().any(|&c| !self.in_pattern[c])
        };
        if changed {
            let mut cells = active.clone();
            for _ in 0..self.pattern_rings {
                cells = grid.dilate(&cells);
            }
            self.in_pattern = vec![false; num_cells];
            for &c in &cells {
                self.in_pattern[c] = true;
            }
            self.pattern_cells = cells;
        }
        self.active_cells = active;
        self.cell_ptr = ptr;
        // blocks of the pattern: active index, or the identity rows of nodes no active cell touches
        let mut live = vec![false; grid.mesh.coords.len()];
        for &c in &self.active_cells {
            for &a in grid.mesh.cell(c) {
                live[a] = true;
            }
        }
        self.block_active.clear();
        self.block_orphans.clear();
        let mut next = 0;
        for &c in &self.pattern_cells {
            if next < self.active_cells.len() && self.active_cells[next] == c {
                self.block_active.push(next);
                self.block_orphans.push(0);
                next += 1;
            } else {
                self.block_active.push(EMPTY);
                let mut mask = 0u8;
                for (a, &node) in grid.mesh.cell(c).iter().enumerate() {
                    if !live[node] {
                        live[node] = true; // owned by this block
                        mask |= 1 << a;
                    }
                }
                self.block_orphans.push(mask);
            }
        }
        debug_assert_eq!(next, self.active_cells.len());
        self.trial_state.clone_from(&self.points.state);
        self.trial_out.resize(self.points.len(), PointOutput::default());
        // grid reset and projection (summed with other domains on the same grid)
        projection.points.extend(self.point_extents());
        let dim = self.dim();
        for &g in &self.node_ids {
            projection.reset[g] = true;
        }
        for (p, &cell) in self.cell_of_point.iter().enumerate() {
            let m = self.points.mass[p];
            for (a, &node) in grid.mesh.cell(cell).iter().enumerate().take(nn) {
                let w = self.geometry[p].shape[a] * m;
                let g = self.node_ids[node];
                projection.mass[g] += w;
                for i in 0..dim {
                    projection.momentum[g * dim + i] += w * self.points.velocity[p][i];
                    projection.inertia[g * dim + i] += w * self.points.acceleration[p][i];
                }
            }
        }
        changed
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        let dim = self.dim();
        for &c in &self.pattern_cells {
            layout.push(self.grid.mesh.cell(c).iter().flat_map(|&a| (0..dim).map(move |i| self.node_ids[a] * dim + i)));
        }
    }

    /// Updated-Lagrangian phase: the material points of each active cell are the kernel's
    /// integration points (weight `V_p^n`, `F0 = F_p^n`); lumped mass `M_I = Σ_p N_I m_p`.
    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let element = self.grid.mesh.element;
        let nn = element.num_nodes();
        let dim = self.dim();
        let nd = nn * dim;
        let sl = self.law.state_len();
        let ctx = KernelContext {
            element,
            formulation: self.formulation,
            law: self.law.as_ref(),
            time_step: input.time_step,
        };
        // per-block mutable views of the trial arrays (none for blocks without points)
        let mut views: Vec<Option<(&mut [f64], &mut [PointOutput])>> = Vec::with_capacity(self.block_active.len());
        let (mut rest_s, mut rest_o) = (self.trial_state.as_mut_slice(), self.trial_out.as_mut_slice());
        for &k in &self.block_active {
            if k == EMPTY {
                views.push(None);
                continue;
            }
            let np = self.cell_ptr[k + 1] - self.cell_ptr[k];
            let (s, r) = std::mem::take(&mut rest_s).split_at_mut(np * sl);
            rest_s = r;
            let (o, r) = std::mem::take(&mut rest_o).split_at_mut(np);
            rest_o = r;
            views.push(Some((s, o)));
        }
        let (grid, node_ids, geometry, points, cell_ptr, cells, name) =
            (&self.grid, &self.node_ids, &self.geometry, &self.points, &self.cell_ptr, &self.active_cells, &self.name);
        let (block_active, block_orphans) = (&self.block_active, &self.block_orphans);
        matrices
            .par_chunks_mut(nd * nd)
            .zip(vectors.par_chunks_mut(nd))
            .zip(views.into_par_iter())
            .enumerate()
            .with_min_len(16)
            .try_for_each(|(b, ((km, fv), view))| {
                let Some((trial, out)) = view else {
                    fv.fill(0.0);
                    if input.with_tangent {
                        km.fill(0.0);
                        for a in 0..nn {
                            if block_orphans[b] & (1 << a) != 0 {
                                for i in 0..dim {
                                    km[(a * dim + i) * nd + a * dim + i] = 1.0;
                                }
                            }
                        }
                    }
                    return Ok(());
                };
                let k = block_active[b];
                let cell = grid.mesh.cell(cells[k]);
                let mut disp = [[0.0; 3]; MAX_NODES];
                for (a, &local) in cell.iter().enumerate() {
                    for i in 0..dim {
                        let dof = node_ids[local] * dim + i;
                        disp[a][i] = input.state.u[dof] - input.committed.u[dof];
                    }
                }
                let range = cell_ptr[k]..cell_ptr[k + 1];
                let f = &points.deformation_gradient[range.clone()];
                solid_element(
                    &ctx,
                    &disp[..nn],
                    &geometry[range.clone()],
                    f,
                    f,
                    &points.state[range.start * sl..range.end * sl],
                    trial,
                    out,
                    fv,
                    if input.with_tangent && input.stiffness {
                        Some(&mut *km)
                    } else {
                        if input.with_tangent {
                            km.fill(0.0);
                        }
                        None
                    },
                )
                .map_err(|err| DomainError {
                    domain: name.clone(),
                    element: cells[k],
                    message: err.to_string(),
                })?;
                let mut lumped = [0.0; MAX_NODES];
                for p in range {
                    for (a, m) in lumped.iter_mut().enumerate().take(nn) {
                        *m += geometry[p].shape[a] * points.mass[p];
                    }
                }
                for a in 0..nn {
                    let g = node_ids[cell[a]] * dim;
                    for i in 0..dim {
                        let mut r = -lumped[a] * input.gravity[i];
                        if let Some(acc) = input.inertial_acceleration {
                            r += lumped[a] * acc[g + i];
                        }
                        fv[a * dim + i] += r;
                        if input.with_tangent {
                            km[(a * dim + i) * nd + a * dim + i] += input.mass_coefficient * lumped[a];
                        }
                    }
                }
                Ok(())
            })?;
        self.add_point_loads(input.time, vectors);
        Ok(())
    }

    /// Convective phase: `Δu_p = Σ N_I Δu_I`, `a_p = Σ N_I a_I`,
    /// `v_p ← v_p + Δt ((1 − γ) a_p^n + γ a_p^{n+1})` (γ = ½: trapezoidal), `x_p ← x_p + Δu_p`, `F_p`, `V_p = J_p V_p^0`,
    /// law state and stress committed.
    fn commit(&mut self, input: &AssemblyInput<'_>) {
        let element = self.grid.mesh.element;
        let nn = element.num_nodes();
        let dim = self.dim();
        let (dt, gamma) = (input.time_step, input.gamma);
        let theta = self.velocity_blend.theta(dt);
        let dynamic = input.inertial_acceleration.is_some();
        let (grid, node_ids, geometry, cells) = (&self.grid, &self.node_ids, &self.geometry, &self.cell_of_point);
        let pts = &mut self.points;
        let outs = &self.trial_out;
        (
            pts.position.par_iter_mut(),
            pts.displacement.par_iter_mut(),
            pts.velocity.par_iter_mut(),
            pts.acceleration.par_iter_mut(),
            pts.deformation_gradient.par_iter_mut(),
            pts.cauchy.par_iter_mut(),
            pts.volume.par_iter_mut(),
        )
            .into_par_iter()
            .zip(pts.work.par_iter_mut().zip(pts.initial_volume.par_iter()))
            .enumerate()
            .for_each(|(p, ((x, u, v, a, f, sigma, vol), (work, v0)))| {
                let cell = grid.mesh.cell(cells[p]);
                let mut du = [0.0; 3];
                let mut acc = [0.0; 3];
                let mut v_grid = [0.0; 3];
                for a_ in 0..nn {
                    let g = node_ids[cell[a_]] * dim;
                    let n = geometry[p].shape[a_];
                    for i in 0..dim {
                        du[i] += n * (input.state.u[g + i] - input.committed.u[g + i]);
                        acc[i] += n * input.state.a[g + i];
                        v_grid[i] += n * input.state.v[g + i];
                    }
                }
                for i in 0..dim {
                    if dynamic {
                        let flip = v[i] + dt * ((1.0 - gamma) * a[i] + gamma * acc[i]);
                        v[i] = (1.0 - theta) * flip + theta * v_grid[i];
                        a[i] = acc[i];
                    }
                    x[i] += du[i];
                    u[i] += du[i];
                }
                let o = &outs[p];
                let delta_f = o.deformation_gradient * f.try_inverse().unwrap_or_else(Matrix3::identity);
                *work += 0.5 * (*sigma + o.stress).dot(&(delta_f - Matrix3::identity())) * *vol;
                *f = o.deformation_gradient;
                *sigma = o.cauchy;
                *vol = v0 * f.determinant();
            });
        self.points.state.copy_from_slice(&self.trial_state);
    }

    fn accept_initial_acceleration(&mut self, a: &[f64]) {
        let element = self.grid.mesh.element;
        let dim = self.dim();
        for (p, &cell) in self.cell_of_point.iter().enumerate() {
            let mut acc = [0.0; 3];
            for (k, &node) in self.grid.mesh.cell(cell).iter().enumerate().take(element.num_nodes()) {
                let g = self.node_ids[node] * dim;
                for i in 0..dim {
                    acc[i] += self.geometry[p].shape[k] * a[g + i];
                }
            }
            self.points.acceleration[p] = acc;
        }
    }

    fn kinetic_energy(&self, _v: &[f64]) -> f64 {
        (0..self.points.len())
            .map(|p| 0.5 * self.points.mass[p] * self.points.velocity[p].iter().map(|c| c * c).sum::<f64>())
            .sum()
    }

    fn strain_energy(&self) -> f64 {
        self.points.work.iter().sum()
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
        (0..self.points.len())
            .min_by(|&a, &b| d2(&self.points.position[a]).total_cmp(&d2(&self.points.position[b])))
            .map(|p| (self.points.id[p], d2(&self.points.position[p]).sqrt()))
    }

    fn point_extents(&self) -> Vec<PointExtent> {
        let pts = &self.points;
        (0..pts.len())
            .map(|p| {
                let x = pts.position[p];
                let size = |v: f64| match self.formulation {
                    Formulation::ThreeD => v.cbrt(),
                    Formulation::Axisymmetric => (v / (2.0 * std::f64::consts::PI * x[0].max(1e-300))).sqrt(),
                    _ => (v / self.thickness).sqrt(),
                };
                PointExtent { position: x, size: size(pts.volume[p]), initial_size: size(pts.initial_volume[p]) }
            })
            .collect()
    }

    fn point_tensor(&self, id: usize, quantity: PointTensor) -> Option<[[f64; 3]; 3]> {
        let &k = self.index_of_id.get(id)?;
        if k == usize::MAX {
            return None;
        }
        let m = match quantity {
            PointTensor::CauchyStress => &self.points.cauchy[k],
            PointTensor::DeformationGradient => &self.points.deformation_gradient[k],
        };
        Some(std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])))
    }

    fn points_in_box(&self, min: &[f64], max: &[f64]) -> Vec<usize> {
        let inside = |x: &[f64; 3]| (0..min.len()).all(|d| x[d] >= min[d] && x[d] <= max[d]);
        let mut ids: Vec<usize> =
            (0..self.points.len()).filter(|&p| inside(&self.points.position[p])).map(|p| self.points.id[p]).collect();
        ids.sort_unstable();
        ids
    }

    fn points_volume_mass(&self, min: &[f64], max: &[f64]) -> (f64, f64) {
        let pts = &self.points;
        let inside = |x: &[f64; 3]| (0..min.len()).all(|d| x[d] >= min[d] && x[d] <= max[d]);
        (0..pts.len())
            .filter(|&p| inside(&pts.position[p]))
            .fold((0.0, 0.0), |(v, m), p| (v + pts.volume[p], m + pts.mass[p]))
    }

    fn add_point_load(&mut self, load: PointLoad) -> bool {
        self.point_loads.push(load);
        true
    }

    fn point_quantity(&self, id: usize, quantity: PointQuantity) -> Option<[f64; 3]> {
        let &k = self.index_of_id.get(id)?;
        if k == usize::MAX {
            return None;
        }
        Some(match quantity {
            PointQuantity::Position => self.points.position[k],
            PointQuantity::Displacement => self.points.displacement[k],
            PointQuantity::Velocity => self.points.velocity[k],
            PointQuantity::Acceleration => self.points.acceleration[k],
        })
    }

    /// The background grid in its reference position with nodal `mass` (`Σ_p N_I m_p` of
    /// this domain's points in the last step), `displacement_increment` (`Δu` of the last
    /// step: the grid is reset at the start of each step), `velocity`, `acceleration` and
    /// `active` (1 on nodes of cells holding points in the last step, else 0).
    fn grid_output(&self, committed: &NodalState) -> Option<DomainOutput> {
        let mesh = &self.grid.mesh;
        let (dim, nn) = (self.dim(), mesh.element.num_nodes());
        let nodal = |src: &[f64]| -> Vec<f64> {
            self.node_ids
                .iter()
                .flat_map(|&g| (0..3).map(move |i| if i < dim { src[g * dim + i] } else { 0.0 }))
                .collect()
        };
        let mut mass = vec![0.0; mesh.coords.len()];
        for (p, &cell) in self.cell_of_point.iter().enumerate() {
            for (a, &node) in mesh.cell(cell).iter().enumerate().take(nn) {
                mass[node] += self.geometry[p].shape[a] * self.points.mass[p];
            }
        }
        let mut active = vec![0.0; mesh.coords.len()];
        for &c in &self.active_cells {
            for &node in mesh.cell(c) {
                active[node] = 1.0;
            }
        }
        let point_fields = vec![
            Field { name: "mass".into(), components: 1, values: mass },
            Field { name: "displacement_increment".into(), components: 3, values: nodal(&committed.u) },
            Field { name: "velocity".into(), components: 3, values: nodal(&committed.v) },
            Field { name: "acceleration".into(), components: 3, values: nodal(&committed.a) },
            Field { name: "active".into(), components: 1, values: active },
        ];
        Some(DomainOutput {
            points: mesh.coords.clone(),
            cells: Some((mesh.element, mesh.connectivity.clone())),
            point_fields,
            cell_fields: Vec::new(),
        })
    }

    fn output(&self, _committed: &NodalState) -> DomainOutput {
        let pts = &self.points;
        let n = pts.len();
        let vec3 = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
        let tensor =
            |v: &[Matrix3<f64>]| v.iter().flat_map(|m| m.transpose().iter().copied().collect::<Vec<_>>()).collect();
        let names = self.law.state_variables();
        let sl = self.law.state_len();
        let mut states = vec![vec![0.0; n]; names.len()];
        let mut tmp = vec![0.0; names.len()];
        for p in 0..n {
            self.law.state_output(&pts.state[p * sl..(p + 1) * sl], &mut tmp);
            for (k, v) in tmp.iter().enumerate() {
                states[k][p] = *v;
            }
        }
        let mut point_fields = vec![
            Field { name: "displacement".into(), components: 3, values: vec3(&pts.displacement) },
            Field { name: "velocity".into(), components: 3, values: vec3(&pts.velocity) },
            Field { name: "acceleration".into(), components: 3, values: vec3(&pts.acceleration) },
            Field { name: "mass".into(), components: 1, values: pts.mass.clone() },
            Field { name: "volume".into(), components: 1, values: pts.volume.clone() },
            Field { name: "cauchy_stress".into(), components: 9, values: tensor(&pts.cauchy) },
            Field { name: "deformation_gradient".into(), components: 9, values: tensor(&pts.deformation_gradient) },
            Field {
                name: "von_mises_stress".into(),
                components: 1,
                values: pts.cauchy.iter().map(loam_fem::von_mises).collect(),
            },
            Field { name: "id".into(), components: 1, values: pts.id.iter().map(|&i| i as f64).collect() },
        ];
        for (k, name) in names.iter().enumerate() {
            point_fields.push(Field { name: name.to_string(), components: 1, values: std::mem::take(&mut states[k]) });
        }
        DomainOutput { points: pts.position.clone(), cells: None, point_fields, cell_fields: Vec::new() }
    }
}
