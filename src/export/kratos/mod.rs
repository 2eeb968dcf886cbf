//! `loam export kratos CASE.json -o DIR`: a Loam MPM case as a Kratos Multiphysics MPM case
//! folder, the inverse of [`crate::import::kratos`].
//!
//! The folder holds `ProjectParameters.json` ([`parameters`]), the background grid
//! `Grid.mdpa` (its cells as `Element2D3N` … `Element3D8N`, one sub model part per condition
//! with its nodes and, for loads and slip, the grid's boundary facets in the region as
//! conditions), the bodies `Body.mdpa` (their cells as `MPMUpdatedLagrangian…` elements, one
//! sub model part `Parts_<domain>` each; [`mdpa`]) and `ParticleMaterials.json`
//! ([`materials`]). Kratos places `MATERIAL_POINTS_PER_ELEMENT` points in each body cell at
//! the positions and with the volumes Loam gives `material_points.cells` (both codes use the
//! cell's Gauss rule); a lattice body (`disk`, `polygon`) is written as one square cell per
//! point with one point each.
//!
//! What Kratos cannot express is refused with one line naming the JSON path; what it expresses
//! only approximately, or what is left out (output settings, monitors other than a point's
//! displacement), is returned as notes, one line per key. A `displacement` monitor becomes a
//! `json_output_process` writing `DISPLACEMENT` of the grid node nearest to its point to
//! `<monitor>.json`, as Kratos' own tests write their results.

pub mod materials;
pub mod mdpa;
pub mod parameters;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::mesh::Mesh;
use loam_mpm::basis::Basis;
use loam_mpm::grid::Grid;
use serde_json::{json, Value};

use crate::case::{
    BodySpec, Case, CaseError, DomainKind, ElementFormulation, LoadSpec, MonitorSpec, Quadrature, DEFAULT_GHOST_PENALTY,
};
use crate::import::kratos::mdpa::{EntityBlock, Mdpa, SubModelPart};
use crate::import::kratos::parameters::Condition;
use crate::model_builder::{body_points, build_mesh, line_tolerance, nearest_node, select_region, structured_grid};

/// Why a case could not be exported: one line naming the JSON path and the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ExportError(pub String);

impl From<CaseError> for ExportError {
    fn from(e: CaseError) -> Self {
        ExportError(e.to_string())
    }
}

/// What an export produced.
#[derive(Debug, Clone)]
pub struct Export {
    /// Files written.
    pub files: Vec<PathBuf>,
    /// One line per key approximated or left out.
    pub notes: Vec<String>,
}

/// The grid's own sub model part.
const GRID_PART: &str = "Parts_Grid";

/// Exports the case file `case_path` into the folder `dir`: the case checked (it must build,
/// and Kratos must express it), the grid with its conditions and outputs, the bodies with
/// their materials, the parameters, and the four files written.
pub fn export(case_path: &Path, dir: &Path) -> Result<Export, ExportError> {
    let case = Case::load(case_path)?;
    let raw = crate::input::parse_value(&crate::input::read_json_text(case_path, "case file")?)?;
    // the case must be one Loam runs
    crate::model_builder::build_model(&case)?;
    let mut notes = Vec::new();
    refuse_unexpressed(&case, &raw, &mut notes)?;

    let grid = grid_mesh(&case, &raw)?;
    let mut grid_mdpa = grid_model_part(&grid, case.formulation.dim());
    let mut grid_parts = GridParts { mdpa: &mut grid_mdpa, next_condition: 1 };
    let conditions = grid_conditions(&case, &grid, &mut grid_parts)?;
    let outputs = outputs(&case, &raw, &grid, &mut grid_parts, &mut notes)?;
    let (body_mdpa, properties, mut parts) = bodies(&case, &raw, &grid, &mut notes)?;
    parts.push(GRID_PART.into());

    let process_parts: Vec<String> = grid_mdpa.sub_model_parts.iter().skip(1).map(|p| p.name.clone()).collect();
    let dim = case.formulation.dim();
    let gravity = case.gravity.as_ref().map(|g| {
        let mut a = [0.0; 3];
        a[..dim].copy_from_slice(&g.acceleration[..dim]);
        a
    });
    let files = parameters::Files {
        parts: &parts,
        process_parts: &process_parts,
        pressure_dofs: case.domains[0].element_formulation == ElementFormulation::MixedUp,
        mass_matrix: case.domains[0].mass_matrix,
    };
    let project = parameters::project(&case, &files, &conditions, gravity, &outputs, &mut notes)?;

    let pretty = |v: &Value| serde_json::to_string_pretty(v).expect("JSON values serialise") + "\n";
    let files = write_folder(
        dir,
        [
            ("ProjectParameters.json", pretty(&project)),
            ("ParticleMaterials.json", pretty(&json!({ "properties": properties }))),
            ("Grid.mdpa", mdpa::write(&grid_mdpa)),
            ("Body.mdpa", mdpa::write(&body_mdpa)),
        ],
    )?;
    Ok(Export { files, notes })
}

