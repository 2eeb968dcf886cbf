//! The commands of the `loam` executable. Each takes its parsed arguments and returns the
//! process's exit code (0 done, 1 a run or write that failed, 2 bad input, 130 interrupted);
//! `main.rs` only parses the command line (clap) and calls them.
//!
//! - [`run`]: `loam run`, a case to its end with output, checkpoints and signals;
//! - [`check`]: `loam check`, a case built without running;
//! - [`plot`]: `loam plot`, pictures of a run's results;
//! - [`law`]: `loam law`, one material point along a laboratory path;
//! - [`fit`]: `loam fit`, a law calibrated to laboratory curves;
//! - [`fmu`]: `loam fmu`, a case packaged as an FMU.

pub mod check;
pub mod fit;
pub mod fmu;
pub mod law;
pub mod plot;
pub mod run;

use std::process::ExitCode;

use crate::case::CaseError;

/// The outcome of a conversion between formats (`loam import`, `loam export`): the notes
/// (one line each, on stderr), the files written and a count of the notes, exit code 0; or
/// the one-line error and exit code 2.
pub fn conversion<E: std::fmt::Display>(
    outcome: Result<(Vec<std::path::PathBuf>, Vec<String>), E>,
    noted: &str,
) -> ExitCode {
    match outcome {
        Ok((files, notes)) => {
            for note in &notes {
                eprintln!("note: {note}");
            }
            for f in &files {
                println!("loam: wrote {}", f.display());
            }
            println!("loam: {} notes ({noted}, listed above)", notes.len());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Prints a bad-input error (one line) and returns exit code 2.
pub fn bad_input(e: &CaseError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(2)
}
