//! Laws in volumetric–deviatoric form, for the mixed displacement–pressure (u–p)
//! formulation of nearly and exactly incompressible materials (undrained soil, rubber).
//!
//! In the u–p formulation the mean stress is an unknown field of its own (Iaconeta, Larese,
//! Rossi & Oñate 2019, "A stabilized mixed implicit Material Point Method for non-linear
//! incompressible solid mechanics", Comput. Mech. 63:1243–1260,
//! doi:10.1007/s00466-018-1647-9). Here that field `p` is the **mean Kirchhoff stress**
//! `p = tr τ / 3` (tension positive, as every stress in Loam; the Cauchy mean stress is
//! `p / J`, and `J → 1` where the formulation matters). A law in u–p form gives, at the
//! deformation gradient `F`, the pressure `p` and its history,
//!
//! - the stress `τ = τ_dev(F, p) + p 1`, `P = τ F⁻ᵀ`, with the tangents `A = ∂P/∂F` at fixed
//!   `p` and `∂P/∂p` at fixed `F` (`τ_dev` depends on `p` only through a pressure-dependent
//!   yield surface: Mohr–Coulomb or Drucker–Prager with φ > 0);
//! - the volumetric law `p = K θ`, `θ = ln J_e`, through its bulk modulus `K` (`∞` for an
//!   exactly incompressible material): the mixed element imposes `θ − p/K = 0` weakly, where
//!   `θ` is `ln J` unless the history carries an elastic volume change from the start (a
//!   geostatic prestrain) or a committed dilation at the apex of a frictional law
//!   ([`MixedLaw::volumetric_strain`], [`elastic_strain_up`]).
//!
//! `K ln J` is the mean Kirchhoff stress of Hencky elasticity, and of every Hencky-based
//! plasticity law of this crate whose plastic flow is isochoric (`det Cp = 1`, so that
//! `J_e = J`): Tresca and Mohr–Coulomb with ψ = 0, von Mises and Drucker–Prager with ψ = 0, and
//! the μ(I) law of granular flow ([`crate::mu_i`]).
//! Their u–p return is the return of the displacement form at a fixed mean stress, which a
//! deviatoric flow keeps; beyond the apex of a frictional surface (`p ≥ c cot φ`) no
//! deviatoric stress is admissible and `τ = p 1` (a tension cut-off, continuous with the
//! cone as it shrinks to its apex). For Neo-Hookean the u–p form is the decoupled energy
//! `ψ = μ/2 (J^{-2/3} tr C − 3) + K/2 (ln J)²` (Simo, Taylor & Pister 1985,
//! doi:10.1016/0045-7825(85)90033-7), equal to the compressible law of
//! [`crate::neo_hookean`] to first order in the strain.
//!
//! The principal-space laws go through [`mixed_kirchhoff_update`]: the frame of
//! [`crate::multiplicative`] (Simo 1992) with the principal return given `p`, which also
//! returns `∂τ_a/∂p`; then `∂τ/∂p = Σ_a ∂τ_a/∂p n_a ⊗ n_a` and `∂P/∂p = ∂τ/∂p F⁻ᵀ`.

use nalgebra::Matrix3;

use crate::dual::Dual;
use crate::multiplicative::{checked_inverse, kirchhoff_update, PrincipalResponse};
use crate::tensor::piola_from_kirchhoff;
use crate::{Kinematics, LawError, StressResponse};

/// A law in volumetric–deviatoric form (see the module doc).
pub trait MixedLaw: Send + Sync {
    /// Bulk modulus `K` (Pa) of the volumetric law `p = K ln J`; `f64::INFINITY` when the
    /// material is incompressible.
    fn bulk_modulus(&self) -> f64;

    /// Elastic shear modulus μ (Pa): the scale of the pressure stabilisation.
    fn shear_modulus(&self) -> f64;

    /// The elastic volumetric strain `θ = ln J_e` of the volumetric law `p = K θ` at the total
    /// volume change `ln J`, from the committed history (`dθ/d ln J = 1`). By default
    /// `θ = ln J`. A history may carry an elastic volume change from the start (a geostatic
    /// prestrain) or a committed plastic dilation, both in `Cp⁻¹`: `θ = ln J + ½ ln det Cp⁻¹`.
    /// A frictional law's apex does not cap `θ` here: it is a return of each point at the end
    /// of the step ([`elastic_strain_up`]).
    fn volumetric_strain(&self, ln_j: f64, _committed: &[f64]) -> f64 {
        ln_j
    }