/// Writes the `files` (name, text) into the folder `dir`; returns their paths.
fn write_folder(dir: &Path, files: [(&str, String); 4]) -> Result<Vec<PathBuf>, ExportError> {
    std::fs::create_dir_all(dir).map_err(|e| ExportError(format!("{}: cannot create: {e}", dir.display())))?;
    let mut written = Vec::new();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| ExportError(format!("{}: cannot write: {e}", path.display())))?;
        written.push(path);
    }
    Ok(written)
}

/// The grid's model part: its nodes (Kratos ids from 1) and cells (`Element2D4N` …), sub
/// model part [`GRID_PART`].
fn grid_model_part(grid: &Mesh, dim: usize) -> Mdpa {
    let mut m = Mdpa { nodes: grid.coords.iter().enumerate().map(|(n, x)| (n + 1, *x)).collect(), ..Mdpa::default() };
    let kind = format!("Element{}", entity_suffix(dim, grid.element.num_nodes()));
    m.elements.push(block(&kind, (0..grid.num_cells()).map(|e| grid.cell(e).to_vec()), 0));
    m.sub_model_parts.push(SubModelPart {
        name: GRID_PART.into(),
        nodes: (1..=grid.coords.len()).collect(),
        elements: (1..=grid.num_cells()).collect(),
        conditions: Vec::new(),
    });
    m
}

