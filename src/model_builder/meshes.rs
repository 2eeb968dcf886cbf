//! Meshes, background grids and their bodies of material points, the interfaces that attach
//! grids to structures, and the one global node set with the role of every node.
//!
//! Node numbering follows the roles, not the coordinates alone: FEM meshes share the nodes
//! they have at the same position (a multi-material structure); MPM domains whose grids are
//! specified identically are bodies on one grid; a grid node is a structure node only where
//! an interface says so (tied), or the partner of one (slip). Any other contact between an
//! FEM mesh and a grid is refused (`loam_coupling::interface`), but for a non-conforming tie
//! (`"coupling": "tie"`), whose structure lies in the grid, keeps its own nodes and is
//! joined to the soil by a [`InterfacePoints`] placed after every part.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use loam_coupling::interface::{self as coupling, InterfaceNode, InterfaceRequest, InterfaceSummary, Structure};
use loam_coupling::interface_law::InterfaceLaw;
use loam_coupling::interface_points::{
    self, InterfaceFacet, InterfacePoints, DEFAULT_TANGENTIAL_PENALTY_FACTOR, DEFAULT_TIE_PENALTY_FACTOR,
};
use loam_fem::dofs::NodeRole;
use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::gmsh::{GmshError, GmshLimits};
use loam_fem::mesh::Mesh;
use loam_fem::model::Model;
use loam_fem::rigid_body::{self, RigidBody, RigidFrame};
use loam_fem::solid_domain::FemDomain;
use loam_laws::{ConstitutiveLaw, Kinematics, TangentRequest};
use loam_mpm::body::{Body, VelocityBlend};
use loam_mpm::grid::Grid;
use loam_mpm::material_points::{self, MaterialPoints};
use loam_mpm::mpm_domain::{young_modulus, MpmDomain};
use loam_mpm::quadrature::PointQuadrature;
use nalgebra::Matrix3;

use super::regions::{line_tolerance, select_region};
use super::{check_len, check_positive, unknown_name};
use crate::case::{
    AnalysisType, BodySpec, Case, CaseError, DomainKind, ElementFormulation, GridSpec, InitialStressSpec,
    InitialVelocity, InterfaceCoupling, MassMatrix, MeshSpec, Quadrature, DEFAULT_GHOST_PENALTY,
};

/// A part of the model: an FEM domain, or a grid with its bodies.
pub(super) enum Part {
    /// An FEM domain (case index, domain).
    Fem(usize, Box<FemDomain>),
    /// A background grid.
    Grid(Box<GridPart>),
    /// A rigid body (case index, domain).
    Rigid(usize, Box<RigidBody>),
}

/// A background grid with its bodies, as an MPM domain.
pub(super) struct GridPart {
    /// The domain (grid, bodies, later walls and attachment).
    pub domain: MpmDomain,
    /// Case indices of its bodies, in order.
    pub bodies: Vec<usize>,
    /// Where it touches structures, if an interface attaches it.
    pub coupling: Option<GridCoupling>,
}

/// A grid's interface nodes.
pub(super) struct GridCoupling {
    /// Per grid node: on which interface, and the global node of the structure there.
    pub on_interface: Vec<Option<(InterfaceNode, usize)>>,
    /// Indices (into the case's interfaces) of the interfaces on this grid.
    pub interfaces: Vec<usize>,
}

/// An interface after numbering.
pub(super) struct ResolvedInterface {
    /// What `loam check` reports.
    pub summary: InterfaceSummary,
    /// Index of the grid's part (while numbering: the case index of its first body).
    pub part: usize,
    /// Global nodes where the soil's force on the structure acts (tied: the shared nodes;
    /// slip: the soil's partner nodes).
    pub soil_nodes: Vec<usize>,
}

/// Everything numbered: global nodes with roles, Gmsh groups, parts, interfaces.
pub(super) struct Discretisation {
    pub coords: Vec<[f64; 3]>,
    pub roles: Vec<NodeRole>,
    pub groups: BTreeMap<String, Vec<usize>>,
    pub parts: Vec<Part>,
    pub interfaces: Vec<ResolvedInterface>,
    /// The non-conforming ties, placed after every part (their initialisation phase reads
    /// what their grid's soil reaches).
    pub ties: Vec<InterfacePoints>,
    /// Where each rigid domain's unknowns are, by domain name.
    pub rigid_frames: BTreeMap<String, RigidFrame>,
    /// What `loam check` reports of each rigid domain.
    pub rigid_bodies: Vec<RigidSummary>,
}

/// A rigid domain as `loam check` reports it.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidSummary {
    /// Domain name.
    pub name: String,
    /// Mass (kg, over the plane thickness or the full ring) and moment of inertia about the
    /// centroid (kg m²).
    pub mass: f64,
    /// Moment of inertia about the centroid (kg m²).
    pub inertia: f64,
    /// Centroid (m).
    pub centre: [f64; 2],
    /// Which unknowns `motion` prescribes (`u_x`, `u_y`, `θ`).
    pub held: [bool; 3],
}

/// A non-conforming tie of a grid, before numbering.
struct TieRequest {
    /// Case index of the interface.
    interface: usize,
    /// Case index of the structure.
    structure: usize,
    /// Its facets (the structure mesh's numbering) and their length.
    facets: Vec<[usize; 2]>,
    length: f64,
}

/// How a grid is specified: domains with equal specs share the grid.
#[derive(PartialEq)]
enum GridKey<'a> {
    Structured(&'a GridSpec),
    Mesh(&'a MeshSpec),
}

/// A grid before numbering, with its bodies' points.
struct GridGroup<'a> {
    key: GridKey<'a>,
    grid: Grid,
    /// (case index, points) of each body.
    bodies: Vec<(usize, MaterialPoints)>,
    coupled: Option<coupling::CoupledGrid>,
    /// Case indices of the structures of `coupled.on_interface[..].structure`.
    structures: Vec<usize>,
    interfaces: Vec<usize>,
    ties: Vec<TieRequest>,
}

/// Builds the mesh described by `spec` (at JSON path `loc`).
pub(crate) fn build_mesh(case: &Case, loc: &str, spec: &MeshSpec) -> Result<Mesh, CaseError> {
    let dim = case.formulation.dim();
    let mesh = match spec {
        MeshSpec::Rectangle { origin, size, cells, element, rotation } => {
            for (i, s) in size.iter().enumerate() {
                check_positive(&format!("{loc}.rectangle.size[{i}]"), *s)?;
            }
            if cells.contains(&0) {
                return Err(CaseError::new(
                    format!("{loc}.rectangle.cells"),
                    "needs at least one cell in each direction",
                ));
            }
            if element.dim() != 2 {
                return Err(CaseError::new(format!("{loc}.rectangle.element"), "a rectangle takes quad4 or tri3"));
            }
            check_block_size(case, &format!("{loc}.rectangle.cells"), cells, *element)?;
            if !rotation.is_finite() {
                return Err(CaseError::new(format!("{loc}.rectangle.rotation"), "must be a finite angle in degrees"));
            }
            let mut mesh = Mesh::rectangle(*origin, *size, *cells, *element);
            if *rotation != 0.0 {
                let (sin, cos) = rotation.to_radians().sin_cos();
                for x in &mut mesh.coords {
                    let (dx, dy) = (x[0] - origin[0], x[1] - origin[1]);
                    x[0] = origin[0] + cos * dx - sin * dy;
                    x[1] = origin[1] + sin * dx + cos * dy;
                }
            }
            mesh
        }
        MeshSpec::Box { origin, size, cells, element } => {
            for (i, s) in size.iter().enumerate() {
                check_positive(&format!("{loc}.box.size[{i}]"), *s)?;
            }
            if cells.contains(&0) {
                return Err(CaseError::new(format!("{loc}.box.cells"), "needs at least one cell in each direction"));
            }
            if element.dim() != 3 {
                return Err(CaseError::new(format!("{loc}.box.element"), "a box takes hex8 or tet4"));
            }
            check_block_size(case, &format!("{loc}.box.cells"), cells, *element)?;
            Mesh::cuboid(*origin, *size, *cells, *element)
        }
        MeshSpec::Strip { vertices, width, cells } => super::walls::strip_mesh(vertices, *width, cells),
        MeshSpec::Gmsh(file) => {
            let path = case.directory.join(file);
            let limits = GmshLimits { max_entries: case.limits.cells as u64, ..GmshLimits::default() };
            loam_fem::gmsh::read_gmsh_limited(&path, &limits).map_err(|e| {
                let hint = if matches!(e, GmshError::TooLarge { .. }) { " (limits.cells)" } else { "" };
                CaseError::new(format!("{loc}.gmsh"), format!("{e}{hint}"))
            })?
        }
    };
    if mesh.element.dim() != dim {
        return Err(CaseError::new(
            loc,
            format!("{} elements do not fit the {} formulation", mesh.element.name(), case.formulation.name()),
        ));
    }
    if case.formulation == Formulation::Axisymmetric && mesh.coords.iter().any(|c| c[0] < -1e-12) {
        return Err(CaseError::new(loc, "axisymmetric meshes need r = x ≥ 0"));
    }
    Ok(mesh)
}

