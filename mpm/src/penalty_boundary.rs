//! Non-conforming Dirichlet boundaries by penalty augmentation: a rigid wall anywhere in the
//! background grid, cutting through its cells (Chandra, Singer, Teschemacher, Wüchner &
//! Larese 2021, *Nonconforming Dirichlet boundary conditions in implicit material point
//! method by means of penalty augmentation*, Acta Geotechnica 16, 2315–2335,
//! doi:10.1007/s11440-020-01123-3; Kratos' `MPMParticlePenaltyDirichletCondition`).
//!
//! The wall is a set of *boundary particles* `b` at positions `x_b` (fixed, or moving with
//! the wall), each carrying the measure `w_b` of the wall it represents (length × thickness
//! in plane problems, length × 2πr in axisymmetry) and the unit normal `n_b` that points
//! from the wall into the body. The grid is reset every step, so the nodal unknowns of a
//! step are increments `Δu_I`; the grid's displacement at a boundary particle and its gap to
//! the wall's own displacement over the step `Δū` are
//!
//! $$ g_b = \sum_I N_I(x_b)\, \Delta u_I - \Delta\bar u . $$
//!
//! The penalty adds the potential `Π = ½ Σ_b β w_b g_bᵀ P_b g_b` with the penalty factor
//! `β` (N/m³) and the projection `P_b = I` (**no-slip**: the wall holds every component) or
//! `P_b = n_b ⊗ n_b` (**slip**: frictionless, only the normal component is held), so each
//! boundary particle adds to the residual `r = f_int − f_ext + M ã` and to the tangent of the
//! nodes `I, J` of the cell that holds it
//!
//! $$ r_I \mathrel{+}= \beta\, w_b\, N_I(x_b)\, P_b\, g_b, \qquad
//!    K_{IJ} \mathrel{+}= \beta\, w_b\, N_I(x_b)\, N_J(x_b)\, P_b $$
//!
//! (Chandra et al. 2021, eqs. 20–23, with Kratos' weighting by the condition's area), and
//! the wall exerts `f_b = −β w_b P_b g_b` on the body. Choices, as in Chandra et al.:
//!
//! - **Only where there is material.** A boundary particle acts only if every node of its
//!   cell carries projected mass (`m_I > 0`, summed over the bodies on the grid), i.e. its
//!   cell lies inside the support of the bodies' material points; elsewhere it would tie
//!   nodes that carry no equation of the body. The nodal masses come from the
//!   [`Projection`] handed to [`Domain::begin_step`], so a penalty boundary must come after
//!   the particle domains of its grid in the model's domain list.
//! - **Incremental gap.** The gap is measured over the step (the grid is reset), so a wall
//!   holding a body at rest admits a penetration of `f / (β w)` per step (1e-8 m for the
//!   benchmark), not a growing one: the material points move only by `Δu_p`.
//! - **Optional contact** (separable wall, Kratos' `CONTACT` flag): a boundary particle acts
//!   only while the grid moves into the wall, `n_b · g_b ≤ 0`, and releases a body that
//!   moves away. Off by default; the cylinder benchmarks run without it.
//! - **Initial acceleration.** In the solve for `a₀` (assembly with `stiffness == false`)
//!   the penalty matrix is kept, so `a₀` obeys the wall as `Δu` does later; without it a body
//!   resting on the wall would start with the free-fall acceleration into it, and the
//!   trapezoidal rule would carry the resulting `±a` alternation for the whole run.

use loam_fem::amplitude::Amplitude;
use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{AssemblyInput, Domain, DomainError, DomainOutput, Field, NodalState, Projection};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;

use crate::grid::Grid;

/// Which components of the grid's motion a penalty wall holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PenaltyKind {
    /// Every component (`P = I`): the body sticks to the wall (it may still roll).
    NoSlip,
    /// The normal component only (`P = n ⊗ n`): frictionless sliding along the wall.
    Slip,
}

/// Boundary particles of a wall: reference positions, measures and normals.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BoundaryParticles {
    /// Position at `t = 0` (m).
    pub position: Vec<[f64; 3]>,
    /// Measure of the wall each represents: length × thickness (plane), length × 2πr
    /// (axisymmetric), area (3D).
    pub weight: Vec<f64>,
    /// Unit normal pointing from the wall into the body.
    pub normal: Vec<[f64; 3]>,
}

