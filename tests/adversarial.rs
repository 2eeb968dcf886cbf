//! Issue 16 item 4: a generated corpus of hostile and careless inputs, each run through the
//! `loam` command as a subprocess with a timeout. No input may panic, abort, hang (time
//! out) or write outside `--out`; every bad input exits 2 with exactly one line naming its
//! JSON path (or file and line).
//!
//! The corpus (about 3 000 inputs, built in a temporary directory when the test runs):
//!
//! - **wrong types**: every leaf of seven bundled cases and three `loam law` path files
//!   replaced by a value of another type (a number by a string, a string by a number, a
//!   boolean by a string), expected to be named by its exact JSON path, also inside
//!   internally tagged enums (monitors, loads, materials);
//! - **unknown keys**: a key added to every object, expected to be named;
//! - **extreme values**: every number replaced by 0, −1e300, 1e300, 1e-300 and 2³²: valid or
//!   refused, but never a crash, a hang or more than one line (this is where allocation
//!   aborts and endless runs were found);
//! - **missing keys**: every key removed in turn (valid where optional);
//! - **syntax**: truncated files, text after the object, duplicate keys;
//! - **hand-written classes** of the issue: names that would write outside the output
//!   directory, sizes that exhaust memory, step counts that never end, `/dev/zero` as a
//!   case or mesh file, broken Gmsh files, and the rest (see [`named_inputs`]).
//!
//! It runs in the default suite in about 20 s (four workers). The figures are printed:
//! `cargo test --release --test adversarial -- --nocapture`; with `LOAM_ADVERSARIAL_DUMP=FILE`
//! every input's name, exit code and message are appended to FILE.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

/// Longest a `loam check` of one input may take before it counts as a hang.
const TIMEOUT: Duration = Duration::from_secs(30);

/// What an input must do.
#[derive(Debug, Clone)]
enum Expect {
    /// Refused: exit 2, one line naming exactly this JSON path (`exact`), or a path on the
    /// way to it (an ancestor, e.g. `loads[0].amplitude` for a bad table entry) that names
    /// `mention` somewhere in the line.
    Bad { path: String, exact: bool, mention: Option<String> },
    /// Refused: exit 2, one line whose location starts with the file's path and names a
    /// line (syntax errors, unreadable files).
    BadFile,
    /// Refused: exit 2, one line containing `text`.
    BadSaying(String),
    /// Anything but a crash or a hang: exit 0, or exit 2 (1 for `loam law`) with one line.
    Survives,
    /// `loam law` on a path the material point cannot follow: exit 1, one line.
    Fails,
}

/// One input of the corpus.
struct Input {
    name: String,
    /// `check`, `law` or `run` (the last with `--out <dir>/out`, the run's directory
    /// checked for files written outside it).
    command: &'static str,
    file: PathBuf,
    expect: Expect,
}

