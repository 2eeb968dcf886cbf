//! Spectral decomposition of symmetric 3×3 tensors and the derivative of isotropic tensor
//! functions, robust to repeated eigenvalues.
//!
//! For a symmetric `X = Σ_a x_a n_a ⊗ n_a` and an isotropic tensor function
//! `Y(X) = Σ_a y_a(x_1, x_2, x_3) n_a ⊗ n_a`, the differential written in the eigenbasis
//! (`X̃ = Qᵀ X Q`, columns of `Q` are `n_a`) is
//!
//! `dỸ_aa = Σ_c ∂y_a/∂x_c dX̃_cc`,   `dỸ_ab = θ_ab dX̃_ab` (a ≠ b),
//!
//! with `θ_ab = (y_a − y_b)/(x_a − x_b)` for distinct eigenvalues. For (nearly) coincident
//! `x_a ≈ x_b` the quotient is replaced by its limit, evaluated in the symmetric form
//!
//! `θ_ab = ½ (∂y_a/∂x_a − ∂y_a/∂x_b + ∂y_b/∂x_b − ∂y_b/∂x_a)`,
//!
//! which is second-order accurate in `x_a − x_b` because `y` is permutation-equivariant
//! (the expression is even in the half-difference). This is the eigenbasis form of
//! de Souza Neto, Perić & Owen (2008), *Computational Methods for Plasticity*, Wiley,
//! Appendix A (doi:10.1002/9780470694626), covering its two- and three-fold repeated
//! eigenvalue cases without separate formulas.

use nalgebra::{Matrix3, SymmetricEigen};

/// Relative eigenvalue gap below which the limit form of `θ_ab` is used.
const COALESCENCE: f64 = 1e-6;

/// Eigenvalues and orthonormal eigenvectors (columns) of a symmetric 3×3 tensor.
#[derive(Debug, Clone, Copy)]
pub struct Spectral {
    /// Eigenvalues `x_a` (unsorted).
    pub values: [f64; 3],
    /// Eigenvectors `n_a` as the columns of an orthogonal matrix `Q`.
    pub vectors: Matrix3<f64>,
}

impl Spectral {
    /// Decomposes a symmetric tensor; `None` if the iteration fails (non-finite input).
    pub fn of(m: &Matrix3<f64>) -> Option<Self> {
        if !m.iter().all(|v| v.is_finite()) {
            return None;
        }
        if m[(0, 2)] == 0.0 && m[(1, 2)] == 0.0 && m[(2, 0)] == 0.0 && m[(2, 1)] == 0.0 {
            return Some(Self::of_in_plane(m));
        }
        let e = SymmetricEigen::try_new(*m, f64::EPSILON, 200)?;
        Some(Self { values: [e.eigenvalues[0], e.eigenvalues[1], e.eigenvalues[2]], vectors: e.eigenvectors })
    }

    /// Closed form for a tensor without `xz`, `yz` components (plane strain, plane stress and
    /// axisymmetry): the in-plane block `[[a, b], [b, d]]` has the eigenvalues
    /// `(a + d)/2 ± r`, `r = √(((a − d)/2)² + b²)`, the smaller in magnitude taken as
    /// `(a d − b²)` over the larger (no cancellation); the eigenvector of `(a + d)/2 + r` is
    /// `(x₁ − d, b)` if `a ≥ d`, else `(b, x₁ − a)` (the longer of the two, each at least
    /// `|b|` long), normalised; `zz` is the third eigenvalue, on `e_z`.
    fn of_in_plane(m: &Matrix3<f64>) -> Self {
        let (a, b, d) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
        let mean = 0.5 * (a + d);
        let r = (0.5 * (a - d)).hypot(b);
        let (big, small) = if mean >= 0.0 { (mean + r, mean - r) } else { (mean - r, mean + r) };
        let small = if big != 0.0 { (a * d - b * b) / big } else { small };
        let (first, second) = if mean >= 0.0 { (big, small) } else { (small, big) };
        let upper = mean + r;
        let (vx, vy) = if a >= d { (upper - d, b) } else { (b, upper - a) };
        let length = (vx * vx + vy * vy).sqrt();
        let (cos, sin) = if length > 0.0 { (vx / length, vy / length) } else { (1.0, 0.0) };
        Self { values: [first, second, m[(2, 2)]], vectors: Matrix3::new(cos, -sin, 0.0, sin, cos, 0.0, 0.0, 0.0, 1.0) }
    }

    /// `Σ_a y_a n_a ⊗ n_a` on this eigenbasis.
    pub fn compose(&self, y: [f64; 3]) -> Matrix3<f64> {
        let q = &self.vectors;
        Matrix3::from_fn(|i, j| (0..3).map(|a| q[(i, a)] * y[a] * q[(j, a)]).sum())
    }
}