impl BoundaryParticles {
    /// Particles along the polyline `vertices` (2D): each segment of length `L` is split
    /// into `⌈L / spacing⌉` equal parts with a particle at the middle of each, weighted by the
    /// part's length times the formulation's measure factor (thickness or `2πr`). The normal
    /// is the segment's left normal: the body lies on the left of the polyline as it runs
    /// from its first vertex to its last.
    pub fn on_polyline(vertices: &[[f64; 2]], spacing: f64, formulation: Formulation, thickness: f64) -> Self {
        let mut p = Self::default();
        for w in vertices.windows(2) {
            let (a, b) = (w[0], w[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len = d[0].hypot(d[1]);
            if len <= 0.0 {
                continue;
            }
            let n = (len / spacing).ceil().max(1.0) as usize;
            let part = len / n as f64;
            let normal = [-d[1] / len, d[0] / len, 0.0];
            for k in 0..n {
                let s = (k as f64 + 0.5) / n as f64;
                let x = [a[0] + s * d[0], a[1] + s * d[1], 0.0];
                p.position.push(x);
                p.weight.push(part * formulation.measure_factor(thickness, x[0]));
                p.normal.push(normal);
            }
        }
        p
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
}

/// Parameters of a penalty wall.
#[derive(Debug, Clone, PartialEq)]
pub struct PenaltySettings {
    /// Penalty factor β (N/m³: force per wall measure per metre of gap). Chandra et al. use
    /// 1e13 for steel-like bodies (E = 200 MPa); β w_b should exceed the body's stiffness
    /// `E · thickness` by two to four orders of magnitude.
    pub penalty_factor: f64,
    /// No-slip or slip.
    pub kind: PenaltyKind,
    /// Act only while the grid moves into the wall (separable contact).
    pub contact: bool,
    /// Wall displacement (m) scaled by `amplitude(t)`: a moving wall (zero for a fixed one).
    pub displacement: [f64; 3],
    /// Time function of the wall displacement.
    pub amplitude: Amplitude,
}

/// A rigid wall enforced on a background grid by penalty-augmented boundary particles.
pub struct PenaltyBoundary {
    name: String,
    formulation: Formulation,
    thickness: f64,
    grid: Grid,
    node_ids: Vec<usize>,
    particles: BoundaryParticles,
    settings: PenaltySettings,
    /// Time `t_n` of the committed state.
    time: f64,
    /// Wall displacement at `t_n`.
    offset: [f64; 3],
    /// Cells with acting particles (ascending): the element blocks.
    cells: Vec<usize>,
    /// Particles of block `k`: `order[cell_ptr[k]..cell_ptr[k+1]]`.
    cell_ptr: Vec<usize>,
    order: Vec<usize>,
    /// Shape functions at each particle of `order`.
    shape: Vec<[f64; MAX_NODES]>,
    /// Force of the wall on the body at each particle (N), committed.
    force: Vec<[f64; 3]>,
    /// Whether each particle acted in the last converged step.
    acting: Vec<bool>,
}

impl PenaltyBoundary {
    /// A wall of `particles` on `grid`, whose local node `a` is global node `node_ids[a]`.
    pub fn new(
        name: &str,
        grid: Grid,
        node_ids: Vec<usize>,
        formulation: Formulation,
        thickness: f64,
        particles: BoundaryParticles,
        settings: PenaltySettings,
    ) -> Self {
        let n = particles.len();
        Self {
            name: name.to_string(),
            formulation,
            thickness,
            grid,
            node_ids,
            particles,
            settings,
            time: 0.0,
            offset: [0.0; 3],
            cells: Vec::new(),
            cell_ptr: vec![0],
            order: Vec::new(),
            shape: Vec::new(),
            force: vec![[0.0; 3]; n],
            acting: vec![false; n],
        }
    }

    /// Sum of the forces the wall exerts on the bodies (N) in the last converged step.
    pub fn total_force(&self) -> [f64; 3] {
        let mut f = [0.0; 3];
        for b in &self.force {
            for i in 0..3 {
                f[i] += b[i];
            }
        }
        f
    }

    /// Number of boundary particles that acted in the last converged step.
    pub fn acting_particles(&self) -> usize {
        self.acting.iter().filter(|a| **a).count()
    }

    fn dim(&self) -> usize {
        self.grid.mesh.element.dim()
    }

    fn wall_displacement(&self, t: f64) -> [f64; 3] {
        let f = self.settings.amplitude.at(t);
        self.settings.displacement.map(|d| d * f)
    }

    /// `(β w_b, g_b, whether it acts)` of particle `k` of `order` in block `cell` at `input`.
    fn gap(&self, k: usize, cell: usize, input: &AssemblyInput<'_>) -> (f64, [f64; 3], bool) {
        let b = self.order[k];
        let dim = self.dim();
        let wall = self.wall_displacement(input.time);
        let mut g = [0.0; 3];
        for i in 0..dim {
            g[i] = -(wall[i] - self.offset[i]);
        }
        for (a, &node) in self.grid.mesh.cell(cell).iter().enumerate() {
            let dof = self.node_ids[node] * dim;
            for i in 0..dim {
                g[i] += self.shape[k][a] * (input.state.u[dof + i] - input.committed.u[dof + i]);
            }
        }
        let n = self.particles.normal[b];
        let gn: f64 = (0..dim).map(|i| n[i] * g[i]).sum();
        let acts = !self.settings.contact || gn <= 0.0;
        if self.settings.kind == PenaltyKind::Slip {
            for i in 0..dim {
                g[i] = n[i] * gn;
            }
        }
        (self.settings.penalty_factor * self.particles.weight[b], g, acts)
    }
}

impl Domain for PenaltyBoundary {
    fn name(&self) -> &str {
        &self.name
    }

    fn formulation(&self) -> Formulation {
        self.formulation
    }

    fn thickness(&self) -> f64 {
        self.thickness
    }

    /// Locates the boundary particles at the wall's position at `t_n` and keeps those whose
    /// cell has projected mass on every node; their cells are the element blocks.
    fn begin_step(&mut self, projection: &mut Projection) -> bool {
        self.offset = self.wall_displacement(self.time);
        let element = self.grid.mesh.element;
        let nn = element.num_nodes();
        let mut found: Vec<(usize, usize, [f64; MAX_NODES])> = Vec::new();
        for (b, x0) in self.particles.position.iter().enumerate() {
            let x = [x0[0] + self.offset[0], x0[1] + self.offset[1], x0[2] + self.offset[2]];
            let Some((cell, xi)) = self.grid.locate(&x) else { continue };
            let with_mass = self.grid.mesh.cell(cell).iter().all(|&a| projection.mass[self.node_ids[a]] > 0.0);
            if with_mass {
                let mut n = [0.0; MAX_NODES];
                element.shape_functions(&xi, &mut n[..nn]);
                found.push((cell, b, n));
            }
        }
        found.sort_unstable_by_key(|f| (f.0, f.1));
        let mut cells = Vec::new();
        self.cell_ptr.clear();
        self.cell_ptr.push(0);
        self.order.clear();
        self.shape.clear();
        for (k, (cell, b, n)) in found.into_iter().enumerate() {
            if cells.last() != Some(&cell) {
                if k > 0 {
                    self.cell_ptr.push(k);
                }
                cells.push(cell);
            }
            self.order.push(b);
            self.shape.push(n);
        }
        if !cells.is_empty() {
            self.cell_ptr.push(self.order.len());
        }
        let changed = cells != self.cells;
        self.cells = cells;
        changed
    }

    fn blocks(&self, layout: &mut BlockLayout) {
        let dim = self.dim();
        for &c in &self.cells {
            layout.push(self.grid.mesh.cell(c).iter().flat_map(|&a| (0..dim).map(move |i| self.node_ids[a] * dim + i)));
        }
    }

    /// `r_I = Σ_b β w_b N_I P_b g_b` and `K_IJ = Σ_b β w_b N_I N_J P_b` over the acting
    /// particles of each block.
    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError> {
        let nn = self.grid.mesh.element.num_nodes();
        let dim = self.dim();
        let nd = nn * dim;
        for (blk, &cell) in self.cells.iter().enumerate() {
            let fv = &mut vectors[blk * nd..(blk + 1) * nd];
            fv.fill(0.0);
            let km = &mut matrices[blk * nd * nd..(blk + 1) * nd * nd];
            if input.with_tangent {
                km.fill(0.0);
            }
            for k in self.cell_ptr[blk]..self.cell_ptr[blk + 1] {
                let (bw, g, acts) = self.gap(k, cell, input);
                if !acts {
                    continue;
                }
                let n = &self.shape[k];
                let normal = self.particles.normal[self.order[k]];
                let p = |i: usize, j: usize| match self.settings.kind {
                    PenaltyKind::NoSlip => f64::from(u8::from(i == j)),
                    PenaltyKind::Slip => normal[i] * normal[j],
                };
                for a in 0..nn {
                    for i in 0..dim {
                        fv[a * dim + i] += bw * n[a] * g[i];
                    }
                }
                if input.with_tangent {
                    for a in 0..nn {
                        for c in 0..nn {
                            let s = bw * n[a] * n[c];
                            for i in 0..dim {
                                for j in 0..dim {
                                    km[(a * dim + i) * nd + c * dim + j] += s * p(i, j);
                                }
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Records the force of the wall on the body at each particle, `f_b = −β w_b P_b g_b`,
    /// and moves the wall's clock to `t_{n+1}`.
    fn commit(&mut self, input: &AssemblyInput<'_>) {
        self.force.iter_mut().for_each(|f| *f = [0.0; 3]);
        self.acting.iter_mut().for_each(|a| *a = false);
        for (blk, &cell) in self.cells.iter().enumerate() {
            for k in self.cell_ptr[blk]..self.cell_ptr[blk + 1] {
                let (bw, g, acts) = self.gap(k, cell, input);
                let b = self.order[k];
                if acts {
                    self.force[b] = g.map(|v| -bw * v);
                    self.acting[b] = true;
                }
            }
        }
        self.time = input.time;
    }

    fn kinetic_energy(&self, _v: &[f64]) -> f64 {
        0.0
    }

    fn strain_energy(&self) -> f64 {
        0.0
    }

    fn boundary_facets(&self) -> Vec<Vec<usize>> {
        Vec::new()
    }

    /// The boundary particles at the wall's current position with `force` (of the wall on
    /// the body, N), `normal` and `active` (1 where the particle acted in the last step).
    fn output(&self, _committed: &NodalState) -> DomainOutput {
        let offset = self.wall_displacement(self.time);
        let points = self.particles.position.iter().map(|x| [x[0] + offset[0], x[1] + offset[1], x[2] + offset[2]]);
        DomainOutput {
            points: points.collect(),
            cells: None,
            point_fields: vec![
                Field { name: "force".into(), components: 3, values: self.force.iter().flatten().copied().collect() },
                Field {
                    name: "normal".into(),
                    components: 3,
                    values: self.particles.normal.iter().flatten().copied().collect(),
                },
                Field {
                    name: "active".into(),
                    components: 1,
                    values: self.acting.iter().map(|&a| f64::from(u8::from(a))).collect(),
                },
            ],
            cell_fields: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use loam_fem::element::ElementType;

    use super::*;

    /// A 3 × 2 quad grid of unit cells, a wall along a slanted segment through it, and a
    /// projection with mass on every node but the top-right one.
    fn setup(kind: PenaltyKind, contact: bool) -> (PenaltyBoundary, Projection) {
        let grid = Grid::new([0.0; 3], [3.0, 2.0, 0.0], [3, 2, 1], ElementType::Quad4);
        let nodes = grid.mesh.coords.len();
        let particles = BoundaryParticles::on_polyline(&[[0.1, 0.3], [2.9, 1.7]], 0.25, Formulation::PlaneStrain, 2.0);
        let settings = PenaltySettings {
            penalty_factor: 1e3,
            kind,
            contact,
            displacement: [0.0; 3],
            amplitude: Amplitude::default(),
        };
        let wall = PenaltyBoundary::new(
            "wall",
            grid,
            (0..nodes).collect(),
            Formulation::PlaneStrain,
            2.0,
            particles,
            settings,
        );
        let mut projection = Projection::new(nodes, 2);
        projection.mass.iter_mut().for_each(|m| *m = 1.0);
        projection.mass[nodes - 1] = 0.0;
        (wall, projection)
    }

    fn input<'a>(state: &'a NodalState, committed: &'a NodalState) -> AssemblyInput<'a> {
        AssemblyInput {
            state,
            committed,
            inertial_acceleration: None,
            mass_coefficient: 0.0,
            gravity: [0.0; 3],
            time_step: 1.0,
            gamma: 0.5,
            time: 1.0,
            with_tangent: true,
            stiffness: true,
        }
    }

    #[test]
    fn polyline_particles_carry_the_wall_measure() {
        let p = BoundaryParticles::on_polyline(&[[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]], 0.3, Formulation::PlaneStrain, 2.0);
        assert_eq!(p.len(), 17 + 4);
        let total: f64 = p.weight.iter().sum();
        assert!((total - 2.0 * 6.0).abs() < 1e-12, "{total}");
        assert!((p.normal[0][0] + 0.8).abs() < 1e-15 && (p.normal[0][1] - 0.6).abs() < 1e-15);
    }

    #[test]
    fn particles_act_only_in_cells_with_mass_on_every_node() {
        let (mut wall, mut projection) = setup(PenaltyKind::NoSlip, false);
        assert!(wall.begin_step(&mut projection));
        // the segment crosses cells 0, 1, 4 and 5; cell 5 has the massless top-right node
        assert_eq!(wall.cells, vec![0, 1, 4]);
        assert!(!wall.begin_step(&mut projection), "same blocks: the pattern is kept");
    }

    /// The penalty tangent is the derivative of the penalty residual (central differences),
    /// no-slip, slip and contact (away from its switch).
    #[test]
    fn tangent_matches_finite_differences_of_the_residual() {
        for (kind, contact) in [(PenaltyKind::NoSlip, false), (PenaltyKind::Slip, false), (PenaltyKind::Slip, true)] {
            let (mut wall, mut projection) = setup(kind, contact);
            wall.begin_step(&mut projection);
            let mut layout = BlockLayout::default();
            wall.blocks(&mut layout);
            let ndof = 2 * wall.grid.mesh.coords.len();
            let committed = NodalState::zeros(ndof);
            let mut state = NodalState::zeros(ndof);
            for (k, u) in state.u.iter_mut().enumerate() {
                // into the wall (−n = (0.447, −0.894)) plus a pseudo-random part
                *u = 0.01 * (if k % 2 == 0 { 0.447 } else { -0.894 }) + 1e-3 * ((k * 7919) % 13) as f64 / 13.0;
            }
            let mut mats = vec![0.0; layout.matrix_len()];
            let mut vecs = vec![0.0; layout.vector_len()];
            wall.assemble(&input(&state, &committed), &mut mats, &mut vecs).unwrap();
            let scale = mats.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(scale > 0.0);
            let h = 1e-6;
            for blk in 0..layout.num_blocks() {
                let dofs = &layout.dofs[layout.dof_ptr[blk]..layout.dof_ptr[blk + 1]];
                let nd = dofs.len();
                for (j, &gj) in dofs.iter().enumerate() {
                    let mut r = [vec![0.0; layout.vector_len()], vec![0.0; layout.vector_len()]];
                    for (s, sign) in [1.0, -1.0].into_iter().enumerate() {
                        let mut st = state.clone();
                        st.u[gj] += sign * h;
                        let mut m = vec![0.0; layout.matrix_len()];
                        wall.assemble(&input(&st, &committed), &mut m, &mut r[s]).unwrap();
                    }
                    for i in 0..nd {
                        let fd = (r[0][layout.dof_ptr[blk] + i] - r[1][layout.dof_ptr[blk] + i]) / (2.0 * h);
                        let k = mats[layout.matrix_offset[blk] + i * nd + j];
                        assert!((fd - k).abs() <= 1e-7 * scale, "{kind:?} contact {contact}: K {k} vs FD {fd}");
                    }
                }
            }
        }
    }

    /// Slip holds only the normal component; contact releases a body moving away; the
    /// committed forces sum to the wall's total force.
    #[test]
    fn slip_holds_the_normal_component_and_contact_releases() {
        for (kind, contact, sign) in [
            (PenaltyKind::Slip, false, 1.0),
            (PenaltyKind::NoSlip, false, 1.0),
            (PenaltyKind::Slip, true, 1.0),
            (PenaltyKind::Slip, true, -1.0),
        ] {
            let (mut wall, mut projection) = setup(kind, contact);
            wall.begin_step(&mut projection);
            let ndof = 2 * wall.grid.mesh.coords.len();
            let committed = NodalState::zeros(ndof);
            let mut state = NodalState::zeros(ndof);
            let n = wall.particles.normal[0];
            let t = [n[1], -n[0]];
            // uniform motion: tangential 1 cm, normal 1 mm into (sign 1) or away from the wall
            for node in 0..ndof / 2 {
                for i in 0..2 {
                    state.u[2 * node + i] = 0.01 * t[i] - sign * 0.001 * n[i];
                }
            }
            wall.commit(&input(&state, &committed));
            let f = wall.total_force();
            let measure: f64 = (0..wall.order.len()).map(|k| wall.particles.weight[wall.order[k]]).sum();
            let (fn_, ft) = (f[0] * n[0] + f[1] * n[1], f[0] * t[0] + f[1] * t[1]);
            if contact && sign < 0.0 {
                assert_eq!((fn_, ft, wall.acting_particles()), (0.0, 0.0, 0));
                continue;
            }
            assert!((fn_ - 1e3 * measure * 0.001).abs() < 1e-9 * fn_, "{kind:?}: normal force {fn_}");
            let expected_t = if kind == PenaltyKind::NoSlip { -1e3 * measure * 0.01 } else { 0.0 };
            assert!((ft - expected_t).abs() < 1e-9 * fn_.abs().max(1.0), "{kind:?}: tangential force {ft}");
        }
    }
}