/// What an input did.
enum Outcome {
    Ok,
    Panic(String),
    Signal(String),
    Hang,
    Wrong(String),
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Outcome::Ok => write!(f, "ok"),
            Outcome::Panic(m) => write!(f, "PANIC {m}"),
            Outcome::Signal(m) => write!(f, "SIGNAL {m}"),
            Outcome::Hang => write!(f, "HANG (no answer in {} s)", TIMEOUT.as_secs()),
            Outcome::Wrong(m) => write!(f, "WRONG {m}"),
        }
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn work_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("loam-adversarial-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A JSON path step.
#[derive(Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn path_string(steps: &[Step]) -> String {
    let mut s = String::new();
    for st in steps {
        match st {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

fn get_mut<'a>(v: &'a mut Value, steps: &[Step]) -> &'a mut Value {
    steps.iter().fold(v, |v, s| match s {
        Step::Key(k) => &mut v[k.as_str()],
        Step::Index(i) => &mut v[*i],
    })
}

/// Every leaf and every object of `v`, with their paths.
fn walk(v: &Value, steps: &mut Vec<Step>, leaves: &mut Vec<Vec<Step>>, objects: &mut Vec<Vec<Step>>) {
    match v {
        Value::Object(m) => {
            objects.push(steps.clone());
            for (k, x) in m {
                steps.push(Step::Key(k.clone()));
                walk(x, steps, leaves, objects);
                steps.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                steps.push(Step::Index(i));
                walk(x, steps, leaves, objects);
                steps.pop();
            }
        }
        _ => leaves.push(steps.clone()),
    }
}

/// The generated mutations of one base file (`name`, parsed `base`), written to `dir`.
fn mutations(dir: &Path, name: &str, base: &Value, command: &'static str, inputs: &mut Vec<Input>) {
    let (mut leaves, mut objects) = (Vec::new(), Vec::new());
    walk(base, &mut Vec::new(), &mut leaves, &mut objects);
    let mut add = |tag: String, value: &Value, expect: Expect| {
        let file = dir.join(format!("{name}__{}.json", inputs.len()));
        std::fs::write(&file, serde_json::to_string_pretty(value).unwrap()).unwrap();
        inputs.push(Input { name: format!("{name}: {tag}"), command, file, expect });
    };
    for leaf in &leaves {
        let path = path_string(leaf);
        let mut v = base.clone();
        let target = get_mut(&mut v, leaf);
        let replacement = match target {
            Value::Number(_) | Value::Bool(_) | Value::Null => json!("not-a-number-77"),
            Value::String(_) => json!(12345.678),
            _ => continue,
        };
        *target = replacement;
        // an amplitude (a number or a table) is untagged: serde names only the amplitude
        let untagged = path.contains("amplitude");
        let expect = Expect::Bad { path: path.clone(), exact: !untagged, mention: None };
        add(format!("{path} of another type"), &v, expect);
        if matches!(get_mut(&mut base.clone(), leaf), Value::Number(_)) {
            for x in [json!(0), json!(-1e300), json!(1e300), json!(1e-300), json!(4294967296u64)] {
                let mut v = base.clone();
                *get_mut(&mut v, leaf) = x.clone();
                add(format!("{path} = {x}"), &v, Expect::Survives);
            }
        }
    }
    for object in &objects {
        let path = path_string(object);
        let mut v = base.clone();
        let keys: Vec<String> = get_mut(&mut v, object).as_object().unwrap().keys().cloned().collect();
        get_mut(&mut v, object)["zz_typo_77"] = json!(1);
        add(
            format!("unknown key in {path}"),
            &v,
            Expect::Bad { path: path.clone(), exact: false, mention: Some("zz_typo_77".into()) },
        );
        for k in keys {
            let mut v = base.clone();
            get_mut(&mut v, object).as_object_mut().unwrap().remove(&k);
            add(format!("{path}.{k} removed"), &v, Expect::Survives);
        }
    }
    // syntax: truncated, trailing text, a duplicated top-level key
    let text = serde_json::to_string_pretty(base).unwrap();
    for k in 1..=6 {
        let cut = text.len() * k / 7;
        let cut = (0..=cut).rev().find(|&i| text.is_char_boundary(i)).unwrap();
        let file = dir.join(format!("{name}__cut{k}.json"));
        std::fs::write(&file, &text[..cut]).unwrap();
        inputs.push(Input { name: format!("{name}: truncated at {cut}"), command, file, expect: Expect::BadFile });
    }
    for (tag, extra) in [("trailing text", " x"), ("second object", " {}"), ("trailing comma", ",")] {
        let file = dir.join(format!("{name}__{}.json", tag.replace(' ', "_")));
        std::fs::write(&file, format!("{text}{extra}")).unwrap();
        inputs.push(Input { name: format!("{name}: {tag}"), command, file, expect: Expect::BadFile });
    }
    let file = dir.join(format!("{name}__duplicate.json"));
    std::fs::write(&file, text.replacen('{', "{\n  \"description\": \"first\",", 1)).unwrap();
    inputs.push(Input {
        name: format!("{name}: duplicate description"),
        command,
        file,
        expect: Expect::Bad { path: "description".into(), exact: true, mention: None },
    });
}

/// A small Gmsh MSH 4.1 mesh: two quads on [0, 2] × [0, 1], physical line "left" (x = 0)
/// and surface "body".
const TWO_QUADS: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 1 \"left\"\n2 2 \"body\"\n\
$EndPhysicalNames\n$Entities\n0 1 1 0\n1 0 0 0 0 1 0 1 1 0\n1 0 0 0 2 1 0 1 2 0\n$EndEntities\n\
$Nodes\n2 6 1 6\n1 1 0 2\n1\n4\n0 0 0\n0 1 0\n2 1 0 4\n2\n3\n5\n6\n1 0 0\n2 0 0\n1 1 0\n2 1 0\n$EndNodes\n\
$Elements\n2 3 1 3\n1 1 1 1\n1 1 4\n2 1 3 2\n2 1 2 5 4\n3 2 3 6 5\n$EndElements\n";

/// A case on the two-quad Gmsh mesh, clamped on the group "left".
fn gmsh_case(mesh: &str) -> Value {
    json!({
        "description": "two quads from a Gmsh file",
        "materials": {"m": {"law": "linear_elastic", "density": 1000, "young_modulus": 1e7, "poisson_ratio": 0.3}},
        "domains": [{"name": "plate", "type": "fem", "material": "m", "mesh": {"gmsh": mesh}}],
        "regions": {"left": {"group": "left"}, "tip": {"nearest": [2, 1]}},
        "boundary_conditions": [{"region": "left", "displacement": [0, 0]}],
        "loads": [{"type": "nodal_force", "region": "tip", "force": [0, -10]}],
        "analysis": {"type": "static", "time_step": 1, "end_time": 1},
        "monitors": [{"name": "tip_uy", "type": "displacement", "point": [2, 1], "component": "y"}]
    })
}

/// The classes of the issue, written by hand: (name, file contents or case edit, expected).
fn named_inputs(dir: &Path, inputs: &mut Vec<Input>) {
    let read = |case: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(root().join("cases").join(case)).unwrap()).unwrap()
    };
    let (fem, mpm) = (read("cantilever_fem.json"), read("cantilever_mpm.json"));
    let penalty = read("cylinder_incline_slip_mpm.json");
    let collapse = read("collapse_bui2008_quad_mc.json");
    let coupled = read("coupled_beam_split.json");
    let mut n = 0;
    let mut case = |name: &str, command: &'static str, base: &Value, edit: &dyn Fn(&mut Value), expect: Expect| {
        let mut v = base.clone();
        edit(&mut v);
        n += 1;
        let sub = dir.join(format!("named{n}"));
        std::fs::create_dir_all(&sub).unwrap();
        let file = sub.join("case.json");
        std::fs::write(&file, serde_json::to_string_pretty(&v).unwrap()).unwrap();
        inputs.push(Input { name: name.to_string(), command, file, expect });
    };
    let bad = |path: &str| Expect::Bad { path: path.into(), exact: true, mention: None };
    let saying = |t: &str| Expect::BadSaying(t.into());

    // names that become file names: refused at load, nothing written outside --out
    for name in ["../escape", "/tmp/loam-adversarial-absolute", "", "a/b", ".hidden", "a\nb", "con:", "x_grid", "a\\b"]
    {
        for (base, what) in [(&fem, "fem"), (&mpm, "mpm")] {
            let name_s = name.to_string();
            case(
                &format!("{what} domain named {name:?}"),
                "run",
                base,
                &move |v| v["domains"][0]["name"] = json!(name_s),
                bad("domains[0].name"),
            );
        }
    }
    case(
        "penalty wall named ../wall",
        "run",
        &penalty,
        &|v| v["boundary_conditions"][0]["name"] = json!("../wall"),
        bad("boundary_conditions[0].name"),
    );
    case(
        "two domains differing in case",
        "check",
        &fem,
        &|v| {
            let mut d = v["domains"][0].clone();
            d["name"] = json!("BEAM");
            d["mesh"]["rectangle"]["origin"] = json!([0, 5]);
            v["domains"].as_array_mut().unwrap().push(d);
        },
        bad("domains[1].name"),
    );
    // sizes refused before allocating
    for cells in [json!([1000000000, 1]), json!([100000, 100000]), json!([3000, 1000])] {
        let c = cells.clone();
        case(
            &format!("FEM mesh cells {cells}"),
            "check",
            &fem,
            &move |v| v["domains"][0]["mesh"]["rectangle"]["cells"] = c.clone(),
            bad("domains[0].mesh.rectangle.cells"),
        );
        let c = cells.clone();
        case(
            &format!("grid cells {cells}"),
            "check",
            &mpm,
            &move |v| v["domains"][0]["grid"]["cells"] = c.clone(),
            bad("domains[0].grid.cells"),
        );
        let c = cells.clone();
        case(
            &format!("body mesh cells {cells}"),
            "check",
            &mpm,
            &move |v| v["domains"][0]["material_points"]["cells"]["mesh"]["rectangle"]["cells"] = c.clone(),
            bad("domains[0].material_points.cells.mesh.rectangle.cells"),
        );
    }
    case(
        "box cells [1000, 1000, 1000]",
        "check",
        &fem,
        &|v| {
            v["formulation"] = json!("3d");
            v.as_object_mut().unwrap().remove("thickness");
            v["domains"][0]["mesh"] = json!({"box": {"origin": [0, 0, 0], "size": [1, 1, 1], "cells": [1000, 1000, 1000], "element": "hex8"}});
        },
        bad("domains[0].mesh.box.cells"),
    );
    for spacing in [1e-8, 1e-12, 1e-200] {
        case(
            &format!("disk spacing {spacing}"),
            "check",
            &mpm,
            &move |v| {
                v["domains"][0]["material_points"] =
                    json!({"disk": {"centre": [3.5, 0.5], "radius": 0.4, "spacing": spacing}})
            },
            bad("domains[0].material_points.disk.spacing"),
        );
        case(
            &format!("polygon spacing {spacing}"),
            "check",
            &mpm,
            &move |v| {
                v["domains"][0]["material_points"] =
                    json!({"polygon": {"vertices": [[0, 0], [7, 0], [7, 1], [0, 1]], "spacing": spacing}})
            },
            bad("domains[0].material_points.polygon.spacing"),
        );
        case(
            &format!("penalty wall spacing {spacing}"),
            "check",
            &penalty,
            &move |v| v["boundary_conditions"][0]["penalty"]["spacing"] = json!(spacing),
            bad("boundary_conditions[0].penalty.spacing"),
        );
    }
    case(
        "penalty wall of overflowing length",
        "check",
        &penalty,
        &|v| v["boundary_conditions"][0]["penalty"]["segment"] = json!([[-1e308, 0], [1e308, 0]]),
        bad("boundary_conditions[0].penalty.segment"),
    );
    case(
        "grid size 1e160",
        "check",
        &mpm,
        &|v| v["domains"][0]["grid"]["size"] = json!([1e160, 1e160]),
        bad("domains[0].grid"),
    );
    case(
        "points per cell 10^18",
        "check",
        &mpm,
        &|v| v["domains"][0]["material_points"]["cells"]["points_per_cell"] = json!(1_000_000_000_000_000_000u64),
        bad("domains[0].material_points.cells.points_per_cell"),
    );
    // runs that never end
    case("time_step 1e-300", "check", &fem, &|v| v["analysis"]["time_step"] = json!(1e-300), bad("analysis.time_step"));
    case("end_time 1e308", "check", &fem, &|v| v["analysis"]["end_time"] = json!(1e308), bad("analysis.time_step"));
    case(
        "adaptive run of 1e12 steps at its largest step",
        "check",
        &collapse,
        &|v| v["analysis"]["end_time"] = json!(1e9),
        bad("analysis.adaptive.max_time_step"),
    );
    case(
        "error_tolerance 0",
        "check",
        &collapse,
        &|v| v["analysis"]["adaptive"]["error_tolerance"] = json!(0.0),
        bad("analysis.adaptive.error_tolerance"),
    );
    case(
        "max_step_cuts 10^9",
        "check",
        &fem,
        &|v| v["analysis"]["max_step_cuts"] = json!(1_000_000_000),
        bad("analysis.max_step_cuts"),
    );
    case(
        "max_iterations 10^9",
        "check",
        &fem,
        &|v| v["solver"]["max_iterations"] = json!(1_000_000_000),
        bad("solver.max_iterations"),
    );
    case("limits.steps 0", "check", &fem, &|v| v["limits"] = json!({"steps": 0}), bad("limits.steps"));
    // errors that did not name the JSON path
    case("formulation 1", "check", &fem, &|v| v["formulation"] = json!(1), bad("formulation"));
    case(
        "region with a typo key",
        "check",
        &fem,
        &|v| v["regions"]["clamp"] = json!({"x": 0, "zz_typo": 1}),
        Expect::Bad { path: "regions.clamp".into(), exact: true, mention: Some("zz_typo".into()) },
    );
    case(
        "newmark and bossak",
        "check",
        &fem,
        &|v| {
            v["analysis"]["type"] = json!("dynamic");
            v["analysis"]["scheme"] = json!({"newmark": {"beta": 0.25, "gamma": 0.5}, "bossak": {"alpha": -0.1}});
        },
        Expect::Bad { path: "analysis.scheme".into(), exact: true, mention: Some("bossak".into()) },
    );
    case(
        "3D origin of a rectangle",
        "check",
        &fem,
        &|v| v["domains"][0]["mesh"]["rectangle"]["origin"] = json!([0, 0, 0]),
        bad("domains[0].mesh.rectangle.origin"),
    );
    case(
        "density as a string",
        "check",
        &fem,
        &|v| v["materials"]["beam"]["density"] = json!("1000"),
        bad("materials.beam.density"),
    );
    case(
        "monitor point as a string",
        "check",
        &fem,
        &|v| v["monitors"][0]["point"] = json!("tip"),
        bad("monitors[0].point"),
    );
    case(
        "unknown monitor type",
        "check",
        &fem,
        &|v| v["monitors"][0]["type"] = json!("displacment"),
        bad("monitors[0].type"),
    );
    case(
        "unknown law",
        "check",
        &fem,
        &|v| v["materials"]["beam"]["law"] = json!("neo_hooke"),
        bad("materials.beam.law"),
    );
    // accepted silently before
    case(
        "monitor name with a newline",
        "check",
        &fem,
        &|v| v["monitors"][0]["name"] = json!("tip\nuy"),
        bad("monitors[0].name"),
    );
    case(
        "monitor name with a quote",
        "check",
        &fem,
        &|v| v["monitors"][0]["name"] = json!("tip\"uy"),
        bad("monitors[0].name"),
    );
    case(
        "runout by thickness without its bin",
        "check",
        &collapse,
        &|v| v["monitors"][0]["measure"] = json!("thickness"),
        bad("monitors[0].bin"),
    );
    case(
        "runout bin on the surface measure",
        "check",
        &collapse,
        &|v| v["monitors"][0]["bin"] = json!(0.005),
        bad("monitors[0].bin"),
    );
    case(
        "runout depth on a plane case",
        "check",
        &collapse,
        &|v| {
            v["monitors"][0]["measure"] = json!("thickness");
            v["monitors"][0]["bin"] = json!(0.005);
            v["monitors"][0]["depth"] = json!(0.005);
        },
        bad("monitors[0].depth"),
    );
    case(
        "runout measure unknown",
        "check",
        &collapse,
        &|v| v["monitors"][0]["measure"] = json!("volume"),
        bad("monitors[0].measure"),
    );
    case(
        "geostatic surface below the body",
        "check",
        &collapse,
        &|v| v["domains"][0]["initial_stress"]["geostatic"]["surface"] = json!(0.05),
        bad("domains[0].initial_stress.geostatic.surface"),
    );
    case(
        "geostatic stress on a material of 1 Pa",
        "check",
        &collapse,
        &|v| {
            let m = v["domains"][0]["material"].as_str().unwrap().to_string();
            v["materials"][m.as_str()]["young_modulus"] = json!(1.0);
        },
        bad("domains[0].initial_stress.geostatic"),
    );
    for key in ["displacement_absolute_tolerance", "displacement_relative_tolerance", "residual_relative_tolerance"] {
        for value in [0.0, -1e-6] {
            case(
                &format!("{key} = {value}"),
                "check",
                &fem,
                &move |v| v["solver"][key] = json!(value),
                bad(&format!("solver.{key}")),
            );
        }
    }
    case(
        "two overlapping FEM domains",
        "check",
        &fem,
        &|v| {
            let mut d = v["domains"][0].clone();
            d["name"] = json!("beam2");
            d["mesh"]["rectangle"]["origin"] = json!([3.5, 0.5]);
            v["domains"].as_array_mut().unwrap().push(d);
        },
        bad("domains[1]"),
    );
    case(
        "two overlapping bodies",
        "check",
        &mpm,
        &|v| {
            let mut d = v["domains"][0].clone();
            d["name"] = json!("beam2");
            d["material_points"] = json!({"disk": {"centre": [3.5, 0.5], "radius": 0.3, "spacing": 0.05}});
            v["domains"].as_array_mut().unwrap().push(d);
        },
        bad("domains[1]"),
    );
    case(
        "thickness in 3D",
        "check",
        &fem,
        &|v| {
            v["formulation"] = json!("3d");
            v["domains"][0]["mesh"] =
                json!({"box": {"origin": [0, 0, 0], "size": [7, 1, 1], "cells": [7, 1, 1], "element": "hex8"}});
        },
        bad("thickness"),
    );
    case(
        "output.times after end_time",
        "check",
        &fem,
        &|v| v["output"] = json!({"times": [0.5, 2.0]}),
        bad("output.times[1]"),
    );
    case(
        "huge negative Young's modulus printed compactly",
        "check",
        &fem,
        &|v| v["materials"]["beam"]["young_modulus"] = json!(-1e300),
        Expect::Bad { path: "materials.beam.young_modulus".into(), exact: true, mention: Some("-1e300".into()) },
    );
    // issue 31: values that failed later with a message hiding the cause
    case(
        "Young's modulus 1e308 in the Bui collapse",
        "check",
        &collapse,
        &|v| v["materials"]["aluminium_bars"]["young_modulus"] = json!(1e308),
        Expect::Bad {
            path: "materials.aluminium_bars.young_modulus".into(),
            exact: true,
            mention: Some("at most 1e15 Pa".into()),
        },
    );
    case(
        "subnormal density",
        "check",
        &fem,
        &|v| v["materials"]["beam"]["density"] = json!(1e-320),
        Expect::Bad { path: "materials.beam.density".into(), exact: true, mention: Some("1e-320".into()) },
    );
    case(
        "static analysis without supports",
        "check",
        &fem,
        &|v| {
            v.as_object_mut().unwrap().remove("boundary_conditions");
        },
        Expect::Bad { path: "boundary_conditions".into(), exact: true, mention: Some("supports".into()) },
    );
    case(
        "interface band 1e300",
        "check",
        &coupled,
        &|v| v["interfaces"][0]["band"] = json!(1e300),
        Expect::Bad { path: "interfaces[0].band".into(), exact: true, mention: Some("diagonal of the grid".into()) },
    );
    case(
        "interface band negative",
        "check",
        &coupled,
        &|v| v["interfaces"][0]["band"] = json!(-1e300),
        bad("interfaces[0].band"),
    );
    // the non-conforming tie (issue 25)
    let tied = read("coupled_beam_split_tied.json");
    case(
        "interface coupling unknown",
        "check",
        &tied,
        &|v| v["interfaces"][0]["coupling"] = json!("glue"),
        bad("interfaces[0].coupling"),
    );
    case("tie with slip", "check", &tied, &|v| v["interfaces"][0]["slip"] = json!(true), bad("interfaces[0].slip"));
    case("tie with a band", "check", &tied, &|v| v["interfaces"][0]["band"] = json!(0.5), bad("interfaces[0].band"));
    case(
        "tie penalty negative",
        "check",
        &tied,
        &|v| v["interfaces"][0]["penalty"] = json!(-1.0),
        bad("interfaces[0].penalty"),
    );
    case(
        "penalty on shared nodes",
        "check",
        &coupled,
        &|v| v["interfaces"][0]["penalty"] = json!(1e9),
        bad("interfaces[0].penalty"),
    );
    case(
        "tie and shared nodes on one grid",
        "check",
        &tied,
        &|v| {
            let shared = json!({ "name": "cut2", "soil": "beam_mpm", "structure": "beam_fem", "region": "cut" });
            v["interfaces"].as_array_mut().unwrap().push(shared);
        },
        Expect::Bad {
            path: "interfaces[0].coupling".into(),
            exact: true,
            mention: Some("one kind of interface per grid".into()),
        },
    );
    case(
        "tie facets outside the grid",
        "check",
        &tied,
        &|v| v["regions"]["cut"] = json!({"segment": {"from": [0.0, 0.0], "to": [0.0, 1.0]}}),
        Expect::Bad {
            path: "interfaces[0].region".into(),
            exact: true,
            mention: Some("outside the soil's grid".into()),
        },
    );
    // non-conforming contact (issue 25)
    let contact = read("block_on_incline_slide.json");
    case(
        "contact friction negative",
        "check",
        &contact,
        &|v| v["interfaces"][0]["friction"] = json!(-0.2),
        bad("interfaces[0].friction"),
    );
    case(
        "friction on a tie",
        "check",
        &tied,
        &|v| v["interfaces"][0]["friction"] = json!(0.3),
        bad("interfaces[0].friction"),
    );
    case(
        "contact tangential penalty negative",
        "check",
        &contact,
        &|v| v["interfaces"][0]["tangential_penalty"] = json!(-1e9),
        bad("interfaces[0].tangential_penalty"),
    );
    case(
        "rectangle rotation not a number",
        "check",
        &contact,
        &|v| v["domains"][1]["mesh"]["rectangle"]["rotation"] = json!("thirty"),
        bad("domains[1].mesh.rectangle.rotation"),
    );
    // whole files
    let mut file = |name: &str, contents: &[u8], expect: Expect| {
        let f = dir.join(format!("file_{}.json", inputs.len()));
        std::fs::write(&f, contents).unwrap();
        inputs.push(Input { name: name.to_string(), command: "check", file: f, expect });
    };
    file("empty file", b"", Expect::BadFile);
    file("null", b"null", Expect::BadSaying("one JSON object".into()));
    file("array", b"[]", Expect::BadSaying("one JSON object".into()));
    file("empty object", b"{}", Expect::BadSaying("missing field `description`".into()));
    file("not UTF-8", b"{\"description\": \"\xff\xfe\"}", Expect::BadSaying("not UTF-8".into()));
    file("number out of range", b"{\"description\": 1e999}", Expect::BadFile);
    file("deep nesting", &[b'['; 100_000], Expect::BadFile);
    file("a NUL byte", b"{\"description\": \"a\0b\"}", Expect::BadFile);
    file("a byte-order mark", "\u{feff}{}".as_bytes(), Expect::BadFile);
    file("huge file", &vec![b' '; 17 << 20], Expect::BadSaying("limit of 16 MiB".into()));
    inputs.push(Input {
        name: "/dev/zero as the case file".into(),
        command: "check",
        file: PathBuf::from("/dev/zero"),
        expect: Expect::BadSaying("limit of 16 MiB".into()),
    });
    inputs.push(Input {
        name: "a directory as the case file".into(),
        command: "check",
        file: dir.to_path_buf(),
        expect: Expect::BadSaying("is a directory".into()),
    });
    inputs.push(Input {
        name: "a missing case file".into(),
        command: "check",
        file: dir.join("missing.json"),
        expect: Expect::BadSaying("cannot read".into()),
    });
    // meshes
    let mesh_case = |name: &str, mesh: &str, contents: Option<&[u8]>, expect: Expect, inputs: &mut Vec<Input>| {
        let sub = dir.join(format!("mesh{}", inputs.len()));
        std::fs::create_dir_all(&sub).unwrap();
        if let Some(c) = contents {
            std::fs::write(sub.join(mesh), c).unwrap();
        }
        let file = sub.join("case.json");
        std::fs::write(&file, serde_json::to_string_pretty(&gmsh_case(mesh)).unwrap()).unwrap();
        inputs.push(Input { name: name.to_string(), command: "check", file, expect });
    };
    let gmsh = || Expect::Bad { path: "domains[0].mesh.gmsh".into(), exact: true, mention: None };
    mesh_case("/dev/zero as the mesh", "/dev/zero", None, gmsh(), inputs);
    mesh_case("a missing mesh", "nowhere.msh", None, gmsh(), inputs);
    mesh_case("MSH 2.2", "old.msh", Some(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"), gmsh(), inputs);
    mesh_case("garbage mesh", "garbage.msh", Some(&[0x5a; 4096]), gmsh(), inputs);
    let huge = TWO_QUADS.replace("$Nodes\n2 6 1 6", "$Nodes\n2 1000000000000000000 1 6");
    mesh_case("mesh declaring 10^18 nodes", "huge.msh", Some(huge.as_bytes()), gmsh(), inputs);
    let huge = TWO_QUADS.replace("$Elements\n2 3 1 3", "$Elements\n2 3000000000 1 3");
    mesh_case("mesh declaring 3e9 elements", "huge2.msh", Some(huge.as_bytes()), gmsh(), inputs);
    for k in 1..20 {
        let cut = TWO_QUADS.len() * k / 20;
        mesh_case(&format!("mesh truncated at {cut}"), "cut.msh", Some(&TWO_QUADS.as_bytes()[..cut]), gmsh(), inputs);
    }
    // a background grid from Gmsh with a degenerate cell (node 5 moved onto node 2)
    let sub = dir.join("degenerate_grid");
    std::fs::create_dir_all(&sub).unwrap();
    std::fs::write(sub.join("grid.msh"), TWO_QUADS.replace("1 0 0\n2 0 0\n1 1 0\n", "1 0 0\n2 0 0\n1 0 0\n")).unwrap();
    let grid_case = json!({
        "description": "MPM disk on a Gmsh grid with a degenerate cell",
        "materials": {"m": {"law": "linear_elastic", "density": 1000, "young_modulus": 1e7, "poisson_ratio": 0.3}},
        "domains": [{"name": "disk", "type": "mpm", "material": "m", "grid_mesh": {"gmsh": "grid.msh"},
                     "material_points": {"disk": {"centre": [1.5, 0.5], "radius": 0.2, "spacing": 0.05}}}],
        "analysis": {"type": "static", "time_step": 1, "end_time": 1}
    });
    std::fs::write(sub.join("case.json"), grid_case.to_string()).unwrap();
    inputs.push(Input {
        name: "degenerate grid_mesh cell".into(),
        command: "check",
        file: sub.join("case.json"),
        expect: Expect::Bad { path: "domains[0].grid_mesh".into(), exact: true, mention: Some("degenerate".into()) },
    });
    // loam law
    let law = |name: &str, value: Value, expect: Expect, inputs: &mut Vec<Input>| {
        let file = dir.join(format!("law_{}.json", inputs.len()));
        std::fs::write(&file, value.to_string()).unwrap();
        inputs.push(Input { name: name.to_string(), command: "law", file, expect });
    };
    let elastic = json!({"law": "linear_elastic", "density": 1, "young_modulus": 1e6, "poisson_ratio": 0.3});
    law(
        "law: 10^9 steps",
        json!({"description": "x", "material": elastic, "path": {"type": "oedometric", "axial_strain": 0.1, "steps": 1_000_000_000}}),
        bad("path.steps"),
        inputs,
    );
    law(
        "law: density as a string",
        json!({"description": "x", "material": {"law": "linear_elastic", "density": "1", "young_modulus": 1e6, "poisson_ratio": 0.3},
               "path": {"type": "oedometric", "axial_strain": 0.1, "steps": 10}}),
        bad("material.density"),
        inputs,
    );
    law(
        "law: extension of a cohesionless sand to 90 % strain",
        json!({"description": "x", "material": {"law": "mohr_coulomb", "density": 1, "young_modulus": 1e6, "poisson_ratio": 0.3,
               "friction_angle": 30, "cohesion": 0, "dilatancy_angle": 0},
               "path": {"type": "triaxial", "drainage": "drained", "loading": "extension", "confining_pressure": 1e5,
                        "axial_strain": 0.9, "steps": 2}}),
        Expect::Fails,
        inputs,
    );
    law(
        "law: subnormal Young's modulus (det F = NaN before)",
        json!({"description": "x", "material": {"law": "linear_elastic", "density": 1, "young_modulus": 1e-320, "poisson_ratio": 0.3},
               "path": {"type": "oedometric", "axial_strain": 0.1, "steps": 10}}),
        Expect::Bad { path: "material.young_modulus".into(), exact: true, mention: Some("1e-320".into()) },
        inputs,
    );
    let f = dir.join("law_dup.json");
    std::fs::write(&f, "{\"description\": \"x\", \"description\": \"y\"}").unwrap();
    inputs.push(Input { name: "law: duplicate key".into(), command: "law", file: f, expect: bad("description") });
    inputs.push(Input {
        name: "law: /dev/zero".into(),
        command: "law",
        file: PathBuf::from("/dev/zero"),
        expect: saying("limit of 16 MiB"),
    });
}

/// Runs `input` and judges it.
fn judge(input: &Input, dir: &Path) -> Outcome {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_loam"));
    cmd.arg(input.command).arg(&input.file).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped());
    let run_dir = input.file.parent().unwrap_or(dir).to_path_buf();
    let before = if input.command == "run" { Some(listing(&run_dir)) } else { None };
    match input.command {
        "law" => {
            cmd.arg("--out").arg(dir.join(format!("law_out_{}", input.file.file_stem().unwrap().to_string_lossy())));
        }
        "run" => {
            cmd.arg("--quiet").arg("--out").arg("out").current_dir(&run_dir);
        }
        _ => {}
    }
    let mut child = cmd.spawn().expect("loam starts");
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        match child.try_wait().unwrap() {
            Some(s) => break s,
            None if start.elapsed() > TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return Outcome::Hang;
            }
            None => std::thread::sleep(Duration::from_millis(2)),
        }
    };
    let err = reader.join().unwrap();
    if let Ok(dump) = std::env::var("LOAM_ADVERSARIAL_DUMP") {
        use std::io::Write;
        // one write per input: appends of the four workers do not interleave
        let line = format!("{}\t{:?}\t{}\n", input.name.replace('\n', "\\n"), status.code(), err.trim_end());
        let mut f = std::fs::OpenOptions::new().create(true).append(true).open(dump).unwrap();
        let _ = f.write_all(line.as_bytes());
    }
    if err.contains("panicked") {
        return Outcome::Panic(err.lines().take(2).collect::<Vec<_>>().join(" | "));
    }
    let Some(code) = status.code() else {
        return Outcome::Signal(format!("{status:?}: {}", err.trim()));
    };
    if let Some(before) = before {
        let after = listing(&run_dir);
        let outside: Vec<&String> =
            after.iter().filter(|f| !before.contains(f) && !f.starts_with("out/") && *f != "out").collect();
        if !outside.is_empty() {
            return Outcome::Wrong(format!("wrote outside --out: {outside:?}"));
        }
        if !std::fs::read_dir("/tmp")
            .unwrap()
            .all(|e| !e.unwrap().file_name().to_string_lossy().starts_with("loam-adversarial-absolute"))
        {
            return Outcome::Wrong("wrote to an absolute path".into());
        }
    }
    let lines: Vec<&str> = err.lines().collect();
    let one_line = || -> Result<&str, String> {
        match lines.as_slice() {
            [l] if l.starts_with("error: ") => Ok(&l["error: ".len()..]),
            _ => Err(format!("exit {code} with {} lines: {err:?}", lines.len())),
        }
    };
    let verdict = match &input.expect {
        Expect::Survives => match code {
            0 => Ok(()),
            2 => one_line().and_then(located),
            1 if input.command == "law" => one_line().map(|_| ()),
            _ => Err(format!("exit {code}: {}", err.trim())),
        },
        Expect::Fails => match code {
            1 => one_line().map(|_| ()),
            _ => Err(format!("exit {code} (expected 1): {}", err.trim())),
        },
        expect => {
            if code != 2 {
                Err(format!("exit {code} (expected 2): {}", err.trim()))
            } else {
                one_line().and_then(|line| check_location(expect, line, &input.file))
            }
        }
    };
    match verdict {
        Ok(()) => Outcome::Ok,
        Err(e) => Outcome::Wrong(e),
    }
}

