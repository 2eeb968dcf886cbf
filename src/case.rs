//! Case files: the JSON description of a simulation.
//!
//! Every object rejects unknown keys, and every error names its JSON path, e.g.
//! `materials.beam.poisson_ratio: must lie in (-1, 0.5), got 0.5`. See docs/cases.md
//! for a commented example and every key with its type, default and unit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use loam_fem::amplitude::Amplitude;
use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::linear_solver::PetscOptions;
use loam_fem::model::NewtonSettings;
use loam_fem::scheme::TimeScheme;
use loam_laws::MaterialSpec;
use loam_mpm::basis::Basis;
use serde::Deserialize;

/// A problem in a case file, with the JSON path (or file and line) it concerns.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error("{location}: {message}")]
pub struct CaseError {
    /// JSON path such as `domains[0].mesh.rectangle.cells`, or `file:line:column`.
    pub location: String,
    /// What is wrong.
    pub message: String,
}

impl CaseError {
    /// An error at `location`.
    /// Numbers of more than 20 characters in `message` are written in exponent form
    /// ([`crate::input::compact_numbers`]). Control characters (a name with a newline) are escaped, so that the message stays one
    /// line.
    pub fn new(location: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            location: escape_controls(&location.into()),
            message: escape_controls(&crate::input::compact_numbers(&message.into())),
        }
    }
}

/// `text` with its control characters escaped (`\n`, `\u{1b}`).
fn escape_controls(text: &str) -> String {
    if text.chars().any(char::is_control) {
        text.chars().map(|c| if c.is_control() { c.escape_debug().to_string() } else { c.to_string() }).collect()
    } else {
        text.to_string()
    }
}

/// The whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// What the case shows and which reference it reproduces.
    pub description: String,
    /// Kinematic formulation shared by all domains (default `plane_strain`).
    #[serde(default = "default_formulation")]
    pub formulation: Formulation,
    /// Out-of-plane thickness in m for plane problems (default 1).
    #[serde(default = "one")]
    pub thickness: f64,
    /// Materials by name.
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Domains: FEM meshes (nodes at the same position are shared between FEM domains) and
    /// MPM bodies (domains with identical grids share one grid).
    pub domains: Vec<DomainSpec>,
    /// Interfaces between an MPM domain's grid (soil) and an FEM domain (structure), solved
    /// in one Newton system with them; without one, an FEM mesh must not touch a grid.
    #[serde(default)]
    pub interfaces: Vec<InterfaceSpec>,
    /// Named node sets.
    #[serde(default)]
    pub regions: BTreeMap<String, RegionSpec>,
    /// Prescribed displacements.
    #[serde(default)]
    pub boundary_conditions: Vec<BoundaryConditionSpec>,
    /// Nodal forces and surface loads.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
    /// Gravity.
    #[serde(default)]
    pub gravity: Option<GravitySpec>,
    /// Analysis type and time stepping.
    pub analysis: AnalysisSpec,
    /// Newton and linear-solver settings.
    #[serde(default)]
    pub solver: NewtonSettings,
    /// `solver.petsc_options`: extra PETSc options of `solver.linear_solver: "petsc"`, in the
    /// order of their names (taken out of the `solver` object before it is read as the `Copy`
    /// [`NewtonSettings`]; see [`Case::parse`]).
    #[serde(skip)]
    pub petsc_options: PetscOptions,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Named scalar time histories written to `monitors.csv`.
    #[serde(default)]
    pub monitors: Vec<MonitorSpec>,
    /// Variables of the case as an FMU (`loam fmu`), and the inputs the library API
    /// [`crate::simulation::Simulation::set_input`] accepts.
    #[serde(default)]
    pub fmu: Option<FmuSpec>,
    /// Bounds on the size of the model and the length of the run, checked before anything
    /// is allocated or run (defaults in [`LimitsSpec`]).
    #[serde(default)]
    pub limits: LimitsSpec,
    /// Directory of the case file (for relative mesh paths); set by the loader.
    #[serde(skip)]
    pub directory: PathBuf,
    /// Stem of the case file name (default output directory `out/<name>`).
    #[serde(skip)]
    pub name: String,
}

/// Bounds on what a case may ask for (`limits`), so that a typing error (`"cells": [100000,
/// 100000]`, `"spacing": 1e-9`, `"time_step": 1e-300`) is refused with a message naming the
/// bound before memory is allocated or time spent, instead of exhausting the machine. The
/// defaults suit a workstation of 16–32 GB; raise them in the case file for larger models.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsSpec {
    /// Largest number of cells, and of nodes, of one mesh or grid (also the most nodes and
    /// elements a Gmsh file may declare); default 2 000 000. Measured: an MPM grid of 2
    /// million quad4 cells takes 1.2 GB, an FEM mesh of 2 million quad4 cells 7 GB to build,
    /// before any factorisation.
    pub cells: usize,
    /// Largest number of material points of one body, and of boundary particles of one
    /// penalty wall; default 5 000 000 (a run takes about 1.5 GB per million points).
    pub material_points: usize,
    /// Largest number of steps of a run: `end_time / time_step` (adaptive steps:
    /// `end_time / max_time_step`), plus one per `output.times` entry (default 1 000 000).
    pub steps: usize,
}

impl Default for LimitsSpec {
    fn default() -> Self {
        Self { cells: 2_000_000, material_points: 5_000_000, steps: 1_000_000 }
    }
}

fn default_formulation() -> Formulation {
    Formulation::PlaneStrain
}

fn one() -> f64 {
    1.0
}

