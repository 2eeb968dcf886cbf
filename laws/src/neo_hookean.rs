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
//!
//! **u–p form** ([`crate::mixed`]): the decoupled energy
//! `ψ = μ/2 (J^{-2/3} I₁ − 3) + K/2 (ln J)²`, `I₁ = tr C`, `K = λ + 2μ/3`
//! (Bonet & Wood 2008, §6.5; Simo, Taylor & Pister 1985, doi:10.1016/0045-7825(85)90033-7),
//! whose volumetric part `p = K ln J` is imposed by the mixed element and whose stress at the
//! pressure `p` (mean Kirchhoff stress) is
//!
//! `P = μ J^{-2/3} (F − I₁/3 F⁻ᵀ) + p F⁻ᵀ`  (`τ = μ J^{-2/3} dev b + p 1`),
//!
//! `A_iJkL = μ J^{-2/3} [δ_ik δ_JL − ⅔ F_iJ F⁻¹_Lk − ⅔ F_kL F⁻¹_Ji + ²⁄₉ I₁ F⁻¹_Ji F⁻¹_Lk
//! + ⅓ I₁ F⁻¹_Jk F⁻¹_Li] − p F⁻¹_Jk F⁻¹_Li`,  `∂P/∂p = F⁻ᵀ`.
//! With `ν = 0.5` (`K = ∞`) the material is incompressible: only the u–p form applies.

use nalgebra::Matrix3;

use crate::mixed::MixedLaw;
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

    fn mixed(&self) -> Result<&dyn MixedLaw, String> {
        Ok(self)
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

impl MixedLaw for NeoHookean {
    fn bulk_modulus(&self) -> f64 {
        self.lambda + 2.0 * self.mu / 3.0
    }

    fn shear_modulus(&self) -> f64 {
        self.mu
    }

    fn update_mixed(
        &self,
        kinematics: &Kinematics,
        pressure: f64,
        _committed: &[f64],
        _trial: &mut [f64],
        response: &mut StressResponse,
        pressure_tangent: &mut Matrix3<f64>,
    ) -> Result<(), LawError> {
        let f = &kinematics.deformation_gradient;
        let det_f = f.determinant();
        if det_f <= 0.0 || !det_f.is_finite() {
            return Err(LawError::InvertedDeformation { det_f });
        }
        let f_inv: Matrix3<f64> = f.try_inverse().ok_or(LawError::InvertedDeformation { det_f })?;
        let a = det_f.powf(-2.0 / 3.0);
        let i1 = f.norm_squared();
        let (mu_a, p) = (self.mu * a, pressure);
        response.first_piola = mu_a * (f - i1 / 3.0 * f_inv.transpose()) + p * f_inv.transpose();
        *pressure_tangent = f_inv.transpose();
        let tangent = &mut response.tangent;
        crate::with_components!(kinematics.tangent.components(), |components| {
            for &row in components {
                let (i, jj) = (row / 3, row % 3);
                for &col in components {
                    let (k, l) = (col / 3, col % 3);
                    let mut v = mu_a
                        * (-2.0 / 3.0 * f[(i, jj)] * f_inv[(l, k)] - 2.0 / 3.0 * f[(k, l)] * f_inv[(jj, i)]
                            + 2.0 / 9.0 * i1 * f_inv[(jj, i)] * f_inv[(l, k)]
                            + i1 / 3.0 * f_inv[(jj, k)] * f_inv[(l, i)])
                        - p * f_inv[(jj, k)] * f_inv[(l, i)];
                    if i == k && jj == l {
                        v += mu_a;
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

    /// u–p form: `A` and `∂P/∂p` against central differences, compressible and
    /// incompressible (`ν = 0.5`), at a general `F` and pressure; the mean Kirchhoff stress
    /// is the given pressure.
    #[test]
    fn mixed_tangents_match_central_differences() {
        let f = Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05);
        for nu in [0.3, 0.5] {
            let law = NeoHookean::new(1000.0, 9.0e7, nu);
            let p = -2.0e7;
            let (ea, ep) = crate::mixed::mixed_tangent_relative_error(&law, &Kinematics::at(f), p, &[]).unwrap();
            println!("neo-Hookean u–p (ν = {nu}): A error {ea:.2e}, ∂P/∂p error {ep:.2e} (tolerance 1e-6)");
            assert!(ea < 1e-6 && ep < 1e-6);
            let (mut r, mut dp) = (StressResponse::default(), Matrix3::zeros());
            law.update_mixed(&Kinematics::at(f), p, &[], &mut [], &mut r, &mut dp).unwrap();
            let tau = r.first_piola * f.transpose();
            assert!((tau.trace() / 3.0 - p).abs() < 1e-9 * p.abs());
        }
    }

    #[test]
    fn stress_free_in_reference_state() {
        let law = NeoHookean::new(1000.0, 9.0e7, 0.3);
        let r = law.stress_response(&Kinematics::at(Matrix3::identity()), &[], &mut []).unwrap();
        assert!(r.first_piola.amax() < 1e-6);
    }
}
