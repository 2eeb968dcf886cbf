//! Monolithic MPM–FEM coupling (issue 13): soil as material points and a structure as FEM in
//! one Newton system, through shared interface nodes (tied) or node pairs sharing their
//! normal DOF (frictionless slip). Every test prints measured vs reference and fails for a
//! wrong coupling.

mod common;

use common::{case, last, monitor, report, run};
use loam::case::Case;
use loam::simulation::Simulation;
use loam_fem::dofs::Block;

/// A slab of FEM (clamped at its base) under a block of Mohr–Coulomb soil as material
/// points, joined on the slab's top face by an interface (`slip` or tied), dynamic.
fn slab_and_soil(slip: bool) -> Case {
    let text = format!(
        r#"{{
  "description": "FEM slab under MC soil, coupled on the slab's top face",
  "materials": {{
    "slab": {{ "law": "neo_hookean", "density": 2500.0, "young_modulus": 3.0e7, "poisson_ratio": 0.2 }},
    "soil": {{ "law": "mohr_coulomb", "density": 1800.0, "young_modulus": 1.0e6, "poisson_ratio": 0.3,
              "friction_angle": 30.0, "cohesion": 1000.0, "dilatancy_angle": 5.0 }}
  }},
  "domains": [
    {{ "name": "slab", "type": "fem", "material": "slab",
       "mesh": {{ "rectangle": {{ "origin": [0.0, -0.1], "size": [0.4, 0.1], "cells": [4, 2], "element": "quad4" }} }} }},
    {{ "name": "soil", "type": "mpm", "material": "soil",
       "grid": {{ "origin": [0.0, 0.0], "size": [0.4, 0.3], "cells": [4, 3], "element": "quad4" }},
       "material_points": {{ "cells": {{ "mesh": {{ "rectangle": {{ "origin": [0.0, 0.0], "size": [0.4, 0.2], "cells": [4, 2], "element": "quad4" }} }}, "points_per_cell": 4 }} }} }}
  ],
  "interfaces": [ {{ "name": "top", "soil": "soil", "structure": "slab", "region": "top", "slip": {slip} }} ],
  "regions": {{ "base": {{ "y": -0.1 }}, "top": {{ "y": 0.0 }} }},
  "boundary_conditions": [ {{ "region": "base", "displacement": [0.0, 0.0] }} ],
  "gravity": {{ "acceleration": [0.0, -9.81] }},
  "analysis": {{ "type": "dynamic", "time_step": 0.01, "end_time": 1.0 }},
  "output": {{ "vtk": false }}
}}"#
    );
    Case::parse(&text).expect("case parses")
}

/// The consistent tangent of the coupled system is the derivative of its residual: central
/// differences of `R(δu)` at a correction `δu₀` large enough to make the soil's points
/// plastic (Mohr–Coulomb returns), compared entry by entry in every block row (soil,
/// interface, structure), tied and slip; relative error < 1e-6 of the block's largest entry.
#[test]
fn coupled_tangent_matches_finite_differences() {
    for slip in [false, true] {
        let mut sim = Simulation::new(slab_and_soil(slip)).expect("builds");
        let mut lin = sim.model.linearise(0.01).expect("step starts");
        let n = lin.num_equations();
        // a smooth deformation δu₀ of ~1e-3 m (strains ~1e-2: the soil yields)
        let delta0: Vec<f64> = (0..n).map(|e| 1e-3 * ((e * 7919 % 23) as f64 / 23.0 - 0.3)).collect();
        let (_, k) = lin.evaluate(&delta0).expect("assembles");
        let h = 1e-8;
        let mut worst = [0.0f64; 3];
        let mut scale = [0.0f64; 3];
        for j in 0..n {
            let mut plus = delta0.clone();
            plus[j] += h;
            let mut minus = delta0.clone();
            minus[j] -= h;
            let (rp, _) = lin.evaluate(&plus).unwrap();
            let (rm, _) = lin.evaluate(&minus).unwrap();
            for i in 0..n {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                let b = lin.block(i) as usize;
                worst[b] = worst[b].max((fd - k[i * n + j]).abs());
                scale[b] = scale[b].max(k[i * n + j].abs());
            }
        }
        for (b, name) in [(Block::Soil, "soil"), (Block::Interface, "interface"), (Block::Structure, "structure")] {
            let (w, s) = (worst[b as usize], scale[b as usize]);
            println!(
                "{} interface, {name} rows: max |K − K_FD| = {w:.3e}, max |K| = {s:.3e}, relative {:.2e} (tolerance 1e-6)",
                if slip { "slip" } else { "tied" },
                w / s
            );
            assert!(s > 0.0, "the {name} block has entries");
            assert!(w <= 1e-6 * s, "{name} block: tangent off its finite differences");
        }
        drop(lin);
    }
}