/// The boundary conditions and loads of the case on the grid, their sub model parts added to
/// `grid_parts` (with the grid's boundary facets in the region as conditions where Kratos
/// applies them on facets).
fn grid_conditions(case: &Case, grid: &Mesh, grid_parts: &mut GridParts) -> Result<Vec<Condition>, ExportError> {
    let dim = case.formulation.dim();
    let tol = line_tolerance(&grid.coords);
    let region = |name: &str, loc: String| -> Result<Vec<usize>, ExportError> {
        let spec =
            case.regions.get(name).ok_or_else(|| ExportError(format!("{loc}: no region named '{name}' in regions")))?;
        Ok(select_region(name, spec, &grid.coords, dim, &grid.node_groups, tol)?)
    };
    let facets = grid.boundary_facets();
    let part_name = part_names(case);
    let mut conditions = Vec::new();
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        let loc = format!("boundary_conditions[{k}]");
        let nodes = region(&bc.region, format!("{loc}.region"))?;
        if bc.slip.is_some() {
            let part = part_name("SLIP", &bc.region);
            let kind = if dim == 2 { "LineCondition2D2N" } else { "SurfaceCondition3D" };
            grid_parts.add(&part, &nodes, &facets, Some(kind), &loc)?;
            conditions.push(Condition::Slip { part });
        } else {
            let part = part_name("DISPLACEMENT", &bc.region);
            grid_parts.add(&part, &nodes, &facets, None, &loc)?;
            // in 2D, DISPLACEMENT_Z held at 0 as in Kratos' own 2D cases
            let mut value = [None, None, Some(0.0)];
            for (d, v) in bc.displacement.iter().enumerate().take(dim) {
                value[d] = *v;
            }
            conditions.push(Condition::Displacement { part, value });
        }
    }
    let axisymmetric = case.formulation == Formulation::Axisymmetric;
    for (k, load) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        match load {
            LoadSpec::Traction { region: r, traction, .. } => {
                let nodes = region(r, format!("{loc}.region"))?;
                let part = part_name("LINE_LOAD", r);
                let kind =
                    if axisymmetric { "MPMGridAxisymLineLoadCondition2D2N" } else { "MPMGridLineLoadCondition2D2N" };
                grid_parts.add(&part, &nodes, &facets, Some(kind), &loc)?;
                let t = if axisymmetric { 1.0 } else { case.thickness };
                conditions.push(Condition::LineLoad { part, load: [traction[0] * t, traction[1] * t, 0.0] });
            }
            LoadSpec::NodalForce { region: r, force, .. } => {
                let nodes = region(r, format!("{loc}.region"))?;
                let part = part_name("POINT_LOAD", r);
                let kind = format!("MPMGridPointLoadCondition{dim}D1N");
                grid_parts.points(&part, &nodes, &kind);
                let mut f = [0.0; 3];
                f[..dim].copy_from_slice(&force[..dim]);
                conditions.push(Condition::PointLoad { part, force: f });
            }
            LoadSpec::Pressure { .. } | LoadSpec::MaterialPointForce { .. } => unreachable!("refused above"),
        }
    }
    Ok(conditions)
}

/// The `json_output_process` outputs `(sub model part, file)`: one per `displacement`
/// monitor, of the grid node nearest to its point (`OUTPUT_<monitor>`, `<monitor>.json`);
/// other monitors are noted as left out.
fn outputs(
    case: &Case,
    raw: &Value,
    grid: &Mesh,
    grid_parts: &mut GridParts,
    notes: &mut Vec<String>,
) -> Result<Vec<(String, String)>, ExportError> {
    let mut outputs = Vec::new();
    for (k, m) in case.monitors.iter().enumerate() {
        match m {
            MonitorSpec::Displacement { name, point, .. } => {
                let node = nearest_node(&grid.coords, point)
                    .ok_or_else(|| ExportError(format!("monitors[{k}].point: no grid node")))?;
                let part = format!("OUTPUT_{name}");
                if grid_parts.mdpa.sub_model_part(&part).is_some() {
                    return Err(ExportError(format!(
                        "monitors[{k}].name: \"{name}\": its sub model part {part} is a region's name"
                    )));
                }
                grid_parts.add(&part, &[node], &[], None, &format!("monitors[{k}]"))?;
                outputs.push((part, format!("{name}.json")));
            }
            other => notes.push(format!(
                "monitors[{k}]: the {} monitor '{}' left out (exported: displacement monitors, as Kratos' json_output_process of a grid node)",
                monitor_type(raw, k),
                other.name()
            )),
        }
    }
    Ok(outputs)
}

