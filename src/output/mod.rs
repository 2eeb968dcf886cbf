//! Output: VTK files, .pvd series, monitors.csv and the run report summary.json.

pub mod pvd;
pub mod pvtu;
pub mod results;
pub mod summary;
pub mod vtk;
pub mod vtk_output;