/// Off-diagonal coefficients `θ_ab` of the derivative of an isotropic tensor function with
/// eigenvalue functions `y_a(x)` and Jacobian `dydx[(a, c)] = ∂y_a/∂x_c` (module doc).
/// The diagonal of the returned matrix is unused (zero).
pub fn isotropic_theta(x: [f64; 3], y: [f64; 3], dydx: &Matrix3<f64>) -> Matrix3<f64> {
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    let mut theta = Matrix3::zeros();
    for a in 0..3 {
        for b in 0..3 {
            if a == b {
                continue;
            }
            let gap = x[a] - x[b];
            theta[(a, b)] = if gap.abs() > COALESCENCE * scale {
                (y[a] - y[b]) / gap
            } else {
                0.5 * (dydx[(a, a)] - dydx[(a, b)] + dydx[(b, b)] - dydx[(b, a)])
            };
        }
    }
    theta
}

/// Differential `dY` of the isotropic function for a symmetric increment `dX̃` given in the
/// eigenbasis, returned in the eigenbasis.
#[inline]
pub fn isotropic_differential(dydx: &Matrix3<f64>, theta: &Matrix3<f64>, dx: &Matrix3<f64>) -> Matrix3<f64> {
    let mut dy = theta.component_mul(dx);
    for a in 0..3 {
        dy[(a, a)] = (0..3).map(|c| dydx[(a, c)] * dx[(c, c)]).sum();
    }
    dy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Y = ln X` (y_a = ln x_a) differentiated at a tensor with a double and at one with a
    /// triple eigenvalue, against central differences.
    #[test]
    fn in_plane_closed_form_reconstructs_the_tensor() {
        let cases = [
            [1.2, 0.3, 0.9, 1.1],
            [1.0, 0.0, 1.0, 1.0],
            [-2.0e5, 3.0e4, -5.0e4, -7.0e4],
            [1.0, 1e-12, 1.0 + 1e-14, 0.5],
            [-1.0, 0.0, 1e-10, 0.0],
            [0.9, -0.4, 1.3, 1.0],
        ];
        for [a, b, d, z] in cases {
            let m = Matrix3::new(a, b, 0.0, b, d, 0.0, 0.0, 0.0, z);
            let s = Spectral::of(&m).expect("finite");
            let back = s.compose(s.values);
            let scale = m.amax();
            let err = (back - m).amax() / scale;
            let orth = (s.vectors.transpose() * s.vectors - Matrix3::identity()).amax();
            let general = SymmetricEigen::new(m).eigenvalues;
            let mut ours = s.values;
            let mut theirs = [general[0], general[1], general[2]];
            ours.sort_by(f64::total_cmp);
            theirs.sort_by(f64::total_cmp);
            let value_err = (0..3).map(|i| (ours[i] - theirs[i]).abs()).fold(0.0, f64::max) / scale;
            println!("{m:?}: reconstruction {err:.1e}, orthogonality {orth:.1e}, eigenvalues vs QR {value_err:.1e}");
            assert!(err < 1e-14 && orth < 1e-15 && value_err < 1e-14);
        }
    }

    #[test]
    fn log_derivative_at_repeated_eigenvalues() {
        let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner();
        for vals in [[1.2, 0.9, 0.9], [1.1, 1.1, 1.1], [1.3, 0.8, 1.05]] {
            let x = rot * Matrix3::from_diagonal(&vals.into()) * rot.transpose();
            let f = |m: &Matrix3<f64>| {
                let s = Spectral::of(m).unwrap();
                s.compose(s.values.map(f64::ln))
            };
            let s = Spectral::of(&x).unwrap();
            let dydx = Matrix3::from_diagonal(&s.values.map(|v| 1.0 / v).into());
            let theta = isotropic_theta(s.values, s.values.map(f64::ln), &dydx);
            let dir = Matrix3::new(0.3, 0.1, -0.2, 0.1, -0.4, 0.25, -0.2, 0.25, 0.15);
            let dx = s.vectors.transpose() * dir * s.vectors;
            let dy = s.vectors * isotropic_differential(&dydx, &theta, &dx) * s.vectors.transpose();
            let h = 1e-6;
            let fd = (f(&(x + dir * h)) - f(&(x - dir * h))) / (2.0 * h);
            let err = (dy - fd).amax() / fd.amax();
            println!("d ln X at eigenvalues {vals:?}: relative error vs FD {err:.2e} (tolerance 1e-7)");
            assert!(err < 1e-7);
        }
    }
}
