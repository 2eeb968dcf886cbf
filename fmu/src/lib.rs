//! loam-fmu: the shared library inside every FMU that `loam fmu` writes.
//!
//! The FMI 3.0 C API (co-simulation interface) implemented directly, without bindgen:
//! the C types are written by hand in [`ffi`], the only module where unsafe code is
//! allowed, and every exported function runs inside `catch_unwind`, so that a bug never
//! unwinds into (or aborts) the importing process. The library is generic: it reads its
//! case from the FMU's `resources/` (named by `resources/loam_fmu.json`), and the
//! variables by value reference from [`loam::fmu_package::fmu_variables`], the same
//! table the model description was written from. Stepping is
//! [`loam::simulation::Simulation::advance_to`], the run loop of the CLI, so an FMU run
//! reproduces `loam run`.

pub mod ffi;
pub mod instance;
