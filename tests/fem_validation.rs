//! FEM validation (issue 2): benchmark 1 (static and dynamic cantilever), patch tests of
//! every element type and formulation, Lamé's thick cylinder
//! (axisymmetric), a 3D hex8 cantilever, and two domains sharing interface nodes.
//! Each test prints measured vs reference and asserts its tolerance.

mod common;

use approx::assert_abs_diff_eq;
use std::sync::Arc;

use common::{case, euler_bernoulli, frequency, monitor, report, run as run_to_end, timoshenko};
use loam::case::Case;
use loam_fem::element::ElementType;
use loam_fem::formulation::Formulation;
use loam_fem::mesh::Mesh;
use loam_fem::model::{Constraint, Model, NewtonSettings};
use loam_fem::scheme::TimeScheme;
use loam_fem::solid_domain::FemDomain;
use loam_laws::neo_hookean::NeoHookean;
use nalgebra::Matrix3;

/// Benchmark 1, static, quad4 56 × 8: the tip node's deflection (7, 0.5) against Timoshenko
/// at x = 7, −0.39897 m (Euler–Bernoulli q L⁴/(8 E I) = −0.39256 m, BENCHMARKS.md, plus the
/// shear deflection q L²/(2 κ G A) = −0.00641 m). Tolerance 2 %: the discretisation error
/// at 8 cells through the depth is 0.8 % and the geometric nonlinearity 0.24 %
/// (`tests/convergence.rs`: order 2, Richardson limit −0.3980 m); measured −1.03 %.
/// BENCHMARKS.md allows 3 % against Euler–Bernoulli (printed).
#[test]
fn cantilever_static_tip_deflection() {
    let (sim, h) = run_to_end(case("cantilever_fem.json"));
    let tip = h.last().unwrap().1[monitor(&sim, "tip_uy")];
    println!(
        "Euler–Bernoulli at x = 7: {:.5} m ({:+.2} %)",
        euler_bernoulli(7.0),
        100.0 * (tip / euler_bernoulli(7.0) - 1.0)
    );
    report("benchmark 1 static tip_uy vs Timoshenko [m]", tip, timoshenko(7.0), 0.02);
    // the clamp carries the weight ρ g L h b
    let reaction = h.last().unwrap().1[monitor(&sim, "clamp_reaction_y")];
    report("clamp reaction [N]", reaction, 1000.0 * 9.81 * 7.0, 1e-9);
}

/// Benchmark 1, dynamic: first natural frequency 0.9889 Hz from the tip history, 3 %.
#[test]
fn cantilever_dynamic_natural_frequency() {
    let (sim, h) = run_to_end(case("cantilever_fem_dynamic.json"));
    let k = monitor(&sim, "tip_uy");
    let frequency = frequency(&h.iter().map(|r| (r.0, r.1[k])).collect::<Vec<_>>());
    report("benchmark 1 first natural frequency [Hz]", frequency, 0.9889, 0.03);
}

