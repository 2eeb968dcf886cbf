//! What `loam fit` writes: `fit.csv` (measured and fitted curves), `material.json` (the
//! material block with the fitted values, ready to paste into a case) and
//! `fit_summary.json` (parameters, intervals, correlation, misfit per test, status), and
//! the text report on stdout.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::{FitError, FitResult, Problem, Status};

/// `v` rounded to 6 significant digits (the material block and the report: the data never
/// determine a parameter better).
pub fn round(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    format!("{v:.5e}").parse().unwrap_or(v)
}

/// The material block with the fitted values, `law` first, as pretty JSON.
pub fn material_json(problem: &Problem, theta: &[f64]) -> String {
    let block = problem.material_block(theta);
    let mut s = String::from("{\n");
    let mut entries: Vec<(&String, &Value)> = block.iter().collect();
    entries.sort_by_key(|(k, _)| *k != "law");
    for (i, (k, v)) in entries.iter().enumerate() {
        let value = match (v, problem.parameters.iter().position(|p| &p.name == *k)) {
            (_, Some(j)) => Value::from(round(theta[j])).to_string(),
            _ => v.to_string(),
        };
        let _ = writeln!(s, "  \"{k}\": {value}{}", if i + 1 < entries.len() { "," } else { "" });
    }
    s.push('}');
    s
}

/// `fit.csv`: one row per measured point and curve: `test, x_quantity, x_unit, x,
/// y_quantity, y_unit, measured, fitted`, in the CSV's units and sign.
pub fn fit_csv(problem: &Problem, fitted: &[Vec<Vec<f64>>]) -> String {
    let mut s = String::from("test,x_quantity,x_unit,x,y_quantity,y_unit,measured,fitted\n");
    for (test, sim) in problem.tests.iter().zip(fitted) {
        let xs = &test.spec.x;
        for (curve, y_sim) in test.curves.iter().zip(sim) {
            for ((x, y), f) in test.x.iter().zip(&curve.y).zip(y_sim) {
                let _ = writeln!(
                    s,
                    "{},{},{},{x:e},{},{},{y:e},{f:e}",
                    test.spec.name,
                    xs.quantity,
                    xs.unit.label(),
                    curve.column.quantity,
                    curve.column.unit.label()
                );
            }
        }
    }
    s
}

/// `fit_summary.json`.
pub fn summary_json(problem: &Problem, result: &FitResult) -> Value {
    let st = &result.stats;
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    let parameters: Vec<Value> = problem
        .parameters
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let (v, h) = (result.theta[j], st.half_width(j));
            json!({
                "name": p.name, "value": v, "initial": p.initial, "min": p.min, "max": p.max,
                "standard_error": finite(st.standard_errors[j]),
                "ci95": [finite(v - h), finite(v + h)],
                "at_bound": p.at_bound(v),
            })
        })
        .collect();
    let n = problem.parameters.len();
    let correlation: Vec<Vec<Value>> =
        (0..n).map(|a| (0..n).map(|b| finite(st.correlation[(a, b)])).collect()).collect();
    let tests: Vec<Value> = problem
        .tests
        .iter()
        .enumerate()
        .map(|(t, test)| {
            let curves: Vec<Value> = test
                .curves
                .iter()
                .enumerate()
                .map(|(c, curve)| {
                    json!({"quantity": curve.column.quantity, "rms_relative": finite(st.rms[t][c]),
                           "runs_z": finite(st.runs_z[t][c])})
                })
                .collect();
            json!({"name": test.spec.name, "points": test.x.len(), "weight": test.spec.weight, "curves": curves})
        })
        .collect();
    let (converged, reason) = match &result.status {
        Status::Converged(r) => (true, r.clone()),
        Status::NotConverged(r) => (false, r.clone()),
    };
    json!({
        "law": problem.law,
        "converged": converged,
        "reason": reason,
        "iterations": result.iterations,
        "evaluations": result.evaluations,
        "seconds": result.seconds,
        "sum_of_squares": st.sum_of_squares,
        "residuals": st.residuals,
        "degrees_of_freedom": st.dof,
        "t_quantile_0975": finite(st.t_quantile),
        "parameters": parameters,
        "correlation": correlation,
        "tests": tests,
        "warnings": result.warnings,
        "material": serde_json::from_str::<Value>(&material_json(problem, &result.theta)).unwrap_or(Value::Null),
    })
}