/// A domain: a mesh with one material.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    /// Name (used for output files `<name>_<step>.vtu`).
    pub name: String,
    /// Discretisation: `fem` (Lagrangian FEM, default), `mpm` (material points) or `rigid`
    /// (a plane rigid body: its mesh gives its shape, mass and inertia from the material's
    /// density; it meets soil by a tie or contact interface).
    #[serde(rename = "type", default = "fem")]
    pub kind: DomainKind,
    /// Mesh (FEM and rigid domains).
    #[serde(default)]
    pub mesh: Option<MeshSpec>,
    /// Prescribed motion of a `rigid` domain (default: free, moved by its weight, inertia and
    /// contacts; a static analysis needs every one of its three unknowns prescribed).
    #[serde(default)]
    pub motion: Option<RigidMotionSpec>,
    /// Initial angular velocity (rad/s, counter-clockwise) of a `rigid` domain about its
    /// centroid (default 0; its translation's is `initial_velocity`, `uniform` only).
    #[serde(default)]
    pub initial_angular_velocity: Option<f64>,
    /// Structured background grid (MPM domains).
    #[serde(default)]
    pub grid: Option<GridSpec>,
    /// Instead of `grid`: any mesh as the background grid (e.g. `{"gmsh": "grid.msh"}`;
    /// tri3, quad4, tet4 or hex8), with a bin-based point search.
    #[serde(default)]
    pub grid_mesh: Option<MeshSpec>,
    /// Where the material points are (MPM domains).
    #[serde(default)]
    pub material_points: Option<BodySpec>,
    /// Initial velocity of the domain's nodes (FEM) or material points (MPM).
    #[serde(default)]
    pub initial_velocity: Option<InitialVelocity>,
    /// Share θ ∈ [0, 1] of the grid (PIC) velocity in the material points' velocity update
    /// (MPM domains; default 0: the Newmark FLIP-type update). A few per cent damp the
    /// velocity noise of granular bodies coming to rest.
    #[serde(default)]
    pub pic_fraction: f64,
    /// Instead of `pic_fraction`: relaxation time τ (s) of the PIC blend, θ = 1 − exp(−Δt/τ)
    /// in a step Δt, so that the damping does not depend on the step size.
    #[serde(default)]
    pub pic_relaxation_time: Option<f64>,
    /// Initial stress of the material points (MPM domains), e.g. a geostatic `K0` state.
    #[serde(default)]
    pub initial_stress: Option<InitialStressSpec>,
    /// Material name (a key of `materials`).
    pub material: String,
    /// Mass matrix of an `fem` domain: `consistent` (default) or `lumped`. An `mpm` domain's
    /// grid mass is always lumped (the row sums `m_I = Σ_p N_I(x_p) m_p`, as in Kratos'
    /// default and Sulsky's MPM): `lumped` may be written there, `consistent` is refused.
    #[serde(default)]
    pub mass_matrix: Option<MassMatrix>,
    /// Unknowns of the domain's elements: `displacement` (default, the irreducible element)
    /// or `mixed_up` (nodal displacements and pressures with a stabilised equal-order
    /// element, for nearly and exactly incompressible materials: undrained soil, rubber).
    /// All bodies on one background grid share it.
    #[serde(default)]
    pub element_formulation: ElementFormulation,
    /// How a grid cell integrates over its material points (MPM domains): `material_points`
    /// (default: the points' volumes as weights, standard MPM) or `filled_cells` (in every
    /// cell the material fills, the weights scaled to add up to the cell's volume: no soft
    /// or stiff cells where points have crossed, for quasi-static plastic flow such as a
    /// footing; `loam_mpm::quadrature`). All bodies on one background grid share it.
    #[serde(default)]
    pub quadrature: Quadrature,
    /// Factor α ≥ 0 of the ghost penalty on the faces of cut cells (MPM
    /// domains; `γ = α E` on the jump of the normal derivative of the step's displacement
    /// across a face, Burman 2010, Coombs 2023; `loam_mpm::ghost_penalty`): keeps the nodes
    /// that the material only grazes in the system (default [`DEFAULT_GHOST_PENALTY`] in
    /// static and quasi-static analyses, 0 in dynamic ones, whose inertia holds those nodes;
    /// 0 switches it off). All bodies on one background grid share it.
    #[serde(default)]
    pub ghost_penalty: Option<f64>,
}

/// Default factor of `domains[k].ghost_penalty`.
pub const DEFAULT_GHOST_PENALTY: f64 = 0.1;

/// How a grid cell integrates over its material points (`domains[k].quadrature`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quadrature {
    /// The points' volumes as the weights.
    #[default]
    MaterialPoints,
    /// The weights scaled to the cell's volume in cells the material fills.
    FilledCells,
}

impl Quadrature {
    /// The name in the case file.
    pub fn as_str(self) -> &'static str {
        match self {
            Quadrature::MaterialPoints => "material_points",
            Quadrature::FilledCells => "filled_cells",
        }
    }
}

/// The unknowns of a domain's elements (`domains[k].element_formulation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementFormulation {
    /// Nodal displacements only (the irreducible element).
    #[default]
    Displacement,
    /// Nodal displacements and pressures (mean Kirchhoff stress), equal order, stabilised by
    /// the polynomial pressure projection (Dohrmann & Bochev 2004).
    MixedUp,
}

impl ElementFormulation {
    /// The name in the case file.
    pub fn as_str(self) -> &'static str {
        match self {
            ElementFormulation::Displacement => "displacement",
            ElementFormulation::MixedUp => "mixed_up",
        }
    }
}

fn fem() -> DomainKind {
    DomainKind::Fem
}

/// Discretisation of a domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DomainKind {
    /// Lagrangian finite elements.
    Fem,
    /// Implicit material point method on a background grid.
    Mpm,
    /// A plane rigid body (`loam_fem::rigid_body`).
    Rigid,
}

impl DomainKind {
    /// The name in the case file.
    pub fn as_str(self) -> &'static str {
        match self {
            DomainKind::Fem => "fem",
            DomainKind::Mpm => "mpm",
            DomainKind::Rigid => "rigid",
        }
    }
}

/// What a `rigid_body` monitor measures: the centroid's `displacement` (m), `velocity`,
/// `acceleration` and the `reaction` (N) of its prescribed motion (the force that drives or
/// holds it), by component; the `rotation` (rad, counter-clockwise), `angular_velocity`,
/// `angular_acceleration` and the `reaction_moment` (N m) about the centroid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RigidQuantity {
    /// Centroid displacement.
    Displacement,
    /// Centroid velocity.
    Velocity,
    /// Centroid acceleration.
    Acceleration,
    /// Reaction force of the prescribed motion.
    Reaction,
    /// Rotation about the centroid.
    Rotation,
    /// Angular velocity.
    AngularVelocity,
    /// Angular acceleration.
    AngularAcceleration,
    /// Reaction moment of the prescribed rotation about the centroid.
    ReactionMoment,
}

impl RigidQuantity {
    /// Whether it is a vector of the centroid (with a component), not of the rotation.
    pub fn is_vector(self) -> bool {
        matches!(self, Self::Displacement | Self::Velocity | Self::Acceleration | Self::Reaction)
    }

    /// Unit in monitors.csv and the FMU's variables.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Displacement => "m",
            Self::Velocity => "m/s",
            Self::Acceleration => "m/s2",
            Self::Reaction => "N",
            Self::Rotation => "rad",
            Self::AngularVelocity => "rad/s",
            Self::AngularAcceleration => "rad/s2",
            Self::ReactionMoment => "N m",
        }
    }
}

