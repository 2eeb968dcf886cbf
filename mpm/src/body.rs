//! A body: the material points of one material on a background grid, and what each phase of
//! a step computes for them (CB-Geo's names: `locate_particles`, `p2g`,
//! `compute_internal_forces`, `g2p`/`update_particles`).
//!
//! - [`Body::locate`]: find each point's support (its cell on the linear basis, the 3 × 3
//!   nodes its functions reach on a smooth one: [`crate::basis`]; points outside the grid are
//!   erased), sort the points by (support, id), evaluate the shape functions and their
//!   gradients at the points in the grid's configuration at the start of the step;
//! - [`Body::project`]: `m_I += Σ_p N_I m_p`, `(m v)_I += Σ_p N_I m_p v_p`,
//!   `(m a)_I += Σ_p N_I m_p a_p`;
//! - [`Body::cell_contribution`]: the points of one support as the kernel's integration points (weight
//!   `V_p^n`, `F0 = F_p^n`) and their lumped mass `M_I = Σ_p N_I m_p` with gravity and inertia;
//! - [`Body::convect`]: `Δu_p = Σ N_I Δu_I`, `a_p = Σ N_I a_I`,
//!   `v_p ← v_p + Δt ((1 − γ) a_p^n + γ a_p^{n+1})` (blended with the grid velocity, see
//!   [`VelocityBlend`]), `x_p ← x_p + Δu_p`, and `F_p`, `V_p = J_p V_p^0`, stress and law
//!   state committed.

use std::sync::Arc;

use loam_fem::domain::{AssemblyInput, PointExtent, PointLoad};
use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;
use loam_fem::kernel::{solid_element, KernelContext, KernelError, PointGeometry, PointOutput};
use loam_fem::mixed_kernel::{mixed_element, CellProjection};
use loam_fem::packed_geometry::PackedGeometry;
use loam_laws::ConstitutiveLaw;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::grid::Grid;
use crate::material_points::MaterialPoints;

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

/// Edge of the square (cube in 3D) of volume `volume` of a point at `x`: `V^(1/3)` in 3D,
/// `√(V/t)` in plane strain and stress, `√(V/(2π x))` in axisymmetry.
pub fn point_size(formulation: Formulation, thickness: f64, volume: f64, x: &[f64; 3]) -> f64 {
    match formulation {
        Formulation::ThreeD => volume.cbrt(),
        Formulation::Axisymmetric => (volume / (2.0 * std::f64::consts::PI * x[0].max(1e-300))).sqrt(),
        _ => (volume / thickness).sqrt(),
    }
}

/// Nodal sums of the point-to-grid projection, per grid node.
#[derive(Debug, Clone, Default)]
pub struct GridSums {
    /// `m_I`.
    pub mass: Vec<f64>,
    /// `(m v)_I`.
    pub momentum: Vec<[f64; 3]>,
    /// `(m a)_I`.
    pub inertia: Vec<[f64; 3]>,
}

impl GridSums {
    /// Zero sums for `nodes` grid nodes.
    pub fn reset(&mut self, nodes: usize) {
        self.mass.clear();
        self.mass.resize(nodes, 0.0);
        self.momentum.clear();
        self.momentum.resize(nodes, [0.0; 3]);
        self.inertia.clear();
        self.inertia.resize(nodes, [0.0; 3]);
    }

    /// The sums of every rank's points, every rank receiving the same bits (a node's seven
    /// values sent by the ranks whose points reach it; `Ranks::sum_rows_identically_in`).
    pub fn sum_over(&mut self, ranks: loam_fem::ranks::Ranks) {
        ranks.sum_rows_identically_in(self);
    }
}

/// A node's row: `[m, (m v)_x, (m v)_y, (m v)_z, (m a)_x, (m a)_y, (m a)_z]`.
impl loam_fem::ranks::SummedRows for GridSums {
    fn rows(&self) -> usize {
        self.mass.len()
    }

    fn width(&self) -> usize {
        7
    }

    fn read(&self, a: usize, out: &mut [f64]) {
        out[0] = self.mass[a];
        out[1..4].copy_from_slice(&self.momentum[a]);
        out[4..7].copy_from_slice(&self.inertia[a]);
    }

