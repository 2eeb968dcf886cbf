//! The `loam` command line: acceptance runs and bad input (one-line message naming the
//! JSON path, exit code 2, never a panic).

mod common;

use common::cli::{loam, root, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

fn last_monitor(csv: &Path, column: &str) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == column).expect("column present");
    lines.last().unwrap().split(',').nth(k).unwrap().parse().unwrap()
}

/// Issue 2 acceptance: `loam run cases/cantilever_fem.json --out D` writes D/monitors.csv
/// whose last tip_uy is within 3 % of −0.39256 m, and a .pvd series.
#[test]
fn run_cantilever_writes_monitors_and_vtk() {
    let out = temp_dir("cantilever");
    let status = loam()
        .args(["run", "cases/cantilever_fem.json", "--quiet", "--out"])
        .arg(&out)
        .current_dir(root())
        .status()
        .unwrap();
    assert!(status.success());
    let tip = last_monitor(&out.join("monitors.csv"), "tip_uy");
    println!("loam run: last tip_uy {tip:.6} m vs Euler–Bernoulli −0.39256 m (tolerance 3 %, BENCHMARKS.md)");
    assert!((tip + 0.39256).abs() / 0.39256 < 0.03);
    assert!(out.join("beam.pvd").exists() && out.join("beam_000001.vtu").exists());
}