/// The prescribed motion of a rigid domain (`domains[k].motion`): its centroid's
/// displacement and its rotation about the centroid, each entry a number (prescribed,
/// scaled by `amplitude`) or `null` / absent (free).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidMotionSpec {
    /// Displacement of the centroid (m), one entry per component, `null` for a free one
    /// (default: both free).
    #[serde(default)]
    pub displacement: Vec<Option<f64>>,
    /// Rotation about the centroid (rad, counter-clockwise); absent or `null`: free.
    #[serde(default)]
    pub rotation: Option<f64>,
    /// Time function scaling the prescribed values (default constant 1).
    #[serde(default)]
    pub amplitude: Amplitude,
}

/// An initial velocity field.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum InitialVelocity {
    /// The same velocity everywhere (m/s), one entry per component.
    Uniform(Vec<f64>),
    /// A mode shape `v(x) = amplitude · sin(wavenumber · x)`.
    Sine {
        /// Velocity amplitude (m/s), one entry per component.
        amplitude: Vec<f64>,
        /// Wave vector (rad/m), one entry per coordinate.
        wavenumber: Vec<f64>,
    },
}

impl InitialVelocity {
    /// Velocity at `x` (first `dim` components).
    pub fn at(&self, x: &[f64; 3], dim: usize) -> [f64; 3] {
        let mut v = [0.0; 3];
        match self {
            InitialVelocity::Uniform(u) => v[..dim].copy_from_slice(&u[..dim]),
            InitialVelocity::Sine { amplitude, wavenumber } => {
                let phase: f64 = (0..dim).map(|d| wavenumber[d] * x[d]).sum();
                for d in 0..dim {
                    v[d] = amplitude[d] * phase.sin();
                }
            }
        }
        v
    }
}

/// A structured MPM background grid.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Lowest corner (m), one entry per coordinate.
    pub origin: Vec<f64>,
    /// Extent (m), one entry per coordinate.
    pub size: Vec<f64>,
    /// Cells per direction.
    pub cells: Vec<usize>,
    /// `quad4` or `tri3` (2D), `hex8` (3D).
    pub element: ElementType,
    /// Counter-clockwise rotation of the grid about `origin` in degrees (2D; default 0):
    /// inclined grid boundaries, e.g. for slip on a slope.
    #[serde(default)]
    pub rotation: f64,
    /// Shape functions: `linear` (default: the cell's), `gimp` (uGIMP) or `bspline2`
    /// (quadratic B-splines), the smooth ones on unrotated quad4 grids in 2D without
    /// shared-node interfaces (`loam_mpm::basis`).
    #[serde(default)]
    pub basis: Basis,
}

/// Where an MPM body's material points are.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum BodySpec {
    /// At Gauss positions of the cells of a body mesh (as Kratos' body model part).
    Cells {
        /// The body mesh.
        mesh: MeshSpec,
        /// Points per cell: 1, 4, 9, 16 (quad4); 1, 8, 27, 64 (hex8); 1, 3 (tri3); 1, 4 (tet4).
        points_per_cell: usize,
    },
    /// On a square lattice inside a disk (2D).
    Disk {
        /// Centre (m).
        centre: [f64; 2],
        /// Radius (m).
        radius: f64,
        /// Lattice spacing (m).
        spacing: f64,
    },
    /// On a square lattice inside a polygon (2D, vertices in order).
    Polygon {
        /// Vertices (m).
        vertices: Vec<[f64; 2]>,
        /// Lattice spacing (m).
        spacing: f64,
    },
}

/// Mass matrix choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassMatrix {
    /// `∫ ρ N_a N_b dV`.
    #[default]
    Consistent,
    /// Row sums on the diagonal.
    Lumped,
}

/// A mesh: generated or read from a Gmsh file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSpec {
    /// Structured rectangle.
    Rectangle {
        /// Lower-left corner (m).
        origin: [f64; 2],
        /// Width and height (m).
        size: [f64; 2],
        /// Cells along x and y.
        cells: [usize; 2],
        /// `quad4` or `tri3`.
        element: ElementType,
        /// Rotation (degrees, counter-clockwise) of the rectangle about `origin` (default 0),
        /// e.g. an inclined slab in an axis-aligned grid.
        #[serde(default)]
        rotation: f64,
    },
    /// Structured box.
    Box {
        /// Lowest corner (m).
        origin: [f64; 3],
        /// Extent along x, y, z (m).
        size: [f64; 3],
        /// Cells along x, y, z.
        cells: [usize; 3],
        /// `hex8` or `tet4`.
        element: ElementType,
    },
    /// Gmsh MSH 4.1 file, path relative to the case file.
    Gmsh(PathBuf),
    /// Set by the model builder, not the case file: one row of quad4 cells along a polyline,
    /// on its right (the shape of a contact wall built as a rigid structure,
    /// `model_builder::walls`).
    #[serde(skip)]
    Strip {
        /// The polyline (m).
        vertices: Vec<[f64; 2]>,
        /// Width of the row (m), on the polyline's right.
        width: f64,
        /// Cells along each of its segments.
        cells: Vec<usize>,
    },
}

/// A named node set, selected geometrically or by a Gmsh physical group.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum RegionSpec {
    /// Nodes with `x = value`.
    X(f64),
    /// Nodes with `y = value`.
    Y(f64),
    /// Nodes with `z = value`.
    Z(f64),
    /// Nodes inside an axis-aligned box (bounds included).
    Box {
        /// Lower corner.
        min: Vec<f64>,
        /// Upper corner.
        max: Vec<f64>,
    },
    /// Nodes on the segment between two points.
    Segment {
        /// Start point.
        from: Vec<f64>,
        /// End point.
        to: Vec<f64>,
    },
    /// Nodes on a polyline (points in order, each one entry per coordinate), e.g. the faces
    /// of a structure that the soil touches.
    Polyline(Vec<Vec<f64>>),
    /// The single node nearest to a point.
    Nearest(Vec<f64>),
    /// A Gmsh physical group by name.
    Group(String),
    /// Every node.
    All(bool),
}