/// The bodies' model part (one sub model part `Parts_<domain>` each, `MPMUpdatedLagrangian…`
/// elements), their materials' `properties` and the sub model part names.
fn bodies(
    case: &Case,
    raw: &Value,
    grid: &Mesh,
    notes: &mut Vec<String>,
) -> Result<(Mdpa, Vec<Value>, Vec<String>), ExportError> {
    let dim = case.formulation.dim();
    let axisymmetric = case.formulation == Formulation::Axisymmetric;
    let mut body_mdpa = Mdpa::default();
    let mut properties = Vec::new();
    let mut parts = Vec::new();
    for (k, d) in case.domains.iter().enumerate() {
        let (m, points_per_cell) = body_mesh(case, k, grid, notes)?;
        let part = format!("Parts_{}", d.name);
        let (node0, element0) =
            (body_mdpa.nodes.len(), body_mdpa.elements.iter().map(|b| b.entities.len()).sum::<usize>());
        body_mdpa.nodes.extend(m.coords.iter().enumerate().map(|(n, x)| (node0 + n + 1, *x)));
        let up = if d.element_formulation == ElementFormulation::MixedUp { "UP" } else { "" };
        let kind = format!("MPMUpdatedLagrangian{up}{}", entity_suffix(dim, m.element.num_nodes()));
        let cells = (0..m.num_cells()).map(|e| m.cell(e).iter().map(|n| n + node0).collect::<Vec<_>>());
        let b = block(&kind, cells, element0);
        body_mdpa.sub_model_parts.push(SubModelPart {
            name: part.clone(),
            nodes: (node0 + 1..=node0 + m.coords.len()).collect(),
            elements: b.entities.iter().map(|e| e.0).collect(),
            conditions: Vec::new(),
        });
        body_mdpa.elements.push(b);
        let kin = materials::BodyKinematics {
            part: &part,
            formulation: case.formulation.name(),
            mixed_up: !up.is_empty(),
            // Kratos' 2D elements need THICKNESS, also in axisymmetry (where it is not used)
            thickness: (dim == 2).then_some(if axisymmetric { 1.0 } else { case.thickness }),
            points_per_cell,
        };
        let id = properties.len() + 1;
        properties.push(materials::properties(&d.material, &raw["materials"][&d.material], id, &kin)?);
        parts.push(part);
    }
    Ok((body_mdpa, properties, parts))
}

/// The grid sub model part of the conditions of kind `KIND` (`DISPLACEMENT`, `SLIP`,
/// `LINE_LOAD`, `POINT_LOAD`) on a region: the region's name where only one kind uses it (a
/// re-import gives the region back by its name), else `KIND_<region>` (Kratos puts the
/// conditions of a sub model part under one process).
fn part_names(case: &Case) -> impl Fn(&str, &str) -> String {
    let mut kinds: BTreeMap<String, BTreeSet<&'static str>> = BTreeMap::new();
    for bc in &case.boundary_conditions {
        kinds.entry(bc.region.clone()).or_default().insert(if bc.slip.is_some() { "SLIP" } else { "DISPLACEMENT" });
    }
    for l in &case.loads {
        match l {
            LoadSpec::Traction { region, .. } => kinds.entry(region.clone()).or_default().insert("LINE_LOAD"),
            LoadSpec::NodalForce { region, .. } => kinds.entry(region.clone()).or_default().insert("POINT_LOAD"),
            _ => false,
        };
    }
    move |kind, region| {
        if kinds.get(region).is_some_and(|k| k.len() == 1) && region != GRID_PART {
            region.to_string()
        } else {
            format!("{kind}_{region}")
        }
    }
}

/// Kratos' suffix of a linear entity of `nodes` nodes in `dim` dimensions (`2D4N`).
fn entity_suffix(dim: usize, nodes: usize) -> String {
    format!("{dim}D{nodes}N")
}

/// An entity block of `kind` numbering `cells` (0-based node indices) from `first + 1`.
fn block(kind: &str, cells: impl Iterator<Item = Vec<usize>>, first: usize) -> EntityBlock {
    let entities = cells.enumerate().map(|(e, c)| (first + e + 1, 0, c.iter().map(|n| n + 1).collect())).collect();
    EntityBlock { kind: kind.into(), line: 0, entities }
}

/// The grid's sub model parts as they are added.
struct GridParts<'a> {
    mdpa: &'a mut Mdpa,
    next_condition: usize,
}

