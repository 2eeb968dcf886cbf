//! Issue 17: `loam plot` and the run report `summary.json`, on a small FEM and a small MPM
//! run (the static cantilevers, one step each): pictures of the stated size whose pixels
//! show each body where it is, in the colour-map colour of its field; missing fields and
//! directories refused with one line and exit code 2.

mod common;

use common::cli::{loam, root, temp_dir};
use std::path::{Path, PathBuf};
use std::process::Output;

use loam::plot::colormap::Colormap;
use loam::plot::frame::{fit_view, pixel_of};
use loam::plot::results::{read_pvd, read_vtu, Cells};

/// Runs a bundled case into a fresh directory of its own for test `tag`.
fn run_case(case: &str, tag: &str) -> PathBuf {
    let out = temp_dir(&format!("{case}-{tag}"));
    let status = loam()
        .args(["run", &format!("cases/{case}.json"), "--quiet", "--out"])
        .arg(&out)
        .current_dir(root())
        .status()
        .unwrap();
    assert!(status.success(), "loam run {case}");
    out
}

fn plot(dir: &Path, args: &[&str]) -> Output {
    loam().arg("plot").arg(dir).args(args).output().unwrap()
}

fn pixel(png: &Path, (x, y): (i32, i32)) -> [u8; 3] {
    let img = image::open(png).unwrap().to_rgb8();
    img.get_pixel(x as u32, y as u32).0
}

/// The file `loam plot` reports for the frame at the last output.
fn frame_file(stdout: &[u8]) -> PathBuf {
    let text = String::from_utf8_lossy(stdout);
    let line = text.lines().find(|l| l.contains(".png (t =")).unwrap_or_else(|| panic!("no frame in: {text}"));
    PathBuf::from(line.trim_start_matches("loam: wrote ").split(" (t =").next().unwrap())
}

/// FEM: the deformed cantilever coloured by von Mises stress; the pixel at the deformed
/// centre of a cell near the clamp and of one near the tip has the colour map's colour of
/// that cell's value; above the beam the picture is background.
#[test]
fn fem_frame_shows_the_deformed_mesh_in_its_colours() {
    let dir = run_case("cantilever_fem", "frame");
    let series = read_pvd(&dir.join("beam.pvd")).unwrap().expect("a series");
    let piece = read_vtu(&series.steps.last().unwrap().1).unwrap();
    let Cells::Mesh { connectivity, .. } = &piece.cells else { panic!("a mesh") };
    let u = &piece.field("displacement").unwrap().0.values;
    let vm = &piece.field("von_mises_stress").unwrap().0.values;
    let vmax = vm.iter().fold(0.0, |m: f64, &v| m.max(v));
    let (size, view) = ((640u32, 400u32), [-0.5, 7.5, -1.0, 1.5]);
    let range = format!("0,{vmax}");
    let out = plot(
        &dir,
        &["--field", "von_mises_stress", "--last", "--size", "640x400", "--range", &range, "--view", "-0.5,7.5,-1,1.5"],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let png = frame_file(&out.stdout);
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), size);
    let view = fit_view(view, 0.0, size).unwrap();
    // cells 0 (at the clamp, bottom row) and 55 (at the tip) of the 56 × 8 mesh
    for cell in [0usize, 55] {
        let nodes = &connectivity[4 * cell..4 * cell + 4];
        let centre = |k: usize| nodes.iter().map(|&a| piece.points[a][k] + u[3 * a + k]).sum::<f64>() / 4.0;
        let (x, y) = (centre(0), centre(1));
        let expected = Colormap::Viridis.at(vm[cell] / vmax);
        let at = pixel_of(size, &view, x, y).unwrap();
        println!("cell {cell}: centre ({x:.4}, {y:.4}) m, σ_vM {:.4e} Pa → pixel {at:?}", vm[cell]);
        assert_eq!(pixel(&png, at), expected, "cell {cell}");
    }
    // the tip has moved down by 0.39 m: where it started there is no beam now
    let empty = pixel(&png, pixel_of(size, &view, 6.95, 0.9).unwrap());
    assert!(empty.iter().all(|&c| c >= 225), "{empty:?}");
}

