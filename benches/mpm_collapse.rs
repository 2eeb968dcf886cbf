//! Time per step of the Bui et al. (2008) column collapse (benchmark 8 of
//! `shared/BENCHMARKS.md`), by phase, at the refinement levels of `cases/`.
//!
//! Two parts:
//!
//! - **steps** (default): from the start of the collapse, one warm-up step and then
//!   `LOAM_BENCH_STEPS` (default 10) steps of Kratos' step Δt = 5e-5 s, with 1 and 2 threads,
//!   on the quadrilateral grids h = 10 / 5 / 2.5 mm (`collapse_bui2008_quad_mc_h10`, `_quad_mc`,
//!   `_quad_mc_h2.5`: Mohr–Coulomb on the linear basis, as Kratos runs it) and on Kratos' own validation discretisation of this benchmark
//!   (`collapse_bui2008_tri_h2`: triangles h = 2 mm, 3 points each, 30 000 points). Kratos'
//!   MPM application needs 0.83 s per step there on one thread (`shared/kratos/README.md`);
//!   the last column is that over Loam's time per step.
//! - **full** (`LOAM_BENCH_COLLAPSE=full`): each quadrilateral level run as its case file
//!   says (adaptive steps until at rest, no output files), with its wall time, steps, Newton
//!   iterations, per-step phase split, and final runout and height at the wall; threads from
//!   `LOAM_BENCH_THREADS` (default 2). The h = 2.5 mm level takes about 10 minutes on 2 cores.
//!
//! - **small step** (`LOAM_BENCH_COLLAPSE=small_step`): the first case (default
//!   `collapse_bui2008_quad_mc`) run twice until at rest, with Kratos' fixed step Δt = 5e-5 s
//!   and with the case's adaptive steps; prints both wall times and the RMS vertical distance
//!   between the two final surfaces (sampled every millimetre from the wall to 0.5 m).
//! - **repeat** (`LOAM_BENCH_COLLAPSE=repeat`): the same with two identical adaptive runs,
//!   which measures how far round-off (parallel sums) alone moves the final surface.
//!
//!
//! In the last two modes the material points of each final state (position, size, initial size: the
//! surface) are written to `target/mpm_collapse/<case>_<k>.csv`;
//! `LOAM_BENCH_REFERENCE=<file>` takes the first run's surface from such a file instead of
//! running it, and `LOAM_BENCH_OVERRIDE='{"analysis":{"adaptive":{"max_time_step":0.002}}}'`
//! merges a JSON patch into the case for the last run: variants of the step control are
//! compared with one small-step run, and a perturbation at round-off level (e.g. gravity
//! −9.81 (1 + 1e-12)) in repeat mode measures how far the final surface moves under it.
//!
//! Choose cases with `LOAM_BENCH_CASES=collapse_bui2008_quad_mc,collapse_bui2008_tri_h2`, and
//! the element of every domain with `LOAM_BENCH_FORMULATION=mixed_up` (the u–p refinement
//! study: `LOAM_BENCH_COLLAPSE=full LOAM_BENCH_FORMULATION=mixed_up`, about 10 minutes).
//! Run: `cargo bench --bench mpm_collapse`. Nothing is asserted about times.

mod common;

use std::path::Path;
use std::time::Instant;

use common::{print_table, time_steps, StepTiming};
use loam::case::Case;
use loam::monitor::point_extents;
use loam::simulation::Simulation;
use loam_fem::domain::PointExtent;
use loam_mpm::surface::SurfaceProfile;

/// Kratos' MPM application on `collapse_bui2008_tri_h2`'s discretisation at Δt = 5e-5 s,
/// one thread (s per step; `shared/kratos/README.md`).
const KRATOS_SECONDS_PER_STEP: f64 = 0.83;
const KRATOS_CASE: &str = "collapse_bui2008_tri_h2";
const KRATOS_TIME_STEP: f64 = 5e-5;

/// How [`load`] changes the case's analysis.
enum Steps {
    /// As in the case file.
    AsCase,
    /// As in the case file with the JSON patch of `LOAM_BENCH_OVERRIDE` (if any) merged in.
    Patched,
    /// `n` fixed steps of length `dt` (no adaptivity, no rest criterion).
    Fixed(f64, usize),
    /// Fixed steps of length `dt` until at rest (the case's rest criterion).
    FixedToRest(f64),
}

fn load(name: &str, steps: Steps) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(format!("{name}.json"));
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("case file")).expect("case JSON");
    json["output"] = serde_json::json!({ "interval": 0, "vtk": false });
    if let Ok(formulation) = std::env::var("LOAM_BENCH_FORMULATION") {
        for domain in json["domains"].as_array_mut().expect("domains") {
            domain["element_formulation"] = formulation.clone().into();
        }
    }
    if matches!(steps, Steps::Patched) {
        if let Ok(text) = std::env::var("LOAM_BENCH_OVERRIDE") {
            let patch: serde_json::Value = serde_json::from_str(&text).expect("LOAM_BENCH_OVERRIDE is JSON");
            merge(&mut json, &patch);
        }
    }
    let analysis = json["analysis"].as_object_mut().expect("analysis");
    match steps {
        Steps::AsCase | Steps::Patched => {}
        Steps::Fixed(dt, n) => {
            analysis.remove("adaptive");
            analysis.remove("stop_at_rest");
            analysis.insert("time_step".into(), dt.into());
            analysis.insert("end_time".into(), (dt * (n + 1) as f64).into());
        }
        Steps::FixedToRest(dt) => {
            analysis.remove("adaptive");
            analysis.insert("time_step".into(), dt.into());
        }
    }
    Case::parse(&json.to_string()).expect("case parses")
}

