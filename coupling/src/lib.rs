//! Monolithic MPM–FEM coupling: soil (material points on a background grid) and structures
//! (Lagrangian FEM meshes) in one Newton system.
//!
//! Key design decision: **coupling is assembly over shared nodes**, not a solver of its
//! own. An interface is a named region of a structure's boundary; the background grid is
//! made to conform to it (no cells inside the structure, a grid node at every interface
//! node: [`interface`]), and those grid nodes become the structure's nodes (tied) or their
//! partners whose normal DOF shares the structure node's equation (frictionless slip). One
//! DOF map then carries the block system of the seed,
//!
//! ```text
//! | K_S    K_SΓ   0    | |δu_S |     |R_S |
//! | K_ΓS   K_ΓΓ   K_ΓSt| |δu_Γ | = − |R_Γ |
//! | 0      K_StΓ  K_St | |δu_St|     |R_St|
//! ```
//!
//! where soil cells give `K_S`, `K_SΓ` and their part of `K_ΓΓ`, structure elements `K_St`,
//! `K_StΓ` and theirs. At every step the grid is placed where the structure is: interface
//! nodes at the structure's nodes, a band around them moved by the harmonic extension of
//! their displacement ([`mesh_motion`]), the far grid at its reference position. The node
//! roles of the DOF map (`loam_fem::dofs::NodeRole`) give the residual norms per block that
//! the Newton log reports, and the soil's residual at the interface nodes is the force that
//! the soil exerts on the structure.

//!
//! The second form, for structures that do not fit the grid, is a **non-conforming tie or
//! contact** ([`interface_points`]): quadrature points on the structure's interface facets,
//! located in the fixed grid, each an element block over its grid nodes and its facet's
//! nodes, under a penalty law ([`interface_law`]: bilateral tie, or unilateral contact with
//! Coulomb friction; [`tie`] gives the moving-point block of a tie).

pub mod interface;
pub mod interface_law;
pub mod interface_points;
pub mod mesh_motion;
pub mod tie;
