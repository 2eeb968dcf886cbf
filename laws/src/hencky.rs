//! Hencky hyperelasticity: Hooke's law between the logarithmic strain and the Kirchhoff
//! stress — the elastic part of every elasto-plastic law of this crate.
//!
//! Energy `ψ = λ/2 (tr ε)² + μ ε:ε`, `ε = ½ ln b`, `b = F Fᵀ`.
//! Stress `τ = λ tr(ε) I + 2 μ ε` (Kirchhoff), `P = τ F⁻ᵀ`.
//! Tangent: `τ(b)` is an isotropic tensor function with `∂τ_a/∂ε_b = λ + 2μ δ_ab`, differentiated
//! by [`crate::multiplicative::kirchhoff_update`] (robust at repeated stretches).
//!
//! **u–p form** ([`crate::mixed`]): at the pressure `p` (mean Kirchhoff stress),
//! `τ = 2μ dev ε + p 1`, i.e. principal `τ_a = 2μ (ε_a − tr ε/3) + p`,
//! `∂τ_a/∂ε_b = 2μ (δ_ab − ⅓)`, `∂τ_a/∂p = 1`; the volumetric law `p = K ln J`,
//! `K = λ + 2μ/3`, is imposed by the mixed element (`K = ∞` for `ν = 0.5`).
//!
//! Reference: Simo (1992), CMAME 99:61–112, doi:10.1016/0045-7825(92)90123-2;
//! Bruhns, Xiao & Meyers (2001), "Constitutive inequalities for an isotropic elastic strain-energy
//! function based on Hencky's logarithmic strain tensor", Proc. R. Soc. A 457:2207–2226,
//! doi:10.1098/rspa.2001.0818.

use nalgebra::Matrix3;

use crate::mixed::{deviator, mixed_kirchhoff_update, MixedLaw};
use crate::multiplicative::{checked_inverse, hencky_matrix, hencky_stress, kirchhoff_update, PrincipalResponse};
use crate::tensor::piola_from_kirchhoff;
use crate::{ConstitutiveLaw, Kinematics, LawError, StressResponse};

/// Hencky (logarithmic-strain) hyperelastic solid with Lamé constants `λ`, `μ` (Pa).
#[derive(Debug, Clone, Copy)]
pub struct Hencky {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ in Pa.
    pub mu: f64,
}

impl Hencky {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `ν`.
    pub fn new(density: f64, young_modulus: f64, poisson_ratio: f64) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self { density, lambda, mu }
    }
}

impl ConstitutiveLaw for Hencky {
    fn name(&self) -> &'static str {
        "hencky"
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
        let f_inv = checked_inverse(f)?;
        let components = kinematics.tangent.components();
        let ku = kirchhoff_update(f, &Matrix3::identity(), components, &mut response.tangent, |eps| {
            Ok(PrincipalResponse {
                tau: hencky_stress(self.lambda, self.mu, eps),
                eps_e: eps,
                dtau_deps: hencky_matrix(self.lambda, self.mu),
            })
        })?;
        response.first_piola = piola_from_kirchhoff(&f_inv, &ku.tau, &mut response.tangent, components);
        Ok(())
    }
}

impl MixedLaw for Hencky {
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
        let components = kinematics.tangent.components();
        let f = &kinematics.deformation_gradient;
        let two_mu = 2.0 * self.mu;
        mixed_kirchhoff_update(f, &Matrix3::identity(), components, response, pressure_tangent, |eps| {
            let tau = deviator(eps).map(|e| two_mu * e + pressure);
            let dtau_deps = Matrix3::from_fn(|a, b| two_mu * (if a == b { 1.0 } else { 0.0 } - 1.0 / 3.0));
            Ok((PrincipalResponse { tau, eps_e: eps, dtau_deps }, [1.0; 3]))
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_relative_error;

    #[test]
    fn tangent_matches_central_differences() {
        let law = Hencky::new(1000.0, 1.0e7, 0.3);
        for f in [Matrix3::identity(), Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05)] {
            let err = tangent_relative_error(&law, &Kinematics::at(f), &[]).unwrap();
            println!("hencky tangent: relative error vs central FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }

    /// u–p form: tangents against central differences, compressible and incompressible.
    #[test]
    fn mixed_tangents_match_central_differences() {
        for nu in [0.3, 0.5] {
            let law = Hencky::new(1000.0, 1.0e7, nu);
            for f in [Matrix3::identity(), Matrix3::new(1.1, 0.2, 0.05, -0.1, 0.95, 0.02, 0.03, 0.01, 1.05)] {
                let (ea, ep) =
                    crate::mixed::mixed_tangent_relative_error(&law, &Kinematics::at(f), -3.0e5, &[]).unwrap();
                println!("hencky u–p (ν = {nu}): A error {ea:.2e}, ∂P/∂p error {ep:.2e} (tolerance 1e-6)");
                assert!(ea < 1e-6 && ep < 1e-6);
            }
        }
    }
}

#[cfg(test)]
mod closed_form {
    use super::*;

    /// Uniaxial stretch λ₁ = e^{0.1} with lateral stretches 1: τ₁₁ = (λ + 2μ) 0.1, τ₂₂ = λ 0.1.
    #[test]
    fn kirchhoff_stress_is_linear_in_log_strain() {
        let law = Hencky::new(1000.0, 1.0e7, 0.3);
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.1f64.exp(), 1.0, 1.0));
        let r = law.stress_response(&Kinematics::at(f), &[], &mut []).unwrap();
        let tau = r.first_piola * f.transpose();
        let (t11, t22) = ((law.lambda + 2.0 * law.mu) * 0.1, law.lambda * 0.1);
        println!(
            "hencky: τ11 {:.6e} vs {t11:.6e}, τ22 {:.6e} vs {t22:.6e} (tolerance 1e-12 relative)",
            tau[(0, 0)],
            tau[(1, 1)]
        );
        assert!((tau[(0, 0)] - t11).abs() < 1e-12 * t11 && (tau[(1, 1)] - t22).abs() < 1e-12 * t11);
    }
}
