//! From a parsed [`Case`] to a solvable [`Model`]: meshes, shared nodes, regions,
//! constraints, loads and monitors, with every consistency check that needs more than the
//! JSON schema (empty regions, missing materials, inverted elements, wrong vector lengths).

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use loam_fem::domain::{PointLoad, PointQuantity, PointTensor};
use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::loads::{facet_forces, SurfaceLoad};
use loam_fem::mesh::Mesh;
use loam_fem::model::{Constraint, Load, Model};
use loam_fem::scheme::TimeScheme;
use loam_fem::slip::Slip;
use loam_fem::solid_domain::FemDomain;
use loam_laws::ConstitutiveLaw;
use loam_mpm::grid::Grid;
use loam_mpm::material_points::{self, MaterialPoints};
use loam_mpm::mpm_domain::{MpmDomain, VelocityBlend};
use loam_mpm::penalty_boundary::{BoundaryParticles, PenaltyBoundary, PenaltyKind, PenaltySettings};

use crate::case::{
    AnalysisType, BodySpec, Case, CaseError, Component, DomainKind, GridSpec, InitialStressSpec, InitialVelocity,
    InputTarget, LoadSpec, MassMatrix, MeshSpec, MonitorSpec, PenaltySpec, PointBox, RegionSpec,
};
use crate::monitor::{Monitor, MonitorKind};
use nalgebra::Matrix3;

/// A model ready to run, with the monitors resolved to nodes and regions.
pub struct BuiltModel {
    /// The model.
    pub model: Model,
    /// Monitors in case-file order.
    pub monitors: Vec<Monitor>,
    /// Node sets of the regions (global ids).
    pub regions: BTreeMap<String, Vec<usize>>,
    /// Named inputs (`fmu.inputs`), resolved to their targets in the model.
    pub inputs: Vec<ModelInput>,
    /// Named outputs (`fmu.outputs`, or every monitor), resolved to monitors.
    pub outputs: Vec<ModelOutput>,
}

/// Where an input acts in the [`Model`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputSlot {
    /// `model.loads[i]`.
    Load(usize),
    /// `model.constraints[i]`.
    Constraint(usize),
    /// `model.gravity`.
    Gravity,
}

/// A named input resolved to its target.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInput {
    /// Variable name.
    pub name: String,
    /// The amplitude it replaces.
    pub slot: InputSlot,
    /// Unit (`1` for a factor).
    pub unit: String,
    /// Start value (FMI `start`).
    pub start: f64,
    /// Description.
    pub description: String,
}

/// A named output resolved to a monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelOutput {
    /// Variable name.
    pub name: String,
    /// Index into the monitors.
    pub monitor: usize,
    /// Unit.
    pub unit: String,
    /// Description.
    pub description: String,
}

fn check_positive(location: &str, value: f64) -> Result<(), CaseError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(CaseError::new(location, format!("must be > 0, got {value}")))
    }
}

fn check_len(location: &str, v: &[impl Sized], dim: usize) -> Result<(), CaseError> {
    if v.len() == dim {
        Ok(())
    } else {
        Err(CaseError::new(location, format!("needs {dim} components (one per coordinate), got {}", v.len())))
    }
}

fn component_index(location: &str, c: Component, dim: usize) -> Result<Option<usize>, CaseError> {
    let i = match c {
        Component::X => 0,
        Component::Y => 1,
        Component::Z => 2,
        Component::Magnitude => return Ok(None),
    };
    if i < dim {
        Ok(Some(i))
    } else {
        Err(CaseError::new(location, format!("component z does not exist in a {dim}D model")))
    }
}

