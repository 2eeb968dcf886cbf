//! Multiplicative finite-strain plasticity on Hencky elasticity: the frame shared by every
//! elasto-plastic law of this crate (Mohr–Coulomb, its softening variant, Drucker–Prager,
//! Modified Cam Clay) and by the Hencky hyperelastic law.
//!
//! Simo (1992), "Algorithms for static and dynamic multiplicative plasticity that preserve
//! the classical return mapping schemes of the infinitesimal theory", CMAME 99:61–112,
//! doi:10.1016/0045-7825(92)90123-2:
//!
//! 1. History holds the inverse plastic right Cauchy–Green tensor `Cp⁻¹` (6 components).
//! 2. Trial elastic left Cauchy–Green tensor `b_e,tr = F Cp⁻¹ Fᵀ = Σ_a x_a n_a ⊗ n_a`.
//! 3. Trial principal elastic logarithmic strains `ε_tr,a = ½ ln x_a`.
//! 4. A **principal-space return** ([`PrincipalModel`]) gives the principal Kirchhoff
//!    stresses `τ_a`, the updated elastic log strains `ε_e,a` and `∂τ_a/∂ε_tr,b`
//!    (exponential map: the plastic flow is integrated as `ε_e = ε_tr − Δε_p`). It also
//!    receives the step's `Δt`, which a rate-dependent flow rule reads (the μ(I) law)
//!    and the rate-independent ones ignore.
//! 5. `τ = Σ_a τ_a n_a ⊗ n_a`, `b_e = Σ_a exp(2 ε_e,a) n_a ⊗ n_a`,
//!    `Cp⁻¹_{n+1} = F⁻¹ b_e F⁻ᵀ`.
//! 6. Tangent: `τ(b_e,tr)` is an isotropic tensor function with eigenvalue functions
//!    `τ_a(x)`, `∂τ_a/∂x_b = (∂τ_a/∂ε_tr,b) / (2 x_b)`; its derivative is taken with
//!    [`crate::spectral`] (robust at repeated eigenvalues) and chained with
//!    `∂b_e,tr/∂F`: `db = dF G ᵀ + G dFᵀ`, `G = F Cp⁻¹`. Finally
//!    [`crate::tensor::piola_from_kirchhoff`] gives `P = τ F⁻ᵀ` and `A = ∂P/∂F`.
//!
//! The yield functions are evaluated on the Kirchhoff stress τ (as in Simo 1992 and
//! Borja & Tamagnini 1998); the Cauchy stress is `σ = τ / J`.

use nalgebra::Matrix3;

use crate::spectral::{isotropic_differential, isotropic_theta, Spectral};
use crate::tensor::piola_from_kirchhoff;
use crate::{idx, Kinematics, LawError, StressResponse, Tangent};

/// Number of history slots holding `Cp⁻¹` (xx, yy, zz, xy, yz, xz) at the start of the state.
pub const CP_INV_LEN: usize = 6;

/// Result of a principal-space return.
#[derive(Debug, Clone, Copy)]
pub struct PrincipalResponse {
    /// Principal Kirchhoff stresses `τ_a` in Pa (tension positive).
    pub tau: [f64; 3],
    /// Updated principal elastic logarithmic strains `ε_e,a`.
    pub eps_e: [f64; 3],
    /// Algorithmic tangent `∂τ_a/∂ε_tr,b` in Pa.
    pub dtau_deps: Matrix3<f64>,
}

/// An isotropic elasto-plastic model written in principal Kirchhoff stresses and principal
/// elastic logarithmic strains. Its internal variables follow the `Cp⁻¹` slots.
pub trait PrincipalModel: Send + Sync {
    /// Number of internal variables after the [`CP_INV_LEN`] slots of `Cp⁻¹`.
    fn internal_len(&self) -> usize;

    /// Writes the virgin internal variables.
    fn initialise_internal(&self, internal: &mut [f64]);

