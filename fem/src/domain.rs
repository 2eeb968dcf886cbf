//! The `Domain` seam: anything that contributes element blocks to the global system.
//!
//! An FEM mesh and an MPM background grid are both domains. A domain refers to nodes by
//! global id, declares its element blocks once per pattern, fills its part of the element
//! buffers at every Newton iteration, and commits its history when a step has converged.

use crate::assembly::BlockLayout;
use crate::element::ElementType;
use crate::formulation::Formulation;

/// Nodal unknowns of the whole model, full DOF vectors (node-major, `dim` per node).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NodalState {
    /// Displacement from the reference configuration.
    pub u: Vec<f64>,
    /// Velocity.
    pub v: Vec<f64>,
    /// Acceleration.
    pub a: Vec<f64>,
}

impl NodalState {
    /// All zero for `n` DOFs.
    pub fn zeros(n: usize) -> Self {
        Self { u: vec![0.0; n], v: vec![0.0; n], a: vec![0.0; n] }
    }
}

/// What a domain needs to assemble at one Newton iteration.
pub struct AssemblyInput<'a> {
    /// Current iterate at `t_{n+1}`.
    pub state: &'a NodalState,
    /// Committed state at `t_n`.
    pub committed: &'a NodalState,
    /// Acceleration at which inertia is evaluated (`ã`, full DOF vector); `None` if static.
    pub inertial_acceleration: Option<&'a [f64]>,
    /// Mass coefficient of the tangent (`c_M`, 0 if static).
    pub mass_coefficient: f64,
    /// Gravity vector at `t_{n+1}` (m/s²), already scaled by its amplitude.
    pub gravity: [f64; 3],
    /// Time step Δt.
    pub time_step: f64,
    /// Newmark γ of the velocity update `v = vₙ + Δt ((1 − γ) aₙ + γ a)` (½ for the
    /// average-acceleration rule, ½ − α_B for Bossak); particle domains update their points'
    /// velocities with it.
    pub gamma: f64,
    /// Time `t_{n+1}` of the iterate (s): loads a domain carries itself (forces on material
    /// points) take their amplitude here.
    pub time: f64,
    /// Whether to compute element matrices (else only vectors).
    pub with_tangent: bool,
    /// Whether the matrices include the stiffness `K_t` (else only `c_M M`: used for the
    /// consistent initial acceleration `M a₀ = f_ext − f_int`).
    pub stiffness: bool,
}

impl<'a> AssemblyInput<'a> {
    /// A static assembly with the stiffness tangent at `state` (time 1 s, unit step, no
    /// gravity, no inertia): what a domain's tests differentiate against central differences.
    pub fn static_tangent(state: &'a NodalState, committed: &'a NodalState) -> Self {
        Self {
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
}

/// Failure while a domain assembles.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error("domain '{domain}', element {element}: {message}")]
pub struct DomainError {
    /// Domain name.
    pub domain: String,
    /// Element (or cell) index within the domain.
    pub element: usize,
    /// What went wrong.
    pub message: String,
}

/// A named output field (per node or per cell) for VTK files.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name, e.g. `displacement`, `cauchy_stress`.
    pub name: String,
    /// Components per entity (1 scalar, 3 vector, 9 tensor).
    pub components: usize,
    /// Values back to back.
    pub values: Vec<f64>,
}

/// A domain's geometry and fields for output.
#[derive(Debug, Clone, PartialEq)]
pub struct DomainOutput {
    /// Point coordinates (reference configuration for meshes; current for material points).
    pub points: Vec<[f64; 3]>,
    /// Cell type and flat connectivity into `points`; `None` for a point cloud.
    pub cells: Option<(ElementType, Vec<usize>)>,
    /// Fields per point.
    pub point_fields: Vec<Field>,
    /// Fields per cell.
    pub cell_fields: Vec<Field>,
}

/// The `k`-th of `parts` contiguous ranges of `0..n`, as equal as integers allow: the share of
/// rank `k` of `parts` in an output's points or cells ([`DomainOutput::piece`]).
pub fn share(n: usize, k: usize, parts: usize) -> std::ops::Range<usize> {
    (n * k / parts)..(n * (k + 1) / parts)
}

impl Field {
    /// Entities `range` of the field.
    pub fn restrict(&self, range: std::ops::Range<usize>) -> Field {
        let c = self.components;
        Field { name: self.name.clone(), components: c, values: self.values[range.start * c..range.end * c].to_vec() }
    }

