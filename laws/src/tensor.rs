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
/// `∂P_iJ/∂F_mN = Σ_k ∂τ_ik/∂F_mN F^{-1}_Jk − τ_ik F^{-1}_Jm F^{-1}_Nk`
/// (using `∂F^{-1}_Jk/∂F_mN = −F^{-1}_Jm F^{-1}_Nk`).
pub fn piola_from_kirchhoff(
    f_inv: &Matrix3<f64>,
    tau: &Matrix3<f64>,
    dtau_df: &Tangent,
) -> (Matrix3<f64>, Tangent) {
    let p = tau * f_inv.transpose();
    let mut a = Tangent::zeros();
    for i in 0..3 {
        for jj in 0..3 {
            for m in 0..3 {
                for n in 0..3 {
                    let mut v = 0.0;
                    for k in 0..3 {
                        v += dtau_df[(idx(i, k), idx(m, n))] * f_inv[(jj, k)]
                            - tau[(i, k)] * f_inv[(jj, m)] * f_inv[(n, k)];
                    }
                    a[(idx(i, jj), idx(m, n))] = v;
                }
            }
        }
    }
    (p, a)
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