/// Benchmark 1, dynamic, with the step length set by the local time-integration error
/// (`analysis.adaptive.error_tolerance`: Zienkiewicz & Xie's estimate `Δt² |β − 1/6| |Δa|`).
/// Gravity is ramped in as `sin²(π t / 2 t_r)` over `t_r` = 0.5 s (a table every 0.025 s), so
/// that the beam swings in its first mode and the higher modes, which the steps do not
/// resolve, stay quiet. Asserted: the first natural frequency of the free swing after the ramp
/// within 3 % of Euler–Bernoulli's 0.9889 Hz at two tolerances 8× apart, and their step
/// counts in the ratio 8^(1/3) = 2 that a local error of third order in Δt gives (within
/// 1.8–2.3: second order would give 2.8, fourth order 1.7, an estimate without its Δt² 8).
/// Measured: 177 and 353 steps (1.99), 0.9807 and 0.9815 Hz. With gravity applied suddenly
/// (the bundled case) the ratio is 2.35 (579 and 1 359 steps): the jump excites modes above
/// 1/Δt, whose `Δa` does not shrink with Δt.
#[test]
fn cantilever_dynamic_steps_follow_the_local_error() {
    let run_at = |tolerance: f64| {
        let mut json = common::case_json("cantilever_fem_dynamic.json");
        json["analysis"]["adaptive"] =
            serde_json::json!({ "min_time_step": 1e-5, "max_time_step": 0.1, "error_tolerance": tolerance });
        let ramp: Vec<[f64; 2]> = (0..=20)
            .map(|k| {
                let t = 0.025 * k as f64;
                [t, (std::f64::consts::PI * t / 1.0).sin().powi(2)]
            })
            .collect();
        json["gravity"]["amplitude"] = serde_json::json!(ramp);
        let (sim, h) = run_to_end(common::parse(json));
        let k = monitor(&sim, "tip_uy");
        let swing: Vec<(f64, f64)> = h.iter().filter(|r| r.0 >= 0.5).map(|r| (r.0, r.1[k])).collect();
        let f = frequency(&swing);
        println!("error tolerance {tolerance:.2e} m: {} steps, first natural frequency {f:.4} Hz", sim.stats.steps);
        (sim.stats.steps as f64, f)
    };
    let (coarse_steps, coarse) = run_at(8e-6);
    let (fine_steps, fine) = run_at(1e-6);
    report("first natural frequency, error tolerance 8e-6 m [Hz]", coarse, 0.9889, 0.03);
    report("first natural frequency, error tolerance 1e-6 m [Hz]", fine, 0.9889, 0.03);
    let ratio = fine_steps / coarse_steps;
    println!("steps at 1e-6 / at 8e-6: {ratio:.3} (third order: 8^(1/3) = 2)");
    assert!((1.8..=2.3).contains(&ratio), "steps ratio {ratio:.3} is not that of a third-order local error");
}

fn neo_hookean() -> Arc<NeoHookean> {
    Arc::new(NeoHookean::new(1000.0, 1.0e6, 0.3))
}

/// A mesh of the unit square/cube with interior nodes moved off the lattice.
fn distorted_patch(element: ElementType) -> Mesh {
    let mut mesh = match element.dim() {
        2 => Mesh::rectangle([1.0, 0.0], [1.0, 1.0], [3, 3], element),
        _ => Mesh::cuboid([0.0; 3], [1.0; 3], [2, 2, 2], element),
    };
    let dim = element.dim();
    for (n, c) in mesh.coords.iter_mut().enumerate() {
        let interior = (0..dim).all(|d| {
            let lo = if d == 0 && dim == 2 { 1.0 } else { 0.0 };
            c[d] > lo + 1e-9 && c[d] < lo + 1.0 - 1e-9
        });
        if interior {
            for d in 0..dim {
                c[d] += 0.08 * ((n * 7 + d * 3) as f64).sin();
            }
        }
    }
    mesh
}

