//! `loam import kratos`: Kratos Multiphysics' own MPM test cases imported, run with the `loam`
//! binary and compared with Kratos' results.
//!
//! The case folders in `tests/data/kratos/` are copies of `/work/shared/kratos/cases/` (Kratos'
//! MPMApplication test suite, with their stored `results_reference.json`);
//! `kratos_10.4.4_results.json` holds what Kratos 10.4.4 computes for the same folders on this
//! machine (see its `source`). Each check prints Loam's value beside both. Kratos' own tests
//! compare grid-node displacements with an absolute tolerance of 1e-3 m
//! (`from_json_check_result_process`; 1e-2 m for the penalty cantilever).

mod common;

use common::cli::{loam, temp_dir};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

fn data(case: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/kratos").join(case)
}

/// Imports `dir` into `out/case.json`; returns the case path and the importer's stderr.
fn import(dir: &Path, out: &Path) -> (PathBuf, String) {
    let case = out.join("case.json");
    let o = loam().args(["import", "kratos"]).arg(dir).arg("-o").arg(&case).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "import of {} failed: {stderr}", dir.display());
    (case, stderr)
}

/// Coordinates of node `id` of the case's grid file (two or three, as the case's
/// `domain_size`).
fn grid_node(dir: &Path, id: usize) -> Vec<f64> {
    let m = loam::import::kratos::mdpa::read(&dir.join("Grid.mdpa")).unwrap();
    let p: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("ProjectParameters.json")).unwrap()).unwrap();
    let dim = p["solver_settings"]["domain_size"].as_u64().unwrap_or(2) as usize;
    m.nodes[&id][..dim].to_vec()
}

