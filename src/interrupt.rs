//! SIGINT and SIGTERM during `loam run`.
//!
//! The first signal asks the run to stop after the step in progress: the run loop sees
//! [`Interrupt::is_requested`] between steps, writes the results and a checkpoint of the last
//! converged step and ends with exit code 130. A second signal, for a step that takes too
//! long, ends the process at once and abandons that step; even then `summary.json` must not
//! stay at `"status": "running"` (issue 31). The signal handler runs on a thread of its own
//! (the `ctrlc` crate), which cannot reach the simulation that the run loop is changing, so
//! the run loop hands it the report as of each converged step ([`Interrupt::record`]) and
//! the handler writes that one, marked interrupted ([`Interrupt::abandon`]). The report is
//! kept under a mutex that the final write of the run also takes ([`Interrupt::finish`]):
//! a second signal after it finds nothing to write and cannot overwrite the final report.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use crate::output::summary::{seconds, RunEndReport, RunStatus, RunSummary, SUMMARY_FILE};

/// The report of the last converged step, where it goes and when that step ended.
#[derive(Debug)]
struct Recorded {
    dir: PathBuf,
    summary: RunSummary,
    /// Time of the last converged state (s).
    time: f64,
    /// End time of the case (s).
    end_time: f64,
}

/// What the signal handler and the run loop share (see the module doc).
#[derive(Debug, Default)]
pub struct Interrupt {
    requested: AtomicBool,
    recorded: Mutex<Option<Recorded>>,
}

impl Interrupt {
    /// No signal yet, no report recorded.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the run to stop after the step in progress; returns whether it had been asked
    /// already (a second signal).
    pub fn request(&self) -> bool {
        self.requested.swap(true, Ordering::SeqCst)
    }

    /// Whether a stop has been asked for.
    pub fn is_requested(&self) -> bool {
        self.requested.load(Ordering::SeqCst)
    }

    /// Keeps `summary` (of the converged state at `time`, with the case's `end_time`), to be
    /// written into `dir` if a second signal abandons the next step.
    pub fn record(&self, dir: &Path, summary: RunSummary, time: f64, end_time: f64) {
        let mut recorded = self.recorded.lock().unwrap_or_else(|e| e.into_inner());
        *recorded = Some(Recorded { dir: dir.to_path_buf(), summary, time, end_time });
    }

    /// Runs `write` (the final report of the run) and forgets the recorded report, both
    /// under the lock that [`Interrupt::abandon`] takes.
    pub fn finish<T>(&self, write: impl FnOnce() -> T) -> T {
        let mut recorded = self.recorded.lock().unwrap_or_else(|e| e.into_inner());
        *recorded = None;
        write()
    }

    /// For a second signal: writes the recorded report with the status `interrupted` and
    /// a reason saying that the step after its time was abandoned. Returns the file written,
    /// or `None` if there is nothing to write (the run has not started or has finished).
    pub fn abandon(&self) -> Option<std::io::Result<PathBuf>> {
        let mut recorded = self.recorded.lock().unwrap_or_else(|e| e.into_inner());
        let Recorded { dir, mut summary, time, end_time } = recorded.take()?;
        summary.status = RunStatus::Interrupted;
        summary.read_peak_memory();
        summary.end = Some(RunEndReport {
            reason: format!(
                "interrupted twice: the step after t = {} was abandoned, without a checkpoint; the last converged state is at t = {}",
                seconds(time),
                seconds(time)
            ),
            time,
            end_time,
        });
        Some(summary.write(&dir).map(|()| dir.join(SUMMARY_FILE)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::summary::WallTimeReport;

    fn summary() -> RunSummary {
        RunSummary {
            case: "c".into(),
            case_file: None,
            version: "0".into(),
            threads: 1,
            ranks: 1,
            formulation: "plane_strain".into(),
            thickness: 1.0,
            status: RunStatus::Running,
            end: None,
            steps: 3,
            newton: Default::default(),
            linear_solver: Default::default(),
            wall_time: WallTimeReport::default(),
            memory: Default::default(),
            monitors: Default::default(),
            monitor_units: Default::default(),
            grid_motion: Vec::new(),
            distributed: Vec::new(),
        }
    }

    /// A second signal writes the last recorded report as interrupted, with the peak memory
    /// read then; after the run's final report it writes nothing.
    #[test]
    fn abandon_writes_the_recorded_report_until_the_run_finishes() {
        let dir = std::env::temp_dir().join(format!("loam-interrupt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let interrupt = Interrupt::new();
        assert!(!interrupt.request() && interrupt.request() && interrupt.is_requested());
        assert!(interrupt.abandon().is_none(), "nothing recorded yet");
        interrupt.record(&dir, summary(), 0.25, 1.0);
        let path = interrupt.abandon().unwrap().unwrap();
        let written = RunSummary::read(&dir).unwrap();
        println!("{}: {:?} {:?}", path.display(), written.status, written.end);
        assert_eq!(written.status, RunStatus::Interrupted);
        let end = written.end.unwrap();
        assert!(end.reason.contains("abandoned") && end.time == 0.25 && written.steps == 3);
        // the recorded report carries no memory reading; the abandoned one reads it
        if cfg!(target_os = "linux") {
            assert!(written.memory.peak_rss_mb.is_some_and(|mb| mb > 0.0), "{:?}", written.memory);
        }
        interrupt.record(&dir, summary(), 0.5, 1.0);
        interrupt.finish(|| ());
        assert!(interrupt.abandon().is_none(), "the run wrote its final report");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