/// An interface between soil (an MPM domain's grid) and a structure (an FEM domain):
/// the boundary facets of the structure's mesh whose nodes all lie in `region`. The grid
/// must have a node at every node of the interface (its cells inside the structure are
/// removed); those nodes are shared (tied: soil and structure move together) or paired
/// (slip: only the normal component is shared, the soil slides freely along the
/// structure). At each step the grid follows the structure: interface nodes sit on it,
/// grid nodes within `band` of it move by the harmonic extension of its displacement,
/// the grid farther away stays in place.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceSpec {
    /// Name (messages, `interface_force` monitors).
    pub name: String,
    /// The MPM domain whose grid is the soil side (every body on that grid is coupled).
    pub soil: String,
    /// The FEM domain on the structure side.
    pub structure: String,
    /// Region (a key of `regions`) selecting the structure's interface nodes.
    pub region: String,
    /// Frictionless: share only the normal component (default false: tied, no slip).
    #[serde(default)]
    pub slip: bool,
    /// Width (m) of the band of grid nodes that moves with the structure (default 20 grid
    /// cells).
    #[serde(default)]
    pub band: Option<f64>,
    /// How soil and structure are joined (default shared nodes).
    #[serde(default)]
    pub coupling: InterfaceCoupling,
    /// Penalty β (Pa/m) of a tie, the normal penalty β_N of a contact (default
    /// `DEFAULT_TIE_PENALTY_FACTOR · E_soil / h`).
    #[serde(default)]
    pub penalty: Option<f64>,
    /// Tangential (stick) penalty β_T (Pa/m) of a contact with friction (default
    /// `DEFAULT_TANGENTIAL_PENALTY_FACTOR · E_soil / h`).
    #[serde(default)]
    pub tangential_penalty: Option<f64>,
    /// Coulomb coefficient μ ≥ 0 of a contact (default 0: frictionless).
    #[serde(default)]
    pub friction: Option<f64>,
    /// Augmented Lagrangian of a contact: the largest penetration (m) a converged step may
    /// leave; above it the contact pressures become multipliers and the step is solved again
    /// (absent: pure penalty, penetration `t_N/β_N`).
    #[serde(default)]
    pub gap_tolerance: Option<f64>,
}

/// How an interface joins soil and structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterfaceCoupling {
    /// The grid conforms to the structure and shares its interface nodes (its cells inside
    /// the structure removed, a band of it moving with the structure).
    #[default]
    SharedNodes,
    /// Non-conforming penalty tie: the structure's facets carry quadrature points tied to
    /// the soil interpolated on the fixed grid, which keeps all its cells
    /// (`loam_coupling::interface_points`).
    Tie,
    /// Non-conforming penalty contact, unilateral, frictionless or with Coulomb friction
    /// (`friction`): quadrature points like the tie's (`loam_coupling::interface_law`).
    Contact,
}

impl InterfaceCoupling {
    /// Whether the structure lies in a fixed grid and is joined to it by interface points
    /// (tie or contact), rather than by shared nodes.
    pub fn is_non_conforming(self) -> bool {
        matches!(self, InterfaceCoupling::Tie | InterfaceCoupling::Contact)
    }
}

/// Prescribed displacement on a region.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundaryConditionSpec {
    /// Optional name, by which an FMU input can drive it.
    #[serde(default)]
    pub name: Option<String>,
    /// Region name (not with `penalty`).
    #[serde(default)]
    pub region: String,
    /// One entry per component: a value in m, or `null` for a free component. With
    /// `penalty`: the wall's displacement (every component a number), scaled by `amplitude`.
    #[serde(default)]
    pub displacement: Vec<Option<f64>>,
    /// Instead of `displacement`: frictionless slip (no motion along the boundary normal).
    #[serde(default)]
    pub slip: Option<SlipSpec>,
    /// Instead of `region`: a rigid wall anywhere in an MPM grid, enforced by penalty on
    /// boundary particles (non-conforming Dirichlet condition).
    #[serde(default)]
    pub penalty: Option<PenaltySpec>,
    /// Time function scaling the values (default constant 1).
    #[serde(default)]
    pub amplitude: Amplitude,
    /// Set by the model builder, not the case file: this contact wall (`penalty.contact`) is
    /// built as a rigid structure with a contact interface (`model_builder::walls`).
    #[serde(skip)]
    pub as_rigid_wall: bool,
}

/// A non-conforming rigid wall on an MPM background grid: in the Dirichlet form (Chandra et
/// al. 2021) boundary particles along a segment or polyline add `β w N_I N_J` (no-slip) or
/// `β w N_I N_J n⊗n` (slip) to the grid nodes of the cells they lie in, where those cells
/// hold material (`loam_mpm::penalty_boundary`); in the contact form it is a rigid structure
/// held or moved by the wall's motion, with a non-conforming contact on its face
/// (`model_builder::walls`, issue 25).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    /// MPM domain whose background grid carries the wall (default: the only MPM domain);
    /// the wall acts on every body on that grid.
    #[serde(default)]
    pub domain: Option<String>,
    /// The wall from its first point to its second (m, 2D); the body lies on its left.
    #[serde(default)]
    pub segment: Option<[[f64; 2]; 2]>,
    /// Instead of `segment`: a polyline (m, 2D), the body on its left.
    #[serde(default)]
    pub polyline: Option<Vec<[f64; 2]>>,
    /// Distance between boundary particles along the wall (m), e.g. a quarter of a cell
    /// (Dirichlet form only).
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Penalty factor β (N/m³; Chandra et al. use 1e13 for E = 200 MPa).
    pub penalty_factor: f64,
    /// Frictionless: hold only the normal component (default false: no-slip).
    #[serde(default)]
    pub slip: bool,
    /// Contact form: unilateral, for bodies that leave the wall, roll or slide on it, built as
    /// a rigid structure with a contact interface `<name>_contact` (default false: the
    /// bilateral Dirichlet form).
    #[serde(default)]
    pub contact: bool,
    /// Coulomb friction coefficient μ of a contact wall (instead of `slip`, which is μ = 0,
    /// and of the default no-slip): stick while the tangential force stays within μ times
    /// the normal one, slide at that limit (`loam_coupling::interface_law`).
    #[serde(default)]
    pub friction: Option<f64>,
}

/// A slip boundary: frictionless, or with Coulomb friction ([`loam_fem::friction`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlipSpec {
    /// Boundary normal; by default the mean normal of the boundary edges/faces in the region.
    #[serde(default)]
    pub normal: Option<Vec<f64>>,
    /// Coulomb coefficient μ_b of the boundary (default 0, frictionless): stick while the
    /// tangential force is within μ_b times the normal reaction, slide otherwise.
    #[serde(default)]
    pub friction: f64,
}

