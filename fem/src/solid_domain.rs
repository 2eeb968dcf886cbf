//! The Lagrangian FEM domain: a total-Lagrangian solid on a mesh whose nodes are global.
//!
//! Gauss points are the kernel's integration points (`F0 = I`, weights `det J · w_q` on the
//! reference mesh), so the geometry of every point is computed once. The mass matrix
//! `M_ab = ∫ ρ0 N_a N_b dV0` is constant in a total-Lagrangian description and is also
//! computed once (consistent with a higher-order rule, or lumped by row sums).
//!
//! A domain in the mixed u–p formulation ([`FemDomain::new_mixed`]) also carries a pressure
//! DOF at each of its nodes and integrates with [`crate::mixed_kernel::mixed_element`] on the
//! rule [`ElementType::gauss_points_mixed`].

use std::sync::Arc;

use loam_laws::ConstitutiveLaw;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::assembly::BlockLayout;
use crate::domain::{AssemblyInput, Domain, DomainError, DomainOutput, Field, NamedOutput, NodalState};
use crate::element::{ElementType, MAX_NODES};
use crate::formulation::Formulation;
use crate::kernel::{point_geometry, solid_element, KernelContext, PointOutput};
use crate::mesh::Mesh;
use crate::mixed_kernel::mixed_element;
use crate::packed_geometry::PackedGeometry;

/// What an FEM domain carries from step to step beside the nodal unknowns.
#[derive(serde::Serialize, serde::Deserialize)]
struct FemState {
    law_history: Vec<f64>,
    points: Vec<PointOutput>,
    previous_deformation_gradient: Vec<Matrix3<f64>>,
    work: Vec<f64>,
}

/// A solid FEM domain of one element type and one material.
pub struct FemDomain {
    name: String,
    formulation: Formulation,
    thickness: f64,
    element: ElementType,
    mesh: Mesh,
    node_ids: Vec<usize>,
    law: Arc<dyn ConstitutiveLaw>,
    points_per_element: usize,
    geometry: PackedGeometry,
    identity: Vec<Matrix3<f64>>,
    f_prev: Vec<Matrix3<f64>>,
    state_stride: usize,
    committed_state: Vec<f64>,
    trial_state: Vec<f64>,
    committed_out: Vec<PointOutput>,
    trial_out: Vec<PointOutput>,
    mass: Vec<f64>,
    work: Vec<f64>,
    /// Global pressure DOF of each local node (mixed u–p domains).
    pressure_dofs: Option<Vec<usize>>,
    /// In a distributed run, the rank that evaluates each element ([`Domain::own_blocks`]).
    owners: Option<crate::ranks::BlockOwners>,
}

impl FemDomain {
    /// Builds the domain on `mesh`, whose local node `a` is global node `node_ids[a]`.
    /// Fails with the index of the first inverted element.
    pub fn new(
        name: &str,
        mesh: Mesh,
        node_ids: Vec<usize>,
        formulation: Formulation,
        thickness: f64,
        law: Arc<dyn ConstitutiveLaw>,
        lumped_mass: bool,
    ) -> Result<Self, DomainError> {
        Self::build(name, mesh, node_ids, None, formulation, thickness, law, lumped_mass)
    }

    /// A domain in the mixed u–p formulation, as [`FemDomain::new`] on the u–p rule; its
    /// nodes' pressure DOFs are given by [`FemDomain::set_pressure_dofs`] before it assembles.
    pub fn new_mixed(
        name: &str,
        mesh: Mesh,
        node_ids: Vec<usize>,
        formulation: Formulation,
        thickness: f64,
        law: Arc<dyn ConstitutiveLaw>,
        lumped_mass: bool,
    ) -> Result<Self, DomainError> {
        Self::build(name, mesh, node_ids, Some(Vec::new()), formulation, thickness, law, lumped_mass)
    }

    /// The global pressure DOF `dofs[a]` of each local node `a` (u–p domains).
    ///
    /// # Panics
    /// If the domain is not a u–p one or `dofs` does not have one entry per node.
    pub fn set_pressure_dofs(&mut self, dofs: Vec<usize>) {
        assert!(self.pressure_dofs.is_some() && dofs.len() == self.node_ids.len(), "a u–p domain, one DOF per node");
        self.pressure_dofs = Some(dofs);
    }