/// Adds `monitors` to the imported case, runs it and returns the last row of monitors.csv.
fn run(case: &Path, monitors: Vec<Value>) -> BTreeMap<String, f64> {
    let mut c: Value = serde_json::from_str(&std::fs::read_to_string(case).unwrap()).unwrap();
    c["monitors"] = Value::Array(monitors);
    c["output"] = json!({ "vtk": false });
    std::fs::write(case, serde_json::to_string_pretty(&c).unwrap()).unwrap();
    let out = case.parent().unwrap().join("out");
    let o = loam().arg("run").arg(case).args(["--quiet", "--threads", "1", "--out"]).arg(&out).output().unwrap();
    assert!(o.status.success(), "loam run failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("monitors.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let last: Vec<f64> = lines.last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    header.into_iter().zip(last).collect()
}

/// The last value of `variable` of `key` (e.g. `NODE_93`) in a Kratos result file.
fn stored(file: &Path, key: &str, variable: &str) -> f64 {
    let r: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    let v = &r[key][variable];
    v.as_array().map_or_else(|| v.as_f64(), |a| a.last().and_then(Value::as_f64)).unwrap()
}

/// Kratos 10.4.4's value on this machine (`kratos_10.4.4_results.json`).
fn kratos_now(case: &str, key: &str, variable: &str) -> f64 {
    let r: Value = serde_json::from_str(&std::fs::read_to_string(data("kratos_10.4.4_results.json")).unwrap()).unwrap();
    r[case][key][variable].as_f64().unwrap()
}

/// Imports and runs `case`, returning Loam's displacement `component` at grid node `node`.
fn grid_displacement(case: &str, node: usize, component: &str) -> f64 {
    let dir = data(case);
    let (json, _) = import(&dir, &temp_dir(case));
    let m = run(
        &json,
        vec![json!({ "name": "u", "type": "displacement", "point": grid_node(&dir, node), "component": component })],
    );
    m["u"]
}

/// Prints and checks Loam against Kratos' stored reference and today's Kratos.
fn compare(case: &str, node: usize, component: &str, tol_stored: f64, tol_now: f64) {
    let var = if component == "x" { "DISPLACEMENT_X" } else { "DISPLACEMENT_Y" };
    let key = format!("NODE_{node}");
    let loam = grid_displacement(case, node, component);
    let reference = stored(&data(case).join("results_reference.json"), &key, var);
    let now = kratos_now(case, &key, var);
    println!(
        "{case}: grid node {node} {var}: Loam {loam:.10e}, Kratos stored reference {reference:.10e} (diff {:.3e}), Kratos 10.4.4 {now:.10e} (diff {:.3e})",
        loam - reference,
        loam - now
    );
    assert!(
        (loam - reference).abs() <= tol_stored,
        "{case}: Loam {loam} vs stored reference {reference} beyond {tol_stored}"
    );
    assert!((loam - now).abs() <= tol_now, "{case}: Loam {loam} vs Kratos 10.4.4 {now} beyond {tol_now}");
}

/// The issue's acceptance case. Kratos 10.4.4 computes −0.673829 m at the tip (8, 1), and
/// Loam the same to 1e-12 m (checked to 1e-6 m); the stored `results_reference.json` says −0.660814 m, which
/// Kratos 10.4.4 itself does not reproduce (1.3e-2 m off, its own check tolerance is 1e-3 m):
/// the stored file is stale (its horizontal displacements are also three times the beam's
/// foreshortening), so the stored reference is checked only to 2 %.
#[test]
fn cantilever_selfweight_matches_kratos() {
    compare("cantilever_selfweight_2D_quad", 93, "y", 0.02 * 0.66, 1e-6);
    compare("cantilever_selfweight_2D_quad", 1, "x", 0.06, 1e-6);
}

/// Linear elastic cantilever under a line load on its top edge: Loam equals Kratos to 1e-4
/// relative (the displacements are 3e-6 m, far below Kratos' absolute 1e-3 m).
#[test]
fn cantilever_lineload_matches_kratos() {
    compare("cantilever_lineload_2D_quad", 881, "y", 3e-10, 3e-10);
}

/// The self-weight cantilever clamped by penalty boundary particles. Kratos' test compares it
/// with the conforming result at 1e-2 m. Loam places its boundary particles evenly along the
/// condition lines (Kratos: 5 per line at its own positions): 9e-4 m from Kratos 10.4.4.
#[test]
fn cantilever_penalty_matches_kratos() {
    compare("cantilever_selfweight_penalty_2D_quad", 93, "y", 1e-2, 2e-3);
}

/// Axisymmetric circular plate under a line load, triangles, 3 points per cell: within
/// Kratos' 1e-3 m (6e-5 m apart). The two codes differ by a uniform factor 1.00082 over the
/// whole grid at this load (0.08 % of a 0.076 m deflection of a 1 m thick plate): a second-order
/// (large-deformation) difference in the axisymmetric terms; in the linear range they agree to
/// 1e-6 ([`circular_plate_axisym_linear_range_matches_kratos`]). Likely cause, from reading
/// Kratos' source (not confirmed by a run: Kratos refuses `move_mesh_flag: true` here): its
/// spatial hoop row `N_a / r` takes `r` from the grid's node coordinates, which are not moved
/// (`move_mesh_flag: false`), so it integrates `σ_θθ N_a / R dv` where the consistent form has
/// `σ_θθ N_a / r dv` (Loam's `P̃_θθ N_a / R dV`): they differ by `r / R = F_θθ`.
#[test]
fn circular_plate_axisym_matches_kratos() {
    compare("circular_plate_axisym", 1, "y", 1e-3, 1e-3);
}

/// The same plate with the line load scaled by 1e-3 (Kratos 10.4.4 run on the folder with
/// `LINE_LOAD` modulus 0.10184): the centre deflection within 1e-6 relative of Kratos — the
/// axisymmetric weights `2πr` of points and line load, the hoop strain and the law agree in
/// the linear range (measured 8e-7: the remainder of the second-order difference above).
#[test]
fn circular_plate_axisym_linear_range_matches_kratos() {
    let case = "circular_plate_axisym";
    let dir = data(case);
    let (json, _) = import(&dir, &temp_dir("axisym-linear"));
    let mut c: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let load = &mut c["loads"][0]["traction"][1];
    *load = json!(load.as_f64().unwrap() * 1e-3);
    std::fs::write(&json, serde_json::to_string_pretty(&c).unwrap()).unwrap();
    let m =
        run(&json, vec![json!({ "name": "u", "type": "displacement", "point": grid_node(&dir, 1), "component": "y" })]);
    let now = kratos_now("circular_plate_axisym_load_1e-3", "NODE_1", "DISPLACEMENT_Y");
    let error = (m["u"] - now).abs() / now.abs();
    println!("{case}, load × 1e-3: grid node 1 u_y Loam {:.10e}, Kratos 10.4.4 {now:.10e}, relative {error:.2e} (tolerance 1e-6)", m["u"]);
    assert!(error <= 1e-6, "axisymmetric plate in the linear range: Loam {} vs Kratos {now}", m["u"]);
}

/// Cook's membrane, incompressible (ν = 0.499999) Neo-Hookean with pressure unknowns. Kratos'
/// `MPMUpdatedLagrangianUP2D3N` is a stabilised equal-order u–p triangle, Loam's `mixed_up` a
/// different mixed form, so the loaded corner is 2e-3 m (0.8 %) apart, beyond Kratos' 1e-3 m:
/// checked to 1 %.
#[test]
fn cooks_membrane_up_close_to_kratos() {
    compare("cooks_membrane_UP_incompressible", 1594, "y", 0.01 * 0.257, 0.01 * 0.257);
}

/// Two triangles sliding down a frictionless 45° slip boundary (dynamic, Newmark): the
/// material point velocity at 1.5 s against Kratos' stored one (analytical g sin45 cos45 t).
#[test]
fn slip_boundary_matches_kratos() {
    let case = "slip_boundary_2D";
    let dir = data(case);
    let (json, _) = import(&dir, &temp_dir(case));
    let m = run(
        &json,
        vec![
            json!({ "name": "vx", "type": "material_point_velocity", "point": [-7.07107, 6.36396], "component": "x" }),
        ],
    );
    let reference = stored(&dir.join("results_reference.json"), "MP_26", "MP_VELOCITY_X");
    println!(
        "{case}: MP_VELOCITY_X at 1.5 s: Loam {:.10e}, Kratos stored {reference:.10e}, analytical {:.6}",
        m["vx"],
        4.905 * 1.5
    );
    assert!((m["vx"] - reference).abs() < 1e-3);
}

/// The 3D self-weight cantilever (7 × 1 × 1 m, Neo-Hookean, ν = 0, h = 0.5 m) on hexahedra,
/// 8 points per cell, written by `benches/kratos/gen_cantilever_3d.py` (Kratos' test suite has no
/// 3D case with its parameters published; the stored reference is Kratos 10.4.4's own result
/// on this folder): the tip's grid node (7, 1, 0.5) to 1e-9 m in both components. With ν = 0
/// it bends as the plane-strain beam of the same h.
#[test]
fn cantilever_3d_hexahedra_matches_kratos() {
    compare("cantilever_selfweight_3D_hexa", 338, "y", 1e-9, 1e-9);
    compare("cantilever_selfweight_3D_hexa", 338, "x", 1e-9, 1e-9);
}

/// The same beam with every hexahedron of grid and body split into six tetrahedra (Kuhn),
/// 4 points per cell: the linear tetrahedra lock (−0.221 m against −0.355 m on hexahedra) in
/// Kratos and in Loam alike, to 1e-9 m.
#[test]
fn cantilever_3d_tetrahedra_matches_kratos() {
    compare("cantilever_selfweight_3D_tetra", 338, "y", 1e-9, 1e-9);
    compare("cantilever_selfweight_3D_tetra", 338, "x", 1e-9, 1e-9);
}

/// A copy of `case` in a temporary folder, `edit` applied to the named file's text.
fn edited_copy(case: &str, name: &str, file: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let dir = temp_dir(name).join("case");
    std::fs::create_dir_all(&dir).unwrap();
    for e in std::fs::read_dir(data(case)).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
    }
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    std::fs::write(dir.join(file), edit(&text)).unwrap();
    dir
}