/// A uniform stress state across the interface: a 1 m × 1 m FEM square tied to a 1 m × 1 m
/// square of material points (4 per cell at the Gauss positions), stretched by 0.2 % along x
/// with free top and roller base: every Gauss point and every material point carries the
/// closed-form stress of the law to 1e-10. (The small-strain law gives the first
/// Piola–Kirchhoff stress `P_xx = E/(1 − ν²) ε`, `P_yy = 0` with `ε_y = −ν/(1 − ν) ε`; the
/// Cauchy stress is `σ_xx = P_xx / (1 + ε_y)`.)
#[test]
fn uniform_stress_patch_across_the_interface() {
    let text = r#"{
  "description": "patch test across an MPM-FEM interface",
  "materials": { "m": { "law": "linear_elastic", "density": 1000.0, "young_modulus": 1.0e7, "poisson_ratio": 0.3 } },
  "domains": [
    { "name": "left", "type": "fem", "material": "m",
      "mesh": { "rectangle": { "origin": [0.0, 0.0], "size": [1.0, 1.0], "cells": [4, 4], "element": "quad4" } } },
    { "name": "right", "type": "mpm", "material": "m",
      "grid": { "origin": [1.0, 0.0], "size": [1.0, 1.0], "cells": [4, 4], "element": "quad4" },
      "material_points": { "cells": { "mesh": { "rectangle": { "origin": [1.0, 0.0], "size": [1.0, 1.0], "cells": [4, 4], "element": "quad4" } }, "points_per_cell": 4 } } }
  ],
  "interfaces": [ { "name": "cut", "soil": "right", "structure": "left", "region": "cut" } ],
  "regions": { "cut": { "x": 1.0 }, "left_end": { "x": 0.0 }, "right_end": { "x": 2.0 }, "base": { "y": 0.0 } },
  "boundary_conditions": [
    { "region": "left_end", "displacement": [0.0, null] },
    { "region": "right_end", "displacement": [0.004, null] },
    { "region": "base", "displacement": [null, 0.0] }
  ],
  "analysis": { "type": "static", "time_step": 1.0, "end_time": 1.0 },
  "solver": { "residual_relative_tolerance": 1e-12, "residual_absolute_tolerance": 1e-9 },
  "output": { "vtk": false }
}"#;
    let (sim, _) = run(Case::parse(text).unwrap());
    let (e, nu, eps) = (1.0e7, 0.3, 0.002);
    let expected = e / (1.0 - nu * nu) * eps / (1.0 - nu / (1.0 - nu) * eps);
    let mut worst = 0.0f64;
    for name in ["left", "right"] {
        let out = sim.model.output(name).unwrap();
        let (fields, per) = if name == "left" {
            (&out.cell_fields, out.cell_fields[0].values.len() / 9)
        } else {
            (&out.point_fields, out.points.len())
        };
        let stress = &fields.iter().find(|f| f.name == "cauchy_stress").unwrap().values;
        for p in 0..per {
            worst = worst.max((stress[9 * p] - expected).abs() / expected).max(stress[9 * p + 4].abs() / expected);
        }
        println!("{name}: {per} stress points");
    }
    println!("uniform stress across the interface: sigma_xx = {expected:.3} Pa expected, largest relative deviation {worst:.2e} (tolerance 1e-10)");
    assert!(worst < 1e-10);
}

/// Timoshenko deflection `w(x) = q/(24EI)(x⁴ − 4Lx³ + 6L²x²) + q(Lx − x²/2)/(κGA)` of the
/// cantilever of benchmark 12 (q = ρgA = 9810 N/m, EI = 7.5e6 N m², κGA = 5/6 · 4.5e7 N).
fn timoshenko(x: f64) -> f64 {
    let (q, l, ei, kga) = (9810.0, 8.0, 9.0e7 / 12.0, 5.0 / 6.0 * 4.5e7);
    -(q / (24.0 * ei) * (x.powi(4) - 4.0 * l * x.powi(3) + 6.0 * l * l * x * x) + q * (l * x - x * x / 2.0) / kga)
}

