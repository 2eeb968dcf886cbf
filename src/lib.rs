//! Loam: implicit MPM and Lagrangian FEM for large-deformation solid and soil mechanics.
//!
//! This package holds what turns a JSON case file into results: the case schema
//! ([`case`]), model building ([`model_builder`]), the steppable simulation
//! ([`simulation`]), monitors and output ([`output`]), and the `loam` CLI. The numerics
//! live in the member crates `loam-laws`, `loam-fem`, `loam-mpm` and `loam-coupling`.

pub mod case;
pub mod checkpoint;
pub mod cli;
pub mod export;
pub mod fit;
pub mod fmu_package;
pub mod hints;
pub mod import;
pub mod input;
pub mod interrupt;
pub mod model_builder;
pub mod monitor;
pub mod output;
pub mod plot;
pub mod run;
pub mod simulation;

pub use loam_fem as fem;
pub use loam_laws as laws;
