//! The μ(I) rheology of dense granular flow at finite strain: a cohesionless, rate-dependent
//! friction law with isochoric plastic flow on Hencky elasticity.
//!
//! **Model** (Jop, Forterre & Pouliquen 2006, "A constitutive law for dense granular flows",
//! Nature 441:727–730, doi:10.1038/nature04801). In Kirchhoff stress with the pressure
//! **compression positive**, `p = −tr τ/3`, the deviator `s = dev τ` and the equivalent shear
//! stress `τ̄ = ‖s‖/√2`, the grains flow when `τ̄` exceeds `μ(I) p`, with the friction
//! coefficient
//!
//! `μ(I) = μ_s + (μ₂ − μ_s)/(I₀/I + 1)`,  `I = γ̇_p d/√(p/ρ_s)`,
//!
//! the inertial number `I` of the equivalent plastic shear rate `γ̇_p = √2 ‖D_p‖`, the grain
//! diameter `d` and the grain density `ρ_s`: `μ_s` at rest (`I → 0`), rising to `μ₂` in
//! fast flow (`I ≫ I₀`). The flow is isochoric (no dilatancy) along the deviator,
//! `D_p = γ̇_p s/(√2 ‖s‖)`. Below `τ̄ = μ_s p` the material is an elastic solid at rest; in
//! tension it carries no stress at all (the "disconnected" state of Dunatunga & Kamrin). `p`
//! is the mean **Kirchhoff** stress (`J` times the Cauchy mean stress): it enters `I` and the
//! yield condition, as every yield function of this crate acts on τ.
//!
//! **Elasticity**: Hencky, `p = −K tr ε_e`, `s = 2G dev ε_e`, in the multiplicative frame
//! of [`crate::multiplicative`] (Simo 1992); the return below acts on the trial principal
//! elastic log strains `ε_tr` and the step's `Δt`.
//!
//! **Return mapping** (backward Euler, after the implicit form of Dunatunga & Kamrin 2015,
//! "Continuum modelling and simulation of granular flows through their many phases",
//! J. Fluid Mech. 779:483–513, doi:10.1017/jfm.2015.383): trial `p_tr = −K tr ε_tr`,
//! `s_tr = 2G dev ε_tr`, `τ̄_tr = ‖s_tr‖/√2`, overstress `f = τ̄_tr − μ_s p_tr`.
//!
//! 1. `f ≤ 0` (to round-off): **elastic**, `τ = s_tr − p_tr 1`.
//! 2. Otherwise, `p_tr ≤ 0`: **apex** (disconnected), `τ = 0`, `ε_e = 0`: the whole trial
//!    strain is released as plastic strain (the volumetric part is the grains' separation).
//! 3. Otherwise **flow** at `p = p_tr` (isochoric flow keeps the pressure) with the plastic
//!    shear strain increment `Δγ = γ̇_p Δt`: `τ̄ = τ̄_tr − G Δγ = μ(I) p`,
//!    `I = Δγ t_g/Δt`, `t_g = d √(ρ_s/p)` the inertial time of a grain. In the unknown
//!    `x = I/(I₀ + I) ∈ [0, 1)` (the share of the friction range `μ₂ − μ_s` mobilised,
//!    `μ = μ_s + (μ₂ − μ_s) x`) this scalar equation is
//!
//!    `f − c x/(1 − x) − α x = 0`,  `α = (μ₂ − μ_s) p`,  `c = G I₀ Δt/t_g`,
//!
//!    a quadratic `α x² − (f + c + α) x + f = 0` whose root in `[0, 1)` is
//!    `x = 2f / (f + c + α + √((f − α + c)² + 4αc))`: a closed form without cancellation
//!    (every term is positive), exact to round-off, so this law needs no local iteration
//!    (a safeguarded Newton would only approximate it). Then `I = I₀ x/(1 − x)`,
//!    `s = (μ p/τ̄_tr) s_tr`, `τ = s − p 1`, `ε_e = tr ε_tr/3 + s/2G` (volume unchanged).
//!    The limits: `Δt → ∞` (slow loading) gives `x → 0`, `μ → μ_s`; `Δt → 0⁺` gives
//!    `μ → μ₂` where `τ̄_tr ≥ μ₂ p` and no flow (`Δγ → 0`) below (an instantaneous load meets
//!    the largest friction).
//!    **A static step** (`Δt = 0`) is a step without time, taken as infinitely slow: the
//!    quasi-static limit `μ = μ_s` (`x = 0`, `I = 0`), a rate-independent Drucker–Prager
//!    cone with `√J₂ = μ_s p` and isochoric flow. It is not the limit `Δt → 0⁺` above: a
//!    load step of a static analysis that hands the law a pseudo-time `Δt > 0` gets the
//!    rate-dependent law at that `Δt`.
//!
//! The algorithmic tangent `∂τ_a/∂ε_tr,b` is the exact derivative of this closed form,
//! evaluated in dual numbers ([`crate::dual`]); it is `Hencky` when elastic and 0 at the
//! apex (where `P = 0` in a neighbourhood).
//!
//! **u–p form** ([`crate::mixed`]; the flow is isochoric): at the given pressure (mean
//! Kirchhoff stress, tension positive, `p = −pressure`) the deviatoric return is the same
//! scalar equation; `τ = s + pressure 1`. At the apex (`pressure ≥ 0`) no deviator is
//! admissible, `τ = pressure 1`, and at the end of the step the volume beyond `θ_apex = 0`
//! is released as plastic dilation ([`crate::mixed::elastic_strain_up`]), as for
//! Drucker–Prager with `c = 0`. Tangents by dual numbers seeded on `(ε_tr, pressure)`.
//!
//! **State variables**: `accumulated_plastic_deviatoric_strain` (`Σ √(2/3) ‖dev Δε_p‖ =
//! Σ Δγ/√3`), `accumulated_plastic_volumetric_strain` (nonzero only at the apex),
//! `yield_flag` (1 if the step flowed or reached the apex) and `inertial_number` (the `I`
//! of the last step; 0 when it did not flow, at the apex and in a static step).

