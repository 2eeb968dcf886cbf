//! Drucker–Prager elasto-plasticity at finite strain, matched to Mohr–Coulomb by a
//! selectable fit, non-associated.
//!
//! In Kirchhoff stress (tension positive), `p = tr τ / 3`, `s = dev τ`, `J₂ = ½ s:s`:
//!
//! - yield `f = √J₂ + η p − ξ c`, plastic potential `g = √J₂ + η̄ p`;
//! - elasticity: Hencky, `p = K ε_v^e`, `s = 2G e^e` (multiplicative frame of
//!   [`crate::multiplicative`], Simo 1992).
//!
//! Return mapping (de Souza Neto, Perić & Owen 2008, *Computational Methods for
//! Plasticity*, Wiley, §8.3.3 and Box 8.8, perfect plasticity, doi:10.1002/9780470694626):
//! cone `Δγ = f_tr/(G + K η η̄)`, `s = (1 − G Δγ/√J₂,tr) s_tr`, `p = p_tr − K η̄ Δγ`, valid while
//! `√J₂,tr − G Δγ ≥ 0`; otherwise apex `s = 0`, `p = ξ c/η`. The algorithmic tangent is the
//! exact derivative of this algorithm ([`crate::dual`]).
//!
//! Fits to Mohr–Coulomb (de Souza Neto et al. 2008, §6.4.2), with φ (and ψ for η̄):
//! - `outer` (compression cone, coincides with MC in triaxial compression):
//!   `η = 6 sin φ/(√3 (3 − sin φ))`, `ξ = 6 cos φ/(√3 (3 − sin φ))`;
//! - `inner` (extension cone): same with `3 + sin φ`;
//! - `plane_strain` (same plane-strain collapse load): `η = 3 tan φ/√(9 + 12 tan² φ)`,
//!   `ξ = 3/√(9 + 12 tan² φ)`.
//!
//! **u–p form** ([`crate::mixed`], ψ = 0 so that `η̄ = 0` and the flow is isochoric; φ = 0
//! is von Mises): at the given pressure `p` (mean Kirchhoff stress) the trial deviator
//! `s_tr = 2μ dev ε_tr` returns radially, `f_tr = √J₂,tr + η p − ξ c`, `G Δγ = f_tr`,
//! `s = (1 − f_tr/√J₂,tr) s_tr`, `τ = s + p 1`, while `ξ c − η p ≥ 0`; beyond the apex
//! `τ = p 1`, and at the end of the step the volume beyond `θ_apex = p_apex/K`,
//! `p_apex = ξ c/η`, is released as plastic dilation where the point's pressure is at the
//! apex, as for Mohr–Coulomb ([`crate::mixed::elastic_strain_up`]). Tangents by dual numbers seeded on
//! `(ε_tr, p)`.

use nalgebra::Matrix3;
use serde::Deserialize;

use crate::dual::{Dual, Real};
use crate::mixed::{dual_mixed_response, MixedPrincipalModel, MixedPrincipalResponse, MixedReturn};
use crate::multiplicative::{
    self, accumulate_plastic_strain, hencky_matrix, hencky_strain, hencky_stress, PrincipalModel, PrincipalResponse,
    PLASTIC_OUTPUT,
};
use crate::LawError;

/// How the Drucker–Prager cone is matched to the Mohr–Coulomb pyramid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DruckerPragerFit {
    /// Through the compressive meridians (outer cone).
    Outer,
    /// Through the tensile meridians (inner cone).
    Inner,
    /// Same limit load in plane strain.
    PlaneStrain,
}

impl DruckerPragerFit {
    /// `(η, ξ)` for friction angle `phi` (rad); use `phi = ψ` for `η̄`.
    pub fn coefficients(self, phi: f64) -> (f64, f64) {
        let (s, c) = phi.sin_cos();
        let r3 = 3f64.sqrt();
        match self {
            Self::Outer => (6.0 * s / (r3 * (3.0 - s)), 6.0 * c / (r3 * (3.0 - s))),
            Self::Inner => (6.0 * s / (r3 * (3.0 + s)), 6.0 * c / (r3 * (3.0 + s))),
            Self::PlaneStrain => {
                let t = phi.tan();
                let d = (9.0 + 12.0 * t * t).sqrt();
                (3.0 * t / d, 3.0 / d)
            }
        }
    }
}

/// Return region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DruckerPragerRegion {
    /// Elastic step.
    Elastic,
    /// Return to the smooth cone.
    Cone,
    /// Return to the apex.
    Apex,
}

/// Drucker–Prager law with Hencky elasticity (perfect plasticity).
#[derive(Debug, Clone, Copy)]
pub struct DruckerPrager {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ = G in Pa.
    pub mu: f64,
    /// Friction coefficient η.
    pub eta: f64,
    /// Cohesion coefficient ξ.
    pub xi: f64,
    /// Dilatancy coefficient η̄.
    pub eta_bar: f64,
    /// Cohesion c in Pa.
    pub cohesion: f64,
}