/// A load on a region.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LoadSpec {
    /// The same force (N) on every node of the region.
    NodalForce {
        /// Optional name, by which an FMU input can drive it.
        #[serde(default)]
        name: Option<String>,
        /// Region name.
        region: String,
        /// Force vector in N, one entry per component.
        force: Vec<f64>,
        /// Time function.
        #[serde(default)]
        amplitude: Amplitude,
    },
    /// Pressure (Pa, positive pushing into the body) on the boundary facets of the region.
    Pressure {
        /// Optional name, by which an FMU input can drive it.
        #[serde(default)]
        name: Option<String>,
        /// Region name.
        region: String,
        /// Pressure in Pa.
        pressure: f64,
        /// Time function.
        #[serde(default)]
        amplitude: Amplitude,
    },
    /// A force (N) on material points, carried with them as the body moves (particle
    /// Neumann condition): the point nearest to `point`, or every point inside `box`, at the
    /// start; each adds `N_I(x_p) force` to the grid nodes of its cell at every step.
    MaterialPointForce {
        /// MPM domain whose points carry the force (default: any MPM domain).
        #[serde(default)]
        domain: Option<String>,
        /// Location (m); give `point` or `box`.
        #[serde(default)]
        point: Option<Vec<f64>>,
        /// Box (m) whose material points each carry `force`; give `point` or `box`.
        #[serde(default, rename = "box")]
        within: Option<PointBox>,
        /// Force per material point in N, one entry per component.
        force: Vec<f64>,
        /// Time function (evaluated at the end of each step).
        #[serde(default)]
        amplitude: Amplitude,
    },
    /// Traction vector (Pa) on the boundary facets of the region.
    Traction {
        /// Optional name, by which an FMU input can drive it.
        #[serde(default)]
        name: Option<String>,
        /// Region name.
        region: String,
        /// Traction in Pa, one entry per component.
        traction: Vec<f64>,
        /// Time function.
        #[serde(default)]
        amplitude: Amplitude,
    },
}

impl LoadSpec {
    /// The load's optional name.
    pub fn name(&self) -> Option<&str> {
        match self {
            LoadSpec::NodalForce { name, .. } | LoadSpec::Pressure { name, .. } | LoadSpec::Traction { name, .. } => {
                name.as_deref()
            }
            LoadSpec::MaterialPointForce { .. } => None,
        }
    }
}

/// Gravity acceleration and its time function.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    /// Acceleration in m/s², one entry per component (e.g. `[0, -9.81]`).
    pub acceleration: Vec<f64>,
    /// Time function (default constant 1: gravity applied suddenly).
    #[serde(default)]
    pub amplitude: Amplitude,
}

/// Analysis type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisType {
    /// Equilibrium, load stepping in pseudo-time.
    Static,
    /// Equilibrium without inertia at each time of a slow process.
    QuasiStatic,
    /// Equations of motion (Newmark or Bossak).
    Dynamic,
}

impl AnalysisType {
    /// The name in the case file.
    pub fn as_str(self) -> &'static str {
        match self {
            AnalysisType::Static => "static",
            AnalysisType::QuasiStatic => "quasi_static",
            AnalysisType::Dynamic => "dynamic",
        }
    }
}

/// Time stepping.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSpec {
    /// `static`, `quasi_static` or `dynamic`.
    #[serde(rename = "type")]
    pub kind: AnalysisType,
    /// Step Δt in s (pseudo-time for static analyses).
    pub time_step: f64,
    /// End time in s.
    pub end_time: f64,
    /// Dynamic scheme (default Newmark β = 0.25, γ = 0.5).
    #[serde(default)]
    pub scheme: Option<TimeScheme>,
    /// How many times a failed step is halved before the run stops (default 4).
    #[serde(default = "default_cuts")]
    pub max_step_cuts: u32,
    /// Adaptive step control: `time_step` is the first step, later steps grow or shrink
    /// with the Newton effort (absent: every step is `time_step`, cut only on failure).
    #[serde(default)]
    pub adaptive: Option<AdaptiveSpec>,
    /// End the run before `end_time` once the bodies are at rest.
    #[serde(default)]
    pub stop_at_rest: Option<RestSpec>,
    /// Periodic checkpoints of `loam run` (`DIR/checkpoints/step_<k>.ckpt`), from which
    /// `loam run --resume` continues.
    #[serde(default)]
    pub checkpoint: Option<CheckpointSpec>,
}

/// When `loam run` writes checkpoints (`analysis.checkpoint`): every `every_steps` steps
/// and/or every `every_seconds` of wall time (whichever comes first), keeping the newest
/// `keep`. An interrupted run writes one whatever this says.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointSpec {
    /// Steps between checkpoints.
    #[serde(default)]
    pub every_steps: Option<usize>,
    /// Wall-clock seconds between checkpoints.
    #[serde(default)]
    pub every_seconds: Option<f64>,
    /// How many checkpoints to keep (default 2).
    #[serde(default = "default_keep")]
    pub keep: usize,
}

fn default_keep() -> usize {
    2
}

fn default_cuts() -> u32 {
    4
}

/// Initial stress of an MPM body (`domains[k].initial_stress`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum InitialStressSpec {
    /// Geostatic state under the case's gravity (along −y in 2D, −z in 3D): vertical stress
    /// `σ_v = −ρ g (surface − y)` below the free surface at height `surface`, horizontal
    /// stresses `K0 σ_v` (tension positive). `K0 = 1 − sin φ` (Jaky) is the usual choice for
    /// normally consolidated soil.
    Geostatic {
        /// Height of the free surface (m).
        surface: f64,
        /// Coefficient of lateral earth pressure at rest.
        k0: f64,
    },
}

/// Adaptive step control (`analysis.adaptive`): after a converged step with `k` Newton
/// iterations the next step is `Δt · clamp(√(target_iterations / k), 1/2, growth)`, limited
/// to `[min_time_step, max_time_step]`; a failed step is halved down to `min_time_step`.
/// With `error_tolerance` the step's local time-integration error `η` sets the factor
/// instead and the iterations can only shorten the step: `0.9 (tol/η)^(1/3)`, or the smaller
/// of it and `√(target_iterations / k)` when `k > target_iterations`, clamped to
/// `[1/2, growth]` and the step limits.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveSpec {
    /// Smallest step in s (a step failing at it stops the run).
    pub min_time_step: f64,
    /// Largest step in s.
    pub max_time_step: f64,
    /// Newton iterations per step aimed at (default 6).
    #[serde(default = "default_target_iterations")]
    pub target_iterations: usize,
    /// Largest growth factor from one step to the next (default 1.5).
    #[serde(default = "default_growth")]
    pub growth: f64,
    /// Local time-integration error aimed at per step (m, root mean square over the moving
    /// DOFs; Zienkiewicz & Xie's estimate, [`loam_fem::model::TimeError`]). When given, the
    /// step length follows it (`Δt · 0.9 (tol/η)^(1/3)`) and `target_iterations` only
    /// shortens steps whose Newton iterations exceed it; when absent (default), the
    /// iteration count alone sets the step.
    #[serde(default)]
    pub error_tolerance: Option<f64>,
}

