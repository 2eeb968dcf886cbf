//! The CLI run loop: steps a [`Simulation`] to its end time with a progress bar, writes
//! results as it goes, and on failure keeps everything converged so far. The run report
//! `summary.json` is written when the loop starts and rewritten when it ends, however it
//! ends.
//!
//! Nothing converged is lost: checkpoints are written as `analysis.checkpoint` says; an
//! interruption (SIGINT, SIGTERM) lets the current step finish, writes its results and a
//! checkpoint, and ends the run ([`RunEnd::Interrupted`]); if writing the results fails
//! (a full disk), the state is saved as a checkpoint in the system's temporary directory
//! and the error says where.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use crate::case::CheckpointSpec;
use crate::checkpoint::{self, Checkpoint};
use crate::interrupt::Interrupt;
use crate::output::results::{ResultWriter, WriterState};
use crate::output::summary::{seconds, RunEndReport, RunStatus, RunSummary, WallTimeReport};
use crate::simulation::{RunError, Simulation};

/// How a run ended.
#[derive(Debug)]
pub enum RunEnd {
    /// Reached the end time.
    Finished,
    /// Stopped by a step that failed after all cuts; results up to `error.time` written.
    Failed(RunError),
    /// Interrupted after a converged step; results so far and a checkpoint (this file)
    /// written.
    Interrupted(PathBuf),
}

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Show a progress bar.
    pub progress: bool,
    /// [`checkpoint::fingerprint`] of the case file (stored in checkpoints).
    pub case_fingerprint: u32,
    /// Continue the results of a checkpoint (the simulation is restored already).
    pub resume: Option<WriterState>,
    /// Set by a signal handler: finish the step, checkpoint and stop; it also keeps the
    /// report of the last converged step for a second signal ([`Interrupt`]).
    pub interrupt: Option<Arc<Interrupt>>,
}

/// Runs `sim` to its end time writing into `out_dir` (see the module doc). Returns how the
/// run ended and its wall time (s).
pub fn run(sim: &mut Simulation, out_dir: &Path, options: &RunOptions) -> std::io::Result<(RunEnd, f64)> {
    // the loop's clock starts after the set-up (output files, the first report), which
    // run_loop restarts it at
    let mut loop_start = Instant::now();
    let mut output_time = 0.0;
    let result = run_loop(sim, out_dir, options, &mut output_time, &mut loop_start);
    let wall = loop_start.elapsed().as_secs_f64();
    let mut summary =
        RunSummary::of(sim, RunStatus::Running, WallTimeReport::new(wall, &sim.stats.timings, output_time));
    let (status, reason) = match &result {
        Ok(RunEnd::Finished) if sim.at_rest => {
            (RunStatus::AtRest, format!("at rest (analysis.stop_at_rest) at t = {}", seconds(sim.time())))
        }
        Ok(RunEnd::Finished) => (RunStatus::Finished, format!("reached the end time {}", seconds(sim.end_time()))),
        Ok(RunEnd::Failed(e)) => (RunStatus::Failed, format!("stopped at {e}")),
        Ok(RunEnd::Interrupted(path)) => (
            RunStatus::Interrupted,
            format!("interrupted at t = {}; checkpoint {}", seconds(sim.time()), path.display()),
        ),
        Err(e) => (RunStatus::OutputError, format!("writing results to {}: {e}", out_dir.display())),
    };
    summary.status = status;
    summary.end = Some(RunEndReport { reason, time: sim.time(), end_time: sim.end_time() });
    // the final report, which a second signal must no longer overwrite
    let write = || summary.write(out_dir);
    let written = match &options.interrupt {
        Some(interrupt) => interrupt.finish(write),
        None => write(),
    };
    match result {
        Ok(end) => {
            written?;
            Ok((end, wall))
        }
        // the report was written as best effort: the directory may be what failed
        Err(e) => Err(e),
    }
}

/// When the next checkpoint is due.
pub(crate) struct CheckpointClock {
    spec: Option<CheckpointSpec>,
    last_step: usize,
    last_time: Instant,
}

