//! Kinematic formulation of a solid: plane strain, plane stress, axisymmetric or 3D.
//!
//! The laws always see a 3×3 deformation gradient; the formulation decides what fills the
//! out-of-plane component `F33` and what measure an integration point's weight carries:
//!
//! | formulation   | `F33`                             | weight of a point            |
//! |---------------|-----------------------------------|------------------------------|
//! | plane strain  | 1                                 | area × thickness             |
//! | plane stress  | solves `P33 = 0` (local Newton)   | area × thickness             |
//! | axisymmetric  | `1 + u_r / R` (hoop stretch)      | area × 2πR (full revolution) |
//! | 3D            | from the gradient                 | volume                       |
//!
//! In the axisymmetric case the first coordinate is the radius `r ≥ 0` and the second the
//! axial coordinate `z`; loads and reactions are totals over the full circumference.

use serde::Deserialize;

/// Kinematic formulation of a domain.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// 2D, `ε33 = 0`.
    PlaneStrain,
    /// 2D, `σ33 = 0`.
    PlaneStress,
    /// 2D meridian section (r, z) of a body of revolution.
    Axisymmetric,
    /// Full 3D.
    #[serde(rename = "3d")]
    ThreeD,
}

impl Formulation {
    /// Spatial dimension of the unknowns (2 or 3).
    pub const fn dim(self) -> usize {
        match self {
            Formulation::ThreeD => 3,
            _ => 2,
        }
    }

    /// Name as written in case files.
    pub const fn name(self) -> &'static str {
        match self {
            Formulation::PlaneStrain => "plane_strain",
            Formulation::PlaneStress => "plane_stress",
            Formulation::Axisymmetric => "axisymmetric",
            Formulation::ThreeD => "3d",
        }
    }

    /// Factor turning an area (2D) into the integration measure at radius `r`:
    /// the thickness in plane problems, `2πr` for axisymmetry, 1 in 3D.
    pub fn measure_factor(self, thickness: f64, r: f64) -> f64 {
        match self {
            Formulation::PlaneStrain | Formulation::PlaneStress => thickness,
            Formulation::Axisymmetric => 2.0 * std::f64::consts::PI * r,
            Formulation::ThreeD => 1.0,
        }
    }
}
