//! Time per Newton iteration of a plane-strain Neo-Hookean quad mesh, by phase.
//!
//! A clamped block `2H × H` (E = 1 MPa, ν = 0.3, ρ = 1000 kg/m³) sags under its own
//! weight in one static step: `R(u) = f_int(u) − f_body = 0`, bilinear quads with 2×2
//! Gauss points, about 10k, 100k and 400k DOFs. For each size the benchmark reports
//!
//! - assembly per iteration (element kernels writing the element buffers, then the gather
//!   of residual and matrix values), best of several repetitions, in a local rayon pool of
//!   1 thread and of 2 threads, and the speed-up;
//! - numeric factorisation and triangular solve per Newton iteration of the step (faer,
//!   sequential, Cholesky when the tangent is symmetric: the solver `auto`);
//! - the symbolic analysis, done once per sparsity pattern.
//!
//! Run: `cargo bench --bench fem_newton` (all sizes; a few minutes on 2 cores), or pick
//! sizes with `LOAM_BENCH_SIZES=10k,100k cargo bench --bench fem_newton`. Add
//! `LOAM_BENCH_REPEAT=N` to change the assembly repetitions (default 10; the best is kept,
//! which filters out time slices lost to other processes on a shared machine).
//!
//! This is a benchmark, not a timed test: nothing is asserted about times.

use std::time::Instant;

use loam::case::Case;
use loam::simulation::Simulation;
use loam_fem::model::AssemblyTimings;

/// Cells along x and y for a nominal DOF count (`2 (nx+1)(ny+1)`, nx = 2 ny).
fn cells_for(dofs: usize) -> (usize, usize) {
    let ny = ((dofs as f64 / 4.0).sqrt()).round() as usize;
    (2 * ny, ny)
}

fn parse_size(s: &str) -> Option<usize> {
    let s = s.trim().to_ascii_lowercase();
    if let Some(k) = s.strip_suffix('k') {
        k.parse::<f64>().ok().map(|v| (v * 1e3) as usize)
    } else if let Some(m) = s.strip_suffix('m') {
        m.parse::<f64>().ok().map(|v| (v * 1e6) as usize)
    } else {
        s.parse().ok()
    }
}

fn case_json(nx: usize, ny: usize) -> String {
    format!(
        r#"{{
  "description": "fem_newton benchmark: clamped Neo-Hookean block under gravity",
  "formulation": "plane_strain",
  "thickness": 1.0,
  "materials": {{ "block": {{ "law": "neo_hookean", "density": 1000.0, "young_modulus": 1.0e6, "poisson_ratio": 0.3 }} }},
  "domains": [ {{ "name": "block", "material": "block",
     "mesh": {{ "rectangle": {{ "origin": [0.0, 0.0], "size": [2.0, 1.0], "cells": [{nx}, {ny}], "element": "quad4" }} }} }} ],
  "regions": {{ "clamp": {{ "x": 0.0 }} }},
  "boundary_conditions": [ {{ "region": "clamp", "displacement": [0.0, 0.0] }} ],
  "gravity": {{ "acceleration": [0.0, -9.81] }},
  "analysis": {{ "type": "static", "time_step": 1.0, "end_time": 1.0 }},
  "solver": {{ "residual_relative_tolerance": 1e-8, "residual_absolute_tolerance": 1e-6 }}
}}"#
    )
}

fn best_assembly(pool: &rayon::ThreadPool, sim: &mut Simulation, repeat: usize) -> AssemblyTimings {
    pool.install(|| {
        sim.model.assemble_only().expect("assembly"); // warm-up: first touch of the buffers
        let mut best = AssemblyTimings { kernels: f64::INFINITY, gather: f64::INFINITY };
        for _ in 0..repeat {
            let t = sim.model.assemble_only().expect("assembly");
            if t.kernels + t.gather < best.kernels + best.gather {
                best = t;
            }
        }
        best
    })
}

struct Row {
    dofs: usize,
    elements: usize,
    nnz: usize,
    asm1: AssemblyTimings,
    asm2: AssemblyTimings,
    iterations: usize,
    factorisation: f64,
    solve: f64,
    symbolic: f64,
    pattern: f64,
}