/// A refusal's line must start with a location (a JSON path, or a file and line) before
/// its message.
fn located(line: &str) -> Result<(), String> {
    match line.split_once(": ") {
        Some((location, message)) if !location.is_empty() && !message.is_empty() => Ok(()),
        _ => Err(format!("no location: {line}")),
    }
}

/// Whether the one `line` of a refusal names what `expect` says.
fn check_location(expect: &Expect, line: &str, file: &Path) -> Result<(), String> {
    let (location, message) = line.split_once(": ").unwrap_or((line, ""));
    let ok = match expect {
        Expect::Bad { path, exact, mention } => {
            let named = mention.as_ref().is_none_or(|m| line.contains(m.as_str()));
            let on_the_way = path.starts_with(location)
                && matches!(path[location.len()..].chars().next(), None | Some('.') | Some('['))
                && !location.is_empty();
            let below = location.starts_with(path.as_str());
            named && (location == path || (!exact && (on_the_way || below)))
        }
        Expect::BadFile => {
            location.starts_with(&file.display().to_string()) && (location.contains("line") || !message.is_empty())
        }
        Expect::BadSaying(text) => line.contains(text.as_str()),
        Expect::Survives | Expect::Fails => true,
    };
    if ok {
        Ok(())
    } else {
        Err(format!("expected {expect:?}, got: {line}"))
    }
}

