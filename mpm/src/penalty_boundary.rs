//! Non-conforming rigid walls on a background grid, enforced by penalty: a wall anywhere in
//! the grid, cutting through its cells.
//!
//! # Dirichlet form (Chandra et al. 2021)
//!
//! Chandra, Singer, Teschemacher, Wüchner & Larese (2021), *Nonconforming Dirichlet boundary
//! conditions in implicit material point method by means of penalty augmentation*, Acta
//! Geotechnica 16, 2315–2335, doi:10.1007/s11440-020-01123-3; Kratos'
//! `MPMParticlePenaltyDirichletCondition`. The wall is a set of *boundary particles* `b` at
//! positions `x_b` (fixed, or moving with the wall), each carrying the measure `w_b` of the
//! wall it represents (length × thickness in plane problems, length × 2πr in axisymmetry) and
//! the unit normal `n_b` that points from the wall into the body. The grid is reset every
//! step, so the nodal unknowns of a step are increments `Δu_I`; the grid's displacement at a
//! boundary particle and its gap to the wall's own displacement over the step `Δū` are
//!
//! $$ g_b = \sum_I N_I(x_b)\, \Delta u_I - \Delta\bar u . $$
//!
//! The penalty adds the potential `Π = ½ Σ_b β w_b g_bᵀ P_b g_b` with the penalty factor
//! `β` (N/m³) and the projection `P_b = I` (**no-slip**: every component held) or
//! `P_b = n_b ⊗ n_b` (**slip**: frictionless, only the normal component held), so each
//! boundary particle adds to the residual `r = f_int − f_ext + M ã` and to the tangent of the
//! nodes `I, J` of the cell that holds it
//!
//! $$ r_I \mathrel{+}= \beta\, w_b\, N_I(x_b)\, P_b\, g_b, \qquad
//!    K_{IJ} \mathrel{+}= \beta\, w_b\, N_I(x_b)\, N_J(x_b)\, P_b $$
//!
//! (Chandra et al. 2021, with Kratos' weighting by the condition's area), and the wall
//! exerts `f_b = −β w_b P_b g_b` on the body. A boundary particle acts only **where there is
//! material**: if every node of its cell carries projected mass (`m_I > 0`, summed over the
//! bodies on the grid), i.e. its cell lies inside the support of the bodies' material
//! points; elsewhere it would tie nodes that carry no equation of the body. This form is a
//! bilateral *Dirichlet* condition: it holds a body to the wall in tension as in
//! compression (a clamp, or a slip support that cuts the grid). Benchmark 6 with slip: the
//! cylinder slides ½ g sin α t² to 5e-7.
//!
//! # The contact form is a rigid structure
//!
//! A wall in the contact form (`"contact": true`: unilateral, the body may leave it, roll on
//! it or slide on it with Coulomb friction) is not built here: the model builder writes it
//! as a rigid structure held in place or moved by the wall's motion, with a non-conforming
//! contact on its face (`src/model_builder/walls.rs`, `loam_coupling::interface_points`,
//! `loam_fem::rigid_body`), so that walls and structures share one contact code (issue 25).
//! This form, on boundary particles, is the Dirichlet one alone: a bilateral condition. (A
//! no-slip Dirichlet wall stops a rolling body: its boundary particles hold the grid across
//! the band of cut cells under it, which a rotation about the contact point moves, as in
//! Kratos 10.4.4; measured 3.8 % and 0.9 % of the rolling distance after 0.1 s.)
//!
//! The wall keeps its penalty matrix in the solve for the initial acceleration
//! (assembly with `stiffness == false`), so `a₀` obeys the wall as `Δu` does later: a body
//! pressed on a wall does not start with the free-fall acceleration into it (which the
//! trapezoidal rule would carry as a `±a` alternation for the whole run). A wall is a
//! condition of its grid: the MPM domain that owns the grid places the wall's points after
//! projecting its bodies (nodal masses, material points) and assembles its blocks after the
//! bodies' cells.

use loam_fem::amplitude::Amplitude;
use loam_fem::assembly::BlockLayout;
use loam_fem::domain::{AssemblyInput, DomainOutput, Field};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;

use crate::grid::Grid;