    fn clear(&mut self, a: usize) {
        self.mass[a] = 0.0;
        self.momentum[a] = [0.0; 3];
        self.inertia[a] = [0.0; 3];
    }

    fn add(&mut self, a: usize, values: &[f64]) {
        self.mass[a] += values[0];
        for i in 0..3 {
            self.momentum[a][i] += values[1 + i];
            self.inertia[a][i] += values[4 + i];
        }
    }
}

/// The points' trial history and kernel output of the current iterate (committed in the
/// convective phase).
#[derive(Debug, Clone, Default)]
pub struct Trial {
    /// Law history, `state_len` values per point.
    pub state: Vec<f64>,
    /// Kernel output per point.
    pub out: Vec<PointOutput>,
}

impl Trial {
    /// Per-block mutable views for the cells `blocks` (ascending; `None` where the body has
    /// no point), for the parallel element loop; `support_start` as [`Body::points_in_support`].
    pub fn views(
        &mut self,
        support_start: &[usize],
        state_len: usize,
        blocks: &[usize],
    ) -> Vec<Option<(&mut [f64], &mut [PointOutput])>> {
        let mut views = Vec::with_capacity(blocks.len());
        let (mut rest_s, mut rest_o) = (self.state.as_mut_slice(), self.out.as_mut_slice());
        let mut consumed = 0;
        for &c in blocks {
            let range = support_start[c]..support_start[c + 1];
            if range.is_empty() {
                views.push(None);
                continue;
            }
            // every occupied cell is a block, so the points are consumed in order
            debug_assert_eq!(range.start, consumed);
            let np = range.len();
            let (s, r) = std::mem::take(&mut rest_s).split_at_mut(np * state_len);
            rest_s = r;
            let (o, r) = std::mem::take(&mut rest_o).split_at_mut(np);
            rest_o = r;
            consumed += np;
            views.push(Some((s, o)));
        }
        views
    }
}

/// What a body carries from step to step: its points (in their current order) and how many
/// left the grid.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct BodyState {
    /// The points with their committed fields and law histories.
    pub points: MaterialPoints,
    /// Points erased so far.
    pub erased: usize,
}

/// The material points of one material (see the module doc).
pub struct Body {
    /// Name from the case file (its output file `<name>.pvd`).
    pub name: String,
    law: Arc<dyn ConstitutiveLaw>,
    /// The material points (sorted by cell during a step).
    pub points: MaterialPoints,
    /// Ids of this body's points seen from outside: `id_offset + points.id`.
    pub id_offset: usize,
    /// Number of points at the start (ids run over `0..initial_count`).
    initial_count: usize,
    index_of_id: Vec<usize>,
    /// Per point (in the sorted order): its support and its shape functions there, packed to
    /// the support's nodes.
    support_of_point: Vec<usize>,
    geometry: PackedGeometry,
    /// [`Body::locate`]'s scratch: every point's support and functions in the order before
    /// the sort.
    located: (Vec<Option<usize>>, PackedGeometry),
    /// Points of support `s`: `support_start[s]..support_start[s + 1]`.
    support_start: Vec<usize>,
    trial: Trial,
    erased: usize,
    /// Forces carried by material points (particle Neumann conditions).
    point_loads: Vec<PointLoad>,
    velocity_blend: VelocityBlend,
}

impl Body {
    /// A body of `points` of the material `law`; its point ids start at `id_offset`.
    pub fn new(name: &str, law: Arc<dyn ConstitutiveLaw>, mut points: MaterialPoints, id_offset: usize) -> Self {
        let sl = law.state_len();
        points.state = vec![0.0; points.len() * sl];
        for p in 0..points.len() {
            law.initialise_state(&mut points.state[p * sl..(p + 1) * sl]);
        }
        let initial_count = points.len();
        Self {
            name: name.to_string(),
            law,
            points,
            id_offset,
            initial_count,
            index_of_id: (0..initial_count).collect(),
            support_of_point: Vec::new(),
            geometry: PackedGeometry::default(),
            located: (Vec::new(), PackedGeometry::default()),
            support_start: Vec::new(),
            trial: Trial::default(),
            erased: 0,
            point_loads: Vec::new(),
            velocity_blend: VelocityBlend::PicFraction(0.0),
        }
    }

    /// The material's law.
    pub fn law(&self) -> &dyn ConstitutiveLaw {
        self.law.as_ref()
    }

