//! `loam fit`: calibrates a law to laboratory curves ([`crate::fit`]), prints the fitted
//! parameters with their intervals and writes fit.csv, material.json and fit_summary.json.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::bad_input;
use crate::fit::{self, FitFile, Status};
use crate::run::default_out_dir;

/// Fits the fit file `path`, writing to `out` (default `out/<fit file name>`). Exit code 0
/// converged, 1 not converged (the best point so far is written) or a failure, 2 bad input.
pub fn fit_command(path: &Path, out: Option<PathBuf>) -> ExitCode {
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let out = out.unwrap_or_else(|| default_out_dir(&crate::case::output_name(&name)));
    let file = match crate::input::read_strict::<FitFile>(path, "fit file") {
        Ok(f) => f,
        Err(e) => return bad_input(&e),
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let problem = match fit::Problem::new(&file, base) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(e.exit_code());
        }
    };
    let result = fit::fit(&problem);
    print!("{}", fit::output::report(&problem, &result));
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    match fit::output::write(&problem, &result, &out) {
        Ok(files) => {
            let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            println!("loam: wrote {}", names.join(", "));
        }
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    }
    println!("material block:\n{}", fit::output::material_json(&problem, &result.theta));
    match &result.status {
        Status::Converged(_) => ExitCode::SUCCESS,
        Status::NotConverged(why) => {
            eprintln!("error: the fit did not converge: {why}; wrote the best point so far");
            ExitCode::from(1)
        }
    }
}
