//! VTK series of the model's domains (placeholder until the VTK writer lands).

use std::path::Path;

use crate::simulation::Simulation;

/// One `.pvd` series per domain.
pub struct VtkSeries;

impl VtkSeries {
    /// A series in `dir` for the domains of `sim`.
    pub fn new(_dir: &Path, _sim: &Simulation) -> Self {
        VtkSeries
    }

    /// Writes the committed state of every domain.
    pub fn write(&mut self, _sim: &Simulation) -> std::io::Result<()> {
        Ok(())
    }
}