fn default_target_iterations() -> usize {
    6
}

fn default_growth() -> f64 {
    1.5
}

/// When a run may end early at rest (`analysis.stop_at_rest`): after `min_time`, once the
/// total kinetic energy has stayed below `kinetic_energy_ratio` × its peak for `duration`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestSpec {
    /// Kinetic energy relative to the run's peak below which the bodies count as at rest
    /// (default 1e-3).
    #[serde(default = "default_rest_ratio")]
    pub kinetic_energy_ratio: f64,
    /// How long (s) the kinetic energy must stay below the threshold (default 0.05).
    #[serde(default = "default_rest_duration")]
    pub duration: f64,
    /// No early end before this time (s, default 0).
    #[serde(default)]
    pub min_time: f64,
}

fn default_rest_ratio() -> f64 {
    1e-3
}

fn default_rest_duration() -> f64 {
    0.05
}

/// Output settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Write VTK every this many steps (default 1; 0 writes only the last state).
    pub interval: usize,
    /// Whether to write VTK files at all (default true).
    pub vtk: bool,
    /// Instead of `interval`: write VTK whenever the time passes a multiple of this (s);
    /// the natural choice with adaptive steps.
    pub time_interval: Option<f64>,
    /// Also write the MPM background grids (`<domain>_grid.pvd`) with nodal mass,
    /// displacement increment, velocity, acceleration and active flag (default false).
    pub grid: bool,
    /// Write VTK at exactly these times (s, increasing; e.g. the instants of a published
    /// sequence of snapshots): steps are shortened to land on them. With `times`, `interval`
    /// is not used; `time_interval` may be combined with it.
    pub times: Vec<f64>,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { interval: 1, vtk: true, time_interval: None, grid: false, times: Vec::new() }
    }
}

/// A vector component by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    /// x (or r).
    X,
    /// y (or z in axisymmetry).
    Y,
    /// z.
    Z,
    /// Euclidean norm.
    Magnitude,
}

/// A component of a symmetric tensor, or an invariant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TensorComponent {
    /// σ_xx (σ_rr in axisymmetry).
    Xx,
    /// σ_yy (σ_zz in axisymmetry).
    Yy,
    /// σ_zz (out of plane; σ_θθ in axisymmetry).
    Zz,
    /// σ_xy.
    Xy,
    /// σ_yz.
    Yz,
    /// σ_xz.
    Xz,
    /// Mean stress tr σ / 3 (tension positive).
    Mean,
    /// Von Mises stress √(3/2 s:s).
    VonMises,
}

/// An axis-aligned box of material points (bounds included).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointBox {
    /// Lower corner (m), one entry per coordinate.
    pub min: Vec<f64>,
    /// Upper corner (m), one entry per coordinate.
    pub max: Vec<f64>,
}