/// A grid with the global ids of its nodes: where a wall's points lie and which equations
/// they touch.
#[derive(Clone, Copy)]
pub struct GridNodes<'a> {
    /// The grid (current configuration).
    pub grid: &'a Grid,
    /// Global node id of each grid node.
    pub node_ids: &'a [usize],
}

/// Which components of the motion a penalty wall holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PenaltyKind {
    /// Every component (`P = I`): the body is held to the wall.
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
    /// into `⌈L / spacing⌉` equal parts (one if `spacing` is not positive) with a particle at the middle of each, weighted by the
    /// part's length times the formulation's measure factor (thickness or `2πr`). The normal
    /// is the segment's left normal: the body lies on the left of the polyline as it runs
    /// from its first vertex to its last.
    pub fn on_polyline(vertices: &[[f64; 2]], spacing: f64, formulation: Formulation, thickness: f64) -> Self {
        let mut p = Self::default();
        for Segment { start: a, direction: d, length, normal } in segments(vertices) {
            let n = if spacing > 0.0 { (length / spacing).ceil().max(1.0) as usize } else { 1 };
            let part = length / n as f64;
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

/// A straight piece of a wall.
#[derive(Debug, Clone, Copy)]
struct Segment {
    /// First point.
    start: [f64; 2],
    /// From the first point to the second.
    direction: [f64; 2],
    /// Length.
    length: f64,
    /// Left unit normal (into the body).
    normal: [f64; 3],
}

/// The segments of a 2D polyline that have a positive length.
fn segments(vertices: &[[f64; 2]]) -> Vec<Segment> {
    vertices
        .windows(2)
        .filter_map(|w| {
            let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
            let length = d[0].hypot(d[1]);
            (length > 0.0).then(|| Segment {
                start: w[0],
                direction: d,
                length,
                normal: [-d[1] / length, d[0] / length, 0.0],
            })
        })
        .collect()
}

/// Parameters of a penalty wall.
#[derive(Debug, Clone, PartialEq)]
pub struct PenaltySettings {
    /// Penalty factor β (N/m³: force per wall measure per metre of gap). Chandra et al. use
    /// 1e13 for steel-like bodies (E = 200 MPa); β w should exceed the body's stiffness
    /// `E · thickness` by two to four orders of magnitude.
    pub penalty_factor: f64,
    /// No-slip or slip.
    pub kind: PenaltyKind,
    /// Wall displacement (m) scaled by `amplitude(t)`: a moving wall (zero for a fixed one).
    pub displacement: [f64; 3],
    /// Time function of the wall displacement.
    pub amplitude: Amplitude,
}

/// One penalty point of a step: a boundary particle where the material is.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PenaltyPoint {
    /// Grid support that holds it (its cell on the linear basis).
    cell: usize,
    /// Shape functions of the support's nodes at the point.
    shape: [f64; MAX_NODES],
    /// Measure `w` (m² in plane problems).
    weight: f64,
    /// Unit normal from the wall into the body.
    normal: [f64; 3],
    /// Position at the start of the step.
    position: [f64; 3],
}

/// What a wall carries from step to step (its penalty points are placed anew each step).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct WallState {
    /// Time of the committed state.
    pub time: f64,
    /// Force of the wall on the body at each point of the last step.
    pub force: Vec<[f64; 3]>,
    /// Whether each point acted.
    pub acting: Vec<bool>,
}

/// A rigid wall enforced on a background grid by penalty (see the module doc).
pub struct PenaltyBoundary {
    name: String,
    formulation: Formulation,
    thickness: f64,
    /// Boundary particles.
    particles: BoundaryParticles,
    settings: PenaltySettings,
    /// Time `t_n` of the committed state.
    time: f64,
    /// Wall displacement at `t_n`.
    offset: [f64; 3],
    /// Penalty points of the step, sorted by cell.
    points: Vec<PenaltyPoint>,
    /// Cells holding penalty points (ascending): the element blocks.
    cells: Vec<usize>,
    /// Points of block `k`: `points[cell_ptr[k]..cell_ptr[k+1]]`.
    cell_ptr: Vec<usize>,
    /// Force of the wall on the body at each point (N) and whether it acted, committed.
    force: Vec<[f64; 3]>,
    acting: Vec<bool>,
}

