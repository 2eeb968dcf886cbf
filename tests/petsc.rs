//! Issue 26, items 2–3: `solver.linear_solver: "petsc"` on one process (a build with the
//! `petsc` feature: `cargo test --release --features petsc --test petsc`). Each validation
//! test compares with the closed-form reference of the direct-solver test it mirrors, and
//! then, as a **consistency check**, with the same case under the default direct solver:
//! Newton meets the same tolerances either way and the Krylov tolerance (1e-10 relative) is
//! far below them, so the monitors agree to round-off of the Newton iterate.

#![cfg(feature = "petsc")]

mod common;

use common::{case_json, last, mean_plane_force, monitor, nearest_point, parse, report, run, timoshenko, History};
use loam::simulation::Simulation;
use serde_json::{json, Value};

/// Relative agreement of every monitor with the direct solver's run (consistency check).
const DIRECT_AGREEMENT: f64 = 1e-9;

/// `json` with the PETSc solver and the given extra options.
fn with_petsc(mut json: Value, options: Value) -> Value {
    json["solver"]["linear_solver"] = json!("petsc");
    if options.as_object().is_some_and(|o| !o.is_empty()) {
        json["solver"]["petsc_options"] = options;
    }
    json
}

/// Every monitor of the last rows agrees to [`DIRECT_AGREEMENT`] (relative to the largest
/// magnitude of that monitor over the run).
fn assert_same_monitors(what: &str, sim: &Simulation, petsc: &History, direct: &History) {
    assert_eq!(petsc.len(), direct.len(), "{what}: as many steps");
    for (k, name) in sim.monitor_names().iter().enumerate() {
        let scale = direct.iter().map(|r| r.1[k].abs()).fold(0.0, f64::max).max(1e-300);
        let diff = petsc.iter().zip(direct).map(|(a, b)| (a.1[k] - b.1[k]).abs()).fold(0.0, f64::max);
        println!("{what}: {name}: largest difference PETSc vs direct {:.2e} (relative)", diff / scale);
        assert!(diff <= DIRECT_AGREEMENT * scale, "{what}: monitor {name} differs by {diff:e} (scale {scale:e})");
    }
}

/// Benchmark 1, static FEM (quad4 56 × 8) with CG + GAMG: the tip deflection against
/// Timoshenko at x = 7 within 2 % (as `fem_validation::cantilever_static_tip_deflection`),
/// the Krylov iterations reported, and every monitor equal to the direct solver's.
#[test]
fn cantilever_fem_petsc_matches_beam_theory_and_the_direct_solver() {
    let (sim, h) = run(parse(with_petsc(case_json("cantilever_fem.json"), json!({}))));
    let (direct_sim, direct) = run(parse(case_json("cantilever_fem.json")));
    report("benchmark 1 static tip_uy (PETSc) vs Timoshenko [m]", last(&sim, &h, "tip_uy"), timoshenko(7.0), 0.02);
    let timings = sim.model.solver_timings();
    println!(
        "PETSc: {} solves, {} Krylov iterations ({:.1} per solve); direct: {} factorisations",
        timings.krylov_solves,
        timings.krylov_iterations,
        timings.krylov_iterations as f64 / timings.krylov_solves.max(1) as f64,
        direct_sim.model.solver_timings().factorisations
    );
    assert!(timings.krylov_solves > 0 && timings.krylov_iterations >= timings.krylov_solves);
    assert_same_monitors("cantilever_fem", &sim, &h, &direct);
}

/// Benchmark 1 with MPM (static, h = 0.125 m, 4 points per cell): the deflection of the point
/// nearest (7, 0.5) against Timoshenko at its position within 2 % (as
/// `mpm_validation::cantilever_mpm_static_beside_fem`), and every monitor equal to the
/// direct solver's.
#[test]
fn cantilever_mpm_petsc_matches_beam_theory_and_the_direct_solver() {
    let (sim, h) = run(parse(with_petsc(case_json("cantilever_mpm.json"), json!({}))));
    let (_, direct) = run(parse(case_json("cantilever_mpm.json")));
    let (x_p, u_p) = nearest_point(&sim, &[7.0, 0.5]);
    report("MPM point deflection (PETSc) vs Timoshenko at the point [m]", u_p[1], timoshenko(x_p[0]), 0.02);
    assert!(sim.model.solver_timings().krylov_iterations > 0);
    assert_same_monitors("cantilever_mpm", &sim, &h, &direct);
}

