//! Everything a discretisation needs, and the Lagrangian FEM domain.
//!
//! Key design decision: **one node set and one DOF map for all domains**, and element
//! kernels that do not know who owns their integration points. An FEM mesh passes Gauss
//! points to [`kernel::solid_element`], an MPM grid passes material points; both fill
//! element blocks that one lock-free gather ([`assembly`]) adds into one sparse system
//! solved by one Newton loop ([`newton::NewtonStrategy`], driven by [`model::Model::solve_step`]). Coupling MPM and FEM is then
//! assembly over shared nodes, not a special solver. The mixed u–p element
//! ([`mixed_kernel::mixed_element`]) goes through the same seam, with pressure DOFs appended
//! to the DOF map ([`dofs`]).

#![allow(non_snake_case)]

pub mod amplitude;
pub mod assembler;
pub mod assembly;
pub mod convergence;
pub mod dofs;
pub mod domain;
pub mod element;
pub mod formulation;
pub mod friction;
pub mod gmsh;
pub mod kernel;
pub mod krylov;
pub mod linear_solver;
pub mod loads;
pub mod mesh;
pub mod mixed_kernel;
pub mod model;
pub mod newton;
pub mod packed_geometry;
pub mod pattern_lu;
pub mod permuted_lower;
#[cfg(feature = "petsc")]
mod petsc_solver;
pub mod ranks;
pub mod rigid_body;
pub mod rigid_modes;
pub mod scheme;
pub mod simd_state;
pub mod slip;
pub mod solid_domain;

/// Von Mises equivalent stress `√(3/2 s:s)`, `s` the deviator of `σ`.
pub fn von_mises(sigma: &nalgebra::Matrix3<f64>) -> f64 {
    let s = sigma - nalgebra::Matrix3::identity() * (sigma.trace() / 3.0);
    (1.5 * s.dot(&s)).sqrt()
}
