//! Implicit MPM validation (issue 4): benchmark 1 with material points, side by side with
//! FEM (the seed's "FEM code / MPM code" comparison), and benchmark 2, the axisymmetric
//! plate, on quadrilateral and triangular grids. Each test prints measured vs reference and
//! asserts its tolerance.

mod common;

use approx::{assert_abs_diff_eq, assert_relative_eq};
use common::{case, case_json, euler_bernoulli, frequency, last, nearest_point, parse, report, run, timoshenko};
use loam::case::{Case, LoadSpec, RegionSpec};
use loam_fem::element::ElementType;

/// Benchmark 1 with MPM, static (h = 0.125 m, 4 points per cell). **Measured:** the
/// deflection of the material point that starts nearest the free end's mid-height (7, 0.5),
/// at X_p = (6.974, 0.526), against beam theory **at X_p**: Timoshenko (Euler–Bernoulli plus
/// shear, κ = 5/6; BENCHMARKS.md gives Euler–Bernoulli −0.39256 m at x = 7 and notes that
/// shear adds 1.6 %). Tolerance 2 %: the discretisation error at this h is 0.8 % and the
/// geometric nonlinearity 0.24 % (`tests/convergence.rs`: order 2, Richardson limit),
/// measured −1.01 %; BENCHMARKS.md allows 5 %.
///
/// Measured where the reference is: the grid node at the tip (7, 0.5) carries the same
/// discrete field (in one static step from the reference state the grid's displacement is
/// the step's), and its error against Timoshenko at x = 7 must equal the point's error at
/// X_p within 0.1 percentage point (measured −1.03 % and −1.01 %). The point compared with
/// the beam at x = 7 instead would be 0.5 points off.
///
/// Printed beside the FEM result on the same discretisation: material points at the FEM
/// Gauss points give the FEM stiffness exactly (strain energies agree to 1e-9, a consistency
/// check).
#[test]
fn cantilever_mpm_static_beside_fem() {
    let mut c = case_json("cantilever_mpm.json");
    c["monitors"].as_array_mut().expect("monitors").push(
        serde_json::json!({ "name": "grid_tip_uy", "type": "displacement", "point": [7.0, 0.5], "component": "y" }),
    );
    let (mpm, hm) = run(parse(c));
    let (fem, hf) = run(case("cantilever_fem.json"));
    assert_eq!(mpm.stats.steps, 1, "one static step");
    let (x_p, u_p) = nearest_point(&mpm, &[7.0, 0.5]);
    let (tip_grid, tip_fem) = (last(&mpm, &hm, "grid_tip_uy"), last(&fem, &hf, "tip_uy"));
    println!(
        "benchmark 1 static: MPM point at X_p = ({:.4}, {:.4}) {:.5} m (Euler–Bernoulli there {:.5}, Timoshenko {:.5}); \
         MPM grid node (7, 0.5) {tip_grid:.5} m; FEM node (7, 0.5) {tip_fem:.5} m; at x = 7 Euler–Bernoulli {:.5}, \
         Timoshenko {:.5}; Kratos MPM (n = 8) −0.3930 m",
        x_p[0],
        x_p[1],
        u_p[1],
        euler_bernoulli(x_p[0]),
        timoshenko(x_p[0]),
        euler_bernoulli(7.0),
        timoshenko(7.0)
    );
    report("MPM point deflection vs Timoshenko at the point's position [m]", u_p[1], timoshenko(x_p[0]), 0.02);
    let (e_point, e_grid) = (u_p[1] / timoshenko(x_p[0]) - 1.0, tip_grid / timoshenko(7.0) - 1.0);
    println!(
        "error of the point at X_p {:+.3} %, of the grid node at the tip {:+.3} %: {:.3} points apart (tolerance 0.1)",
        100.0 * e_point,
        100.0 * e_grid,
        100.0 * (e_point - e_grid).abs()
    );
    assert_abs_diff_eq!(e_point, e_grid, epsilon = 1e-3);
    let e_wrong = u_p[1] / timoshenko(7.0) - 1.0;
    println!(
        "the point against the beam at x = 7 instead: {:+.3} %, {:.3} points from the tip node's",
        100.0 * e_wrong,
        100.0 * (e_wrong - e_grid).abs()
    );
    assert!((e_wrong - e_grid).abs() > 1e-3, "the agreement check must reject the un-fixed measurement point");
    let (wm, wf) = (last(&mpm, &hm, "strain_energy"), last(&fem, &hf, "strain_energy"));
    println!("strain energy: FEM {wf:.9} J, MPM {wm:.9} J (consistency, 1e-9)");
    assert_relative_eq!(wm, wf, max_relative = 1e-9);
}