use nalgebra::Matrix3;

use crate::dual::{Dual, Real};
use crate::mixed::{
    deviator, dual_mixed_response, elastic_strain_up, MixedPrincipalModel, MixedPrincipalResponse, MixedReturn,
};
use crate::multiplicative::{
    self, accumulate_plastic_strain, hencky_strain, hencky_stress, PrincipalModel, PrincipalResponse,
};
use crate::LawError;

/// Names of the μ(I) state variables, in slot order.
pub const MU_I_OUTPUT: [&str; 4] =
    ["accumulated_plastic_deviatoric_strain", "accumulated_plastic_volumetric_strain", "yield_flag", "inertial_number"];

/// Return region of a μ(I) step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MuIRegion {
    /// `τ̄_tr ≤ μ_s p_tr`: the solid at rest.
    Elastic,
    /// `τ̄ = μ(I) p`: dense flow.
    Flowing,
    /// `p_tr ≤ 0`: the stress-free, disconnected state.
    Apex,
}

/// The μ(I) law with Hencky elasticity (module doc).
#[derive(Debug, Clone, Copy)]
pub struct MuI {
    /// Density ρ₀ of the bulk material in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ = G in Pa.
    pub mu: f64,
    /// Static friction coefficient μ_s (> 0).
    pub static_friction: f64,
    /// Limit friction coefficient μ₂ (> μ_s) of fast flow.
    pub limit_friction: f64,
    /// Reference inertial number I₀ (> 0).
    pub reference_inertial_number: f64,
    /// Grain diameter d in m.
    pub grain_diameter: f64,
    /// Grain (solid) density ρ_s in kg/m³.
    pub grain_density: f64,
}

/// A deviatoric return: the new deviator, the region and the inertial number.
struct DeviatoricReturn<T> {
    s: [T; 3],
    region: MuIRegion,
    inertial_number: f64,
}