    /// Blends the particle velocity update with the grid velocity ([`VelocityBlend`]).
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

    /// Range of the ids of this body's points.
    pub fn id_range(&self) -> std::ops::Range<usize> {
        self.id_offset..self.id_offset + self.initial_count
    }

    /// Current index of the point with (outside) id `id`, if it is this body's and not erased.
    pub fn index_of(&self, id: usize) -> Option<usize> {
        let local = id.checked_sub(self.id_offset)?;
        self.index_of_id.get(local).copied().filter(|&k| k != usize::MAX)
    }

    /// Points of support `s` (indices into the sorted points).
    pub fn points_in_support(&self, s: usize) -> std::ops::Range<usize> {
        self.support_start[s]..self.support_start[s + 1]
    }

    /// Whether the body has points in support `s` (a grid cell on the linear basis).
    pub fn occupies(&self, s: usize) -> bool {
        self.support_start[s + 1] > self.support_start[s]
    }

    /// Sum of the quadrature weights of the body's points in support `s` (a grid cell on
    /// the linear basis).
    pub fn cell_weight(&self, s: usize) -> f64 {
        self.points_in_support(s).map(|p| self.geometry.weight(p)).sum()
    }

    /// Adds the quadrature weights of the body's points to the grid cells that hold them
    /// (per grid cell; on a smooth basis, whose supports are not cells, located from the
    /// points' positions).
    pub fn add_cell_weights(&self, grid: &Grid, weights: &mut [f64]) {
        if !grid.basis().is_smooth() {
            for (s, w) in weights.iter_mut().enumerate().take(grid.num_supports()) {
                *w += self.cell_weight(s);
            }
            return;
        }
        for (p, x) in self.points.position.iter().enumerate() {
            if let Some((c, _)) = grid.locate(x) {
                weights[c] += self.geometry.weight(p);
            }
        }
    }

    /// Scales the quadrature weights of the body's points in support `s`.
    pub fn scale_cell_weights(&mut self, s: usize, factor: f64) {
        let range = self.points_in_support(s);
        self.geometry.scale_weights(range, factor);
    }

    /// Attaches a force to some of the body's points.
    pub fn add_point_load(&mut self, load: PointLoad) {
        self.point_loads.push(load);
    }

    /// Locate: every point's support in `grid` (points outside are erased), the points
    /// sorted by (support, id), their shape functions and gradients in the grid's current
    /// configuration (on GIMP with the point's initial domain: the square of its initial
    /// volume, [`crate::basis`]).
    pub fn locate(&mut self, grid: &Grid, formulation: Formulation, thickness: f64) {
        let n_before = self.points.len();
        let nodes = grid.support_len();
        // every point's support and functions, packed, in the present order
        let (supports, functions) = &mut self.located;
        supports.resize(n_before, None);
        functions.resize(nodes, n_before);
        let pts = &self.points;
        (functions.par_records_mut(), supports.par_iter_mut(), pts.position.par_iter(), pts.initial_volume.par_iter())
            .into_par_iter()
            .with_min_len(1024)
            .for_each_init(PointGeometry::default, |g, (record, support, x, &v0)| {
                let half = 0.5 * point_size(formulation, thickness, v0, x);
                *support = grid.point_functions_into(x, [half; 3], formulation, thickness, g);
                if support.is_some() {
                    PackedGeometry::pack(record, g);
                }
            });
        // counting sort by support, each support's points by id: order (support, id)
        let num_cells = grid.num_supports();
        let mut start = vec![0usize; num_cells + 1];
        for c in supports.iter().flatten() {
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
            for (p, s) in supports.iter().enumerate() {
                if let Some(c) = s {
                    order[fill[*c]] = p;
                    fill[*c] += 1;
                }
            }
        }
        let ids = &self.points.id;
        for c in 0..num_cells {
            order[start[c]..start[c + 1]].sort_unstable_by_key(|&p| ids[p]);
        }
        let sl = self.law.state_len();
        let reordered = kept != n_before || order.iter().enumerate().any(|(k, &p)| k != p);
        if reordered {
            self.points.reorder(&order, sl);
        }
        self.index_of_id.iter_mut().for_each(|i| *i = usize::MAX);
        for (k, &id) in self.points.id.iter().enumerate() {
            self.index_of_id[id] = k;
        }
        let (supports, functions) = &mut self.located;
        self.support_of_point.clear();
        self.support_of_point.extend(order.iter().map(|&p| supports[p].expect("kept points are located")));
        // the functions in the sorted order, weighted by the points' present volumes (in
        // place where the order did not change: the located records become the geometry)
        if reordered {
            self.geometry.resize(nodes, kept);
            (self.geometry.par_records_mut(), order.par_iter()).into_par_iter().with_min_len(1024).for_each(
                |(record, &p)| {
                    record.copy_from_slice(functions.record(p));
                },
            );
        } else {
            std::mem::swap(&mut self.geometry, functions);
        }
        (self.geometry.par_records_mut(), self.points.volume.par_iter())
            .into_par_iter()
            .with_min_len(1024)
            .for_each(|(record, &volume)| record[0] = volume);
        self.support_start = start;
        self.trial.state.clone_from(&self.points.state);
        self.trial.out.resize(self.points.len(), PointOutput::default());
    }