/// Benchmark 1 with MPM, dynamic: first natural frequency within 5 % of 0.9889 Hz.
#[test]
fn cantilever_mpm_dynamic_frequency() {
    let (sim, h) = run(case("cantilever_mpm_dynamic.json"));
    let k = sim.monitor_names().iter().position(|n| *n == "tip_uy").unwrap();
    let f = frequency(&h.iter().map(|r| (r.0, r.1[k])).collect::<Vec<_>>());
    report("MPM first natural frequency [Hz]", f, 0.9889, 0.05);
}

/// Benchmark 1 with MPM, dynamic, under modified Newton (`solver.tangent_reuse` `auto`): the
/// first natural frequency within 5 % of 0.9889 Hz as under full Newton, with at most half
/// the factorisations (measured over the 300 steps: 298 against 901, with 1 152 solves by
/// kept factors, which also serve the steps' first iterations), and the tip at the end within
/// the Newton tolerance's reach of the full-Newton run (consistency, 1e-5 relative).
#[test]
fn cantilever_mpm_dynamic_frequency_under_modified_newton() {
    let full = run(case("cantilever_mpm_dynamic.json"));
    let mut json = case_json("cantilever_mpm_dynamic.json");
    json["solver"]["tangent_reuse"] = serde_json::json!("auto");
    let modified = run(parse(json));
    let tip = |(sim, h): &(loam::simulation::Simulation, common::History)| {
        let k = sim.monitor_names().iter().position(|n| *n == "tip_uy").unwrap();
        h.iter().map(|r| (r.0, r.1[k])).collect::<Vec<_>>()
    };
    let f = frequency(&tip(&modified));
    report("MPM first natural frequency under modified Newton [Hz]", f, 0.9889, 0.05);
    let factorisations = |s: &loam::simulation::Simulation| s.model.solver_timings().factorisations;
    let (n_full, n_modified) = (factorisations(&full.0), factorisations(&modified.0));
    let reused = modified.0.model.solver_timings().reused_factors;
    println!(
        "factorisations over the run: full Newton {n_full}, modified {n_modified} ({reused} solves with kept factors)"
    );
    assert!(2 * n_modified <= n_full, "modified Newton must at least halve the factorisations");
    let (a, b) = (tip(&full).last().unwrap().1, tip(&modified).last().unwrap().1);
    println!("tip at the end: full Newton {a:.7} m, modified {b:.7} m (consistency, 1e-5)");
    assert!((a - b).abs() <= 1e-5 * a.abs(), "modified Newton moved the converged answer");
}