/// MPM: the material points as squares coloured by `displacement:y`; the pixel at a point
/// in the middle of the beam has its colour; monitor plots and the GIF are written.
#[test]
fn mpm_frame_shows_the_points_in_their_colours() {
    let dir = run_case("cantilever_mpm", "frame");
    let size = (1000u32, 500u32);
    let view = [-0.2, 7.4, -0.8, 1.2];
    let out = plot(
        &dir,
        &[
            "--field",
            "displacement:y",
            "--last",
            "--size",
            "1000x500",
            "--range",
            "-0.4,0",
            "--view",
            "-0.2,7.4,-0.8,1.2",
            "--gif",
        ],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let png = frame_file(&out.stdout);
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), size);

    let series = read_pvd(&dir.join("beam.pvd")).unwrap().expect("a series");
    let piece = read_vtu(&series.steps.last().unwrap().1).unwrap();
    let u = &piece.field("displacement").unwrap().0.values;
    let view = fit_view(view, 0.0, size).unwrap();
    // the points nearest to (3.5, 0.5) and to (6.9, 0.5) at the start
    for target in [[3.5, 0.5], [6.9, 0.5]] {
        let p = (0..piece.points.len())
            .min_by(|&a, &b| {
                let d = |k: usize| {
                    let x = piece.points[k];
                    (x[0] - u[3 * k] - target[0]).hypot(x[1] - u[3 * k + 1] - target[1])
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let x = piece.points[p];
        let expected = Colormap::Viridis.at((u[3 * p + 1] + 0.4) / 0.4);
        let at = pixel_of(size, &view, x[0], x[1]).unwrap();
        println!("point {p} at ({:.4}, {:.4}) m, u_y {:.5} m → pixel {at:?}", x[0], x[1], u[3 * p + 1]);
        assert_eq!(pixel(&png, at), expected, "point {p}");
    }
    let plots = dir.join("plots");
    assert!(
        plots.join("monitors_length.png").is_file(),
        "{:?}",
        std::fs::read_dir(&plots).unwrap().collect::<Vec<_>>()
    );
    let gif = std::fs::read(plots.join("displacement_y.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
}

/// Bad input never panics: a missing field names the fields that exist, a missing
/// directory names itself; one line each, exit code 2.
#[test]
fn missing_field_and_directory_are_one_line_errors() {
    let dir = run_case("cantilever_fem", "errors");
    let out = plot(&dir, &["--field", "no_such_field", "--last"]);
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{err}");
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.starts_with("error: no field `no_such_field`"), "{err}");
    for name in ["von_mises_stress", "cauchy_stress:xx|yy|zz|xy|yz|xz", "displacement:x|y|z|magnitude"] {
        assert!(err.contains(name), "{name} missing from: {err}");
    }
    let out = plot(&dir, &["--field", "cauchy_stress"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("give a component, e.g. `cauchy_stress:yy`"));
    let out = plot(&dir, &["--x", "no_monitor"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("monitors: tip_uy"));
    let missing = dir.join("no/such/dir");
    let out = plot(&missing, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(err.trim_end(), format!("error: {}: no such directory", missing.display()));
}

/// `summary.json`: what a script reads instead of the terminal.
#[test]
fn run_writes_its_report() {
    let dir = run_case("cantilever_fem", "summary");
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(s["case"], "cantilever_fem");
    assert_eq!(s["status"], "finished");
    assert_eq!(s["formulation"], "plane_strain");
    assert_eq!(s["steps"], 1);
    assert!(s["newton"]["iterations"].as_u64().unwrap() >= 2);
    assert!(s["threads"].as_u64().unwrap() >= 1);
    let assembly = s["wall_time"]["assembly"].as_f64().unwrap();
    assert!(s["wall_time"]["total"].as_f64().unwrap() >= assembly);
    // the kernels of the one domain, part of the assembly
    let kernels = s["wall_time"]["kernels_by_domain"].as_object().expect("kernels_by_domain");
    assert_eq!(kernels.keys().collect::<Vec<_>>(), ["beam"]);
    let beam = kernels["beam"].as_f64().unwrap();
    assert!(beam > 0.0 && beam <= assembly, "kernels {beam} s of the assembly's {assembly} s");
    // memory: the FEM cantilever's symmetric tangent is factorised by Cholesky, whose factor
    // holds at least the matrix's lower triangle
    let (nnz, factor) =
        (s["memory"]["matrix_nonzeros"].as_u64().unwrap(), s["memory"]["factor_entries"].as_u64().unwrap());
    assert!(nnz > 0 && 2 * factor >= nnz, "matrix {nnz}, factor {factor}");
    if cfg!(target_os = "linux") {
        assert!(s["memory"]["peak_rss_mb"].as_f64().unwrap() > 1.0);
    }
    let tip = s["monitors"]["tip_uy"].as_f64().unwrap();
    assert!((tip + 0.39256).abs() / 0.39256 < 0.03, "{tip}");
    assert_eq!(s["monitor_units"]["tip_uy"], "m");
    assert!(s["end"]["reason"].as_str().unwrap().starts_with("reached the end time"));
}

/// A run that stops on a step that fails still writes its report, saying why, with the
/// results so far.
#[test]
fn failed_run_writes_its_report() {
    let text = std::fs::read_to_string(root().join("cases/cantilever_fem.json")).unwrap();
    let mut case: serde_json::Value = serde_json::from_str(&text).unwrap();
    // one Newton iteration cannot converge the large-deflection step, and no cut is allowed
    case["solver"]["max_iterations"] = 1.into();
    case["analysis"]["max_step_cuts"] = 0.into();
    let dir = temp_dir("failed");
    let path = dir.join("failing.json");
    std::fs::write(&path, serde_json::to_string_pretty(&case).unwrap()).unwrap();
    let out = dir.join("out");
    let status = loam().arg("run").arg(&path).args(["--quiet", "--out"]).arg(&out).status().unwrap();
    assert_eq!(status.code(), Some(1));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    println!("{}", s["end"]);
    assert_eq!(s["status"], "failed");
    assert_eq!(s["case"], "failing");
    assert_eq!(s["steps"], 0);
    assert!(s["end"]["reason"].as_str().unwrap().starts_with("stopped at step 1"), "{}", s["end"]);
    assert_eq!(s["end"]["time"], 0.0);
    assert!(out.join("monitors.csv").is_file() && out.join("beam.pvd").is_file());
}

/// 3D: an MPM cantilever on a hex8 grid projected on the x–z plane, seen from −y: at the
/// pixel of a point of the front layer (smallest y) the picture has that point's colour of
/// `displacement:x`, which bending makes differ from the layers behind it.
#[test]
fn three_d_points_are_projected_nearest_in_front() {
    let case = r#"{
        "description": "3D MPM cantilever", "formulation": "3d",
        "materials": {"beam": {"law": "neo_hookean", "density": 1000, "young_modulus": 9.0e7, "poisson_ratio": 0.0}},
        "domains": [{"name": "beam", "type": "mpm", "material": "beam",
            "grid": {"origin": [0, -1, 0], "size": [8, 2.5, 1], "cells": [16, 5, 2], "element": "hex8"},
            "material_points": {"cells": {"mesh": {"box": {"origin": [0, 0, 0], "size": [7, 1, 1], "cells": [14, 2, 2], "element": "hex8"}},
                                          "points_per_cell": 8}}}],
        "regions": {"clamp": {"x": 0.0}},
        "boundary_conditions": [{"region": "clamp", "displacement": [0, 0, 0]}],
        "gravity": {"acceleration": [0, -9.81, 0]},
        "analysis": {"type": "static", "time_step": 1, "end_time": 1},
        "monitors": [{"name": "tip_uy", "type": "material_point_displacement", "point": [7, 0.5, 0.5], "component": "y"}]
    }"#;
    let dir = temp_dir("3d");
    std::fs::write(dir.join("beam3d.json"), case).unwrap();
    let out = dir.join("out");
    let status = loam().arg("run").arg(dir.join("beam3d.json")).args(["--quiet", "--out"]).arg(&out).status().unwrap();
    assert!(status.success());
    let size = (800u32, 500u32);
    let view = [-0.2, 7.2, -0.5, 1.5];
    let o = plot(
        &out,
        &[
            "--field",
            "displacement:x",
            "--last",
            "--plane",
            "xz",
            "--range",
            "-0.06,0.06",
            "--view",
            "-0.2,7.2,-0.5,1.5",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = frame_file(&o.stdout);
    let piece = read_vtu(&read_pvd(&out.join("beam.pvd")).unwrap().expect("a series").steps.last().unwrap().1).unwrap();
    let u = &piece.field("displacement").unwrap().0.values;
    // the front point of the column of points around x = 3.6, z = 0.6
    let p = (0..piece.points.len())
        .filter(|&k| (piece.points[k][0] - 3.6).abs() < 0.13 && (piece.points[k][2] - 0.6).abs() < 0.13)
        .min_by(|&a, &b| piece.points[a][1].total_cmp(&piece.points[b][1]))
        .expect("a point there");
    let x = piece.points[p];
    let at = pixel_of(size, &fit_view(view, 0.0, size).unwrap(), x[0], x[2]).unwrap();
    let back = (0..piece.points.len())
        .filter(|&k| (piece.points[k][0] - 3.6).abs() < 0.13 && (piece.points[k][2] - 0.6).abs() < 0.13)
        .max_by(|&a, &b| piece.points[a][1].total_cmp(&piece.points[b][1]))
        .unwrap();
    println!(
        "front point {p} at {x:?}, u_x {:.5} m (back point {back}: {:.5} m) → pixel {at:?}",
        u[3 * p],
        u[3 * back]
    );
    let color = |ux: f64| Colormap::Viridis.at((ux + 0.06) / 0.12);
    assert_ne!(color(u[3 * p]), color(u[3 * back]));
    assert_eq!(pixel(&png, at), color(u[3 * p]));
}