/// Benchmark 1 in 3D (`cases/cantilever_fem_3d.json`, hex8 56 × 8 × 8, 13 608 equations, two
/// load steps): the tip deflection against Timoshenko within 3 % (BENCHMARKS.md, FEM; as
/// `fem_validation::hex8_cantilever_matches_beam_theory`), CG + GAMG with the rigid-body
/// modes in at most 40 iterations per solve (measured 23), and every monitor equal to the
/// direct solver's.
#[test]
fn cantilever_3d_petsc_matches_beam_theory_and_the_direct_solver() {
    let (sim, h) = run(parse(with_petsc(case_json("cantilever_fem_3d.json"), json!({}))));
    let (_, direct) = run(parse(case_json("cantilever_fem_3d.json")));
    report("3D hex8 cantilever tip_uy (PETSc) vs Timoshenko [m]", last(&sim, &h, "tip_uy"), timoshenko(7.0), 0.03);
    let t = sim.model.solver_timings();
    let per_solve = t.krylov_iterations as f64 / t.krylov_solves.max(1) as f64;
    println!("{} solves, {per_solve:.1} CG iterations per solve", t.krylov_solves);
    assert!(t.krylov_solves > 0 && per_solve <= 40.0, "GAMG with the rigid-body modes: {per_solve} per solve");
    assert_same_monitors("cantilever_fem_3d", &sim, &h, &direct);
}

/// The other preconditioners and a user's Krylov type (consistency checks on the FEM
/// cantilever): BoomerAMG (`-pc_type hypre`), MUMPS's direct LU (`-pc_type mumps`, one
/// iteration per solve), BiCGStab with GAMG.
#[test]
fn petsc_options_choose_hypre_mumps_and_the_krylov_type() {
    let (_, direct) = run(parse(case_json("cantilever_fem.json")));
    for options in [json!({"-pc_type": "hypre"}), json!({"-pc_type": "mumps"}), json!({"ksp_type": "bcgs"})] {
        let (sim, h) = run(parse(with_petsc(case_json("cantilever_fem.json"), options.clone())));
        let t = sim.model.solver_timings();
        println!("{options}: {} solves, {} iterations", t.krylov_solves, t.krylov_iterations);
        if options["-pc_type"] == "mumps" {
            assert_eq!(t.krylov_iterations, t.krylov_solves, "a direct preconditioner: one iteration per solve");
        }
        assert_same_monitors(&options.to_string(), &sim, &h, &direct);
    }
}

/// Unsymmetric tangents (non-associated Mohr–Coulomb with softening: the biaxial test's first
/// 20 steps, into plastic flow) go to GMRES + GAMG; the load–displacement monitors equal the
/// direct solver's (LU). (Without the rigid-body modes as GAMG's near null space a few
/// softening tangents needed more than 1000 iterations: docs/distributed.md.)
#[test]
fn unsymmetric_mohr_coulomb_tangent_solves_by_gmres() {
    let mut json = case_json("biaxial_mc_softening.json");
    json["analysis"]["end_time"] = json!(0.2);
    let (sim, h) = run(parse(with_petsc(json.clone(), json!({}))));
    let (_, direct) = run(parse(json));
    assert!(sim.model.solver_timings().krylov_iterations > 0);
    assert_same_monitors("biaxial_mc_softening to t = 0.2", &sim, &h, &direct);
}

/// Benchmark 1 with MPM, dynamic (300 steps, `K + M/(βΔt²)`): no step is cut and every
/// monitor equals the direct solver's (consistency check). GAMG's Chebyshev smoothers were
/// indefinite on a few of these tangents (CG: `DIVERGED_INDEFINITE_PC`); such a solve is
/// repeated by GMRES (printed: preconditioner set-ups beyond the solves).
#[test]
fn dynamic_mpm_cantilever_keeps_the_direct_path() {
    let (sim, h) = run(parse(with_petsc(case_json("cantilever_mpm_dynamic.json"), json!({}))));
    let (_, direct) = run(parse(case_json("cantilever_mpm_dynamic.json")));
    let t = sim.model.solver_timings();
    println!(
        "{} steps, {} cuts; {} set-ups for {} solves ({} repeated by GMRES), {} iterations",
        sim.stats.steps,
        sim.stats.cuts,
        t.factorisations,
        t.krylov_solves,
        t.factorisations - t.krylov_solves,
        t.krylov_iterations
    );
    assert_eq!(sim.stats.cuts, 0, "no step cut");
    assert_same_monitors("cantilever_mpm_dynamic", &sim, &h, &direct);
}

