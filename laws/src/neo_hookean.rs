//! Compressible Neo-Hookean hyperelasticity (the law of Kratos' `HyperElasticNeoHookean*Law`).
//!
//! Strain energy per unit reference volume
//! `ψ(F) = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)²`, `C = FᵀF`, `J = det F`.
//!
//! Stress: `P = ∂ψ/∂F = μ F + (λ ln J − μ) F^{-T}`.
//!
//! Tangent: `A_iJkL = μ δ_ik δ_JL + λ F^{-1}_Ji F^{-1}_Lk − (λ ln J − μ) F^{-1}_Jk F^{-1}_Li`.
//!
//! Reference: Bonet & Wood (2008), *Nonlinear Continuum Mechanics for Finite Element
//! Analysis*, 2nd ed., §6.4.3, Cambridge University Press, doi:10.1017/CBO9780511755446.

use nalgebra::Matrix3;

use crate::{ConstitutiveLaw, Kinematics, LawError, StressResponse};

/// Compressible Neo-Hookean solid with Lamé constants `λ`, `μ` (Pa) and density ρ (kg/m³).
#[derive(Debug, Clone, Copy)]
pub struct NeoHookean {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ in Pa.
    pub mu: f64,
}

impl NeoHookean {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `ν`.
    pub fn new(density: f64, young_modulus: f64, poisson_ratio: f64) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self { density, lambda, mu }
    }
}

impl ConstitutiveLaw for NeoHookean {
    fn name(&self) -> &'static str {
        "neo_hookean"
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
        let det_f = f.determinant();
        if det_f <= 0.0 || !det_f.is_finite() {
            return Err(LawError::InvertedDeformation { det_f });
        }
        let f_inv: Matrix3<f64> = f.try_inverse().ok_or(LawError::InvertedDeformation { det_f })?;
        let ln_j = det_f.ln();
        let c = self.lambda * ln_j - self.mu;
        response.first_piola = self.mu * f + c * f_inv.transpose();
        let tangent = &mut response.tangent;
        crate::with_components!(kinematics.tangent.components(), |components| {
            for &row in components {
                let (i, jj) = (row / 3, row % 3);
                for &col in components {
                    let (k, l) = (col / 3, col % 3);
                    let mut v = self.lambda * f_inv[(jj, i)] * f_inv[(l, k)] - c * f_inv[(jj, k)] * f_inv[(l, i)];
                    if i == k && jj == l {
                        v += self.mu;
                    }
                    tangent[(row, col)] = v;
                }
            }
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::finite_difference_tangent;

    #[test]
    fn tangent_matches_central_differences() {
        let law = NeoHookean::new(1000.0, 9.0e7, 0.3);
        let f = Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05);
        let r = law.stress_response(&Kinematics::at(f), &[], &mut []).unwrap();
        let fd = finite_difference_tangent(&f, 1e-6, |g| {
            law.stress_response(&Kinematics::at(*g), &[], &mut []).unwrap().first_piola
        });
        let err = (r.tangent - fd).amax() / r.tangent.amax();
        println!("neo-Hookean tangent: relative error vs central FD {err:.2e} (tolerance 1e-6)");
        assert!(err < 1e-6);
    }

    #[test]
    fn stress_free_in_reference_state() {
        let law = NeoHookean::new(1000.0, 9.0e7, 0.3);
        let r = law.stress_response(&Kinematics::at(Matrix3::identity()), &[], &mut []).unwrap();
        assert!(r.first_piola.amax() < 1e-6);
    }
}