/// The comparison catches a wrong importer: the line load along x instead of y (a swapped
/// axis) moves the loaded tip by far more than the tolerance.
#[test]
fn swapped_axis_is_caught() {
    let case = "cantilever_lineload_2D_quad";
    let dir = edited_copy(case, "swapped", "ProjectParameters.json", |t| {
        t.replacen(
            "\"direction\": [\n                        0.0,\n                        -1.0,",
            "\"direction\": [\n                        -1.0,\n                        0.0,",
            1,
        )
    });
    let (json, _) = import(&dir, dir.parent().unwrap());
    let m = run(
        &json,
        vec![json!({ "name": "u", "type": "displacement", "point": grid_node(&dir, 881), "component": "y" })],
    );
    let reference = stored(&dir.join("results_reference.json"), "NODE_881", "DISPLACEMENT_Y");
    println!("swapped axis: Loam {:.4e} vs reference {reference:.4e}", m["u"]);
    assert!((m["u"] - reference).abs() > 100.0 * 3e-10, "a swapped load direction went unnoticed");
}

/// Imports `dir` expecting a refusal: exit code 2; returns stderr (printed).
fn refused_import(dir: &Path) -> String {
    let o = loam()
        .args(["import", "kratos"])
        .arg(dir)
        .arg("-o")
        .arg(dir.parent().unwrap().join("c.json"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    println!("{stderr}");
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    stderr
}

/// A malformed node line: exit code 2, one line naming the file and line, no panic.
#[test]
fn malformed_mdpa_names_file_and_line() {
    let dir = edited_copy("cantilever_lineload_2D_quad", "malformed", "Grid.mdpa", |t| {
        let mut lines: Vec<String> = t.lines().map(String::from).collect();
        lines[9] = "    3   0.1000000000   zero   0.0000000000".into();
        lines.join("\n")
    });
    let stderr = refused_import(&dir);
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("Grid.mdpa:10: coordinate `zero` is not a finite number"), "{stderr}");
}

/// Every key the importer does not take over is reported with its file and JSON path; an
/// unknown law is refused (exit code 2) naming its JSON path.
#[test]
fn unknown_keys_reported_unknown_law_refused() {
    let dir = edited_copy("cantilever_lineload_2D_quad", "unknown", "ProjectParameters.json", |t| {
        t.replacen("\"pressure_dofs\": false", "\"pressure_dofs\": false, \"block_builder\": true", 1)
    });
    let (_, notes) = import(&dir, dir.parent().unwrap());
    println!("{notes}");
    assert!(notes
        .contains("ProjectParameters.json: solver_settings.block_builder: ignored (not understood by the importer)"));
    assert!(notes.contains("processes.list_other_processes[0]: from_json_check_result_process: ignored"));
    let dir = edited_copy("cantilever_lineload_2D_quad", "law", "materials.json", |t| {
        t.replacen("LinearElasticIsotropicPlaneStrain2DLaw", "SandHypoplasticPlaneStrain2DLaw", 1)
    });
    let stderr = refused_import(&dir);
    assert!(stderr.contains("materials.json: properties[0].Material.constitutive_law.name: Kratos law 'SandHypoplasticPlaneStrain2DLaw' has no Loam counterpart"), "{stderr}");
    // a law Loam has, given without its variables: the missing one is named
    let dir = edited_copy("cantilever_lineload_2D_quad", "camclay", "materials.json", |t| {
        t.replacen("LinearElasticIsotropicPlaneStrain2DLaw", "HenckyBorjaCamClayPlasticPlaneStrain2DLaw", 1)
    });
    let stderr = refused_import(&dir);
    assert!(
        stderr.contains("materials.json: properties[0].Material.Variables.PRE_CONSOLIDATION_STRESS: missing"),
        "{stderr}"
    );
}

/// A line load in a 3D case (Loam has no line loads on 3D grids) is refused, exit code 2,
/// naming the file, the condition and its sub model part.
#[test]
fn line_load_in_3d_refused() {
    let dir = edited_copy("cantilever_selfweight_3D_hexa", "3d-line-load", "ProjectParameters.json", |t| {
        t.replacen(
            "\"gravity\": [",
            r#""loads_process_list": [{"python_module": "assign_vector_by_direction_to_condition_process",
                "Parameters": {"model_part_name": "Background_Grid.DISPLACEMENT_Support", "variable_name": "LINE_LOAD",
                "modulus": 1.0, "direction": [0.0, -1.0, 0.0], "interval": [0.0, "End"]}}], "gravity": ["#,
            1,
        )
    });
    let stderr = refused_import(&dir);
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("ProjectParameters.json: LINE_LOAD on DISPLACEMENT_Support in a 3D case"), "{stderr}");
}