/// Where GAMG does not converge and the options name no preconditioner, MUMPS's LU takes over
/// for the pattern: benchmark 6 with slip (`cases/cylinder_incline_slip_mpm.json`, a penalty
/// wall of 10¹³ N/m³ whose initial acceleration, the mass matrix and the penalty alone, breaks
/// CG and GMRES with GAMG down), its first 0.2 s. Asserted: at least one such fallback
/// (`gamg_failures`), the displacements of the four points around the centre equal to the
/// direct solver's within [`DIRECT_AGREEMENT`], the centre's slide against `½ g sin α t²`
/// within 2 % and the plane's mean normal force against `m g cos α` (1 264 points of
/// ρ s² = 0.78 kg/m) within 1 %. The wall's force is not compared with the direct solver's: it
/// is the penalty times a gap of about 10⁻⁸ m, which carries the solvers' round-off at about
/// 3e-9 of itself.
#[test]
fn gamg_that_fails_on_a_penalty_wall_hands_the_pattern_to_mumps() {
    let json = |solver: Value| {
        let mut json = case_json("cylinder_incline_slip_mpm.json");
        json["analysis"]["end_time"] = json!(0.2);
        json["solver"] = solver;
        json
    };
    let (sim, h) = run(parse(json(json!({"linear_solver": "petsc"}))));
    let (_, direct) = run(parse(json(json!({"linear_solver": "lu"}))));
    let fallbacks = sim.model.solver_timings().gamg_failures;
    println!("GAMG failures handed to MUMPS: {fallbacks}");
    assert!(fallbacks >= 1, "GAMG failed on the penalty wall and MUMPS took over");
    let a = 60f64.to_radians();
    let (mut ux, mut uy) = (0.0, 0.0);
    for k in 0..4 {
        ux += 0.25 * last(&sim, &h, &format!("c{k}_ux"));
        uy += 0.25 * last(&sim, &h, &format!("c{k}_uy"));
        for c in ["ux", "uy"] {
            let name = format!("c{k}_{c}");
            let (m, d) = (monitor(&sim, &name), &direct);
            let scale = d.iter().map(|r| r.1[m].abs()).fold(0.0, f64::max);
            let diff = h.iter().zip(d).map(|(p, q)| (p.1[m] - q.1[m]).abs()).fold(0.0, f64::max);
            assert!(diff <= DIRECT_AGREEMENT * scale, "{name}: {diff:e} of {scale:e}");
        }
    }
    let t = h.last().unwrap().0;
    report(
        "cylinder with PETSc → MUMPS: centre down the 60° plane [m]",
        -(ux * a.cos() + uy * a.sin()),
        4.905 * a.sin() * t * t,
        0.02,
    );
    let (fx, fy) = (monitor(&sim, "wall_fx"), monitor(&sim, "wall_fy"));
    let forces: Vec<(f64, f64)> = h[1..].iter().map(|r| (r.1[fx], r.1[fy])).collect();
    let (normal, _) = mean_plane_force(&forces, a);
    report(
        "cylinder with PETSc → MUMPS: mean normal force vs m g cos α [N/m]",
        normal,
        7800.0 * 1e-4 * 1264.0 * 9.81 * a.cos(),
        0.01,
    );
}

/// A Krylov solve that does not converge is a failed step, retried with shorter ones: with
/// GAMG named in the options (so that MUMPS does not take over) and at most 3 iterations
/// allowed none converges, the step is cut `max_step_cuts` times and the error names PETSc's
/// reason.
#[test]
fn krylov_non_convergence_fails_the_step_with_petscs_reason() {
    let mut json = with_petsc(case_json("cantilever_fem.json"), json!({"-pc_type": "gamg", "-ksp_max_it": 3}));
    json["analysis"]["max_step_cuts"] = json!(2);
    let mut sim = Simulation::new(parse(json)).expect("case builds");
    let err = sim.step().expect_err("3 Krylov iterations cannot reach 1e-10").to_string();
    println!("{err}");
    assert!(err.contains("did not converge") && err.contains("DIVERGED_ITS"), "{err}");
    assert_eq!(sim.stats.cuts, 2, "the step was retried with shorter ones");
    let _ = monitor(&sim, "tip_uy");
}