/// A structured block of `cells` (per direction) of `element`s must fit `limits.cells` in
/// cells and in nodes, checked before anything is allocated (issue 16: `"cells":
/// [1000000000, 1]` aborted on a failed allocation of 48 GB).
fn check_block_size(case: &Case, loc: &str, cells: &[usize], element: ElementType) -> Result<(), CaseError> {
    let per_block = match element {
        ElementType::Tri3 => 2.0,
        ElementType::Tet4 => 6.0,
        ElementType::Quad4 | ElementType::Hex8 => 1.0,
    };
    let n_cells: f64 = per_block * cells.iter().map(|&c| c as f64).product::<f64>();
    let n_nodes: f64 = cells.iter().map(|&c| c as f64 + 1.0).product();
    let limit = case.limits.cells;
    if !super::within(n_cells, limit) || !super::within(n_nodes, limit) {
        let counts: Vec<String> = cells.iter().map(|c| c.to_string()).collect();
        return Err(CaseError::new(
            loc,
            format!(
                "[{}] makes {} {} cells and {} nodes, more than limits.cells = {limit} (raise it in the case's \"limits\" for a larger model)",
                counts.join(", "),
                count(n_cells),
                element.name(),
                count(n_nodes)
            ),
        ));
    }
    Ok(())
}

/// A count for messages: in full up to a million, else `1.000e9`.
pub(super) fn count(n: f64) -> String {
    if !n.is_finite() {
        "more than 1e308".into()
    } else if n < 1e6 {
        format!("{n}")
    } else {
        format!("{n:.3e}")
    }
}