    /// Stress and tangents at `kinematics` and the pressure `pressure` (mean Kirchhoff stress,
    /// Pa): writes `P` and the requested entries of `A = ∂P/∂F` into `response` (as
    /// [`crate::ConstitutiveLaw::update`]) and `∂P/∂p` (every entry) into
    /// `pressure_tangent`, and the trial history into `trial`.
    fn update_mixed(
        &self,
        kinematics: &Kinematics,
        pressure: f64,
        committed: &[f64],
        trial: &mut [f64],
        response: &mut StressResponse,
        pressure_tangent: &mut Matrix3<f64>,
    ) -> Result<(), LawError>;
}

/// Result of a principal-space return in u–p form: the principal response at the trial
/// strains and `∂τ_a/∂p`.
pub type MixedPrincipalResponse = (PrincipalResponse, [f64; 3]);

/// The frame of [`crate::multiplicative::update`] for a principal-space law in u–p form:
/// `b_e,tr = F Cp⁻¹ Fᵀ`, the return `principal_return(ε_tr)` (which knows `p`), `τ`,
/// `P = τ F⁻ᵀ`, `A` (requested `components`) and `∂P/∂p`. Returns the updated elastic `b_e`.
pub fn mixed_kirchhoff_update(
    F: &Matrix3<f64>,
    cp_inv: &Matrix3<f64>,
    components: &[usize],
    response: &mut StressResponse,
    pressure_tangent: &mut Matrix3<f64>,
    principal_return: impl FnOnce([f64; 3]) -> Result<MixedPrincipalResponse, LawError>,
) -> Result<Matrix3<f64>, LawError> {
    let f_inv = checked_inverse(F)?;
    let mut dtau_dp = [0.0; 3];
    let ku = kirchhoff_update(F, cp_inv, components, &mut response.tangent, |eps_tr| {
        let (r, d) = principal_return(eps_tr)?;
        dtau_dp = d;
        Ok(r)
    })?;
    *pressure_tangent = ku.spectral.compose(dtau_dp) * f_inv.transpose();
    response.first_piola = piola_from_kirchhoff(&f_inv, &ku.tau, &mut response.tangent, components);
    Ok(ku.b_e)
}

/// The deviatoric part `e_a = ε_a − tr ε / 3` of principal strains (generic for the dual
/// numbers of the returns).
pub fn deviator<T: crate::dual::Real>(eps: [T; 3]) -> [T; 3] {
    let mean = (eps[0] + eps[1] + eps[2]) / 3.0;
    eps.map(|e| e - mean)
}

/// Updated principal elastic log strains of a u–p return: the volumetric part of the trial,
/// capped at `θ_apex` where the point's **pressure** has reached the apex (`apex_cap =
/// Some(θ_apex)`: the grains separate and the excess is a plastic dilation; isochoric flow
/// below it, `J_e = J`), and the deviator carrying `dev τ`:
/// `ε_e,a = vol/3 + (τ_a − tr τ/3)/(2μ)`.
///
/// The apex in u–p form is a **return at the end of the step**: within a step the volumetric
/// law `p = K θ` holds weakly and uncapped, so that a point that opens up meets a growing
/// (tensile) pressure, as an elastic point would; where the converged pressure has reached
/// the apex, the point's volume beyond `θ_apex` is released as plastic dilation, and the
/// next step starts at the apex. The tension beyond the apex that a step carries is bounded
/// by that step's volume increase (measured on the Bui collapse at h = 5 mm: 3 % of the
/// points in the middle of the collapse, up to 1.7 kPa against an overburden of 2.6 kPa;
/// 0.7 % at rest, below 0.1 kPa).
///
/// Two stricter forms were tried on the Bui collapse (φ = 19.8°, c = 0, h = 5 mm) and
/// fail. (1) Capping each point's `θ` at `θ_apex` inside the step (`p = K min(θ, θ_apex)`):
/// the volumetric law holds weakly, so a point's own `θ` scatters about `p/K`; a capped point
/// has no volumetric stiffness, and if its scatter is committed as dilation the volume
/// ratchets up step after step (volume doubled, runout 0.66 m against the experiment's
/// 0.42 m, never at rest), and if it is not (only the pressure deciding) the scatter stays
/// as a loose, stiffness-free state that only grows (44 % of the points at `θ > 0.01` under
/// compression, volume +39 %, runout 0.479 m, growing under refinement). (2) Clipping the
/// stress at the apex inside the step (`τ = p_apex 1` for `p > p_apex`), with the point's or
/// the pressure's excess committed: an opening region meets no resistance and dilates
/// (runout 0.441 m, volume +20 %, or with the pressure's excess 0.508 m, volume +33 %).
pub fn elastic_strain_up(eps_tr: [f64; 3], tau: [f64; 3], mu: f64, apex_cap: Option<f64>) -> [f64; 3] {
    let trace = eps_tr[0] + eps_tr[1] + eps_tr[2];
    let vol = apex_cap.map_or(trace, |cap| trace.min(cap)) / 3.0;
    let s = deviator(tau);
    s.map(|si| vol + si / (2.0 * mu))
}