/// Merges the JSON object `patch` into `target` (objects key by key, anything else replaced).
fn merge(target: &mut serde_json::Value, patch: &serde_json::Value) {
    match (target, patch) {
        (serde_json::Value::Object(t), serde_json::Value::Object(p)) => {
            for (key, value) in p {
                merge(t.entry(key.clone()).or_insert(serde_json::Value::Null), value);
            }
        }
        (t, p) => *t = p.clone(),
    }
}

fn point_count(sim: &Simulation) -> usize {
    sim.model.domains.iter().map(|d| d.points_in_box(&[f64::MIN; 3], &[f64::MAX; 3]).len()).sum()
}

fn env_list(name: &str) -> Option<Vec<String>> {
    std::env::var(name).ok().map(|v| v.split(',').map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect())
}

/// Runs `case` until its end (or rest) in a pool of `threads`; returns the simulation and the
/// wall time.
fn run_whole(case: Case, threads: usize) -> (Simulation, f64) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    let mut sim = Simulation::new(case).expect("case builds");
    let t = Instant::now();
    pool.install(|| {
        while !sim.finished() {
            sim.step().expect("step converges");
        }
    });
    (sim, t.elapsed().as_secs_f64())
}

/// Prints the `n` material points with the largest volume ratio J = det F (position, J),
/// which single out points whose volume, and so their square on the surface, has grown.
fn print_most_dilated(sim: &Simulation, n: usize) {
    let mut points: Vec<([f64; 3], f64, [f64; 4])> = Vec::new();
    for named in sim.model.outputs(false) {
        let out = named.output;
        let Some(f) = out.point_fields.iter().find(|f| f.name == "deformation_gradient") else { continue };
        for (p, x) in out.points.iter().enumerate() {
            let m = nalgebra::Matrix3::from_fn(|i, j| f.values[9 * p + 3 * i + j]);
            points.push((*x, m.determinant(), [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]]));
        }
    }
    points.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (x, j, f) in points.iter().take(n) {
        println!("|   point at ({:.4}, {:.4}) m: J = {j:.3}, F = {f:.3?} | | | | | | |", x[0], x[1]);
    }
}

/// Writes the material points' extents (the final surface) as `x,y,z,size,initial_size`
/// lines, with all digits.
fn write_points(path: &Path, points: &[PointExtent]) {
    let text: String = points
        .iter()
        .map(|p| {
            let [x, y, z] = p.position;
            format!("{x:e},{y:e},{z:e},{:e},{:e}\n", p.size, p.initial_size)
        })
        .collect();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).expect("surface directory");
    }
    std::fs::write(path, format!("x,y,z,size,initial_size\n{text}")).expect("points file written");
}

/// Reads points written by [`write_points`].
fn read_points(path: &Path) -> Vec<PointExtent> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .skip(1)
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|s| s.parse().expect("a number")).collect();
            PointExtent { position: [v[0], v[1], v[2]], size: v[3], initial_size: v[4] }
        })
        .collect()
}

/// RMS vertical distance between the surfaces of two sets of points, sampled every
/// millimetre from the wall to 0.5 m.
fn rms_between(a: &[PointExtent], b: &[PointExtent]) -> f64 {
    let samples: Vec<(f64, f64)> =
        (0..=500).map(|k| 1e-3 * k as f64).map(|x| (x, SurfaceProfile::new(a, 0.0).height_at(x))).collect();
    SurfaceProfile::new(b, 0.0).rms_distance(&samples)
}