impl DruckerPrager {
    /// From `E` (Pa), `ν`, MC φ (rad), c (Pa), ψ (rad) and the fit.
    pub fn new(
        density: f64,
        young_modulus: f64,
        poisson_ratio: f64,
        friction_angle: f64,
        cohesion: f64,
        dilatancy_angle: f64,
        fit: DruckerPragerFit,
    ) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        let (eta, xi) = fit.coefficients(friction_angle);
        let (eta_bar, _) = fit.coefficients(dilatancy_angle);
        Self { density, lambda, mu, eta, xi, eta_bar, cohesion }
    }

    /// Yield function `f = √J₂ + η p − ξ c` (Pa) at principal Kirchhoff stresses.
    pub fn yield_function(&self, tau: [f64; 3]) -> f64 {
        let p = (tau[0] + tau[1] + tau[2]) / 3.0;
        let j2 = 0.5 * tau.iter().map(|t| (t - p).powi(2)).sum::<f64>();
        j2.sqrt() + self.eta * p - self.xi * self.cohesion
    }

    /// The return at trial strains `eps` (plastic trial assumed), generic for the tangent.
    fn plastic_return<T: Real>(&self, eps: [T; 3]) -> ([T; 3], DruckerPragerRegion) {
        let (g, k) = (self.mu, self.lambda + 2.0 * self.mu / 3.0);
        let tau_b = hencky_stress(self.lambda, self.mu, eps);
        let p = (tau_b[0] + tau_b[1] + tau_b[2]) / 3.0;
        let s = tau_b.map(|t| t - p);
        let j2 = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) * 0.5;
        let sq = if j2.re() > 0.0 { j2.sqrt() } else { T::cst(0.0) };
        let f = sq + p * self.eta - self.xi * self.cohesion;
        let dgamma = f / (g + k * self.eta * self.eta_bar);
        if sq.re() - g * dgamma.re() >= 0.0 && sq.re() > 0.0 {
            let factor = -(dgamma * g / sq) + 1.0;
            let p_new = p - dgamma * (k * self.eta_bar);
            (s.map(|si| si * factor + p_new), DruckerPragerRegion::Cone)
        } else {
            let apex = T::cst(self.xi * self.cohesion / self.eta);
            ([apex, apex, apex], DruckerPragerRegion::Apex)
        }
    }

    /// Return region taken by trial principal elastic log strains `eps_tr`.
    pub fn region(&self, eps_tr: [f64; 3]) -> DruckerPragerRegion {
        let tau_b = hencky_stress(self.lambda, self.mu, eps_tr);
        if self.yield_function(tau_b) <= self.yield_tolerance(tau_b) {
            DruckerPragerRegion::Elastic
        } else {
            self.plastic_return(eps_tr).1
        }
    }

    fn yield_tolerance(&self, tau: [f64; 3]) -> f64 {
        1e-10 * tau.iter().fold(1.0_f64, |a, t| a.max(t.abs()))
    }
}

impl PrincipalModel for DruckerPrager {
    fn internal_len(&self) -> usize {
        3
    }

    fn initialise_internal(&self, internal: &mut [f64]) {
        internal[..3].fill(0.0);
    }

    fn principal_update(
        &self,
        eps_tr: [f64; 3],
        _time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<PrincipalResponse, LawError> {
        let tau_b = hencky_stress(self.lambda, self.mu, eps_tr);
        if self.yield_function(tau_b) <= self.yield_tolerance(tau_b) {
            accumulate_plastic_strain(committed, trial, eps_tr, eps_tr, false);
            return Ok(PrincipalResponse { tau: tau_b, eps_e: eps_tr, dtau_deps: hencky_matrix(self.lambda, self.mu) });
        }
        let eps: [Dual<3>; 3] = [Dual::seed(eps_tr[0], 0), Dual::seed(eps_tr[1], 1), Dual::seed(eps_tr[2], 2)];
        let (t, _) = self.plastic_return(eps);
        let tau = t.map(|x| x.v);
        let eps_e = hencky_strain(self.lambda, self.mu, tau);
        accumulate_plastic_strain(committed, trial, eps_tr, eps_e, true);
        Ok(PrincipalResponse { tau, eps_e, dtau_deps: Matrix3::from_fn(|a, b| t[a].d[b]) })
    }

    fn elastic_strain(&self, tau: [f64; 3]) -> Result<[f64; 3], LawError> {
        Ok(hencky_strain(self.lambda, self.mu, tau))
    }
}

impl DruckerPrager {
    /// The elastic volumetric strain at the apex, `θ_apex = p_apex/K`, `p_apex = ξ c/η`
    /// (`+∞` without an apex: η = 0, von Mises).
    fn apex_strain(&self) -> f64 {
        if self.eta > 0.0 {
            self.xi * self.cohesion / self.eta / (self.lambda + 2.0 * self.mu / 3.0)
        } else {
            f64::INFINITY
        }
    }