    /// The return mapping: from the trial principal elastic log strains (unsorted), the time
    /// step `time_step` (Δt in s, 0 for a static step; only rate-dependent models read it)
    /// and the committed internal variables, writes the trial internal variables.
    fn principal_update(
        &self,
        eps_tr: [f64; 3],
        time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<PrincipalResponse, LawError>;

    /// Inverse of the elastic law: the principal elastic log strains at principal
    /// Kirchhoff stresses `tau` (used to start from an initial stress).
    fn elastic_strain(&self, tau: [f64; 3]) -> Result<[f64; 3], LawError>;
}

/// Reads a symmetric tensor stored as (xx, yy, zz, xy, yz, xz).
pub fn read_sym(s: &[f64]) -> Matrix3<f64> {
    Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2])
}

/// Writes a symmetric tensor as (xx, yy, zz, xy, yz, xz).
pub fn write_sym(m: &Matrix3<f64>, s: &mut [f64]) {
    s[0] = m[(0, 0)];
    s[1] = m[(1, 1)];
    s[2] = m[(2, 2)];
    s[3] = 0.5 * (m[(0, 1)] + m[(1, 0)]);
    s[4] = 0.5 * (m[(1, 2)] + m[(2, 1)]);
    s[5] = 0.5 * (m[(0, 2)] + m[(2, 0)]);
}

/// Kirchhoff stress and the updated elastic `b_e`.
#[derive(Debug, Clone)]
pub struct KirchhoffUpdate {
    /// Kirchhoff stress τ in Pa.
    pub tau: Matrix3<f64>,
    /// Updated elastic left Cauchy–Green tensor `b_e`.
    pub b_e: Matrix3<f64>,
    /// The principal directions `n_a` of the trial `b_e,tr` (shared by τ and `b_e`).
    pub spectral: Spectral,
}

/// Steps 2–6 of the module doc for a given `F` and `Cp⁻¹` with the principal return
/// `principal_return(ε_tr)`. Writes the columns `components` of `dτ/dF` (`∂τ_ij/∂F_kL` at
/// `(3i+j, 3k+L)`, all rows of each) into `dtau_df`; other entries are left as they were.
#[inline(always)]
pub fn kirchhoff_update(
    F: &Matrix3<f64>,
    cp_inv: &Matrix3<f64>,
    components: &[usize],
    dtau_df: &mut Tangent,
    principal_return: impl FnOnce([f64; 3]) -> Result<PrincipalResponse, LawError>,
) -> Result<KirchhoffUpdate, LawError> {
    let G = F * cp_inv;
    let b_tr = G * F.transpose();
    let b_tr = 0.5 * (b_tr + b_tr.transpose());
    let det_f = F.determinant();
    let spec = Spectral::of(&b_tr).ok_or(LawError::InvertedDeformation { det_f })?;
    let x = spec.values;
    if x.iter().any(|&v| v.is_nan() || v <= 0.0) {
        return Err(LawError::InvertedDeformation { det_f });
    }
    let eps_tr = x.map(|v| 0.5 * v.ln());
    let r = principal_return(eps_tr)?;
    if !components.is_empty() {
        let dydx = Matrix3::from_fn(|a, c| r.dtau_deps[(a, c)] / (2.0 * x[c]));
        let theta = isotropic_theta(x, r.tau, &dydx);
        let q = &spec.vectors;
        // h_L = Qᵀ g_L, g_L the L-th column of G.
        let h = q.transpose() * G;
        if components == &crate::law::IN_PLANE[..] && is_in_plane(q) && is_in_plane(&G) {
            in_plane_tangent(q, &h, &dydx, &theta, dtau_df);
        } else {
            general_tangent(q, &h, &dydx, &theta, components, dtau_df);
        }
    }
    Ok(KirchhoffUpdate {
        tau: spec.compose(r.tau),
        b_e: spec.compose(r.eps_e.map(|e| (2.0 * e).exp())),
        spectral: spec,
    })
}