/// Malformed JSON and an unknown Kratos process in a load list: exit code 2, one line naming
/// the file and the line or JSON path.
#[test]
fn malformed_parameters_refused() {
    let dir = edited_copy("cantilever_lineload_2D_quad", "badjson", "ProjectParameters.json", |t| {
        t.replacen("\"end_time\": 1.0,", "\"end_time\": 1.0,,", 1)
    });
    let stderr = refused_import(&dir);
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("ProjectParameters.json:6: invalid JSON"), "{stderr}");
    let dir = edited_copy("cantilever_lineload_2D_quad", "process", "ProjectParameters.json", |t| {
        t.replacen("assign_vector_by_direction_to_condition_process", "assign_scalar_variable_to_conditions_process", 1)
    });
    let stderr = refused_import(&dir);
    assert!(stderr.contains("ProjectParameters.json: processes.loads_process_list[0].python_module: \"assign_scalar_variable_to_conditions_process\""), "{stderr}");
}

/// `loam run DIR` on a Kratos case folder imports it on the fly into `OUT/imported/` and runs
/// it: the imported case is the one `loam import kratos` writes (same settings, materials,
/// conditions), and the results land in the run's folder.
#[test]
fn run_on_a_kratos_folder_imports_on_the_fly() {
    let dir = data("cantilever_selfweight_2D_quad");
    let out = temp_dir("run-folder");
    let o = loam().arg("run").arg(&dir).arg("--out").arg(&out).arg("--quiet").output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert!(o.status.success(), "loam run on the folder: {stderr}");
    let on_the_fly = out.join("imported/cantilever_selfweight_2D_quad.json");
    assert!(stderr.contains("imported the Kratos case"), "{stderr}");
    let (explicit, _) = import(&dir, &temp_dir("run-folder-explicit"));
    let strip = |p: &Path| {
        let mut v: Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        // mesh file names differ with the case name; the settings and materials must not
        v["domains"].as_array_mut().unwrap().iter_mut().for_each(|d| {
            d.as_object_mut().unwrap().retain(|k, _| k != "grid_mesh" && k != "material_points");
        });
        v.as_object_mut().unwrap().remove("description");
        v
    };
    assert_eq!(strip(&on_the_fly), strip(&explicit), "the on-the-fly import is the explicit one");
    assert!(out.join("monitors.csv").is_file(), "results written in the run's folder");
}

