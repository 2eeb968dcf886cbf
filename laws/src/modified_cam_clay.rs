//! Modified Cam Clay at finite strain (Borja & Tamagnini 1998) with Houlsby-type
//! pressure-dependent hyperelasticity.
//!
//! Frame: multiplicative plasticity with logarithmic elastic strains ([`crate::multiplicative`],
//! Simo 1992). Soil-mechanics invariants of the Kirchhoff stress and elastic log strain,
//! **compression positive**: `p = −tr τ/3`, `q = √(3/2) ‖dev τ‖`, `ε_v = −tr ε_e`,
//! `ε_s = √(2/3) ‖dev ε_e‖`.
//!
//! **Elasticity** (Houlsby 1985, Computers and Geotechnics 1:3–13,
//! doi:10.1016/0266-352X(85)90012-6; Borja & Tamagnini 1998, eqs. 3.5–3.7), from the free
//! energy `Ψ = κ̂ p_r e^ω + (3/2)(μ₀ + α p_r e^ω) ε_s²`, `ω = ε_v/κ̂`:
//!
//! `p = p_r e^ω (1 + 3α ε_s²/(2κ̂))`,  `q = 3 μ ε_s`,  `μ = μ₀ + α p_r e^ω`.
//!
//! The **reference pressure** is `p_r = p′c/OCR`: the virgin state (`ε_e = 0`) is the
//! isotropic stress `p₀ = p′c/OCR`, the mean stress at which the sample was unloaded from
//! its preconsolidation pressure (as in Kratos' MPM Cam Clay). Other initial (e.g.
//! geostatic) stresses enter through
//! [`crate::ConstitutiveLaw::initialise_state_at_stress`].
//!
//! **Yield and flow** (associated): `f = q²/M² + p (p − p_c) ≤ 0`;
//! `Δε_v^p = Δλ (2p − p_c)`, `Δε_s^p = Δλ 2q/M²`.
//! **Hardening**: `p_c = p_c,n exp(Δε_v^p/(λ̂ − κ̂))`, so that isotropic virgin loading
//! follows `ln J = −λ̂ ln p + const` (the normal consolidation line in `ln v – ln p`,
//! Butterfield 1979, with `p` the Kirchhoff pressure of this model).
//!
//! **Return mapping** (Borja & Tamagnini 1998, §4, "Cam-Clay plasticity, Part III: Extension
//! of the infinitesimal model to include finite strains", CMAME 155:73–95,
//! doi:10.1016/S0045-7825(97)00141-2): the deviatoric direction is fixed by the trial
//! (`dev ε_e = ρ dev ε_tr`, `ρ = ε_s/ε_s,tr = 1/(1 + 6 μ Δλ/M²)`), leaving two unknowns
//! `(ε_v, Δλ)` solved by Newton on
//!
//! `r₁ = ε_v − ε_v,tr + Δλ (2p − p_c) = 0`,  `r₂ = (q²/M² + p(p − p_c))/p_c,n² = 0`.
//!
//! The algorithmic tangent follows from the implicit function theorem at the converged
//! point, `d(ε_v, Δλ)/d(ε_v,tr, ε_s,tr) = −(∂r/∂x)⁻¹ ∂r/∂(ε_v,tr, ε_s,tr)`, with all partial
//! derivatives from [`crate::dual`]; `τ_a = −p + 2 μ ρ dev ε_tr,a`.

use nalgebra::{Matrix2, Matrix3};

use crate::dual::{Dual, Real};
use crate::multiplicative::{self, accumulate_plastic_strain, PrincipalModel, PrincipalResponse};
use crate::LawError;

/// Names of the MCC state variables, in slot order.
pub const MCC_OUTPUT: [&str; 4] = [
    "accumulated_plastic_deviatoric_strain",
    "accumulated_plastic_volumetric_strain",
    "yield_flag",
    "preconsolidation_pressure",
];