    /// Entities `ids` (ascending) of the field.
    pub fn select(&self, ids: &[usize]) -> Field {
        let c = self.components;
        let mut values = Vec::with_capacity(ids.len() * c);
        for &i in ids {
            values.extend_from_slice(&self.values[i * c..(i + 1) * c]);
        }
        Field { name: self.name.clone(), components: c, values }
    }
}

impl DomainOutput {
    /// Piece `rank` of `size` of the output, what that rank writes in a distributed run
    /// (docs/distributed.md, "Output"): for a point cloud its points in the rank's [`share`]
    /// of the storage order; for a mesh its cells in the rank's share and the points they
    /// use, renumbered in ascending order (a point shared by cells of two pieces is in both).
    pub fn piece(&self, rank: usize, size: usize) -> DomainOutput {
        match &self.cells {
            None => {
                let range = share(self.points.len(), rank, size);
                DomainOutput {
                    points: self.points[range.clone()].to_vec(),
                    cells: None,
                    point_fields: self.point_fields.iter().map(|f| f.restrict(range.clone())).collect(),
                    cell_fields: self.cell_fields.iter().map(|f| f.restrict(range.clone())).collect(),
                }
            }
            Some((element, connectivity)) => {
                let nn = element.num_nodes();
                let cells = share(connectivity.len() / nn, rank, size);
                let own = &connectivity[cells.start * nn..cells.end * nn];
                let mut used: Vec<usize> = own.to_vec();
                used.sort_unstable();
                used.dedup();
                let mut local = vec![usize::MAX; self.points.len()];
                for (k, &a) in used.iter().enumerate() {
                    local[a] = k;
                }
                DomainOutput {
                    points: used.iter().map(|&a| self.points[a]).collect(),
                    cells: Some((*element, own.iter().map(|&a| local[a]).collect())),
                    point_fields: self.point_fields.iter().map(|f| f.select(&used)).collect(),
                    cell_fields: self.cell_fields.iter().map(|f| f.restrict(cells.clone())).collect(),
                }
            }
        }
    }
}

/// Where a tracked point's material lies: its current position and two sizes, the sides of
/// the squares (2D, per unit thickness or per radian-ring length) or cubes (3D) of its
/// current volume `V = J V₀` and of its initial volume `V₀`.
///
/// The current size is how far the point's material reaches sideways (contact walls, the
/// joining of a surface's stretch). How high it stands above its centre is half the
/// smaller of the two ([`PointExtent::half_height`]): a point whose volume has grown stands
/// no higher than its material packed. In the cohesionless, non-dilatant soils that flow
/// and heap, volume growth is spreading — the thin toe of a flow stretched into a layer
/// thinner than a point, points dragged along a rough base, whose deformation gradients
/// can become degenerate (J in the hundreds to thousands in the toe of the Bui collapse on
/// triangles) — not material rising: counted by its current volume such a point stood as a
/// column several centimetres tall over the toe of a settled heap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointExtent {
    /// Current position.
    pub position: [f64; 3],
    /// Side of the square (cube) of the current volume.
    pub size: f64,
    /// Side of the square (cube) of the initial volume.
    pub initial_size: f64,
}

impl PointExtent {
    /// A point whose volume has not changed.
    pub fn new(position: [f64; 3], size: f64) -> Self {
        Self { position, size, initial_size: size }
    }

    /// Height of the top of the point's material above its centre: `min(s, s₀) / 2`.
    pub fn half_height(&self) -> f64 {
        0.5 * self.size.min(self.initial_size)
    }

    /// Every rank's `local` extents, in rank order (collective: the points of a domain whose
    /// points are distributed over `ranks`, for what reads all of them: the surface monitors
    /// and the contacts' gaps to the soil). One process: `local`.
    pub fn gathered(ranks: crate::ranks::Ranks, local: Vec<PointExtent>) -> Vec<PointExtent> {
        if !ranks.is_distributed() {
            return local;
        }
        let mine: Vec<f64> =
            local.iter().flat_map(|p| [p.position[0], p.position[1], p.position[2], p.size, p.initial_size]).collect();
        ranks
            .all_gather_varcount(&mine)
            .iter()
            .flat_map(|part| part.chunks_exact(5))
            .map(|r| PointExtent { position: [r[0], r[1], r[2]], size: r[3], initial_size: r[4] })
            .collect()
    }
}

/// Vector quantities of tracked points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointQuantity {
    /// Position in the current configuration.
    Position,
    /// Displacement from the initial position.
    Displacement,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
}

/// Tensor quantities of tracked points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointTensor {
    /// Cauchy stress σ (Pa, tension positive).
    CauchyStress,
    /// Deformation gradient F.
    DeformationGradient,
}

/// A force carried by tracked points (material points) that move with the body: at every
/// Newton iteration each point `p` adds `f_I = N_I(x_p) F amplitude(t_{n+1})` to the
/// external force of the nodes `I` of the cell it lies in (Kratos' particle point load).
#[derive(Debug, Clone, PartialEq)]
pub struct PointLoad {
    /// Ids of the tracked points that each carry the force.
    pub ids: Vec<usize>,
    /// Force per point (N; axisymmetric: total over the circumference).
    pub force: [f64; 3],
    /// Time function.
    pub amplitude: crate::amplitude::Amplitude,
}

