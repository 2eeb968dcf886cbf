//! From a parsed [`Case`] to a solvable [`Model`]: meshes, shared nodes, regions,
//! constraints, loads and monitors, with every consistency check that needs more than the
//! JSON schema (empty regions, missing materials, inverted elements, wrong vector lengths).

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use loam_fem::formulation::Formulation;
use loam_fem::loads::{facet_forces, SurfaceLoad};
use loam_fem::mesh::Mesh;
use loam_fem::model::{Constraint, Load, Model};
use loam_fem::scheme::TimeScheme;
use loam_fem::solid_domain::FemDomain;
use loam_laws::ConstitutiveLaw;

use crate::case::{AnalysisType, Case, CaseError, Component, LoadSpec, MassMatrix, MeshSpec, MonitorSpec, RegionSpec};
use crate::monitor::{Monitor, MonitorKind};

/// A model ready to run, with the monitors resolved to nodes and regions.
pub struct BuiltModel {
    /// The model.
    pub model: Model,
    /// Monitors in case-file order.
    pub monitors: Vec<Monitor>,
    /// Node sets of the regions (global ids).
    pub regions: BTreeMap<String, Vec<usize>>,
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

/// Builds the mesh of domain `k`.
fn build_mesh(case: &Case, k: usize) -> Result<Mesh, CaseError> {
    let loc = format!("domains[{k}].mesh");
    let dim = case.formulation.dim();
    let mesh = match &case.domains[k].mesh {
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
    let meshes = case.domains.iter().enumerate().map(|(k, _)| build_mesh(case, k)).collect::<Result<Vec<_>, _>>()?;
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
    for (k, (d, (mesh, id))) in case.domains.iter().zip(meshes.into_iter().zip(ids)).enumerate() {
        let law = laws[d.material.as_str()].clone();
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

    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        let nodes = region(format!("boundary_conditions[{k}].region"), &bc.region)?;
        check_len(&format!("boundary_conditions[{k}].displacement"), &bc.displacement, dim)?;
        bc.amplitude.check().map_err(|m| CaseError::new(format!("boundary_conditions[{k}].amplitude"), m))?;
        let mut c = Constraint { dofs: Vec::new(), values: Vec::new(), amplitude: bc.amplitude.clone() };
        for &n in nodes {
            for (i, v) in bc.displacement.iter().enumerate() {
                if let Some(v) = v {
                    c.dofs.push(n * dim + i);
                    c.values.push(*v);
                }
            }
        }
        model.constraints.push(c);
    }

    let facets: Vec<Vec<usize>> = model.domains.iter().flat_map(|d| d.boundary_facets()).collect();
    for (k, l) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        let (region_name, amplitude) = match l {
            LoadSpec::NodalForce { region, amplitude, .. }
            | LoadSpec::Pressure { region, amplitude, .. }
            | LoadSpec::Traction { region, amplitude, .. } => (region, amplitude),
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
            MonitorSpec::KineticEnergy { .. } => MonitorKind::KineticEnergy,
            MonitorSpec::StrainEnergy { .. } => MonitorKind::StrainEnergy,
        };
        monitors.push(Monitor { name: m.name().to_string(), kind });
    }
    Ok(BuiltModel { model, monitors, regions })
}