/// Issue 3 acceptance: `loam law cases/laws/mc_triaxial_drained.json --out D` writes
/// D/path.csv whose largest q is within 1 % of the closed-form Mohr–Coulomb peak
/// σ₃ (1 + sin φ)/(1 − sin φ) + 2 c cos φ/(1 − sin φ) − σ₃ = 162.088 kPa.
#[test]
fn law_driver_mohr_coulomb_triaxial_peak() {
    let out = temp_dir("law");
    let status = loam()
        .args(["law", "cases/laws/mc_triaxial_drained.json", "--out"])
        .arg(&out)
        .current_dir(root())
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(out.join("path.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let kq = header.iter().position(|h| *h == "q").unwrap();
    let q = lines.map(|l| l.split(',').nth(kq).unwrap().parse::<f64>().unwrap()).fold(0.0, f64::max);
    let (phi, c, s3) = (25f64.to_radians(), 5e3, 100e3);
    let closed = s3 * (1.0 + phi.sin()) / (1.0 - phi.sin()) + 2.0 * c * phi.cos() / (1.0 - phi.sin()) - s3;
    println!("loam law: peak q {:.3} kPa vs closed form {:.3} kPa (tolerance 1 %)", q / 1e3, closed / 1e3);
    assert!((q - closed).abs() / closed < 0.01);
}

/// Writes the cantilever case with `edit` applied to its JSON and runs `loam check`.
fn check_edited(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> (i32, String) {
    let text = std::fs::read_to_string(root().join("cases/cantilever_fem.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut json);
    let dir = temp_dir(name);
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    check_file(&path)
}

fn check_file(path: &Path) -> (i32, String) {
    let out = loam().arg("check").arg(path).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
    (out.status.code().unwrap_or(-1), stderr)
}

fn expect_bad(name: &str, (code, msg): (i32, String), must_contain: &[&str]) {
    println!("{name}: exit {code}: {msg}");
    assert_eq!(code, 2, "{name}: exit code");
    assert_eq!(msg.lines().count(), 1, "{name}: one-line message");
    assert!(!msg.contains("panicked"), "{name}: panic");
    for m in must_contain {
        assert!(msg.contains(m), "{name}: message should name '{m}': {msg}");
    }
}

#[test]
fn bad_input_exits_2_naming_the_json_path() {
    use serde_json::json;
    expect_bad(
        "unknown key",
        check_edited("unknown", |j| j["solver"]["max_iteration"] = json!(3)),
        &["solver", "max_iteration"],
    );
    // issue 26: the PETSc solver needs the `petsc` feature; a default build refuses it
    if cfg!(not(feature = "petsc")) {
        expect_bad(
            "petsc without the feature",
            check_edited("petsc", |j| j["solver"]["linear_solver"] = json!("petsc")),
            &["solver.linear_solver", "petsc", "feature"],
        );
    }
    // PETSc options apply to the petsc solver only, and are an object of names and values
    expect_bad(
        "petsc_options without petsc",
        check_edited("petsc-options", |j| j["solver"]["petsc_options"] = json!({"-ksp_type": "cg"})),
        &["solver.petsc_options", "linear_solver"],
    );
    expect_bad(
        "petsc_options of the wrong type",
        check_edited("petsc-options-type", |j| {
            j["solver"]["linear_solver"] = json!("petsc");
            j["solver"]["petsc_options"] = json!("-ksp_type cg");
        }),
        &["solver.petsc_options", "object"],
    );
    expect_bad(
        "petsc_options value of the wrong type",
        check_edited("petsc-options-value", |j| {
            j["solver"]["linear_solver"] = json!("petsc");
            j["solver"]["petsc_options"] = json!({"-ksp_type": ["cg"]});
        }),
        &["solver.petsc_options.-ksp_type", "string"],
    );
    expect_bad("unknown top key", check_edited("unknown-top", |j| j["gravityy"] = json!(1)), &["gravityy"]);
    // an MPM grid's mass is lumped: a consistent mass there would be silently ignored
    let mut mpm: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join("cases/cantilever_mpm.json")).unwrap()).unwrap();
    mpm["domains"][0]["mass_matrix"] = json!("consistent");
    let path = temp_dir("mpm-consistent-mass").join("case.json");
    std::fs::write(&path, mpm.to_string()).unwrap();
    expect_bad("consistent mass on an mpm domain", check_file(&path), &["domains[0].mass_matrix", "lumped"]);
    expect_bad(
        "wrong type",
        check_edited("type", |j| j["analysis"]["time_step"] = json!("one")),
        &["analysis.time_step"],
    );
    expect_bad(
        "E <= 0",
        check_edited("young", |j| j["materials"]["beam"]["young_modulus"] = json!(-1.0)),
        &["materials.beam.young_modulus", "> 0"],
    );
    expect_bad(
        "nu out of range",
        check_edited("nu", |j| j["materials"]["beam"]["poisson_ratio"] = json!(0.6)),
        &["materials.beam.poisson_ratio"],
    );
    // ν = 0.5 (incompressible) is a valid Neo-Hookean material, for mixed u–p domains only
    expect_bad(
        "incompressible in a displacement domain",
        check_edited("nu05", |j| j["materials"]["beam"]["poisson_ratio"] = json!(0.5)),
        &["domains[0].material", "mixed_up"],
    );
    expect_bad(
        "missing material",
        check_edited("mat", |j| j["domains"][0]["material"] = json!("steel")),
        &["domains[0].material", "steel"],
    );
    expect_bad(
        "empty region",
        check_edited("region", |j| j["regions"]["clamp"] = json!({"x": -5.0})),
        &["regions.clamp", "no node"],
    );
    expect_bad(
        "unknown region",
        check_edited("bcregion", |j| j["boundary_conditions"][0]["region"] = json!("wall")),
        &["boundary_conditions[0].region", "wall"],
    );
    expect_bad(
        "vector length",
        check_edited("len", |j| j["gravity"]["acceleration"] = json!([0.0, -9.81, 0.0])),
        &["gravity.acceleration"],
    );
    expect_bad(
        "missing mesh file",
        check_edited("mesh", |j| j["domains"][0]["mesh"] = json!({"gmsh": "nowhere.msh"})),
        &["domains[0].mesh.gmsh", "nowhere.msh"],
    );
    expect_bad(
        "inverted element",
        check_edited("inverted", |j| j["domains"][0]["mesh"]["rectangle"]["size"] = json!([7.0, -1.0])),
        &["domains[0].mesh.rectangle.size[1]"],
    );
    let dir = temp_dir("syntax");
    std::fs::write(dir.join("bad.json"), "{\n  \"description\": \"x\",\n  \"materials\": {,\n}").unwrap();
    expect_bad("syntax error", check_file(&dir.join("bad.json")), &["line 3"]);
    std::fs::write(dir.join("corrupt.msh"), "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n").unwrap();
    expect_bad(
        "corrupt mesh",
        check_edited("corrupt", |j| j["domains"][0]["mesh"] = json!({"gmsh": dir.join("corrupt.msh")})),
        &["domains[0].mesh.gmsh"],
    );
    expect_bad("no case file", check_file(Path::new("/nonexistent/case.json")), &["cannot read"]);
}

/// A step that still fails after all cuts stops the run with exit 1, a message naming the
/// step, time and cause, and everything converged so far written (monitors and VTK).
#[test]
fn failing_step_keeps_converged_results() {
    let path = write_case(
        "failing",
        &bundled("cantilever_fem", |json| {
            json["gravity"]["amplitude"] = serde_json::json!([[0, 0], [1, 1], [2, 2000]]);
            json["analysis"] =
                serde_json::json!({"type": "static", "time_step": 0.5, "end_time": 2.0, "max_step_cuts": 2});
            json["solver"]["max_iterations"] = serde_json::json!(8);
        }),
    );
    let dir = path.parent().unwrap();
    let (code, stderr) = run_file(&path);
    println!("exit {code}: {stderr}");
    assert_eq!(code, 1);
    assert!(
        stderr.contains("stopped at step 3") && stderr.contains("after 2 cuts") && stderr.contains("t = 1.000000e0")
    );
    let csv = std::fs::read_to_string(dir.join("out/monitors.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 3, "header, t = 0, 0.5 and 1");
    assert!(dir.join("out/beam_000002.vtu").exists());
    let tip = last_monitor(&dir.join("out/monitors.csv"), "tip_uy");
    assert!((tip + 0.39256).abs() / 0.39256 < 0.03, "the converged state at t = 1 is the benchmark's");
}

/// Issue 31: every converged sub-step of a cut step is written as it converges — a row of
/// `monitors.csv`, a `.vtu` and its entry in the `.pvd` series — so that a later sub-step
/// that fails loses nothing. The static MPM cantilever under a load that turns steep after
/// t = 0.25 (gravity × 10 to 0.25, then × 400 at 0.5) in one step of 0.5 with at most 4 cuts and 4
/// Newton iterations: the step converges only in sub-steps of 0.125 and 0.0625 (t = 0.125,
/// 0.1875, 0.25), then fails; all three are in the results, and the message says so.
#[test]
fn cut_step_writes_every_converged_substep() {
    let path = write_case(
        "substeps",
        &bundled("cantilever_mpm", |json| {
            json["gravity"] = serde_json::json!({"acceleration": [0.0, -100.0],
                "amplitude": [[0.0, 0.0], [0.25, 0.25], [0.5, 100.0]]});
            json["analysis"] =
                serde_json::json!({"type": "static", "time_step": 0.5, "end_time": 0.5, "max_step_cuts": 4});
            json["solver"]["max_iterations"] = serde_json::json!(4);
        }),
    );
    let dir = path.parent().unwrap();
    let (code, stderr) = run_file(&path);
    println!("exit {code}: {stderr}");
    assert_eq!(code, 1);
    assert!(stderr.contains("results up to t = 2.500000e-1 s") && stderr.contains("(3 steps"), "{stderr}");
    let csv = std::fs::read_to_string(dir.join("out/monitors.csv")).unwrap();
    let times: Vec<f64> = csv.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    println!("monitors.csv times {times:?}");
    assert_eq!(times, vec![0.0, 0.125, 0.1875, 0.25], "a row per converged sub-step");
    for k in 0..4 {
        assert!(dir.join(format!("out/beam_{k:06}.vtu")).exists(), "beam_{k:06}.vtu");
    }
    let pvd = std::fs::read_to_string(dir.join("out/beam.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 4, "the series lists every sub-step");
    let summary = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\"") && summary.contains("\"steps\": 3"));
}

/// Writes `case` (JSON) into a fresh directory `name` and returns the file.
fn write_case(name: &str, case: &serde_json::Value) -> PathBuf {
    let dir = temp_dir(name);
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string_pretty(case).unwrap()).unwrap();
    path
}

/// A bundled case as JSON with `edit` applied.
fn bundled(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> serde_json::Value {
    let text = std::fs::read_to_string(root().join("cases").join(format!("{name}.json"))).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut json);
    json
}

/// `loam run` of `case` in its own output directory: exit code and stderr.
fn run_file(case: &Path) -> (i32, String) {
    let out = loam().arg("run").arg(case).arg("--quiet").arg("--out").arg(case.with_file_name("out")).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).trim().to_string())
}

/// Issue 31: a static model without supports is named as such, not by its symptom
/// ("inverted deformation gradient (det F = 0)"). With no boundary condition at all `loam
/// check` refuses it (exit 2, naming `boundary_conditions`); with too few supports (rollers
/// that leave the vertical translation free, a single pinned node that leaves a rotation
/// free) the run stops at the first step saying which rigid-body motion is free (exit 1).
/// Without supports but dynamic, the mass holds it and the run finishes.
#[test]
fn static_model_without_supports_is_named() {
    use serde_json::json;
    let unsupported = bundled("cantilever_fem", |j| {
        j.as_object_mut().unwrap().remove("boundary_conditions");
    });
    expect_bad(
        "static, no boundary condition",
        check_file(&write_case("unsupported", &unsupported)),
        &["boundary_conditions", "static analysis needs supports", "singular"],
    );
    for (name, region, displacement, motion) in [
        ("rollers", "clamp", json!([0.0, null]), "free to move as a rigid body: translation in y"),
        ("pinned", "tip", json!([0.0, 0.0]), "free to move as a rigid body: rotation about (7, 0.5)"),
    ] {
        let mut case = unsupported.clone();
        case["boundary_conditions"] = json!([{ "region": region, "displacement": displacement }]);
        let (code, stderr) = run_file(&write_case(name, &case));
        println!("{name}: exit {code}: {stderr}");
        assert_eq!(code, 1);
        assert_eq!(stderr.lines().count(), 1);
        for expected in ["stopped at step 1", "the static model is not supported", "singular", "domain 'beam'", motion]
        {
            assert!(stderr.contains(expected), "{name}: should say '{expected}': {stderr}");
        }
    }
    let mut dynamic = unsupported;
    dynamic["analysis"] = json!({"type": "dynamic", "time_step": 0.01, "end_time": 0.05});
    let (code, stderr) = run_file(&write_case("dynamic_unsupported", &dynamic));
    println!("dynamic without supports: exit {code} {stderr}");
    assert_eq!(code, 0, "a dynamic case without supports runs: {stderr}");
}

/// Issue 31: `--threads 5000` spent 22 s creating threads before "Resource temporarily
/// unavailable"; more than 4 threads per available core (and 0) are refused at once, exit 2.
#[test]
fn thread_counts_beyond_the_machine_are_refused() {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    for threads in ["5000".to_string(), (4 * cores + 1).to_string(), "0".to_string()] {
        let started = std::time::Instant::now();
        let out = loam()
            .args(["run", "cases/cantilever_fem.json", "--quiet", "--threads", &threads, "--out"])
            .arg(temp_dir("threads").join("out"))
            .current_dir(root())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
        let seconds = started.elapsed().as_secs_f64();
        println!("--threads {threads}: exit {:?} in {seconds:.2} s: {stderr}", out.status.code());
        assert_eq!(out.status.code(), Some(2));
        assert_eq!(stderr.lines().count(), 1);
        assert!(stderr.starts_with("error: --threads") && stderr.contains(&format!("got {threads}")), "{stderr}");
        assert!(seconds < 5.0, "refused before anything is built");
    }
    let out = loam()
        .args(["run", "cases/cantilever_fem.json", "--quiet", "--threads", &(4 * cores).to_string(), "--out"])
        .arg(temp_dir("threads_ok").join("out"))
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "4 threads per core run: {}", String::from_utf8_lossy(&out.stderr));
}

/// Issue 31 item 5: a step that does not converge names where its residual is largest: the
/// domain (uncoupled) or the block of the monolithic system (coupled), the node and its
/// coordinates. A static MPM cantilever under 10 g with 4 Newton iterations and no step cut,
/// and the coupled split beam under 10 g with 3.
#[test]
fn newton_failure_names_the_node_with_the_largest_residual() {
    use serde_json::json;
    let mpm = bundled("cantilever_mpm", |j| {
        j["gravity"]["acceleration"] = json!([0.0, -98.1]);
        j["analysis"]["max_step_cuts"] = json!(0);
        j["solver"]["max_iterations"] = json!(4);
    });
    let coupled = bundled("coupled_beam_split", |j| {
        j["gravity"]["acceleration"] = json!([0.0, -98.1]);
        j["analysis"]["max_step_cuts"] = json!(0);
        j["solver"]["max_iterations"] = json!(3);
    });
    for (name, case, owner) in [("mpm", mpm, "largest in domain 'beam': node "), ("coupled", coupled, " block: node ")]
    {
        let (code, stderr) = run_file(&write_case(&format!("newton_{name}"), &case));
        println!("{name}: exit {code}: {stderr}");
        assert_eq!(code, 1);
        assert!(stderr.contains("Newton did not converge in") && stderr.contains(owner), "{stderr}");
        // "node 835 at (6.875, 0), 2.42e3 N": coordinates inside the grid and a force
        let at = stderr.split(owner).nth(1).unwrap();
        let coords: Vec<f64> = at
            .split(" at (")
            .nth(1)
            .unwrap()
            .split(')')
            .next()
            .unwrap()
            .split(", ")
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(coords.len(), 2, "{stderr}");
        assert!(coords[0] >= 0.0 && coords[0] <= 8.5 && coords[1] >= -1.5 && coords[1] <= 1.5, "{coords:?}");
        assert!(
            at.split("), ").nth(1).unwrap().starts_with(|c: char| c.is_ascii_digit()) && at.contains(" N)"),
            "{stderr}"
        );
    }
}

/// Issue 31: a second SIGINT, during a step that takes long, ends the run at once (exit 130)
/// but no longer leaves `summary.json` at `"status": "running"`: it says `interrupted`, the
/// step in progress abandoned. One static step of a fine FEM cantilever (about 90 000
/// DOFs) takes seconds; both signals arrive during it.
#[test]
fn second_interrupt_still_writes_the_summary() {
    use serde_json::json;
    let case = bundled("cantilever_fem", |j| {
        j["domains"][0]["mesh"]["rectangle"]["cells"] = json!([560, 80]);
    });
    let path = write_case("second_sigint", &case);
    let out_dir = path.with_file_name("out");
    let child = loam()
        .arg("run")
        .arg(&path)
        .arg("--quiet")
        .arg("--threads")
        .arg("1")
        .arg("--out")
        .arg(&out_dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let summary = out_dir.join("summary.json");
    let waited = std::time::Instant::now();
    while !std::fs::read_to_string(&summary).is_ok_and(|t| t.contains("\"running\"")) {
        assert!(waited.elapsed().as_secs() < 120, "the run did not start");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    for _ in 0..2 {
        assert!(Command::new("kill").arg("-INT").arg(child.id().to_string()).status().unwrap().success());
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    println!("exit {:?}: {stderr}\nsummary: status {} end {}", out.status.code(), written["status"], written["end"]);
    assert_eq!(out.status.code(), Some(130));
    assert!(stderr.contains("interrupted again"), "{stderr}");
    assert_eq!(written["status"], "interrupted");
    let reason = written["end"]["reason"].as_str().unwrap();
    assert!(reason.contains("abandoned") && written["end"]["time"] == 0.0, "{reason}");
}

/// A smooth basis where it cannot act: each refused with exit 2 and one line naming the key
/// (issue 23's acceptance: `"basis": "bspline2"` on a tri grid).
#[test]
fn smooth_basis_where_it_cannot_act_is_refused_naming_the_key() {
    use serde_json::json;
    let check = |name: &str, case: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(root().join("cases").join(case)).unwrap()).unwrap();
        edit(&mut json);
        check_file(&write_case(name, &json))
    };
    expect_bad(
        "bspline2 on tri3",
        check("basis-tri", "collapse_bui2008_tri.json", &|j| j["domains"][0]["grid"]["basis"] = json!("bspline2")),
        &["domains[0].grid.basis", "quad4"],
    );
    expect_bad(
        "unknown basis",
        check("basis-name", "cantilever_mpm.json", &|j| j["domains"][0]["grid"]["basis"] = json!("cubic")),
        &["domains[0].grid.basis", "cubic"],
    );
    // coupled grids take the smooth bases: a structure on the grid's edge, and one inside it
    // (the removed nodes' functions folded into their neighbours)
    for (name, case, basis) in
        [("basis-edge", "coupled_beam_split.json", "bspline2"), ("basis-holed", "coupled_collapse_rubber.json", "gimp")]
    {
        let (code, msg) = check(name, case, &|j| {
            let k = j["domains"].as_array().unwrap().iter().position(|d| d["type"] == "mpm").unwrap();
            j["domains"][k]["grid"]["basis"] = json!(basis);
        });
        assert_eq!(code, 0, "{case} on {basis}: {msg}");
    }
    // 3D: a hex8 grid takes the smooth bases; coupled to a structure it is refused (the
    // supports follow structures in 2D only)
    let (code, msg) =
        check("basis-3d", "cantilever_mpm_3d.json", &|j| j["domains"][0]["grid"]["basis"] = json!("gimp"));
    assert_eq!(code, 0, "3D cantilever on gimp: {msg}");
    let coupled_3d = json!({
        "description": "a 3D smooth grid tied to a wall (refused)",
        "formulation": "3d",
        "materials": { "m": { "law": "linear_elastic", "density": 1000.0, "young_modulus": 1.0e6, "poisson_ratio": 0.3 } },
        "domains": [
            { "name": "soil", "type": "mpm", "material": "m",
              "grid": { "origin": [0.0, 0.0, 0.0], "size": [1.0, 1.0, 1.0], "cells": [4, 4, 4], "element": "hex8",
                        "basis": "bspline2" },
              "material_points": { "cells": { "mesh": { "box": { "origin": [0.0, 0.0, 0.0], "size": [1.0, 0.5, 1.0],
                                                                "cells": [4, 2, 4], "element": "hex8" } },
                                             "points_per_cell": 8 } } },
            { "name": "wall", "material": "m",
              "mesh": { "box": { "origin": [1.0, 0.0, 0.0], "size": [0.25, 1.0, 1.0], "cells": [1, 4, 4], "element": "hex8" } } }
        ],
        "interfaces": [ { "name": "face", "soil": "soil", "structure": "wall", "region": "face" } ],
        "regions": { "face": { "x": 1.0 } },
        "analysis": { "type": "static", "time_step": 1.0, "end_time": 1.0 }
    });
    expect_bad(
        "3D smooth grid coupled to a structure",
        check_file(&write_case("basis-3d-coupled", &coupled_3d)),
        &["interfaces[0].soil", "3D grid on the smooth basis", "linear"],
    );
    expect_bad(
        "filled_cells on a smooth grid",
        check("basis-filled", "cantilever_mpm.json", &|j| {
            j["domains"][0]["grid"]["basis"] = json!("gimp");
            j["domains"][0]["quadrature"] = json!("filled_cells");
        }),
        &["domains[0].quadrature"],
    );
}

/// Issue 28: `loam --version` names the version and the build's cargo features.
#[test]
fn version_names_the_features() {
    let out = loam().arg("--version").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout).trim().to_string();
    println!("{text}");
    assert!(text.starts_with(&format!("loam {} (features: ", env!("CARGO_PKG_VERSION"))), "{text}");
    assert!(text.ends_with(')'), "{text}");
}

/// Issue 28: `loam run --trace-newton` prints every Newton iteration on stderr (the former
/// environment variable LOAM_NEWTON_TRACE, now a flag); without it nothing is printed.
#[test]
fn trace_newton_prints_every_iteration() {
    let case = write_case("trace", &bundled("cantilever_fem", |_| {}));
    let run = |trace: bool| {
        let mut cmd = loam();
        cmd.arg("run").arg(&case).arg("--quiet").arg("--out").arg(case.with_file_name("out"));
        if trace {
            cmd.arg("--trace-newton");
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let traced = run(true);
    let lines: Vec<&str> = traced.lines().filter(|l| l.starts_with("newton t=")).collect();
    println!("{} Newton lines, first: {}", lines.len(), lines.first().copied().unwrap_or(""));
    assert!(lines.len() >= 2, "{traced}");
    assert!(lines[0].contains(" it=0 ") && lines[0].contains("|r|=") && lines[0].contains(" peak="), "{}", lines[0]);
    assert!(lines[1].contains(" dpeak="), "{}", lines[1]);
    assert!(!run(false).contains("newton t="));
    let help = loam().args(["run", "--help"]).output().unwrap();
    assert!(String::from_utf8_lossy(&help.stdout).contains("--trace-newton"));
}

/// Issue 28: the solver settings that were environment variables (LOAM_CHOLESKY,
/// LOAM_MPM_PATTERN_RINGS) are case keys: accepted, and a bad value refused in one line
/// naming its JSON path and what is expected.
#[test]
fn former_environment_knobs_are_case_keys() {
    use serde_json::json;
    let mpm = bundled("cantilever_mpm", |j| {
        j["solver"]["cholesky_factorisation"] = json!("simplicial");
        j["solver"]["mpm_pattern_rings"] = json!(0);
    });
    let (code, msg) = check_file(&write_case("knobs-ok", &mpm));
    assert_eq!(code, 0, "{msg}");
    expect_bad(
        "unknown factorisation",
        check_edited("knobs-chol", |j| j["solver"]["cholesky_factorisation"] = json!("multifrontal")),
        &["solver.cholesky_factorisation", "supernodal", "simplicial"],
    );
    expect_bad(
        "too many rings",
        check_edited("knobs-rings", |j| j["solver"]["mpm_pattern_rings"] = json!(1000)),
        &["solver.mpm_pattern_rings", "at most 100"],
    );
    expect_bad(
        "negative rings",
        check_edited("knobs-rings-neg", |j| j["solver"]["mpm_pattern_rings"] = json!(-1)),
        &["solver.mpm_pattern_rings"],
    );
    // the same MPM run with the pattern rebuilt at every change gives the same answer
    let out = |rings: u64| {
        let case = write_case(
            &format!("knobs-run-{rings}"),
            &bundled("cantilever_mpm", |j| j["solver"]["mpm_pattern_rings"] = json!(rings)),
        );
        let (code, msg) = run_file(&case);
        assert_eq!(code, 0, "{msg}");
        last_monitor(&case.with_file_name("out").join("monitors.csv"), "tip_uy")
    };
    let (a, b) = (out(0), out(1));
    assert!((a - b).abs() <= 1e-9 * a.abs(), "{a} vs {b}");
}

/// Issue 28 item C: the ten commonest mistakes in a case file (edits of the bundled
/// cantilevers) are refused in one line (exit 2) that names the JSON path, says what is
/// expected and gives an example value or the name that was probably meant.
#[test]
fn common_mistakes_say_what_is_expected_with_an_example() {
    use serde_json::json;
    let mpm = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        check_file(&write_case(name, &bundled("cantilever_mpm", |j| edit(j))))
    };
    // 1. wrong array length: a grid's cells (checked by the model builder) and a mesh's
    //    cells (a fixed-size array, refused by the parser)
    expect_bad(
        "grid cells of the wrong length",
        mpm("mistake-grid-cells", &|j| j["domains"][0]["grid"]["cells"] = json!([64])),
        &[
            "domains[0].grid.cells: expected 2 entries",
            "whole numbers of cells per direction",
            "e.g. [64, 24]",
            "got [64]",
        ],
    );
    expect_bad(
        "mesh cells of the wrong length",
        check_edited("mistake-mesh-cells", |j| j["domains"][0]["mesh"]["rectangle"]["cells"] = json!([56])),
        &["domains[0].mesh.rectangle.cells:", "expected an array of length 2", "e.g. [64, 24]", "got [56]"],
    );
    // 2. unknown law name
    expect_bad(
        "unknown law",
        check_edited("mistake-law", |j| j["materials"]["beam"]["law"] = json!("neohookean")),
        &["materials.beam.law:", "unknown value `neohookean`", "did you mean \"neo_hookean\"?", "expected one of"],
    );
    // 3. misspelt key
    expect_bad(
        "misspelt key",
        check_edited("mistake-key", |j| {
            let e = j["materials"]["beam"].as_object_mut().unwrap().remove("young_modulus").unwrap();
            j["materials"]["beam"]["youngs_modulus"] = e;
        }),
        &["materials.beam.youngs_modulus:", "did you mean \"young_modulus\"?", "expected one of `density`"],
    );
    // 4. missing material property
    expect_bad(
        "missing property",
        check_edited("mistake-missing", |j| {
            j["materials"]["beam"].as_object_mut().unwrap().remove("poisson_ratio");
        }),
        &["materials.beam:", "missing field `poisson_ratio`", "e.g. \"poisson_ratio\": 0.3"],
    );
    // 5. a region that selects nothing
    expect_bad(
        "empty region",
        mpm("mistake-region", &|j| j["regions"]["clamp"] = json!({"x": -1.0})),
        &["regions.clamp:", "selects no node", "x in [0, 8], y in [-1.5, 1.5]", "e.g. {\"x\": 0}"],
    );
    // 6. wrong element name
    expect_bad(
        "wrong element",
        mpm("mistake-element", &|j| j["domains"][0]["grid"]["element"] = json!("quad")),
        &["domains[0].grid.element:", "did you mean \"quad4\"?", "expected one of `tri3`, `quad4`"],
    );
    // 7. negative time step
    expect_bad(
        "negative time step",
        check_edited("mistake-dt", |j| j["analysis"]["time_step"] = json!(-1.0)),
        &["analysis.time_step:", "must be > 0", "e.g. 0.01", "got -1"],
    );
    // 8. unknown monitor type
    expect_bad(
        "unknown monitor type",
        check_edited("mistake-monitor", |j| j["monitors"][0]["type"] = json!("displacment")),
        &["monitors[0].type:", "did you mean \"displacement\"?", "expected one of"],
    );
    // 9. a string where a number is expected
    expect_bad(
        "string for a number",
        check_edited("mistake-string", |j| j["materials"]["beam"]["density"] = json!("1000")),
        &["materials.beam.density:", "expected a number", "e.g. 1000 (without the quotes)"],
    );
    // 10. a boundary condition naming an unknown region
    expect_bad(
        "unknown region",
        check_edited("mistake-bc-region", |j| j["boundary_conditions"][0]["region"] = json!("clmap")),
        &["boundary_conditions[0].region:", "no region named 'clmap'", "did you mean \"clamp\"?", "expected one of"],
    );
}