    /// Releases the room of the per-point arrays beyond the present points: after the first
    /// partition of a distributed run, where the body had been built and located with every
    /// rank's points (the located functions, the trial state and the kernel output keep
    /// their room otherwise, about 1.3 kB per point of the whole body on every rank).
    pub fn shrink_to_fit(&mut self) {
        self.located.0.clear();
        self.located.0.shrink_to_fit();
        self.located.1.shrink_to_fit(true);
        self.geometry.shrink_to_fit(false);
        self.support_of_point.shrink_to_fit();
        self.trial.state.shrink_to_fit();
        self.trial.out.shrink_to_fit();
    }

    /// Project (p2g): adds the points' mass, momentum and mass-weighted acceleration to the
    /// grid nodes of their supports.
    pub fn project(&self, grid: &Grid, dim: usize, sums: &mut GridSums) {
        for (p, &support) in self.support_of_point.iter().enumerate() {
            let m = self.points.mass[p];
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                let w = n * m;
                sums.mass[node] += w;
                for i in 0..dim {
                    sums.momentum[node][i] += w * self.points.velocity[p][i];
                    sums.inertia[node][i] += w * self.points.acceleration[p][i];
                }
            }
        }
    }

    /// Takes the trial arrays out for the element loop (give them back with
    /// [`Body::restore_trial`]), so that the kernel can read the body while writing them.
    pub fn take_trial(&mut self) -> Trial {
        std::mem::take(&mut self.trial)
    }

    /// Gives back the trial arrays of [`Body::take_trial`].
    pub fn restore_trial(&mut self, trial: Trial) {
        self.trial = trial;
    }

    /// The support of point `p` (in the order of the last [`Body::locate`]).
    pub fn support_of(&self, p: usize) -> usize {
        self.support_of_point[p]
    }

    /// Start of each support's points (see [`Body::points_in_support`]).
    pub fn support_start(&self) -> &[usize] {
        &self.support_start
    }

    /// Compute internal forces of one cell: the kernel over the body's points in `cell`
    /// (`trial`, `out` their views), written into `f_int` and `stiffness` (overwritten), then
    /// the lumped mass terms `r_I += M_I (ã_I − g)`, `K_II += c_M M_I` added. With the
    /// nodal `pressure` of the cell the kernel is the mixed u–p one
    /// ([`loam_fem::mixed_kernel`]): `f_int` then holds the displacement rows and the `nn`
    /// pressure rows (which carry no mass; in a mass-only assembly they are `1 · a_p = 0`),
    /// and `cell` the integrals over the cell's region with which it integrates its pressure
    /// projection.
    #[allow(clippy::too_many_arguments)]
    pub fn cell_contribution(
        &self,
        ctx: &KernelContext<'_>,
        cell: usize,
        disp: &[[f64; 3]],
        pressure: Option<(&[f64], &CellProjection)>,
        inertia: &[[f64; 3]],
        input: &AssemblyInput<'_>,
        trial: &mut [f64],
        out: &mut [PointOutput],
        f_int: &mut [f64],
        stiffness: Option<&mut [f64]>,
    ) -> Result<(), KernelError> {
        let range = self.points_in_support(cell);
        let sl = self.law.state_len();
        let nn = disp.len();
        let dim = ctx.element.dim();
        let nd = f_int.len();
        let f = &self.points.deformation_gradient[range.clone()];
        let with_stiffness = input.with_tangent && input.stiffness;
        let mut stiffness = stiffness;
        let (geometry, committed) =
            (&self.geometry.points(range.clone()), &self.points.state[range.start * sl..range.end * sl]);
        let k = if with_stiffness { stiffness.as_deref_mut() } else { None };
        match pressure {
            None => solid_element(ctx, disp, geometry, f, f, committed, trial, out, f_int, k)?,
            Some((p, cell)) => {
                mixed_element(ctx, disp, p, geometry, f, f, committed, trial, out, f_int, k, Some(cell))?
            }
        }
        if let (Some(km), false) = (stiffness.as_deref_mut(), with_stiffness) {
            km.fill(0.0);
        }
        if pressure.is_some() && !input.stiffness {
            let nu = nn * dim;
            f_int[nu..].fill(0.0);
            if let Some(km) = stiffness.as_deref_mut() {
                for a in 0..nn {
                    km[(nu + a) * nd + nu + a] = 1.0;
                }
            }
        }
        let mut lumped = [0.0; MAX_NODES];
        for p in range {
            for (m, &n) in lumped.iter_mut().zip(self.geometry.shape(p)) {
                *m += n * self.points.mass[p];
            }
        }
        for a in 0..nn {
            for i in 0..dim {
                let mut r = -lumped[a] * input.gravity[i];
                if input.inertial_acceleration.is_some() {
                    r += lumped[a] * inertia[a][i];
                }
                f_int[a * dim + i] += r;
                if let Some(km) = stiffness.as_deref_mut() {
                    km[(a * dim + i) * nd + a * dim + i] += input.mass_coefficient * lumped[a];
                }
            }
        }
        Ok(())
    }

    /// Particle Neumann: every loaded point `p` in support `s` adds `−N_I(ξ_p) F f(t)` to
    /// the residual of the block of `s` (`r = f_int − f_ext + M ã`; blocks of `nd` DOFs whose
    /// first `nn · dim` are the displacements of the support's `nn` nodes); `block_of_support`
    /// gives the block of a support. The point's functions are fixed within a step (the grid
    /// moves with the body), so the force is a follower of the body without a tangent
    /// contribution.
    pub fn add_point_loads(
        &self,
        time: f64,
        (nn, dim, nd): (usize, usize, usize),
        block_of_support: impl Fn(usize) -> usize,
        vectors: &mut [f64],
    ) {
        for load in &self.point_loads {
            let f = load.amplitude.at(time);
            for &id in &load.ids {
                let Some(k) = self.index_of(id) else { continue }; // erased
                let b = block_of_support(self.support_of_point[k]);
                let v = &mut vectors[b * nd..(b + 1) * nd];
                for a in 0..nn {
                    let n = self.geometry.shape(k)[a];
                    for i in 0..dim {
                        v[a * dim + i] -= n * load.force[i] * f;
                    }
                }
            }
        }
    }

    /// Convect (g2p, update particles): see the module doc. `node_ids` maps grid nodes to
    /// global nodes.
    pub fn convect(&mut self, grid: &Grid, node_ids: &[usize], input: &AssemblyInput<'_>) {
        let dim = grid.mesh.element.dim();
        let (dt, gamma) = (input.time_step, input.gamma);
        let theta = self.velocity_blend.theta(dt);
        let dynamic = input.inertial_acceleration.is_some();
        let (geometry, supports) = (&self.geometry, &self.support_of_point);
        let pts = &mut self.points;
        let outs = &self.trial.out;
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
                let nodes = grid.support(supports[p]);
                let mut du = [0.0; 3];
                let mut acc = [0.0; 3];
                let mut v_grid = [0.0; 3];
                for (&node, &n) in nodes.iter().zip(geometry.shape(p)) {
                    let g = node_ids[node] * dim;
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
        self.points.state.copy_from_slice(&self.trial.state);
    }

    /// The committed state of the body (its points and how many left the grid).
    pub fn state(&self) -> BodyState {
        BodyState { points: self.points.clone(), erased: self.erased }
    }

    /// Restores a state of [`Body::state`] of the same body.
    pub fn restore(&mut self, state: BodyState) -> Result<(), String> {
        let sl = self.law.state_len();
        let p = &state.points;
        let n = p.id.len();
        let consistent = [
            p.position.len(),
            p.displacement.len(),
            p.velocity.len(),
            p.acceleration.len(),
            p.mass.len(),
            p.volume.len(),
            p.initial_volume.len(),
            p.deformation_gradient.len(),
            p.cauchy.len(),
            p.work.len(),
        ]
        .iter()
        .all(|&l| l == n)
            && p.state.len() == n * sl
            && p.id.iter().all(|&id| id < self.initial_count);
        if !consistent || n + state.erased != self.initial_count {
            return Err(format!("body '{}': the saved points are of another body or law", self.name));
        }
        self.points = state.points;
        self.erased = state.erased;
        self.index_of_id.iter_mut().for_each(|i| *i = usize::MAX);
        for (k, &id) in self.points.id.iter().enumerate() {
            self.index_of_id[id] = k;
        }
        Ok(())
    }

    /// Interpolates the nodal accelerations `a` (full DOF vector) to the points.
    pub fn interpolate_acceleration(&mut self, grid: &Grid, node_ids: &[usize], a: &[f64]) {
        let dim = grid.mesh.element.dim();
        for (p, &support) in self.support_of_point.iter().enumerate() {
            let mut acc = [0.0; 3];
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                let g = node_ids[node] * dim;
                for i in 0..dim {
                    acc[i] += n * a[g + i];
                }
            }
            self.points.acceleration[p] = acc;
        }
    }

    /// Linear momentum `Σ_p m_p v_p` (kg m/s).
    pub fn momentum(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (m, v) in self.points.mass.iter().zip(&self.points.velocity) {
            (0..3).for_each(|i| p[i] += m * v[i]);
        }
        p
    }

    /// Kinetic energy `Σ_p ½ m_p |v_p|²`.
    pub fn kinetic_energy(&self) -> f64 {
        (0..self.points.len())
            .map(|p| 0.5 * self.points.mass[p] * self.points.velocity[p].iter().map(|c| c * c).sum::<f64>())
            .sum()
    }

    /// Current position and sizes of every point ([`PointExtent`]).
    pub fn point_extents(&self, formulation: Formulation, thickness: f64) -> impl Iterator<Item = PointExtent> + '_ {
        let pts = &self.points;
        (0..pts.len()).map(move |p| {
            let x = pts.position[p];
            let size = |v: f64| point_size(formulation, thickness, v, &x);
            PointExtent { position: x, size: size(pts.volume[p]), initial_size: size(pts.initial_volume[p]) }
        })
    }

    /// Adds `Σ_p N_I m_p p_p` to `sums` (per grid node): the mass-weighted projection of the
    /// points' pressure `p_p = J_p tr σ_p / 3` (the mean Kirchhoff stress of the u–p
    /// formulation), the start of a step's nodal pressures.
    pub fn project_pressure(&self, grid: &Grid, sums: &mut [f64]) {
        for (p, &support) in self.support_of_point.iter().enumerate() {
            let f = &self.points.deformation_gradient[p];
            let pressure = f.determinant() * self.points.cauchy[p].trace() / 3.0;
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                sums[node] += n * self.points.mass[p] * pressure;
            }
        }
    }

    /// Marks the grid nodes whose function is non-zero at one of the body's points.
    pub fn mark_reached_nodes(&self, grid: &Grid, reached: &mut [bool]) {
        for (p, &support) in self.support_of_point.iter().enumerate() {
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                reached[node] |= n != 0.0;
            }
        }
    }

    /// Adds the nodal weight `Σ_p N_I w_p` of this body's points (their quadrature weights:
    /// the measure of the material each node's function covers) to `weights`.
    pub fn add_node_weights(&self, grid: &Grid, weights: &mut [f64]) {
        for (p, &support) in self.support_of_point.iter().enumerate() {
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                weights[node] += n * self.geometry.weight(p);
            }
        }
    }

    /// Nodal mass `Σ_p N_I m_p` of this body's points (per grid node).
    pub fn nodal_mass(&self, grid: &Grid, mass: &mut [f64]) {
        for (p, &support) in self.support_of_point.iter().enumerate() {
            for (&node, &n) in grid.support(support).iter().zip(self.geometry.shape(p)) {
                mass[node] += n * self.points.mass[p];
            }
        }
    }
}
