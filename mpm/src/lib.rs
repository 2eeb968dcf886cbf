//! The implicit Material Point Method (Iaconeta et al. 2017; Chandra et al. 2021), built on
//! `loam-fem`'s kernels, assembly and Newton loop.
//!
//! Key design decision: **the MPM grid is just another `Domain`**. Its material points are
//! handed to the same solid element kernel as FEM Gauss points (weight = current volume,
//! `F0` = the point's deformation gradient at the start of the step), so the
//! updated-Lagrangian phase is ordinary assembly into the shared system. What is particular
//! to MPM happens around it, in the seed's three phases:
//!
//! 1. *initialisation* ([`mpm_domain::MpmDomain::move_grid`], `locate_points`,
//!    `update_pattern`, `project_to_grid`, `place_walls`): place the grid (its reference
//!    position, or where an attached structure puts it: [`attachment`]), locate points in it
//!    (O(1) per point on a structured grid), sort them by cell, project mass, momentum and
//!    acceleration to its nodes and reset them;
//! 2. *updated-Lagrangian phase*: Newton on the global system (in `loam-fem`), the points of
//!    every body as the kernel's integration points (`compute_internal_forces`);
//! 3. *convective phase* (`interpolate_to_points`): interpolate `Δu` and `a` back to the
//!    points, `v_p ← v_p + Δt/2 (a_p^n + a_p^{n+1})`, `x_p ← x_p + Δu_p`, commit `F`, volume
//!    and law state.
//!
//! A grid's shape functions are the cells' linear ones or a smooth basis (uGIMP, quadratic
//! B-splines: [`basis`]) whose functions reach over neighbouring cells; a point's block is
//! then its **support**, the 3 × 3 nodes its functions reach, in place of its cell.
//!
//! One grid is one [`mpm_domain::MpmDomain`]: the bodies ([`body::Body`], one material each)
//! and the penalty walls ([`penalty_boundary`]) on it are parts of it, not domains of their
//! own.

#![allow(non_snake_case)]

pub mod attachment;
pub mod basis;
pub mod body;
pub mod ghost_penalty;
pub mod grid;
pub mod material_points;
pub mod mpm_domain;
pub mod penalty_boundary;
pub mod quadrature;
pub mod surface;
