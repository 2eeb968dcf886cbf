//! Named inputs of the library API (issue 6): an input that replaces the amplitude of a
//! load, a boundary condition or gravity gives exactly the run of a case whose amplitude
//! table holds the same values; bad names and values are rejected with their JSON path.

use loam::case::Case;
use loam::fem::amplitude::Amplitude;
use loam::simulation::{InputError, Simulation};
use serde_json::{json, Value};

/// A small dynamic cantilever (7 m × 1 m, 14 × 2 quad4, Neo-Hookean) with a named tip
/// load, a named support and gravity, Newmark, Δt = 0.01 s, 0.2 s.
fn base() -> Value {
    json!({
        "description": "small dynamic cantilever for the input tests",
        "materials": { "beam": { "law": "neo_hookean", "density": 1000.0, "young_modulus": 9.0e7, "poisson_ratio": 0.0 } },
        "domains": [ { "name": "beam", "mesh": { "rectangle": { "origin": [0.0, 0.0], "size": [7.0, 1.0], "cells": [14, 2], "element": "quad4" } }, "material": "beam" } ],
        "regions": { "clamp": { "x": 0.0 }, "tip": { "nearest": [7.0, 0.5] } },
        "boundary_conditions": [
            { "name": "support", "region": "clamp", "displacement": [0.0, 1.0], "amplitude": 0.0 }
        ],
        "loads": [ { "name": "tip_load", "type": "nodal_force", "region": "tip", "force": [0.0, -1.0e5], "amplitude": 0.0 } ],
        "gravity": { "acceleration": [0.0, -9.81], "amplitude": 0.0 },
        "analysis": { "type": "dynamic", "time_step": 0.01, "end_time": 0.2 },
        "solver": { "residual_relative_tolerance": 1e-10, "residual_absolute_tolerance": 1e-8 },
        "monitors": [
            { "name": "tip_uy", "type": "displacement", "point": [7.0, 0.5], "component": "y" },
            { "name": "clamp_ry", "type": "reaction", "region": "clamp", "component": "y" }
        ]
    })
}

fn sim(v: &Value) -> Simulation {
    Simulation::new(Case::parse(&v.to_string()).expect("case parses")).expect("case builds")
}

/// The ramp an input follows: 0 at t = 0, 1 at t = 0.1, then back to 0.5 at t = 0.2.
fn ramp(t: f64) -> f64 {
    Amplitude::Table(vec![[0.0, 0.0], [0.1, 1.0], [0.2, 0.5]]).at(t)
}

/// The time the next [`Simulation::step`] ends at, computed as the step computes it (so
/// that the ramp is evaluated at the very time the amplitude table is).
fn next_time(s: &Simulation) -> f64 {
    let target = (s.time() + s.case.analysis.time_step).min(s.end_time());
    s.time() + (target - s.time())
}

/// Runs `with_input` setting `input` to the ramp at the end of each step before the step,
/// and `with_table` (same case, the target's amplitude a table of the ramp); returns the
/// largest relative difference `|a − b| / (1 + |b|)` of any monitor at any step.
fn compare(with_input: &Value, with_table: &Value, input: &str) -> f64 {
    let (mut a, mut b) = (sim(with_input), sim(with_table));
    let mut max_diff: f64 = 0.0;
    let mut moved: f64 = 0.0;
    while !b.finished() {
        a.set_input(input, ramp(next_time(&a))).expect("finite input");
        a.step().expect("step converges");
        b.step().expect("step converges");
        for (x, y) in a.monitor_values().iter().zip(b.monitor_values()) {
            max_diff = max_diff.max((x - y).abs() / (1.0 + y.abs()));
            moved = moved.max(y.abs());
        }
    }
    assert!(moved > 1e-6, "the ramp should move the beam (largest monitor {moved:e})");
    max_diff
}

fn with_fmu_input(mut v: Value, drives: Value) -> Value {
    v["fmu"] = json!({ "inputs": [ { "name": "u", "drives": drives, "unit": "1", "start": 0.0 } ] });
    v
}

/// The ramp as an amplitude table, as the input run sees it: the value set before the
/// first step (the ramp at t = 0.01) also holds at t = 0, where it sets the consistent
/// initial acceleration (zero-order hold of the first input value).
fn table() -> Value {
    // one row per step end, at the very times the steps compute (t ← t + Δt)
    let mut t = 0.0f64;
    let mut rows = vec![[0.0, ramp(0.01)]];
    while t < 0.2 - 1e-12 {
        t += (t + 0.01f64).min(0.2) - t;
        rows.push([t, ramp(t)]);
    }
    json!(rows)
}

#[test]
fn load_input_ramp_equals_amplitude_table() {
    let a = with_fmu_input(base(), json!({ "load": "tip_load" }));
    let mut b = base();
    b["loads"][0]["amplitude"] = table();
    let d = compare(&a, &b, "u");
    println!("load input vs amplitude table: max relative difference = {d:e} (tolerance 1e-12)");
    assert!(d <= 1e-12);
}

