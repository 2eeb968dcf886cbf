//! The CLI run loop: steps a [`Simulation`] to its end time with a progress bar, writes
//! results as it goes, and on failure keeps everything converged so far. The run report
//! `summary.json` is written when the loop starts and rewritten when it ends, however it
//! ends.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use crate::output::results::ResultWriter;
use crate::output::summary::{seconds, RunEndReport, RunStatus, RunSummary, WallTimeReport};
use crate::simulation::{RunError, Simulation};

/// How a run ended.
#[derive(Debug)]
pub enum RunEnd {
    /// Reached the end time.
    Finished,
    /// Stopped by a step that failed after all cuts; results up to `error.time` written.
    Failed(RunError),
}

/// Runs `sim` to its end time writing into `out_dir`; `progress` shows a progress bar.
/// Returns how the run ended and its wall time (s).
pub fn run(sim: &mut Simulation, out_dir: &Path, progress: bool) -> std::io::Result<(RunEnd, f64)> {
    let start = Instant::now();
    let mut output_time = 0.0;
    let result = run_loop(sim, out_dir, progress, &mut output_time);
    let wall = start.elapsed().as_secs_f64();
    let mut summary =
        RunSummary::of(sim, RunStatus::Running, WallTimeReport::new(wall, &sim.stats.timings, output_time));
    let (status, reason) = match &result {
        Ok(RunEnd::Finished) if sim.at_rest => {
            (RunStatus::AtRest, format!("at rest (analysis.stop_at_rest) at t = {}", seconds(sim.time())))
        }
        Ok(RunEnd::Finished) => (RunStatus::Finished, format!("reached the end time {}", seconds(sim.end_time()))),
        Ok(RunEnd::Failed(e)) => (RunStatus::Failed, format!("stopped at {e}")),
        Err(e) => (RunStatus::OutputError, format!("writing results to {}: {e}", out_dir.display())),
    };
    summary.status = status;
    summary.end = Some(RunEndReport { reason, time: sim.time(), end_time: sim.end_time() });
    match result {
        Ok(end) => {
            summary.write(out_dir)?;
            Ok((end, wall))
        }
        Err(e) => {
            // best effort: the directory may be what failed
            let _ = summary.write(out_dir);
            Err(e)
        }
    }
}

/// The steps and the results written after each; `output_time` accumulates the time spent
/// writing.
fn run_loop(sim: &mut Simulation, out_dir: &Path, progress: bool, output_time: &mut f64) -> std::io::Result<RunEnd> {
    let timed = |output_time: &mut f64, f: &mut dyn FnMut() -> std::io::Result<()>| {
        let t = Instant::now();
        let r = f();
        *output_time += t.elapsed().as_secs_f64();
        r
    };
    let mut writer = ResultWriter::create(out_dir, sim)?;
    RunSummary::of(sim, RunStatus::Running, WallTimeReport::default()).write(out_dir)?;
    timed(output_time, &mut || writer.write_step(sim, true))?;
    // fixed steps: progress in steps; adaptive steps: in per mille of the end time
    let adaptive = sim.case.analysis.adaptive.is_some();
    let length = if adaptive { 1000 } else { sim.total_steps() as u64 };
    let bar = if progress { ProgressBar::new(length) } else { ProgressBar::hidden() };
    let template = if adaptive {
        "{bar:30} {percent}%  {msg}  [{elapsed_precise} < {eta}]"
    } else {
        "{bar:30} {pos}/{len} steps  {msg}  [{elapsed_precise} < {eta}]"
    };
    bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
    let end = loop {
        if sim.finished() {
            break RunEnd::Finished;
        }
        match sim.step() {
            Ok(s) => {
                bar.set_position(if adaptive {
                    (1000.0 * sim.time() / sim.end_time()) as u64
                } else {
                    sim.step as u64
                });
                let blocks = if sim.is_coupled() {
                    let b = s.block_residual;
                    format!(" (soil {:.1e}, interface {:.1e}, structure {:.1e})", b.soil, b.interface, b.structure)
                } else {
                    String::new()
                };
                bar.set_message(format!(
                    "t = {:.4e} s  Δt {:.2e}  Newton {}{}  residual {:.2e}{blocks}",
                    sim.time(),
                    s.last_time_step,
                    s.iterations,
                    if s.substeps > 1 { format!(" ({} sub-steps)", s.substeps) } else { String::new() },
                    s.residual
                ));
                let last = sim.finished();
                timed(output_time, &mut || writer.write_step(sim, last))?;
            }
            Err(e) => break RunEnd::Failed(e),
        }
    };
    if let RunEnd::Failed(_) = end {
        timed(output_time, &mut || writer.write_final_state(sim))?;
    }
    bar.finish_and_clear();
    Ok(end)
}

/// Default output directory `out/<case name>`.
pub fn default_out_dir(case_name: &str) -> PathBuf {
    PathBuf::from("out").join(case_name)
}