/// Every file under `dir`, relative to it.
fn listing(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            out.push(p.strip_prefix(dir).unwrap().to_string_lossy().into_owned());
            if p.is_dir() {
                stack.push(p);
            }
        }
    }
    out
}

/// Issue 16 acceptance: the adversarial-input corpus gives 0 panics, 0 aborts and 0 hangs,
/// every bad input exits 2 with one line naming its JSON path (or file and line), and no
/// input writes outside `--out`.
#[test]
fn adversarial_corpus_is_refused_cleanly() {
    let dir = work_dir();
    let mut inputs = Vec::new();
    let bases = [
        "cantilever_fem",
        "cantilever_mpm",
        "cylinder_incline_slip_mpm",
        "coupled_beam_split",
        "collapse_bui2008_quad_mc",
        "footing_fmu",
        "disk_collision_mpm",
    ];
    for name in bases {
        let base: Value =
            serde_json::from_str(&std::fs::read_to_string(root().join(format!("cases/{name}.json"))).unwrap()).unwrap();
        mutations(&dir, name, &base, "check", &mut inputs);
    }
    let gmsh_dir = dir.join("gmsh");
    std::fs::create_dir_all(&gmsh_dir).unwrap();
    std::fs::write(gmsh_dir.join("two_quads.msh"), TWO_QUADS).unwrap();
    mutations(&gmsh_dir, "gmsh", &gmsh_case("two_quads.msh"), "check", &mut inputs);
    for name in ["mc_triaxial_drained", "mcc_triaxial_undrained", "neo_hookean_simple_shear"] {
        let base: Value =
            serde_json::from_str(&std::fs::read_to_string(root().join(format!("cases/laws/{name}.json"))).unwrap())
                .unwrap();
        mutations(&dir, name, &base, "law", &mut inputs);
    }
    named_inputs(&dir, &mut inputs);

    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let counts = Mutex::new([0usize; 3]); // bad inputs refused, survived, law failures
    let slowest = Mutex::new(Vec::new());
    let start = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(input) = inputs.get(k) else { break };
                let t = Instant::now();
                let outcome = judge(input, &dir);
                slowest.lock().unwrap().push((t.elapsed().as_secs_f64(), k));
                match outcome {
                    Outcome::Ok => {
                        let mut c = counts.lock().unwrap();
                        match input.expect {
                            Expect::Survives => c[1] += 1,
                            Expect::Fails => c[2] += 1,
                            _ => c[0] += 1,
                        }
                    }
                    other => failures.lock().unwrap().push(format!("{}: {other}", input.name)),
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    let [bad, survived, law_failures] = counts.into_inner().unwrap();
    let kind = |k: &str| failures.iter().filter(|f| f.contains(&format!(": {k}"))).count();
    println!(
        "adversarial corpus: {} inputs in {:.1} s: {bad} bad inputs refused with exit 2 and one line naming the path, \
         {survived} extreme or incomplete inputs handled (exit 0 or 2), {law_failures} law divergence(s) exit 1; \
         {} panics, {} signals (aborts), {} hangs, {} wrong answers",
        inputs.len(),
        start.elapsed().as_secs_f64(),
        kind("PANIC"),
        kind("SIGNAL"),
        kind("HANG"),
        kind("WRONG")
    );
    let mut slowest = slowest.into_inner().unwrap();
    slowest.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (t, k) in slowest.iter().take(3) {
        println!("  slowest: {t:.2} s {}", inputs[*k].name);
    }
    for f in failures.iter().take(60) {
        println!("  {f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(inputs.len() >= 300);
    assert!(failures.is_empty(), "{} of {} inputs failed", failures.len(), inputs.len());
}

/// Property tests of the case parser and model builder, in process (issue 16): any text,
/// any JSON value and any single-leaf mutation of a bundled case give a case or a one-line
/// error with a location, never a panic. Sizes are bounded by the case's `limits` (set
/// small here, so that a mutated size costs no memory).
mod properties {
    use loam::case::Case;
    use loam::simulation::Simulation;
    use proptest::prelude::*;
    use serde_json::{json, Value};

    use super::{root, walk, Step};

    /// JSON values built from the words of the case schema, extreme numbers and short
    /// strings.
    fn value() -> impl Strategy<Value = Value> {
        let words = prop_oneof![
            Just("fem"),
            Just("mpm"),
            Just("quad4"),
            Just("tri3"),
            Just("hex8"),
            Just("x"),
            Just("y"),
            Just("beam"),
            Just("clamp"),
            Just("static"),
            Just("dynamic"),
            Just("plane_strain"),
            Just("3d"),
            Just("rectangle"),
            Just("newmark"),
            Just("displacement"),
            Just("magnitude"),
            Just("neo_hookean"),
            Just("../x"),
            Just(""),
            Just("a\nb"),
        ];
        let leaf = prop_oneof![
            Just(Value::Null),
            any::<bool>().prop_map(Value::from),
            any::<i64>().prop_map(Value::from),
            prop_oneof![Just(0.0), Just(-1.0), Just(1e300), Just(-1e-300), Just(0.5), Just(7.0), Just(1e9)]
                .prop_map(|f: f64| json!(f)),
            (-1e6f64..1e6).prop_map(|f| json!(f)),
            words.prop_map(Value::from),
        ];
        leaf.prop_recursive(4, 48, 6, |inner| {
            prop_oneof![
                proptest::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
                proptest::collection::btree_map("[a-z_]{1,12}", inner, 0..6)
                    .prop_map(|m| Value::Object(m.into_iter().collect())),
            ]
        })
    }

    fn one_line(result: Result<Simulation, loam::case::CaseError>) -> Result<(), TestCaseError> {
        if let Err(e) = result {
            let m = e.to_string();
            prop_assert!(!m.contains('\n'), "message of more than one line: {m:?}");
            prop_assert!(!m.is_empty());
        }
        Ok(())
    }

    fn bases() -> Vec<Value> {
        ["cantilever_fem", "cantilever_mpm", "cylinder_incline_slip_mpm", "coupled_beam_split", "disk_collision_mpm"]
            .iter()
            .map(|n| {
                let text = std::fs::read_to_string(root().join(format!("cases/{n}.json"))).unwrap();
                let mut v: Value = serde_json::from_str(&text).unwrap();
                v["limits"] = json!({"cells": 20000, "material_points": 20000, "steps": 100000});
                v
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

        /// Any text: a case or a one-line error.
        #[test]
        fn any_text_is_parsed_or_refused(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let text = String::from_utf8_lossy(&bytes);
            if let Err(e) = Case::parse(&text) {
                prop_assert!(!e.to_string().contains('\n'));
            }
        }

        /// Any JSON value as a case: parsed and built, or a one-line error.
        #[test]
        fn any_json_value_is_built_or_refused(v in value()) {
            one_line(Case::parse(&v.to_string()).and_then(Simulation::new))?;
        }

        /// A bundled case with one leaf replaced by any value: built or refused, never a panic.
        #[test]
        fn mutated_cases_are_built_or_refused(base in 0usize..5, leaf in any::<prop::sample::Index>(), v in value()) {
            let mut case = bases()[base].clone();
            let (mut leaves, mut objects) = (Vec::new(), Vec::new());
            walk(&case, &mut Vec::new(), &mut leaves, &mut objects);
            let steps: &Vec<Step> = leaf.get(&leaves);
            let mut target = &mut case;
            for s in steps {
                target = match s {
                    Step::Key(k) => &mut target[k.as_str()],
                    Step::Index(i) => &mut target[*i],
                };
            }
            *target = v;
            one_line(Case::parse(&case.to_string()).and_then(Simulation::new))?;
        }

        /// A bundled case with one number replaced by another (extreme, zero, negative,
        /// fractional where an integer is expected): built or refused, never a panic. These
        /// reach the model builder's checks rather than the parser's.
        #[test]
        fn cases_with_a_changed_number_are_built_or_refused(
            base in 0usize..5,
            leaf in any::<prop::sample::Index>(),
            x in prop_oneof![
                Just(0.0), Just(-1.0), Just(1e300), Just(-1e300), Just(1e-300), Just(4294967296.0),
                -100.0f64..100.0, (0u32..100).prop_map(f64::from),
            ],
        ) {
            let mut case = bases()[base].clone();
            let (mut leaves, mut objects) = (Vec::new(), Vec::new());
            walk(&case, &mut Vec::new(), &mut leaves, &mut objects);
            let numeric: Vec<&Vec<Step>> = leaves
                .iter()
                .filter(|steps| {
                    let mut v = &case;
                    for s in steps.iter() {
                        v = match s {
                            Step::Key(k) => &v[k.as_str()],
                            Step::Index(i) => &v[*i],
                        };
                    }
                    v.is_number()
                })
                .collect();
            let steps = leaf.get(&numeric).to_vec();
            let mut target = &mut case;
            for s in &steps {
                target = match s {
                    Step::Key(k) => &mut target[k.as_str()],
                    Step::Index(i) => &mut target[*i],
                };
            }
            *target = if x.fract() == 0.0 && x.abs() < 1e15 { json!(x as i64) } else { json!(x) };
            one_line(Case::parse(&case.to_string()).and_then(Simulation::new))?;
        }
    }
}