/// Whether `m` has no `xz`, `yz`, `zx`, `zy` components (exactly: as plane strain leaves them).
#[inline(always)]
fn is_in_plane(m: &Matrix3<f64>) -> bool {
    m[(0, 2)] == 0.0 && m[(1, 2)] == 0.0 && m[(2, 0)] == 0.0 && m[(2, 1)] == 0.0
}

/// Step 6 for the columns `components` of `dτ/dF`, all nine rows of each: for column
/// `(k, L)`, `d b̃ = q_k h_Lᵀ + h_L q_kᵀ` in the eigenbasis, the isotropic differential there,
/// rotated back with `Q`.
#[inline(always)]
fn general_tangent(
    q: &Matrix3<f64>,
    h: &Matrix3<f64>,
    dydx: &Matrix3<f64>,
    theta: &Matrix3<f64>,
    components: &[usize],
    dtau_df: &mut Tangent,
) {
    for &col in components {
        let (k, l) = (col / 3, col % 3);
        // d b̃ = Qᵀ (e_k g_Lᵀ + g_L e_kᵀ) Q = q_k h_Lᵀ + h_L q_kᵀ, q_k = row k of Q.
        let db = Matrix3::from_fn(|a, b| q[(k, a)] * h[(b, l)] + h[(a, l)] * q[(k, b)]);
        let dtau = q * isotropic_differential(dydx, theta, &db) * q.transpose();
        for i in 0..3 {
            for j in 0..3 {
                dtau_df[(idx(i, j), col)] = dtau[(i, j)];
            }
        }
    }
}

/// [`general_tangent`] for the in-plane columns ([`crate::law::IN_PLANE`]) when `Q` and `G`
/// are block diagonal (plane strain): then `d b̃` has only its in-plane block, so the
/// differential's in-plane block is rotated with the 2×2 block of `Q`, `dτ_zz =
/// Σ_c ∂y_z/∂x_c d b̃_cc`, and the out-of-plane shear rows are zero — the same nine rows at
/// a quarter of the products, bit for bit the same.
#[inline(always)]
fn in_plane_tangent(
    q: &Matrix3<f64>,
    h: &Matrix3<f64>,
    dydx: &Matrix3<f64>,
    theta: &Matrix3<f64>,
    dtau_df: &mut Tangent,
) {
    let (c, s) = (q[(0, 0)], q[(1, 0)]);
    let (q01, q11) = (q[(0, 1)], q[(1, 1)]);
    for &col in &crate::law::IN_PLANE {
        let (k, l) = (col / 3, col % 3);
        let (qk0, qk1) = (q[(k, 0)], q[(k, 1)]);
        let (h0, h1) = (h[(0, l)], h[(1, l)]);
        // d b̃ in the eigenbasis: diagonal (d00, d11), shear d01; d22 = 0
        let d00 = qk0 * h0 + h0 * qk0;
        let d11 = qk1 * h1 + h1 * qk1;
        let d01 = qk0 * h1 + h0 * qk1;
        let y00 = dydx[(0, 0)] * d00 + dydx[(0, 1)] * d11;
        let y11 = dydx[(1, 0)] * d00 + dydx[(1, 1)] * d11;
        let y22 = dydx[(2, 0)] * d00 + dydx[(2, 1)] * d11;
        // θ_01 and θ_10 agree only to rounding where the pair coalesces (their limit forms
        // sum in different orders): each where the general product reads it
        let (y01, y10) = (theta[(0, 1)] * d01, theta[(1, 0)] * d01);
        // dτ = (Q dỸ) Qᵀ on the in-plane block, in the general product's order of operations
        // (its other terms are exact zeros), so that both paths agree bit for bit
        let (p00, p01) = (c * y00 + q01 * y10, c * y01 + q01 * y11);
        let (p10, p11) = (s * y00 + q11 * y10, s * y01 + q11 * y11);
        let (t00, t01) = (p00 * c + p01 * q01, p00 * s + p01 * q11);
        let (t10, t11) = (p10 * c + p11 * q01, p10 * s + p11 * q11);
        let column = [t00, t01, 0.0, t10, t11, 0.0, 0.0, 0.0, y22];
        for (row, v) in column.into_iter().enumerate() {
            dtau_df[(row, col)] = v;
        }
    }
}

