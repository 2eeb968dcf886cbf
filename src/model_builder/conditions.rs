//! Boundary conditions (prescribed displacements, slip, penalty walls), loads and gravity.

use std::collections::BTreeMap;

use loam_fem::domain::PointLoad;
use loam_fem::loads::{facet_forces, SurfaceLoad};
use loam_fem::model::{Constraint, Load, Model};
use loam_fem::slip::Slip;
use loam_mpm::penalty_boundary::{BoundaryParticles, PenaltyBoundary, PenaltyKind, PenaltySettings};

use super::meshes::Part;
use super::regions::{mean_boundary_normal, region, select_points};
use super::{check_len, check_positive};
use crate::case::{Case, CaseError, DomainKind, LoadSpec, PenaltySpec};

/// The boundary conditions of the case: constraints and slips on the model, penalty walls
/// on their grids. Returns, per boundary condition, the index of its constraint (the slot
/// of its amplitude, which an FMU input can drive).
pub(super) fn boundary_conditions(
    case: &Case,
    model: &mut Model,
    regions: &BTreeMap<String, Vec<usize>>,
    parts: &mut [Part],
) -> Result<Vec<usize>, CaseError> {
    let dim = case.formulation.dim();
    let mut constraint_of_bc = Vec::with_capacity(case.boundary_conditions.len());
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        if bc.as_rigid_wall {
            // a contact wall, built as a rigid structure (`walls`): the slot of its amplitude
            constraint_of_bc.push(model.constraints.len());
            model.constraints.push(Constraint::without_dofs(bc.amplitude.clone()));
            continue;
        }
        if let Some(spec) = &bc.penalty {
            let (part, wall) = build_penalty_wall(case, k, spec, parts)?;
            match &mut parts[part] {
                Part::Grid(grid) => grid.domain.add_wall(wall),
                Part::Fem(..) | Part::Rigid(..) => unreachable!("walls are on grids"),
            }
            constraint_of_bc.push(model.constraints.len());
            model.constraints.push(Constraint::without_dofs(bc.amplitude.clone()));
            continue;
        }
        if bc.region.is_empty() {
            return Err(CaseError::new(format!("boundary_conditions[{k}]"), "needs a region (or a penalty wall)"));
        }
        let nodes = region(regions, format!("boundary_conditions[{k}].region"), &bc.region)?;
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
                None => mean_boundary_normal(&model.coords, &part_facets(parts), nodes).ok_or_else(|| {
                    CaseError::new(
                        format!("boundary_conditions[{k}].region"),
                        format!("region '{}' contains no boundary edge or face to take a slip normal from", bc.region),
                    )
                })?,
            };
            if normal[..dim].iter().map(|v| v * v).sum::<f64>() <= 0.0 {
                return Err(CaseError::new(format!("boundary_conditions[{k}].slip.normal"), "must not be zero"));
            }
            let friction = slip.friction;
            if !(0.0..=MAX_FRICTION).contains(&friction) {
                return Err(CaseError::new(
                    format!("boundary_conditions[{k}].slip.friction"),
                    format!("must be a Coulomb coefficient in [0, {MAX_FRICTION}], got {friction}"),
                ));
            }
            // friction takes the sign of the normal force from the outward normal
            let normal = if friction > 0.0 { outward(normal, nodes, &model.coords, parts) } else { normal };
            model.slips.extend(nodes.iter().map(|&node| Slip { node, normal, friction }));
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

    Ok(constraint_of_bc)
}

