//! `loam law`: drives one material point of a law along a laboratory path
//! ([`loam_laws::driver`]) and writes path.csv.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::bad_input;
use crate::run::default_out_dir;

/// Runs the path file `path`, writing to `out` (default `out/<path name>`).
pub fn law_command(path: &Path, out: Option<PathBuf>) -> ExitCode {
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let out = out.unwrap_or_else(|| default_out_dir(&crate::case::output_name(&name)));
    let file = match crate::input::read_strict::<loam_laws::driver::PathFile>(path, "path file") {
        Ok(f) => f,
        Err(e) => return bad_input(&e),
    };
    match loam_laws::driver::run_parsed_path(&file, &out) {
        Ok(s) => {
            println!(
                "loam: {} ({} rows): peak q = {:.4} kPa, final p = {:.4} kPa, final q = {:.4} kPa; wrote {}",
                s.law,
                s.rows,
                s.peak_q / 1e3,
                s.final_p / 1e3,
                s.final_q / 1e3,
                out.join("path.csv").display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            use loam_laws::driver::DriverError;
            eprintln!("error: {}", crate::input::compact_numbers(&e.to_string()));
            // bad input 2; a material point that cannot follow the path, or a write
            // failure, 1 (issue 16: a divergence was reported as bad input)
            ExitCode::from(match e {
                DriverError::Input { .. } | DriverError::Read { .. } => 2,
                DriverError::Law { .. } | DriverError::ControlNotConverged { .. } | DriverError::Write { .. } => 1,
            })
        }
    }
}