impl GridParts<'_> {
    /// Adds sub model part `name` (if new) of `nodes` (0-based); with `condition`, the
    /// `facets` whose nodes all lie in it become conditions of that kind (refused if none).
    fn add(
        &mut self,
        name: &str,
        nodes: &[usize],
        facets: &[Vec<usize>],
        condition: Option<&str>,
        loc: &str,
    ) -> Result<(), ExportError> {
        if self.mdpa.sub_model_part(name).is_some() {
            return Ok(());
        }
        let mut conditions = Vec::new();
        if let Some(kind) = condition {
            let inside: BTreeSet<usize> = nodes.iter().copied().collect();
            let on: Vec<Vec<usize>> = facets.iter().filter(|f| f.iter().all(|n| inside.contains(n))).cloned().collect();
            if on.is_empty() {
                return Err(ExportError(format!(
                    "{loc}.region: no boundary facet of the grid has all its nodes in the region (Kratos applies this condition on facets)"
                )));
            }
            let kind =
                if kind.starts_with("SurfaceCondition") { format!("{kind}{}N", on[0].len()) } else { kind.into() };
            let b = block(&kind, on.into_iter(), self.next_condition - 1);
            self.next_condition += b.entities.len();
            conditions = b.entities.iter().map(|e| e.0).collect();
            self.mdpa.conditions.push(b);
        }
        self.mdpa.sub_model_parts.push(SubModelPart {
            name: name.into(),
            nodes: nodes.iter().map(|n| n + 1).collect(),
            elements: Vec::new(),
            conditions,
        });
        Ok(())
    }

    /// Adds sub model part `name` of `nodes` with one point condition of `kind` on each.
    fn points(&mut self, name: &str, nodes: &[usize], kind: &str) {
        if self.mdpa.sub_model_part(name).is_some() {
            return;
        }
        let b = block(kind, nodes.iter().map(|&n| vec![n]), self.next_condition - 1);
        self.next_condition += b.entities.len();
        self.mdpa.sub_model_parts.push(SubModelPart {
            name: name.into(),
            nodes: nodes.iter().map(|n| n + 1).collect(),
            elements: Vec::new(),
            conditions: b.entities.iter().map(|e| e.0).collect(),
        });
        self.mdpa.conditions.push(b);
    }
}

/// The body mesh of MPM domain `k` and its points per cell. A `cells` body as given; a lattice
/// body (`disk`, `polygon`) as one square cell of side `spacing` centred on each of its
/// lattice points with one point per cell, which Kratos (as Loam) places at the cell's centre
/// with the square's area as its volume: Loam's lattice point, position and volume.
fn body_mesh(case: &Case, k: usize, grid: &Mesh, notes: &mut Vec<String>) -> Result<(Mesh, usize), ExportError> {
    let loc = format!("domains[{k}].material_points");
    let spacing = match case.domains[k].material_points.as_ref().expect("an mpm domain has points") {
        BodySpec::Cells { mesh, points_per_cell } => {
            return Ok((build_mesh(case, &format!("{loc}.cells.mesh"), mesh)?, *points_per_cell));
        }
        BodySpec::Disk { spacing, .. } | BodySpec::Polygon { spacing, .. } => *spacing,
    };
    let points = body_points(case, k, &Grid::unstructured(grid.clone()))?;
    let mut ids: BTreeMap<(i64, i64), usize> = BTreeMap::new();
    let mut coords = Vec::new();
    let mut connectivity = Vec::new();
    for x in &points.position {
        for (di, dj) in [(-1, -1), (1, -1), (1, 1), (-1, 1)] {
            // corners on the lattice of half spacings, so that neighbours share them
            let key = ((2.0 * x[0] / spacing).round() as i64 + di, (2.0 * x[1] / spacing).round() as i64 + dj);
            let id = *ids.entry(key).or_insert_with(|| {
                coords.push([x[0] + 0.5 * spacing * di as f64, x[1] + 0.5 * spacing * dj as f64, 0.0]);
                coords.len() - 1
            });
            connectivity.push(id);
        }
    }
    notes.push(format!(
        "{loc}: the lattice of {} points written as one {spacing} m square cell per point, 1 point per cell (the same points and volumes)",
        points.len()
    ));
    Ok((Mesh { element: ElementType::Quad4, coords, connectivity, node_groups: BTreeMap::new() }, 1))
}