/// Modified Cam Clay parameters (compression-positive pressures in Pa).
#[derive(Debug, Clone, Copy)]
pub struct ModifiedCamClay {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// Initial preconsolidation pressure p′c in Pa.
    pub preconsolidation_pressure: f64,
    /// Overconsolidation ratio OCR = p′c/p₀ ≥ 1.
    pub ocr: f64,
    /// Swelling slope κ̂ (ln v – ln p).
    pub swelling_slope: f64,
    /// Compression slope λ̂ (ln v – ln p), > κ̂.
    pub compression_slope: f64,
    /// Critical state slope M.
    pub critical_state_slope: f64,
    /// Initial (constant part of the) shear modulus μ₀ in Pa.
    pub initial_shear_modulus: f64,
    /// Coupling α of the shear modulus to the pressure, `μ = μ₀ + α p_r e^ω`.
    pub alpha_shear: f64,
}

/// Converged return state, with intermediate quantities for the tangent.
struct Invariants<T> {
    residual: [T; 2],
    p: T,
    mu: T,
    rho: T,
    pc: T,
}

/// Maximum local Newton iterations.
const MAX_ITERATIONS: usize = 60;

impl ModifiedCamClay {
    /// Reference pressure `p_r = p′c / OCR` (Pa).
    pub fn reference_pressure(&self) -> f64 {
        self.preconsolidation_pressure / self.ocr
    }

    /// Yield function `f = q²/M² + p (p − p_c)` (Pa²), compression-positive `p`.
    pub fn yield_function(&self, p: f64, q: f64, pc: f64) -> f64 {
        q * q / self.critical_state_slope.powi(2) + p * (p - pc)
    }

    /// Elastic law and residuals at unknowns `x = (ε_v, Δλ)` and trial invariants.
    fn invariants<T: Real>(&self, x: [T; 2], ev_tr: T, es_tr: T, pc_n: f64) -> Invariants<T> {
        let (kap, lam, m2) = (self.swelling_slope, self.compression_slope, self.critical_state_slope.powi(2));
        let [ev, dl] = x;
        let w = (ev / kap).exp() * self.reference_pressure();
        let mu = w * self.alpha_shear + self.initial_shear_modulus;
        let rho = T::cst(1.0) / (mu * dl * (6.0 / m2) + 1.0);
        let es = rho * es_tr;
        let p = w * (es * es * (1.5 * self.alpha_shear / kap) + 1.0);
        let q = mu * es * 3.0;
        let pc = ((ev_tr - ev) / (lam - kap)).exp() * pc_n;
        let r1 = ev - ev_tr + dl * (p * 2.0 - pc);
        let r2 = (q * q / m2 + p * (p - pc)) / (pc_n * pc_n);
        Invariants { residual: [r1, r2], p, mu, rho, pc }
    }

    /// Newton solution `(ε_v, Δλ)` of the plastic return.
    fn solve(&self, ev_tr: f64, es_tr: f64, pc_n: f64) -> Result<[f64; 2], LawError> {
        let eval = |x: [f64; 2]| {
            let r = self.invariants(
                [Dual::<2>::seed(x[0], 0), Dual::seed(x[1], 1)],
                Dual::cst(ev_tr),
                Dual::cst(es_tr),
                pc_n,
            );
            r.residual
        };
        let norm = |r: &[Dual<2>; 2]| (r[0].v.powi(2) + r[1].v.powi(2)).sqrt();
        let mut x = [ev_tr, 0.0];
        let mut r = eval(x);
        for _ in 0..MAX_ITERATIONS {
            if r[0].v.abs() < 1e-14 && r[1].v.abs() < 1e-13 {
                return Ok(x);
            }
            let j = Matrix2::new(r[0].d[0], r[0].d[1], r[1].d[0], r[1].d[1]);
            let step = j
                .try_inverse()
                .map(|ji| ji * nalgebra::Vector2::new(-r[0].v, -r[1].v))
                .ok_or(LawError::ReturnMappingFailed { iterations: 0, residual: norm(&r) })?;
            // Backtracking on the residual norm, keeping Δλ ≥ 0.
            let mut t = 1.0;
            loop {
                let cand = [x[0] + t * step[0], (x[1] + t * step[1]).max(0.0)];
                let rc = eval(cand);
                if norm(&rc) < norm(&r) || t < 1e-4 {
                    x = cand;
                    r = rc;
                    break;
                }
                t *= 0.5;
            }
        }
        Err(LawError::ReturnMappingFailed { iterations: MAX_ITERATIONS, residual: norm(&r) })
    }
}

