//! `loam fmu`: packages a case as an FMI 3.0 co-simulation FMU ([`crate::fmu_package`]).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::bad_input;

/// Writes the FMU of `case` to `output` (default `<case name>.fmu`) with the loam-fmu
/// library `library` (default: next to the executable).
pub fn fmu_command(case: &Path, output: Option<PathBuf>, library: Option<PathBuf>) -> ExitCode {
    use crate::fmu_package::{default_library_path, package, PackageError};
    let output = output
        .unwrap_or_else(|| PathBuf::from(format!("{}.fmu", case.file_stem().unwrap_or_default().to_string_lossy())));
    match package(case, &output, &library.unwrap_or_else(default_library_path)) {
        Ok(s) => {
            println!(
                "loam: wrote {} (FMI 3.0 co-simulation, model identifier {}; inputs: {}; outputs: {})",
                output.display(),
                s.model_identifier,
                if s.inputs.is_empty() { "none".into() } else { s.inputs.join(", ") },
                s.outputs.join(", ")
            );
            ExitCode::SUCCESS
        }
        Err(PackageError::Case(e)) => bad_input(&e),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