impl CheckpointClock {
    /// The clock of `sim`'s case, started now at its step.
    pub(crate) fn new(sim: &Simulation) -> Self {
        Self { spec: sim.case.analysis.checkpoint, last_step: sim.step, last_time: Instant::now() }
    }

    fn due(&self, step: usize) -> bool {
        let Some(spec) = self.spec else { return false };
        spec.every_steps.is_some_and(|n| step >= self.last_step + n)
            || spec.every_seconds.is_some_and(|s| self.last_time.elapsed().as_secs_f64() >= s)
    }

    /// Whether a checkpoint is due after `sim`'s last step; where the model's points are
    /// distributed, agreed by the ranks (collective: saving the state gathers every rank's
    /// points, so every rank must take part; `every_seconds` is measured on each rank, and
    /// one is enough). The clock restarts when it is due.
    pub(crate) fn due_on_every_rank(&mut self, sim: &Simulation) -> bool {
        let mut due = self.due(sim.step);
        if sim.model.has_distributed_points() {
            due = sim.case.solver.ranks.any(due);
        }
        if due {
            self.last_step = sim.step;
            self.last_time = Instant::now();
        }
        due
    }
}

/// The checkpoint of `sim` with the model's state `model` (taken first: a collective where the
/// points are distributed) and the writer's state `writer`.
fn checkpoint_of(
    sim: &Simulation,
    model: loam_fem::model::ModelState,
    writer: Option<WriterState>,
    fingerprint: u32,
) -> Checkpoint {
    Checkpoint {
        loam_version: env!("CARGO_PKG_VERSION").to_string(),
        case_name: sim.case.name.clone(),
        case_fingerprint: fingerprint,
        simulation: sim.save_state(),
        model,
        writer,
    }
}

/// Writes the checkpoint of the committed state to `out_dir/checkpoints` (keeping the
/// newest `keep`) and returns its file.
fn write_checkpoint(
    sim: &Simulation,
    writer: &mut ResultWriter,
    out_dir: &Path,
    fingerprint: u32,
    keep: usize,
) -> std::io::Result<PathBuf> {
    let path = checkpoint::path_of(out_dir, sim.step);
    let model = sim.model.save_state();
    let state = writer.state()?;
    checkpoint::write(&path, &checkpoint_of(sim, model, Some(state), fingerprint)).map_err(std::io::Error::other)?;
    checkpoint::prune(out_dir, keep);
    Ok(path)
}

/// After a failure to write results: the committed state as a checkpoint in the system's
/// temporary directory (the writer's state as of its last complete row), and the error
/// with where it went.
fn rescue(sim: &Simulation, writer: Option<WriterState>, fingerprint: u32, error: std::io::Error) -> std::io::Error {
    if sim.model.has_distributed_points() {
        // rank 0 alone is here: the state would gather the other ranks' points, which they do
        // not send (this rank's exit ends the run under mpirun; docs/distributed.md, stage 3)
        return std::io::Error::new(
            error.kind(),
            format!(
                "{error}; the state at t = {} (step {}) was not saved: its material points are distributed over the MPI ranks (the results up to the last complete output are written; resume from an earlier checkpoint, analysis.checkpoint)",
                seconds(sim.time()),
                sim.step
            ),
        );
    }
    let path =
        std::env::temp_dir().join(format!("loam_{}_{}_step_{}.ckpt", sim.case.name, std::process::id(), sim.step));
    match checkpoint::write(&path, &checkpoint_of(sim, sim.model.save_state(), writer, fingerprint)) {
        Ok(()) => std::io::Error::new(
            error.kind(),
            format!(
                "{error}; the state at t = {} (step {}) was saved to {} (free space, then resume with --resume {})",
                seconds(sim.time()),
                sim.step,
                path.display(),
                path.display()
            ),
        ),
        Err(e) => std::io::Error::new(
            error.kind(),
            format!("{error}; saving the state at t = {} elsewhere failed too: {e}", seconds(sim.time())),
        ),
    }
}

