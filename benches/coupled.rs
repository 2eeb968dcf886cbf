//! Cost of a coupled MPM–FEM step (issue 13, item 8): a step of soil and structure in one
//! Newton system against the MPM step of the same soil on the same grid plus the FEM step of
//! the structure alone, with the Newton iterations of each.
//!
//! - **collapse**: the Bui column onto the rubber plate (`cases/coupled_collapse_rubber.json`)
//!   against the same column without the plate (`collapse_bui2008_quad_mc.json`, the same grid
//!   without the plate's 24 cells) and the plate alone (FEM, clamped, under gravity); fixed
//!   steps of 1 ms from t = 0.1 s (the flow reaches the plate at about 0.11 s: the steps
//!   time the impact), after one warm-up step.
//! - **beam**: the split beam of benchmark 12, dynamic (`coupled_beam_split_dynamic.json`)
//!   against its MPM half clamped at x = 4 and its FEM half clamped at x = 0, each alone.
//!
//! - **contact** (issue 25, item 6): the rubber plate met by Coulomb contact, rotated 10°
//!   against the unmoved grid (`cases/coupled_collapse_rubber_rotated.json`), against the
//!   shared-node plate of the first row, over the same fixed steps: Newton iterations per step
//!   (target within 1.5× of the shared nodes') and the contact's share of the assembly (its
//!   interface's element kernels, target ≤ 20 %).
//!
//! Prints the per-step phase split of every run and the ratio
//! `coupled / (MPM alone + FEM alone)` (target ≤ 1.15). Threads from `LOAM_BENCH_THREADS`
//! (default 1), steps from `LOAM_BENCH_STEPS` (default 20). Run: `cargo bench --bench coupled`.
//! Nothing is asserted about times.

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
    Simulation::new(Case::parse(&v.to_string()).expect("case parses")).expect("case builds")
}

/// Fixed steps of `dt` to `end`, no rest criterion.
fn fixed_steps(v: &mut Value, dt: f64, end: f64) {
    let a = v["analysis"].as_object_mut().expect("analysis");
    a.remove("adaptive");
    a.remove("stop_at_rest");
    a.insert("time_step".into(), json!(dt));
    a.insert("end_time".into(), json!(end));
}

/// Steps `sim` to time `t` (untimed).
fn advance(sim: &mut Simulation, t: f64) {
    sim.advance_to(t).expect("steps converge");
}

fn points(sim: &Simulation) -> usize {
    sim.model.domains.iter().map(|d| d.point_extents().len()).sum()
}

fn timed(sim: Simulation, label: &str, start: f64, threads: usize, steps: usize) -> StepTiming {
    timed_with_kernels(sim, label, start, threads, steps).0
}

/// As [`timed`], with the seconds of each domain's element kernels in the timed steps, by
/// domain name.
fn timed_with_kernels(
    mut sim: Simulation,
    label: &str,
    start: f64,
    threads: usize,
    steps: usize,
) -> (StepTiming, Vec<(String, f64)>) {
    advance(&mut sim, start);
    let n = points(&sim);
    let before = sim.model.kernel_seconds_by_domain();
    let timing = time_steps(&mut sim, label, n, threads, 1, steps);
    let kernels = sim.model.domains.iter().zip(sim.model.kernel_seconds_by_domain()).zip(before);
    (timing, kernels.map(|((d, after), before)| (d.name().to_string(), after - before)).collect())
}

fn per_step(r: &StepTiming) -> f64 {
    r.wall / r.steps.max(1) as f64
}

fn iterations(r: &StepTiming) -> f64 {
    r.iterations as f64 / r.steps.max(1) as f64
}