    /// The material's law.
    pub fn law(&self) -> &dyn ConstitutiveLaw {
        self.law.as_ref()
    }

    fn build(
        name: &str,
        mesh: Mesh,
        node_ids: Vec<usize>,
        pressure_dofs: Option<Vec<usize>>,
        formulation: Formulation,
        thickness: f64,
        law: Arc<dyn ConstitutiveLaw>,
        lumped_mass: bool,
    ) -> Result<Self, DomainError> {
        let element = mesh.element;
        let nn = element.num_nodes();
        let rule = if pressure_dofs.is_some() { element.gauss_points_mixed() } else { element.gauss_points() };
        let mass_rule = element.gauss_points_high();
        let ngp = rule.len();
        let ne = mesh.num_cells();
        let mut geometry = PackedGeometry::default();
        geometry.resize(nn, ne * ngp);
        let mut records = geometry.records_mut();
        let mut mass = vec![0.0; ne * nn * nn];
        let rho = law.density();
        for e in 0..ne {
            let coords: Vec<[f64; 3]> = mesh.cell(e).iter().map(|&a| mesh.coords[a]).collect();
            let fail = |err: crate::kernel::KernelError| DomainError {
                domain: name.to_string(),
                element: e,
                message: format!("{err} (check the node ordering: counter-clockwise in 2D)"),
            };
            for gp in &rule {
                let g =
                    point_geometry(element, formulation, thickness, &coords, &gp.xi, gp.weight, None).map_err(fail)?;
                PackedGeometry::pack(records.next().expect("one record per point"), &g);
            }
            let me = &mut mass[e * nn * nn..(e + 1) * nn * nn];
            for gp in &mass_rule {
                let g =
                    point_geometry(element, formulation, thickness, &coords, &gp.xi, gp.weight, None).map_err(fail)?;
                for a in 0..nn {
                    for b in 0..nn {
                        me[a * nn + b] += rho * g.weight * g.shape[a] * g.shape[b];
                    }
                }
            }
            if lumped_mass {
                for a in 0..nn {
                    let row: f64 = me[a * nn..(a + 1) * nn].iter().sum();
                    me[a * nn..(a + 1) * nn].fill(0.0);
                    me[a * nn + a] = row;
                }
            }
        }
        let state_len = law.state_len();
        let state_stride = ngp * state_len.max(1);
        let mut committed_state = vec![0.0; ne * state_stride];
        for p in 0..ne * ngp {
            let (e, q) = (p / ngp, p % ngp);
            let start = e * state_stride + q * state_len;
            law.initialise_state(&mut committed_state[start..start + state_len]);
        }
        Ok(Self {
            name: name.to_string(),
            formulation,
            thickness,
            element,
            mesh,
            node_ids,
            law,
            points_per_element: ngp,
            geometry,
            identity: vec![Matrix3::identity(); ngp],
            f_prev: vec![Matrix3::identity(); ne * ngp],
            state_stride,
            trial_state: committed_state.clone(),
            committed_state,
            committed_out: vec![PointOutput::default(); ne * ngp],
            trial_out: vec![PointOutput::default(); ne * ngp],
            mass,
            work: vec![0.0; ne * ngp],
            pressure_dofs,
            owners: None,
        })
    }

    /// Global node ids of the domain's nodes.
    pub fn node_ids(&self) -> &[usize] {
        &self.node_ids
    }

    /// The mesh (local node numbering).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn dim(&self) -> usize {
        self.element.dim()
    }

    /// DOFs of an element block: `nn·dim` displacements, then `nn` pressures if mixed.
    fn block_len(&self) -> usize {
        let nn = self.element.num_nodes();
        nn * self.dim() + if self.pressure_dofs.is_some() { nn } else { 0 }
    }
}

impl Domain for FemDomain {
    fn name(&self) -> &str {
        &self.name
    }

    fn formulation(&self) -> Formulation {
        self.formulation
    }