impl MuI {
    /// From `E` (Pa), `ν`, μ_s, μ₂, I₀, `d` (m) and `ρ_s` (kg/m³).
    pub fn new(
        density: f64,
        young_modulus: f64,
        poisson_ratio: f64,
        static_friction: f64,
        limit_friction: f64,
        reference_inertial_number: f64,
        grain_diameter: f64,
        grain_density: f64,
    ) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self {
            density,
            lambda,
            mu,
            static_friction,
            limit_friction,
            reference_inertial_number,
            grain_diameter,
            grain_density,
        }
    }

    /// The friction coefficient `μ(I) = μ_s + (μ₂ − μ_s)/(I₀/I + 1)` (closed form).
    pub fn friction(&self, inertial_number: f64) -> f64 {
        let (ms, m2, i0) = (self.static_friction, self.limit_friction, self.reference_inertial_number);
        ms + (m2 - ms) * inertial_number / (i0 + inertial_number)
    }

    /// The inertial number `I = γ̇ d/√(p/ρ_s)` of the shear rate `shear_rate` (1/s) at the
    /// pressure `pressure` (Pa, compression positive).
    pub fn inertial_number(&self, shear_rate: f64, pressure: f64) -> f64 {
        shear_rate * self.grain_diameter / (pressure / self.grain_density).sqrt()
    }

    /// The shear rate (1/s) at which the inertial number is `inertial_number` under the
    /// pressure `pressure` (Pa, compression positive): the inverse of
    /// [`MuI::inertial_number`].
    pub fn shear_rate(&self, inertial_number: f64, pressure: f64) -> f64 {
        inertial_number * (pressure / self.grain_density).sqrt() / self.grain_diameter
    }

    /// Steps 1–3 of the module doc on the trial deviator `s` (principal, Pa) at the pressure
    /// `p` (compression positive), generic for the dual numbers of the tangent.
    fn deviatoric_return<T: Real>(&self, s: [T; 3], p: T, time_step: f64) -> DeviatoricReturn<T> {
        let j2 = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) * 0.5;
        let tau_bar = if j2.re() > 0.0 { j2.sqrt() } else { T::cst(0.0) };
        let f = tau_bar - p * self.static_friction;
        let scale = s.iter().fold(p.re().abs(), |m, x| m.max(x.re().abs())).max(1.0);
        if f.re() <= 1e-10 * scale {
            return DeviatoricReturn { s, region: MuIRegion::Elastic, inertial_number: 0.0 };
        }
        if p.re() <= 0.0 {
            return DeviatoricReturn { s: [T::cst(0.0); 3], region: MuIRegion::Apex, inertial_number: 0.0 };
        }
        // x = I/(I₀ + I), the mobilised share of μ₂ − μ_s; 0 in a static step.
        let x = if time_step > 0.0 {
            let alpha = p * (self.limit_friction - self.static_friction);
            // c = G I₀ Δt/t_g, 1/t_g = √(p/ρ_s)/d
            let c = (p / self.grain_density).sqrt()
                * (self.mu * self.reference_inertial_number * time_step / self.grain_diameter);
            let root = ((f - alpha + c) * (f - alpha + c) + alpha * c * 4.0).sqrt();
            f * 2.0 / (f + c + alpha + root)
        } else {
            T::cst(0.0)
        };
        let friction = x * (self.limit_friction - self.static_friction) + self.static_friction;
        let factor = friction * p / tau_bar;
        DeviatoricReturn {
            s: s.map(|si| si * factor),
            region: MuIRegion::Flowing,
            inertial_number: self.reference_inertial_number * x.re() / (1.0 - x.re()),
        }
    }

    /// The return at trial principal elastic log strains `eps` (displacement form):
    /// principal Kirchhoff stresses (tension positive), region and inertial number.
    fn principal_return<T: Real>(&self, eps: [T; 3], time_step: f64) -> ([T; 3], MuIRegion, f64) {
        let tau_tr = hencky_stress(self.lambda, self.mu, eps);
        let p = -(tau_tr[0] + tau_tr[1] + tau_tr[2]) / 3.0;
        let s = tau_tr.map(|t| t + p);
        let r = self.deviatoric_return(s, p, time_step);
        let tau = match r.region {
            MuIRegion::Apex => [T::cst(0.0); 3],
            _ => r.s.map(|si| si - p),
        };
        (tau, r.region, r.inertial_number)
    }

    /// Return region taken by trial principal elastic log strains `eps_tr` in a step `Δt`.
    pub fn region(&self, eps_tr: [f64; 3], time_step: f64) -> MuIRegion {
        self.principal_return(eps_tr, time_step).1
    }
}

impl PrincipalModel for MuI {
    fn internal_len(&self) -> usize {
        MU_I_OUTPUT.len()
    }

    fn initialise_internal(&self, internal: &mut [f64]) {
        internal[..MU_I_OUTPUT.len()].fill(0.0);
    }