#[test]
fn gravity_input_ramp_equals_amplitude_table() {
    let a = with_fmu_input(base(), json!("gravity"));
    let mut b = base();
    b["gravity"]["amplitude"] = table();
    let d = compare(&a, &b, "u");
    println!("gravity input vs amplitude table: max relative difference = {d:e} (tolerance 1e-12)");
    assert!(d <= 1e-12);
}

#[test]
fn boundary_condition_input_ramp_equals_amplitude_table() {
    // the clamp's y displacement follows the input (m): the whole beam is shaken
    let a = with_fmu_input(base(), json!({ "boundary_condition": "support" }));
    let mut b = base();
    b["boundary_conditions"][0]["amplitude"] = json!([[0.0, 0.0], [0.1, 0.01], [0.2, 0.005]]);
    let (mut sa, mut sb) = (sim(&a), sim(&b));
    let mut max_diff: f64 = 0.0;
    while !sb.finished() {
        sa.set_input("u", 0.01 * ramp(next_time(&sa))).expect("finite input");
        sa.step().expect("step converges");
        sb.step().expect("step converges");
        for (x, y) in sa.monitor_values().iter().zip(sb.monitor_values()) {
            max_diff = max_diff.max((x - y).abs() / (1.0 + y.abs()));
        }
    }
    println!("boundary-condition input vs amplitude table: max relative difference = {max_diff:e} (tolerance 1e-12)");
    assert!(max_diff <= 1e-12);
}

/// A rigid block (`"type": "rigid"`) pressed into elastic MPM soil by its prescribed
/// `motion` (static, frictionless contact on its base): an input driving the motion
/// (`"drives": {"motion": "block"}`) gives the run of the same case with the ramp as the
/// motion's amplitude table (to 1e-12), block reaction and soil settlement alike.
fn rigid_block() -> Value {
    json!({
        "description": "a rigid block pressed into MPM soil for the input tests",
        "materials": {
            "soil": { "law": "neo_hookean", "density": 1000.0, "young_modulus": 1.0e6, "poisson_ratio": 0.3 },
            "block": { "law": "linear_elastic", "density": 1000.0, "young_modulus": 1.0e9, "poisson_ratio": 0.3 }
        },
        "domains": [
            { "name": "soil", "type": "mpm", "material": "soil",
              "grid": { "origin": [0.0, 0.0], "size": [0.6, 0.3], "cells": [30, 15], "element": "quad4" },
              "material_points": { "cells": { "mesh": { "rectangle": { "origin": [0.0, 0.0], "size": [0.6, 0.2], "cells": [30, 10], "element": "quad4" } }, "points_per_cell": 4 } } },
            { "name": "block", "type": "rigid", "material": "block",
              "mesh": { "rectangle": { "origin": [0.2, 0.2], "size": [0.2, 0.05], "cells": [8, 2], "element": "quad4" } },
              "motion": { "displacement": [0.0, -0.005], "rotation": 0.0, "amplitude": 0.0 } }
        ],
        "regions": { "base": { "y": 0.0 }, "sides": { "box": { "min": [0.0, 0.0], "max": [0.0, 0.3] } }, "right": { "x": 0.6 },
                     "face": { "segment": { "from": [0.2, 0.2], "to": [0.4, 0.2] } } },
        "boundary_conditions": [
            { "region": "base", "displacement": [0.0, 0.0] },
            { "region": "sides", "displacement": [0.0, null] },
            { "region": "right", "displacement": [0.0, null] }
        ],
        "interfaces": [ { "name": "contact", "soil": "soil", "structure": "block", "region": "face", "coupling": "contact" } ],
        "analysis": { "type": "static", "time_step": 0.01, "end_time": 0.2 },
        "solver": { "residual_relative_tolerance": 1e-10, "residual_absolute_tolerance": 1e-8 },
        "monitors": [
            { "name": "block_ry", "type": "rigid_body", "domain": "block", "quantity": "reaction", "component": "y" },
            { "name": "block_uy", "type": "rigid_body", "domain": "block", "quantity": "displacement", "component": "y" },
            { "name": "soil_uy", "type": "material_point_displacement", "point": [0.3, 0.195], "component": "y" }
        ]
    })
}

#[test]
fn rigid_motion_input_ramp_equals_amplitude_table() {
    let a = with_fmu_input(rigid_block(), json!({ "motion": "block" }));
    let mut b = rigid_block();
    b["domains"][1]["motion"]["amplitude"] = table();
    let d = compare(&a, &b, "u");
    println!("rigid motion input vs amplitude table: max relative difference = {d:e} (tolerance 1e-12)");
    assert!(d <= 1e-12);
    // a domain that is not rigid, or a rigid one without motion, is refused naming the key
    for (domain, edit) in [("soil", false), ("block", true)] {
        let mut c = with_fmu_input(rigid_block(), json!({ "motion": domain }));
        if edit {
            c["domains"][1].as_object_mut().unwrap().remove("motion");
            c["analysis"]["type"] = json!("dynamic");
        }
        let e = build_error(&c);
        println!("drives motion of '{domain}': {e}");
        assert!(e.contains("fmu.inputs[0].drives.motion"), "{e}");
    }
}