    fn thickness(&self) -> f64 {
        self.thickness
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        let dim = self.dim();
        for e in 0..self.mesh.num_cells() {
            let cell = self.mesh.cell(e);
            let pressures = self.pressure_dofs.iter().flat_map(|p| cell.iter().map(move |&a| p[a]));
            layout.push(cell.iter().flat_map(|&a| (0..dim).map(move |i| self.node_ids[a] * dim + i)).chain(pressures));
        }
    }

    /// One unit per Gauss point of every element.
    fn block_costs(&self, costs: &mut Vec<f64>) {
        costs.extend(std::iter::repeat_n(self.points_per_element as f64, self.mesh.num_cells()));
    }

    fn own_blocks(&mut self, owners: Option<crate::ranks::BlockOwners>) {
        self.owners = owners.filter(|o| o.len() == self.mesh.num_cells());
    }

    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let owners = self.owners.as_ref();
        let nn = self.element.num_nodes();
        let dim = self.dim();
        let nd = self.block_len();
        let ngp = self.points_per_element;
        let pressure_dofs = self.pressure_dofs.as_deref();
        let ctx = KernelContext {
            element: self.element,
            formulation: self.formulation,
            law: self.law.as_ref(),
            time_step: input.time_step,
        };
        let (mesh, node_ids, geometry, f_prev, identity, mass, committed) = (
            &self.mesh,
            &self.node_ids,
            &self.geometry,
            &self.f_prev,
            &self.identity,
            &self.mass,
            &self.committed_state,
        );
        let name = &self.name;
        matrices
            .par_chunks_mut(nd * nd)
            .zip(vectors.par_chunks_mut(nd))
            .zip(self.trial_state.par_chunks_mut(self.state_stride))
            .zip(self.trial_out.par_chunks_mut(ngp))
            .enumerate()
            .try_for_each(|(e, (((km, fv), trial), out))| {
                if owners.is_some_and(|o| !o.owns(e)) {
                    return Ok(()); // another rank's element
                }
                let cell = mesh.cell(e);
                let mut disp = [[0.0; 3]; MAX_NODES];
                for (a, &local) in cell.iter().enumerate() {
                    for i in 0..dim {
                        disp[a][i] = input.state.u[node_ids[local] * dim + i];
                    }
                }
                let points = e * ngp..(e + 1) * ngp;
                let stride = self.state_stride;
                let stiffness = if input.with_tangent && input.stiffness {
                    Some(&mut *km)
                } else {
                    if input.with_tangent {
                        km.fill(0.0);
                    }
                    None
                };
                let (geometry, f_prev, committed) =
                    (&geometry.points(points.clone()), &f_prev[points], &committed[e * stride..(e + 1) * stride]);
                match pressure_dofs {
                    None => solid_element(
                        &ctx,
                        &disp[..nn],
                        geometry,
                        identity,
                        f_prev,
                        committed,
                        trial,
                        out,
                        fv,
                        stiffness,
                    ),
                    Some(p_dofs) => {
                        let mut pressure = [0.0; MAX_NODES];
                        for (a, &local) in cell.iter().enumerate() {
                            pressure[a] = input.state.u[p_dofs[local]];
                        }
                        mixed_element(
                            &ctx,
                            &disp[..nn],
                            &pressure[..nn],
                            geometry,
                            identity,
                            f_prev,
                            committed,
                            trial,
                            out,
                            fv,
                            stiffness,
                            None,
                        )
                    }
                }
                .map_err(|err| DomainError {
                    domain: name.clone(),
                    element: e,
                    message: err.to_string(),
                })?;
                let me = &mass[e * nn * nn..(e + 1) * nn * nn];
                // the mass block enters the tangent only in dynamics (c_M = 0 in statics)
                let mass_tangent = input.with_tangent && input.mass_coefficient != 0.0;
                for a in 0..nn {
                    for b in 0..nn {
                        let m = me[a * nn + b];
                        if m == 0.0 {
                            continue;
                        }
                        let gb = node_ids[cell[b]] * dim;
                        for i in 0..dim {
                            let mut r = -m * input.gravity[i];
                            if let Some(acc) = input.inertial_acceleration {
                                r += m * acc[gb + i];
                            }
                            fv[a * dim + i] += r;
                            if mass_tangent {
                                km[(a * dim + i) * nd + b * dim + i] += input.mass_coefficient * m;
                            }
                        }
                    }
                }
                if pressure_dofs.is_some() && !input.stiffness {
                    // mass only (the consistent initial acceleration): pressures carry no
                    // inertia, their rows are `1 · a_p = 0`
                    let nu = nn * dim;
                    fv[nu..].fill(0.0);
                    if input.with_tangent {
                        for a in 0..nn {
                            km[(nu + a) * nd + nu + a] = 1.0;
                        }
                    }
                }
                Ok(())
            })
    }

    fn commit(&mut self, _input: &AssemblyInput<'_>) {
        if let Some(o) = &self.owners {
            // the Gauss points of other ranks' elements (docs/distributed.md)
            let ngp = self.points_per_element;
            let owner: Vec<usize> = (0..self.trial_out.len()).map(|p| o.owner(p / ngp)).collect();
            o.ranks().replicate_points(&owner, &mut self.trial_out, &mut self.trial_state, self.state_stride / ngp);
        }
        for (p, (new, old)) in self.trial_out.iter().zip(self.committed_out.iter()).enumerate() {
            let d_f = new.deformation_gradient - old.deformation_gradient;
            self.work[p] += 0.5 * (new.stress + old.stress).dot(&d_f) * self.geometry.weight(p);
            self.f_prev[p] = new.deformation_gradient;
        }
        self.committed_out.copy_from_slice(&self.trial_out);
        self.committed_state.copy_from_slice(&self.trial_state);
    }

    /// `½ vᵀ M v` over the elements, summed in element order (a parallel sum would depend on
    /// how the work was split: not reproducible in the last digit from run to run).
    fn kinetic_energy(&self, v: &[f64]) -> f64 {
        let nn = self.element.num_nodes();
        let dim = self.dim();
        (0..self.mesh.num_cells())
            .map(|e| {
                let cell = self.mesh.cell(e);
                let me = &self.mass[e * nn * nn..(e + 1) * nn * nn];
                let mut k = 0.0;
                for a in 0..nn {
                    for b in 0..nn {
                        let (ga, gb) = (self.node_ids[cell[a]] * dim, self.node_ids[cell[b]] * dim);
                        for i in 0..dim {
                            k += 0.5 * me[a * nn + b] * v[ga + i] * v[gb + i];
                        }
                    }
                }
                k
            })
            .sum()
    }

    fn strain_energy(&self) -> f64 {
        self.work.iter().sum()
    }

    /// `Σ_e Σ_ab M_ab v_b`: the element mass matrices (consistent or lumped) applied to the
    /// nodal velocities and summed, `∫ ρ v dV`.
    fn momentum(&self, name: Option<&str>, v: &[f64]) -> Option<[f64; 3]> {
        if name.is_some_and(|n| n != self.name) {
            return None;
        }
        let nn = self.element.num_nodes();
        let dim = self.dim();
        let mut p = [0.0; 3];
        for e in 0..self.mesh.num_cells() {
            let cell = self.mesh.cell(e);
            let me = &self.mass[e * nn * nn..(e + 1) * nn * nn];
            for a in 0..nn {
                for b in 0..nn {
                    let gb = self.node_ids[cell[b]] * dim;
                    for (i, pi) in p.iter_mut().enumerate().take(dim) {
                        *pi += me[a * nn + b] * v[gb + i];
                    }
                }
            }
        }
        Some(p)
    }

    fn boundary_facets(&self) -> Vec<Vec<usize>> {
        self.mesh.boundary_facets().into_iter().map(|f| f.into_iter().map(|a| self.node_ids[a]).collect()).collect()
    }

    fn save_state(&self) -> Vec<u8> {
        let state = FemState {
            law_history: self.committed_state.clone(),
            points: self.committed_out.clone(),
            previous_deformation_gradient: self.f_prev.clone(),
            work: self.work.clone(),
        };
        bincode::serialize(&state).expect("an FEM domain's state encodes")
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let state: FemState = bincode::deserialize(bytes).map_err(|e| format!("domain '{}': {e}", self.name))?;
        if state.law_history.len() != self.committed_state.len()
            || state.points.len() != self.committed_out.len()
            || state.previous_deformation_gradient.len() != self.f_prev.len()
            || state.work.len() != self.work.len()
        {
            return Err(format!("domain '{}': the saved state is of another mesh or law", self.name));
        }
        self.trial_state.clone_from(&state.law_history);
        self.committed_state = state.law_history;
        self.trial_out.clone_from(&state.points);
        self.committed_out = state.points;
        self.f_prev = state.previous_deformation_gradient;
        self.work = state.work;
        Ok(())
    }

    fn outputs(&self, committed: &NodalState, _with_grid: bool) -> Vec<NamedOutput> {
        vec![NamedOutput { name: self.name.clone(), output: self.mesh_output(committed) }]
    }
}