/// Inverse of `F` with the inversion check used by every law.
pub fn checked_inverse(F: &Matrix3<f64>) -> Result<Matrix3<f64>, LawError> {
    let det_f = F.determinant();
    if !det_f.is_finite() || det_f <= 0.0 {
        return Err(LawError::InvertedDeformation { det_f });
    }
    F.try_inverse().ok_or(LawError::InvertedDeformation { det_f })
}

/// Full update of a [`PrincipalModel`] with history layout `[Cp⁻¹ (6) | internal]`.
pub fn update<M: PrincipalModel + ?Sized>(
    model: &M,
    kinematics: &Kinematics,
    committed: &[f64],
    trial: &mut [f64],
    response: &mut StressResponse,
) -> Result<(), LawError> {
    let F = &kinematics.deformation_gradient;
    let f_inv = checked_inverse(F)?;
    let cp_inv = read_sym(&committed[..CP_INV_LEN]);
    let (trial_cp, trial_internal) = trial.split_at_mut(CP_INV_LEN);
    let components = kinematics.tangent.components();
    let ku = kirchhoff_update(F, &cp_inv, components, &mut response.tangent, |eps_tr| {
        model.principal_update(eps_tr, kinematics.time_step, &committed[CP_INV_LEN..], trial_internal)
    })?;
    write_sym(&(f_inv * ku.b_e * f_inv.transpose()), trial_cp);
    response.first_piola = piola_from_kirchhoff(&f_inv, &ku.tau, &mut response.tangent, components);
    Ok(())
}

/// Virgin history: `Cp⁻¹ = I` and the model's virgin internal variables.
pub fn initialise<M: PrincipalModel + ?Sized>(model: &M, state: &mut [f64]) {
    write_sym(&Matrix3::identity(), &mut state[..CP_INV_LEN]);
    model.initialise_internal(&mut state[CP_INV_LEN..]);
}

/// History of a material point at rest (`F = I`) under the Cauchy stress `stress`
/// (= Kirchhoff stress at `J = 1`): the elastic strain carrying the stress is stored as
/// `Cp⁻¹ = b_e = Σ_a exp(2 ε_e,a) n_a ⊗ n_a`. Fails if the stress is not symmetric or
/// lies outside the elastic domain of the virgin internal variables.
pub fn initialise_at_stress<M: PrincipalModel + ?Sized>(
    model: &M,
    stress: &Matrix3<f64>,
    state: &mut [f64],
) -> Result<(), LawError> {
    initialise(model, state);
    let scale = stress.amax().max(1.0);
    if (stress - stress.transpose()).amax() > 1e-12 * scale {
        return Err(LawError::InitialStress { problem: "the initial stress must be symmetric".into() });
    }
    let spec = Spectral::of(stress)
        .ok_or_else(|| LawError::InitialStress { problem: "the initial stress is not finite".into() })?;
    let eps_e = model.elastic_strain(spec.values)?;
    // Admissibility: the state must be elastic at the virgin internal variables, at rest
    // (a static step, Δt = 0).
    let committed = state[CP_INV_LEN..].to_vec();
    let mut scratch = committed.clone();
    let r = model.principal_update(eps_e, 0.0, &committed, &mut scratch)?;
    let mismatch = (0..3).map(|a| (r.tau[a] - spec.values[a]).abs()).fold(0.0, f64::max);
    if mismatch > 1e-8 * scale {
        return Err(LawError::InitialStress { problem: "the initial stress lies outside the yield surface".into() });
    }
    write_sym(&spec.compose(eps_e.map(|e| (2.0 * e).exp())), &mut state[..CP_INV_LEN]);
    Ok(())
}

/// Names of the internal variables shared by the soil laws, in their slot order.
pub const PLASTIC_OUTPUT: [&str; 3] =
    ["accumulated_plastic_deviatoric_strain", "accumulated_plastic_volumetric_strain", "yield_flag"];

