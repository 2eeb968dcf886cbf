//! VTK series of the model's domains: `<domain>_<step>.vtu` per output step and
//! `<domain>.pvd` listing them with their times; with `output.grid`, also the background
//! grid of every MPM domain as `<domain>_grid_<step>.vtu` in `<domain>_grid.pvd`.

use std::path::{Path, PathBuf};

use loam_fem::domain::Field;

use super::pvd::PvdSeries;
use super::vtk::{write_vtu, VtuCells, VtuField};
use crate::simulation::Simulation;

/// One `.pvd` series per domain.
pub struct VtkSeries {
    dir: PathBuf,
    series: Vec<PvdSeries>,
    /// Per domain: the series of its background grid (`output.grid`, MPM domains).
    grids: Vec<Option<PvdSeries>>,
}

fn fields(f: &[Field]) -> Vec<VtuField<'_>> {
    f.iter().map(|f| VtuField { name: &f.name, components: f.components, values: &f.values }).collect()
}

impl VtkSeries {
    /// A series in `dir` for the domains of `sim`.
    pub fn new(dir: &Path, sim: &Simulation) -> Self {
        let series = sim.model.domains.iter().map(|d| PvdSeries::new(dir.join(format!("{}.pvd", d.name())))).collect();
        let grids = sim
            .model
            .domains
            .iter()
            .map(|d| {
                (sim.case.output.grid && d.grid_output(&sim.model.committed).is_some())
                    .then(|| PvdSeries::new(dir.join(format!("{}_grid.pvd", d.name()))))
            })
            .collect();
        Self { dir: dir.to_path_buf(), series, grids }
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
        for (d, series) in sim.model.domains.iter().zip(&mut self.grids) {
            let (Some(series), Some(out)) = (series, d.grid_output(&sim.model.committed)) else { continue };
            let file = format!("{}_grid_{:06}.vtu", d.name(), sim.step);
            let Some((element, connectivity)) = &out.cells else { continue };
            write_vtu(
                &self.dir.join(&file),
                &out.points,
                &VtuCells::Mesh { element: *element, connectivity },
                &fields(&out.point_fields),
                &fields(&out.cell_fields),
            )
            .map_err(std::io::Error::other)?;
            series.add(sim.time(), &file).map_err(std::io::Error::other)?;
        }
        Ok(())
    }
}