/// Benchmark 2 with MPM: axisymmetric plate (h = t/8), on quadrilateral and triangular
/// grids. **Measured:** the mid-surface's deflection at the centre relative to the
/// mid-surface at the support radius, `w(0, t/2) − w(a, t/2)`, from the grid nodes there (one
/// static step: the grid holds the step's displacement). Plate theory's deflection is that
/// of the mid-surface with the mid-surface fixed at the support; the case supports the bottom
/// fibre on a single ring of nodes, whose local indentation is logarithmically singular and
/// keeps growing under refinement (`tests/convergence.rs`), so the centre point's own
/// deflection (printed) does not converge to plate theory. **Reference:** Mindlin,
/// Kirchhoff's 0.07604 m (BENCHMARKS.md: 0.0760 m, 3 %) plus the shear deflection
/// q a²/(4 κ G t) = 0.00076 m. **Tolerance** 1 %: the discretisation error at h = t/8, from
/// the refinement study (order 2, limits within 0.02 % of Mindlin), is 0.33 % (quad) and
/// 0.62 % (tri). The support carries the load q π a² (equilibrium, 1e-9).
#[test]
fn plate_axisym_mpm_quads_and_triangles() {
    let (a, t, e, nu, q) = (10.0f64, 1.0f64, 1.0e7, 0.24, 101.84);
    let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
    let kirchhoff = -(5.0 + nu) * q * a.powi(4) / (64.0 * (1.0 + nu) * d);
    let mindlin = kirchhoff - q * a * a / (4.0 * 5.0 / 6.0 * e / (2.0 * (1.0 + nu)) * t);
    for (element, ppc) in [("quad4", 4), ("tri3", 3)] {
        let mut c = case_json("plate_axisym_mpm.json");
        c["domains"][0]["grid"]["element"] = serde_json::json!(element);
        c["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["element"] = serde_json::json!(element);
        c["domains"][0]["material_points"]["cells"]["points_per_cell"] = serde_json::json!(ppc);
        let monitors = c["monitors"].as_array_mut().expect("monitors");
        monitors.push(
            serde_json::json!({ "name": "grid_centre", "type": "displacement", "point": [0.0, 0.5], "component": "y" }),
        );
        monitors.push(
            serde_json::json!({ "name": "grid_edge", "type": "displacement", "point": [10.0, 0.5], "component": "y" }),
        );
        let (sim, h) = run(parse(c));
        assert_eq!(sim.stats.steps, 1, "one static step");
        let relative = last(&sim, &h, "grid_centre") - last(&sim, &h, "grid_edge");
        println!(
            "plate {element}: w(0) − w(a) at mid-surface {relative:.6} m; Kirchhoff {kirchhoff:.6} m ({:+.2} %), Mindlin \
             {mindlin:.6} m; centre point's own deflection {:.6} m (support indentation included)",
            100.0 * (relative / kirchhoff - 1.0),
            last(&sim, &h, "centre_uy")
        );
        report(&format!("plate {element}: w(0) − w(a) vs Mindlin [m]"), relative, mindlin, 0.01);
        report("support reaction [N]", last(&sim, &h, "support_reaction"), q * std::f64::consts::PI * a * a, 1e-9);
    }
}

/// Benchmark 3: axial vibration of a bar in its first mode (h = 1 m, Δt = 0.1 s). Period
/// 2π/ω₁ = 10 s and the velocity amplitude v₀ sin(πx_p/2L) at the free-end material point
/// (at its own position x_p) within 1 % over five periods; total energy drift below 1 %.
///
/// Valid only while no material point crosses a cell boundary: the outermost points start at
/// x_p = 24.789 m and swing by ±0.159 m, so they stay 5 mm inside their cell; asserted below.
/// Refined at this amplitude (h ≤ 0.5 m) they cross into the empty cell beyond the bar and
/// the energy falls (the cell-crossing error of linear-shape-function MPM; docs/validation.md, "What is
/// not validated"); `tests/convergence.rs` refines at a tenth of the amplitude.
#[test]
fn vibrating_bar_period_amplitude_energy() {
    let (sim, h) = run(case("vibrating_bar_mpm.json"));
    let col = |n: &str| sim.monitor_names().iter().position(|m| *m == n).unwrap();
    let (kv, ke, ks) = (col("end_vx"), col("kinetic_energy"), col("strain_energy"));
    let (x_end, _) = nearest_point(&sim, &[25.0, 0.5]);
    let swing = h.iter().map(|r| r.1[col("end_ux")].abs()).fold(0.0, f64::max);
    println!(
        "outermost point: X = {:.4} m, largest |u_x| {swing:.4} m: stays {:.1} mm inside its cell [24, 25]",
        x_end[0],
        1e3 * (25.0 - x_end[0] - swing)
    );
    assert!(x_end[0] + swing < 25.0, "the bar's outer points must not cross a cell boundary");
    let mut crossings = Vec::new();
    for w in h.windows(2) {
        let (a, b) = (w[0].1[kv], w[1].1[kv]);
        if a > 0.0 && b <= 0.0 {
            crossings.push(w[0].0 + (w[1].0 - w[0].0) * a / (a - b));
        }
    }
    assert!(crossings.len() >= 5, "five periods: {crossings:?}");
    let period = (crossings.last().unwrap() - crossings[0]) / (crossings.len() - 1) as f64;
    let (l, e, rho, v0) = (25.0f64, 100.0f64, 1.0f64, 0.1);
    let omega = std::f64::consts::PI / (2.0 * l) * (e / rho).sqrt();
    report("bar period [s]", period, 2.0 * std::f64::consts::PI / omega, 0.01);
    let x_p = x_end[0];
    let amplitude_exact = v0 * (std::f64::consts::PI * x_p / (2.0 * l)).sin();
    let last_period: Vec<f64> = h.iter().filter(|r| r.0 > h.last().unwrap().0 - 10.0).map(|r| r.1[kv].abs()).collect();
    report(
        "bar velocity amplitude in the 5th period [m/s]",
        last_period.iter().fold(0.0, |a: f64, &b| a.max(b)),
        amplitude_exact,
        0.01,
    );
    let energy: Vec<f64> = h.iter().map(|r| r.1[ke] + r.1[ks]).collect();
    let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max) / energy[0];
    println!(
        "bar total energy: initial {:.6e} J (exact ρ v₀² L/4 = {:.6e}), largest drift {:.3} % (tolerance 1 %)",
        energy[0],
        rho * v0 * v0 * l / 4.0,
        drift * 100.0
    );
    assert!(drift < 0.01);
}