/// A static analysis needs supports (issue 31): refused if no boundary condition holds any
/// node (no prescribed component, slip or penalty wall) and no interface ties a grid to a
/// structure. Then every rigid-body motion is free and the stiffness matrix singular; a
/// dynamic analysis is regularised by the mass and runs. (Supports that hold some bodies
/// but not others, or too few components, are found at the first solve:
/// `loam_fem::rigid_modes`.)
pub(super) fn check_supported(case: &Case, model: &Model) -> Result<(), CaseError> {
    let holds = model.constraints.iter().any(|c| !c.dofs.is_empty())
        || !model.slips.is_empty()
        || !model.ties.is_empty()
        || case.boundary_conditions.iter().any(|bc| bc.penalty.is_some())
        || case.domains.iter().any(|d| d.motion.is_some())
        || !case.interfaces.is_empty();
    if model.scheme.is_dynamic() || holds {
        return Ok(());
    }
    Err(CaseError::new(
        "boundary_conditions",
        "a static analysis needs supports, and no boundary condition holds any node: the stiffness matrix \
         would be singular (the bodies are free to move as rigid bodies); prescribe displacements, or make \
         the analysis dynamic",
    ))
}

/// The loads of the case (nodal forces, pressures, tractions on the model; forces on
/// material points in their domains). Returns, per load, its index in `model.loads`
/// (`usize::MAX` for forces on material points, which no input can drive).
pub(super) fn loads(
    case: &Case,
    model: &mut Model,
    regions: &BTreeMap<String, Vec<usize>>,
) -> Result<Vec<usize>, CaseError> {
    let dim = case.formulation.dim();
    let facets: Vec<Vec<usize>> = model.domains.iter().flat_map(|d| d.boundary_facets()).collect();
    let mut load_of_load = Vec::with_capacity(case.loads.len());
    for (k, l) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        if let LoadSpec::MaterialPointForce { domain, point, within, force, amplitude } = l {
            amplitude.check().map_err(|m| CaseError::new(format!("{loc}.amplitude"), m))?;
            check_len(&format!("{loc}.force"), force, dim)?;
            if let Some(name) = domain {
                if !model.domains.iter().any(|d| d.point_set(name).is_some()) {
                    return Err(CaseError::new(
                        format!("{loc}.domain"),
                        format!("no mpm domain named '{name}' in domains"),
                    ));
                }
            }
            let points = select_points(model, &loc, dim, domain.as_deref(), point.as_deref(), within.as_ref())?;
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
        let nodes = region(regions, format!("{loc}.region"), region_name)?;
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

    Ok(load_of_load)
}

/// Gravity and its amplitude.
pub(super) fn gravity(case: &Case, model: &mut Model) -> Result<(), CaseError> {
    let dim = case.formulation.dim();
    if let Some(g) = &case.gravity {
        check_len("gravity.acceleration", &g.acceleration, dim)?;
        g.amplitude.check().map_err(|m| CaseError::new("gravity.amplitude", m))?;
        let mut a = [0.0; 3];
        a[..dim].copy_from_slice(&g.acceleration);
        model.gravity = (a, g.amplitude.clone());
    }

    Ok(())
}

/// A penalty wall's keys, checked (see [`check_wall`]).
pub(super) struct WallKeys {
    /// The condition's `name` (default `penalty_<k>`): its output series.
    pub name: String,
    /// Its vertices (m).
    pub vertices: Vec<[f64; 2]>,
    /// `segment` or `polyline`: the key that gave them.
    pub key: &'static str,
    /// Spacing of the Dirichlet form's boundary particles (0 in the contact form).
    pub spacing: f64,
    /// Its displacement at amplitude 1 (m).
    pub displacement: [f64; 3],
    /// What it holds.
    pub hold: WallHold,
    /// Case index of the MPM domain whose grid carries it (`penalty.domain`, or the only grid).
    pub domain: usize,
}

/// What a penalty wall holds (`slip`, `friction`, neither).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum WallHold {
    /// Every component.
    NoSlip,
    /// The normal component: frictionless.
    Slip,
    /// Coulomb friction of this coefficient (contact form only).
    Coulomb(f64),
}

/// Largest Coulomb coefficient a wall or slip boundary accepts (μ = 10 already holds any grain).
pub(super) const MAX_FRICTION: f64 = 10.0;

