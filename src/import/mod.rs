//! Importers of other codes' case formats into Loam cases (`loam import`).

pub mod kratos;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The formats `loam import` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A Kratos Multiphysics MPM case folder (ProjectParameters.json, .mdpa files, materials).
    Kratos,
}

/// `loam import FORMAT DIR [-o CASE]`: imports, prints every note (one line each, on stderr)
/// and the files written; exit code 2 on bad input, 0 otherwise. The case defaults to
/// `<folder name>.json` in the current directory.
pub fn cli(format: Format, dir: &Path, output: Option<&Path>) -> ExitCode {
    let out = output.map(Path::to_path_buf).unwrap_or_else(|| {
        let name = dir.canonicalize().ok().and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()));
        PathBuf::from(format!("{}.json", name.unwrap_or_else(|| "kratos".into())))
    });
    match format {
        Format::Kratos => crate::cli::conversion(
            kratos::import(dir, &out).map(|i| (i.files, i.notes)),
            "keys or blocks ignored or approximated",
        ),
    }
}