/// Kratos' partitioned MPM–FEM co-simulation `mpm_fem_beam` (CoSimulationApplication test
/// `test_MPM_FEM_beam_penalty`; benchmark 12 of BENCHMARKS.md): the plane-strain Neo-Hookean
/// cantilever L = 8 m, h = 1 m clamped at x = 0 under its own weight, FEM (h = 0.1 m) on
/// x ∈ [0, 4] and MPM (grid h = 0.1 m, 4 points per cell) on x ∈ [4, 8], one static step.
/// Kratos iterates between the two solvers (Gauss–Seidel, MVQN); Loam imports the folder as ONE
/// case and solves both halves in one Newton system, tied by the non-conforming penalty tie on
/// the structure's interface sub model part.
///
/// Compared at the tip and at the interface with:
/// - Timoshenko's beam (linear): tip −0.67806 m, w(4) = −0.24346 m (1.5 %);
/// - Kratos 10.4.4 run with the MPM interface's contact force computed (the case README's
///   `--contact-force-fix`; as shipped 10.4.4 passes no load from MPM to FEM): grid node
///   (8, 0.5) −0.6660 m, tip material points −0.6637 m, FEM node (4, 0.5) −0.2383 m (2 %);
/// - the stored `cosim_mpm_fem_beam_{particle,structure}_results.json`, Kratos' partitioned
///   answer of an older Kratos: tip material points MP_1598 (x0 = 7.979, y0 = 0.479) and
///   MP_1757 (y0 = 0.521) −0.6534 / −0.6541 m, FEM node 26 (4, 0.5) −0.2374 m. Kratos 10.4.4
///   itself lands 2.4 % below the stored tip (README), so the stored values are checked to 3 %.
///
/// - the same beam all FEM (quad4, h = 0.1 m): the tie must give the one-piece beam (0.5 %).
///
/// An import that loses the interface leaves the MPM half unsupported: the run fails or its
/// tip is far off.
#[test]
fn mpm_fem_beam_cosimulation_as_one_system() {
    let dir = data("mpm_fem_beam");
    let (json, stderr) = import(&dir, &temp_dir("mpm_fem_beam"));
    println!("{stderr}");
    let case: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(case["interfaces"][0]["coupling"], "tie", "the interface is a tie: {}", case["interfaces"]);
    assert!(stderr.contains("apply_mpm_coupling_interface_dirichlet_condition_process"), "{stderr}");
    let (a, b) = (0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt());
    let m = run(
        &json,
        vec![
            json!({ "name": "tip", "type": "displacement", "point": [8.0, 0.5], "component": "y" }),
            json!({ "name": "mp_lo", "type": "material_point_displacement", "point": [7.9 + 0.1 * b, 0.4 + 0.1 * b], "component": "y" }),
            json!({ "name": "mp_hi", "type": "material_point_displacement", "point": [7.9 + 0.1 * b, 0.5 + 0.1 * a], "component": "y" }),
            json!({ "name": "interface", "type": "displacement", "point": [4.0, 0.5], "component": "y" }),
            json!({ "name": "clamp", "type": "reaction", "region": "DISPLACEMENT_fix_support", "component": "y" }),
        ],
    );
    let mp = 0.5 * (m["mp_lo"] + m["mp_hi"]);
    let stored_mp = 0.5
        * (stored(&dir.join("cosim_mpm_fem_beam_particle_results.json"), "MP_1598", "MP_DISPLACEMENT_Y")
            + stored(&dir.join("cosim_mpm_fem_beam_particle_results.json"), "MP_1757", "MP_DISPLACEMENT_Y"));
    let stored_interface = stored(&dir.join("cosim_mpm_fem_beam_structure_results.json"), "NODE_26", "DISPLACEMENT_Y");
    let (timoshenko_tip, timoshenko_interface) = (-0.67806, -0.24346);
    let (kratos_tip, kratos_mp, kratos_interface) = (-0.6660, -0.6637, -0.2383);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    println!(
        "mpm_fem_beam: tip grid node (8, 0.5) u_y: Loam {:.6} m, Timoshenko {timoshenko_tip} ({:+.2} %), Kratos 10.4.4 partitioned {kratos_tip} ({:+.2} %)",
        m["tip"],
        100.0 * (m["tip"] / timoshenko_tip - 1.0),
        100.0 * (m["tip"] / kratos_tip - 1.0)
    );
    println!(
        "mpm_fem_beam: tip material points (7.979, 0.479/0.521) u_y: Loam {mp:.6} m, Kratos stored {stored_mp:.6} ({:+.2} %), Kratos 10.4.4 partitioned {kratos_mp} ({:+.2} %)",
        100.0 * (mp / stored_mp - 1.0),
        100.0 * (mp / kratos_mp - 1.0)
    );
    println!(
        "mpm_fem_beam: interface FEM node (4, 0.5) u_y: Loam {:.6} m, Timoshenko {timoshenko_interface} ({:+.2} %), Kratos stored {stored_interface:.6} ({:+.2} %), Kratos 10.4.4 partitioned {kratos_interface} ({:+.2} %); clamp reaction {:.1} N (weight 78480 N)",
        m["interface"],
        100.0 * (m["interface"] / timoshenko_interface - 1.0),
        100.0 * (m["interface"] / stored_interface - 1.0),
        100.0 * (m["interface"] / kratos_interface - 1.0),
        m["clamp"]
    );
    assert!(rel(m["tip"], timoshenko_tip) <= 0.015, "tip {} vs Timoshenko {timoshenko_tip}", m["tip"]);
    assert!(rel(m["tip"], kratos_tip) <= 0.015, "tip {} vs Kratos 10.4.4 {kratos_tip}", m["tip"]);
    assert!(rel(mp, kratos_mp) <= 0.015, "tip points {mp} vs Kratos 10.4.4 {kratos_mp}");
    assert!(rel(mp, stored_mp) <= 0.03, "tip points {mp} vs stored {stored_mp}");
    let i = m["interface"];
    assert!(rel(i, timoshenko_interface) <= 0.015, "interface {i} vs Timoshenko {timoshenko_interface}");
    assert!(rel(i, kratos_interface) <= 0.02, "interface {i} vs Kratos 10.4.4 {kratos_interface}");
    assert!(rel(i, stored_interface) <= 0.02, "interface {i} vs stored {stored_interface}");
    assert!(rel(m["clamp"], 78480.0) <= 1e-6, "the clamp carries the whole beam: {}", m["clamp"]);

    // the same beam all FEM (quad4, h = 0.1 m as both halves, the structure's material)
    let fem = json.parent().unwrap().join("fem_only.json");
    let fem_case = json!({
        "description": "mpm_fem_beam all FEM",
        "formulation": "plane_strain",
        "materials": { "beam": case["materials"]["structure"] },
        "domains": [{ "name": "beam", "type": "fem", "material": "beam",
            "mesh": { "rectangle": { "origin": [0.0, 0.0], "size": [8.0, 1.0], "cells": [80, 10], "element": "quad4" } } }],
        "regions": { "clamp": { "x": 0.0 } },
        "boundary_conditions": [{ "region": "clamp", "displacement": [0.0, 0.0] }],
        "gravity": case["gravity"],
        "analysis": case["analysis"],
        "solver": case["solver"]
    });
    std::fs::write(&fem, serde_json::to_string_pretty(&fem_case).unwrap()).unwrap();
    let f = run(
        &fem,
        vec![
            json!({ "name": "tip", "type": "displacement", "point": [8.0, 0.5], "component": "y" }),
            json!({ "name": "interface", "type": "displacement", "point": [4.0, 0.5], "component": "y" }),
        ],
    );
    println!(
        "mpm_fem_beam: all-FEM beam (h = 0.1 m): tip {:.6} m (coupled {:+.3} %), (4, 0.5) {:.6} m (coupled {:+.3} %)",
        f["tip"],
        100.0 * (m["tip"] / f["tip"] - 1.0),
        f["interface"],
        100.0 * (i / f["interface"] - 1.0)
    );
    assert!(rel(m["tip"], f["tip"]) <= 0.005, "tip {} vs the all-FEM beam {}", m["tip"], f["tip"]);
    assert!(rel(i, f["interface"]) <= 0.005, "interface {i} vs the all-FEM beam {}", f["interface"]);
}

