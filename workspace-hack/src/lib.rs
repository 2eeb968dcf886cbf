//! No code. This crate exists for its build-dependencies' features (its Cargo.toml): every
//! workspace crate depends on it through `loam-laws`, so the `petsc` and `mpi` features build
//! the same proc macros as a build without them and reuse the workspace's artifacts.