/// Updates the shared internal variables `[ε̄_p^d, ε_p^v, yield flag]` from the plastic
/// log-strain increment `Δε_p = ε_tr − ε_e` (principal):
/// `Δε̄_p^d = √(2/3) ‖dev Δε_p‖` (accumulated, ≥ 0), `Δε_p^v = tr Δε_p` (signed, dilation
/// positive), flag 1 when the step yielded.
pub fn accumulate_plastic_strain(
    committed: &[f64],
    trial: &mut [f64],
    eps_tr: [f64; 3],
    eps_e: [f64; 3],
    plastic: bool,
) {
    let d = [eps_tr[0] - eps_e[0], eps_tr[1] - eps_e[1], eps_tr[2] - eps_e[2]];
    let vol = d[0] + d[1] + d[2];
    let dev = (2.0 / 3.0 * d.iter().map(|v| (v - vol / 3.0).powi(2)).sum::<f64>()).sqrt();
    trial[0] = committed[0] + if plastic { dev } else { 0.0 };
    trial[1] = committed[1] + if plastic { vol } else { 0.0 };
    trial[2] = if plastic { 1.0 } else { 0.0 };
}

/// Principal Kirchhoff stress of isotropic linear elasticity in log strains (Hencky):
/// `τ_a = λ Σ_b ε_b + 2 μ ε_a`.
pub fn hencky_stress<T: crate::dual::Real>(lambda: f64, mu: f64, eps: [T; 3]) -> [T; 3] {
    let tr = (eps[0] + eps[1] + eps[2]) * lambda;
    eps.map(|e| tr + e * (2.0 * mu))
}

/// Inverse of [`hencky_stress`]: `ε_a = (τ_a − λ/(3λ+2μ) Σ_b τ_b) / (2μ)`.
pub fn hencky_strain<T: crate::dual::Real>(lambda: f64, mu: f64, tau: [T; 3]) -> [T; 3] {
    let tr = (tau[0] + tau[1] + tau[2]) * (lambda / (3.0 * lambda + 2.0 * mu));
    tau.map(|t| (t - tr) / (2.0 * mu))
}

/// The Hencky elastic matrix `∂τ_a/∂ε_b = λ + 2μ δ_ab`.
pub fn hencky_matrix(lambda: f64, mu: f64) -> Matrix3<f64> {
    Matrix3::from_element(lambda) + Matrix3::identity() * (2.0 * mu)
}