    fn principal_update(
        &self,
        eps_tr: [f64; 3],
        time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<PrincipalResponse, LawError> {
        let eps: [Dual<3>; 3] = [Dual::seed(eps_tr[0], 0), Dual::seed(eps_tr[1], 1), Dual::seed(eps_tr[2], 2)];
        let (t, region, inertial_number) = self.principal_return(eps, time_step);
        let tau = t.map(|x| x.v);
        // Isochoric flow keeps the trial volume exactly (`ε_e = tr ε_tr/3 + s/2G`); the apex
        // releases all of it.
        let eps_e = match region {
            MuIRegion::Elastic => eps_tr,
            MuIRegion::Flowing => elastic_strain_up(eps_tr, tau, self.mu, None),
            MuIRegion::Apex => [0.0; 3],
        };
        accumulate_plastic_strain(committed, trial, eps_tr, eps_e, region != MuIRegion::Elastic);
        trial[3] = inertial_number;
        Ok(PrincipalResponse { tau, eps_e, dtau_deps: Matrix3::from_fn(|a, b| t[a].d[b]) })
    }

    fn elastic_strain(&self, tau: [f64; 3]) -> Result<[f64; 3], LawError> {
        Ok(hencky_strain(self.lambda, self.mu, tau))
    }
}

impl MuI {
    /// The u–p return (module doc) at trial principal log strains `eps` and pressure
    /// `pressure` (mean Kirchhoff stress, tension positive).
    fn mixed_return<T: Real>(&self, eps: [T; 3], pressure: T, time_step: f64) -> ([T; 3], MuIRegion, f64) {
        let s = deviator(eps).map(|e| e * (2.0 * self.mu));
        let r = self.deviatoric_return(s, -pressure, time_step);
        (r.s.map(|si| si + pressure), r.region, r.inertial_number)
    }
}

impl MixedPrincipalModel for MuI {
    fn lame(&self) -> (f64, f64) {
        (self.lambda, self.mu)
    }

    fn mixed_principal_update(
        &self,
        eps_tr: [f64; 3],
        pressure: f64,
        time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<MixedPrincipalResponse, LawError> {
        let mut inertial_number = 0.0;
        let response = dual_mixed_response(eps_tr, pressure, self.mu, committed, trial, |eps, p| {
            let (t, region, i) = self.mixed_return(eps, p, time_step);
            inertial_number = i;
            let apex_cap = (region == MuIRegion::Apex).then_some(0.0);
            Ok((t, MixedReturn { yielded: region != MuIRegion::Elastic, apex_cap }))
        })?;
        trial[3] = inertial_number;
        Ok(response)
    }
}

multiplicative::impl_principal_law!(impl[] MuI, name: "mu_i", outputs: &MU_I_OUTPUT, lame: |law| (law.lambda, law.mu),
    mixed: |law| Ok(law));

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiplicative::CP_INV_LEN;
    use crate::tensor::{finite_difference_tangent, tangent_relative_error};
    use crate::{ConstitutiveLaw, Kinematics, TangentRequest};

    /// Jop, Forterre & Pouliquen (2006)'s glass beads: μ_s = tan 20.9°, μ₂ = tan 32.76°,
    /// I₀ = 0.279, d = 0.5 mm, ρ_s = 2450 kg/m³; Young's modulus `e`, ν = 0.3.
    fn glass_beads(e: f64) -> MuI {
        MuI::new(1500.0, e, 0.3, 20.9f64.to_radians().tan(), 32.76f64.to_radians().tan(), 0.279, 0.5e-3, 2450.0)
    }

    fn kinematics(f: Matrix3<f64>, time_step: f64) -> Kinematics {
        Kinematics { time_step, ..Kinematics::at(f) }
    }

    /// The Kirchhoff stress `τ = P Fᵀ` and its `(τ̄, p)`: `τ̄ = ‖dev τ‖/√2`, `p = −tr τ/3`.
    fn shear_and_pressure(law: &MuI, kin: &Kinematics, committed: &[f64], trial: &mut [f64]) -> (f64, f64) {
        let r = law.stress_response(kin, committed, trial).unwrap();
        let tau = r.first_piola * kin.deformation_gradient.transpose();
        let p = -tau.trace() / 3.0;
        ((tau + Matrix3::identity() * p).norm() / 2f64.sqrt(), p)
    }