/// Builds the mesh described by `spec` (at JSON path `loc`).
fn build_mesh(case: &Case, loc: &str, spec: &MeshSpec) -> Result<Mesh, CaseError> {
    let dim = case.formulation.dim();
    let mesh = match spec {
        MeshSpec::Rectangle { origin, size, cells, element } => {
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
            Mesh::rectangle(*origin, *size, *cells, *element)
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
            Mesh::cuboid(*origin, *size, *cells, *element)
        }
        MeshSpec::Gmsh(file) => {
            let path = case.directory.join(file);
            loam_fem::gmsh::read_gmsh(&path).map_err(|e| CaseError::new(format!("{loc}.gmsh"), e.to_string()))?
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

/// The mesh of domain `k` (for MPM: the grid, with the grid and the material points).
fn build_discretisation(
    case: &Case,
    k: usize,
    density: f64,
) -> Result<(Mesh, Option<(Grid, MaterialPoints)>), CaseError> {
    let d = &case.domains[k];
    let loc = format!("domains[{k}]");
    let dim = case.formulation.dim();
    let misplaced = |key: &str| {
        CaseError::new(
            format!("{loc}.{key}"),
            format!(
                "does not apply to an {} domain",
                match d.kind {
                    DomainKind::Fem => "fem",
                    DomainKind::Mpm => "mpm",
                }
            ),
        )
    };
    match d.kind {
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
            let spec =
                d.mesh.as_ref().ok_or_else(|| CaseError::new(format!("{loc}.mesh"), "an fem domain needs a mesh"))?;
            Ok((build_mesh(case, &format!("{loc}.mesh"), spec)?, None))
        }
        DomainKind::Mpm => {
            if d.mesh.is_some() {
                return Err(misplaced("mesh"));
            }
            let grid = match (&d.grid, &d.grid_mesh) {
                (Some(_), Some(_)) => {
                    return Err(CaseError::new(format!("{loc}.grid_mesh"), "give either grid or grid_mesh, not both"));
                }
                (None, None) => {
                    return Err(CaseError::new(format!("{loc}.grid"), "an mpm domain needs a grid (or a grid_mesh)"));
                }
                (Some(g), None) => structured_grid(case, &loc, g)?,
                (None, Some(spec)) => Grid::unstructured(build_mesh(case, &format!("{loc}.grid_mesh"), spec)?),
            };
            let body_loc = format!("{loc}.material_points");
            let body = d
                .material_points
                .as_ref()
                .ok_or_else(|| CaseError::new(&body_loc, "an mpm domain needs material_points"))?;
            let (f, t) = (case.formulation, case.thickness);
            let points = match body {
                BodySpec::Cells { mesh, points_per_cell } => {
                    let m = build_mesh(case, &format!("{body_loc}.cells.mesh"), mesh)?;
                    material_points::from_mesh(&m, *points_per_cell, f, t, density)
                        .map_err(|e| CaseError::new(format!("{body_loc}.cells.points_per_cell"), e))?
                }
                BodySpec::Disk { centre, radius, spacing } => {
                    check_positive(&format!("{body_loc}.disk.radius"), *radius)?;
                    check_positive(&format!("{body_loc}.disk.spacing"), *spacing)?;
                    let (c, r) = (*centre, *radius);
                    material_points::from_lattice_2d(
                        [c[0] - r, c[1] - r],
                        [c[0] + r, c[1] + r],
                        *spacing,
                        f,
                        t,
                        density,
                        |x, y| (x - c[0]).powi(2) + (y - c[1]).powi(2) <= r * r,
                    )
                }
                BodySpec::Polygon { vertices, spacing } => {
                    check_positive(&format!("{body_loc}.polygon.spacing"), *spacing)?;
                    if vertices.len() < 3 {
                        return Err(CaseError::new(
                            format!("{body_loc}.polygon.vertices"),
                            "needs at least 3 vertices",
                        ));
                    }
                    let lo = [0, 1].map(|d| vertices.iter().map(|v| v[d]).fold(f64::MAX, f64::min));
                    let hi = [0, 1].map(|d| vertices.iter().map(|v| v[d]).fold(f64::MIN, f64::max));
                    material_points::from_lattice_2d(lo, hi, *spacing, f, t, density, |x, y| {
                        point_in_polygon(vertices, x, y)
                    })
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
            Ok((grid.mesh.clone(), Some((grid, points))))
        }
    }
}

/// The structured grid of `g` (at JSON path `loc`), checked.
fn structured_grid(case: &Case, loc: &str, g: &GridSpec) -> Result<Grid, CaseError> {
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
    Ok(Grid::rotated(origin, size, cells, g.element, g.rotation.to_radians()))
}

/// Area-weighted mean outward normal of the boundary facets of all domains whose nodes all
/// lie in `nodes`.
fn mean_boundary_normal(model: &Model, nodes: &[usize]) -> Option<[f64; 3]> {
    let set: std::collections::HashSet<usize> = nodes.iter().copied().collect();
    let mut sum = [0.0; 3];
    let mut found = false;
    for f in model.domains.iter().flat_map(|d| d.boundary_facets()) {
        if !f.iter().all(|n| set.contains(n)) {
            continue;
        }
        found = true;
        let x: Vec<[f64; 3]> = f.iter().map(|&n| model.coords[n]).collect();
        let n = match x.len() {
            2 => [x[1][1] - x[0][1], x[0][0] - x[1][0], 0.0],
            _ => {
                let (a, b) = ([0, 1, 2].map(|d| x[1][d] - x[0][d]), [0, 1, 2].map(|d| x[2][d] - x[0][d]));
                [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            }
        };
        for d in 0..3 {
            sum[d] += n[d];
        }
    }
    found.then_some(sum)
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

fn select_region(
    name: &str,
    spec: &RegionSpec,
    coords: &[[f64; 3]],
    dim: usize,
    groups: &BTreeMap<String, Vec<usize>>,
    tol: f64,
) -> Result<Vec<usize>, CaseError> {
    let loc = format!("regions.{name}");
    let pick = |f: &dyn Fn(&[f64; 3]) -> bool| (0..coords.len()).filter(|&n| f(&coords[n])).collect::<Vec<_>>();
    let nodes = match spec {
        RegionSpec::X(v) => pick(&|c| (c[0] - v).abs() <= tol),
        RegionSpec::Y(v) => pick(&|c| (c[1] - v).abs() <= tol),
        RegionSpec::Z(v) => {
            if dim < 3 {
                return Err(CaseError::new(format!("{loc}.z"), "z does not exist in a 2D model"));
            }
            pick(&|c| (c[2] - v).abs() <= tol)
        }
        RegionSpec::Box { min, max } => {
            check_len(&format!("{loc}.box.min"), min, dim)?;
            check_len(&format!("{loc}.box.max"), max, dim)?;
            pick(&|c| (0..dim).all(|d| c[d] >= min[d] - tol && c[d] <= max[d] + tol))
        }
        RegionSpec::Segment { from, to } => {
            check_len(&format!("{loc}.segment.from"), from, dim)?;
            check_len(&format!("{loc}.segment.to"), to, dim)?;
            let d: Vec<f64> = (0..dim).map(|i| to[i] - from[i]).collect();
            let l2: f64 = d.iter().map(|x| x * x).sum();
            pick(&|c| {
                let s = if l2 > 0.0 {
                    ((0..dim).map(|i| (c[i] - from[i]) * d[i]).sum::<f64>() / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (0..dim).map(|i| (c[i] - from[i] - s * d[i]).powi(2)).sum::<f64>().sqrt() <= tol
            })
        }
        RegionSpec::Nearest(p) => {
            check_len(&format!("{loc}.nearest"), p, dim)?;
            nearest_node(coords, p).into_iter().collect()
        }
        RegionSpec::Group(g) => groups
            .get(g)
            .cloned()
            .ok_or_else(|| CaseError::new(format!("{loc}.group"), format!("no Gmsh physical group named '{g}'")))?,
        RegionSpec::All(true) => (0..coords.len()).collect(),
        RegionSpec::All(false) => Vec::new(),
    };
    if nodes.is_empty() {
        return Err(CaseError::new(loc, "selects no node (check the coordinates against the mesh)"));
    }
    Ok(nodes)
}

/// Material points (domain index, id) selected at `loc` by `point` (the nearest one) or
/// `box` (every one inside), in domain `domain` or in any domain; an empty selection is an
/// error.
fn select_points(
    model: &Model,
    loc: &str,
    dim: usize,
    domain: Option<usize>,
    point: Option<&[f64]>,
    within: Option<&PointBox>,
) -> Result<Vec<(usize, usize)>, CaseError> {
    let candidates = |k: &usize| domain.is_none_or(|d| d == *k);
    let selected: Vec<(usize, usize)> = match (point, within) {
        (Some(p), None) => {
            check_len(&format!("{loc}.point"), p, dim)?;
            model
                .domains
                .iter()
                .enumerate()
                .filter(|(k, _)| candidates(k))
                .filter_map(|(k, d)| d.nearest_point(p).map(|(id, dist)| (k, id, dist)))
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map(|(k, id, _)| vec![(k, id)])
                .unwrap_or_default()
        }
        (None, Some(b)) => {
            check_len(&format!("{loc}.box.min"), &b.min, dim)?;
            check_len(&format!("{loc}.box.max"), &b.max, dim)?;
            model
                .domains
                .iter()
                .enumerate()
                .filter(|(k, _)| candidates(k))
                .flat_map(|(k, d)| d.points_in_box(&b.min, &b.max).into_iter().map(move |id| (k, id)))
                .collect()
        }
        _ => return Err(CaseError::new(loc, "give either point or box")),
    };
    if selected.is_empty() {
        let place = match domain {
            Some(d) => format!("domain '{}'", model.domains[d].name()),
            None => "the model".into(),
        };
        return Err(CaseError::new(
            format!("{loc}.{}", if point.is_some() { "point" } else { "box" }),
            format!("selects no material point ({place} has none there)"),
        ));
    }
    Ok(selected)
}

/// Index of the node nearest to `p` (first `p.len()` coordinates).
pub fn nearest_node(coords: &[[f64; 3]], p: &[f64]) -> Option<usize> {
    let dist = |c: &[f64; 3]| p.iter().enumerate().map(|(d, v)| (c[d] - v).powi(2)).sum::<f64>();
    (0..coords.len()).min_by(|&a, &b| dist(&coords[a]).total_cmp(&dist(&coords[b])))
}

/// Builds the model of `case`.
pub fn build_model(case: &Case) -> Result<BuiltModel, CaseError> {
    let dim = case.formulation.dim();
    check_positive("thickness", case.thickness)?;
    check_positive("analysis.time_step", case.analysis.time_step)?;
    check_positive("analysis.end_time", case.analysis.end_time)?;
    if case.analysis.time_step > case.analysis.end_time * (1.0 + 1e-12) {
        return Err(CaseError::new("analysis.time_step", "is longer than analysis.end_time"));
    }
    check_positive("solver.residual_relative_tolerance", case.solver.residual_relative_tolerance)?;
    check_positive("solver.residual_absolute_tolerance", case.solver.residual_absolute_tolerance)?;
    if let Some(a) = &case.analysis.adaptive {
        check_positive("analysis.adaptive.min_time_step", a.min_time_step)?;
        check_positive("analysis.adaptive.max_time_step", a.max_time_step)?;
        if a.min_time_step > case.analysis.time_step || a.max_time_step < case.analysis.time_step {
            return Err(CaseError::new(
                "analysis.adaptive",
                format!(
                    "time_step {} must lie in [min_time_step, max_time_step] = [{}, {}]",
                    case.analysis.time_step, a.min_time_step, a.max_time_step
                ),
            ));
        }
        if a.target_iterations == 0 {
            return Err(CaseError::new("analysis.adaptive.target_iterations", "must be at least 1"));
        }
        if !(a.growth >= 1.0 && a.growth.is_finite()) {
            return Err(CaseError::new("analysis.adaptive.growth", format!("must be ≥ 1, got {}", a.growth)));
        }
    }
    if let Some(r) = &case.analysis.stop_at_rest {
        check_positive("analysis.stop_at_rest.kinetic_energy_ratio", r.kinetic_energy_ratio)?;
        if !(r.duration >= 0.0 && r.min_time >= 0.0) {
            return Err(CaseError::new("analysis.stop_at_rest", "duration and min_time must be ≥ 0"));
        }
    }
    if let Some(t) = case.output.time_interval {
        check_positive("output.time_interval", t)?;
    }
    for (k, &t) in case.output.times.iter().enumerate() {
        check_positive(&format!("output.times[{k}]"), t)?;
        if k > 0 && t <= case.output.times[k - 1] {
            return Err(CaseError::new(format!("output.times[{k}]"), "times must increase"));
        }
    }
    if case.solver.max_iterations == 0 {
        return Err(CaseError::new("solver.max_iterations", "must be at least 1"));
    }
    let scheme = match (case.analysis.kind, case.analysis.scheme) {
        (AnalysisType::Dynamic, None) => TimeScheme::Newmark { beta: 0.25, gamma: 0.5 },
        (AnalysisType::Dynamic, Some(TimeScheme::Static)) => {
            return Err(CaseError::new("analysis.scheme", "a dynamic analysis needs newmark or bossak"));
        }
        (AnalysisType::Dynamic, Some(s)) => s,
        (_, None) => TimeScheme::Static,
        (_, Some(TimeScheme::Static)) => TimeScheme::Static,
        (_, Some(_)) => return Err(CaseError::new("analysis.scheme", "only dynamic analyses take a time scheme")),
    };
    scheme.check().map_err(|(k, m)| CaseError::new(format!("analysis.scheme.{k}"), m))?;

    let mut laws: BTreeMap<&str, Arc<dyn ConstitutiveLaw>> = BTreeMap::new();
    for (name, spec) in &case.materials {
        let law = spec.build().map_err(|e| CaseError::new(format!("materials.{name}.{}", e.parameter), e.problem))?;
        laws.insert(name, Arc::from(law));
    }
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
                format!("no material named '{}' in materials", d.material),
            ));
        }
    }
    let mut meshes = Vec::new();
    let mut bodies = Vec::new();
    for (k, d) in case.domains.iter().enumerate() {
        let (mesh, body) = build_discretisation(case, k, laws[d.material.as_str()].density())?;
        meshes.push(mesh);
        bodies.push(body);
    }
    let (coords, ids) = merge_nodes(&meshes);
    let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (m, id) in meshes.iter().zip(&ids) {
        for (g, nodes) in &m.node_groups {
            let e = groups.entry(g.clone()).or_default();
            e.extend(nodes.iter().map(|&n| id[n]));
            e.sort_unstable();
            e.dedup();
        }
    }
    let mut model = Model::new(dim, coords, scheme, case.solver);
    // grid and global node ids of every MPM domain, for penalty walls
    let mut mpm_grids: BTreeMap<&str, (Grid, Vec<usize>)> = BTreeMap::new();
    for (k, ((d, body), (mesh, id))) in case.domains.iter().zip(bodies).zip(meshes.into_iter().zip(ids)).enumerate() {
        let law = laws[d.material.as_str()].clone();
        if let Some(v0) = &d.initial_velocity {
            let loc = format!("domains[{k}].initial_velocity");
            match v0 {
                InitialVelocity::Uniform(u) => check_len(&format!("{loc}.uniform"), u, dim)?,
                InitialVelocity::Sine { amplitude, wavenumber } => {
                    check_len(&format!("{loc}.sine.amplitude"), amplitude, dim)?;
                    check_len(&format!("{loc}.sine.wavenumber"), wavenumber, dim)?;
                }
            }
        }
        if let Some((grid, mut points)) = body {
            if let Some(v0) = &d.initial_velocity {
                for (x, v) in points.position.iter().zip(points.velocity.iter_mut()) {
                    *v = v0.at(x, dim);
                }
            }
            let density = law.density();
            mpm_grids.insert(&d.name, (grid.clone(), id.clone()));
            let mut domain = MpmDomain::new(&d.name, grid, id, case.formulation, case.thickness, law, points);
            if !(0.0..=1.0).contains(&d.pic_fraction) {
                return Err(CaseError::new(
                    format!("domains[{k}].pic_fraction"),
                    format!("must lie in [0, 1], got {}", d.pic_fraction),
                ));
            }
            let blend = match d.pic_relaxation_time {
                None => VelocityBlend::PicFraction(d.pic_fraction),
                Some(_) if d.pic_fraction != 0.0 => {
                    return Err(CaseError::new(
                        format!("domains[{k}].pic_relaxation_time"),
                        "give either pic_fraction or pic_relaxation_time, not both",
                    ))
                }
                Some(tau) if tau > 0.0 && tau.is_finite() => VelocityBlend::RelaxationTime(tau),
                Some(tau) => {
                    return Err(CaseError::new(
                        format!("domains[{k}].pic_relaxation_time"),
                        format!("must be a positive time in s, got {tau}"),
                    ))
                }
            };
            domain.set_velocity_blend(blend);
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
                domain
                    .set_initial_stress(|x| {
                        let sigma_v = density * g * (surface - x[vertical]).max(0.0);
                        let mut s = Matrix3::from_diagonal_element(k0 * sigma_v);
                        s[(vertical, vertical)] = sigma_v;
                        s
                    })
                    .map_err(|(p, e)| CaseError::new(&loc, format!("material point {p}: {e}")))?;
            }
            model.domains.push(Box::new(domain));
            continue;
        }
        if let Some(v0) = &d.initial_velocity {
            for &g in &id {
                let v = v0.at(&model.coords[g], dim);
                model.committed.v[g * dim..(g + 1) * dim].copy_from_slice(&v[..dim]);
            }
            model.state.v.clone_from(&model.committed.v);
        }
        let domain = FemDomain::new(
            &d.name,
            mesh,
            id,
            case.formulation,
            case.thickness,
            law,
            d.mass_matrix == MassMatrix::Lumped,
        )
        .map_err(|e| CaseError::new(format!("domains[{k}].mesh"), format!("element {}: {}", e.element, e.message)))?;
        model.domains.push(Box::new(domain));
    }

    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for c in &model.coords {
        for d in 0..3 {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
    }
    let tol = 1e-6 * (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let mut regions = BTreeMap::new();
    for (name, spec) in &case.regions {
        regions.insert(name.clone(), select_region(name, spec, &model.coords, dim, &groups, tol)?);
    }
    let region = |loc: String, name: &str| -> Result<&Vec<usize>, CaseError> {
        regions.get(name).ok_or_else(|| CaseError::new(loc, format!("no region named '{name}' in regions")))
    };

    let mut constraint_of_bc = Vec::with_capacity(case.boundary_conditions.len());
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        if let Some(spec) = &bc.penalty {
            // after every case domain: the wall reads the nodal masses they project
            let wall = build_penalty_wall(case, k, spec, &mpm_grids)?;
            model.domains.push(Box::new(wall));
            constraint_of_bc.push(model.constraints.len());
            model.constraints.push(Constraint::without_dofs(bc.amplitude.clone()));
            continue;
        }
        if bc.region.is_empty() {
            return Err(CaseError::new(format!("boundary_conditions[{k}]"), "needs a region (or a penalty wall)"));
        }
        let nodes = region(format!("boundary_conditions[{k}].region"), &bc.region)?;
        if let Some(slip) = &bc.slip {
            if !bc.displacement.is_empty() {
                return Err(CaseError::new(
                    format!("boundary_conditions[{k}]"),
                    "give either displacement or slip, not both",
                ));
            }
            let normal = match &slip.normal {
                Some(n) => {
                    check_len(&format!("boundary_conditions[{k}].slip.normal"), n, dim)?;
                    let mut v = [0.0; 3];
                    v[..dim].copy_from_slice(n);
                    v
                }
                None => mean_boundary_normal(&model, nodes).ok_or_else(|| {
                    CaseError::new(
                        format!("boundary_conditions[{k}].region"),
                        format!("region '{}' contains no boundary edge or face to take a slip normal from", bc.region),
                    )
                })?,
            };
            if normal[..dim].iter().map(|v| v * v).sum::<f64>() <= 0.0 {
                return Err(CaseError::new(format!("boundary_conditions[{k}].slip.normal"), "must not be zero"));
            }
            model.slips.extend(nodes.iter().map(|&node| Slip { node, normal }));
            constraint_of_bc.push(model.constraints.len());
            model.constraints.push(Constraint::without_dofs(bc.amplitude.clone()));
            continue;
        }
        check_len(&format!("boundary_conditions[{k}].displacement"), &bc.displacement, dim)?;
        bc.amplitude.check().map_err(|m| CaseError::new(format!("boundary_conditions[{k}].amplitude"), m))?;
        let mut c = Constraint::without_dofs(bc.amplitude.clone());
        for &n in nodes {
            for (i, v) in bc.displacement.iter().enumerate() {
                if let Some(v) = v {
                    c.dofs.push(n * dim + i);
                    c.values.push(*v);
                }
            }
        }
        constraint_of_bc.push(model.constraints.len());
        model.constraints.push(c);
    }

    let facets: Vec<Vec<usize>> = model.domains.iter().flat_map(|d| d.boundary_facets()).collect();
    let mut load_of_load = Vec::with_capacity(case.loads.len());
    for (k, l) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        if let LoadSpec::MaterialPointForce { domain, point, within, force, amplitude } = l {
            amplitude.check().map_err(|m| CaseError::new(format!("{loc}.amplitude"), m))?;
            check_len(&format!("{loc}.force"), force, dim)?;
            let domain = match domain {
                Some(name) => Some(model.domains.iter().position(|d| d.name() == name).ok_or_else(|| {
                    CaseError::new(format!("{loc}.domain"), format!("no domain named '{name}' in domains"))
                })?),
                None => None,
            };
            let points = select_points(&model, &loc, dim, domain, point.as_deref(), within.as_ref())?;
            let mut f = [0.0; 3];
            f[..dim].copy_from_slice(force);
            let mut domains: Vec<usize> = points.iter().map(|p| p.0).collect();
            domains.dedup();
            for d in domains {
                let ids = points.iter().filter(|p| p.0 == d).map(|p| p.1).collect();
                model.domains[d].add_point_load(PointLoad { ids, force: f, amplitude: amplitude.clone() });
            }
            load_of_load.push(usize::MAX); // not a model load; cannot be named (no FMU input)
            continue;
        }
        let (region_name, amplitude) = match l {
            LoadSpec::NodalForce { region, amplitude, .. }
            | LoadSpec::Pressure { region, amplitude, .. }
            | LoadSpec::Traction { region, amplitude, .. } => (region, amplitude),
            LoadSpec::MaterialPointForce { .. } => unreachable!("handled above"),
        };
        amplitude.check().map_err(|m| CaseError::new(format!("{loc}.amplitude"), m))?;
        let nodes = region(format!("{loc}.region"), region_name)?;
        let mut forces = Vec::new();
        let surface = match l {
            LoadSpec::NodalForce { force, .. } => {
                check_len(&format!("{loc}.force"), force, dim)?;
                for &n in nodes {
                    forces.extend((0..dim).map(|i| (n * dim + i, force[i])));
                }
                None
            }
            LoadSpec::Pressure { pressure, .. } => Some(SurfaceLoad::Pressure(*pressure)),
            LoadSpec::Traction { traction, .. } => {
                check_len(&format!("{loc}.traction"), traction, dim)?;
                let mut t = [0.0; 3];
                t[..dim].copy_from_slice(traction);
                Some(SurfaceLoad::Traction(t))
            }
            LoadSpec::MaterialPointForce { .. } => unreachable!("handled above"),
        };
        if let Some(load) = surface {
            let in_region: std::collections::HashSet<usize> = nodes.iter().copied().collect();
            let mut count = 0;
            for f in facets.iter().filter(|f| f.iter().all(|n| in_region.contains(n))) {
                let xs: Vec<[f64; 3]> = f.iter().map(|&n| model.coords[n]).collect();
                let mut fa = vec![[0.0; 3]; f.len()];
                facet_forces(case.formulation, case.thickness, &xs, load, &mut fa);
                for (&n, v) in f.iter().zip(&fa) {
                    forces.extend((0..dim).map(|i| (n * dim + i, v[i])));
                }
                count += 1;
            }
            if count == 0 {
                return Err(CaseError::new(
                    format!("{loc}.region"),
                    format!("region '{region_name}' contains no boundary edge or face"),
                ));
            }
        }
        load_of_load.push(model.loads.len());
        model.loads.push(Load { forces, amplitude: amplitude.clone() });
    }

    if let Some(g) = &case.gravity {
        check_len("gravity.acceleration", &g.acceleration, dim)?;
        g.amplitude.check().map_err(|m| CaseError::new("gravity.amplitude", m))?;
        let mut a = [0.0; 3];
        a[..dim].copy_from_slice(&g.acceleration);
        model.gravity = (a, g.amplitude.clone());
    }

    let mut monitor_names = std::collections::BTreeSet::new();
    let mut monitors = Vec::new();
    for (k, m) in case.monitors.iter().enumerate() {
        let loc = format!("monitors[{k}]");
        if m.name() == "time" || m.name().is_empty() || m.name().contains(',') {
            return Err(CaseError::new(format!("{loc}.name"), "must be non-empty, not 'time', without commas"));
        }
        if !monitor_names.insert(m.name().to_string()) {
            return Err(CaseError::new(format!("{loc}.name"), format!("duplicate monitor name '{}'", m.name())));
        }
        let kind = match m {
            MonitorSpec::Displacement { point, component, .. }
            | MonitorSpec::Velocity { point, component, .. }
            | MonitorSpec::Acceleration { point, component, .. } => {
                check_len(&format!("{loc}.point"), point, dim)?;
                let node = nearest_node(&model.coords, point).expect("model has nodes");
                let c = component_index(&format!("{loc}.component"), *component, dim)?;
                match m {
                    MonitorSpec::Displacement { .. } => MonitorKind::Displacement { node, component: c },
                    MonitorSpec::Velocity { .. } => MonitorKind::Velocity { node, component: c },
                    _ => MonitorKind::Acceleration { node, component: c },
                }
            }
            MonitorSpec::Reaction { region: r, component, .. } => MonitorKind::Reaction {
                nodes: region(format!("{loc}.region"), r)?.clone(),
                component: component_index(&format!("{loc}.component"), *component, dim)?,
            },
            MonitorSpec::MaterialPointDisplacement { point, component, .. }
            | MonitorSpec::MaterialPointVelocity { point, component, .. } => {
                check_len(&format!("{loc}.point"), point, dim)?;
                let nearest = model
                    .domains
                    .iter()
                    .enumerate()
                    .filter_map(|(k, d)| d.nearest_point(point).map(|(id, dist)| (k, id, dist)))
                    .min_by(|a, b| a.2.total_cmp(&b.2))
                    .ok_or_else(|| CaseError::new(format!("{loc}.type"), "the model has no material points"))?;
                let quantity = match m {
                    MonitorSpec::MaterialPointDisplacement { .. } => PointQuantity::Displacement,
                    _ => PointQuantity::Velocity,
                };
                MonitorKind::MaterialPoint {
                    domain: nearest.0,
                    id: nearest.1,
                    quantity,
                    component: component_index(&format!("{loc}.component"), *component, dim)?,
                }
            }
            MonitorSpec::Runout { wall, base, threshold, .. } => {
                check_surface_monitor(&loc, &model, dim)?;
                check_positive(&format!("{loc}.threshold"), *threshold)?;
                MonitorKind::Runout { wall: *wall, base: *base, threshold: *threshold }
            }
            MonitorSpec::SurfaceHeight { x, base, .. } => {
                check_surface_monitor(&loc, &model, dim)?;
                MonitorKind::SurfaceHeight { x: *x, base: *base }
            }
            MonitorSpec::MaterialPointStress { point, within, component, .. } => MonitorKind::MaterialPointTensor {
                points: select_points(&model, &loc, dim, None, point.as_deref(), within.as_ref())?,
                quantity: PointTensor::CauchyStress,
                component: *component,
            },
            MonitorSpec::WallForce { wall, component, .. } => MonitorKind::WallForce {
                domain: model.domains.iter().position(|d| d.wall_force().is_some() && d.name() == wall).ok_or_else(
                    || {
                        CaseError::new(
                            format!("{loc}.wall"),
                            format!("no penalty wall named '{wall}' in boundary_conditions"),
                        )
                    },
                )?,
                component: component_index(&format!("{loc}.component"), *component, dim)?,
            },
            MonitorSpec::MaterialVolume { within, .. } | MonitorSpec::MaterialMass { within, .. } => {
                if model.domains.iter().all(|d| d.point_extents().is_empty()) {
                    return Err(CaseError::new(format!("{loc}.type"), "the model has no material points"));
                }
                let (min, max) = match within {
                    Some(b) => {
                        check_len(&format!("{loc}.box.min"), &b.min, dim)?;
                        check_len(&format!("{loc}.box.max"), &b.max, dim)?;
                        if let Some(d) = (0..dim).find(|&d| b.max[d] < b.min[d]) {
                            return Err(CaseError::new(
                                format!("{loc}.box.max[{d}]"),
                                format!("must not lie below box.min[{d}] = {}, got {}", b.min[d], b.max[d]),
                            ));
                        }
                        (b.min.clone(), b.max.clone())
                    }
                    None => (vec![f64::NEG_INFINITY; dim], vec![f64::INFINITY; dim]),
                };
                match m {
                    MonitorSpec::MaterialVolume { .. } => MonitorKind::MaterialVolume { min, max },
                    _ => MonitorKind::MaterialMass { min, max },
                }
            }
            MonitorSpec::KineticEnergy { .. } => MonitorKind::KineticEnergy,
            MonitorSpec::StrainEnergy { .. } => MonitorKind::StrainEnergy,
        };
        monitors.push(Monitor { name: m.name().to_string(), kind });
    }
    let (inputs, outputs) = resolve_fmu_variables(case, &constraint_of_bc, &load_of_load, &monitors)?;
    Ok(BuiltModel { model, monitors, regions, inputs, outputs })
}

/// The penalty wall of `boundary_conditions[k]` (`spec` its `penalty`) on the grid of an
/// MPM domain; its name is the condition's `name` (default `penalty_<k>`).
fn build_penalty_wall(
    case: &Case,
    k: usize,
    spec: &PenaltySpec,
    mpm_grids: &BTreeMap<&str, (Grid, Vec<usize>)>,
) -> Result<PenaltyBoundary, CaseError> {
    let bc = &case.boundary_conditions[k];
    let loc = format!("boundary_conditions[{k}]");
    let dim = case.formulation.dim();
    if dim != 2 {
        return Err(CaseError::new(format!("{loc}.penalty"), "penalty walls are segments or polylines of 2D problems"));
    }
    if !bc.region.is_empty() {
        return Err(CaseError::new(format!("{loc}.region"), "a penalty wall takes no region"));
    }
    if bc.slip.is_some() {
        return Err(CaseError::new(format!("{loc}.slip"), "a penalty wall sets its own \"slip\": true | false"));
    }
    let name = bc.name.clone().unwrap_or_else(|| format!("penalty_{k}"));
    if case.domains.iter().any(|d| d.name == name) {
        return Err(CaseError::new(format!("{loc}.name"), format!("'{name}' is already a domain name")));
    }
    let domain = match &spec.domain {
        Some(d) => d.as_str(),
        None if mpm_grids.len() == 1 => mpm_grids.keys().next().copied().expect("one grid"),
        None => {
            return Err(CaseError::new(
                format!("{loc}.penalty.domain"),
                format!("name the mpm domain whose grid carries the wall ({} mpm domains)", mpm_grids.len()),
            ));
        }
    };
    let (grid, node_ids) = mpm_grids.get(domain).ok_or_else(|| {
        CaseError::new(format!("{loc}.penalty.domain"), format!("no mpm domain named '{domain}' in domains"))
    })?;
    let vertices: Vec<[f64; 2]> = match (&spec.segment, &spec.polyline) {
        (Some(s), None) => s.to_vec(),
        (None, Some(p)) => p.clone(),
        _ => return Err(CaseError::new(format!("{loc}.penalty"), "give either segment or polyline")),
    };
    let key = if spec.segment.is_some() { "segment" } else { "polyline" };
    if vertices.len() < 2 || vertices.windows(2).any(|w| w[0] == w[1]) {
        return Err(CaseError::new(
            format!("{loc}.penalty.{key}"),
            "needs at least two points, consecutive points distinct",
        ));
    }
    let spacing = match (spec.spacing, spec.contact) {
        (Some(_), true) => {
            return Err(CaseError::new(
                format!("{loc}.penalty.spacing"),
                "the contact form has no boundary particles (its contact points are the material points)",
            ));
        }
        (None, false) => {
            return Err(CaseError::new(
                format!("{loc}.penalty.spacing"),
                "the Dirichlet form needs the spacing of its boundary particles",
            ));
        }
        (Some(s), false) => {
            check_positive(&format!("{loc}.penalty.spacing"), s)?;
            s
        }
        (None, true) => 0.0,
    };
    check_positive(&format!("{loc}.penalty.penalty_factor"), spec.penalty_factor)?;
    let mut displacement = [0.0; 3];
    if !bc.displacement.is_empty() {
        check_len(&format!("{loc}.displacement"), &bc.displacement, dim)?;
        for (i, v) in bc.displacement.iter().enumerate() {
            displacement[i] = v.ok_or_else(|| {
                CaseError::new(format!("{loc}.displacement[{i}]"), "a penalty wall moves as a whole: give a number")
            })?;
        }
    }
    bc.amplitude.check().map_err(|m| CaseError::new(format!("{loc}.amplitude"), m))?;
    let length: f64 = vertices.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
    let samples = BoundaryParticles::on_polyline(&vertices, 1e-3 * length, case.formulation, case.thickness);
    if !samples.position.iter().any(|x| grid.locate(x).is_some()) {
        return Err(CaseError::new(
            format!("{loc}.penalty.{key}"),
            format!("lies outside the grid of domain '{domain}'"),
        ));
    }
    let settings = PenaltySettings {
        penalty_factor: spec.penalty_factor,
        kind: if spec.slip { PenaltyKind::Slip } else { PenaltyKind::NoSlip },
        contact: spec.contact,
        displacement,
        amplitude: bc.amplitude.clone(),
    };
    Ok(PenaltyBoundary::new(
        &name,
        grid.clone(),
        node_ids.clone(),
        case.formulation,
        case.thickness,
        vertices,
        spacing,
        settings,
    ))
}

/// Surface monitors need material points in a plane problem.
fn check_surface_monitor(loc: &str, model: &Model, dim: usize) -> Result<(), CaseError> {
    if dim != 2 {
        return Err(CaseError::new(format!("{loc}.type"), "surface monitors need a plane (2D) problem"));
    }
    if model.domains.iter().all(|d| d.point_extents().is_empty()) {
        return Err(CaseError::new(format!("{loc}.type"), "the model has no material points"));
    }
    Ok(())
}

/// SI unit of a monitor's value.
pub fn monitor_unit(kind: &MonitorKind) -> &'static str {
    match kind {
        MonitorKind::Displacement { .. } => "m",
        MonitorKind::Velocity { .. } => "m/s",
        MonitorKind::Acceleration { .. } => "m/s2",
        MonitorKind::Reaction { .. } | MonitorKind::WallForce { .. } => "N",
        MonitorKind::Runout { .. } | MonitorKind::SurfaceHeight { .. } => "m",
        MonitorKind::MaterialPoint { quantity, .. } => match quantity {
            PointQuantity::Position | PointQuantity::Displacement => "m",
            PointQuantity::Velocity => "m/s",
            PointQuantity::Acceleration => "m/s2",
        },
        MonitorKind::MaterialPointTensor { quantity, .. } => match quantity {
            PointTensor::CauchyStress => "Pa",
            PointTensor::DeformationGradient => "1",
        },
        MonitorKind::MaterialVolume { .. } => "m3",
        MonitorKind::MaterialMass { .. } => "kg",
        MonitorKind::KineticEnergy | MonitorKind::StrainEnergy => "J",
    }
}

/// Resolves `fmu.inputs` to loads, constraints or gravity, and `fmu.outputs` (default:
/// every monitor) to monitors; names must be unique, non-empty and not `time`.
fn resolve_fmu_variables(
    case: &Case,
    constraint_of_bc: &[usize],
    load_of_load: &[usize],
    monitors: &[Monitor],
) -> Result<(Vec<ModelInput>, Vec<ModelOutput>), CaseError> {
    let mut bc_names = BTreeMap::new();
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        if let Some(name) = &bc.name {
            if bc_names.insert(name.as_str(), constraint_of_bc[k]).is_some() {
                return Err(CaseError::new(
                    format!("boundary_conditions[{k}].name"),
                    format!("duplicate boundary condition name '{name}'"),
                ));
            }
        }
    }
    let mut load_names = BTreeMap::new();
    for (k, l) in case.loads.iter().enumerate() {
        if let Some(name) = l.name() {
            if load_names.insert(name, load_of_load[k]).is_some() {
                return Err(CaseError::new(format!("loads[{k}].name"), format!("duplicate load name '{name}'")));
            }
        }
    }
    let Some(fmu) = &case.fmu else {
        let outputs = monitors
            .iter()
            .enumerate()
            .map(|(i, m)| ModelOutput {
                name: m.name.clone(),
                monitor: i,
                unit: monitor_unit(&m.kind).into(),
                description: String::new(),
            })
            .collect();
        return Ok((Vec::new(), outputs));
    };
    let mut names = std::collections::BTreeSet::new();
    let mut check_name = |loc: String, name: &str| -> Result<(), CaseError> {
        if name.is_empty() || name == "time" || name.chars().any(char::is_control) {
            return Err(CaseError::new(loc, "must be non-empty, not 'time', without control characters"));
        }
        if !names.insert(name.to_string()) {
            return Err(CaseError::new(loc, format!("duplicate FMU variable name '{name}'")));
        }
        Ok(())
    };
    let mut inputs = Vec::new();
    for (k, i) in fmu.inputs.iter().enumerate() {
        let loc = format!("fmu.inputs[{k}]");
        check_name(format!("{loc}.name"), &i.name)?;
        if !i.start.is_finite() {
            return Err(CaseError::new(format!("{loc}.start"), format!("must be finite, got {}", i.start)));
        }
        let slot = match &i.drives {
            InputTarget::Load(n) => InputSlot::Load(*load_names.get(n.as_str()).ok_or_else(|| {
                CaseError::new(format!("{loc}.drives.load"), format!("no load named '{n}' in loads"))
            })?),
            InputTarget::BoundaryCondition(n) => InputSlot::Constraint(*bc_names.get(n.as_str()).ok_or_else(|| {
                CaseError::new(
                    format!("{loc}.drives.boundary_condition"),
                    format!("no boundary condition named '{n}' in boundary_conditions"),
                )
            })?),
            InputTarget::Gravity => {
                if case.gravity.is_none() {
                    return Err(CaseError::new(format!("{loc}.drives"), "the case has no gravity to scale"));
                }
                InputSlot::Gravity
            }
        };
        if inputs.iter().any(|j: &ModelInput| j.slot == slot) {
            return Err(CaseError::new(format!("{loc}.drives"), "another input already drives this target"));
        }
        inputs.push(ModelInput {
            name: i.name.clone(),
            slot,
            unit: i.unit.clone().unwrap_or_else(|| "1".into()),
            start: i.start,
            description: i.description.clone().unwrap_or_default(),
        });
    }
    let mut outputs = Vec::new();
    match &fmu.outputs {
        None => {
            for (i, m) in monitors.iter().enumerate() {
                check_name(format!("monitors[{i}].name"), &m.name)?;
                outputs.push(ModelOutput {
                    name: m.name.clone(),
                    monitor: i,
                    unit: monitor_unit(&m.kind).into(),
                    description: String::new(),
                });
            }
        }
        Some(list) => {
            for (k, o) in list.iter().enumerate() {
                let loc = format!("fmu.outputs[{k}]");
                check_name(format!("{loc}.name"), &o.name)?;
                let monitor_name = o.monitor.as_deref().unwrap_or(&o.name);
                let monitor = monitors.iter().position(|m| m.name == monitor_name).ok_or_else(|| {
                    CaseError::new(
                        format!("{loc}.{}", if o.monitor.is_some() { "monitor" } else { "name" }),
                        format!("no monitor named '{monitor_name}' in monitors"),
                    )
                })?;
                outputs.push(ModelOutput {
                    name: o.name.clone(),
                    monitor,
                    unit: o.unit.clone().unwrap_or_else(|| monitor_unit(&monitors[monitor].kind).into()),
                    description: o.description.clone().unwrap_or_default(),
                });
            }
        }
    }
    Ok((inputs, outputs))
}
