//! Exporters of Loam cases into other codes' input (`loam export`).

pub mod kratos;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The formats `loam export` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A Kratos Multiphysics MPM case folder (ProjectParameters.json, Grid.mdpa, Body.mdpa,
    /// ParticleMaterials.json).
    Kratos,
}

/// `loam export FORMAT CASE [-o DIR]`: exports, prints every note (one line each, on stderr)
/// and the files written; exit code 2 on a case the format cannot express (one line naming
/// the JSON path), 0 otherwise. The folder defaults to `<case name>_kratos`.
pub fn cli(format: Format, case: &Path, output: Option<&Path>) -> ExitCode {
    let out = output.map(Path::to_path_buf).unwrap_or_else(|| {
        let stem = case.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "case".into());
        PathBuf::from(format!("{stem}_kratos"))
    });
    match format {
        Format::Kratos => crate::cli::conversion(
            kratos::export(case, &out).map(|e| (e.files, e.notes)),
            "keys approximated or left out",
        ),
    }
}