/// Patch test: a uniform deformation gradient prescribed on the boundary is reproduced
/// inside a distorted patch to 1e-10, for every element type and 2D formulation.
#[test]
fn patch_test_every_element_and_formulation() {
    let cases = [
        (ElementType::Tri3, Formulation::PlaneStrain),
        (ElementType::Quad4, Formulation::PlaneStrain),
        (ElementType::Tri3, Formulation::PlaneStress),
        (ElementType::Quad4, Formulation::PlaneStress),
        (ElementType::Tri3, Formulation::Axisymmetric),
        (ElementType::Quad4, Formulation::Axisymmetric),
        (ElementType::Tet4, Formulation::ThreeD),
        (ElementType::Hex8, Formulation::ThreeD),
    ];
    for (element, formulation) in cases {
        let mesh = distorted_patch(element);
        let dim = element.dim();
        // axisymmetry admits no uniform shear (σ_rz / r would be out of balance) and
        // u_r = a r only (the hoop stretch 1 + u_r/r must be uniform)
        let f = match formulation {
            Formulation::Axisymmetric => Matrix3::new(1.1, 0.0, 0.0, 0.0, 0.9, 0.0, 0.0, 0.0, 1.1),
            Formulation::ThreeD => Matrix3::new(1.1, 0.2, -0.05, 0.1, 0.92, 0.03, 0.02, -0.1, 1.05),
            _ => Matrix3::new(1.1, 0.2, 0.0, 0.1, 0.92, 0.0, 0.0, 0.0, 1.0),
        };
        let exact = |x: &[f64; 3]| {
            let v = (f - Matrix3::identity()) * nalgebra::Vector3::from(*x);
            [v[0], v[1], v[2]]
        };
        let boundary: std::collections::BTreeSet<usize> = mesh.boundary_facets().into_iter().flatten().collect();
        let coords = mesh.coords.clone();
        let n = coords.len();
        let domain = FemDomain::new("patch", mesh, (0..n).collect(), formulation, 1.0, neo_hookean(), false).unwrap();
        let settings = NewtonSettings {
            residual_relative_tolerance: 1e-13,
            residual_absolute_tolerance: 1e-12,
            ..Default::default()
        };
        let mut model = Model::new(dim, coords.clone(), TimeScheme::Static, settings);
        model.domains.push(Box::new(domain));
        let mut c = Constraint { dofs: vec![], values: vec![], amplitude: Default::default() };
        for &b in &boundary {
            for d in 0..dim {
                c.dofs.push(b * dim + d);
                c.values.push(exact(&coords[b])[d]);
            }
        }
        model.constraints.push(c);
        model.solve_step(1.0).expect("patch converges");
        let mut err = 0.0f64;
        for (node, x) in coords.iter().enumerate().filter(|(k, _)| !boundary.contains(k)) {
            for d in 0..dim {
                err = err.max((model.committed.u[node * dim + d] - exact(x)[d]).abs());
            }
        }
        let out = model.outputs(false).remove(0).output;
        let stress = &out.cell_fields.iter().find(|f| f.name == "cauchy_stress").unwrap().values;
        let spread = (0..9)
            .map(|k| {
                let v: Vec<f64> = stress.iter().skip(k).step_by(9).copied().collect();
                v.iter().fold(f64::MIN, |a, &b| a.max(b)) - v.iter().fold(f64::MAX, |a, &b| a.min(b))
            })
            .fold(0.0, f64::max);
        println!("patch {element:?} {formulation:?}: max interior displacement error {err:.2e} m, stress spread {spread:.2e} Pa (tolerances 1e-10 m, 1e-10 × μ)");
        assert!(err < 1e-10, "{element:?} {formulation:?}");
        assert!(spread < 1e-10 * 1e6 / 2.6, "{element:?} {formulation:?}");
    }
}

/// Lamé's thick cylinder under internal pressure (axisymmetric, plane strain along the
/// axis): `u_r(r) = (1+ν) a² p / (E (b² − a²)) ((1 − 2ν) r + b²/r)`, within 1 %.
#[test]
fn thick_cylinder_matches_lame() {
    for element in ["quad4", "tri3"] {
        let text = format!(
            r#"{{
            "description": "thick cylinder", "formulation": "axisymmetric",
            "materials": {{"steel": {{"law": "neo_hookean", "density": 7800, "young_modulus": 2.0e8, "poisson_ratio": 0.3}}}},
            "domains": [{{"name": "cylinder", "material": "steel",
                "mesh": {{"rectangle": {{"origin": [1.0, 0.0], "size": [1.0, 0.25], "cells": [24, 6], "element": "{element}"}}}}}}],
            "regions": {{"inner": {{"x": 1.0}}, "ends": {{"box": {{"min": [1.0, 0.0], "max": [2.0, 0.0]}}}}, "top": {{"y": 0.25}}}},
            "boundary_conditions": [{{"region": "ends", "displacement": [null, 0.0]}}, {{"region": "top", "displacement": [null, 0.0]}}],
            "loads": [{{"type": "pressure", "region": "inner", "pressure": 1.0e4}}],
            "analysis": {{"type": "static", "time_step": 1.0, "end_time": 1.0}},
            "monitors": [{{"name": "ur_inner", "type": "displacement", "point": [1.0, 0.125], "component": "x"}},
                         {{"name": "ur_outer", "type": "displacement", "point": [2.0, 0.125], "component": "x"}}]
        }}"#
        );
        let (sim, h) = run_to_end(Case::parse(&text).unwrap());
        let (a, b, p, e, nu) = (1.0f64, 2.0f64, 1.0e4, 2.0e8, 0.3);
        let lame = |r: f64| (1.0 + nu) * a * a * p / (e * (b * b - a * a)) * ((1.0 - 2.0 * nu) * r + b * b / r);
        let v = &h.last().unwrap().1;
        report(&format!("Lamé u_r(a) {element} [m]"), v[monitor(&sim, "ur_inner")], lame(a), 0.01);
        report(&format!("Lamé u_r(b) {element} [m]"), v[monitor(&sim, "ur_outer")], lame(b), 0.01);
    }
}