/// The background grid shared by every body, as a mesh (a structured `grid` rotated as given).
fn grid_mesh(case: &Case, raw: &Value) -> Result<Mesh, ExportError> {
    let key = |k: usize| {
        let d = &raw["domains"][k];
        if d.get("grid").is_some() {
            ("grid", d["grid"].clone())
        } else {
            ("grid_mesh", d["grid_mesh"].clone())
        }
    };
    let first = key(0);
    if let Some(k) = (1..case.domains.len()).find(|&k| key(k) != first) {
        return Err(ExportError(format!(
            "domains[{k}].{}: Kratos has one background grid: every body must be on the grid of domains[0]",
            key(k).0
        )));
    }
    let d = &case.domains[0];
    let mesh = match (&d.grid, &d.grid_mesh) {
        (Some(g), _) => {
            if g.basis != Basis::Linear {
                return Err(ExportError(format!(
                    "domains[0].grid.basis: \"{}\": Kratos' implicit MPM has the cells' linear functions",
                    g.basis.name()
                )));
            }
            structured_grid(case, "domains[0]", g)?.mesh
        }
        (None, Some(spec)) => build_mesh(case, "domains[0].grid_mesh", spec)?,
        (None, None) => unreachable!("checked by build_model"),
    };
    Ok(mesh)
}

/// The `type` of monitor `k` as written in the case.
fn monitor_type(raw: &Value, k: usize) -> String {
    raw["monitors"][k]["type"].as_str().unwrap_or("?").to_string()
}

/// A name that becomes part of a Kratos sub model part name (`Begin SubModelPart NAME`, and
/// `Background_Grid.NAME` in processes) must be one word of letters, digits and `_`.
fn check_kratos_name(loc: &str, name: &str) -> Result<(), ExportError> {
    if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        Ok(())
    } else {
        Err(ExportError(format!("{loc}: \"{name}\" names a Kratos sub model part: use letters, digits and _ only")))
    }
}