/// Implements [`crate::ConstitutiveLaw`] for a [`PrincipalModel`]: every elasto-plastic law
/// of this crate is the same Simo (1992) frame around its own principal-space return, so the
/// trait methods only delegate. `name`, `outputs` (the state-variable names, one per internal
/// variable) and `lame` (`|law| (λ, μ)` at the reference state) are what differs.
macro_rules! impl_principal_law {
    (impl[$($generics:tt)*] $ty:ty, name: $name:expr, outputs: $outputs:expr, lame: |$law:ident| $lame:expr) => {
        $crate::multiplicative::impl_principal_law!(impl[$($generics)*] $ty, name: $name, outputs: $outputs, lame: |$law| $lame,
            mixed: |law| Err(format!("law `{}` has no volumetric–deviatoric (u–p) form", $crate::ConstitutiveLaw::name(law))));
    };
    (impl[$($generics:tt)*] $ty:ty, name: $name:expr, outputs: $outputs:expr, lame: |$law:ident| $lame:expr, mixed: |$mlaw:ident| $mixed:expr) => {
        impl<$($generics)*> $crate::ConstitutiveLaw for $ty {
            fn name(&self) -> &'static str {
                $name
            }

            fn density(&self) -> f64 {
                self.density
            }

            fn state_len(&self) -> usize {
                $crate::multiplicative::CP_INV_LEN + $crate::multiplicative::PrincipalModel::internal_len(self)
            }

            fn initialise_state(&self, state: &mut [f64]) {
                $crate::multiplicative::initialise(self, state);
            }

            fn initialise_state_at_stress(
                &self,
                stress: &nalgebra::Matrix3<f64>,
                state: &mut [f64],
            ) -> Result<(), $crate::LawError> {
                $crate::multiplicative::initialise_at_stress(self, stress, state)
            }

            fn state_variables(&self) -> &'static [&'static str] {
                $outputs
            }

            fn state_output(&self, state: &[f64], out: &mut [f64]) {
                let (start, n) = ($crate::multiplicative::CP_INV_LEN, $outputs.len());
                out[..n].copy_from_slice(&state[start..start + n]);
            }

            fn update(
                &self,
                kinematics: &$crate::Kinematics,
                committed: &[f64],
                trial: &mut [f64],
                response: &mut $crate::StressResponse,
            ) -> Result<(), $crate::LawError> {
                $crate::multiplicative::update(self, kinematics, committed, trial, response)
            }

            fn elastic_lame(&self) -> (f64, f64) {
                let $law = self;
                $lame
            }

            fn mixed(&self) -> Result<&dyn $crate::mixed::MixedLaw, String> {
                let $mlaw = self;
                $mixed
            }
        }
    };
}
pub(crate) use impl_principal_law;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mohr_coulomb::MohrCoulomb;

    /// The plane-strain shortcut of step 6 ([`in_plane_tangent`]) against the general loop
    /// ([`general_tangent`]) on a Mohr–Coulomb state that yields at an in-plane `F` and a
    /// plastic `Cp⁻¹` (distinct eigenvalues and a coalesced pair): the nine rows of the four
    /// in-plane columns agree bit for bit (results do not move with the shortcut).
    #[test]
    fn in_plane_tangent_equals_the_general_loop() {
        let law = MohrCoulomb::new(2650.0, 8.4e5, 0.3, 19.8f64.to_radians(), 0.0, 0.0);
        let cases = [
            (
                Matrix3::new(1.02, 0.15, 0.0, -0.04, 0.93, 0.0, 0.0, 0.0, 1.0),
                Matrix3::new(1.01, 0.02, 0.0, 0.02, 0.98, 0.0, 0.0, 0.0, 1.0),
            ),
            (Matrix3::new(0.97, 0.0, 0.0, 0.0, 0.97, 0.0, 0.0, 0.0, 1.0), Matrix3::identity()),
            (
                Matrix3::new(1.3, -0.4, 0.0, 0.2, 0.7, 0.0, 0.0, 0.0, 1.0),
                Matrix3::new(0.9, -0.05, 0.0, -0.05, 1.1, 0.0, 0.0, 0.0, 1.02),
            ),
        ];
        for (F, cp_inv) in cases {
            let b_tr = F * cp_inv * F.transpose();
            let spec = Spectral::of(&(0.5 * (b_tr + b_tr.transpose()))).expect("finite");
            let x = spec.values;
            let eps_tr = x.map(|v| 0.5 * v.ln());
            let mut internal = vec![0.0; law.internal_len()];
            law.initialise_internal(&mut internal);
            let mut trial = internal.clone();
            let r = law.principal_update(eps_tr, 0.0, &internal, &mut trial).expect("return");
            let dydx = Matrix3::from_fn(|a, c| r.dtau_deps[(a, c)] / (2.0 * x[c]));
            let theta = isotropic_theta(x, r.tau, &dydx);
            let q = &spec.vectors;
            let h = q.transpose() * (F * cp_inv);
            assert!(is_in_plane(q) && is_in_plane(&(F * cp_inv)));
            let (mut fast, mut general) = (Tangent::zeros(), Tangent::zeros());
            in_plane_tangent(q, &h, &dydx, &theta, &mut fast);
            general_tangent(q, &h, &dydx, &theta, &crate::law::IN_PLANE, &mut general);
            let err = (fast - general).amax() / general.amax();
            println!("F = {F:?}: in-plane vs general tangent, relative difference {err:.1e} (yielded: {})", trial[2]);
            assert!(fast == general, "relative difference {err}");
        }
    }
}