/// The steps and the results written after each; `output_time` accumulates the time spent
/// writing, and `loop_start` is set when the set-up (the writer's files, the first
/// `summary.json`) is done and the loop proper starts (`wall_time.total` counts from it).
fn run_loop(
    sim: &mut Simulation,
    out_dir: &Path,
    options: &RunOptions,
    output_time: &mut f64,
    loop_start: &mut Instant,
) -> std::io::Result<RunEnd> {
    let timed = |output_time: &mut f64, f: &mut dyn FnMut() -> std::io::Result<()>| {
        let t = Instant::now();
        let r = f();
        *output_time += t.elapsed().as_secs_f64();
        r
    };
    let fingerprint = options.case_fingerprint;
    let mut writer = match &options.resume {
        Some(state) => ResultWriter::resume(out_dir, sim, state.clone())?,
        None => ResultWriter::create(out_dir, sim)?,
    };
    RunSummary::of(sim, RunStatus::Running, WallTimeReport::default()).write(out_dir)?;
    let started = Instant::now();
    *loop_start = started;
    // the report a second signal writes, as of each converged state (its peak memory is read
    // when it is written: `Interrupt::abandon`)
    let record = |sim: &Simulation, output_time: f64| {
        if let Some(interrupt) = &options.interrupt {
            let wall = WallTimeReport::new(started.elapsed().as_secs_f64(), &sim.stats.timings, output_time);
            interrupt.record(out_dir, RunSummary::snapshot(sim, RunStatus::Running, wall), sim.time(), sim.end_time());
        }
    };
    record(sim, *output_time);
    if options.resume.is_none() {
        timed(output_time, &mut || writer.write_step(sim, true))?;
    }
    let keep = sim.case.analysis.checkpoint.map_or(2, |s| s.keep);
    let mut clock = CheckpointClock::new(sim);
    // fixed steps: progress in planned steps; adaptive steps: in per mille of the end time
    let adaptive = sim.case.analysis.adaptive.is_some();
    let length = if adaptive { 1000 } else { sim.total_steps() as u64 };
    let bar = if options.progress { ProgressBar::new(length) } else { ProgressBar::hidden() };
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
        if interrupted_on_any_rank(sim, options) {
            let path = write_checkpoint(sim, &mut writer, out_dir, fingerprint, keep)?;
            break RunEnd::Interrupted(path);
        }
        // converged sub-steps of a cut step are written as they come (nothing converged is
        // lost if a later sub-step fails)
        let mut substep_error = None;
        let out_time = *output_time;
        let result = sim.step_observed(&mut |sim| {
            if substep_error.is_none() {
                substep_error = writer.write_step(sim, true).err();
                record(sim, out_time);
            }
        });
        if let Some(e) = substep_error {
            bar.finish_and_clear();
            return Err(rescue(sim, writer.last_complete_state(), fingerprint, e));
        }
        match result {
            Ok(s) => {
                bar.set_position((length as f64 * sim.time() / sim.end_time()).round() as u64);
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
                if let Err(e) = timed(output_time, &mut || writer.write_step(sim, last)) {
                    bar.finish_and_clear();
                    return Err(rescue(sim, writer.last_complete_state(), fingerprint, e));
                }
                if !last && clock.due_on_every_rank(sim) {
                    write_checkpoint(sim, &mut writer, out_dir, fingerprint, keep)?;
                }
                record(sim, *output_time);
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

/// Whether a signal asked to stop (a collective in a distributed run: every rank stops before
/// the same step if any rank received it; every rank's loop asks once before each step).
pub fn interrupted_on_any_rank(sim: &Simulation, options: &RunOptions) -> bool {
    let here = options.interrupt.as_ref().is_some_and(|i| i.is_requested());
    !sim.case.solver.ranks.all(!here)
}

/// Default output directory `out/<case name>`.
pub fn default_out_dir(case_name: &str) -> PathBuf {
    PathBuf::from("out").join(case_name)
}