/// Benchmark 4: two elastic disks collide on one grid (Sulsky et al. 1994). The total
/// energy stays within 5 % of the initial kinetic energy through the collision, kinetic
/// energy is largely turned into strain energy at the peak, and the disks rebound.
#[test]
fn disk_collision_energy_and_rebound() {
    let (sim, h) = run(case("disk_collision_mpm.json"));
    let col = |n: &str| sim.monitor_names().iter().position(|m| *m == n).unwrap();
    let (ke, ks, kv) = (col("kinetic_energy"), col("strain_energy"), col("centre_a_vx"));
    let e0 = h[0].1[ke];
    let worst = h.iter().map(|r| (r.1[ke] + r.1[ks] - e0).abs() / e0).fold(0.0, f64::max);
    let min_kinetic = h.iter().map(|r| r.1[ke]).fold(f64::MAX, f64::min);
    println!(
        "disks: initial energy {e0:.4} J (exact 2 · ½ m |v|² = {:.4} J), largest total-energy error {:.2} % (tolerance 5 %), smallest kinetic energy {:.1} % of initial",
        2.0 * 0.5 * 1000.0 * std::f64::consts::PI * 0.04 * 0.02,
        worst * 100.0,
        100.0 * min_kinetic / e0
    );
    assert!(worst < 0.05);
    assert!(min_kinetic < 0.2 * e0, "the collision stores most of the energy as strain energy");
    let vx_end = h.last().unwrap().1[kv];
    println!("disk A centre velocity: initial +0.1 m/s, final {vx_end:.4} m/s (rebound)");
    assert!(vx_end < -0.05);
}