/// The keys of the penalty wall of `boundary_conditions[k]` (`spec` its `penalty`), each
/// refused with one line naming it: 2D only, no region or slip key, a name that is not a
/// domain's, a segment or a polyline of distinct points, the spacing of the Dirichlet form
/// (and none in the contact form), a positive penalty factor, a displacement of numbers, a
/// Coulomb coefficient only in the contact form; and the MPM domain whose grid carries it.
pub(super) fn check_wall(case: &Case, k: usize, spec: &PenaltySpec) -> Result<WallKeys, CaseError> {
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
    let domain = wall_domain(case, k, spec)?;
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
    let length: f64 = vertices.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
    if !length.is_finite() {
        return Err(CaseError::new(format!("{loc}.penalty.{key}"), "coordinates too large: its length overflows"));
    }
    let spacing = match (spec.spacing, spec.contact) {
        (Some(_), true) => {
            return Err(CaseError::new(
                format!("{loc}.penalty.spacing"),
                "the contact form has no boundary particles (its contact points lie on the wall's face, two per half cell)",
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
            // boundary particles: ceil(length / spacing) per segment
            let n: f64 = vertices.windows(2).map(|w| ((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / s).ceil()).sum();
            let limit = case.limits.material_points;
            if !super::within(n, limit) {
                return Err(CaseError::new(
                    format!("{loc}.penalty.spacing"),
                    format!(
                        "{s} m along {length} m of wall makes {} boundary particles, more than limits.material_points = {limit} \
                         (a quarter of a grid cell is the usual spacing)",
                        super::meshes::count(n)
                    ),
                ));
            }
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
    let hold = match spec.friction {
        None if spec.slip => WallHold::Slip,
        None => WallHold::NoSlip,
        Some(mu) => {
            let at = format!("{loc}.penalty.friction");
            if !(mu.is_finite() && (0.0..=MAX_FRICTION).contains(&mu)) {
                return Err(CaseError::new(at, format!("must be a Coulomb coefficient in [0, 10], got {mu}")));
            }
            if !spec.contact {
                return Err(CaseError::new(
                    at,
                    "Coulomb friction needs the contact form (\"contact\": true): the Dirichlet form holds the body in tension as in compression and has no normal force to scale the friction",
                ));
            }
            if spec.slip {
                return Err(CaseError::new(
                    at,
                    "give either \"slip\": true (frictionless) or a friction coefficient, not both",
                ));
            }
            WallHold::Coulomb(mu)
        }
    };
    Ok(WallKeys { name, vertices, key, spacing, displacement, hold, domain })
}

/// Case index of the MPM domain whose grid carries the wall of `boundary_conditions[k]`:
/// `penalty.domain`, or the first body of the only grid (MPM domains with the same grid share
/// it).
fn wall_domain(case: &Case, k: usize, spec: &PenaltySpec) -> Result<usize, CaseError> {
    let loc = format!("boundary_conditions[{k}].penalty.domain");
    let mpm: Vec<usize> = (0..case.domains.len()).filter(|&d| case.domains[d].kind == DomainKind::Mpm).collect();
    match &spec.domain {
        Some(name) => mpm
            .iter()
            .copied()
            .find(|&d| case.domains[d].name == *name)
            .ok_or_else(|| CaseError::new(loc, format!("no mpm domain named '{name}' in domains"))),
        None => {
            let same_grid = |a: usize, b: usize| {
                let (a, b) = (&case.domains[a], &case.domains[b]);
                a.grid == b.grid && a.grid_mesh == b.grid_mesh
            };
            let grids = mpm.iter().enumerate().filter(|&(i, &d)| mpm[..i].iter().all(|&e| !same_grid(d, e))).count();
            match mpm.first() {
                Some(&d) if grids == 1 => Ok(d),
                _ => {
                    Err(CaseError::new(loc, format!("name the mpm domain whose grid carries the wall ({grids} grids)")))
                }
            }
        }
    }
}

/// The penalty wall (Dirichlet form) of `boundary_conditions[k]` (`spec` its `penalty`) on
/// the grid of its MPM domain ([`check_wall`]), with the index of that grid's part.
fn build_penalty_wall(
    case: &Case,
    k: usize,
    spec: &PenaltySpec,
    parts: &[Part],
) -> Result<(usize, PenaltyBoundary), CaseError> {
    let bc = &case.boundary_conditions[k];
    let loc = format!("boundary_conditions[{k}]");
    let wall = check_wall(case, k, spec)?;
    let part = parts
        .iter()
        .position(|p| matches!(p, Part::Grid(g) if g.bodies.contains(&wall.domain)))
        .expect("every mpm domain is on a grid");
    let Part::Grid(grid_part) = &parts[part] else { unreachable!("a grid part") };
    let grid = grid_part.domain.grid();
    let length: f64 = wall.vertices.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
    let samples = BoundaryParticles::on_polyline(&wall.vertices, 1e-3 * length, case.formulation, case.thickness);
    if !samples.position.iter().any(|x| grid.locate(x).is_some()) {
        return Err(CaseError::new(
            format!("{loc}.penalty.{}", wall.key),
            format!("lies outside the grid of domain '{}'", case.domains[wall.domain].name),
        ));
    }
    let kind = match wall.hold {
        WallHold::NoSlip => PenaltyKind::NoSlip,
        WallHold::Slip => PenaltyKind::Slip,
        WallHold::Coulomb(_) => unreachable!("check_wall: friction needs the contact form, a rigid structure"),
    };
    let settings = PenaltySettings {
        penalty_factor: spec.penalty_factor,
        kind,
        displacement: wall.displacement,
        amplitude: bc.amplitude.clone(),
    };
    Ok((
        part,
        PenaltyBoundary::new(&wall.name, case.formulation, case.thickness, wall.vertices, wall.spacing, settings),
    ))
}

/// `normal` turned to point out of the part whose boundary holds `nodes`: away from the
/// centroid of that part's boundary nodes (the parts that carry slip boundaries, grids and
/// meshes, are convex where a boundary is straight enough to slide on).
fn outward(normal: [f64; 3], nodes: &[usize], coords: &[[f64; 3]], parts: &[Part]) -> [f64; 3] {
    let Some(&first) = nodes.first() else { return normal };
    for p in parts {
        let facets = boundary_facets(p);
        if !facets.iter().any(|f| f.contains(&first)) {
            continue;
        }
        let mut boundary: Vec<usize> = facets.into_iter().flatten().collect();
        boundary.sort_unstable();
        boundary.dedup();
        let centroid = mean(boundary.iter().map(|&n| coords[n]));
        let region = mean(nodes.iter().map(|&n| coords[n]));
        let away: f64 = (0..3).map(|d| normal[d] * (region[d] - centroid[d])).sum();
        return if away < 0.0 { normal.map(|v| -v) } else { normal };
    }
    normal
}

/// Mean of points.
fn mean(points: impl Iterator<Item = [f64; 3]>) -> [f64; 3] {
    let (mut sum, mut count) = ([0.0; 3], 0.0f64);
    for x in points {
        for d in 0..3 {
            sum[d] += x[d];
        }
        count += 1.0;
    }
    sum.map(|v| v / count.max(1.0))
}

/// The boundary facets of one part (its FEM mesh or its grid).
fn boundary_facets(part: &Part) -> Vec<Vec<usize>> {
    use loam_fem::domain::Domain;
    match part {
        Part::Fem(_, d) => d.boundary_facets(),
        Part::Grid(g) => g.domain.boundary_facets(),
        Part::Rigid(..) => Vec::new(),
    }
}

/// The boundary facets of every part.
fn part_facets(parts: &[Part]) -> Vec<Vec<usize>> {
    parts.iter().flat_map(boundary_facets).collect()
}
