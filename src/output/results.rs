//! Everything a run writes: `monitors.csv` (a row per step, flushed as it goes) and, per
//! domain, a `.vtu` per output step with a `.pvd` series that stays valid if the run stops.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::simulation::Simulation;

/// Writer of a run's results.
pub struct ResultWriter {
    dir: PathBuf,
    monitors: BufWriter<File>,
    vtk: Option<super::vtk_output::VtkSeries>,
    interval: usize,
    time_interval: Option<f64>,
    last_vtk_step: Option<usize>,
    /// Index of the last `time_interval` multiple written.
    last_vtk_slot: i64,
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
            monitors,
            vtk,
            interval: sim.case.output.interval,
            time_interval: sim.case.output.time_interval,
            last_vtk_step: None,
            last_vtk_slot: 0,
        })
    }

    /// Output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes the monitors row of the committed state, and VTK files if the step is on the
    /// output interval (or `force`).
    pub fn write_step(&mut self, sim: &Simulation, force: bool) -> std::io::Result<()> {
        write!(self.monitors, "{}", sim.time())?;
        for v in sim.monitor_values() {
            write!(self.monitors, ",{v}")?;
        }
        writeln!(self.monitors)?;
        self.monitors.flush()?;
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