/// The whole beam as one FEM domain at the coupled cases' h = 0.05 m, static, in the same
/// 4 load steps: the single-domain reference the split beams are compared with. Returns its
/// vertical displacement at the reference point `(x, y)` (bilinear interpolation of the
/// nodal field) and at the interface node (4, 0.5).
fn single_domain_beam(x: f64, y: f64) -> (f64, f64) {
    let mut c = case("coupled_beam_split.json");
    c.interfaces.clear();
    c.domains.truncate(1);
    if let Some(loam::case::MeshSpec::Rectangle { size, cells, .. }) = c.domains[0].mesh.as_mut() {
        *size = [8.0, 1.0];
        *cells = [160, 20];
    }
    c.monitors.retain(|m| m.name() == "interface_uy" || m.name() == "clamp_reaction_y");
    let (sim, h) = run(c);
    let out = sim.model.output("beam_fem").unwrap();
    let u = &out.point_fields.iter().find(|f| f.name == "displacement").unwrap().values;
    // node (i, j) of the 161 × 21 structured mesh
    let (fx, fy) = (x / 0.05, y / 0.05);
    let (i, j) = (fx.floor().min(159.0) as usize, fy.floor().min(19.0) as usize);
    let (s, t) = (fx - i as f64, fy - j as f64);
    let node = |i: usize, j: usize| j * 161 + i;
    let w = (1.0 - s) * (1.0 - t) * u[3 * node(i, j) + 1]
        + s * (1.0 - t) * u[3 * node(i + 1, j) + 1]
        + s * t * u[3 * node(i + 1, j + 1) + 1]
        + (1.0 - s) * t * u[3 * node(i, j + 1) + 1];
    (w, last(&sim, &h, "interface_uy"))
}

/// Benchmark 12, FEM on [0, 4] and material points on [4, 8] (`cases/coupled_beam_split.json`):
/// the tip point (x₀ = 7.989 m) within 1.5 % of Timoshenko at its own x and of −0.67806 m at
/// the free end, and within 1 % of the single-domain FEM beam at the same h at the same
/// point; the clamp carries the whole weight and the interface the MPM half's, to 1e-9.
#[test]
fn beam_split_fem_clamped_mpm_free() {
    let (sim, h) = run(case("coupled_beam_split.json"));
    let tip = last(&sim, &h, "tip_uy");
    let (k, id) = tip_point(&sim);
    let x0 = sim.model.domains[k].point_quantity(id, loam_fem::domain::PointQuantity::Position).unwrap();
    let u = sim.model.domains[k].point_quantity(id, loam_fem::domain::PointQuantity::Displacement).unwrap();
    let (x, y) = (x0[0] - u[0], x0[1] - u[1]);
    println!("tip point at its initial position ({x:.4}, {y:.4})");
    report("coupled tip deflection vs Timoshenko at the point [m]", tip, timoshenko(x), 0.015);
    report("coupled tip deflection vs Timoshenko at the free end [m]", tip, -0.67806, 0.015);
    let (single, single_interface) = single_domain_beam(x, y);
    report("coupled tip deflection vs single-domain FEM (h = 0.05 m) at the point [m]", tip, single, 0.01);
    report(
        "coupled interface deflection vs single-domain FEM at (4, 0.5) [m]",
        last(&sim, &h, "interface_uy"),
        single_interface,
        0.01,
    );
    report("clamp reaction = weight of the beam [N]", last(&sim, &h, "clamp_reaction_y"), 78480.0, 1e-9);
    report("interface force = weight of the MPM half [N]", last(&sim, &h, "interface_force_y"), -39240.0, 1e-9);
}

/// The material point that the `tip_uy` monitor follows.
fn tip_point(sim: &Simulation) -> (usize, usize) {
    match &sim.monitors[monitor(sim, "tip_uy")].kind {
        loam::monitor::MonitorKind::MaterialPoint { domain, id, .. } => (*domain, *id),
        other => panic!("tip_uy follows a material point, not {other:?}"),
    }
}

/// Benchmark 12 split the other way (`cases/coupled_beam_split_mpm_clamped.json`): material
/// points on the clamped half, FEM on the free half; the tip node within 1.5 % of −0.67806 m
/// and within 1 % of the single-domain FEM beam there; reactions exact.
#[test]
fn beam_split_mpm_clamped_fem_free() {
    let (sim, h) = run(case("coupled_beam_split_mpm_clamped.json"));
    let tip = last(&sim, &h, "tip_uy");
    report("coupled tip deflection (node (8, 0.5)) vs Timoshenko [m]", tip, -0.67806, 0.015);
    let (single, single_interface) = single_domain_beam(8.0, 0.5);
    report("coupled tip deflection vs single-domain FEM (h = 0.05 m) [m]", tip, single, 0.01);
    report(
        "coupled interface deflection vs single-domain FEM [m]",
        last(&sim, &h, "interface_uy"),
        single_interface,
        0.01,
    );
    report("clamp reaction = weight of the beam [N]", last(&sim, &h, "clamp_reaction_y"), 78480.0, 1e-9);
    report("interface force = weight of the FEM half, upward [N]", last(&sim, &h, "interface_force_y"), 39240.0, 1e-9);
}