/// Refuses what Kratos' MPM cannot express and notes what it only approximates or leaves
/// out, one line per key with its JSON path.
fn refuse_unexpressed(case: &Case, raw: &Value, notes: &mut Vec<String>) -> Result<(), ExportError> {
    let refuse = |loc: String, why: &str| Err(ExportError(format!("{loc}: {why}")));
    if !case.interfaces.is_empty() {
        return refuse(
            "interfaces".into(),
            "soil–structure interfaces are not exported (Kratos' MPM case has no structure)",
        );
    }
    for name in case.regions.keys() {
        check_kratos_name(&format!("regions.{name}"), name)?;
    }
    for (k, m) in case.monitors.iter().enumerate() {
        if matches!(m, MonitorSpec::Displacement { .. }) {
            check_kratos_name(&format!("monitors[{k}].name"), m.name())?;
        }
    }
    for (k, d) in case.domains.iter().enumerate() {
        let loc = format!("domains[{k}]");
        check_kratos_name(&format!("{loc}.name"), &d.name)?;
        if d.kind != DomainKind::Mpm {
            return refuse(
                format!("{loc}.type"),
                "fem domains are not exported (a Kratos MPM case holds material points and a grid)",
            );
        }
        let given = |key: &str| raw["domains"][k].get(key).is_some();
        if given("initial_velocity") {
            return refuse(format!("{loc}.initial_velocity"), "initial velocities are not exported");
        }
        if given("initial_stress") {
            return refuse(format!("{loc}.initial_stress"), "initial stresses are not exported");
        }
        if d.pic_fraction != 0.0 || d.pic_relaxation_time.is_some() {
            return refuse(
                format!("{loc}.pic_fraction"),
                "Kratos' implicit MPM has no PIC blend of the point velocities",
            );
        }
        if d.quadrature != Quadrature::MaterialPoints {
            return refuse(
                format!("{loc}.quadrature"),
                "Kratos integrates over the material points' volumes (material_points)",
            );
        }
        if d.mass_matrix != case.domains[0].mass_matrix || d.element_formulation != case.domains[0].element_formulation
        {
            return refuse(
                loc.clone(),
                "the bodies' mass_matrix and element_formulation must be one (Kratos' solver settings)",
            );
        }
        let alpha = d.ghost_penalty.unwrap_or(match case.analysis.kind {
            crate::case::AnalysisType::Dynamic => 0.0,
            _ => DEFAULT_GHOST_PENALTY,
        });
        if alpha > 0.0 {
            notes.push(format!(
                "{loc}.ghost_penalty: {alpha} left out (Kratos has no ghost penalty; it acts only on cells the material cuts)"
            ));
        }
    }
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        let loc = format!("boundary_conditions[{k}]");
        let given = |key: &str| raw["boundary_conditions"][k].get(key).is_some();
        if bc.penalty.is_some() {
            return refuse(
                format!("{loc}.penalty"),
                "penalty walls are not exported (Kratos places its boundary particles on grid condition lines)",
            );
        }
        if given("amplitude") {
            return refuse(
                format!("{loc}.amplitude"),
                "time functions are not exported (Kratos processes over [0, End])",
            );
        }
        if let Some(s) = &bc.slip {
            if s.friction != 0.0 {
                return refuse(format!("{loc}.slip.friction"), "friction on slip boundaries is not exported");
            }
            if s.normal.is_some() {
                notes.push(format!(
                    "{loc}.slip.normal: approximated by the normals Kratos computes from the region's boundary facets"
                ));
            }
        }
    }
    for (k, l) in case.loads.iter().enumerate() {
        let loc = format!("loads[{k}]");
        if raw["loads"][k].get("amplitude").is_some() {
            return refuse(
                format!("{loc}.amplitude"),
                "time functions are not exported (Kratos processes over [0, End])",
            );
        }
        match l {
            LoadSpec::Pressure { .. } => {
                return refuse(
                    format!("{loc}.type"),
                    "pressure loads are not exported (Kratos' LINE_LOAD is a fixed vector)",
                )
            }
            LoadSpec::MaterialPointForce { .. } => {
                return refuse(format!("{loc}.type"), "material point forces are not exported")
            }
            LoadSpec::Traction { .. } if case.formulation.dim() == 3 => {
                return refuse(
                    format!("{loc}.type"),
                    "tractions on 3D grids are not exported (SURFACE_LOAD is not imported back)",
                )
            }
            LoadSpec::NodalForce { .. } if case.formulation == Formulation::Axisymmetric => {
                return refuse(format!("{loc}.type"), "nodal forces in axisymmetric cases are not exported")
            }
            _ => {}
        }
    }
    if let Some(g) = raw.get("gravity") {
        if g.get("amplitude").is_some() {
            return refuse("gravity.amplitude".into(), "time functions are not exported (Kratos' gravity is constant)");
        }
    }
    let analysis = &raw["analysis"];
    for key in ["adaptive", "stop_at_rest"] {
        if analysis.get(key).is_some() {
            return refuse(format!("analysis.{key}"), "Kratos steps with a fixed time step to the end");
        }
    }
    for key in ["max_step_cuts", "checkpoint"] {
        if analysis.get(key).is_some() {
            notes.push(format!("analysis.{key}: left out (no Kratos counterpart)"));
        }
    }
    let taken = [
        "convergence_criterion",
        "residual_relative_tolerance",
        "residual_absolute_tolerance",
        "displacement_relative_tolerance",
        "displacement_absolute_tolerance",
        "max_iterations",
    ];
    if let Some(s) = raw.get("solver").and_then(Value::as_object) {
        for key in s.keys().filter(|k| !taken.contains(&k.as_str())) {
            notes.push(format!("solver.{key}: left out (Kratos: Newton with the sparse_lu direct solver)"));
        }
    }
    for key in ["output", "fmu", "limits"] {
        if raw.get(key).is_some() {
            notes.push(format!("{key}: left out (Loam's own settings)"));
        }
    }
    Ok(())
}