/// The cantilever of benchmark 1 in 3D with hex8 elements (42 × 6 × 2, b = 1 m, ν = 0): the
/// tip node (7, 0.5, 0.5) within 3 % (BENCHMARKS.md, FEM) of Timoshenko −0.39897 m (6 cells
/// through the depth lock more than the 2D mesh's 8).
#[test]
fn hex8_cantilever_matches_beam_theory() {
    let text = r#"{
        "description": "3D cantilever", "formulation": "3d",
        "materials": {"beam": {"law": "neo_hookean", "density": 1000, "young_modulus": 9.0e7, "poisson_ratio": 0.0}},
        "domains": [{"name": "beam", "material": "beam",
            "mesh": {"box": {"origin": [0, 0, 0], "size": [7, 1, 1], "cells": [42, 6, 2], "element": "hex8"}}}],
        "regions": {"clamp": {"x": 0.0}},
        "boundary_conditions": [{"region": "clamp", "displacement": [0, 0, 0]}],
        "gravity": {"acceleration": [0, -9.81, 0]},
        "analysis": {"type": "static", "time_step": 1, "end_time": 1},
        "monitors": [{"name": "tip_uy", "type": "displacement", "point": [7, 0.5, 0.5], "component": "y"}]
    }"#;
    let (_, h) = run_to_end(Case::parse(text).unwrap());
    let tip = h.last().unwrap().1[0];
    println!(
        "Euler–Bernoulli at x = 7: {:.5} m ({:+.2} %)",
        euler_bernoulli(7.0),
        100.0 * (tip / euler_bernoulli(7.0) - 1.0)
    );
    report("hex8 cantilever tip_uy vs Timoshenko [m]", tip, timoshenko(7.0), 0.03);
}

/// Consistency check (the coupling seam): the cantilever split into two FEM domains that
/// share the interface nodes at x = 3.5 gives the single-domain answer to 1e-10.
#[test]
fn two_domains_sharing_nodes_equal_one_domain() {
    let single = case("cantilever_fem.json");
    let mut split = single.clone();
    let mut left = split.domains[0].clone();
    left.name = "left".into();
    left.mesh = Some(loam::case::MeshSpec::Rectangle {
        origin: [0.0, 0.0],
        size: [3.5, 1.0],
        cells: [28, 8],
        element: ElementType::Quad4,
        rotation: 0.0,
    });
    let mut right = left.clone();
    right.name = "right".into();
    right.mesh = Some(loam::case::MeshSpec::Rectangle {
        origin: [3.5, 0.0],
        size: [3.5, 1.0],
        cells: [28, 8],
        element: ElementType::Quad4,
        rotation: 0.0,
    });
    split.domains = vec![left, right];
    let (s1, h1) = run_to_end(single);
    let (s2, h2) = run_to_end(split);
    assert_eq!(s1.model.coords.len(), s2.model.coords.len(), "interface nodes are shared, not duplicated");
    let (a, b) = (h1.last().unwrap().1[0], h2.last().unwrap().1[0]);
    println!("tip_uy one domain {a:.12}, two domains {b:.12}, difference {:.2e} (tolerance 1e-10)", (a - b).abs());
    assert_abs_diff_eq!(a, b, epsilon = 1e-10);
}
