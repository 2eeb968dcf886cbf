//! Cost of a step of the mixed u–p formulation (issue 15, item 7) against the displacement
//! formulation on the same discretisation, and the linear solvers of the saddle-point system.
//!
//! - **footing**: benchmark 11 in MPM (`footing_undrained_mpm_up.json` against
//!   `footing_undrained_mpm_u.json`), steps 10 to 10 + `LOAM_BENCH_STEPS` of the 50 (the soil
//!   under the footing yielding), after the first 10 steps untimed;
//! - **Bui column**: `collapse_bui2008_quad_up.json` against `collapse_bui2008_quad_mc.json`,
//!   fixed steps of 1 ms from t = 0.1 s (the column collapsing);
//! - **solvers**: the u–p footing and Cook's membrane (Kratos' mesh) with `lu`, `ldlt`
//!   (signed regularisation), `lblt` (Bunch–Kaufman, what `auto` takes on a symmetric saddle
//!   point).
//!
//! Prints the per-step phase split (Markdown tables) with the entries of the last factor, and
//! the ratio of the u–p step to the displacement step. Threads from `LOAM_BENCH_THREADS`
//! (default 1), steps from `LOAM_BENCH_STEPS` (default 10), parts from `LOAM_BENCH_PARTS`
//! (comma-separated among `footing`, `bui`, `solvers`; default all). Run: `cargo bench --bench
//! mixed_up`. Nothing is asserted about times.

mod common;

use std::path::Path;

use common::{print_table, time_steps, StepTiming};
use loam::case::Case;
use loam::simulation::Simulation;
use serde_json::{json, Value};

fn case_json(name: &str) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(name);
    serde_json::from_str(&std::fs::read_to_string(path).expect("bundled case")).expect("JSON")
}

fn build(mut v: Value) -> Simulation {
    v["output"] = json!({ "vtk": false });
    let mut case = Case::parse(&v.to_string()).expect("case parses");
    case.directory = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    Simulation::new(case).expect("case builds")
}

fn points(sim: &Simulation) -> usize {
    sim.model.domains.iter().map(|d| d.point_extents().len()).sum()
}

/// Steps `sim` untimed to `start`, then times `steps` steps.
fn timed(mut sim: Simulation, label: &str, start: f64, threads: usize, steps: usize) -> StepTiming {
    sim.advance_to(start).expect("steps converge");
    let n = points(&sim);
    let mut row = time_steps(&mut sim, label, n, threads, 0, steps);
    let s = sim.model.solver_timings();
    let entries = sim.model.factor_entries().map_or("—".to_string(), |n| format!("{n}"));
    row.extra = vec![
        format!("{}", sim.model.num_equations()),
        format!("{} / {}", s.saddle_point_lu, s.factorisations),
        entries,
    ];
    row
}

fn ratio(what: &str, up: &StepTiming, u: &StepTiming) {
    let per_step = |r: &StepTiming| r.wall / r.steps.max(1) as f64;
    println!(
        "{what}: u–p {:.1} ms per step, displacement {:.1} ms per step: ratio {:.2}",
        1e3 * per_step(up),
        1e3 * per_step(u),
        per_step(up) / per_step(u)
    );
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let threads: usize = std::env::var("LOAM_BENCH_THREADS").ok().and_then(|v| v.parse().ok()).unwrap_or(1);
    let steps: usize = std::env::var("LOAM_BENCH_STEPS").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    let headers = ["equations", "LU / factorisations", "factor entries (L, or L and U)"];
    let parts = std::env::var("LOAM_BENCH_PARTS").unwrap_or_else(|_| "footing,bui,solvers".into());
    let run = |part: &str| parts.split(',').any(|p| p.trim() == part);

    // benchmark 11: the footing
    if run("footing") {
        footing(threads, steps, &headers);
    }
    if run("bui") {
        bui(threads, steps, &headers);
    }
    if run("solvers") {
        solvers(threads, steps, &headers);
    }
}

/// Benchmark 11, u–p against displacement.
fn footing(threads: usize, steps: usize, headers: &[&str]) {
    let start = 0.2;
    let footing = vec![
        timed(
            build(case_json("footing_undrained_mpm_up.json")),
            "footing, u–p (MPM soil + FEM footing)",
            start,
            threads,
            steps,
        ),
        timed(build(case_json("footing_undrained_mpm_u.json")), "footing, displacement", start, threads, steps),
    ];
    print_table(&footing, headers);
    ratio("footing", &footing[0], &footing[1]);
}

/// Benchmark 8, the Bui column: fixed steps of 1 ms from 0.1 s, u–p against displacement.
fn bui(threads: usize, steps: usize, headers: &[&str]) {
    let (dt, start) = (1e-3, 0.1);
    let column = |name: &str| {
        let mut v = case_json(name);
        let a = v["analysis"].as_object_mut().expect("analysis");
        a.remove("adaptive");
        a.remove("stop_at_rest");
        a.insert("time_step".into(), json!(dt));
        a.insert("end_time".into(), json!(start + (steps + 2) as f64 * dt));
        build(v)
    };
    let bui = vec![
        timed(column("collapse_bui2008_quad_up.json"), "Bui column, u–p", start, threads, steps),
        timed(column("collapse_bui2008_quad_mc.json"), "Bui column, displacement", start, threads, steps),
    ];
    print_table(&bui, headers);
    ratio("Bui column", &bui[0], &bui[1]);
}

/// The linear solvers of the saddle point.
fn solvers(threads: usize, steps: usize, headers: &[&str]) {
    let mut solvers = Vec::new();
    for solver in ["lu", "ldlt", "lblt"] {
        let mut v = case_json("footing_undrained_mpm_up.json");
        v["solver"] = json!({ "linear_solver": solver });
        solvers.push(timed(build(v), &format!("footing u–p, {solver}"), 0.2, threads, steps));
    }
    for solver in ["lu", "ldlt", "lblt"] {
        let mut v = case_json("cooks_membrane_up.json");
        v["solver"]["linear_solver"] = json!(solver);
        solvers.push(timed(build(v), &format!("Cook's membrane (Kratos' mesh), {solver}"), 0.0, threads, 1));
    }
    print_table(&solvers, headers);
}