/// A contact wall is a rigid structure (issue 25): an input driving its boundary condition
/// drives the body's motion, the constraint on its three DOFs (the repose case's gate).
#[test]
fn contact_wall_input_drives_its_rigid_body() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/repose_phi20.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["fmu"] =
        json!({ "inputs": [ { "name": "gate_factor", "drives": { "boundary_condition": "gate" }, "start": 0.0 } ] });
    let s = sim(&v);
    let loam::model_builder::InputSlot::Constraint(c) = s.inputs[0].slot else { panic!("a constraint slot") };
    let dofs = &s.model.constraints[c].dofs;
    println!("the gate's input drives constraint {c} on DOFs {dofs:?}");
    assert_eq!(dofs.len(), 3, "the gate's u_x, u_y and θ");
}

#[test]
fn held_input_over_sub_steps_equals_constant_amplitude() {
    // advance_to over several case steps holds the input (zero-order hold)
    let a = with_fmu_input(base(), json!({ "load": "tip_load" }));
    let mut b = base();
    b["loads"][0]["amplitude"] = json!(0.7);
    let (mut sa, mut sb) = (sim(&a), sim(&b));
    sa.set_input("u", 0.7).unwrap();
    sa.advance_to(0.05).unwrap();
    sb.advance_to(0.05).unwrap();
    assert_eq!(sa.step, 5);
    assert_eq!(sa.monitor_values(), sb.monitor_values());
}

#[test]
fn reset_reproduces_the_first_run() {
    let a = with_fmu_input(base(), json!({ "load": "tip_load" }));
    let mut s = sim(&a);
    let run = |s: &mut Simulation| {
        s.set_input("u", 1.0).unwrap();
        s.advance_to(0.05).unwrap();
        s.monitor_values()
    };
    let first = run(&mut s);
    s.reset().unwrap();
    assert_eq!(s.time(), 0.0);
    assert_eq!(s.input_values, vec![None]);
    assert_eq!(run(&mut s), first);
}

#[test]
fn bad_input_values_and_names_are_rejected() {
    let mut s = sim(&with_fmu_input(base(), json!({ "load": "tip_load" })));
    assert_eq!(s.input_names(), vec!["u"]);
    assert!(matches!(s.set_input("u", f64::NAN), Err(InputError::NotFinite { .. })));
    assert!(matches!(s.set_input("u", f64::INFINITY), Err(InputError::NotFinite { .. })));
    assert_eq!(s.input_values, vec![None], "a rejected value leaves the input unset");
    let e = s.set_input("v", 1.0).unwrap_err();
    assert_eq!(e.to_string(), "no input named 'v' (the case's fmu.inputs declare: u)");
}

fn build_error(v: &Value) -> String {
    match Case::parse(&v.to_string()) {
        Err(e) => e.to_string(),
        Ok(case) => Simulation::new(case).err().expect("case must be rejected").to_string(),
    }
}

#[test]
fn fmu_section_errors_name_their_json_path() {
    let mut v = with_fmu_input(base(), json!({ "load": "nope" }));
    assert_eq!(build_error(&v), "fmu.inputs[0].drives.load: no load named 'nope' in loads");
    v["fmu"]["inputs"][0]["drives"] = json!({ "boundary_condition": "nope" });
    assert_eq!(
        build_error(&v),
        "fmu.inputs[0].drives.boundary_condition: no boundary condition named 'nope' in boundary_conditions"
    );
    v["fmu"]["inputs"][0]["drives"] = json!("gravity");
    v["fmu"]["inputs"][0]["colour"] = json!("red");
    assert!(build_error(&v).starts_with("fmu.inputs[0].colour: unknown field `colour`"), "{}", build_error(&v));
    let mut v = with_fmu_input(base(), json!("gravity"));
    v["fmu"]["outputs"] = json!([{ "name": "u" }]);
    assert_eq!(build_error(&v), "fmu.outputs[0].name: duplicate FMU variable name 'u'");
    v["fmu"]["outputs"] = json!([{ "name": "f", "monitor": "missing" }]);
    assert_eq!(build_error(&v), "fmu.outputs[0].monitor: no monitor named 'missing' in monitors");
    v["fmu"]["outputs"] = json!([{ "name": "time", "monitor": "tip_uy" }]);
    assert!(build_error(&v).starts_with("fmu.outputs[0].name: must be non-empty, not 'time'"));
    let mut v = base();
    v["loads"] = json!([v["loads"][0], v["loads"][0]]);
    assert_eq!(build_error(&v), "loads[1].name: duplicate load name 'tip_load'");
}

#[test]
fn outputs_default_to_every_monitor_with_si_units() {
    let s = sim(&base());
    let names: Vec<_> = s.outputs.iter().map(|o| (o.name.as_str(), o.unit.as_str())).collect();
    assert_eq!(names, vec![("tip_uy", "m"), ("clamp_ry", "N")]);
    assert!(s.inputs.is_empty());
}
