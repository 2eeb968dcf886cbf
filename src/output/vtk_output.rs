//! VTK series of the model's domains: per output of a domain (an FEM mesh, each body of
//! material points, each penalty wall; with `output.grid` also every background grid as
//! `<domain>_grid`), `<name>_<step>.vtu` per output step and `<name>.pvd` listing them with
//! their times; with more than one output (e.g. the soil and the structure of a coupled
//! case), also `<case>.pvd` listing all of them at each time as parts of one series, which
//! ParaView opens as one.
//!
//! In a distributed run every rank writes its piece of each output
//! (`<name>_<step>_r<rank>.vtu`, [`super::pvtu`]) and rank 0 also `<name>_<step>.pvtu`, which
//! the `.pvd` series name instead of the `.vtu` files.

use std::path::{Path, PathBuf};

use loam_fem::domain::{DomainOutput, Field};

use super::pvd::{DataSet, PvdSeries};
use super::pvtu;
use super::vtk::{write_vtu, VtuCells, VtuField};
use crate::simulation::Simulation;

/// The series written so far (for checkpoints): per output name its data sets, and those of
/// the `<case>.pvd` of all parts.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct VtkState {
    series: Vec<(String, Vec<DataSet>)>,
    all: Option<Vec<DataSet>>,
}

/// One `.pvd` series per output name, in the order the model first gave them.
pub struct VtkSeries {
    dir: PathBuf,
    series: Vec<(String, PvdSeries)>,
    /// Every output as a part of one series (`<case>.pvd`).
    all: Option<PvdSeries>,
}

fn fields(f: &[Field]) -> Vec<VtuField<'_>> {
    f.iter().map(|f| VtuField { name: &f.name, components: f.components, values: &f.values }).collect()
}

/// Writes `out` as a `.vtu` file at `path`.
pub(crate) fn write_output(path: &Path, out: &DomainOutput) -> Result<(), super::vtk::OutputError> {
    let cells = match &out.cells {
        Some((element, connectivity)) => VtuCells::Mesh { element: *element, connectivity },
        None => VtuCells::Vertices,
    };
    write_vtu(path, &out.points, &cells, &fields(&out.point_fields), &fields(&out.cell_fields))
}

impl VtkSeries {
    /// A series in `dir`.
    pub fn new(dir: &Path) -> Self {
        Self { dir: dir.to_path_buf(), series: Vec::new(), all: None }
    }

    /// The series written so far.
    pub fn state(&self) -> VtkState {
        VtkState {
            series: self.series.iter().map(|(n, s)| (n.clone(), s.steps().to_vec())).collect(),
            all: self.all.as_ref().map(|s| s.steps().to_vec()),
        }
    }

    /// Series in `dir` that continue those of `state` (their `.pvd` files rewritten).
    pub fn resume(dir: &Path, sim: &Simulation, state: VtkState) -> std::io::Result<Self> {
        let pvd = |name: &str, steps| {
            PvdSeries::resume(dir.join(format!("{name}.pvd")), steps).map_err(std::io::Error::other)
        };
        let mut series = Vec::with_capacity(state.series.len());
        for (name, steps) in state.series {
            series.push((name.clone(), pvd(&name, steps)?));
        }
        let all = match state.all {
            Some(steps) => Some(pvd(&sim.case.name, steps)?),
            None => None,
        };
        Ok(Self { dir: dir.to_path_buf(), series, all })
    }

    /// Writes the committed state of every output of every domain.
    pub fn write(&mut self, sim: &Simulation) -> std::io::Result<()> {
        let ranks = sim.case.solver.ranks;
        // a rank builds its own piece of each output only
        let outputs = if ranks.is_distributed() {
            sim.model.output_pieces(sim.case.output.grid, ranks.rank(), ranks.size())
        } else {
            sim.model.outputs(sim.case.output.grid)
        };
        if outputs.len() > 1 && self.all.is_none() && outputs.iter().all(|o| o.name != sim.case.name) {
            self.all = Some(PvdSeries::new(self.dir.join(format!("{}.pvd", sim.case.name))));
        }
        for named in outputs {
            let out = &named.output;
            let file = if ranks.is_distributed() {
                let sources: Vec<String> =
                    (0..ranks.size()).map(|r| pvtu::piece_file(&named.name, sim.step, r)).collect();
                write_output(&self.dir.join(&sources[ranks.rank()]), out).map_err(std::io::Error::other)?;
                if ranks.rank() != 0 {
                    continue;
                }
                let file = pvtu::parallel_file(&named.name, sim.step);
                pvtu::write_pvtu(&self.dir.join(&file), out, &sources).map_err(std::io::Error::other)?;
                file
            } else {
                let file = format!("{}_{:06}.vtu", named.name, sim.step);
                write_output(&self.dir.join(&file), out).map_err(std::io::Error::other)?;
                file
            };
            let k = match self.series.iter().position(|(n, _)| *n == named.name) {
                Some(k) => k,
                None => {
                    let series = PvdSeries::new(self.dir.join(format!("{}.pvd", named.name)));
                    self.series.push((named.name.clone(), series));
                    self.series.len() - 1
                }
            };
            self.series[k].1.add(sim.time(), &file).map_err(std::io::Error::other)?;
            if let Some(all) = &mut self.all {
                all.add_part(sim.time(), &file, k).map_err(std::io::Error::other)?;
            }
        }
        Ok(())
    }
}