fn run(nominal: usize, repeat: usize, pools: &[rayon::ThreadPool; 2]) -> Row {
    let (nx, ny) = cells_for(nominal);
    let t = Instant::now();
    let case = Case::parse(&case_json(nx, ny)).expect("benchmark case");
    let mut sim = Simulation::new(case).expect("benchmark model");
    let build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    sim.model.prepare();
    let pattern = t.elapsed().as_secs_f64();
    let (dofs, nnz) = (sim.model.num_equations(), sim.model.nnz());
    eprintln!(
        "{nominal} nominal DOFs: {nx}×{ny} quads, {dofs} equations, {nnz} nonzeros (model {build:.2} s, pattern {pattern:.2} s)"
    );
    let asm1 = best_assembly(&pools[0], &mut sim, repeat);
    let asm2 = best_assembly(&pools[1], &mut sim, repeat);
    let t = Instant::now();
    let report = pools[1].install(|| sim.model.solve_step(1.0)).expect("Newton step converges");
    let step = t.elapsed().as_secs_f64();
    let solver = sim.model.solver_timings();
    let iterations = report.iterations.max(1);
    let phases = report.timings.assembly + report.timings.factorisation + report.timings.solve;
    eprintln!(
        "  Newton step (2 threads): {step:.3} s, of which assembly {:.3}, factorisation incl. symbolic {:.3}, solve {:.3}, other {:.3}",
        report.timings.assembly,
        report.timings.factorisation,
        report.timings.solve,
        step - phases
    );
    eprintln!(
        "  Newton: {} iterations, residuals {:?}",
        report.iterations,
        report.residuals.iter().map(|r| format!("{r:.2e}")).collect::<Vec<_>>()
    );
    Row {
        dofs,
        elements: nx * ny,
        nnz,
        asm1,
        asm2,
        iterations: report.iterations,
        factorisation: solver.factorisation / iterations as f64,
        solve: solver.solve / iterations as f64,
        symbolic: solver.symbolic,
        pattern,
    }
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let sizes: Vec<usize> = match std::env::var("LOAM_BENCH_SIZES") {
        Ok(s) => {
            s.split(',').map(|v| parse_size(v).unwrap_or_else(|| panic!("LOAM_BENCH_SIZES: bad size '{v}'"))).collect()
        }
        Err(_) => vec![10_000, 100_000, 400_000],
    };
    let repeat = std::env::var("LOAM_BENCH_REPEAT").ok().and_then(|v| v.parse().ok()).unwrap_or(10usize).max(1);
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("thread pool");
    let pools = [pool(1), pool(2)];
    let rows: Vec<Row> = sizes.iter().map(|&n| run(n, repeat, &pools)).collect();

    println!("\nfem_newton: plane-strain Neo-Hookean quad4, one static Newton step, faer sequential");
    println!(
        "times in seconds; assembly = kernels + gather, best of {repeat}; factorisation and solve per iteration\n"
    );
    println!(
        "| DOFs | elements | nnz | assembly 1 thread | assembly 2 threads | speed-up | factorisation | solve | symbolic (once) | Newton its |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let (a1, a2) = (r.asm1.kernels + r.asm1.gather, r.asm2.kernels + r.asm2.gather);
        println!(
            "| {} | {} | {} | {:.4} | {:.4} | {:.2}× | {:.4} | {:.4} | {:.4} | {} |",
            r.dofs,
            r.elements,
            r.nnz,
            a1,
            a2,
            a1 / a2,
            r.factorisation,
            r.solve,
            r.symbolic,
            r.iterations
        );
    }
    println!("\nassembly halves (kernels / gather, seconds) and pattern build:");
    for r in &rows {
        println!(
            "  {} DOFs: 1 thread {:.4} / {:.4}, 2 threads {:.4} / {:.4}; pattern + gather lists {:.3}",
            r.dofs, r.asm1.kernels, r.asm1.gather, r.asm2.kernels, r.asm2.gather, r.pattern
        );
    }
}
