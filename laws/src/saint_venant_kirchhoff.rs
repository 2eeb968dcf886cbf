//! St Venant–Kirchhoff hyperelasticity: Hooke's law between the Green–Lagrange strain and
//! the second Piola–Kirchhoff stress, the large-rotation (small-strain) variant of linear
//! elasticity.
//!
//! Energy `ψ(E) = λ/2 (tr E)² + μ E:E`, `E = ½ (FᵀF − I)`.
//! Stress `S = λ tr(E) I + 2 μ E`, `P = F S`.
//! Tangent `A_iJkL = δ_ik S_LJ + λ F_iJ F_kL + μ F_iL F_kJ + μ (F Fᵀ)_ik δ_JL`.
//!
//! Objective, but softens without bound in compression (not for large compressive strains).
//!
//! Reference: Bonet & Wood (2008), *Nonlinear Continuum Mechanics for Finite Element
//! Analysis*, 2nd ed., §6.4.2, Cambridge University Press, doi:10.1017/CBO9780511755446.

use nalgebra::Matrix3;

use crate::{idx, ConstitutiveLaw, Kinematics, LawError, StressResponse};

/// St Venant–Kirchhoff solid with Lamé constants `λ`, `μ` (Pa) and density ρ (kg/m³).
#[derive(Debug, Clone, Copy)]
pub struct SaintVenantKirchhoff {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ in Pa.
    pub mu: f64,
}

impl SaintVenantKirchhoff {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `ν`.
    pub fn new(density: f64, young_modulus: f64, poisson_ratio: f64) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self { density, lambda, mu }
    }
}

impl ConstitutiveLaw for SaintVenantKirchhoff {
    fn name(&self) -> &'static str {
        "saint_venant_kirchhoff"
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
        crate::multiplicative::checked_inverse(f)?;
        let e = 0.5 * (f.transpose() * f - Matrix3::identity());
        let s = Matrix3::identity() * (self.lambda * e.trace()) + 2.0 * self.mu * e;
        let first_piola = f * s;
        let ffT = f * f.transpose();
        let tangent = &mut response.tangent;
        for i in 0..3 {
            for jj in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let mut v = self.lambda * f[(i, jj)] * f[(k, l)] + self.mu * f[(i, l)] * f[(k, jj)];
                        if i == k {
                            v += s[(l, jj)];
                        }
                        if jj == l {
                            v += self.mu * ffT[(i, k)];
                        }
                        tangent[(idx(i, jj), idx(k, l))] = v;
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
        let law = SaintVenantKirchhoff::new(1000.0, 1.0e7, 0.3);
        for f in [Matrix3::identity(), Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05)] {
            let err = tangent_relative_error(&law, &Kinematics::at(f), &[]).unwrap();
            println!("saint_venant_kirchhoff tangent: relative error vs central FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }
}
