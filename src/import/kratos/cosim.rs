//! A Kratos CoSimulation folder (CoSimulationApplication, `cosim_*_parameters.json`) of one MPM
//! and one structural solver as ONE monolithic Loam case.
//!
//! Kratos couples the two solvers in a partitioned way: Gauss–Seidel iterations between an MPM
//! solve with the structure's interface displacement imposed (`mpm_dirichlet_wrapper`, a penalty
//! condition on the grid's interface) and a structure solve loaded by the MPM interface force,
//! accelerated (MVQN) and mapped between the non-matching interfaces. Loam solves both domains
//! in one Newton system instead: the MPM side is read by the MPM import
//! ([`super::mpm_case`]), the structure ([`super::structural`], its `.mdpa` and materials)
//! becomes an FEM domain, and the structure's interface sub model part (the co-simulation's
//! `solvers.<structure>.data.disp.model_part_name`) the region of a non-conforming penalty
//! tie (`interfaces[].coupling: "tie"`, docs/coupling.md) between the structure's facets and
//! the MPM grid. The coupling iterations, accelerators, criteria and mappers have nothing to
//! do in one system and are reported as ignored; the MPM's interface condition is reported as
//! replaced by the tie.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::json::{ImportError, Section};
use super::{cells_of, locate, materials, mdpa, msh, read_text, structural, write_case, Import};

/// The CoSimulation parameters file of `dir` (`cosim_*parameters.json`), if it has one.
pub fn find(dir: &Path) -> Result<Option<String>, ImportError> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(None) };
    let mut found: Vec<String> = entries
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.starts_with("cosim") && n.ends_with("parameters.json"))
        .collect();
    found.sort();
    match found.len() {
        0 => Ok(None),
        1 => Ok(found.pop()),
        _ => Err(ImportError(format!(
            "{}: several CoSimulation parameters files ({}): import one folder per co-simulation",
            dir.display(),
            found.join(", ")
        ))),
    }
}

/// A solver's `input_file` as a file name (Kratos appends `.json`).
fn input_file(w: &Section) -> Result<String, ImportError> {
    let f = w.string("input_file")?;
    Ok(if f.ends_with(".json") { f } else { format!("{f}.json") })
}