    /// A trial state that flows to the inertial number `target` at the pressure `p` (Pa): the
    /// trial shear stress `τ̄_tr = μ(I) p + G Δγ` with `Δγ = 2e-4` (a 45° deviator direction
    /// off the axes) and `Δt = Δγ t_g/I`; returns the principal trial strains and `Δt`.
    fn flowing_trial(law: &MuI, target: f64, p: f64) -> ([f64; 3], f64) {
        let dgamma = 2e-4;
        let tau_bar = law.friction(target) * p + law.mu * dgamma;
        let n = [1.0, -0.3, -0.7];
        let norm = n.iter().map(|v| v * v).sum::<f64>().sqrt();
        let tau = n.map(|v| v / norm * tau_bar * 2f64.sqrt() - p);
        let dt = dgamma / law.shear_rate(target, p);
        (hencky_strain(law.lambda, law.mu, tau), dt)
    }

    /// Consistent tangent against central differences of the full update: elastic, flowing at
    /// I ≈ 0.01, 0.1, 1, a static flowing step; the reported `I` against the target.
    #[test]
    fn tangent_elastic_flowing_and_static() {
        let law = glass_beads(1e7);
        let rot = nalgebra::Rotation3::from_euler_angles(0.7, -0.2, 0.4).into_inner();
        let stretch = |eps: [f64; 3]| rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
        let mut cases = vec![(
            "elastic",
            hencky_strain(law.lambda, law.mu, [-2000.0, -2400.0, -2600.0]),
            1e-3,
            MuIRegion::Elastic,
            None,
        )];
        for target in [0.01, 0.1, 1.0] {
            let (eps, dt) = flowing_trial(&law, target, 2450.0);
            cases.push(("flowing", eps, dt, MuIRegion::Flowing, Some(target)));
        }
        let (eps, _) = flowing_trial(&law, 0.1, 2450.0);
        cases.push(("static (Δt = 0)", eps, 0.0, MuIRegion::Flowing, Some(0.0)));
        for (label, eps, dt, region, target) in cases {
            assert_eq!(law.region(eps, dt), region, "{label}");
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let kin = kinematics(stretch(eps), dt);
            let err = tangent_relative_error(&law, &kin, &state).unwrap();
            let mut trial = state.clone();
            law.stress_response(&kin, &state, &mut trial).unwrap();
            let inertial_number = trial[CP_INV_LEN + 3];
            println!("mu_i {label}: I = {inertial_number:.6e} (target {target:?}), tangent error vs FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6, "{label}: {err:e}");
            if let Some(target) = target {
                assert!((inertial_number - target).abs() <= 1e-9 * target, "{label}: I = {inertial_number}");
            }
        }
    }

    /// In tension the point is disconnected: `P = 0` and `A = 0`, as the central differences
    /// of the stress (which vanish identically there).
    #[test]
    fn apex_is_stress_free() {
        let law = glass_beads(1e7);
        let rot = nalgebra::Rotation3::from_euler_angles(0.7, -0.2, 0.4).into_inner();
        let eps = hencky_strain(law.lambda, law.mu, [300.0, -100.0, 50.0]);
        assert_eq!(law.region(eps, 1e-4), MuIRegion::Apex);
        let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
        let kin = kinematics(f, 1e-4);
        let mut state = vec![0.0; law.state_len()];
        law.initialise_state(&mut state);
        let mut trial = state.clone();
        let r = law.stress_response(&kin, &state, &mut trial).unwrap();
        let fd = finite_difference_tangent(&f, 1e-6, |g| {
            let mut t = state.clone();
            law.stress_response(
                &Kinematics { deformation_gradient: *g, tangent: TangentRequest::None, ..kin },
                &state,
                &mut t,
            )
            .unwrap()
            .first_piola
        });
        println!(
            "mu_i apex: |P| = {:.1e} Pa, |A| = {:.1e} Pa, |A_FD| = {:.1e} Pa (reference 0), volumetric plastic strain {:.3e}",
            r.first_piola.amax(),
            r.tangent.amax(),
            fd.amax(),
            trial[CP_INV_LEN + 1]
        );
        assert!(r.first_piola.amax() == 0.0 && r.tangent.amax() == 0.0 && fd.amax() == 0.0);
        assert!((trial[CP_INV_LEN + 1] - eps.iter().sum::<f64>()).abs() < 1e-15);
    }

    /// u–p form: tangents `A` and `∂P/∂p` against central differences, elastic, flowing at
    /// I ≈ 0.1 and at the apex.
    #[test]
    fn mixed_tangent() {
        let law = glass_beads(1e7);
        let rot = nalgebra::Rotation3::from_euler_angles(0.7, -0.2, 0.4).into_inner();
        let (eps_flow, dt) = flowing_trial(&law, 0.1, 2450.0);
        let dev = |e: [f64; 3]| deviator(e).map(|x| x - 1e-4);
        for (label, eps, pressure, region) in [
            (
                "elastic",
                dev(hencky_strain(law.lambda, law.mu, [-2000.0, -2400.0, -2600.0])),
                -2450.0,
                MuIRegion::Elastic,
            ),
            ("flowing", dev(eps_flow), -2450.0, MuIRegion::Flowing),
            ("apex", dev(eps_flow), 500.0, MuIRegion::Apex),
        ] {
            assert_eq!(law.mixed_return(eps, pressure, dt).1, region, "{label}");
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let (ea, ep) =
                crate::mixed::mixed_tangent_relative_error(&law, &kinematics(f, dt), pressure, &state).unwrap();
            println!("mu_i u–p {label}: A error {ea:.2e}, ∂P/∂p error {ep:.2e} (tolerance 1e-6)");
            assert!(ea < 1e-6 && ep < 1e-6, "{label}");
        }
    }

    /// Steady simple shear at constant pressure, `F = J^{1/3} (1 + γ e_x ⊗ e_y)`: the
    /// isochoric flow keeps `p = −K ln J`, and after the elastic transient the stress ratio
    /// `τ̄/p` is the closed-form `μ(I)` at the imposed `I = γ̇ d/√(p/ρ_s)` (and at the `I` the
    /// law reports).
    #[test]
    fn steady_simple_shear_follows_mu_of_i() {
        let law = glass_beads(1e7);
        let k = law.lambda + 2.0 * law.mu / 3.0;
        let p = 2450.0;
        let j = (-p / k).exp();
        let (steps, dgamma) = (400, 1e-3);
        for target in [0.01, 0.1, 1.0] {
            let dt = dgamma / law.shear_rate(target, p);
            let mut committed = vec![0.0; law.state_len()];
            law.initialise_state(&mut committed);
            let mut trial = committed.clone();
            let mut f_n = Matrix3::identity() * j.cbrt();
            let (mut ratio, mut drift) = (0.0, 0.0_f64);
            for n in 1..=steps {
                let mut f = Matrix3::identity();
                f[(0, 1)] = dgamma * n as f64;
                let f = f * j.cbrt();
                let kin = Kinematics { previous_deformation_gradient: f_n, ..kinematics(f, dt) };
                let (tau_bar, p_n) = shear_and_pressure(&law, &kin, &committed, &mut trial);
                drift = drift.max((p_n - p).abs() / p);
                ratio = tau_bar / p_n;
                committed.copy_from_slice(&trial);
                f_n = f;
            }
            let reported = committed[CP_INV_LEN + 3];
            let closed = law.friction(target);
            println!(
                "mu_i steady simple shear at I = {target}: p drift {drift:.1e}, τ̄/p = {ratio:.9}, μ(I) = {closed:.9} (rel. {:.1e}, tolerance 1e-6); reported I = {reported:.9} (rel. {:.1e}), μ(I_reported) rel. {:.1e}",
                (ratio - closed) / closed,
                (reported - target) / target,
                (ratio - law.friction(reported)) / closed
            );
            assert!(drift < 1e-8, "p drifted by {drift:e} (round-off of the frame only)");
            assert!(((ratio - closed) / closed).abs() < 1e-6);
            assert!(((ratio - law.friction(reported)) / closed).abs() < 1e-10);
        }
    }

    /// A static step (Δt = 0) returns to the quasi-static friction μ_s, with I = 0.
    #[test]
    fn static_step_uses_static_friction() {
        let law = glass_beads(1e7);
        let (eps, _) = flowing_trial(&law, 1.0, 2450.0);
        let f = Matrix3::from_diagonal(&eps.map(f64::exp).into());
        let mut state = vec![0.0; law.state_len()];
        law.initialise_state(&mut state);
        let mut trial = state.clone();
        let (tau_bar, p) = shear_and_pressure(&law, &Kinematics::at(f), &state, &mut trial);
        println!(
            "mu_i static step: τ̄/p = {:.12}, μ_s = {:.12}, I = {}",
            tau_bar / p,
            law.static_friction,
            trial[CP_INV_LEN + 3]
        );
        assert!((tau_bar / p - law.static_friction).abs() < 1e-12 * law.static_friction);
        assert_eq!(trial[CP_INV_LEN + 3], 0.0);
        assert_eq!(trial[CP_INV_LEN + 2], 1.0);
    }
}