/// Runs `name` until at rest as each of `runs` says, writes each final state's point
/// extents to `target/mpm_collapse/<name>_<k>.csv`, and prints the runs and the RMS vertical distance of
/// each later surface from the first. With `LOAM_BENCH_REFERENCE=<file>` the first run is
/// replaced by the points in that file (written by an earlier run), so that
/// variants of the adaptive run can be compared with one small-step run.
fn surface_comparison(name: &str, threads: usize, runs: Vec<(&str, Steps)>) {
    let out_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target").join("mpm_collapse");
    let reference = std::env::var("LOAM_BENCH_REFERENCE").ok();
    let mut surfaces = Vec::new();
    println!("\n{name}, {threads} thread(s), until at rest:\n");
    println!("| steps | count | end time (s) | wall (s) | s per step | runout (m) | height at wall (m) |");
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for (k, (label, steps)) in runs.into_iter().enumerate() {
        if k == 0 {
            if let Some(file) = &reference {
                println!("| {label} | read from {file} | | | | | |");
                surfaces.push(read_points(Path::new(file)));
                continue;
            }
        }
        let (sim, wall) = run_whole(load(name, steps), threads);
        let value = |m: &str| {
            let k = sim.monitor_names().iter().position(|n| *n == m).expect("monitor");
            sim.monitor_values()[k]
        };
        println!(
            "| {label} | {} | {:.3}{} | {wall:.1} | {:.4} | {:.4} | {:.4} |",
            sim.stats.steps,
            sim.time(),
            if sim.at_rest { " (rest)" } else { "" },
            wall / sim.stats.steps as f64,
            value("runout"),
            value("height_at_wall")
        );
        print_most_dilated(&sim, 3);
        let surface = point_extents(&sim.model);
        let file = out_dir.join(format!("{name}_{k}.csv"));
        write_points(&file, &surface);
        println!("|   (final surface written to {}) | | | | | | |", file.display());
        surfaces.push(surface);
    }
    println!();
    for (k, surface) in surfaces.iter().enumerate().skip(1) {
        println!(
            "RMS vertical distance of surface {k} from surface 0 (x = 0 … 0.5 m every 1 mm): {:.2} mm",
            rms_between(&surfaces[0], surface) * 1e3
        );
    }
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let mode = std::env::var("LOAM_BENCH_COLLAPSE").unwrap_or_default();
    if mode == "small_step" || mode == "repeat" {
        let name = env_list("LOAM_BENCH_CASES").and_then(|v| v.first().cloned());
        let threads = env_list("LOAM_BENCH_THREADS").and_then(|v| v.first().and_then(|s| s.parse().ok()));
        let runs = if mode == "repeat" {
            vec![("adaptive, first run", Steps::AsCase), ("adaptive, second run", Steps::Patched)]
        } else {
            vec![("Δt = 5e-5 s", Steps::FixedToRest(KRATOS_TIME_STEP)), ("adaptive", Steps::Patched)]
        };
        surface_comparison(name.as_deref().unwrap_or("collapse_bui2008_quad_mc"), threads.unwrap_or(2), runs);
        return;
    }
    let full = std::env::var("LOAM_BENCH_COLLAPSE").is_ok_and(|v| v == "full");
    let levels = ["collapse_bui2008_quad_mc_h10", "collapse_bui2008_quad_mc", "collapse_bui2008_quad_mc_h2.5"];
    let mut cases: Vec<String> = levels.iter().map(|s| s.to_string()).collect();
    if !full {
        cases.push(KRATOS_CASE.into());
    }
    let cases = env_list("LOAM_BENCH_CASES").unwrap_or(cases);
    let default_threads = if full { vec![2] } else { vec![1, 2] };
    let threads: Vec<usize> = env_list("LOAM_BENCH_THREADS")
        .map(|v| v.iter().filter_map(|s| s.parse().ok()).collect())
        .unwrap_or(default_threads);
    let steps: usize = std::env::var("LOAM_BENCH_STEPS").ok().and_then(|v| v.parse().ok()).unwrap_or(10);
    let mut rows: Vec<StepTiming> = Vec::new();
    for name in &cases {
        for &th in &threads {
            if full {
                let mut sim = Simulation::new(load(name, Steps::AsCase)).expect("case builds");
                let points = point_count(&sim);
                let t = Instant::now();
                let mut row = time_steps(&mut sim, name, points, th, 0, usize::MAX);
                let wall = t.elapsed().as_secs_f64();
                let value = |m: &str| {
                    let k = sim.monitor_names().iter().position(|n| *n == m).expect("monitor");
                    sim.monitor_values()[k]
                };
                row.extra = vec![
                    format!("{wall:.1}"),
                    format!("{}", row.steps),
                    format!("{:.3}{}", sim.time(), if sim.at_rest { " (rest)" } else { "" }),
                    format!("{:.4}", value("runout")),
                    format!("{:.4}", value("height_at_wall")),
                ];
                rows.push(row);
            } else {
                let mut sim = Simulation::new(load(name, Steps::Fixed(KRATOS_TIME_STEP, steps))).expect("case builds");
                let points = point_count(&sim);
                let mut row = time_steps(&mut sim, name, points, th, 1, steps);
                let per_step = row.wall / row.steps.max(1) as f64;
                row.extra = vec![if name == KRATOS_CASE {
                    format!("{:.1}", KRATOS_SECONDS_PER_STEP / per_step)
                } else {
                    "—".into()
                }];
                rows.push(row);
            }
        }
    }
    if full {
        println!("\nWhole runs (adaptive steps until at rest), no output files.");
        print_table(&rows, &["wall (s)", "steps", "end time (s)", "runout (m)", "height at wall (m)"]);
    } else {
        println!("\nSteps of Δt = {KRATOS_TIME_STEP} s from the start of the collapse.");
        print_table(&rows, &["Kratos 1 thread / Loam"]);
    }
}