impl PrincipalModel for ModifiedCamClay {
    fn internal_len(&self) -> usize {
        4
    }

    fn initialise_internal(&self, internal: &mut [f64]) {
        internal[..3].fill(0.0);
        internal[3] = self.preconsolidation_pressure;
    }

    fn principal_update(
        &self,
        eps_tr: [f64; 3],
        _time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<PrincipalResponse, LawError> {
        let pc_n = committed[3];
        // Trial invariants as functions of the principal trial strains.
        let e: [Dual<3>; 3] = [Dual::seed(eps_tr[0], 0), Dual::seed(eps_tr[1], 1), Dual::seed(eps_tr[2], 2)];
        let ev_tr = -(e[0] + e[1] + e[2]);
        let dev = e.map(|ea| ea + ev_tr / 3.0);
        let es2 = (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]) * (2.0 / 3.0);
        // ε_s,tr is not differentiable at 0, where τ depends on it only through even terms.
        let es_tr = if es2.v > 1e-28 { es2.sqrt() } else { Dual::cst(es2.v.max(0.0).sqrt()) };
        let trial_state = self.invariants([ev_tr.v, 0.0], ev_tr.v, es_tr.v, pc_n);
        let q_tr = 3.0 * trial_state.mu * es_tr.v;
        let f_tr = self.yield_function(trial_state.p, q_tr, pc_n);
        let plastic = f_tr > 1e-12 * pc_n * pc_n;
        // Unknowns and their derivatives with respect to (ε_v,tr, ε_s,tr).
        let (x, dx) = if plastic {
            let x = self.solve(ev_tr.v, es_tr.v, pc_n)?;
            let rx = self
                .invariants(
                    [Dual::<2>::seed(x[0], 0), Dual::seed(x[1], 1)],
                    Dual::cst(ev_tr.v),
                    Dual::cst(es_tr.v),
                    pc_n,
                )
                .residual;
            let ri = self
                .invariants(
                    [Dual::<2>::cst(x[0]), Dual::cst(x[1])],
                    Dual::seed(ev_tr.v, 0),
                    Dual::seed(es_tr.v, 1),
                    pc_n,
                )
                .residual;
            let jx = Matrix2::new(rx[0].d[0], rx[0].d[1], rx[1].d[0], rx[1].d[1]);
            let ji = Matrix2::new(ri[0].d[0], ri[0].d[1], ri[1].d[0], ri[1].d[1]);
            let dx = -jx.try_inverse().ok_or(LawError::ReturnMappingFailed { iterations: 0, residual: 0.0 })? * ji;
            (x, dx)
        } else {
            ([ev_tr.v, 0.0], Matrix2::new(1.0, 0.0, 0.0, 0.0))
        };
        let dv = ev_tr - ev_tr.v;
        let ds = es_tr - es_tr.v;
        let xd = [dv * dx[(0, 0)] + ds * dx[(0, 1)] + x[0], dv * dx[(1, 0)] + ds * dx[(1, 1)] + x[1]];
        let inv = self.invariants(xd, ev_tr, es_tr, pc_n);
        let two_mu_rho = inv.mu * inv.rho * 2.0;
        let tau = dev.map(|d| d * two_mu_rho - inv.p);
        let eps_e: [f64; 3] = dev.map(|d| inv.rho.v * d.v - x[0] / 3.0);
        accumulate_plastic_strain(committed, trial, eps_tr, eps_e, plastic);
        trial[3] = if plastic { inv.pc.v } else { pc_n };
        Ok(PrincipalResponse { tau: tau.map(|t| t.v), eps_e, dtau_deps: Matrix3::from_fn(|a, b| tau[a].d[b]) })
    }

