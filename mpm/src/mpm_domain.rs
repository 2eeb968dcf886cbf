//! The implicit MPM domain: material points on a background grid whose nodes are global.

use std::sync::Arc;

use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{
    AssemblyInput, Domain, DomainError, DomainOutput, Field, NodalState, PointQuantity, Projection,
};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;
use loam_fem::kernel::{point_geometry, solid_element, KernelContext, PointGeometry, PointOutput};
use loam_laws::ConstitutiveLaw;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::grid::StructuredGrid;
use crate::material_points::MaterialPoints;

/// Material points of one material on a structured background grid.
pub struct MpmDomain {
    name: String,
    formulation: Formulation,
    thickness: f64,
    grid: StructuredGrid,
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
}

impl MpmDomain {
    /// A domain with `points` on `grid`, whose local node `a` is global node `node_ids[a]`.
    pub fn new(
        name: &str,
        grid: StructuredGrid,
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
        }
    }

    /// Material points erased so far because they left the grid.
    pub fn erased(&self) -> usize {
        self.erased
    }

    /// The background grid.
    pub fn grid(&self) -> &StructuredGrid {
        &self.grid
    }

    fn dim(&self) -> usize {
        self.grid.mesh.element.dim()
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
    fn begin_step(&mut self, projection: &mut Projection) -> bool {
        let grid = &self.grid;
        let located: Vec<Option<(usize, [f64; 3])>> = self.points.position.par_iter().map(|x| grid.locate(x)).collect();
        let mut order: Vec<usize> = (0..located.len()).filter(|&p| located[p].is_some()).collect();
        self.erased += located.len() - order.len();
        order.sort_by_key(|&p| (located[p].unwrap().0, self.points.id[p]));
        let sl = self.law.state_len();
        if order.len() != located.len() || order.iter().enumerate().any(|(k, &p)| k != p) {
            self.points.reorder(&order, sl);
        }
        self.index_of_id.iter_mut().for_each(|i| *i = usize::MAX);
        for (k, &id) in self.points.id.iter().enumerate() {
            self.index_of_id[id] = k;
        }
        let element = grid.mesh.element;
        let (formulation, thickness) = (self.formulation, self.thickness);
        let cells_xi: Vec<(usize, [f64; 3])> = order.iter().map(|&p| located[p].unwrap()).collect();
        self.cell_of_point = cells_xi.iter().map(|c| c.0).collect();
        self.geometry = cells_xi
            .par_iter()
            .zip(self.points.volume.par_iter())
            .map(|((cell, xi), &volume)| {
                let coords: Vec<[f64; 3]> = grid.mesh.cell(*cell).iter().map(|&a| grid.mesh.coords[a]).collect();
                let mut g = point_geometry(element, formulation, thickness, &coords, xi, 1.0)
                    .expect("structured grid cells are not inverted");
                g.weight = volume;
                g
            })
            .collect();
        let mut active = Vec::new();
        let mut ptr = vec![0];
        for (k, &c) in self.cell_of_point.iter().enumerate() {
            if active.last() != Some(&c) {
                if !active.is_empty() {
                    ptr.push(k);
                }
                active.push(c);
            }
        }
        ptr.push(self.cell_of_point.len());
        if active.is_empty() {
            ptr = vec![0];
        }
        let changed = active != self.active_cells;
        self.active_cells = active;
        self.cell_ptr = ptr;
        self.trial_state.clone_from(&self.points.state);
        self.trial_out = vec![PointOutput::default(); self.points.len()];
        // grid reset and projection (summed with other domains on the same grid)
        let dim = self.dim();
        let nn = element.num_nodes();
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
        for &c in &self.active_cells {
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
        // per-cell mutable views of the trial arrays
        let mut states: Vec<&mut [f64]> = Vec::with_capacity(self.active_cells.len());
        let mut outs: Vec<&mut [PointOutput]> = Vec::with_capacity(self.active_cells.len());
        let (mut rest_s, mut rest_o) = (self.trial_state.as_mut_slice(), self.trial_out.as_mut_slice());
        for k in 0..self.active_cells.len() {
            let np = self.cell_ptr[k + 1] - self.cell_ptr[k];
            let (s, r) = std::mem::take(&mut rest_s).split_at_mut(np * sl);
            states.push(s);
            rest_s = r;
            let (o, r) = std::mem::take(&mut rest_o).split_at_mut(np);
            outs.push(o);
            rest_o = r;
        }
        let (grid, node_ids, geometry, points, cell_ptr, cells, name) =
            (&self.grid, &self.node_ids, &self.geometry, &self.points, &self.cell_ptr, &self.active_cells, &self.name);
        matrices
            .par_chunks_mut(nd * nd)
            .zip(vectors.par_chunks_mut(nd))
            .zip(states.into_par_iter().zip(outs.into_par_iter()))
            .enumerate()
            .try_for_each(|(k, ((km, fv), (trial, out)))| {
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
            })
    }

    /// Convective phase: `Δu_p = Σ N_I Δu_I`, `a_p = Σ N_I a_I`,
    /// `v_p ← v_p + Δt/2 (a_p^n + a_p^{n+1})`, `x_p ← x_p + Δu_p`, `F_p`, `V_p = J_p V_p^0`,
    /// law state and stress committed.
    fn commit(&mut self, input: &AssemblyInput<'_>) {
        let element = self.grid.mesh.element;
        let nn = element.num_nodes();
        let dim = self.dim();
        let dt = input.time_step;
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
                for a_ in 0..nn {
                    let g = node_ids[cell[a_]] * dim;
                    let n = geometry[p].shape[a_];
                    for i in 0..dim {
                        du[i] += n * (input.state.u[g + i] - input.committed.u[g + i]);
                        acc[i] += n * input.state.a[g + i];
                    }
                }
                for i in 0..dim {
                    if dynamic {
                        v[i] += 0.5 * dt * (a[i] + acc[i]);
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
