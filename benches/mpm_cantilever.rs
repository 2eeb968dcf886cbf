//! Time per step of the implicit MPM cantilever (benchmark 1 of `shared/BENCHMARKS.md`), by
//! phase, at several discretisations, with 1 and 2 threads.
//!
//! The beam `7 m × 1 m` (E = 90 MPa, ν = 0, ρ = 1000 kg/m³, Neo-Hookean, plane strain) is
//! clamped at `x = 0` and released under gravity at `t = 0`; Newmark (average
//! acceleration), Δt = 0.01 s. `n` cells through the thickness (`h = 1/n`), 4 material
//! points per cell at the Gauss positions, background grid `[0, 8] × [−1.5, 1.5]` with the
//! same `h`: `28 n²` points (n = 4, 8, 16, 32, 64 → 448, 1 792, 7 168, 28 672, 114 688), the
//! discretisation `shared/kratos/gen_cantilever.py --n N --ppc 4 --mode dynamic` gives Kratos.
//! The case is built as JSON, like `cases/cantilever_mpm_dynamic.json`.
//!
//! For each size and thread count (a local rayon pool; faer sequential) the benchmark runs
//! one warm-up step (consistent initial acceleration, first pattern and symbolic analysis)
//! and then `LOAM_BENCH_STEPS` steps (default 10), and reports per step and per Newton
//! iteration: initialisation phase (point search, sort, shape functions, projection),
//! pattern + symbolic analysis (only in steps whose active-cell set left the pattern),
//! assembly, factorisation + solve, convective phase (back-interpolation and point
//! update), and material-point updates per second (points × steps / wall time).
//!
//! Run: `cargo bench --bench mpm_cantilever` (448, 1 792, 7 168 points), or choose sizes
//! (material points or `nN`) with `LOAM_BENCH_MPM_SIZES=448,28672,n64`; threads with
//! `LOAM_BENCH_THREADS=1,2`; the grid's shape functions with
//! `LOAM_BENCH_BASES=linear,gimp,bspline2` (default linear). `LOAM_BENCH_DIM=3` runs the beam
//! in 3D instead (`7 × 1 × 1 m`, hex8 grid `[0, 8] × [−1.5, 1.5] × [0, 1]`, `n` cells through
//! the depth and the width, 8 points per cell: `56 n³` points; sizes as `nN`). Nothing is
//! asserted about times.

mod common;

use common::{print_table, time_steps, StepTiming};
use loam::case::Case;
use loam::simulation::Simulation;

/// The case JSON for `n` cells through the thickness, `steps` steps of 0.01 s, on the grid
/// basis `basis`, in 2D or (`dim = 3`) 3D.
pub fn case_json(dim: usize, n: usize, steps: usize, basis: &str) -> String {
    let case = case_json_2d(n, steps, basis);
    if dim != 3 {
        return case;
    }
    // the same beam 1 m wide along z, n cells across, 8 points per cell
    use serde_json::json;
    let mut v: serde_json::Value = serde_json::from_str(&case).expect("the 2D case is JSON");
    v["formulation"] = json!("3d");
    v.as_object_mut().expect("an object").remove("thickness");
    let domain = &mut v["domains"][0];
    domain["grid"] = json!({ "origin": [0.0, -1.5, 0.0], "size": [8.0, 3.0, 1.0], "cells": [8 * n, 3 * n, n],
                             "element": "hex8", "basis": basis });
    domain["material_points"]["cells"] = json!({ "mesh": { "box": { "origin": [0.0, 0.0, 0.0], "size": [7.0, 1.0, 1.0],
                                                                   "cells": [7 * n, n, n], "element": "hex8" } },
                                                 "points_per_cell": 8 });
    v["boundary_conditions"][0]["displacement"] = json!([0.0, 0.0, 0.0]);
    v["gravity"]["acceleration"] = json!([0.0, -9.81, 0.0]);
    v["monitors"][0]["point"] = json!([7.0 - 0.25 / n as f64, 0.5, 0.5]);
    v.to_string()
}

