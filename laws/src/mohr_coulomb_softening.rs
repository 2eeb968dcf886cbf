//! Mohr–Coulomb with exponential strain softening (the seed's "Mohr Coulomb Strain
//! Softening"): friction angle, cohesion and dilatancy angle decay from their peak to their
//! residual values with the accumulated plastic deviatoric strain
//! `κ = Σ √(2/3) ‖dev Δε_p‖`:
//!
//! `X(κ) = X_r + (X_p − X_r) exp(−β κ)`,  `X ∈ {φ, c, ψ}`, shape factor `β ≥ 0`.
//!
//! Everything else is [`crate::mohr_coulomb`]: Hencky elasticity, Simo's multiplicative
//! frame, the Clausen, Damkilde & Andersen (2007) return (doi:10.1016/j.compstruc.2007.04.002),
//! here inside a scalar Newton iteration on κ (fully implicit softening; the tangent includes
//! `∂τ/∂κ · dκ/dε_tr`).
//!
//! Softening law after the Kratos MPM strain-softening Mohr–Coulomb law (Iaconeta, Larese,
//! Rossi & Guo 2017, Materials 10(10):1150, doi:10.3390/ma10101150).

use crate::dual::Real;
use crate::mohr_coulomb::{MohrCoulombLaw, Strength, StrengthEvolution};

/// Peak and residual strength with exponential decay in κ.
#[derive(Debug, Clone, Copy)]
pub struct ExponentialSoftening {
    /// Peak strength (φ, ψ in rad, c in Pa).
    pub peak: Strength<f64>,
    /// Residual strength (φ, ψ in rad, c in Pa).
    pub residual: Strength<f64>,
    /// Shape factor β (dimensionless, ≥ 0).
    pub shape_factor: f64,
}

impl StrengthEvolution for ExponentialSoftening {
    const NAME: &'static str = "mohr_coulomb_softening";

    fn at<T: Real>(&self, kappa: T) -> Strength<T> {
        let w = (kappa * (-self.shape_factor)).exp();
        let mix = |p: f64, r: f64| w * (p - r) + r;
        Strength {
            friction_angle: mix(self.peak.friction_angle, self.residual.friction_angle),
            cohesion: mix(self.peak.cohesion, self.residual.cohesion),
            dilatancy_angle: mix(self.peak.dilatancy_angle, self.residual.dilatancy_angle),
        }
    }

    fn evolves(&self) -> bool {
        self.shape_factor > 0.0
            && (self.peak.friction_angle != self.residual.friction_angle
                || self.peak.cohesion != self.residual.cohesion
                || self.peak.dilatancy_angle != self.residual.dilatancy_angle)
    }
}

/// Mohr–Coulomb with exponential strain softening.
pub type MohrCoulombSoftening = MohrCoulombLaw<ExponentialSoftening>;

impl MohrCoulombSoftening {
    /// From `E` (Pa), `ν` and the softening strength.
    pub fn new(density: f64, young_modulus: f64, poisson_ratio: f64, softening: ExponentialSoftening) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self { density, lambda, mu, strength: softening }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mohr_coulomb::Region;
    use crate::multiplicative::CP_INV_LEN;
    use crate::tensor::tangent_relative_error;
    use crate::{ConstitutiveLaw, Kinematics};
    use nalgebra::Matrix3;

    fn law() -> MohrCoulombSoftening {
        let s = |phi: f64, c: f64, psi: f64| Strength {
            friction_angle: phi.to_radians(),
            cohesion: c,
            dilatancy_angle: psi.to_radians(),
        };
        MohrCoulombSoftening::new(
            2000.0,
            5.0e7,
            0.3,
            ExponentialSoftening { peak: s(30.0, 10e3, 8.0), residual: s(20.0, 2e3, 0.0), shape_factor: 40.0 },
        )
    }

    #[test]
    fn softening_tangent_in_every_region() {
        let law = law();
        let rot = nalgebra::Rotation3::from_euler_angles(-0.4, 0.3, 0.9).into_inner();
        // Trial principal Kirchhoff stresses (kPa): plane, extension edge, compression edge, apex.
        for (tau_kpa, kappa) in [
            ([-50.0, -200.0, -400.0], 0.0),
            ([-50.0, -300.0, -300.0], 0.01),
            ([-100.0, -100.0, -400.0], 0.02),
            ([30.0, 40.0, 35.0], 0.005),
        ] {
            let eps = crate::multiplicative::hencky_strain(law.lambda, law.mu, tau_kpa.map(|t| t * 1e3));
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            state[CP_INV_LEN] = kappa;
            let region = law.region(eps, &state[CP_INV_LEN..]);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let err = tangent_relative_error(&law, &Kinematics::at(f), &state).unwrap();
            println!(
                "mohr_coulomb_softening {region:?} (κ_n = {kappa}): tangent error vs FD {err:.2e} (tolerance 1e-6)"
            );
            assert_ne!(region, Region::Elastic);
            assert!(err < 1e-6);
        }
    }
}