/// Where a u–p return ended: whether it yielded, and the volumetric elastic strain cap of an
/// apex return ([`elastic_strain_up`]'s `apex_cap`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MixedReturn {
    /// Whether the step is plastic.
    pub yielded: bool,
    /// `Some(θ_apex)` for a return to the apex, `None` otherwise.
    pub apex_cap: Option<f64>,
}

/// The u–p response of a principal return written once over dual numbers: `principal_return`
/// maps the trial principal log strains and the pressure, seeded as the four derivative
/// directions, to the principal Kirchhoff stresses; the tangent `∂τ_a/∂ε_tr,b` and `∂τ_a/∂p`
/// are their derivatives, the elastic strains follow from [`elastic_strain_up`] with shear
/// modulus `mu`, and the plastic strains accumulate into `trial` (the shared part of every
/// [`MixedPrincipalModel::mixed_principal_update`]).
pub fn dual_mixed_response(
    eps_tr: [f64; 3],
    pressure: f64,
    mu: f64,
    committed: &[f64],
    trial: &mut [f64],
    principal_return: impl FnOnce([Dual<4>; 3], Dual<4>) -> Result<([Dual<4>; 3], MixedReturn), LawError>,
) -> Result<MixedPrincipalResponse, LawError> {
    let eps: [Dual<4>; 3] = [Dual::seed(eps_tr[0], 0), Dual::seed(eps_tr[1], 1), Dual::seed(eps_tr[2], 2)];
    let (t, ret) = principal_return(eps, Dual::seed(pressure, 3))?;
    let tau = t.map(|x| x.v);
    let eps_e = elastic_strain_up(eps_tr, tau, mu, ret.apex_cap);
    crate::multiplicative::accumulate_plastic_strain(committed, trial, eps_tr, eps_e, ret.yielded);
    let dtau_deps = Matrix3::from_fn(|a, b| t[a].d[b]);
    Ok((PrincipalResponse { tau, eps_e, dtau_deps }, t.map(|x| x.d[3])))
}

/// Relative errors `(‖A − A_FD‖, ‖∂P/∂p − FD‖)` (each over the magnitude of its tangent) of
/// a law in u–p form at `kinematics` and `pressure`, against central differences of its
/// stress in `F` (step 1e-6, Richardson-extrapolated as [`crate::tensor::tangent_relative_error`])
/// and in `p` (step 1e-6 of the stress scale). For the verification tests.
pub fn mixed_tangent_relative_error(
    law: &dyn MixedLaw,
    kinematics: &Kinematics,
    pressure: f64,
    committed: &[f64],
) -> Result<(f64, f64), LawError> {
    let mut trial = committed.to_vec();
    let mut r = StressResponse::default();
    let mut dp = Matrix3::zeros();
    law.update_mixed(kinematics, pressure, committed, &mut trial, &mut r, &mut dp)?;
    let mut stress = |f: &Matrix3<f64>, p: f64| -> Result<Matrix3<f64>, LawError> {
        let kin = Kinematics { deformation_gradient: *f, tangent: crate::TangentRequest::None, ..*kinematics };
        let mut s = StressResponse::default();
        let mut scratch = Matrix3::zeros();
        law.update_mixed(&kin, p, committed, &mut trial, &mut s, &mut scratch)?;
        Ok(s.first_piola)
    };
    let f = kinematics.deformation_gradient;
    let mut failure = None;
    let mut at_f = |g: &Matrix3<f64>| {
        stress(g, pressure).unwrap_or_else(|e| {
            failure = Some(e);
            Matrix3::zeros()
        })
    };
    let h = 2e-6;
    let coarse = crate::tensor::finite_difference_tangent(&f, h, &mut at_f);
    let fine = crate::tensor::finite_difference_tangent(&f, 0.5 * h, &mut at_f);
    let a_fd = (4.0 * fine - coarse) / 3.0;
    if let Some(e) = failure {
        return Err(e);
    }
    let scale = r.first_piola.amax().max(pressure.abs()).max(law.shear_modulus() * 1e-3);
    let hp = 1e-6 * scale;
    let (plus, minus) = (stress(&f, pressure + hp)?, stress(&f, pressure - hp)?);
    let dp_fd = (plus - minus) / (2.0 * hp);
    Ok(((r.tangent - a_fd).amax() / r.tangent.amax(), (dp - dp_fd).amax() / dp.amax().max(1e-300)))
}

