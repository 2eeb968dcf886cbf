//! `loam plot`: draws a run's results ([`crate::plot`]), prints what it wrote and maps
//! errors to exit codes.

use std::path::Path;
use std::process::ExitCode;

use crate::plot::{plot, PlotOptions};

/// Draws the results in `dir` with `options`; prints each file written and the field's range.
pub fn plot_command(dir: &Path, options: &PlotOptions) -> ExitCode {
    match plot(dir, options) {
        Ok(report) => {
            for note in &report.notes {
                eprintln!("note: {note}");
            }
            for (file, time) in &report.files {
                match time {
                    Some(t) => println!("loam: wrote {} (t = {t} s)", file.display()),
                    None => println!("loam: wrote {}", file.display()),
                }
            }
            if let Some((field, min, max, unit)) = &report.field {
                println!(
                    "loam: {field} from {min:.4e} to {max:.4e}{}; {:.3} s per frame",
                    if unit.is_empty() || unit == "1" { String::new() } else { format!(" {unit}") },
                    report.seconds_per_frame
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
