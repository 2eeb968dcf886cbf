//! VTK series of the model's domains: `<domain>_<step>.vtu` per output step and
//! `<domain>.pvd` listing them with their times.

use std::path::{Path, PathBuf};

use loam_fem::domain::Field;

use super::pvd::PvdSeries;
use super::vtk::{write_vtu, VtuCells, VtuField};
use crate::simulation::Simulation;

/// One `.pvd` series per domain.
pub struct VtkSeries {
    dir: PathBuf,
    series: Vec<PvdSeries>,
}

fn fields(f: &[Field]) -> Vec<VtuField<'_>> {
    f.iter().map(|f| VtuField { name: &f.name, components: f.components, values: &f.values }).collect()
}

impl VtkSeries {
    /// A series in `dir` for the domains of `sim`.
    pub fn new(dir: &Path, sim: &Simulation) -> Self {
        let series = sim.model.domains.iter().map(|d| PvdSeries::new(dir.join(format!("{}.pvd", d.name())))).collect();
        Self { dir: dir.to_path_buf(), series }
    }

    /// Writes the committed state of every domain.
    pub fn write(&mut self, sim: &Simulation) -> std::io::Result<()> {
        for (d, series) in sim.model.domains.iter().zip(&mut self.series) {
            let out = d.output(&sim.model.committed);
            let file = format!("{}_{:06}.vtu", d.name(), sim.step);
            let cells = match &out.cells {
                Some((element, connectivity)) => VtuCells::Mesh { element: *element, connectivity },
                None => VtuCells::Vertices,
            };
            write_vtu(
                &self.dir.join(&file),
                &out.points,
                &cells,
                &fields(&out.point_fields),
                &fields(&out.cell_fields),
            )
            .map_err(std::io::Error::other)?;
            series.add(sim.time(), &file).map_err(std::io::Error::other)?;
        }
        Ok(())
    }
}