/// 3D: the cantilever of benchmark 1 on a hex8 background grid (h = 1/6 m) with 8 material
/// points per cell: the point nearest (7, 0.5, 0.5), at its own position X_p, against
/// Timoshenko at X_p within 5 % (BENCHMARKS.md, MPM; only 6 cells through the depth).
#[test]
fn hex_grid_mpm_cantilever_matches_beam_theory() {
    let text = r#"{
        "description": "3D MPM cantilever", "formulation": "3d",
        "materials": {"beam": {"law": "neo_hookean", "density": 1000, "young_modulus": 9.0e7, "poisson_ratio": 0.0}},
        "domains": [{"name": "beam", "type": "mpm", "material": "beam",
            "grid": {"origin": [0, -1, 0], "size": [8, 2.5, 1], "cells": [48, 15, 2], "element": "hex8"},
            "material_points": {"cells": {"mesh": {"box": {"origin": [0, 0, 0], "size": [7, 1, 1], "cells": [42, 6, 2], "element": "hex8"}},
                                          "points_per_cell": 8}}}],
        "regions": {"clamp": {"x": 0.0}},
        "boundary_conditions": [{"region": "clamp", "displacement": [0, 0, 0]}],
        "gravity": {"acceleration": [0, -9.81, 0]},
        "analysis": {"type": "static", "time_step": 1, "end_time": 1},
        "monitors": [{"name": "tip_uy", "type": "material_point_displacement", "point": [7, 0.5, 0.5], "component": "y"}]
    }"#;
    let (sim, _) = run(Case::parse(text).unwrap());
    let (x_p, u_p) = nearest_point(&sim, &[7.0, 0.5, 0.5]);
    println!(
        "point at X_p = ({:.4}, {:.4}, {:.4}); Euler–Bernoulli there {:.5} m",
        x_p[0],
        x_p[1],
        x_p[2],
        euler_bernoulli(x_p[0])
    );
    report("hex-grid MPM cantilever: point deflection vs Timoshenko at X_p [m]", u_p[1], timoshenko(x_p[0]), 0.05);
}

/// Benchmark 7: a block on a frictionless slip boundary inclined at 30° (a rotated grid,
/// slip by local rotation of the boundary nodes' DOFs) slides with acceleration g sin α:
/// displacement along the slope ½ g sin α t² within 2 %, and no motion into the slope.
#[test]
fn block_slides_on_inclined_slip_boundary() {
    let (sim, h) = run(case("slip_slope_mpm.json"));
    let (ux, uy) = (last(&sim, &h, "centre_ux"), last(&sim, &h, "centre_uy"));
    let alpha = 30f64.to_radians();
    let t = h.last().unwrap().0;
    let along = ux * alpha.cos() + uy * alpha.sin();
    let normal = -ux * alpha.sin() + uy * alpha.cos();
    report("slide along the 30° slope at t = 0.5 s [m]", along, -0.5 * 9.81 * alpha.sin() * t * t, 0.02);
    println!("motion normal to the slope: {normal:.2e} m (elastic compression only; asserted |·| < 1 mm)");
    assert!(normal.abs() < 1e-3);
}

/// Consistency check: the bin-searched background grid (any mesh, `grid_mesh`) on the same
/// cells as the structured grid gives the same MPM cantilever to round-off (1e-10 m), on
/// quads and triangles.
#[test]
fn unstructured_grid_with_bin_search_equals_structured_grid() {
    for element in [ElementType::Quad4, ElementType::Tri3] {
        let mut structured = case("cantilever_mpm.json");
        structured.domains[0].grid.as_mut().unwrap().element = element;
        if let Some(loam::case::BodySpec::Cells {
            mesh: loam::case::MeshSpec::Rectangle { element: e, .. },
            points_per_cell,
        }) = structured.domains[0].material_points.as_mut()
        {
            *e = element;
            *points_per_cell = if element == ElementType::Tri3 { 3 } else { 4 };
        }
        let mut binned = structured.clone();
        binned.domains[0].grid = None;
        binned.domains[0].grid_mesh = Some(loam::case::MeshSpec::Rectangle {
            origin: [0.0, -1.5],
            size: [8.0, 3.0],
            cells: [64, 24],
            element,
            rotation: 0.0,
        });
        let (s1, h1) = run(structured);
        let (s2, h2) = run(binned);
        let (a, b) = (last(&s1, &h1, "tip_uy"), last(&s2, &h2, "tip_uy"));
        println!("{element:?}: tip_uy structured grid {a:.12} m, bin-searched grid {b:.12} m, difference {:.1e} (tolerance 1e-10)", (a - b).abs());
        assert_abs_diff_eq!(a, b, epsilon = 1e-10);
    }
}

