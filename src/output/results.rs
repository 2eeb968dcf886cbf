//! Everything a run writes: `monitors.csv` (a row per step, flushed as it goes) and, per
//! domain, a `.vtu` per output step with a `.pvd` series that stays valid if the run stops.
//! In a distributed run rank 0 writes all of it and the other ranks their pieces of the VTK
//! output only ([`ResultWriter::pieces`]), at the same steps.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::simulation::Simulation;

/// What the writer has written, for checkpoints: a resumed run continues `monitors.csv` and
/// the `.pvd` series from there, without duplicate or missing rows.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct WriterState {
    /// Length of `monitors.csv` (bytes).
    pub monitors_length: u64,
    /// Step of its last row.
    pub rows_step: usize,
    /// Step of the last VTK output.
    pub last_vtk_step: Option<usize>,
    /// Last `time_interval` multiple written.
    pub last_vtk_slot: i64,
    /// The `.pvd` series.
    pub vtk: Option<super::vtk_output::VtkState>,
}

/// Writer of a run's results.
pub struct ResultWriter {
    dir: PathBuf,
    /// `None` on a rank other than 0 of a distributed run, which writes VTK pieces only.
    monitors: Option<BufWriter<File>>,
    vtk: Option<super::vtk_output::VtkSeries>,
    interval: usize,
    time_interval: Option<f64>,
    last_vtk_step: Option<usize>,
    /// Index of the last `time_interval` multiple written.
    last_vtk_slot: i64,
    /// Step of the last row of `monitors.csv`.
    rows_step: usize,
    /// Length of `monitors.csv` after the last complete [`ResultWriter::write_step`].
    complete_length: u64,
}