impl PenaltyBoundary {
    /// A wall along the 2D polyline `vertices` (the body on its left), its boundary particles
    /// `spacing` apart ([`BoundaryParticles::on_polyline`]).
    pub fn new(
        name: &str,
        formulation: Formulation,
        thickness: f64,
        vertices: Vec<[f64; 2]>,
        spacing: f64,
        settings: PenaltySettings,
    ) -> Self {
        let particles = BoundaryParticles::on_polyline(&vertices, spacing, formulation, thickness);
        Self {
            name: name.to_string(),
            formulation,
            thickness,
            particles,
            settings,
            time: 0.0,
            offset: [0.0; 3],
            points: Vec::new(),
            cells: Vec::new(),
            cell_ptr: vec![0],
            force: Vec::new(),
            acting: Vec::new(),
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

    /// Number of penalty points that acted in the last converged step.
    pub fn acting_points(&self) -> usize {
        self.acting.iter().filter(|a| **a).count()
    }

    /// The committed state: the wall's clock and the forces of its points in the last step.
    pub fn state(&self) -> WallState {
        WallState { time: self.time, force: self.force.clone(), acting: self.acting.clone() }
    }

    /// Restores a state of [`PenaltyBoundary::state`].
    pub fn restore(&mut self, state: WallState) {
        self.time = state.time;
        self.force = state.force;
        self.acting = state.acting;
    }

    /// The wall's name (its output file and its `wall_force` monitor).
    pub fn name(&self) -> &str {
        &self.name
    }

    fn wall_displacement(&self, t: f64) -> [f64; 3] {
        let f = self.settings.amplitude.at(t);
        self.settings.displacement.map(|d| d * f)
    }

    /// The point at `x` if every node its functions reach carries projected mass (`mass` per
    /// grid node): on the linear basis every node of its cell, on a smooth one every node of
    /// its support whose function is not zero there (the functions of a point, without a
    /// GIMP domain: the field's value at `x`).
    fn place(&self, grid: &Grid, x: [f64; 3], weight: f64, normal: [f64; 3], mass: &[f64]) -> Option<PenaltyPoint> {
        let (cell, g) = grid.point_functions(&x, [0.0; 3], self.formulation, self.thickness)?;
        if !grid.support(cell).iter().zip(&g.shape).all(|(&a, &n)| n == 0.0 || mass[a] > 0.0) {
            return None;
        }
        Some(PenaltyPoint { cell, shape: g.shape, weight, normal, position: x })
    }

    /// Penalty vector `v` (force on the body `−β w v`) of point `k` at `input`, its
    /// derivative `P = ∂v/∂g` with respect to the point's displacement (the tangent is
    /// `β w N_I N_J P`), and whether the point acts.
    fn penalty_vector(
        &self,
        at: GridNodes<'_>,
        k: usize,
        input: &AssemblyInput<'_>,
    ) -> ([f64; 3], [[f64; 3]; 3], bool) {
        let p = &self.points[k];
        let dim = at.grid.mesh.element.dim();
        let wall = self.wall_displacement(input.time);
        let mut g = [0.0; 3];
        for i in 0..dim {
            g[i] = -(wall[i] - self.offset[i]);
        }
        for (a, &node) in at.grid.support(p.cell).iter().enumerate() {
            let dof = at.node_ids[node] * dim;
            for i in 0..dim {
                g[i] += p.shape[a] * (input.state.u[dof + i] - input.committed.u[dof + i]);
            }
        }
        let n = p.normal;
        let gn: f64 = (0..dim).map(|i| n[i] * g[i]).sum();
        let mut v = [0.0; 3];
        let mut dv = [[0.0; 3]; 3];
        for i in 0..dim {
            v[i] += gn * n[i];
            for j in 0..dim {
                dv[i][j] += n[i] * n[j];
            }
        }
        if self.settings.kind == PenaltyKind::NoSlip {
            for i in 0..dim {
                v[i] += g[i] - gn * n[i];
                for j in 0..dim {
                    dv[i][j] += f64::from(u8::from(i == j)) - n[i] * n[j];
                }
            }
        }
        (v, dv, true)
    }
}

impl PenaltyBoundary {
    /// Places the penalty points at the wall's position at `t_n`: the boundary particles,
    /// each kept only where its functions reach projected mass alone (`mass` per grid node);
    /// their supports (cells on the linear basis) are the element blocks. Returns whether the
    /// blocks changed.
    pub fn begin_step(&mut self, grid: &Grid, mass: &[f64]) -> bool {
        self.offset = self.wall_displacement(self.time);
        let o = self.offset;
        let mut points = Vec::new();
        for b in 0..self.particles.len() {
            let x0 = self.particles.position[b];
            let x = [x0[0] + o[0], x0[1] + o[1], x0[2] + o[2]];
            let (w, n) = (self.particles.weight[b], self.particles.normal[b]);
            points.extend(self.place(grid, x, w, n, mass));
        }
        // by cell, then by position (deterministic whatever the order of the projection)
        points.sort_by(|a, b| {
            a.cell
                .cmp(&b.cell)
                .then(a.position[0].total_cmp(&b.position[0]))
                .then(a.position[1].total_cmp(&b.position[1]))
        });
        let mut cells: Vec<usize> = Vec::new();
        self.cell_ptr.clear();
        for (k, p) in points.iter().enumerate() {
            if cells.last() != Some(&p.cell) {
                cells.push(p.cell);
                self.cell_ptr.push(k);
            }
        }
        self.cell_ptr.push(points.len());
        self.points = points;
        let changed = cells != self.cells;
        self.cells = cells;
        changed
    }

    /// Appends the wall's blocks (the supports holding its points) to `layout`.
    pub fn blocks(&self, at: GridNodes<'_>, layout: &mut BlockLayout) {
        let dim = at.grid.mesh.element.dim();
        for &c in &self.cells {
            layout.push(at.grid.support(c).iter().flat_map(|&a| (0..dim).map(move |i| at.node_ids[a] * dim + i)));
        }
    }

    /// Length of the wall's part of the element buffers: matrices, vectors.
    pub fn buffer_lengths(&self, grid: &Grid) -> (usize, usize) {
        let nd = grid.support_len() * grid.mesh.element.dim();
        (self.cells.len() * nd * nd, self.cells.len() * nd)
    }

    /// `r_I = Σ β w N_I v` and `K_IJ = Σ β w N_I N_J P` over the acting points of each block
    /// (`v` and `P` of the form, see the module doc).
    pub fn assemble(&self, at: GridNodes<'_>, input: &AssemblyInput<'_>, matrices: &mut [f64], vectors: &mut [f64]) {
        let nn = at.grid.support_len();
        let dim = at.grid.mesh.element.dim();
        let nd = nn * dim;
        for blk in 0..self.cells.len() {
            let fv = &mut vectors[blk * nd..(blk + 1) * nd];
            fv.fill(0.0);
            let km = &mut matrices[blk * nd * nd..(blk + 1) * nd * nd];
            if input.with_tangent {
                km.fill(0.0);
            }
            for k in self.cell_ptr[blk]..self.cell_ptr[blk + 1] {
                let (v, dv, acts) = self.penalty_vector(at, k, input);
                if !acts {
                    continue;
                }
                let p = &self.points[k];
                let bw = self.settings.penalty_factor * p.weight;
                for a in 0..nn {
                    for i in 0..dim {
                        fv[a * dim + i] += bw * p.shape[a] * v[i];
                    }
                }
                if input.with_tangent {
                    for a in 0..nn {
                        for c in 0..nn {
                            let s = bw * p.shape[a] * p.shape[c];
                            for i in 0..dim {
                                for j in 0..dim {
                                    km[(a * dim + i) * nd + c * dim + j] += s * dv[i][j];
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// Records the force of the wall on the body at each point, `f = −β w v`, and moves the
    /// wall's clock to `t_{n+1}`.
    pub fn commit(&mut self, at: GridNodes<'_>, input: &AssemblyInput<'_>) {
        let (force, acting): (Vec<[f64; 3]>, Vec<bool>) = (0..self.points.len())
            .map(|k| {
                let (v, _, acts) = self.penalty_vector(at, k, input);
                let bw = self.settings.penalty_factor * self.points[k].weight;
                (v.map(|c| -bw * c), acts)
            })
            .unzip();
        self.force = force;
        self.acting = acting;
        self.time = input.time;
    }

    /// The penalty points of the last step (its boundary particles where the material is) with `force` (of the wall on the body, N), `normal` and `active` (1 where the
    /// point acted).
    pub fn output(&self) -> DomainOutput {
        let n = self.points.len().min(self.force.len());
        let pts = &self.points[..n];
        DomainOutput {
            points: pts.iter().map(|p| p.position).collect(),
            cells: None,
            point_fields: vec![
                Field {
                    name: "force".into(),
                    components: 3,
                    values: self.force[..n].iter().flatten().copied().collect(),
                },
                Field { name: "normal".into(), components: 3, values: pts.iter().flat_map(|p| p.normal).collect() },
                Field {
                    name: "active".into(),
                    components: 1,
                    values: self.acting[..n].iter().map(|&a| f64::from(u8::from(a))).collect(),
                },
            ],
            cell_fields: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use loam_fem::element::ElementType;

    use loam_fem::domain::NodalState;

    use super::*;

    const WALL: [[f64; 2]; 2] = [[0.1, 0.3], [2.9, 1.7]];

    /// A 3 × 2 quad grid of unit cells, a wall along a slanted segment through it, and a
    /// projection with mass on every node but the top-right one.
    struct Fixture {
        wall: PenaltyBoundary,
        grid: Grid,
        ids: Vec<usize>,
        mass: Vec<f64>,
    }

    impl Fixture {
        fn at(&self) -> GridNodes<'_> {
            GridNodes { grid: &self.grid, node_ids: &self.ids }
        }

        fn begin(&mut self) -> bool {
            self.wall.begin_step(&self.grid, &self.mass)
        }

        fn ndof(&self) -> usize {
            2 * self.grid.mesh.coords.len()
        }
    }

    fn setup(kind: PenaltyKind) -> Fixture {
        let grid = Grid::new([0.0; 3], [3.0, 2.0, 0.0], [3, 2, 1], ElementType::Quad4);
        let nodes = grid.mesh.coords.len();
        let settings =
            PenaltySettings { penalty_factor: 1e3, kind, displacement: [0.0; 3], amplitude: Amplitude::default() };
        let wall = PenaltyBoundary::new("wall", Formulation::PlaneStrain, 2.0, WALL.to_vec(), 0.25, settings);
        let mut mass = vec![1.0; nodes];
        mass[nodes - 1] = 0.0;
        Fixture { wall, grid, ids: (0..nodes).collect(), mass }
    }

    fn input<'a>(state: &'a NodalState, committed: &'a NodalState) -> AssemblyInput<'a> {
        AssemblyInput::static_tangent(state, committed)
    }

    #[test]
    fn polyline_particles_carry_the_wall_measure() {
        let p =
            BoundaryParticles::on_polyline(&[[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]], 0.3, Formulation::PlaneStrain, 2.0);
        assert_eq!(p.len(), 17 + 4);
        let total: f64 = p.weight.iter().sum();
        assert!((total - 2.0 * 6.0).abs() < 1e-12, "{total}");
        assert!((p.normal[0][0] + 0.8).abs() < 1e-15 && (p.normal[0][1] - 0.6).abs() < 1e-15);
    }

    #[test]
    fn penalty_points_lie_where_the_material_is() {
        let mut f = setup(PenaltyKind::NoSlip);
        assert!(f.begin());
        // the segment crosses cells 0, 1, 4 and 5; cell 5 has the massless top-right node
        assert_eq!(f.wall.cells, vec![0, 1, 4]);
        assert!(!f.begin(), "same blocks: the pattern is kept");
    }

    /// A uniform increment `u` of every node.
    fn uniform(ndof: usize, u: [f64; 2]) -> NodalState {
        let mut state = NodalState::zeros(ndof);
        for (k, v) in state.u.iter_mut().enumerate() {
            *v = u[k % 2];
        }
        state
    }

    /// The penalty tangent is the derivative of the penalty residual (central differences),
    /// no-slip and slip.
    #[test]
    fn tangent_matches_finite_differences_of_the_residual() {
        for kind in [PenaltyKind::NoSlip, PenaltyKind::Slip] {
            let mut f = setup(kind);
            f.begin();
            let mut layout = BlockLayout::default();
            f.wall.blocks(f.at(), &mut layout);
            let ndof = f.ndof();
            let committed = NodalState::zeros(ndof);
            let mut state = NodalState::zeros(ndof);
            for (k, u) in state.u.iter_mut().enumerate() {
                // 0.02 into the wall (−n = (0.447, −0.894)) plus a pseudo-random part
                *u = 0.02 * (if k % 2 == 0 { 0.447 } else { -0.894 }) + 1e-3 * ((k * 7919) % 13) as f64 / 13.0;
            }
            let mut mats = vec![0.0; layout.matrix_len()];
            let mut vecs = vec![0.0; layout.vector_len()];
            f.wall.assemble(f.at(), &input(&state, &committed), &mut mats, &mut vecs);
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
                        f.wall.assemble(f.at(), &input(&st, &committed), &mut m, &mut r[s]);
                    }
                    for i in 0..nd {
                        let fd = (r[0][layout.dof_ptr[blk] + i] - r[1][layout.dof_ptr[blk] + i]) / (2.0 * h);
                        let k = mats[layout.matrix_offset[blk] + i * nd + j];
                        assert!((fd - k).abs() <= 1e-7 * scale, "{kind:?}: K {k} vs FD {fd}");
                    }
                }
            }
        }
    }

    /// Slip holds only the normal component, no-slip also the tangential one, at every
    /// boundary particle.
    #[test]
    fn forces_of_slip_and_no_slip() {
        let n = [-0.4472135954999579, 0.8944271909999159];
        let t = [n[1], -n[0]];
        // uniform motion: tangential 1 cm, normal 0.1 into the wall
        let u = [0.01 * t[0] - 0.1 * n[0], 0.01 * t[1] - 0.1 * n[1]];
        for kind in [PenaltyKind::Slip, PenaltyKind::NoSlip] {
            let mut fx = setup(kind);
            fx.begin();
            let ndof = fx.ndof();
            let (committed, state) = (NodalState::zeros(ndof), uniform(ndof, u));
            let at = GridNodes { grid: &fx.grid, node_ids: &fx.ids };
            fx.wall.commit(at, &input(&state, &committed));
            let wall = &fx.wall;
            let f = wall.total_force();
            let (fn_, ft) = (f[0] * n[0] + f[1] * n[1], f[0] * t[0] + f[1] * t[1]);
            // every boundary particle of cells 0, 1, 4
            let m: f64 = wall.points.iter().map(|p| p.weight).sum();
            let stick = if kind == PenaltyKind::NoSlip { -1e3 * m * 0.01 } else { 0.0 };
            assert_eq!(wall.acting_points(), wall.points.len(), "{kind:?}");
            assert!((fn_ - 1e3 * 0.1 * m).abs() < 1e-9 * fn_, "{kind:?}: normal force {fn_}");
            assert!((ft - stick).abs() < 1e-9 * fn_.abs(), "{kind:?}: tangential force {ft}");
        }
    }

    /// A moving wall (displacement × amplitude ramp): a body that follows the wall's
    /// increment feels no force, one left behind is pulled along; boundary particles move
    /// with the wall.
    #[test]
    fn moving_wall_prescribes_its_increment() {
        let mut fx = setup(PenaltyKind::NoSlip);
        fx.wall.settings.displacement = [0.05, -0.02, 0.0];
        fx.wall.settings.amplitude = Amplitude::Table(vec![[0.0, 0.0], [1.0, 1.0], [2.0, 3.0]]);
        fx.begin();
        let ndof = fx.ndof();
        let committed = NodalState::zeros(ndof);
        let at = GridNodes { grid: &fx.grid, node_ids: &fx.ids };
        fx.wall.commit(at, &input(&committed, &committed));
        let left_behind = fx.wall.total_force();
        // t = 1 → 2: the wall moves by 2 × (0.05, −0.02)
        fx.begin();
        let state = uniform(ndof, [0.1, -0.04]);
        let at = GridNodes { grid: &fx.grid, node_ids: &fx.ids };
        fx.wall.commit(at, &AssemblyInput { time: 2.0, ..input(&state, &committed) });
        let wall = &fx.wall;
        let f = wall.total_force();
        assert!(f.iter().all(|v| v.abs() < 1e-9), "a following body feels {f:?}");
        assert!(left_behind[0] > 1.0 && left_behind[1] < -1.0, "left behind: {left_behind:?}");
        let x = wall.points[0].position;
        assert!((x[0] - wall.particles.position[0][0] - 0.05).abs() < 1e-12, "{x:?}");
    }
}