impl FemDomain {
    /// The mesh in its reference configuration with nodal `displacement`, `velocity`,
    /// `acceleration` and the cell averages of the Gauss points' stress, strain and state.
    fn mesh_output(&self, committed: &NodalState) -> DomainOutput {
        let dim = self.dim();
        let nodal = |src: &[f64]| -> Vec<f64> {
            self.node_ids
                .iter()
                .flat_map(|&g| (0..3).map(move |i| if i < dim { src[g * dim + i] } else { 0.0 }))
                .collect()
        };
        let ngp = self.points_per_element;
        let ne = self.mesh.num_cells();
        let names = self.law.state_variables();
        let state_len = self.law.state_len();
        let mut stress = Vec::with_capacity(ne * 9);
        let mut strain = Vec::with_capacity(ne * 9);
        let mut von_mises = Vec::with_capacity(ne);
        let mut states = vec![0.0; ne * names.len()];
        let mut tmp = vec![0.0; names.len()];
        for e in 0..ne {
            let mut s = Matrix3::zeros();
            let mut g = Matrix3::zeros();
            for q in 0..ngp {
                let p = &self.committed_out[e * ngp + q];
                s += p.cauchy / ngp as f64;
                let f = p.deformation_gradient;
                g += 0.5 * (f.transpose() * f - Matrix3::identity()) / ngp as f64;
                let start = e * self.state_stride + q * state_len;
                self.law.state_output(&self.committed_state[start..start + state_len], &mut tmp);
                for (k, v) in tmp.iter().enumerate() {
                    states[e * names.len() + k] += v / ngp as f64;
                }
            }
            stress.extend(s.transpose().iter());
            strain.extend(g.transpose().iter());
            von_mises.push(crate::von_mises(&s));
        }
        let mut cell_fields = vec![
            Field { name: "cauchy_stress".into(), components: 9, values: stress },
            Field { name: "green_lagrange_strain".into(), components: 9, values: strain },
            Field { name: "von_mises_stress".into(), components: 1, values: von_mises },
        ];
        for (k, n) in names.iter().enumerate() {
            cell_fields.push(Field {
                name: n.to_string(),
                components: 1,
                values: (0..ne).map(|e| states[e * names.len() + k]).collect(),
            });
        }
        DomainOutput {
            points: self.mesh.coords.clone(),
            cells: Some((self.element, self.mesh.connectivity.clone())),
            point_fields: {
                let mut fields = vec![
                    Field { name: "displacement".into(), components: 3, values: nodal(&committed.u) },
                    Field { name: "velocity".into(), components: 3, values: nodal(&committed.v) },
                    Field { name: "acceleration".into(), components: 3, values: nodal(&committed.a) },
                ];
                if let Some(p) = &self.pressure_dofs {
                    fields.push(Field {
                        name: "pressure".into(),
                        components: 1,
                        values: p.iter().map(|&d| committed.u[d]).collect(),
                    });
                }
                fields
            },
            cell_fields,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_laws::neo_hookean::NeoHookean;

    /// An inverted (clockwise) element is rejected with its index, never a panic.
    #[test]
    fn inverted_element_is_reported_by_index() {
        let mut mesh = Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [2, 1], ElementType::Quad4);
        mesh.connectivity[4..8].reverse();
        let n = mesh.coords.len();
        let law = Arc::new(NeoHookean::new(1000.0, 1e6, 0.3));
        let err = FemDomain::new("d", mesh, (0..n).collect(), Formulation::PlaneStrain, 1.0, law, false).err().unwrap();
        println!("{err}");
        assert_eq!(err.element, 1);
        assert!(err.message.contains("inverted"));
    }
}