/// Without the interface (the structure's interface sub model part renamed in the
/// co-simulation file) the import is refused: one line naming the file and the sub model part.
#[test]
fn cosimulation_interface_must_exist() {
    let dir = edited_copy("mpm_fem_beam", "no-interface", "cosim_mpm_fem_beam_parameters.json", |t| {
        t.replace("Structure.INTERFACE_normal_vector_calculator", "Structure.INTERFACE_nowhere")
    });
    let stderr = refused_import(&dir);
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("structure.mdpa: no sub model part 'INTERFACE_nowhere'"), "{stderr}");
}

/// The imported case with its interface removed does not run: Loam refuses an FEM mesh on a
/// grid that no interface joins (the MPM half would otherwise hang free).
#[test]
fn cosimulation_without_interface_does_not_run() {
    let (json, _) = import(&data("mpm_fem_beam"), &temp_dir("mpm_fem_beam-noi"));
    let mut c: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    c.as_object_mut().unwrap().remove("interfaces");
    std::fs::write(&json, serde_json::to_string_pretty(&c).unwrap()).unwrap();
    let o = loam()
        .arg("run")
        .arg(&json)
        .args(["--quiet", "--out"])
        .arg(json.parent().unwrap().join("out"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert!(!o.status.success(), "a run without the tie must fail");
    assert!(stderr.contains("no interface joins them"), "{stderr}");
}

/// A co-simulation solver the importer does not couple: exit code 2, one line naming the file
/// and the key.
#[test]
fn cosimulation_unknown_solver_refused() {
    let dir = edited_copy("mpm_fem_beam", "cosim-fluid", "cosim_mpm_fem_beam_parameters.json", |t| {
        t.replace(
            "solver_wrappers.kratos.structural_mechanics_wrapper",
            "solver_wrappers.kratos.fluid_dynamics_wrapper",
        )
    });
    let stderr = refused_import(&dir);
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains("cosim_mpm_fem_beam_parameters.json: solver_settings.solvers.structure.type: \"solver_wrappers.kratos.fluid_dynamics_wrapper\""),
        "{stderr}"
    );
}

/// Kratos' granular flow (`granular_flow_2D`, Kratos' Examples: the Bui et al. 2008 column,
/// `HenckyMCPlastic…`, 30 000 material points on structured triangles h = 2 mm, Newmark,
/// Δt = 5e-5 s; the grid generated by `benches/kratos/gen_granular_grid.py`, the folder has no
/// stored numeric reference): the first 100 steps (5 ms, the column starting to collapse)
/// imported and run, against Kratos 10.4.4 on the same folder
/// (`benches/kratos/granular_flow_probe.py`): the kinetic energy of the material points within
/// 1e-5 relative (measured 5.1e-6) and the vertical displacement of the point nearest the
/// top corner within 1e-6 relative (measured 2.5e-8). About 10 s.
#[test]
fn granular_flow_first_steps_match_kratos() {
    let case = "granular_flow_2D";
    let dir = data(case);
    let (json, _) = import(&dir, &temp_dir(case));
    let mut c: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    c["analysis"]["end_time"] = json!(100.0 * 5e-5);
    std::fs::write(&json, serde_json::to_string_pretty(&c).unwrap()).unwrap();
    let now = |key: &str| kratos_now("granular_flow_2D_100_steps", key, "value");
    let corner = [now("corner_x"), now("corner_y")];
    let m = run(
        &json,
        vec![
            json!({ "name": "kinetic_energy", "type": "kinetic_energy" }),
            json!({ "name": "corner_uy", "type": "material_point_displacement", "point": corner, "component": "y" }),
        ],
    );
    for (name, key, tolerance) in [("kinetic_energy", "kinetic_energy", 1e-5), ("corner_uy", "corner_uy", 1e-6)] {
        let (loam, kratos) = (m[name], now(key));
        let error = (loam - kratos).abs() / kratos.abs();
        println!("{case}, 100 steps: {name} Loam {loam:.10e}, Kratos 10.4.4 {kratos:.10e}, relative {error:.2e} (tolerance {tolerance:.0e})");
        assert!(error <= tolerance, "{case}: {name} Loam {loam} vs Kratos {kratos}");
    }
}