/// Imports the co-simulation `params` of `dir` as one case `out`.
pub fn import(dir: &Path, params: &str, out: &Path) -> Result<Import, ImportError> {
    let mut notes = Vec::new();
    let (text, file) = read_text(&dir.join(params))?;
    let root = super::json::parse_json(&text, &file)?;
    let top = Section::root(&root, &file)?;
    top.ignore("problem_data", "each solver's own time span is used", &mut notes);

    let s = top.object("solver_settings")?;
    let kind = s.string("type")?;
    if !kind.starts_with("coupled_solvers.") {
        return Err(s.error("type", format!("\"{kind}\": expected a coupled_solvers.… co-simulation")));
    }
    notes.push(s.note(
        "type",
        format!("\"{kind}\": partitioned coupling replaced by one monolithic Newton system (interface tie)"),
    ));
    for key in ["num_coupling_iterations", "convergence_accelerators", "convergence_criteria"] {
        s.ignore(key, "no coupling iterations: both domains are solved in one Newton system", &mut notes);
    }
    s.ignore(
        "data_transfer_operators",
        "no mapping: the tie couples the non-matching interfaces through the grid's shape functions",
        &mut notes,
    );
    s.ignore("coupling_operations", "no data exchanged between solvers", &mut notes);
    s.ignore("coupling_sequence", "no data exchanged between solvers", &mut notes);
    s.ignore("echo_level", "verbosity", &mut notes);

    // the two solvers
    let solvers = s.object("solvers")?;
    let names: Vec<String> =
        root["solver_settings"]["solvers"].as_object().map(|m| m.keys().cloned().collect()).unwrap_or_default();
    let (mut mpm, mut fem) = (None, None);
    for name in &names {
        let w = solvers.object(name)?;
        let t = w.string("type")?;
        let settings = w.object("solver_wrapper_settings")?;
        let input = input_file(&settings)?;
        if t.starts_with("solver_wrappers.kratos.mpm_") {
            if mpm.is_some() {
                return Err(w.error("type", "a second MPM solver: Loam imports one MPM and one structure"));
            }
            settings.ignore(
                "interface_model_part_name",
                "the MPM side of the interface: the tie locates the structure's facets in the grid",
                &mut notes,
            );
            w.ignore("data", "the exchanged interface data: none in one system", &mut notes);
            mpm = Some(input);
        } else if t == "solver_wrappers.kratos.structural_mechanics_wrapper" {
            if fem.is_some() {
                return Err(w.error("type", "a second structure: Loam imports one MPM and one structure"));
            }
            let d = w.object("data")?.object("disp")?;
            let part = d.string("model_part_name")?;
            w.take("data");
            fem = Some((input, part));
        } else {
            return Err(w.error("type", format!("\"{t}\": the importer couples a Kratos MPM and a structural solver")));
        }
        settings.finish(&mut notes);
        w.finish(&mut notes);
    }
    let mpm = mpm.ok_or_else(|| s.error("solvers", "no MPM solver (solver_wrappers.kratos.mpm_…)"))?;
    let (fem, interface) =
        fem.ok_or_else(|| s.error("solvers", "no structure (solver_wrappers.kratos.structural_mechanics_wrapper)"))?;
    solvers.finish(&mut notes);
    s.finish(&mut notes);
    top.finish(&mut notes);

    // the MPM side, as an MPM case
    let (mut case, mut files) = super::mpm_case(dir, &mpm, out, &mut notes)?;
    let soil = match case["domains"].as_array().map(Vec::as_slice) {
        Some([d]) => d["name"].as_str().unwrap_or("body").to_string(),
        _ => return Err(ImportError(format!("{}: the MPM side has several bodies: one is coupled", mpm))),
    };

    // the structure
    let (text, fem_file) = read_text(&locate(dir, &fem))?;
    let st = structural::read(&text, &fem_file, &mut notes)?;
    let (text, mat_file) = read_text(&locate(dir, &st.materials_file))?;
    let mats = materials::read(&text, &mat_file, &mut notes)?;
    let [mat] = mats.as_slice() else {
        return Err(ImportError(format!("{mat_file}: properties: one structure material is imported")));
    };
    if Some(mat.formulation) != case["formulation"].as_str() {
        return Err(ImportError(format!(
            "{mat_file}: the structure is {} but the MPM side {} (a Loam case has one formulation)",
            mat.formulation, case["formulation"]
        )));
    }
    let mesh_path = locate(dir, &st.mesh_file);
    let mesh_name = mesh_path.display().to_string();
    let mesh = mdpa::read(&mesh_path)?;
    notes.extend(mesh.notes.iter().cloned());
    let part = mesh
        .sub_model_part(&mat.part)
        .ok_or_else(|| ImportError(format!("{mesh_name}: no sub model part '{}' (named by {mat_file})", mat.part)))?;
    let cells = cells_of(&mesh, &mesh_name, part.elements.iter().copied(), "", st.domain_size)?;
    for b in &mesh.elements {
        notes.push(format!(
            "{mesh_name}:{}: {} {} elements: Loam's FEM {} with the material's law",
            b.line,
            b.entities.len(),
            b.kind,
            if cells[0].len() == 4 { "quad4" } else { "tri3" }
        ));
    }
    for b in &mesh.conditions {
        notes.push(format!(
            "{mesh_name}:{}: {} {} conditions: ignored (the co-simulation's interface loads; the tie replaces them)",
            b.line,
            b.entities.len(),
            b.kind
        ));
    }
    let interface = interface.strip_prefix(&format!("{}.", st.model_part)).map(str::to_string).ok_or_else(|| {
        ImportError(format!(
            "{file}: solver_settings.solvers: interface \"{interface}\" is not a sub model part of {}",
            st.model_part
        ))
    })?;
    let nodes_of = |name: &str| -> Result<BTreeSet<usize>, ImportError> {
        let smp =
            mesh.sub_model_part(name).ok_or_else(|| ImportError(format!("{mesh_name}: no sub model part '{name}'")))?;
        let mut nodes: BTreeSet<usize> = smp.nodes.iter().copied().collect();
        for id in smp.conditions.iter().chain(&smp.elements) {
            let n = mesh.condition(*id).or_else(|| mesh.element(*id)).map(|c| c.1).unwrap_or_default();
            nodes.extend(n);
        }
        Ok(nodes)
    };
    let mut groups: Vec<(String, BTreeSet<usize>)> = Vec::new();
    for name in st.supports.iter().map(|s| &s.0).chain([&interface]) {
        if !groups.iter().any(|g| &g.0 == name) {
            groups.push((name.clone(), nodes_of(name)?));
        }
    }
    // self-weight: on the whole structure and the MPM side's gravity (Loam has one gravity)
    let all: BTreeSet<usize> = cells.iter().flatten().copied().collect();
    let mut gravity: Option<[f64; 3]> = None;
    for (name, g) in &st.volume_accelerations {
        if !nodes_of(name)?.is_superset(&all) {
            return Err(ImportError(format!(
                "{fem_file}: VOLUME_ACCELERATION on {name}, which is not the whole structure: Loam's gravity acts on every domain"
            )));
        }
        gravity = Some(*g);
    }
    let mpm_gravity: Option<Vec<f64>> = case.get("gravity").map(|g| {
        g["acceleration"].as_array().map(|a| a.iter().filter_map(Value::as_f64).collect()).unwrap_or_default()
    });
    let fem_gravity = gravity.map(|g| g[..2].to_vec());
    if mpm_gravity != fem_gravity {
        return Err(ImportError(format!(
            "{fem_file}: VOLUME_ACCELERATION {fem_gravity:?} differs from the MPM side's gravity {mpm_gravity:?}: Loam has one gravity for all domains"
        )));
    }
    let out_dir = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf();
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "kratos".into());
    let mesh_file = format!("{stem}_structure.msh");
    let path: PathBuf = out_dir.join(&mesh_file);
    std::fs::write(&path, msh::write(&mesh.nodes, &cells, st.domain_size, &groups))
        .map_err(|e| ImportError(format!("{}: cannot write: {e}", path.display())))?;
    files.push(path);

    // one case
    let name = "structure";
    case["materials"][name] = mat.material.clone();
    case["domains"].as_array_mut().expect("domains").push(json!({
        "name": name, "type": "fem", "material": name, "mesh": { "gmsh": mesh_file }
    }));
    let regions = case.entry("regions").or_insert_with(|| json!({}));
    for (g, _) in &groups {
        if regions.get(g).is_some() {
            return Err(ImportError(format!(
                "{mesh_name}: sub model part '{g}' has the name of a grid sub model part (one region name for both)"
            )));
        }
        regions[g] = json!({ "group": g });
    }
    let bcs = case.entry("boundary_conditions").or_insert_with(|| json!([]));
    for (part, value) in &st.supports {
        bcs.as_array_mut().expect("array").push(json!({ "region": part, "displacement": value[..2] }));
    }
    case.insert(
        "interfaces".into(),
        json!([{ "name": interface, "soil": soil, "structure": name, "region": interface, "coupling": "tie" }]),
    );
    if st.analysis != case["analysis"] {
        notes.push(format!(
            "{fem_file}: solver_settings: the structure's analysis {} differs from the MPM side's {}: the MPM side's is used (one system)",
            st.analysis, case["analysis"]
        ));
    }
    if st.solver != case["solver"] {
        notes.push(format!(
            "{fem_file}: solver_settings: the structure's Newton settings {} differ from the MPM side's {}: the MPM side's are used (one system)",
            st.solver, case["solver"]
        ));
    }
    case.insert(
        "description".into(),
        json!(format!(
            "Kratos co-simulation '{params}' imported by `loam import kratos {}`: MPM '{mpm}' and structure '{fem}' in one system, tied on '{interface}'",
            dir.display()
        )),
    );
    write_case(out, case)?;
    Ok(Import { files, notes })
}