/// Writes `fit.csv`, `material.json` and `fit_summary.json` to `out`; returns the files.
pub fn write(problem: &Problem, result: &FitResult, out: &Path) -> Result<Vec<PathBuf>, FitError> {
    let err = |file: &Path, e: std::io::Error| FitError::Write { file: file.to_path_buf(), reason: e.to_string() };
    std::fs::create_dir_all(out).map_err(|e| err(out, e))?;
    let files = [
        ("fit.csv", fit_csv(problem, &result.fitted)),
        ("material.json", material_json(problem, &result.theta) + "\n"),
        ("fit_summary.json", serde_json::to_string_pretty(&summary_json(problem, result)).unwrap_or_default() + "\n"),
    ];
    let mut written = Vec::new();
    for (name, text) in files {
        let file = out.join(name);
        std::fs::write(&file, text).map_err(|e| err(&file, e))?;
        written.push(file);
    }
    Ok(written)
}

/// The text report: status, parameters with intervals, correlation, misfit per test.
pub fn report(problem: &Problem, result: &FitResult) -> String {
    let st = &result.stats;
    let mut s = String::new();
    let n = problem.parameters.len();
    let points: usize = problem.tests.iter().map(|t| t.x.len()).sum();
    let status = match &result.status {
        Status::Converged(r) => format!("converged ({r})"),
        Status::NotConverged(r) => format!("NOT converged: {r}; the best point so far follows"),
    };
    let _ = writeln!(
        s,
        "loam fit: {}, {n} parameters from {} tests ({points} points, {} residuals); {status}; {} iterations, {} evaluations, {:.2} s",
        problem.law,
        problem.tests.len(),
        st.residuals,
        result.iterations,
        result.evaluations,
        result.seconds
    );
    let _ = writeln!(
        s,
        "  {:<28} {:>13} {:>13}   {:<29} {:>12}  bounds",
        "parameter",
        "value",
        format!("±95 % (t={:.3})", st.t_quantile),
        "95 % interval",
        "initial"
    );
    for (j, p) in problem.parameters.iter().enumerate() {
        let (v, h) = (result.theta[j], st.half_width(j));
        let _ = writeln!(
            s,
            "  {:<28} {:>13} {:>13}   {:<29} {:>12}  [{}, {}]{}",
            p.name,
            format!("{}", round(v)),
            format!("{:.3e}", h),
            format!("[{}, {}]", round(v - h), round(v + h)),
            format!("{}", p.initial),
            p.min,
            p.max,
            if p.at_bound(v) { "  AT BOUND" } else { "" }
        );
    }
    if n > 1 {
        let _ = writeln!(s, "  correlation:");
        for a in 0..n {
            let row: Vec<String> = (0..n).map(|b| format!("{:>6.3}", st.correlation[(a, b)])).collect();
            let _ = writeln!(s, "  {:<28} {}", problem.parameters[a].name, row.join(" "));
        }
    }
    let _ = writeln!(s, "  misfit per test (rms of (fitted − measured) / largest measured value):");
    for (t, test) in problem.tests.iter().enumerate() {
        let curves: Vec<String> = test
            .curves
            .iter()
            .enumerate()
            .map(|(c, curve)| format!("{} {:.3} %", curve.column.quantity, 100.0 * st.rms[t][c]))
            .collect();
        let _ = writeln!(s, "  {:<28} {}", test.spec.name, curves.join(", "));
    }
    s
}
