//! The `ConstitutiveLaw` seam.
//!
//! Index convention: a 3×3 tensor `T_iJ` is flattened row-major, component `(i, J)` at
//! position `3 i + J` (see [`crate::tensor::idx`]); the tangent `A_iJkL = ∂P_iJ/∂F_kL` is the
//! 9×9 matrix with entry `(3i+J, 3k+L)`.

use nalgebra::Matrix3;

use crate::{LawError, Tangent};

/// The kinematics handed to a law at one integration point.
#[derive(Debug, Clone, Copy)]
pub struct Kinematics {
    /// Total deformation gradient `F_{n+1}` (with `F33` from plane strain/axisymmetry).
    pub deformation_gradient: Matrix3<f64>,
    /// Committed deformation gradient `F_n` at the start of the step (rate-type laws).
    pub previous_deformation_gradient: Matrix3<f64>,
    /// Time step `Δt` in s (0 for a static load step).
    pub time_step: f64,
    /// Which entries of the consistent tangent the caller will read.
    pub tangent: TangentRequest,
}

impl Kinematics {
    /// Kinematics of a static evaluation at `F` from the undeformed state (full tangent).
    pub fn at(deformation_gradient: Matrix3<f64>) -> Self {
        Self {
            deformation_gradient,
            previous_deformation_gradient: Matrix3::identity(),
            time_step: 0.0,
            tangent: TangentRequest::Full,
        }
    }
}

/// The part of the consistent tangent `A = ∂P/∂F` a caller needs. A law may always return
/// more (the full tangent is correct for every request); entries outside the request are
/// unspecified. The finite-element kernel asks for the in-plane components in 2D and for no
/// tangent at all when it assembles a residual alone, which lets the elasto-plastic laws skip
/// most of their work (the derivative of the spectral decomposition).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TangentRequest {
    /// Every entry of the 9×9 tangent.
    Full,
    /// The rows and columns of these flattened components of `F` (see
    /// [`crate::tensor::idx`]), e.g. `xx, xy, yx, yy` in plane strain. The caller guarantees
    /// that `F` is block diagonal with respect to them (the other components do not couple).
    Components(&'static [usize]),
    /// The stress alone (a residual evaluation).
    None,
}

/// The in-plane components `xx, xy, yx, yy` of `F` (plane strain).
pub const IN_PLANE: [usize; 4] = [0, 1, 3, 4];
/// The in-plane components and `zz` (axisymmetry, plane stress).
pub const IN_PLANE_AND_ZZ: [usize; 5] = [0, 1, 3, 4, 8];
/// All nine components.
pub const ALL_COMPONENTS: [usize; 9] = [0, 1, 2, 3, 4, 5, 6, 7, 8];

/// Evaluates `$body` with `$c` bound to the components `$components` (a `&[usize]`): to one
/// of the constant sets [`IN_PLANE`], [`IN_PLANE_AND_ZZ`], [`ALL_COMPONENTS`] when they are
/// equal to it, so that loops over `$c` unroll with their indices known, and to the slice
/// otherwise. `$body` is compiled once per set.
#[macro_export]
macro_rules! with_components {
    ($components:expr, |$c:ident| $body:expr) => {{
        let components: &[usize] = $components;
        if components == &$crate::law::IN_PLANE[..] {
            let $c = &$crate::law::IN_PLANE;
            $body
        } else if components == &$crate::law::IN_PLANE_AND_ZZ[..] {
            let $c = &$crate::law::IN_PLANE_AND_ZZ;
            $body
        } else if components == &$crate::law::ALL_COMPONENTS[..] {
            let $c = &$crate::law::ALL_COMPONENTS;
            $body
        } else {
            let $c = components;
            $body
        }
    }};
}

impl TangentRequest {
    /// The flattened components whose rows and columns are needed (empty for `None`).
    pub fn components(self) -> &'static [usize] {
        match self {
            Self::Full => &ALL_COMPONENTS,
            Self::Components(c) => c,
            Self::None => &[],
        }
    }
}