impl ResultWriter {
    /// Creates `dir` and the files of the series.
    pub fn create(dir: &Path, sim: &Simulation) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut monitors = BufWriter::new(File::create(dir.join("monitors.csv"))?);
        write!(monitors, "time")?;
        for name in sim.monitor_names() {
            write!(monitors, ",{name}")?;
        }
        writeln!(monitors)?;
        let vtk = if sim.case.output.vtk { Some(super::vtk_output::VtkSeries::new(dir)) } else { None };
        Ok(Self {
            dir: dir.to_path_buf(),
            monitors: Some(monitors),
            vtk,
            interval: sim.case.output.interval,
            time_interval: sim.case.output.time_interval,
            last_vtk_step: None,
            last_vtk_slot: 0,
            rows_step: 0,
            complete_length: 0,
        })
    }

    /// The writer of a rank other than 0 in a distributed run: its pieces of the VTK output
    /// at the steps rank 0 writes them ([`super::pvtu`]), continuing `resume` (the
    /// checkpoint's writer state, which every rank reads) if given; no monitors, no series.
    pub fn pieces(dir: &Path, sim: &Simulation, resume: Option<&WriterState>) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let vtk = if sim.case.output.vtk { Some(super::vtk_output::VtkSeries::new(dir)) } else { None };
        let mut writer = Self {
            dir: dir.to_path_buf(),
            monitors: None,
            vtk,
            interval: sim.case.output.interval,
            time_interval: sim.case.output.time_interval,
            last_vtk_step: resume.and_then(|s| s.last_vtk_step),
            last_vtk_slot: resume.map_or(0, |s| s.last_vtk_slot),
            rows_step: resume.map_or(0, |s| s.rows_step),
            complete_length: 0,
        };
        match resume {
            None => writer.write_step(sim, true)?,
            Some(state) if state.rows_step < sim.step => writer.write_step(sim, false)?,
            Some(_) => {}
        }
        Ok(writer)
    }

    /// The state after the last complete [`ResultWriter::write_step`] (what survives a
    /// failure in the middle of one), without touching the files.
    pub fn last_complete_state(&self) -> Option<WriterState> {
        Some(WriterState {
            monitors_length: self.complete_length,
            rows_step: self.rows_step,
            last_vtk_step: self.last_vtk_step,
            last_vtk_slot: self.last_vtk_slot,
            vtk: self.vtk.as_ref().map(|v| v.state()),
        })
    }

    /// What has been written so far (after a flush).
    pub fn state(&mut self) -> std::io::Result<WriterState> {
        let monitors_length = match &mut self.monitors {
            Some(m) => {
                m.flush()?;
                m.get_ref().metadata()?.len()
            }
            None => 0,
        };
        Ok(WriterState {
            monitors_length,
            rows_step: self.rows_step,
            last_vtk_step: self.last_vtk_step,
            last_vtk_slot: self.last_vtk_slot,
            vtk: self.vtk.as_ref().map(|v| v.state()),
        })
    }

    /// Continues the results of a checkpoint in `dir`: `monitors.csv` cut back to its length
    /// then (rows of steps after the checkpoint, written before an interruption, are
    /// dropped; the resumed run writes them again), the `.pvd` series rewritten with the data
    /// sets up to it. The state's own row is written if the checkpoint was taken before it
    /// (an output failure).
    pub fn resume(dir: &Path, sim: &Simulation, state: WriterState) -> std::io::Result<Self> {
        let path = dir.join("monitors.csv");
        let file = std::fs::OpenOptions::new().append(true).open(&path).map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("{}: {e} (the results of the checkpoint's run are not here)", path.display()),
            )
        })?;
        let length = file.metadata()?.len();
        if length < state.monitors_length {
            return Err(std::io::Error::other(format!(
                "{} is shorter ({length} bytes) than when the checkpoint was written ({} bytes)",
                path.display(),
                state.monitors_length
            )));
        }
        file.set_len(state.monitors_length)?;
        let vtk = match state.vtk {
            Some(v) if sim.case.output.vtk => Some(super::vtk_output::VtkSeries::resume(dir, sim, v)?),
            _ if sim.case.output.vtk => Some(super::vtk_output::VtkSeries::new(dir)),
            _ => None,
        };
        let mut writer = Self {
            dir: dir.to_path_buf(),
            monitors: Some(BufWriter::new(file)),
            vtk,
            interval: sim.case.output.interval,
            time_interval: sim.case.output.time_interval,
            last_vtk_step: state.last_vtk_step,
            last_vtk_slot: state.last_vtk_slot,
            rows_step: state.rows_step,
            complete_length: state.monitors_length,
        };
        if state.rows_step < sim.step {
            writer.write_step(sim, false)?;
        }
        Ok(writer)
    }

    /// Output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes the monitors row of the committed state, and VTK files if the step is on the
    /// output interval (or `force`).
    ///
    /// A writer without monitors (a rank other than 0) evaluates them all the same where the
    /// model's points are distributed: their values are sums over the ranks, collectives that
    /// every rank must meet.
    pub fn write_step(&mut self, sim: &Simulation, force: bool) -> std::io::Result<()> {
        if self.monitors.is_none() && sim.model.has_distributed_points() {
            sim.monitor_values();
        }
        if let Some(monitors) = &mut self.monitors {
            write!(monitors, "{}", sim.time())?;
            for v in sim.monitor_values() {
                write!(monitors, ",{v}")?;
            }
            writeln!(monitors)?;
            monitors.flush()?;
        }
        let on_interval = match self.time_interval {
            Some(dt) => {
                let slot = (sim.time() / dt * (1.0 + 1e-9)).floor() as i64;
                let due = slot > self.last_vtk_slot;
                if due {
                    self.last_vtk_slot = slot;
                }
                due
            }
            None => sim.case.output.times.is_empty() && self.interval > 0 && sim.step % self.interval == 0,
        };
        if (force || on_interval || sim.at_output_time()) && self.last_vtk_step != Some(sim.step) {
            if let Some(vtk) = &mut self.vtk {
                vtk.write(sim)?;
            }
            self.last_vtk_step = Some(sim.step);
        }
        self.rows_step = sim.step;
        if let Some(monitors) = &self.monitors {
            self.complete_length = monitors.get_ref().metadata()?.len();
        }
        Ok(())
    }

    /// Writes the VTK files of the last converged state if not yet written (after a failure).
    pub fn write_final_state(&mut self, sim: &Simulation) -> std::io::Result<()> {
        if self.last_vtk_step != Some(sim.step) {
            if let Some(vtk) = &mut self.vtk {
                vtk.write(sim)?;
            }
            self.last_vtk_step = Some(sim.step);
        }
        Ok(())
    }
}
