//! The `loam` command line: acceptance runs and bad input (one-line message naming the
//! JSON path, exit code 2, never a panic).

use std::path::{Path, PathBuf};
use std::process::Command;

fn loam() -> Command {
    Command::new(env!("CARGO_BIN_EXE_loam"))
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("loam-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

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
    expect_bad("unknown top key", check_edited("unknown-top", |j| j["gravityy"] = json!(1)), &["gravityy"]);
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
    let text = std::fs::read_to_string(root().join("cases/cantilever_fem.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["gravity"]["amplitude"] = serde_json::json!([[0, 0], [1, 1], [2, 2000]]);
    json["analysis"] = serde_json::json!({"type": "static", "time_step": 0.5, "end_time": 2.0, "max_step_cuts": 2});
    json["solver"]["max_iterations"] = serde_json::json!(8);
    let dir = temp_dir("failing");
    let path = dir.join("case.json");
    std::fs::write(&path, json.to_string()).unwrap();
    let out = loam().arg("run").arg(&path).arg("--quiet").arg("--out").arg(dir.join("out")).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("exit {:?}: {stderr}", out.status.code());
    assert_eq!(out.status.code(), Some(1));
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
    let text = std::fs::read_to_string(root().join("cases/cantilever_mpm.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["gravity"] =
        serde_json::json!({"acceleration": [0.0, -100.0], "amplitude": [[0.0, 0.0], [0.25, 0.25], [0.5, 100.0]]});
    json["analysis"] = serde_json::json!({"type": "static", "time_step": 0.5, "end_time": 0.5, "max_step_cuts": 4});
    json["solver"]["max_iterations"] = serde_json::json!(4);
    let dir = temp_dir("substeps");
    let path = dir.join("case.json");
    std::fs::write(&path, json.to_string()).unwrap();
    let out = loam().arg("run").arg(&path).arg("--quiet").arg("--out").arg(dir.join("out")).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("exit {:?}: {stderr}", out.status.code());
    assert_eq!(out.status.code(), Some(1));
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