/// [`case_json`] in 2D (plane strain).
fn case_json_2d(n: usize, steps: usize, basis: &str) -> String {
    let h = 1.0 / n as f64;
    format!(
        r#"{{
  "description": "mpm_cantilever benchmark: benchmark 1 with MPM, dynamic, n = {n}",
  "formulation": "plane_strain",
  "thickness": 1.0,
  "materials": {{ "beam": {{ "law": "neo_hookean", "density": 1000.0, "young_modulus": 9.0e7, "poisson_ratio": 0.0 }} }},
  "domains": [ {{ "name": "beam", "type": "mpm", "material": "beam",
     "grid": {{ "origin": [0.0, -1.5], "size": [8.0, 3.0], "cells": [{gx}, {gy}], "element": "quad4", "basis": "{basis}" }},
     "material_points": {{ "cells": {{ "mesh": {{ "rectangle": {{ "origin": [0.0, 0.0], "size": [7.0, 1.0], "cells": [{bx}, {n}], "element": "quad4" }} }},
                           "points_per_cell": 4 }} }} }} ],
  "regions": {{ "clamp": {{ "x": 0.0 }} }},
  "boundary_conditions": [ {{ "region": "clamp", "displacement": [0.0, 0.0] }} ],
  "gravity": {{ "acceleration": [0.0, -9.81] }},
  "analysis": {{ "type": "dynamic", "time_step": 0.01, "end_time": {end},
     "scheme": {{ "newmark": {{ "beta": 0.25, "gamma": 0.5 }} }} }},
  "solver": {{ "residual_relative_tolerance": 1e-8, "residual_absolute_tolerance": 1e-6 }},
  "monitors": [ {{ "name": "tip_uy", "type": "material_point_displacement", "point": [{tx}, 0.5], "component": "y" }} ]
}}"#,
        gx = 8 * n,
        gy = 3 * n,
        bx = 7 * n,
        end = 0.01 * (steps + 1) as f64,
        tx = 7.0 - 0.25 * h,
    )
}

fn parse_size(s: &str) -> Option<usize> {
    let s = s.trim().to_ascii_lowercase();
    if let Some(n) = s.strip_prefix('n') {
        return n.parse().ok();
    }
    let points: f64 = s.parse().ok()?;
    Some(((points / 28.0).sqrt()).round() as usize)
}

fn run(dim: usize, n: usize, threads: usize, steps: usize, basis: &str) -> StepTiming {
    let case = Case::parse(&case_json(dim, n, steps, basis)).expect("benchmark case parses");
    let mut sim = Simulation::new(case).expect("benchmark case builds");
    let label = format!(
        "{}n = {n}{}",
        if dim == 3 { "3D " } else { "" },
        if basis == "linear" { String::new() } else { format!(" {basis}") }
    );
    let points = if dim == 3 { 56 * n * n * n } else { 28 * n * n };
    let mut row = time_steps(&mut sim, &label, points, threads, 1, steps);
    row.extra.push(format!("{:.5}", sim.monitor_values()[0]));
    row
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let sizes: Vec<usize> = std::env::var("LOAM_BENCH_MPM_SIZES")
        .ok()
        .map(|v| v.split(',').filter_map(parse_size).collect())
        .unwrap_or_else(|| vec![4, 8, 16]);
    let threads: Vec<usize> = std::env::var("LOAM_BENCH_THREADS")
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1, 2]);
    let steps: usize = std::env::var("LOAM_BENCH_STEPS").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    let bases: Vec<String> = std::env::var("LOAM_BENCH_BASES")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_string()).collect())
        .unwrap_or_else(|| vec!["linear".into()]);
    let dim: usize = std::env::var("LOAM_BENCH_DIM").ok().and_then(|v| v.parse().ok()).unwrap_or(2);
    let mut rows = Vec::new();
    for &n in &sizes {
        let points = if dim == 3 { 56 * n * n * n } else { 28 * n * n };
        eprintln!("n = {n} (h = {:.5} m), {points} material points", 1.0 / n as f64);
        for basis in &bases {
            for &th in &threads {
                rows.push(run(dim, n, th, steps, basis));
            }
        }
    }
    print_table(&rows, &["tip uy (m)"]);
}