/// A principal-space elasto-plastic model (history `[Cp⁻¹ | internal]` as in
/// [`crate::multiplicative`]) with a return in u–p form; it is a [`MixedLaw`] with Hencky
/// elasticity (`K = λ + 2μ/3`).
pub trait MixedPrincipalModel: Send + Sync {
    /// Lamé's constants `(λ, μ)` of the Hencky elasticity (Pa).
    fn lame(&self) -> (f64, f64);

    /// The return at trial principal elastic log strains `eps_tr`, pressure `pressure` and
    /// time step `time_step` (as [`crate::multiplicative::PrincipalModel::principal_update`]),
    /// from the committed internal variables, writing the trial ones.
    fn mixed_principal_update(
        &self,
        eps_tr: [f64; 3],
        pressure: f64,
        time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<MixedPrincipalResponse, LawError>;
}

impl<M: MixedPrincipalModel> MixedLaw for M {
    fn bulk_modulus(&self) -> f64 {
        let (lambda, mu) = self.lame();
        lambda + 2.0 * mu / 3.0
    }

    fn shear_modulus(&self) -> f64 {
        self.lame().1
    }

    fn volumetric_strain(&self, ln_j: f64, committed: &[f64]) -> f64 {
        principal_volumetric_strain(ln_j, committed)
    }

    fn update_mixed(
        &self,
        kinematics: &Kinematics,
        pressure: f64,
        committed: &[f64],
        trial: &mut [f64],
        response: &mut StressResponse,
        pressure_tangent: &mut Matrix3<f64>,
    ) -> Result<(), LawError> {
        update_principal_mixed(self, kinematics, pressure, committed, trial, response, pressure_tangent)
    }
}

/// [`MixedLaw::volumetric_strain`] of a history `[Cp⁻¹ | internal]`:
/// `θ = ln J + ½ ln det Cp⁻¹`.
pub fn principal_volumetric_strain(ln_j: f64, committed: &[f64]) -> f64 {
    ln_j + 0.5 * crate::multiplicative::read_sym(&committed[..crate::multiplicative::CP_INV_LEN]).determinant().ln()
}

/// [`MixedLaw::update_mixed`] of a [`MixedPrincipalModel`]: [`mixed_kirchhoff_update`] with
/// `Cp⁻¹` read from the committed history and the updated one written to the trial history.
pub fn update_principal_mixed<M: MixedPrincipalModel + ?Sized>(
    model: &M,
    kinematics: &Kinematics,
    pressure: f64,
    committed: &[f64],
    trial: &mut [f64],
    response: &mut StressResponse,
    pressure_tangent: &mut Matrix3<f64>,
) -> Result<(), LawError> {
    use crate::multiplicative::{read_sym, write_sym, CP_INV_LEN};
    let F = &kinematics.deformation_gradient;
    let f_inv = checked_inverse(F)?;
    let cp_inv = read_sym(&committed[..CP_INV_LEN]);
    let (trial_cp, trial_internal) = trial.split_at_mut(CP_INV_LEN);
    let components = kinematics.tangent.components();
    let b_e = mixed_kirchhoff_update(F, &cp_inv, components, response, pressure_tangent, |eps_tr| {
        model.mixed_principal_update(eps_tr, pressure, kinematics.time_step, &committed[CP_INV_LEN..], trial_internal)
    })?;
    write_sym(&(f_inv * b_e * f_inv.transpose()), trial_cp);
    Ok(())
}
