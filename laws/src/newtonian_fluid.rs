//! Compressible Newtonian fluid in displacement form (for fluids carried by material points).
//!
//! Kirchhoff stress `τ = K ln J I + 2 η J dev d`, i.e. Cauchy stress
//! `σ = (K ln J / J) I + 2 η dev d`: a Hencky-type barotropic pressure `p = −K ln J / J` with
//! bulk modulus `K`, and Newtonian viscous shear with dynamic viscosity `η`.
//!
//! The rate of deformation is the backward difference over the step,
//! `l = Ḟ F⁻¹ ≈ (F_{n+1} − F_n) F_{n+1}⁻¹ / Δt = (I − F_n F_{n+1}⁻¹)/Δt`, `d = sym l`, using
//! [`Kinematics::previous_deformation_gradient`] and [`Kinematics::time_step`]. For `Δt = 0`
//! (a static step) the viscous term vanishes and only the pressure remains.
//!
//! Tangent: for `dF = e_k ⊗ e_L`, `dJ/J = F⁻¹_Lk`, `dl = (F_n F⁻¹ e_k)(e_Lᵀ F⁻¹)/Δt`,
//! `dτ = K F⁻¹_Lk I + 2 η J F⁻¹_Lk dev d + 2 η J dev sym dl`, then `P = τ F⁻ᵀ`.
//!
//! Reference: Larese, Rossi, Oñate & Idelsohn (2008), "Validation of the particle finite
//! element method (PFEM) for simulation of free surface flows", Engineering Computations
//! 25(4):385–425, doi:10.1108/02644400810874976 (Newtonian fluid in Lagrangian form); the
//! seed names this law as under development in Kratos' MPM application.

use nalgebra::Matrix3;

use crate::multiplicative::checked_inverse;
use crate::tensor::piola_from_kirchhoff;
use crate::{idx, ConstitutiveLaw, Kinematics, LawError, StressResponse};

/// Newtonian fluid with viscosity η (Pa·s) and bulk modulus K (Pa).
#[derive(Debug, Clone, Copy)]
pub struct NewtonianFluid {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// Dynamic viscosity η in Pa·s.
    pub viscosity: f64,
    /// Bulk modulus K in Pa.
    pub bulk_modulus: f64,
}

fn dev(m: &Matrix3<f64>) -> Matrix3<f64> {
    m - Matrix3::identity() * (m.trace() / 3.0)
}

impl ConstitutiveLaw for NewtonianFluid {
    fn name(&self) -> &'static str {
        "newtonian_fluid"
    }

    fn density(&self) -> f64 {
        self.density
    }

    /// `(λ, μ) = (K, 0)`: no static shear stiffness.
    fn elastic_lame(&self) -> (f64, f64) {
        (self.bulk_modulus, 0.0)
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
        let j = f.determinant();
        let dt = kinematics.time_step;
        let visc = if dt > 0.0 { self.viscosity } else { 0.0 };
        let rate = if dt > 0.0 { 1.0 / dt } else { 0.0 };
        let fnfi = kinematics.previous_deformation_gradient * f_inv;
        let l = (Matrix3::identity() - fnfi) * rate;
        let dev_d = dev(&(0.5 * (l + l.transpose())));
        let tau = Matrix3::identity() * (self.bulk_modulus * j.ln()) + dev_d * (2.0 * visc * j);
        let dtau_df = &mut response.tangent;
        let components = kinematics.tangent.components();
        for &col in components {
            let (k, ll) = (col / 3, col % 3);
            let dj = f_inv[(ll, k)];
            let dl = fnfi.column(k) * f_inv.row(ll) * rate;
            let dtau = Matrix3::identity() * (self.bulk_modulus * dj)
                + dev_d * (2.0 * visc * j * dj)
                + dev(&(0.5 * (dl + dl.transpose()))) * (2.0 * visc * j);
            for a in 0..3 {
                for b in 0..3 {
                    dtau_df[(idx(a, b), col)] = dtau[(a, b)];
                }
            }
        }
        response.first_piola = piola_from_kirchhoff(&f_inv, &tau, &mut response.tangent, components);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_relative_error;
    use crate::TangentRequest;

    #[test]
    fn tangent_with_and_without_time_step() {
        let law = NewtonianFluid { density: 1000.0, viscosity: 1e3, bulk_modulus: 2e6 };
        let f = Matrix3::new(1.02, 0.05, 0.0, -0.01, 0.97, 0.02, 0.0, 0.01, 1.01);
        let fn_ = Matrix3::new(1.01, 0.03, 0.0, 0.0, 0.99, 0.01, 0.0, 0.0, 1.0);
        for dt in [0.0, 1e-3] {
            let kin = Kinematics {
                deformation_gradient: f,
                previous_deformation_gradient: fn_,
                time_step: dt,
                tangent: TangentRequest::Full,
            };
            let err = tangent_relative_error(&law, &kin, &[]).unwrap();
            println!("newtonian_fluid Δt = {dt}: tangent error vs FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }

    /// Simple shear at rate γ̇ from the reference state: σ_xy = η γ̇ (to first order in γ̇ Δt).
    #[test]
    fn shear_stress_is_viscosity_times_rate() {
        let law = NewtonianFluid { density: 1000.0, viscosity: 2.0, bulk_modulus: 2e6 };
        let (rate, dt) = (0.5, 1e-4);
        let mut f = Matrix3::identity();
        f[(0, 1)] = rate * dt;
        let kin = Kinematics {
            deformation_gradient: f,
            previous_deformation_gradient: Matrix3::identity(),
            time_step: dt,
            tangent: TangentRequest::Full,
        };
        let r = law.stress_response(&kin, &[], &mut []).unwrap();
        let sigma = r.first_piola * f.transpose() / f.determinant();
        println!(
            "newtonian_fluid: σ_xy = {:.6} Pa, η γ̇ = {:.6} Pa (tolerance 1e-4 relative)",
            sigma[(0, 1)],
            2.0 * rate
        );
        assert!((sigma[(0, 1)] - 2.0 * rate).abs() < 1e-4 * 2.0 * rate);
    }
}
