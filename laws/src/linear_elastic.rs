//! Linear elasticity at small strain (Hooke's law).
//!
//! Strain `ε = sym(F) − I = ½ (F + Fᵀ) − I`, stress `σ = λ tr(ε) I + 2 μ ε`, returned as the
//! first Piola–Kirchhoff stress `P = σ` (no distinction between configurations at small
//! strain). Tangent `A_iJkL = λ δ_iJ δ_kL + μ (δ_ik δ_JL + δ_iL δ_Jk)`.
//!
//! Not objective: a superposed rigid rotation produces spurious stress. Use
//! [`crate::saint_venant_kirchhoff`] (large rotations, small strains) or the
//! hyperelastic laws for large deformations.
//!
//! Reference: Hughes (2000), *The Finite Element Method*, §2.7, Dover (Hooke's law).

use nalgebra::Matrix3;

use crate::{idx, ConstitutiveLaw, Kinematics, LawError, StressResponse};

/// Small-strain isotropic linear elasticity with Lamé constants `λ`, `μ` (Pa).
#[derive(Debug, Clone, Copy)]
pub struct LinearElastic {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ in Pa.
    pub mu: f64,
}

impl LinearElastic {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `ν`.
    pub fn new(density: f64, young_modulus: f64, poisson_ratio: f64) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self { density, lambda, mu }
    }
}

impl ConstitutiveLaw for LinearElastic {
    fn name(&self) -> &'static str {
        "linear_elastic"
    }

    fn density(&self) -> f64 {
        self.density
    }

    fn elastic_lame(&self) -> (f64, f64) {
        (self.lambda, self.mu)
    }

    fn update(
        &self,
        kinematics: &Kinematics,
        _committed: &[f64],
        _trial: &mut [f64],
        response: &mut StressResponse,
    ) -> Result<(), LawError> {
        let f = &kinematics.deformation_gradient;
        if !f.iter().all(|v| v.is_finite()) {
            return Err(LawError::InvertedDeformation { det_f: f64::NAN });
        }
        let eps = 0.5 * (f + f.transpose()) - Matrix3::identity();
        let first_piola = Matrix3::identity() * (self.lambda * eps.trace()) + 2.0 * self.mu * eps;
        let tangent = &mut response.tangent;
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let d = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
                        tangent[(idx(i, j), idx(k, l))] =
                            self.lambda * d(i, j) * d(k, l) + self.mu * (d(i, k) * d(j, l) + d(i, l) * d(j, k));
                    }
                }
            }
        }
        response.first_piola = first_piola;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_relative_error;

    #[test]
    fn tangent_matches_central_differences() {
        let law = LinearElastic::new(1000.0, 1.0e7, 0.3);
        for f in [Matrix3::identity(), Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05)] {
            let err = tangent_relative_error(&law, &Kinematics::at(f), &[]).unwrap();
            println!("linear_elastic tangent: relative error vs central FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }
}