fn compare(title: &str, rows: &[StepTiming]) {
    let (coupled, mpm, fem) = (per_step(&rows[0]), per_step(&rows[1]), per_step(&rows[2]));
    println!(
        "\n{title}: coupled {:.2} ms/step ({:.2} Newton it/step) vs MPM alone {:.2} ms ({:.2} it) + FEM alone {:.2} ms ({:.2} it): ratio {:.3} (target ≤ 1.15)",
        1e3 * coupled,
        iterations(&rows[0]),
        1e3 * mpm,
        iterations(&rows[1]),
        1e3 * fem,
        iterations(&rows[2]),
        coupled / (mpm + fem)
    );
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let threads: usize = std::env::var("LOAM_BENCH_THREADS").ok().and_then(|v| v.parse().ok()).unwrap_or(1);
    let steps: usize = std::env::var("LOAM_BENCH_STEPS").ok().and_then(|v| v.parse().ok()).unwrap_or(20);
    let (dt, start) = (1e-3, 0.1);
    let end = start + (steps + 2) as f64 * dt;

    // the Bui column onto the rubber plate
    let mut coupled = case_json("coupled_collapse_rubber.json");
    coupled.as_object_mut().unwrap().remove("fmu");
    fixed_steps(&mut coupled, dt, end);
    let mut soil = case_json("collapse_bui2008_quad_mc.json");
    soil["analysis"]["scheme"] = coupled["analysis"]["scheme"].clone();
    fixed_steps(&mut soil, dt, end);
    let mut plate = coupled.clone();
    plate["domains"] = json!([coupled["domains"][1].clone()]);
    plate.as_object_mut().unwrap().remove("interfaces");
    plate["regions"] = json!({ "foot": { "y": 0.0 } });
    plate["boundary_conditions"] = json!([{ "region": "foot", "displacement": [0.0, 0.0] }]);
    plate["monitors"] = json!([]);
    let mut rotated = case_json("coupled_collapse_rubber_rotated.json");
    fixed_steps(&mut rotated, dt, end);
    let rows = vec![
        timed(build(coupled), "Bui column onto the rubber plate (coupled)", start, threads, steps),
        timed(build(soil), "Bui column, no plate (MPM alone)", start, threads, steps),
        timed(build(plate), "rubber plate alone (FEM)", start, threads, steps),
    ];
    print_table(&rows, &[]);
    compare("collapse onto the rubber plate", &rows);

    // the same plate by contact, rotated against the grid
    let interfaces: Vec<String> = rotated["interfaces"]
        .as_array()
        .expect("interfaces")
        .iter()
        .map(|i| i["name"].as_str().unwrap().into())
        .collect();
    let (mut by_contact, kernels) =
        timed_with_kernels(build(rotated), "rubber plate rotated 10°, by contact", start, threads, steps);
    let contact: f64 = kernels.iter().filter(|(name, _)| interfaces.contains(name)).map(|(_, s)| s).sum();
    let share = contact / by_contact.timings.assembly;
    by_contact.extra = vec![format!("{:.2} %", 100.0 * share)];
    let mut shared = rows.into_iter().next().expect("the shared-node row");
    shared.extra = vec!["—".into()];
    let rows = vec![shared, by_contact];
    print_table(&rows, &["contact kernels / assembly"]);
    println!(
        "\ncontact against shared nodes: {:.2} against {:.2} Newton it/step (ratio {:.2}, target ≤ 1.5); the contact's kernels {:.2} % of the assembly (target ≤ 20 %)",
        iterations(&rows[1]),
        iterations(&rows[0]),
        iterations(&rows[1]) / iterations(&rows[0]),
        100.0 * share
    );

    // the split beam, dynamic
    let beam = case_json("coupled_beam_split_dynamic.json");
    let mut mpm_half = beam.clone();
    mpm_half["domains"] = json!([beam["domains"][1].clone()]);
    mpm_half.as_object_mut().unwrap().remove("interfaces");
    mpm_half["regions"] = json!({ "cut": { "segment": { "from": [4.0, 0.0], "to": [4.0, 1.0] } } });
    mpm_half["boundary_conditions"] = json!([{ "region": "cut", "displacement": [0.0, 0.0] }]);
    mpm_half["monitors"] = json!([]);
    let mut fem_half = beam.clone();
    fem_half["domains"] = json!([beam["domains"][0].clone()]);
    fem_half.as_object_mut().unwrap().remove("interfaces");
    fem_half["monitors"] = json!([]);
    let rows = vec![
        timed(build(beam), "split beam, dynamic (coupled)", 0.0, threads, steps),
        timed(build(mpm_half), "MPM half alone", 0.0, threads, steps),
        timed(build(fem_half), "FEM half alone", 0.0, threads, steps),
    ];
    print_table(&rows, &[]);
    compare("split beam", &rows);
}