/// Stress and consistent tangent written by a law.
#[derive(Debug, Clone, Copy)]
pub struct StressResponse {
    /// First Piola–Kirchhoff stress `P = τ F^{-T}` in Pa.
    pub first_piola: Matrix3<f64>,
    /// Consistent tangent `A = ∂P/∂F` (9×9, see the module doc for the index convention).
    pub tangent: Tangent,
}

impl Default for StressResponse {
    fn default() -> Self {
        Self { first_piola: Matrix3::zeros(), tangent: Tangent::zeros() }
    }
}

/// A constitutive law: stress, consistent tangent and history at finite strain.
///
/// Implementations are immutable parameter sets; all evolving data is in the `state`
/// slices, whose length is [`ConstitutiveLaw::state_len`].
pub trait ConstitutiveLaw: Send + Sync + std::fmt::Debug {
    /// Short name of the law as written in case files, e.g. `"neo_hookean"`.
    fn name(&self) -> &'static str;

    /// Mass density ρ₀ in kg/m³ (reference configuration).
    fn density(&self) -> f64;

    /// Number of `f64` history slots an integration point must hold for this law.
    fn state_len(&self) -> usize {
        0
    }

    /// Writes the virgin history (no deformation, no plastic strain) into `state`.
    fn initialise_state(&self, _state: &mut [f64]) {}

    /// Writes the history of a point at rest (`F = I`) carrying the Cauchy stress `stress`
    /// (Pa, tension positive), e.g. a geostatic `K0` state. Laws whose history can hold an
    /// elastic prestrain (the multiplicative elasto-plastic laws) override this; the
    /// default accepts only a zero stress.
    fn initialise_state_at_stress(&self, stress: &Matrix3<f64>, state: &mut [f64]) -> Result<(), LawError> {
        self.initialise_state(state);
        if stress.iter().all(|v| *v == 0.0) {
            Ok(())
        } else {
            Err(LawError::InitialStress {
                problem: format!("law `{}` cannot start from a non-zero stress", self.name()),
            })
        }
    }

    /// Names of the scalar state variables this law reports for output, e.g.
    /// `accumulated_plastic_deviatoric_strain`. Their values come from
    /// [`ConstitutiveLaw::state_output`].
    fn state_variables(&self) -> &'static [&'static str] {
        &[]
    }

    /// Writes the values of [`ConstitutiveLaw::state_variables`] for history `state` into `out`.
    fn state_output(&self, _state: &[f64], _out: &mut [f64]) {}

    /// Evaluates stress and consistent tangent at `kinematics`, starting from the committed
    /// history `committed` and writing the updated (trial) history into `trial`.
    /// Neither the law nor this call commits anything.
    ///
    /// Writes `response.first_piola` and the entries of `response.tangent` that
    /// `kinematics.tangent` requests; the other entries are unspecified on return (they may
    /// hold intermediate values or an earlier point's) and must not be read. Writing into the
    /// caller's storage keeps the 9×9 tangent from being copied on its way out.
    fn update(
        &self,
        kinematics: &Kinematics,
        committed: &[f64],
        trial: &mut [f64],
        response: &mut StressResponse,
    ) -> Result<(), LawError>;

    /// [`ConstitutiveLaw::update`] into a fresh response, returned by value (drivers and
    /// tests; the element kernel keeps its own storage).
    fn stress_response(
        &self,
        kinematics: &Kinematics,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<StressResponse, LawError> {
        let mut response = StressResponse::default();
        self.update(kinematics, committed, trial, &mut response)?;
        Ok(response)
    }

    /// Small-strain elastic constants `(λ, μ)` at the reference state, used for time-step
    /// estimates and penalty scaling (`λ = ∞` for an incompressible material, which only the
    /// mixed u–p formulation accepts).
    fn elastic_lame(&self) -> (f64, f64);

    /// The law in volumetric–deviatoric form for the mixed u–p formulation
    /// ([`crate::mixed`]), or why it has none (e.g. a dilatant plastic flow).
    fn mixed(&self) -> Result<&dyn crate::mixed::MixedLaw, String> {
        Err(format!("law `{}` has no volumetric–deviatoric (u–p) form", self.name()))
    }
}