/// A named scalar time history.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MonitorSpec {
    /// Displacement component of the node nearest to `point`.
    Displacement {
        /// Column name.
        name: String,
        /// Location (m).
        point: Vec<f64>,
        /// Component.
        component: Component,
        /// Factor applied to the value (default 1), e.g. `-1/(B s_u)` for a normalised
        /// bearing pressure, or `-1` for a settlement.
        #[serde(default = "one")]
        scale: f64,
    },
    /// Velocity component of the node nearest to `point`.
    Velocity {
        /// Column name.
        name: String,
        /// Location (m).
        point: Vec<f64>,
        /// Component.
        component: Component,
    },
    /// Acceleration component of the node nearest to `point`.
    Acceleration {
        /// Column name.
        name: String,
        /// Location (m).
        point: Vec<f64>,
        /// Component.
        component: Component,
    },
    /// Sum of the reaction forces (N) over a region.
    Reaction {
        /// Column name.
        name: String,
        /// Region name.
        region: String,
        /// Component.
        component: Component,
        /// Factor applied to the value (default 1), e.g. `-1/(B s_u)` for a normalised
        /// bearing pressure, or `-1` for a settlement.
        #[serde(default = "one")]
        scale: f64,
    },
    /// Displacement component of the material point nearest to `point` at the start.
    MaterialPointDisplacement {
        /// Column name.
        name: String,
        /// Location (m).
        point: Vec<f64>,
        /// Component.
        component: Component,
        /// Factor applied to the value (default 1), e.g. `-1/(B s_u)` for a normalised
        /// bearing pressure, or `-1` for a settlement.
        #[serde(default = "one")]
        scale: f64,
    },
    /// Velocity component of the material point nearest to `point` at the start.
    MaterialPointVelocity {
        /// Column name.
        name: String,
        /// Location (m).
        point: Vec<f64>,
        /// Component.
        component: Component,
    },
    /// A Cauchy stress component (Pa, tension positive) of the material point nearest to
    /// `point` at the start, or the mean over the material points inside `box` at the start.
    MaterialPointStress {
        /// Column name.
        name: String,
        /// Location (m); give `point` or `box`.
        #[serde(default)]
        point: Option<Vec<f64>>,
        /// Box (m) whose material points are averaged; give `point` or `box`.
        #[serde(default, rename = "box")]
        within: Option<PointBox>,
        /// Component.
        component: TensorComponent,
    },
    /// Runout of material points (m) from a wall at `x = wall` towards `+x`: where the free
    /// surface (top envelope of the points' squares) falls below `threshold` above the
    /// base line `y = base` (plane problems; Bui et al. 2008 use 2 mm), or with `"measure":
    /// "thickness"` where the deposit's thickness from the points' areas in bins of `bin`
    /// falls to `threshold` ([`RunoutMeasure`]).
    Runout {
        /// Column name.
        name: String,
        /// x of the wall (m, default 0).
        #[serde(default)]
        wall: f64,
        /// y of the base (m, default 0).
        #[serde(default)]
        base: f64,
        /// Surface height (or thickness) below which the body has ended (m, default 0.002).
        #[serde(default = "default_runout_threshold")]
        threshold: f64,
        /// How the end is read (default `surface`).
        #[serde(default)]
        measure: RunoutMeasure,
        /// Width of the bins along x of `"measure": "thickness"` (m; required there, refused
        /// otherwise).
        #[serde(default)]
        bin: Option<f64>,
        /// Depth across y over which the points' volumes spread, in 3D with `"measure":
        /// "thickness"` (m; required there, refused otherwise).
        #[serde(default)]
        depth: Option<f64>,
    },
    /// Height (m) of the material points' free surface above the base line `y = base` at
    /// abscissa `x` (plane problems), e.g. the height at a wall.
    SurfaceHeight {
        /// Column name.
        name: String,
        /// Abscissa (m).
        x: f64,
        /// y of the base (m, default 0).
        #[serde(default)]
        base: f64,
    },
    /// Sum of the forces (N) a penalty wall (`boundary_conditions[k].penalty`) exerts on the
    /// bodies: its reaction, with the opposite sign.
    WallForce {
        /// Column name.
        name: String,
        /// The wall's boundary-condition `name` (default `penalty_<k>`).
        wall: String,
        /// Component.
        component: Component,
        /// Factor applied to the value (default 1), e.g. `-1/(B s_u)` for a normalised
        /// bearing pressure, or `-1` for a settlement.
        #[serde(default = "one")]
        scale: f64,
    },
    /// Total current volume (m³) of the material points inside `box` (every point if
    /// absent), `Σ_p V_p` with `V_p = J_p V_p⁰` the bulk volume the law carries: per unit
    /// thickness × thickness in plane problems, the full ring (2πr) in axisymmetry. Its
    /// rate of change includes the dilation of the material in the box: a discharge rate is
    /// better taken from `material_mass` divided by the bulk density.
    MaterialVolume {
        /// Column name.
        name: String,
        /// Box (m) in which points are counted at each step (their current position).
        #[serde(default, rename = "box")]
        within: Option<PointBox>,
    },
    /// Total mass (kg) of the material points inside `box` (every point if absent), same
    /// conventions as `material_volume`.
    MaterialMass {
        /// Column name.
        name: String,
        /// Box (m) in which points are counted at each step (their current position).
        #[serde(default, rename = "box")]
        within: Option<PointBox>,
    },
    /// The force (N) that the soil exerts on the structure across an interface: minus the
    /// soil's residual (internal force, weight and inertia of the soil's cells) summed over
    /// the interface nodes. At rest it balances the structure's reactions and loads.
    InterfaceForce {
        /// Column name.
        name: String,
        /// Interface name.
        interface: String,
        /// Component.
        component: Component,
        /// Factor applied to the value (default 1), e.g. `-1/(B s_u)` for a normalised
        /// bearing pressure, or `-1` for a settlement.
        #[serde(default = "one")]
        scale: f64,
    },
    /// The motion of a rigid domain (`type` `rigid`) or the reaction of its prescribed
    /// motion: `quantity` of its centroid (with `component`) or of its rotation about it.
    RigidBody {
        /// Column name.
        name: String,
        /// The rigid domain's name.
        domain: String,
        /// What to measure.
        quantity: RigidQuantity,
        /// Component of `displacement`, `velocity`, `acceleration` and `reaction` (not of
        /// the rotational quantities).
        #[serde(default)]
        component: Option<Component>,
        /// Factor applied to the value (default 1).
        #[serde(default = "one")]
        scale: f64,
    },
    /// Total kinetic energy (J), of every domain or of the domain (FEM domain or MPM body)
    /// named `domain`.
    KineticEnergy {
        /// Column name.
        name: String,
        /// Domain or body (default: all).
        #[serde(default)]
        domain: Option<String>,
    },
    /// Linear momentum `∫ ρ v dV` (kg m/s; per unit thickness in plane problems), of every
    /// domain or of the domain (FEM domain or MPM body) named `domain`: with an
    /// `interface_force` monitor, the impulse balance of a structure or a body.
    Momentum {
        /// Column name.
        name: String,
        /// Domain or body (default: all).
        #[serde(default)]
        domain: Option<String>,
        /// Component.
        component: Component,
    },
    /// Total stored work of internal forces (J): the strain energy for elastic laws; of
    /// every domain or of the domain (FEM domain or MPM body) named `domain`.
    StrainEnergy {
        /// Column name.
        name: String,
        /// Domain or body (default: all).
        #[serde(default)]
        domain: Option<String>,
    },
}

impl MonitorSpec {
    /// The factor applied to the monitor's value (`scale`, 1 where the monitor has none).
    pub fn scale(&self) -> f64 {
        match self {
            MonitorSpec::Displacement { scale, .. }
            | MonitorSpec::Reaction { scale, .. }
            | MonitorSpec::MaterialPointDisplacement { scale, .. }
            | MonitorSpec::WallForce { scale, .. }
            | MonitorSpec::InterfaceForce { scale, .. }
            | MonitorSpec::RigidBody { scale, .. } => *scale,
            _ => 1.0,
        }
    }

    /// The monitor's column name.
    pub fn name(&self) -> &str {
        match self {
            MonitorSpec::Displacement { name, .. }
            | MonitorSpec::Velocity { name, .. }
            | MonitorSpec::Acceleration { name, .. }
            | MonitorSpec::Reaction { name, .. }
            | MonitorSpec::MaterialPointDisplacement { name, .. }
            | MonitorSpec::MaterialPointVelocity { name, .. }
            | MonitorSpec::MaterialPointStress { name, .. }
            | MonitorSpec::Runout { name, .. }
            | MonitorSpec::SurfaceHeight { name, .. }
            | MonitorSpec::WallForce { name, .. }
            | MonitorSpec::MaterialVolume { name, .. }
            | MonitorSpec::MaterialMass { name, .. }
            | MonitorSpec::InterfaceForce { name, .. }
            | MonitorSpec::RigidBody { name, .. }
            | MonitorSpec::KineticEnergy { name, .. }
            | MonitorSpec::Momentum { name, .. }
            | MonitorSpec::StrainEnergy { name, .. } => name,
        }
    }
}

/// How a `runout` monitor reads the end of the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunoutMeasure {
    /// The connected stretch from the wall where the points' squares stand `threshold` above
    /// the base, joined across gaps up to half a point's size
    /// ([`loam_mpm::surface::SurfaceProfile::runout`]).
    #[default]
    Surface,
    /// Where the deposit's thickness, the points' areas summed in bins of `bin` along x and
    /// divided by it (in 3D their volumes over the bin and `depth`), falls
    /// to `threshold` ([`loam_mpm::surface::runout_of_thickness`]): independent of how the
    /// points are stacked, so that a sheet one or two points thick at a front does not make
    /// it jump.
    Thickness,
}

fn default_runout_threshold() -> f64 {
    0.002
}