/// One output of a domain for VTK files, written as `<name>.pvd` / `<name>_<step>.vtu`.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedOutput {
    /// File stem: the domain's (or body's, wall's) name; `<domain>_grid` for a background grid.
    pub name: String,
    /// Geometry and fields.
    pub output: DomainOutput,
}

/// A contributor of element blocks to the global system.
pub trait Domain: Send + Sync {
    /// The domain's name from the case file.
    fn name(&self) -> &str;

    /// Kinematic formulation (all domains of a model share one).
    fn formulation(&self) -> Formulation;

    /// Out-of-plane thickness (plane problems; 1 otherwise).
    fn thickness(&self) -> f64;

    /// Initialisation phase of a step, before any assembly. Particle domains move their
    /// background grid with the structure attached to it, reset their grid nodes in
    /// `committed` (displacement to the grid's own motion, velocity and acceleration
    /// projected from the material points; interface nodes keep the structure's state),
    /// locate and project their points, and return `true` if their element blocks changed
    /// (which rebuilds the sparsity pattern). Mesh domains do nothing. An error here is not
    /// cured by a shorter step (the committed state decides it).
    fn begin_step(&mut self, _committed: &mut NodalState) -> Result<bool, DomainError> {
        Ok(false)
    }

    /// Whether this domain is soil (material points on a background grid): its residual at
    /// interface nodes is the force the soil exerts on the structure.
    fn is_soil(&self) -> bool {
        false
    }

    /// The tracked point (material point) nearest to `x`: its id and distance. Mesh
    /// domains have none.
    fn nearest_point(&self, _x: &[f64]) -> Option<(usize, f64)> {
        None
    }

    /// Ids of the tracked points of the body named `name` in this domain (a contiguous
    /// range), if it has one.
    fn point_set(&self, _name: &str) -> Option<std::ops::Range<usize>> {
        None
    }

    /// Current position and sizes of every tracked point (material point), see
    /// [`PointExtent`]. Mesh domains have none.
    fn point_extents(&self) -> Vec<PointExtent> {
        Vec::new()
    }

    /// A vector quantity of tracked point `id` (material point), if this domain has it.
    fn point_quantity(&self, _id: usize, _quantity: PointQuantity) -> Option<[f64; 3]> {
        None
    }

    /// A tensor quantity (row-major 3×3) of tracked point `id`, if this domain has it.
    fn point_tensor(&self, _id: usize, _quantity: PointTensor) -> Option<[[f64; 3]; 3]> {
        None
    }

    /// Ids of the tracked points whose current position lies in the axis-aligned box
    /// `[min, max]` (first `min.len()` coordinates, bounds included).
    fn points_in_box(&self, _min: &[f64], _max: &[f64]) -> Vec<usize> {
        Vec::new()
    }

    /// Current volume `Σ_p V_p` (m³) and mass `Σ_p m_p` (kg) of the tracked points whose
    /// current position lies in the axis-aligned box `[min, max]` (first `min.len()`
    /// coordinates, bounds included): per unit thickness × thickness in plane problems, the
    /// full ring (2πr) in axisymmetry. Mesh domains have none.
    fn points_volume_mass(&self, _min: &[f64], _max: &[f64]) -> (f64, f64) {
        (0.0, 0.0)
    }

    /// Attaches a force to tracked points (see [`PointLoad`]); `false` if this domain has
    /// no tracked points to carry it.
    fn add_point_load(&mut self, _load: PointLoad) -> bool {
        false
    }

    /// For a background grid attached to a structure: the worst quality of its cells over
    /// the steps so far (smallest corner `det J` over its reference value) and the mesh
    /// motion's reach after each time it was widened; `None` otherwise.
    fn grid_motion(&self) -> Option<(f64, Vec<String>)> {
        None
    }

    /// Sum of the forces (N) that the wall (a penalty boundary) named `wall` exerted on the
    /// bodies in the last converged step; `None` if this domain has no such wall.
    fn wall_force(&self, _wall: &str) -> Option<[f64; 3]> {
        None
    }

    /// Appends this domain's element blocks (global DOF ids) to `layout`, in the order
    /// in which [`Domain::assemble`] fills its buffers.
    fn blocks(&self, layout: &mut BlockLayout);

    /// Appends the cost of each of this domain's blocks' kernels (in the order of
    /// [`Domain::blocks`]), in integration points (material points, Gauss points): the
    /// weights of the distributed partition ([`crate::ranks::rcb`]). By default 0 for every
    /// block: a domain that does not implement [`Domain::own_blocks`] evaluates every block
    /// on every rank, so where its blocks go costs no kernel time.
    fn block_costs(&self, costs: &mut Vec<f64>) {
        let mut layout = BlockLayout::default();
        self.blocks(&mut layout);
        costs.extend(std::iter::repeat_n(0.0, layout.num_blocks()));
    }

