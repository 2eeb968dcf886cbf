//! Constitutive laws at finite strain for Loam.
//!
//! Key design decision: **a law sees only kinematics**. It takes the total deformation
//! gradient `F` (3×3; plane strain and axisymmetry enter only through `F33`), the committed
//! deformation gradient of the previous step, the time step and its committed history, and
//! returns the first Piola–Kirchhoff stress `P` with the consistent tangent `A = ∂P/∂F`.
//! The element kernels of `loam-fem` pull these back to whatever configuration they
//! integrate on (the reference mesh for total-Lagrangian FEM, the configuration at the
//! start of the step for MPM), so one law serves every discretisation.
//!
//! History lives outside the law, in flat `f64` slices owned by the integration point
//! (struct-of-arrays storage in the domains). A law writes its *trial* history during a
//! Newton iteration and never touches the committed one: committing is a copy made by the
//! owner once the step has converged. Laws hold no mutable caches and are `Send + Sync`.
//!
//! The elasto-plastic laws share one machinery: multiplicative plasticity on Hencky
//! elasticity ([`multiplicative`], Simo 1992) around a principal-space return mapping,
//! with the isotropic-function derivative of [`spectral`] for the tangent and forward-mode
//! differentiation ([`dual`]) of the return algorithm for its algorithmic tangent.
//!
//! The mixed displacement–pressure formulation sees a law through [`mixed::MixedLaw`]: the
//! deviatoric stress at `F` with the mean stress given as an independent pressure `p`, and
//! the volumetric law `p = K ln J` (Neo-Hookean, Hencky, and the plasticity laws whose flow
//! is isochoric).
//!
//! [`driver`] runs one material point along a laboratory path (triaxial, oedometer,
//! simple shear, …) from a JSON path file.

#![allow(non_snake_case)]

pub mod driver;
pub mod drucker_prager;
pub mod dual;
pub mod error;
pub mod hencky;
pub mod law;
pub mod linear_elastic;
pub mod material;
pub mod mixed;
pub mod modified_cam_clay;
pub mod mohr_coulomb;
pub mod mohr_coulomb_softening;
pub mod mu_i;
pub mod multiplicative;
pub mod neo_hookean;
pub mod newtonian_fluid;
pub mod saint_venant_kirchhoff;
pub mod spectral;
pub mod tensor;

pub use error::{LawError, ParameterError};
pub use law::{ConstitutiveLaw, Kinematics, StressResponse, TangentRequest, ALL_COMPONENTS, IN_PLANE, IN_PLANE_AND_ZZ};
pub use material::MaterialSpec;
pub use tensor::{idx, Tangent};
