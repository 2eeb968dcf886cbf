//! Small tensor helpers shared by the laws: the 9-index convention and the push-forward /
//! pull-back between the Kirchhoff stress and the first Piola–Kirchhoff stress.

use nalgebra::{Matrix3, SMatrix};

/// A fourth-order tensor `A_iJkL` stored as a 9×9 matrix, entry `(3i+J, 3k+L)`.
pub type Tangent = SMatrix<f64, 9, 9>;

/// Position of component `(i, J)` of a flattened 3×3 tensor.
#[inline(always)]
pub const fn idx(i: usize, j: usize) -> usize {
    3 * i + j
}

/// First Piola–Kirchhoff stress and its tangent from the Kirchhoff stress `τ` and the
/// derivative `dτ/dF` (9×9, same index convention):
///
/// `P = τ F^{-T}`,
/// `∂P_iJ/∂F_mN = Σ_k ∂τ_ik/∂F_mN F^{-1}_Jk − F^{-1}_Jm P_iN`
/// (using `∂F^{-1}_Jk/∂F_mN = −F^{-1}_Jm F^{-1}_Nk`).
///
/// In place: `tangent` holds `dτ/dF` on entry (the columns `components`, all nine rows of
/// each) and `A` on return, in the rows and columns `components` (other entries unspecified).
#[inline(always)]
pub fn piola_from_kirchhoff(
    f_inv: &Matrix3<f64>,
    tau: &Matrix3<f64>,
    tangent: &mut Tangent,
    components: &[usize],
) -> Matrix3<f64> {
    let p = tau * f_inv.transpose();
    crate::with_components!(components, |components| {
        for &col in components {
            let (m, n) = (col / 3, col % 3);
            // column `col` of ∂τ/∂F (all nine rows), overwritten below by that of A
            let dtau: [f64; 9] = std::array::from_fn(|r| tangent[(r, col)]);
            for &row in components {
                let (i, jj) = (row / 3, row % 3);
                let mut v = -f_inv[(jj, m)] * p[(i, n)];
                for k in 0..3 {
                    v += dtau[idx(i, k)] * f_inv[(jj, k)];
                }
                tangent[(row, col)] = v;
            }
        }
    });
    p
}

/// Central finite-difference tangent `∂P/∂F` of `stress` at `f` with step `h` (for tests of
/// the consistent tangent; relative accuracy O(h²)).
pub fn finite_difference_tangent(
    f: &Matrix3<f64>,
    h: f64,
    mut stress: impl FnMut(&Matrix3<f64>) -> Matrix3<f64>,
) -> Tangent {
    let mut a = Tangent::zeros();
    for k in 0..3 {
        for l in 0..3 {
            let mut fp = *f;
            let mut fm = *f;
            fp[(k, l)] += h;
            fm[(k, l)] -= h;
            let d = (stress(&fp) - stress(&fm)) / (2.0 * h);
            for i in 0..3 {
                for j in 0..3 {
                    a[(idx(i, j), idx(k, l))] = d[(i, j)];
                }
            }
        }
    }
    a
}

/// Relative error `max|A − A_FD| / max|A|` of a law's consistent tangent against central
/// differences of its stress, evaluated from the committed history `committed` at
/// `kinematics`. The reference is [`finite_difference_tangent`] at steps `h = 2e-6` and
/// `h/2` combined by one Richardson extrapolation, `A_FD = (4 A_{h/2} − A_h)/3` (error
/// O(h⁴)), so that the check measures the tangent rather than the truncation error of the
/// reference at strongly curved states (e.g. a softening law at the apex). Used by the
/// verification tests of every law.
pub fn tangent_relative_error(
    law: &dyn crate::ConstitutiveLaw,
    kinematics: &crate::Kinematics,
    committed: &[f64],
) -> Result<f64, crate::LawError> {
    let mut trial = committed.to_vec();
    let r = law.stress_response(kinematics, committed, &mut trial)?;
    let mut failure = None;
    let mut stress = |g: &Matrix3<f64>| {
        let kin = crate::Kinematics { deformation_gradient: *g, ..*kinematics };
        match law.stress_response(&kin, committed, &mut trial) {
            Ok(s) => s.first_piola,
            Err(e) => {
                failure = Some(e);
                Matrix3::zeros()
            }
        }
    };
    let h = 2e-6;
    let coarse = finite_difference_tangent(&kinematics.deformation_gradient, h, &mut stress);
    let fine = finite_difference_tangent(&kinematics.deformation_gradient, 0.5 * h, &mut stress);
    if let Some(e) = failure {
        return Err(e);
    }
    let fd = (4.0 * fine - coarse) / 3.0;
    Ok((r.tangent - fd).amax() / r.tangent.amax())
}