/// Particle Neumann condition (issue #4, item 7): the MPM cantilever without gravity under a
/// tip load P = 1000 N carried by its 16 tip material points (x_p = 6.9736 m). Deflection
/// at the load within 3 % of Timoshenko, P a³/(3EI) + P a/(κGA) with a = x_p, κ = 5/6; and
/// the same load as grid nodal forces N_I(x_p) F (worked out by hand below) gives the same
/// deflection to 1e-9 (one static step: the points have not moved yet).
#[test]
fn cantilever_mpm_material_point_load() {
    let (sim, h) = run(case("cantilever_mpm_point_load.json"));
    let tip = last(&sim, &h, "tip_uy");
    let (p, e, nu, kappa) = (1000.0, 9.0e7, 0.0, 5.0 / 6.0);
    let (i, g) = (1.0 / 12.0, e / (2.0 * (1.0 + nu)));
    let xi = 0.5 * (1.0 + 1.0 / 3f64.sqrt()); // outer Gauss coordinate in [0, 1]
    let a = 6.875 + 0.125 * xi;
    let timoshenko = -(p * a.powi(3) / (3.0 * e * i) + p * a / (kappa * g));
    report("tip load on material points: deflection at the load [m]", tip, timoshenko, 0.03);
    report("clamp reaction [N]", last(&sim, &h, "clamp_reaction_y"), p, 1e-9);

    // the same load on the grid: each of the 16 points (62.5 N) in a cell of column
    // [6.875, 7] gives N = ξ to the nodes at x = 7 and 1 − ξ to those at x = 6.875; the two
    // points of a cell row share their y-weights to 1 per node, so an interior node gets two
    // cell rows' worth and the nodes at y = 0 and y = 1 one
    let mut grid = case("cantilever_mpm_point_load.json");
    grid.loads.clear();
    for (x, w) in [(7.0, xi), (6.875, 1.0 - xi)] {
        for (name, lo, hi, share) in [("in", 0.1, 0.9, 2.0), ("bottom", 0.0, 0.0, 1.0), ("top", 1.0, 1.0, 1.0)] {
            let region = format!("{name}_{x}");
            grid.regions.insert(region.clone(), RegionSpec::Box { min: vec![x, lo], max: vec![x, hi] });
            grid.loads.push(LoadSpec::NodalForce {
                name: None,
                region,
                force: vec![0.0, -62.5 * share * w],
                amplitude: Default::default(),
            });
        }
    }
    let (sim2, h2) = run(grid);
    let tip_grid = last(&sim2, &h2, "tip_uy");
    let diff = ((tip - tip_grid) / tip_grid).abs();
    println!("same load as grid nodal forces: {tip_grid:.12} m vs on the points {tip:.12} m, relative difference {diff:.1e} (tolerance 1e-9)");
    assert!(diff < 1e-9);
}

/// Particle Neumann condition moving with the body: the block of benchmark 7 on the
/// horizontal slip boundary (gravity ramped as in `slip_flat_mpm.json`) pushed towards −x by
/// 2000 N carried by its right-hand column of 20 material points, for 1 s. The block slides
/// 1 m (ten cells) and the load stays on it: the centre moves −F t²/(2m) = −1.000 m within
/// 0.5 % (m = 1000 kg per metre of thickness). A grid nodal force would stay on its nodes,
/// which the block leaves after its first cell.
#[test]
fn material_point_load_follows_sliding_block() {
    let mut c = case("slip_flat_mpm.json");
    c.analysis.end_time = 1.0;
    c.loads.push(LoadSpec::MaterialPointForce {
        domain: Some("block".into()),
        point: None,
        within: Some(loam::case::PointBox { min: vec![3.45, 0.0], max: vec![3.5, 1.0] }),
        force: vec![-100.0, 0.0],
        amplitude: Default::default(),
    });
    let (sim, h) = run(c);
    let t = h.last().unwrap().0;
    let ux = last(&sim, &h, "centre_ux");
    report("pushed block: centre displacement at t = 1 s [m]", ux, -2000.0 * t * t / (2.0 * 1000.0), 0.005);
    let uy = last(&sim, &h, "centre_uy");
    println!("centre vertical displacement {uy:.2e} m (stays on the base: asserted |·| < 1e-4 m)");
    assert!(uy.abs() < 1e-4);
}
