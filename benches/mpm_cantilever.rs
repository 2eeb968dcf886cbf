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
//! `LOAM_BENCH_THREADS=1,2`. Nothing is asserted about times.

use std::time::Instant;

use loam::case::Case;
use loam::simulation::Simulation;
use loam_fem::model::PhaseTimings;

/// The case JSON for `n` cells through the thickness, `steps` steps of 0.01 s.
pub fn case_json(n: usize, steps: usize) -> String {
    let h = 1.0 / n as f64;
    format!(
        r#"{{
  "description": "mpm_cantilever benchmark: benchmark 1 with MPM, dynamic, n = {n}",
  "formulation": "plane_strain",
  "thickness": 1.0,
  "materials": {{ "beam": {{ "law": "neo_hookean", "density": 1000.0, "young_modulus": 9.0e7, "poisson_ratio": 0.0 }} }},
  "domains": [ {{ "name": "beam", "type": "mpm", "material": "beam",
     "grid": {{ "origin": [0.0, -1.5], "size": [8.0, 3.0], "cells": [{gx}, {gy}], "element": "quad4" }},
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

struct Row {
    points: usize,
    threads: usize,
    steps: usize,
    iterations: usize,
    wall: f64,
    t: PhaseTimings,
    tip: f64,
}

fn run(n: usize, threads: usize, steps: usize) -> Row {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    let case = Case::parse(&case_json(n, steps)).expect("benchmark case parses");
    let mut sim = Simulation::new(case).expect("benchmark case builds");
    let points = 28 * n * n;
    pool.install(|| {
        let t = Instant::now();
        sim.step().expect("warm-up step converges");
        let warm = t.elapsed().as_secs_f64();
        let before = sim.stats.clone();
        let t = Instant::now();
        for _ in 0..steps {
            sim.step().expect("step converges");
        }
        let wall = t.elapsed().as_secs_f64();
        let mut d = sim.stats.timings;
        let b = before.timings;
        d.search -= b.search;
        d.pattern -= b.pattern;
        d.assembly -= b.assembly;
        d.factorisation -= b.factorisation;
        d.symbolic -= b.symbolic;
        d.solve -= b.solve;
        d.commit -= b.commit;
        d.pattern_builds -= b.pattern_builds;
        let tip = sim.monitor_values()[0];
        eprintln!(
            "  {points} points, {threads} thread(s): warm-up step {warm:.4} s, {steps} steps {wall:.3} s, {} iterations, {} pattern builds, tip uy {tip:.6e}",
            sim.stats.iterations - before.iterations,
            d.pattern_builds
        );
        Row { points, threads, steps, iterations: sim.stats.iterations - before.iterations, wall, t: d, tip }
    })
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
    let mut rows = Vec::new();
    for &n in &sizes {
        eprintln!("n = {n} (h = {:.5} m), {} material points", 1.0 / n as f64, 28 * n * n);
        for &th in &threads {
            rows.push(run(n, th, steps));
        }
    }
    println!();
    println!(
        "Milliseconds per step (mean over {steps} steps after one warm-up step); per Newton iteration in parentheses."
    );
    println!();
    println!("| points | threads | iter/step | step | initialisation | pattern + symbolic | assembly | factorisation + solve | convective | other | MP updates/s | tip uy (m) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let s = r.steps as f64;
        let it = r.iterations.max(1) as f64;
        let ms = |x: f64| 1e3 * x / s;
        let t = &r.t;
        let pattern = t.pattern + t.symbolic;
        let fs = t.factorisation - t.symbolic + t.solve;
        let other = r.wall - (t.search + t.pattern + t.assembly + t.factorisation + t.solve + t.commit);
        println!(
            "| {} | {} | {:.1} | {:.3} | {:.3} | {:.3} ({} builds) | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.3} | {:.3} | {:.3e} | {:.5} |",
            r.points,
            r.threads,
            it / s,
            ms(r.wall),
            ms(t.search),
            ms(pattern),
            t.pattern_builds,
            ms(t.assembly),
            1e3 * t.assembly / it,
            ms(fs),
            1e3 * fs / it,
            ms(t.commit),
            ms(other),
            r.points as f64 * s / r.wall,
            r.tip,
        );
    }
}