    /// The u–p return (module doc) at trial principal log strains `eps` and pressure `p`.
    fn mixed_return<T: Real>(&self, eps: [T; 3], p: T) -> ([T; 3], DruckerPragerRegion) {
        let s = crate::mixed::deviator(eps).map(|e| e * (2.0 * self.mu));
        let j2 = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) * 0.5;
        let sq = if j2.re() > 0.0 { j2.sqrt() } else { T::cst(0.0) };
        let f = sq + p * self.eta - self.xi * self.cohesion;
        let values = s.map(|x| x.re() + p.re());
        if f.re() <= self.yield_tolerance(values) {
            return (s.map(|x| x + p), DruckerPragerRegion::Elastic);
        }
        if sq.re() - f.re() >= 0.0 && sq.re() > 0.0 {
            let factor = -(f / sq) + 1.0;
            (s.map(|x| x * factor + p), DruckerPragerRegion::Cone)
        } else {
            ([p, p, p], DruckerPragerRegion::Apex)
        }
    }
}

impl MixedPrincipalModel for DruckerPrager {
    fn lame(&self) -> (f64, f64) {
        (self.lambda, self.mu)
    }

    fn mixed_principal_update(
        &self,
        eps_tr: [f64; 3],
        pressure: f64,
        _time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<MixedPrincipalResponse, LawError> {
        dual_mixed_response(eps_tr, pressure, self.mu, committed, trial, |eps, p| {
            let (t, region) = self.mixed_return(eps, p);
            let apex_cap = (region == DruckerPragerRegion::Apex).then(|| self.apex_strain());
            Ok((t, MixedReturn { yielded: region != DruckerPragerRegion::Elastic, apex_cap }))
        })
    }
}

multiplicative::impl_principal_law!(impl[] DruckerPrager, name: "drucker_prager", outputs: &PLASTIC_OUTPUT, lame: |law| (law.lambda, law.mu),
mixed: |law| if law.eta_bar == 0.0 {
    Ok(law)
} else {
    Err("mixed_up needs an isochoric plastic flow: dilatancy_angle must be 0".to_string())
});

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_relative_error;
    use crate::{ConstitutiveLaw, Kinematics};

    #[test]
    fn tangent_on_cone_and_apex() {
        let law = DruckerPrager::new(
            2000.0,
            5.0e7,
            0.3,
            30f64.to_radians(),
            5e3,
            10f64.to_radians(),
            DruckerPragerFit::PlaneStrain,
        );
        let rot = nalgebra::Rotation3::from_euler_angles(0.7, -0.2, 0.4).into_inner();
        // Trial principal Kirchhoff stresses (kPa); the apex is at ξ c/η = c cot φ = 8.7 kPa.
        for (tau_kpa, expected) in [
            ([-50.0, -200.0, -400.0], DruckerPragerRegion::Cone),
            ([-50.0, -300.0, -300.0], DruckerPragerRegion::Cone),
            ([30.0, 40.0, 35.0], DruckerPragerRegion::Apex),
            ([-100.0, -120.0, -150.0], DruckerPragerRegion::Elastic),
        ] {
            let eps = hencky_strain(law.lambda, law.mu, tau_kpa.map(|t| t * 1e3));
            assert_eq!(law.region(eps), expected);
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let err = tangent_relative_error(&law, &Kinematics::at(f), &state).unwrap();
            println!("drucker_prager {expected:?}: tangent error vs FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }

    /// u–p form: von Mises (φ = 0, incompressible) and φ = 30° (ψ = 0), tangents against
    /// central differences on the cone, at the apex and elastic.
    #[test]
    fn mixed_tangent_on_cone_and_apex() {
        let rot = nalgebra::Rotation3::from_euler_angles(0.7, -0.2, 0.4).into_inner();
        let fit = DruckerPragerFit::PlaneStrain;
        let von_mises = DruckerPrager::new(2000.0, 1.0e5, 0.5, 0.0, 1.0e3, 0.0, fit);
        let frictional = DruckerPrager::new(2000.0, 5.0e7, 0.3, 30f64.to_radians(), 5e3, 0.0, fit);
        for (law, dev, p_kpa, expected) in [
            (&von_mises, [0.5, -0.2, -0.3], -50.0, DruckerPragerRegion::Elastic),
            (&von_mises, [20.0, -5.0, -15.0], -50.0, DruckerPragerRegion::Cone),
            (&frictional, [2.0, -0.5, -1.5], -100.0, DruckerPragerRegion::Cone),
            (&frictional, [2.0, -0.5, -1.5], 20.0, DruckerPragerRegion::Apex),
        ] {
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let eps = dev.map(|e| e * 1e-3 - 0.001);
            assert_eq!(law.mixed_return(eps, p_kpa * 1e3).1, expected);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let (ea, ep) =
                crate::mixed::mixed_tangent_relative_error(law, &Kinematics::at(f), p_kpa * 1e3, &state).unwrap();
            println!("drucker_prager u–p {expected:?}: A error {ea:.2e}, ∂P/∂p error {ep:.2e} (tolerance 1e-6)");
            assert!(ea < 1e-6 && ep < 1e-6, "{expected:?}");
        }
    }
}