/// Every cell of a grid must have a positive, finite Jacobian determinant at its corners: a
/// degenerate or inverted cell (or sizes beyond floating point) is refused before the run.
fn check_cells(grid: &Grid, loc: &str) -> Result<(), CaseError> {
    let element = grid.mesh.element;
    for c in 0..grid.mesh.num_cells() {
        let coords = grid.cell_coords(c);
        let det = element.min_corner_det_j(&coords[..element.num_nodes()]);
        if !(det > 0.0 && det.is_finite()) {
            let centre = grid.reference_centre(c);
            return Err(CaseError::new(
                loc,
                format!(
                    "cell {c} at ({}) is degenerate or inverted (det J = {det:.3e}): nodes counter-clockwise, sizes finite",
                    centre[..element.dim()].iter().map(|v| format!("{v:.4e}")).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Checks the keys of domain `k` against its kind.
fn check_keys(case: &Case, k: usize) -> Result<(), CaseError> {
    let d = &case.domains[k];
    let loc = format!("domains[{k}]");
    let misplaced =
        |key: &str| CaseError::new(format!("{loc}.{key}"), format!("does not apply to an {} domain", d.kind.as_str()));
    if d.kind != DomainKind::Rigid {
        if d.motion.is_some() {
            return Err(misplaced("motion"));
        }
        if d.initial_angular_velocity.is_some() {
            return Err(misplaced("initial_angular_velocity"));
        }
    }
    match d.kind {
        DomainKind::Rigid => check_rigid_keys(case, k)?,
        DomainKind::Fem => {
            if d.grid.is_some() {
                return Err(misplaced("grid"));
            }
            if d.grid_mesh.is_some() {
                return Err(misplaced("grid_mesh"));
            }
            if d.material_points.is_some() {
                return Err(misplaced("material_points"));
            }
            if d.initial_stress.is_some() {
                return Err(misplaced("initial_stress"));
            }
            if d.pic_fraction != 0.0 {
                return Err(misplaced("pic_fraction"));
            }
            if d.pic_relaxation_time.is_some() {
                return Err(misplaced("pic_relaxation_time"));
            }
            if d.quadrature != Quadrature::MaterialPoints {
                return Err(misplaced("quadrature"));
            }
            if d.ghost_penalty.is_some() {
                return Err(misplaced("ghost_penalty"));
            }
            if d.mesh.is_none() {
                return Err(CaseError::new(format!("{loc}.mesh"), "an fem domain needs a mesh"));
            }
        }
        DomainKind::Mpm => {
            if d.mesh.is_some() {
                return Err(misplaced("mesh"));
            }
            match (&d.grid, &d.grid_mesh) {
                (Some(_), Some(_)) => {
                    return Err(CaseError::new(format!("{loc}.grid_mesh"), "give either grid or grid_mesh, not both"));
                }
                (None, None) => {
                    return Err(CaseError::new(format!("{loc}.grid"), "an mpm domain needs a grid (or a grid_mesh)"));
                }
                _ => {}
            }
            if d.material_points.is_none() {
                return Err(CaseError::new(format!("{loc}.material_points"), "an mpm domain needs material_points"));
            }
            if d.mass_matrix == Some(MassMatrix::Consistent) {
                return Err(CaseError::new(
                    format!("{loc}.mass_matrix"),
                    "\"consistent\": an mpm domain's grid mass is lumped (m_I = Σ N_I(x_p) m_p); omit the key or write \"lumped\"",
                ));
            }
        }
    }
    if let Some(v0) = &d.initial_velocity {
        let dim = case.formulation.dim();
        let loc = format!("{loc}.initial_velocity");
        match v0 {
            InitialVelocity::Uniform(u) => check_len(&format!("{loc}.uniform"), u, dim)?,
            InitialVelocity::Sine { amplitude, wavenumber } => {
                check_len(&format!("{loc}.sine.amplitude"), amplitude, dim)?;
                check_len(&format!("{loc}.sine.wavenumber"), wavenumber, dim)?;
            }
        }
    }
    Ok(())
}

/// The keys of a rigid domain (`domains[k]`, [`DomainKind::Rigid`]): a mesh, none of the
/// keys of deformable bodies, a plane formulation, a motion with one entry per component and
/// finite values, every unknown prescribed in a static analysis, and a uniform initial
/// velocity.
fn check_rigid_keys(case: &Case, k: usize) -> Result<(), CaseError> {
    let d = &case.domains[k];
    let loc = format!("domains[{k}]");
    let misplaced = |key: &str| {
        Err(CaseError::new(
            format!("{loc}.{key}"),
            "does not apply to a rigid domain (it has no material points, elements or strains)",
        ))
    };
    if d.grid.is_some() {
        return misplaced("grid");
    }
    if d.grid_mesh.is_some() {
        return misplaced("grid_mesh");
    }
    if d.material_points.is_some() {
        return misplaced("material_points");
    }
    if d.initial_stress.is_some() {
        return misplaced("initial_stress");
    }
    if d.pic_fraction != 0.0 || d.pic_relaxation_time.is_some() {
        return misplaced(if d.pic_fraction != 0.0 { "pic_fraction" } else { "pic_relaxation_time" });
    }
    if d.quadrature != Quadrature::MaterialPoints {
        return misplaced("quadrature");
    }
    if d.ghost_penalty.is_some() {
        return misplaced("ghost_penalty");
    }
    if d.mass_matrix.is_some() {
        return misplaced("mass_matrix");
    }
    if d.element_formulation != ElementFormulation::Displacement {
        return misplaced("element_formulation");
    }
    if d.mesh.is_none() {
        return Err(CaseError::new(format!("{loc}.mesh"), "a rigid domain needs a mesh (its shape)"));
    }
    if case.formulation == Formulation::ThreeD {
        return Err(CaseError::new(
            format!("{loc}.type"),
            "a rigid domain is 2D (plane or axisymmetric) so far: its rotation is one angle",
        ));
    }
    if let Some(InitialVelocity::Sine { .. }) = d.initial_velocity {
        return Err(CaseError::new(
            format!("{loc}.initial_velocity"),
            "a rigid body moves as a whole: give \"uniform\" (and initial_angular_velocity for its spin)",
        ));
    }
    if let Some(w) = d.initial_angular_velocity {
        if !w.is_finite() {
            return Err(CaseError::new(format!("{loc}.initial_angular_velocity"), format!("must be finite, got {w}")));
        }
    }
    let motion = d.motion.clone().unwrap_or_default();
    let mloc = format!("{loc}.motion");
    if !motion.displacement.is_empty() {
        check_len(&format!("{mloc}.displacement"), &motion.displacement, 2)?;
    }
    for (i, v) in motion.displacement.iter().enumerate() {
        if let Some(v) = v.filter(|v| !v.is_finite()) {
            return Err(CaseError::new(format!("{mloc}.displacement[{i}]"), format!("must be finite, got {v}")));
        }
    }
    if let Some(r) = motion.rotation.filter(|r| !r.is_finite()) {
        return Err(CaseError::new(format!("{mloc}.rotation"), format!("must be finite, got {r}")));
    }
    motion.amplitude.check().map_err(|m| CaseError::new(format!("{mloc}.amplitude"), m))?;
    if case.formulation == Formulation::Axisymmetric
        && (motion.displacement.first() != Some(&Some(0.0)) || motion.rotation != Some(0.0))
    {
        return Err(CaseError::new(
            mloc,
            "an axisymmetric rigid body is a ring: it moves along the axis only (\"displacement\": [0, y or null], \"rotation\": 0)",
        ));
    }
    let held = motion.displacement.iter().filter(|v| v.is_some()).count() + usize::from(motion.rotation.is_some());
    if case.analysis.kind != AnalysisType::Dynamic && held < 3 {
        return Err(CaseError::new(
            mloc,
            "a static or quasi-static analysis needs the rigid body's displacement and rotation prescribed (all three: \"displacement\": [x, y], \"rotation\": θ); a free rigid body needs a dynamic analysis",
        ));
    }
    Ok(())
}

/// The region a body fills, as its case file gives it: the cells of its body mesh, a disk
/// or a polygon. Two bodies overlap where the points of one lie in the region of the other.
enum BodyRegion {
    /// The body mesh, as a locator.
    Mesh(Box<Grid>),
    /// Centre and radius.
    Disk([f64; 2], f64),
    /// Vertices in order.
    Polygon(Vec<[f64; 2]>),
}

impl BodyRegion {
    /// Whether `x` lies in the region (strictly inside a disk or polygon; within 1e-9 of a
    /// cell in local coordinates for a mesh).
    fn contains(&self, x: &[f64; 3]) -> bool {
        match self {
            BodyRegion::Mesh(locator) => locator.locate(x).is_some(),
            BodyRegion::Disk(c, r) => (x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) < r * r,
            BodyRegion::Polygon(v) => point_in_polygon(v, x[0], x[1]),
        }
    }
}

/// The element formulation of domain `k` against its material, its kinematics and its
/// material points: the combinations that cannot work are refused.
fn check_element_formulation(case: &Case, k: usize, law: &dyn ConstitutiveLaw) -> Result<(), CaseError> {
    let d = &case.domains[k];
    let loc = format!("domains[{k}].element_formulation");
    match d.element_formulation {
        ElementFormulation::Displacement if law.elastic_lame().0.is_infinite() => Err(CaseError::new(
            format!("domains[{k}].material"),
            format!(
                "material '{}' is incompressible (poisson_ratio 0.5): it needs \"element_formulation\": \"mixed_up\"",
                d.material
            ),
        )),
        ElementFormulation::Displacement => Ok(()),
        ElementFormulation::MixedUp => {
            if case.formulation == Formulation::PlaneStress {
                return Err(CaseError::new(
                    loc,
                    "mixed_up does not apply to plane_stress (no incompressibility constraint): use plane_strain, \
                     axisymmetric or 3d",
                ));
            }
            law.mixed().map_err(|why| CaseError::new(&loc, format!("material '{}': {why}", d.material)))?;
            if let Some(BodySpec::Cells { points_per_cell: 1, .. }) = &d.material_points {
                return Err(CaseError::new(
                    format!("domains[{k}].material_points.cells.points_per_cell"),
                    "mixed_up needs several material points per cell (its pressure stabilisation acts on the points \
                     of each cell): 3 or more",
                ));
            }
            Ok(())
        }
    }
}

/// The material points of the MPM domain `k` (unit density), checked to lie in `grid`.
pub(crate) fn body_points(case: &Case, k: usize, grid: &Grid) -> Result<MaterialPoints, CaseError> {
    material_points(case, k, 1.0, grid).map(|(points, _)| points)
}

/// The material points of the MPM domain `k` (`density` of its material), checked to lie
/// in `grid`, and the region they fill.
fn material_points(
    case: &Case,
    k: usize,
    density: f64,
    grid: &Grid,
) -> Result<(MaterialPoints, BodyRegion), CaseError> {
    let d = &case.domains[k];
    let dim = case.formulation.dim();
    let body_loc = format!("domains[{k}].material_points");
    let body = d.material_points.as_ref().expect("checked");
    let (f, t) = (case.formulation, case.thickness);
    let limit = case.limits.material_points;
    let too_many = |loc: String, what: String| {
        CaseError::new(
            loc,
            format!("{what}, more than limits.material_points = {limit} (raise it in the case's \"limits\" for a larger body)"),
        )
    };
    let (points, region) = match body {
        BodySpec::Cells { mesh, points_per_cell } => {
            let m = build_mesh(case, &format!("{body_loc}.cells.mesh"), mesh)?;
            let n = m.num_cells() as f64 * *points_per_cell as f64;
            if !super::within(n, limit) {
                return Err(too_many(
                    format!("{body_loc}.cells.points_per_cell"),
                    format!("{} cells × {points_per_cell} points make {} material points", m.num_cells(), count(n)),
                ));
            }
            let points = material_points::from_mesh(&m, *points_per_cell, f, t, density)
                .map_err(|e| CaseError::new(format!("{body_loc}.cells.points_per_cell"), e))?;
            (points, BodyRegion::Mesh(Box::new(Grid::unstructured(m))))
        }
        BodySpec::Disk { centre, radius, spacing } => {
            check_positive(&format!("{body_loc}.disk.radius"), *radius)?;
            check_positive(&format!("{body_loc}.disk.spacing"), *spacing)?;
            let n = (2.0 * radius / spacing).ceil().powi(2);
            if !super::within(n, limit)
                || !(centre[0].abs() + radius).is_finite()
                || !(centre[1].abs() + radius).is_finite()
            {
                return Err(too_many(
                    format!("{body_loc}.disk.spacing"),
                    format!(
                        "a disk of radius {radius} m at spacing {spacing} m takes a lattice of {} positions",
                        count(n)
                    ),
                ));
            }
            let (c, r) = (*centre, *radius);
            let points = material_points::from_lattice_2d(
                [c[0] - r, c[1] - r],
                [c[0] + r, c[1] + r],
                *spacing,
                f,
                t,
                density,
                |x, y| (x - c[0]).powi(2) + (y - c[1]).powi(2) <= r * r,
            );
            (points, BodyRegion::Disk(c, r))
        }
        BodySpec::Polygon { vertices, spacing } => {
            check_positive(&format!("{body_loc}.polygon.spacing"), *spacing)?;
            if vertices.len() < 3 {
                return Err(CaseError::new(format!("{body_loc}.polygon.vertices"), "needs at least 3 vertices"));
            }
            let lo = [0, 1].map(|d| vertices.iter().map(|v| v[d]).fold(f64::MAX, f64::min));
            let hi = [0, 1].map(|d| vertices.iter().map(|v| v[d]).fold(f64::MIN, f64::max));
            let n = ((hi[0] - lo[0]) / spacing).ceil() * ((hi[1] - lo[1]) / spacing).ceil();
            if !super::within(n, limit) {
                return Err(too_many(
                    format!("{body_loc}.polygon.spacing"),
                    format!(
                        "a polygon of {} m × {} m at spacing {spacing} m takes a lattice of {} positions",
                        hi[0] - lo[0],
                        hi[1] - lo[1],
                        count(n)
                    ),
                ));
            }
            let points = material_points::from_lattice_2d(lo, hi, *spacing, f, t, density, |x, y| {
                point_in_polygon(vertices, x, y)
            });
            (points, BodyRegion::Polygon(vertices.clone()))
        }
    };
    if points.is_empty() {
        return Err(CaseError::new(body_loc, "generates no material point"));
    }
    if let Some(p) = points.position.iter().position(|x| grid.locate(x).is_none()) {
        return Err(CaseError::new(
            body_loc,
            format!("material point at {:?} lies outside the grid", &points.position[p][..dim]),
        ));
    }
    Ok((points, region))
}

/// Two domains must not fill the same space (issue 16: two overlapping domains were
/// accepted silently, doubling mass and stiffness there): no material point of one body
/// lies in the region of another (whatever their grids), and no cell centre of one FEM
/// mesh lies in a cell of another (FEM domains may share nodes along a common boundary).
fn check_overlaps(
    case: &Case,
    fem_meshes: &BTreeMap<usize, Mesh>,
    bodies: &[(usize, &MaterialPoints, &BodyRegion)],
) -> Result<(), CaseError> {
    let dim = case.formulation.dim();
    let at = |x: &[f64; 3]| x[..dim].iter().map(|v| format!("{v:.6e}")).collect::<Vec<_>>().join(", ");
    let overlap = |a: usize, b: usize, x: &[f64; 3]| {
        let (a, b) = (a.min(b), a.max(b));
        CaseError::new(
            format!("domains[{b}]"),
            format!(
                "'{}' overlaps '{}' (domains[{a}]) at ({}): two domains must not fill the same space",
                case.domains[b].name,
                case.domains[a].name,
                at(x)
            ),
        )
    };
    for (i, &(a, _, region)) in bodies.iter().enumerate() {
        for (j, &(b, points, _)) in bodies.iter().enumerate() {
            if i != j {
                if let Some(x) = points.position.iter().find(|x| region.contains(x)) {
                    return Err(overlap(a, b, x));
                }
            }
        }
    }
    let locators: Vec<(usize, Grid)> = if fem_meshes.len() > 1 {
        fem_meshes.iter().map(|(&k, m)| (k, Grid::unstructured(m.clone()))).collect()
    } else {
        Vec::new()
    };
    for (a, locator) in &locators {
        for (&b, mesh) in fem_meshes {
            if b == *a {
                continue;
            }
            for e in 0..mesh.num_cells() {
                let cell = mesh.cell(e);
                let mut c = [0.0; 3];
                for &n in cell {
                    for d in 0..3 {
                        c[d] += mesh.coords[n][d] / cell.len() as f64;
                    }
                }
                if locator.locate(&c).is_some() {
                    return Err(overlap(*a, b, &c));
                }
            }
        }
    }
    Ok(())
}

/// The structured grid of `g` (at JSON path `loc`), checked.
pub(crate) fn structured_grid(case: &Case, loc: &str, g: &GridSpec) -> Result<Grid, CaseError> {
    let dim = case.formulation.dim();
    check_len(&format!("{loc}.grid.origin"), &g.origin, dim)?;
    check_len(&format!("{loc}.grid.size"), &g.size, dim)?;
    check_len(&format!("{loc}.grid.cells"), &g.cells, dim)?;
    for (i, v) in g.size.iter().enumerate() {
        check_positive(&format!("{loc}.grid.size[{i}]"), *v)?;
    }
    if g.cells.contains(&0) {
        return Err(CaseError::new(format!("{loc}.grid.cells"), "needs at least one cell in each direction"));
    }
    check_block_size(case, &format!("{loc}.grid.cells"), &g.cells, g.element)?;
    if g.element.dim() != dim || g.element == ElementType::Tet4 {
        return Err(CaseError::new(
            format!("{loc}.grid.element"),
            format!(
                "a structured {} grid takes {}",
                case.formulation.name(),
                if dim == 2 { "quad4 or tri3" } else { "hex8" }
            ),
        ));
    }
    let mut origin = [0.0; 3];
    let mut size = [1.0; 3];
    let mut cells = [1; 3];
    origin[..dim].copy_from_slice(&g.origin);
    size[..dim].copy_from_slice(&g.size);
    cells[..dim].copy_from_slice(&g.cells);
    if case.formulation == Formulation::Axisymmetric && origin[0] < -1e-12 {
        return Err(CaseError::new(format!("{loc}.grid.origin"), "axisymmetric grids need r = x ≥ 0"));
    }
    if g.rotation != 0.0 && dim != 2 {
        return Err(CaseError::new(format!("{loc}.grid.rotation"), "only 2D grids can be rotated"));
    }
    let mut grid = Grid::rotated(origin, size, cells, g.element, g.rotation.to_radians());
    grid.set_basis(g.basis)
        .map_err(|e| CaseError::new(format!("{loc}.grid.basis"), format!("\"{}\": {e}", g.basis.name())))?;
    Ok(grid)
}

/// Even–odd rule.
fn point_in_polygon(vertices: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut inside = false;
    let n = vertices.len();
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + n - 1) % n]);
        if (a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
    }
    inside
}

/// Merges coincident nodes of several meshes into one global node set.
/// Returns the global coordinates and, per mesh, local → global ids.
fn merge_nodes(meshes: &[Mesh]) -> (Vec<[f64; 3]>, Vec<Vec<usize>>) {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for c in meshes.iter().flat_map(|m| &m.coords) {
        for d in 0..3 {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
    }
    let size = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max).max(1e-300);
    let quantum = size * 1e-9;
    let key = |c: &[f64; 3]| c.map(|v| (v / quantum).round() as i64);
    let mut global = Vec::new();
    let mut index: HashMap<[i64; 3], usize> = HashMap::new();
    let ids = meshes
        .iter()
        .map(|m| {
            m.coords
                .iter()
                .map(|c| {
                    *index.entry(key(c)).or_insert_with(|| {
                        global.push(*c);
                        global.len() - 1
                    })
                })
                .collect()
        })
        .collect();
    (global, ids)
}

/// Builds the meshes, grids and bodies of `case`, couples grids to structures by the
/// case's interfaces and numbers the global nodes (see the module doc).
pub(super) fn discretise(
    case: &Case,
    laws: &BTreeMap<&str, Arc<dyn ConstitutiveLaw>>,
) -> Result<Discretisation, CaseError> {
    if case.domains.is_empty() {
        return Err(CaseError::new("domains", "needs at least one domain"));
    }
    let mut names = std::collections::BTreeSet::new();
    for (k, d) in case.domains.iter().enumerate() {
        if !names.insert(&d.name) {
            return Err(CaseError::new(format!("domains[{k}].name"), format!("duplicate domain name '{}'", d.name)));
        }
        if !laws.contains_key(d.material.as_str()) {
            return Err(CaseError::new(
                format!("domains[{k}].material"),
                unknown_name("material", &d.material, "materials", laws.keys().copied()),
            ));
        }
        check_keys(case, k)?;
        if d.kind != DomainKind::Rigid {
            check_element_formulation(case, k, laws[d.material.as_str()].as_ref())?;
        }
    }
    // FEM meshes, and grids with their bodies (identical specs: one grid)
    let mut fem_meshes: BTreeMap<usize, Mesh> = BTreeMap::new();
    let mut groups: Vec<GridGroup<'_>> = Vec::new();
    let mut group_of: HashMap<usize, usize> = HashMap::new();
    let mut regions: Vec<(usize, BodyRegion)> = Vec::new();
    for (k, d) in case.domains.iter().enumerate() {
        let loc = format!("domains[{k}]");
        match d.kind {
            DomainKind::Fem | DomainKind::Rigid => {
                let mesh = build_mesh(case, &format!("{loc}.mesh"), d.mesh.as_ref().expect("checked"))?;
                fem_meshes.insert(k, mesh);
            }
            DomainKind::Mpm => {
                let key = match (&d.grid, &d.grid_mesh) {
                    (Some(g), _) => GridKey::Structured(g),
                    (None, Some(m)) => GridKey::Mesh(m),
                    (None, None) => unreachable!("checked"),
                };
                let g = match groups.iter().position(|g| g.key == key) {
                    Some(g) => g,
                    None => {
                        let (grid, key_loc) = match &key {
                            GridKey::Structured(g) => (structured_grid(case, &loc, g)?, format!("{loc}.grid")),
                            GridKey::Mesh(spec) => (
                                Grid::unstructured(build_mesh(case, &format!("{loc}.grid_mesh"), spec)?),
                                format!("{loc}.grid_mesh"),
                            ),
                        };
                        check_cells(&grid, &key_loc)?;
                        groups.push(GridGroup {
                            key,
                            grid,
                            bodies: Vec::new(),
                            coupled: None,
                            structures: Vec::new(),
                            interfaces: Vec::new(),
                            ties: Vec::new(),
                        });
                        groups.len() - 1
                    }
                };
                let (points, region) = material_points(case, k, laws[d.material.as_str()].density(), &groups[g].grid)?;
                groups[g].bodies.push((k, points));
                regions.push((k, region));
                group_of.insert(k, g);
            }
        }
    }
    let bodies: Vec<(usize, &MaterialPoints, &BodyRegion)> = regions
        .iter()
        .map(|(k, region)| {
            let points = groups[group_of[k]].bodies.iter().find(|(b, _)| b == k).map(|(_, p)| p).expect("listed");
            (*k, points, region)
        })
        .collect();
    check_overlaps(case, &fem_meshes, &bodies)?;
    couple_grids(case, &fem_meshes, &mut groups, &group_of)?;
    number(case, laws, fem_meshes, groups)
}

/// Largest `interfaces[].band` as a multiple of the diagonal of the grid's bounding box: a
/// band this wide already moves every node of the grid with the structure.
const MAX_BAND_PER_GRID_DIAGONAL: f64 = 1e3;

/// An interface's band (m) must be finite, positive and at most
/// [`MAX_BAND_PER_GRID_DIAGONAL`] times the diagonal of its grid (issue 31: 1e300 was
/// accepted).
fn check_band(location: &str, band: f64, grid: &Grid) -> Result<(), CaseError> {
    check_positive(location, band)?;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for x in &grid.mesh.coords {
        for i in 0..3 {
            lo[i] = lo[i].min(x[i]);
            hi[i] = hi[i].max(x[i]);
        }
    }
    let diagonal = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    let max = MAX_BAND_PER_GRID_DIAGONAL * diagonal;
    if band <= max {
        Ok(())
    } else {
        Err(CaseError::new(
            location,
            format!(
                "must be at most {max:.6e} m ({MAX_BAND_PER_GRID_DIAGONAL:e} times the diagonal of the grid, {diagonal:.6} m: \
                 a band of the whole grid moves every node), got {band}"
            ),
        ))
    }
}

/// Resolves the case's interfaces and attaches each grid to its structures; checks that
/// no FEM mesh touches a grid without an interface.
fn couple_grids(
    case: &Case,
    fem_meshes: &BTreeMap<usize, Mesh>,
    groups: &mut [GridGroup<'_>],
    group_of: &HashMap<usize, usize>,
) -> Result<(), CaseError> {
    let dim = case.formulation.dim();
    let domain_index = |loc: String, name: &str| {
        case.domains
            .iter()
            .position(|d| d.name == name)
            .ok_or_else(|| CaseError::new(loc, format!("no domain named '{name}' in domains")))
    };
    let mut names = std::collections::BTreeSet::new();
    let mut requests: Vec<Vec<(usize, usize, Vec<usize>)>> = vec![Vec::new(); groups.len()];
    for (k, spec) in case.interfaces.iter().enumerate() {
        let loc = format!("interfaces[{k}]");
        if spec.name.is_empty() || !names.insert(spec.name.as_str()) {
            return Err(CaseError::new(format!("{loc}.name"), format!("must be a unique name, got '{}'", spec.name)));
        }
        let soil = domain_index(format!("{loc}.soil"), &spec.soil)?;
        let Some(&g) = group_of.get(&soil) else {
            return Err(CaseError::new(format!("{loc}.soil"), format!("'{}' is not an mpm domain", spec.soil)));
        };
        if dim == 3 && groups[g].grid.basis().is_smooth() {
            return Err(CaseError::new(
                format!("{loc}.soil"),
                format!(
                    "'{}' has a 3D grid on the smooth basis \"{}\": the smooth supports follow a structure (folded around it, moved with it) in 2D only; couple a 3D grid on grid.basis \"linear\"",
                    spec.soil,
                    groups[g].grid.basis().name()
                ),
            ));
        }
        let structure = domain_index(format!("{loc}.structure"), &spec.structure)?;
        let Some(mesh) = fem_meshes.get(&structure) else {
            return Err(CaseError::new(
                format!("{loc}.structure"),
                format!("'{}' is not an fem domain", spec.structure),
            ));
        };
        let region_spec = case.regions.get(&spec.region).ok_or_else(|| {
            CaseError::new(
                format!("{loc}.region"),
                unknown_name("region", &spec.region, "regions", case.regions.keys().map(String::as_str)),
            )
        })?;
        let tol = line_tolerance(&mesh.coords);
        let nodes =
            select_region(&spec.region, region_spec, &mesh.coords, dim, &mesh.node_groups, tol).map_err(|e| {
                let message = if e.message.starts_with("selects no node") {
                    format!("selects no node of '{}' (check the coordinates against its mesh)", spec.structure)
                } else {
                    format!("region '{}' on '{}': {}", spec.region, spec.structure, e.message)
                };
                CaseError::new(format!("{loc}.region"), message)
            })?;
        if spec.coupling != InterfaceCoupling::Contact {
            let only_contact = |key: &str| {
                Err(CaseError::new(
                    format!("{loc}.{key}"),
                    format!("only a contact (coupling \"contact\") takes {key}"),
                ))
            };
            if spec.friction.is_some() {
                return only_contact("friction");
            }
            if spec.tangential_penalty.is_some() {
                return only_contact("tangential_penalty");
            }
            if spec.gap_tolerance.is_some() {
                return only_contact("gap_tolerance");
            }
        }
        if spec.coupling.is_non_conforming() {
            let refuse = |key: &str, why: &str| Err(CaseError::new(format!("{loc}.{key}"), why.to_string()));
            if spec.slip {
                return refuse(
                    "slip",
                    "a tie is bilateral and without slip, a contact slides by its friction: slip is for shared nodes",
                );
            }
            if spec.band.is_some() {
                return refuse(
                    "band",
                    "a tie or contact leaves the grid fixed: band is for shared nodes (coupling \"shared_nodes\")",
                );
            }
            if let Some(beta) = spec.penalty {
                check_positive(&format!("{loc}.penalty"), beta)?;
            }
            if let Some(beta) = spec.tangential_penalty {
                check_positive(&format!("{loc}.tangential_penalty"), beta)?;
            }
            if let Some(tolerance) = spec.gap_tolerance {
                check_positive(&format!("{loc}.gap_tolerance"), tolerance)?;
            }
            if let Some(mu) = spec.friction {
                if !(mu.is_finite() && mu >= 0.0) {
                    return Err(CaseError::new(
                        format!("{loc}.friction"),
                        format!("must be a Coulomb coefficient ≥ 0 (0: frictionless), got {mu}"),
                    ));
                }
            }
            let view = Structure { name: &spec.structure, mesh };
            let (facets, length) = interface_points::tie_facets(&view, &nodes, &groups[g].grid)
                .map_err(|e| CaseError::new(format!("{loc}.region"), e.message))?;
            groups[g].ties.push(TieRequest { interface: k, structure, facets, length });
            continue;
        }
        if case.domains[structure].kind == DomainKind::Rigid {
            return Err(CaseError::new(
                format!("{loc}.coupling"),
                format!(
                    "'{}' is rigid: it meets the soil by \"tie\" or \"contact\" (shared nodes would move the grid with a body that has no nodes of its own)",
                    spec.structure
                ),
            ));
        }
        if spec.penalty.is_some() {
            return Err(CaseError::new(
                format!("{loc}.penalty"),
                "only a tie or contact (coupling \"tie\" or \"contact\") takes a penalty; shared nodes need none",
            ));
        }
        if let Some(band) = spec.band {
            check_band(&format!("{loc}.band"), band, &groups[g].grid)?;
        }
        requests[g].push((k, structure, nodes));
    }
    for (g, group) in groups.iter_mut().enumerate() {
        let soil = &case.domains[group.bodies[0].0].name;
        if let (Some(tie), Some(shared)) = (group.ties.first(), requests[g].first()) {
            return Err(CaseError::new(
                format!("interfaces[{}].coupling", tie.interface),
                format!(
                    "a tie or contact needs a fixed grid, and '{soil}' is attached to a structure by shared nodes (interfaces[{}]): one kind of interface per grid",
                    shared.0
                ),
            ));
        }
        let tied: Vec<usize> = group.ties.iter().map(|t| t.structure).collect();
        if !tied.is_empty() {
            let views: Vec<Structure<'_>> =
                tied.iter().map(|&s| Structure { name: &case.domains[s].name, mesh: &fem_meshes[&s] }).collect();
            for (k, points) in &group.bodies {
                coupling::check_points_outside(&case.domains[*k].name, &points.position, &views)
                    .map_err(|e| CaseError::new(format!("domains[{k}].material_points"), e.message))?;
            }
        }
        if !requests[g].is_empty() {
            let mut structures: Vec<usize> = requests[g].iter().map(|r| r.1).collect();
            structures.sort_unstable();
            structures.dedup();
            let views: Vec<Structure<'_>> =
                structures.iter().map(|&s| Structure { name: &case.domains[s].name, mesh: &fem_meshes[&s] }).collect();
            let reqs: Vec<InterfaceRequest<'_>> = requests[g]
                .iter()
                .map(|(k, s, nodes)| InterfaceRequest {
                    name: &case.interfaces[*k].name,
                    structure: structures.iter().position(|x| x == s).expect("listed"),
                    region: nodes.clone(),
                    slip: case.interfaces[*k].slip,
                })
                .collect();
            let at = |e: coupling::InterfaceError| match e.interface {
                Some(i) => CaseError::new(format!("interfaces[{}]", requests[g][i].0), e.message),
                None => CaseError::new("interfaces", e.message),
            };
            let coupled = coupling::couple(soil, &group.grid, &views, &reqs).map_err(at)?;
            for (k, points) in &group.bodies {
                coupling::check_points_outside(&case.domains[*k].name, &points.position, &views)
                    .map_err(|e| CaseError::new(format!("domains[{k}].material_points"), e.message))?;
            }
            group.interfaces = requests[g].iter().map(|r| r.0).collect();
            group.structures = structures;
            group.coupled = Some(coupled);
        }
        let grid = group.coupled.as_ref().map_or(&group.grid, |c| &c.grid);
        for (&s, mesh) in fem_meshes {
            if group.structures.contains(&s) || tied.contains(&s) {
                continue;
            }
            coupling::check_no_overlap(soil, grid, &Structure { name: &case.domains[s].name, mesh })
                .map_err(|e| CaseError::new(format!("domains[{s}].mesh"), e.message))?;
        }
    }
    Ok(())
}

/// Numbers the global nodes (FEM meshes first, merged by position among themselves, then
/// every grid's nodes, shared with the structure on tied interfaces) and builds the parts.
fn number(
    case: &Case,
    laws: &BTreeMap<&str, Arc<dyn ConstitutiveLaw>>,
    fem_meshes: BTreeMap<usize, Mesh>,
    groups: Vec<GridGroup<'_>>,
) -> Result<Discretisation, CaseError> {
    type Meshes = Vec<(usize, Mesh)>;
    let (rigid_list, fem_list): (Meshes, Meshes) =
        fem_meshes.into_iter().partition(|(k, _)| case.domains[*k].kind == DomainKind::Rigid);
    let meshes: Vec<Mesh> = fem_list.iter().map(|(_, m)| m.clone()).collect();
    let (mut coords, fem_ids) = merge_nodes(&meshes);
    let mut roles = vec![NodeRole::Structure; coords.len()];
    // a rigid body's unknowns: a centre node at its centroid and a rotation node (module doc
    // of loam_fem::rigid_body), structure nodes of their own
    let mut rigid_frames: HashMap<usize, RigidFrame> = HashMap::new();
    for (k, mesh) in &rigid_list {
        let (_, centre, _) = rigid_body::area_properties(mesh);
        let frame = RigidFrame { centre, centre_node: coords.len(), rotation_node: coords.len() + 1 };
        coords.extend([[centre[0], centre[1], 0.0]; 2]);
        roles.extend([NodeRole::Structure; 2]);
        rigid_frames.insert(*k, frame);
    }
    let ids_of_structure: HashMap<usize, &Vec<usize>> = fem_list.iter().map(|(k, _)| *k).zip(&fem_ids).collect();
    let mut node_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (m, id) in meshes.iter().zip(&fem_ids) {
        for (g, nodes) in &m.node_groups {
            node_groups.entry(g.clone()).or_default().extend(nodes.iter().map(|&n| id[n]));
        }
    }
    let mut parts: Vec<(usize, Part)> = Vec::new();
    let mut interfaces: Vec<Option<ResolvedInterface>> = (0..case.interfaces.len()).map(|_| None).collect();
    let mut ties = Vec::new();
    for group in groups {
        let (grid, on_interface) = match group.coupled {
            Some(c) => (c.grid, Some((c.on_interface, c.summaries))),
            None => (group.grid, None),
        };
        let mut node_ids = Vec::with_capacity(grid.mesh.coords.len());
        let mut coupling = on_interface.as_ref().map(|_| GridCoupling {
            on_interface: vec![None; grid.mesh.coords.len()],
            interfaces: group.interfaces.clone(),
        });
        let mut soil_nodes: Vec<Vec<usize>> = vec![Vec::new(); group.interfaces.len()];
        for (a, x) in grid.reference_coords().iter().enumerate() {
            let on = on_interface.as_ref().and_then(|(on, _)| on[a]);
            let structure_node = on.map(|n| ids_of_structure[&group.structures[n.structure]][n.node]);
            let g = match (on, structure_node) {
                (Some(n), Some(s)) if !case.interfaces[group.interfaces[n.interface]].slip => {
                    roles[s] = NodeRole::Interface;
                    s
                }
                _ => {
                    coords.push(*x);
                    roles.push(NodeRole::Grid);
                    coords.len() - 1
                }
            };
            if let (Some(n), Some(s), Some(c)) = (on, structure_node, coupling.as_mut()) {
                c.on_interface[a] = Some((n, s));
                soil_nodes[n.interface].push(g);
            }
            node_ids.push(g);
        }
        for (gname, nodes) in &grid.mesh.node_groups {
            node_groups.entry(gname.clone()).or_default().extend(nodes.iter().map(|&n| node_ids[n]));
        }
        let part_key = group.bodies[0].0;
        if let Some((_, summaries)) = on_interface {
            for (i, (&k, summary)) in group.interfaces.iter().zip(summaries).enumerate() {
                interfaces[k] =
                    Some(ResolvedInterface { summary, part: part_key, soil_nodes: std::mem::take(&mut soil_nodes[i]) });
            }
        }
        let tie_grid = (!group.ties.is_empty()).then(|| (grid.clone(), node_ids.clone()));
        let (domain, bodies) = grid_domain(case, laws, grid, node_ids, group.bodies)?;
        if let Some((grid, node_ids)) = tie_grid {
            let modulus = domain.bodies().iter().map(|b| young_modulus(b.law().elastic_lame())).fold(0.0, f64::max);
            let stiffness = modulus / mean_cell_size(&grid.mesh);
            let default_penalty = DEFAULT_TIE_PENALTY_FACTOR * stiffness;
            for t in group.ties {
                let spec = &case.interfaces[t.interface];
                let penalty = spec.penalty.unwrap_or(default_penalty);
                let law = match spec.coupling {
                    InterfaceCoupling::Contact => InterfaceLaw::Contact {
                        normal_penalty: penalty,
                        tangential_penalty: spec
                            .tangential_penalty
                            .unwrap_or(DEFAULT_TANGENTIAL_PENALTY_FACTOR * stiffness),
                        friction: spec.friction.unwrap_or(0.0),
                    },
                    _ => InterfaceLaw::Tie { penalty },
                };
                let rigid = rigid_frames.get(&t.structure).copied();
                let (mesh, ids) = match rigid {
                    Some(_) => (&rigid_list.iter().find(|(k, _)| *k == t.structure).expect("a rigid domain").1, None),
                    None => (
                        &meshes[fem_list.iter().position(|(k, _)| *k == t.structure).expect("an fem domain")],
                        Some(ids_of_structure[&t.structure]),
                    ),
                };
                let facets: Vec<InterfaceFacet> = t
                    .facets
                    .iter()
                    .map(|f| InterfaceFacet {
                        nodes: f.map(|a| ids.map_or(a, |ids| ids[a])),
                        reference: f.map(|a| [mesh.coords[a][0], mesh.coords[a][1]]),
                    })
                    .collect();
                // where the soil's force acts: the facet nodes, or a rigid body's centre
                let mut nodes: Vec<usize> = match rigid {
                    Some(frame) => vec![frame.centre_node],
                    None => facets.iter().flat_map(|f| f.nodes).collect(),
                };
                nodes.sort_unstable();
                nodes.dedup();
                let mut facet_nodes: Vec<usize> = facets.iter().flat_map(|f| f.nodes).collect();
                facet_nodes.sort_unstable();
                facet_nodes.dedup();
                let summary = InterfaceSummary {
                    name: spec.name.clone(),
                    nodes: facet_nodes.len(),
                    measure: t.length,
                    slip: false,
                    law: Some(law),
                };
                interfaces[t.interface] = Some(ResolvedInterface { summary, part: part_key, soil_nodes: nodes });
                let interface = InterfacePoints::new(
                    &spec.name,
                    case.formulation,
                    case.thickness,
                    grid.clone(),
                    node_ids.clone(),
                    domain.soil_nodes(),
                    facets,
                    law,
                );
                let interface =
                    if law.is_contact() { interface.with_soil_points(domain.soil_points()) } else { interface };
                let interface = match rigid {
                    Some(frame) => interface.on_rigid_body(frame),
                    None => interface,
                };
                ties.push(match spec.gap_tolerance {
                    Some(tolerance) => interface.with_gap_tolerance(tolerance),
                    None => interface,
                });
            }
        }
        parts.push((part_key, Part::Grid(Box::new(GridPart { domain, bodies, coupling }))));
    }
    for ((k, mesh), ids) in fem_list.into_iter().zip(fem_ids) {
        let d = &case.domains[k];
        let build = match d.element_formulation {
            ElementFormulation::Displacement => FemDomain::new,
            ElementFormulation::MixedUp => FemDomain::new_mixed,
        };
        let domain = build(
            &d.name,
            mesh,
            ids,
            case.formulation,
            case.thickness,
            laws[d.material.as_str()].clone(),
            d.mass_matrix == Some(MassMatrix::Lumped),
        )
        .map_err(|e| CaseError::new(format!("domains[{k}].mesh"), format!("element {}: {}", e.element, e.message)))?;
        parts.push((k, Part::Fem(k, Box::new(domain))));
    }
    let mut rigid_bodies = Vec::new();
    for (k, mesh) in rigid_list {
        let d = &case.domains[k];
        let density = laws[d.material.as_str()].density();
        let body = RigidBody::new(&d.name, mesh, rigid_frames[&k], density, case.formulation, case.thickness);
        let held = d.motion.as_ref().is_some_and(|m| {
            m.displacement.len() == 2 && m.displacement.iter().all(Option::is_some) && m.rotation.is_some()
        });
        let body = if held { body.driven() } else { body };
        let motion = d.motion.clone().unwrap_or_default();
        let (mass, inertia) = body.mass_and_inertia();
        rigid_bodies.push(RigidSummary {
            name: d.name.clone(),
            mass,
            inertia,
            centre: body.frame().centre,
            held: [
                motion.displacement.first().copied().flatten().is_some(),
                motion.displacement.get(1).copied().flatten().is_some(),
                motion.rotation.is_some(),
            ],
        });
        parts.push((k, Part::Rigid(k, Box::new(body))));
    }
    // the parts in the case's order (a grid where its first body is)
    parts.sort_by_key(|(k, _)| *k);
    let interfaces = interfaces
        .into_iter()
        .map(|i| {
            let mut i = i.expect("every interface is on a grid");
            i.part = parts.iter().position(|(k, _)| *k == i.part).expect("the grid's part");
            i
        })
        .collect();
    for nodes in node_groups.values_mut() {
        nodes.sort_unstable();
        nodes.dedup();
    }
    Ok(Discretisation {
        coords,
        roles,
        groups: node_groups,
        parts: parts.into_iter().map(|(_, p)| p).collect(),
        interfaces,
        ties,
        rigid_frames: rigid_frames.into_iter().map(|(k, f)| (case.domains[k].name.clone(), f)).collect(),
        rigid_bodies,
    })
}

/// The MPM domain of a grid with its bodies `(case index, points)`: ids in body order,
/// initial velocity, PIC blend and initial stress of each. Returns it with the bodies' case
/// indices.
fn grid_domain(
    case: &Case,
    laws: &BTreeMap<&str, Arc<dyn ConstitutiveLaw>>,
    grid: Grid,
    node_ids: Vec<usize>,
    bodies: Vec<(usize, MaterialPoints)>,
) -> Result<(MpmDomain, Vec<usize>), CaseError> {
    let dim = case.formulation.dim();
    let mut domain: Option<MpmDomain> = None;
    let mut indices = Vec::with_capacity(bodies.len());
    let smooth = grid.basis().is_smooth();
    let mut grid = Some(grid);
    let mut node_ids = Some(node_ids);
    let first = bodies[0].0;
    for (k, mut points) in bodies {
        let d = &case.domains[k];
        // what the bodies on one grid share (its cells integrate them together)
        let first_domain = &case.domains[first];
        for (key, what, here, there) in [
            (
                "element_formulation",
                "element formulation",
                d.element_formulation.as_str(),
                first_domain.element_formulation.as_str(),
            ),
            ("quadrature", "quadrature", d.quadrature.as_str(), first_domain.quadrature.as_str()),
        ] {
            if here != there {
                return Err(CaseError::new(
                    format!("domains[{k}].{key}"),
                    format!(
                        "the bodies on one grid share their {what}: '{}' on the same grid has {there}",
                        first_domain.name
                    ),
                ));
            }
        }
        if smooth && d.quadrature == Quadrature::FilledCells {
            return Err(CaseError::new(
                format!("domains[{k}].quadrature"),
                "filled_cells scales the points' weights per cell of the linear basis; a smooth grid.basis integrates over the points' own volumes (material_points)",
            ));
        }
        let default_alpha = default_ghost_penalty(case);
        let alpha = d.ghost_penalty.unwrap_or(default_alpha);
        if !(alpha.is_finite() && (0.0..=1e3).contains(&alpha)) {
            return Err(CaseError::new(
                format!("domains[{k}].ghost_penalty"),
                format!("must be a number in [0, 1000] (e.g. 0.1; 0 switches it off), got {alpha}"),
            ));
        }
        if alpha != first_domain.ghost_penalty.unwrap_or(default_alpha) {
            return Err(CaseError::new(
                format!("domains[{k}].ghost_penalty"),
                format!(
                    "the bodies on one grid share their ghost penalty: '{}' on the same grid has {}",
                    first_domain.name,
                    first_domain.ghost_penalty.unwrap_or(default_alpha)
                ),
            ));
        }
        let law = laws[d.material.as_str()].clone();
        if let Some(v0) = &d.initial_velocity {
            for (x, v) in points.position.iter().zip(points.velocity.iter_mut()) {
                *v = v0.at(x, dim);
            }
        }
        let density = law.density();
        if let Some(InitialStressSpec::Geostatic { surface, .. }) = d.initial_stress {
            check_geostatic_surface(k, surface, &points, dim)?;
        }
        let offset = domain.as_ref().map_or(0, MpmDomain::next_point_id);
        let mut body = Body::new(&d.name, law, points, offset);
        body.set_velocity_blend(velocity_blend(case, k)?);
        if let Some(InitialStressSpec::Geostatic { surface, k0 }) = d.initial_stress {
            let loc = format!("domains[{k}].initial_stress.geostatic");
            if !(k0 >= 0.0 && k0.is_finite()) {
                return Err(CaseError::new(format!("{loc}.k0"), format!("must be ≥ 0, got {k0}")));
            }
            let g = case.gravity.as_ref().map_or(0.0, |g| g.acceleration.get(dim - 1).copied().unwrap_or(0.0));
            if g >= 0.0 {
                return Err(CaseError::new(
                    &loc,
                    "a geostatic stress needs gravity pointing down (negative last component)",
                ));
            }
            let vertical = dim - 1;
            let stress = |x: &[f64; 3]| {
                let sigma_v = density * g * (surface - x[vertical]).max(0.0);
                let mut s = Matrix3::from_diagonal_element(k0 * sigma_v);
                s[(vertical, vertical)] = sigma_v;
                s
            };
            body.set_initial_stress(stress)
                .map_err(|(p, e)| CaseError::new(&loc, format!("material point {p}: {e}")))?;
            check_initial_state(&loc, &*laws[d.material.as_str()], &body.points, &stress)?;
        }
        match domain.as_mut() {
            Some(domain) => domain.add_body(body),
            None => {
                let mut first_domain = MpmDomain::new(
                    grid.take().expect("once"),
                    node_ids.take().expect("once"),
                    case.formulation,
                    case.thickness,
                    body,
                );
                first_domain.set_quadrature(match d.quadrature {
                    Quadrature::MaterialPoints => PointQuadrature::MaterialPoints,
                    Quadrature::FilledCells => PointQuadrature::FilledCells,
                });
                first_domain.set_ghost_penalty(alpha);
                first_domain.set_pattern_rings(case.solver.mpm_pattern_rings);
                domain = Some(first_domain);
            }
        }
        indices.push(k);
    }
    Ok((domain.expect("a grid has a body"), indices))
}

/// The ghost penalty of an MPM grid whose domain does not set `ghost_penalty`:
/// [`DEFAULT_GHOST_PENALTY`] where the analysis has no inertia (static and quasi-static: a
/// node the material only grazes has nothing else to hold it), 0 in dynamic analyses, whose
/// tangent holds every node with mass by `M/(βΔt²)` and whose granular flows keep their
/// validated results without it (`loam_mpm::ghost_penalty`).
fn default_ghost_penalty(case: &Case) -> f64 {
    match case.analysis.kind {
        AnalysisType::Dynamic => 0.0,
        AnalysisType::Static | AnalysisType::QuasiStatic => DEFAULT_GHOST_PENALTY,
    }
}

/// Every material point must be able to carry its initial stress: the law is evaluated at
/// rest (`F = I`) from the state that stress gave it. A material too soft for its stress
/// (E = 1 Pa under a geostatic column) needs an elastic strain the law cannot represent;
/// refused here, it used to stop the run at its first step with "inverted deformation
/// gradient (det F = 1)" (issue 16).
fn check_initial_state(
    loc: &str,
    law: &dyn ConstitutiveLaw,
    points: &MaterialPoints,
    stress: &dyn Fn(&[f64; 3]) -> Matrix3<f64>,
) -> Result<(), CaseError> {
    let n = law.state_len();
    let mut trial = vec![0.0; n];
    for p in 0..points.len() {
        let state = &points.state[p * n..(p + 1) * n];
        trial.copy_from_slice(state);
        let kinematics = Kinematics {
            deformation_gradient: Matrix3::identity(),
            previous_deformation_gradient: Matrix3::identity(),
            time_step: 0.0,
            tangent: TangentRequest::None,
        };
        let sigma = stress(&points.position[p]);
        let failure = match law.stress_response(&kinematics, state, &mut trial) {
            Err(e) => Some(e.to_string()),
            Ok(r)
                if (r.first_piola - sigma).amax() > 1e-6 * sigma.amax().max(1.0)
                    || !r.first_piola.amax().is_finite() =>
            {
                Some(format!("it gives back σ_yy = {:.3e} Pa", r.first_piola[(1, 1)]))
            }
            Ok(_) => None,
        };
        if let Some(f) = failure {
            let x = points.position[p];
            return Err(CaseError::new(
                loc,
                format!(
                    "material point {p} at ({:.4e}, {:.4e}) cannot start at rest under its initial stress (largest component {:.3e} Pa): the law fails on it ({f}): the elastic strain this stress needs is beyond the law's range; is the material too soft for it?",
                    x[0],
                    x[1],
                    sigma.amax()
                ),
            ));
        }
    }
    Ok(())
}

/// A geostatic `surface` must not lie below the body's highest material point: the points
/// above it would start without any stress (issue 16: a surface below the whole body gave
/// zero stress everywhere without a word).
fn check_geostatic_surface(k: usize, surface: f64, points: &MaterialPoints, dim: usize) -> Result<(), CaseError> {
    let top = points.position.iter().map(|x| x[dim - 1]).fold(f64::NEG_INFINITY, f64::max);
    if surface < top {
        let axis = if dim == 2 { "y" } else { "z" };
        return Err(CaseError::new(
            format!("domains[{k}].initial_stress.geostatic.surface"),
            format!(
                "{surface} m lies below the body's highest material point ({axis} = {top:.6} m): the points above it would start without stress"
            ),
        ));
    }
    Ok(())
}

/// The PIC blend of the MPM domain `k`.
fn velocity_blend(case: &Case, k: usize) -> Result<VelocityBlend, CaseError> {
    let d = &case.domains[k];
    if !(0.0..=1.0).contains(&d.pic_fraction) {
        return Err(CaseError::new(
            format!("domains[{k}].pic_fraction"),
            format!("must lie in [0, 1], got {}", d.pic_fraction),
        ));
    }
    match d.pic_relaxation_time {
        None => Ok(VelocityBlend::PicFraction(d.pic_fraction)),
        Some(_) if d.pic_fraction != 0.0 => Err(CaseError::new(
            format!("domains[{k}].pic_relaxation_time"),
            "give either pic_fraction or pic_relaxation_time, not both",
        )),
        Some(tau) if tau > 0.0 && tau.is_finite() => Ok(VelocityBlend::RelaxationTime(tau)),
        Some(tau) => Err(CaseError::new(
            format!("domains[{k}].pic_relaxation_time"),
            format!("must be a positive time in s, got {tau}"),
        )),
    }
}

/// Puts the parts into the model as domains, in the case's order, and gives FEM domains
/// their initial velocity. Returns, by rigid domain name, the index of the constraint of its
/// prescribed motion (whose amplitude an FMU input can drive).
pub(super) fn place_domains(
    case: &Case,
    model: &mut Model,
    parts: Vec<Part>,
) -> Result<BTreeMap<String, usize>, CaseError> {
    let dim = case.formulation.dim();
    let mut motions = BTreeMap::new();
    for part in parts {
        match part {
            Part::Fem(k, domain) => {
                if let Some(v0) = &case.domains[k].initial_velocity {
                    for &g in domain.node_ids() {
                        let v = v0.at(&model.coords[g], dim);
                        model.committed.v[g * dim..(g + 1) * dim].copy_from_slice(&v[..dim]);
                    }
                    model.state.v.clone_from(&model.committed.v);
                }
                model.domains.push(domain);
            }
            Part::Grid(grid) => model.domains.push(Box::new(grid.domain)),
            Part::Rigid(k, body) => {
                if let Some(c) = place_rigid(case, k, model, &body) {
                    motions.insert(case.domains[k].name.clone(), c);
                }
                model.domains.push(body);
            }
        }
    }
    Ok(motions)
}

/// A rigid body's initial velocity and prescribed motion in `model`: `initial_velocity`
/// (uniform) on its centre, `initial_angular_velocity` on its rotation, one constraint for the
/// prescribed entries of `motion` (scaled by its amplitude) and one holding the rotation
/// node's unused second DOF. Returns the index of the motion's constraint, if it prescribes
/// anything.
fn place_rigid(case: &Case, k: usize, model: &mut Model, body: &RigidBody) -> Option<usize> {
    let d = &case.domains[k];
    let [x, y, theta] = body.frame().dofs();
    if let Some(v0) = &d.initial_velocity {
        let v = v0.at(&[0.0; 3], 2);
        (model.committed.v[x], model.committed.v[y]) = (v[0], v[1]);
    }
    model.committed.v[theta] = d.initial_angular_velocity.unwrap_or(0.0);
    model.state.v.clone_from(&model.committed.v);
    let motion = d.motion.clone().unwrap_or_default();
    let prescribed: Vec<(usize, f64)> = [x, y]
        .into_iter()
        .zip(motion.displacement.iter().copied().chain([None, None]))
        .chain([(theta, motion.rotation)])
        .filter_map(|(dof, v)| v.map(|v| (dof, v)))
        .collect();
    let motion_constraint = (!prescribed.is_empty()).then(|| {
        let (dofs, values) = prescribed.into_iter().unzip();
        model.constraints.push(loam_fem::model::Constraint { dofs, values, amplitude: motion.amplitude });
        model.constraints.len() - 1
    });
    let unused = 2 * body.frame().rotation_node + 1;
    model.constraints.push(loam_fem::model::Constraint {
        dofs: vec![unused],
        values: vec![0.0],
        amplitude: Default::default(),
    });
    motion_constraint
}

/// Mean cell size `h = (V_box / cells)^(1/dim)` of a mesh (the length in the equilibration
/// scale `μ/h` of the pressure equations).
fn mean_cell_size(mesh: &Mesh) -> f64 {
    let dim = mesh.element.dim();
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for c in &mesh.coords {
        for d in 0..dim {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
    }
    let volume: f64 = (0..dim).map(|d| (hi[d] - lo[d]).max(1e-300)).product();
    (volume / mesh.num_cells().max(1) as f64).powf(1.0 / dim as f64)
}

/// Gives every node of the mixed u–p parts a pressure DOF in `model` (shared where two u–p
/// parts share a node), with the equilibration scale `μ/h` of the part's material and cells.
pub(super) fn assign_pressure_dofs(case: &Case, model: &mut Model, parts: &mut [Part]) {
    for part in parts.iter_mut() {
        match part {
            Part::Fem(k, domain) if case.domains[*k].element_formulation == ElementFormulation::MixedUp => {
                let mu = domain.law().mixed().expect("checked").shear_modulus();
                let scale = mu / mean_cell_size(domain.mesh());
                let dofs = model.add_pressure_dofs(domain.node_ids(), scale);
                domain.set_pressure_dofs(dofs);
            }
            Part::Grid(grid) if case.domains[grid.bodies[0]].element_formulation == ElementFormulation::MixedUp => {
                let mu = grid
                    .domain
                    .bodies()
                    .iter()
                    .map(|b| b.law().mixed().expect("checked").shear_modulus())
                    .fold(0.0, f64::max);
                let scale = mu / mean_cell_size(&grid.domain.grid().mesh);
                let dofs = model.add_pressure_dofs(grid.domain.node_ids(), scale);
                grid.domain.set_pressure_dofs(dofs, scale);
            }
            _ => {}
        }
    }
}