    /// In a distributed run, which rank evaluates each of this domain's blocks (in the order of
    /// [`Domain::blocks`]; `None`: every block here). A domain may then evaluate the kernels of
    /// its rank's blocks only (the others are not gathered), provided that the state those
    /// kernels update reaches every rank when the step is committed
    /// ([`crate::ranks::Ranks::replicate`] in [`Domain::commit`]); by default it evaluates
    /// every block, as on one process.
    fn own_blocks(&mut self, _owners: Option<crate::ranks::BlockOwners>) {}

    /// In a distributed run, the ranks if this domain's points are distributed over them
    /// (docs/distributed.md, stage 3): its point queries ([`Domain::kinetic_energy`],
    /// [`Domain::point_quantity`], …) then answer for this rank's points only, and their sums
    /// over the ranks are the caller's (`Model::kinetic_energy`, the monitors). `None`: every
    /// rank holds every point.
    fn points_distributed(&self) -> Option<crate::ranks::Ranks> {
        None
    }

    /// Fills the element matrices (row-major) and residual vectors
    /// `r_e = f_int − f_body + M ã` of this domain's blocks.
    fn assemble(
        &mut self,
        input: &AssemblyInput<'_>,
        matrices: &mut [f64],
        vectors: &mut [f64],
    ) -> Result<(), DomainError>;

    /// After the step's Newton iteration has converged at `input`'s iterate: updates the
    /// domain's own unknowns that the iteration holds fixed (the augmented-Lagrangian
    /// multipliers of a contact) and returns `true` if the step must be solved again with
    /// them (default: nothing to update).
    fn augment(&mut self, _input: &AssemblyInput<'_>) -> bool {
        false
    }

    /// The step has converged: commit histories (input as for the last assembly).
    fn commit(&mut self, input: &AssemblyInput<'_>);

    /// Kinetic energy `½ vᵀ M v` for the nodal velocities `v` (full DOF vector).
    fn kinetic_energy(&self, v: &[f64]) -> f64;

    /// Stored work of the internal forces (strain energy for elastic laws), committed.
    fn strain_energy(&self) -> f64;

    /// Linear momentum `∫ ρ v dV` (kg m/s, per unit thickness in plane problems) of the part
    /// of this domain named `name` (the domain itself, or one of its bodies; `None`: the whole
    /// domain) at the nodal velocities `v`; `None` if it has no such part or carries no mass.
    fn momentum(&self, _name: Option<&str>, _v: &[f64]) -> Option<[f64; 3]> {
        None
    }

    /// Kinetic and stored energy of the part of this domain named `name` (the domain
    /// itself, or one of its bodies), if it has one.
    fn energies(&self, name: &str, v: &[f64]) -> Option<(f64, f64)> {
        (name == self.name()).then(|| (self.kinetic_energy(v), self.strain_energy()))
    }

    /// Boundary facets (global node ids, outward orientation) for surface loads.
    fn boundary_facets(&self) -> Vec<Vec<usize>>;

    /// Receives the consistent initial acceleration `a₀` (full DOF vector) computed by
    /// [`crate::model::Model::initialise_acceleration`]; particle domains interpolate it to
    /// their points. Mesh domains need nothing (the model holds nodal accelerations).
    fn accept_initial_acceleration(&mut self, _a: &[f64]) {}

    /// The domain's committed state beyond the model's nodal unknowns (law histories,
    /// material points, walls), encoded for a checkpoint: with the nodal state it
    /// determines every later step bit for bit.
    fn save_state(&self) -> Vec<u8>;

    /// Restores a state of [`Domain::save_state`] into a domain built from the same case.
    fn restore_state(&mut self, state: &[u8]) -> Result<(), String>;

    /// Geometry and fields for output at the committed state: the mesh of an FEM domain;
    /// the material points of each body, the points of each penalty wall and, with
    /// `with_grid`, the background grid of a particle domain.
    fn outputs(&self, committed: &NodalState, with_grid: bool) -> Vec<NamedOutput>;

    /// Piece `rank` of `size` of each of [`Domain::outputs`] ([`DomainOutput::piece`]), what
    /// a rank writes in a distributed run. By default the whole outputs are built and split;
    /// a domain with many points builds only its piece.
    fn output_pieces(&self, committed: &NodalState, with_grid: bool, rank: usize, size: usize) -> Vec<NamedOutput> {
        self.outputs(committed, with_grid)
            .into_iter()
            .map(|o| NamedOutput { name: o.name, output: o.output.piece(rank, size) })
            .collect()
    }
}