/// The variables a case exposes as an FMU (FMI 3.0 co-simulation), and the named inputs
/// of the library API.
///
/// An input *replaces the amplitude factor* of its target while it is set: a load's
/// forces become `forces · value`, a boundary condition's prescribed displacements
/// `displacement · value`, gravity `acceleration · value`. Declare the target with unit
/// magnitude (e.g. `"force": [0, -1]`, `"displacement": [null, 1]`) to make the input
/// the force in N or the displacement in m. A value holds until the next
/// [`crate::simulation::Simulation::set_input`] (zero-order hold); until the first one,
/// the target's own `amplitude` applies. The FMU sets every input to its `start` when
/// it is instantiated or reset.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuSpec {
    /// Inputs (FMI causality `input`).
    #[serde(default)]
    pub inputs: Vec<FmuInputSpec>,
    /// Outputs (FMI causality `output`); absent means every monitor, named as the monitor.
    #[serde(default)]
    pub outputs: Option<Vec<FmuOutputSpec>>,
}

/// A named input.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuInputSpec {
    /// Variable name (unique among inputs and outputs, not `time`).
    pub name: String,
    /// What the input drives: `{"load": NAME}`, `{"boundary_condition": NAME}` or
    /// `"gravity"`.
    pub drives: InputTarget,
    /// Unit of the value, e.g. `N`, `m` or `1` (default `1`: a factor).
    #[serde(default)]
    pub unit: Option<String>,
    /// Value the FMU starts with (FMI `start`).
    pub start: f64,
    /// What the input means.
    #[serde(default)]
    pub description: Option<String>,
}

/// What an input drives.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum InputTarget {
    /// The factor of the load with this `name`.
    Load(String),
    /// The factor of the prescribed displacements of the boundary condition with this
    /// `name`.
    BoundaryCondition(String),
    /// The factor of the prescribed `motion` of the rigid domain with this name.
    Motion(String),
    /// The gravity factor.
    Gravity,
}

/// A named output: the value of a monitor.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuOutputSpec {
    /// Variable name (unique among inputs and outputs, not `time`).
    pub name: String,
    /// Monitor name (default: the output's name).
    #[serde(default)]
    pub monitor: Option<String>,
    /// Unit (default: the monitor's SI unit).
    #[serde(default)]
    pub unit: Option<String>,
    /// What the output means.
    #[serde(default)]
    pub description: Option<String>,
}

impl Case {
    /// Reads and parses a case file (at most [`crate::input::MAX_JSON_FILE_BYTES`]); syntax
    /// and type errors name the JSON path, syntax errors also the file, line and column.
    pub fn load(path: &Path) -> Result<Case, CaseError> {
        let text = crate::input::read_json_text(path, "case file")?;
        let mut case = Case::parse(&text).map_err(|mut e| {
            if e.location.is_empty() {
                e.location = path.display().to_string();
            } else if e.location.starts_with("line") {
                e.location = format!("{}:{}", path.display(), e.location);
            }
            e
        })?;
        case.directory = path.parent().map(Path::to_path_buf).unwrap_or_default();
        case.name = output_name(&path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
        Ok(case)
    }

    /// Parses case JSON text strictly (duplicate keys and text after the object are
    /// refused; see [`crate::input`]). A missing top-level key has the location `""`.
    pub fn parse(text: &str) -> Result<Case, CaseError> {
        let mut value = crate::input::parse_value(text)?;
        crate::input::check_object(&value)?;
        let petsc_options = take_petsc_options(&mut value)?;
        let mut case: Case = crate::input::from_value(&value)?;
        case.petsc_options = petsc_options;
        case.check_given_keys(&value)?;
        Ok(case)
    }

    /// Keys that are wrong by their mere presence (their defaults cannot tell).
    fn check_given_keys(&self, value: &serde_json::Value) -> Result<(), CaseError> {
        if value.get("thickness").is_some()
            && matches!(self.formulation, Formulation::ThreeD | Formulation::Axisymmetric)
        {
            return Err(CaseError::new(
                "thickness",
                format!(
                    "does not apply to the {} formulation (only plane_strain and plane_stress take a thickness)",
                    self.formulation.name()
                ),
            ));
        }
        Ok(())
    }
}

/// Takes `solver.petsc_options` out of the case's JSON (the rest of `solver` is read as
/// [`NewtonSettings`]): an object of PETSc option names, with or without the leading `-`,
/// and their values (a string or a number; `true` or `null` for a flag, `false` as the
/// value `false`).
fn take_petsc_options(value: &mut serde_json::Value) -> Result<PetscOptions, CaseError> {
    let Some(given) = value.get_mut("solver").and_then(|s| s.as_object_mut()).and_then(|s| s.remove("petsc_options"))
    else {
        return Ok(PetscOptions::default());
    };
    let serde_json::Value::Object(map) = given else {
        return Err(CaseError::new(
            "solver.petsc_options",
            "must be an object of PETSc options, e.g. {\"-ksp_type\": \"bcgs\", \"-pc_type\": \"hypre\"}",
        ));
    };
    let mut options = Vec::with_capacity(map.len());
    for (key, v) in map {
        let name = key.trim();
        let bare = name.trim_start_matches('-');
        if bare.is_empty() || bare.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(CaseError::new(
                format!("solver.petsc_options.{key}"),
                "is not a PETSc option name (e.g. \"-ksp_type\")",
            ));
        }
        let value = match v {
            serde_json::Value::String(s) => Some(s),
            serde_json::Value::Number(n) => Some(n.to_string()),
            serde_json::Value::Bool(true) | serde_json::Value::Null => None,
            serde_json::Value::Bool(false) => Some("false".to_string()),
            _ => {
                return Err(CaseError::new(
                    format!("solver.petsc_options.{key}"),
                    "must be a string, a number, true or null (a flag)",
                ))
            }
        };
        options.push((format!("-{bare}"), value));
    }
    Ok(PetscOptions { options })
}

/// The case's name for output files (`<case>.pvd`, the default `out/<case>`) from its file
/// stem: characters that a file name must not carry (path separators, control characters,
/// `<>:"|?*`) become `_`, and a stem that is empty or starts with `.` is prefixed with
/// `case` (a case file named `...json` must not send the output to `out/..`).
pub fn output_name(stem: &str) -> String {
    let mut name: String =
        stem.chars().map(|c| if c.is_control() || "/\\<>:\"|?*".contains(c) { '_' } else { c }).collect();
    if name.is_empty() || name.starts_with('.') {
        name.insert_str(0, "case");
    }
    name
}