    fn elastic_strain(&self, tau: [f64; 3]) -> Result<[f64; 3], LawError> {
        let p = -(tau[0] + tau[1] + tau[2]) / 3.0;
        if p.is_nan() || p <= 0.0 {
            return Err(LawError::InitialStress {
                problem: format!("modified_cam_clay needs a compressive mean stress, got p = {p:.3e} Pa"),
            });
        }
        let s = tau.map(|t| t + p);
        let q = (1.5 * s.iter().map(|v| v * v).sum::<f64>()).sqrt();
        let mut w = p;
        let mut mu = self.initial_shear_modulus + self.alpha_shear * w;
        for _ in 0..100 {
            mu = self.initial_shear_modulus + self.alpha_shear * w;
            let es = q / (3.0 * mu);
            let w_new = p / (1.0 + 1.5 * self.alpha_shear * es * es / self.swelling_slope);
            if (w_new - w).abs() <= 1e-15 * p {
                w = w_new;
                break;
            }
            w = w_new;
        }
        let ev = self.swelling_slope * (w / self.reference_pressure()).ln();
        Ok(s.map(|sa| sa / (2.0 * mu) - ev / 3.0))
    }
}

// Starts at rest under a given stress (`initialise_state_at_stress`): the preconsolidation
// pressure stays `p′c`, the stress must lie inside `f ≤ 0`, the reference pressure
// `p_r = p′c/OCR` is unchanged. Elastic constants at the reference state: `K = p_r/κ̂`,
// `G = μ₀ + α p_r`, `λ = K − 2G/3`.
multiplicative::impl_principal_law!(impl[] ModifiedCamClay, name: "modified_cam_clay", outputs: &MCC_OUTPUT, lame: |law| {
    let pr = law.reference_pressure();
    let g = law.initial_shear_modulus + law.alpha_shear * pr;
    (pr / law.swelling_slope - 2.0 * g / 3.0, g)
});

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_relative_error;
    use crate::{ConstitutiveLaw, Kinematics};

    pub(crate) fn clay(ocr: f64) -> ModifiedCamClay {
        ModifiedCamClay {
            density: 1800.0,
            preconsolidation_pressure: 200e3,
            ocr,
            swelling_slope: 0.02,
            compression_slope: 0.1,
            critical_state_slope: 1.0,
            initial_shear_modulus: 2e6,
            alpha_shear: 50.0,
        }
    }

    #[test]
    fn tangent_elastic_wet_and_dry() {
        let rot = nalgebra::Rotation3::from_euler_angles(0.1, 0.8, -0.6).into_inner();
        for (ocr, eps, label) in [
            (1.5, [-0.0005, 0.0002, 0.0001], "elastic"),
            (1.2, [-0.01, 0.001, 0.002], "wet (p > p_c/2)"),
            (1.0, [-0.004, -0.004, -0.004], "isotropic wet"),
            (6.0, [-0.02, 0.008, 0.009], "dry (p < p_c/2)"),
        ] {
            let law = clay(ocr);
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let mut trial = state.clone();
            law.stress_response(&Kinematics::at(f), &state, &mut trial).unwrap();
            let err = tangent_relative_error(&law, &Kinematics::at(f), &state).unwrap();
            let mut out = [0.0; 4];
            law.state_output(&trial, &mut out);
            println!("modified_cam_clay {label}: yield flag {}, p_c {:.1} kPa, tangent error vs FD {err:.2e} (tolerance 1e-6)", out[2], out[3] / 1e3);
            assert_eq!(out[2] == 1.0, label != "elastic");
            assert!(err < 1e-6);
        }
    }
}
