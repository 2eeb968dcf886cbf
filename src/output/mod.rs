//! Output: VTK files, .pvd series and monitors.csv.

pub mod pvd;
pub mod results;
pub mod vtk;
pub mod vtk_output;
