//! Right-preconditioned GMRES, preconditioned by a factorisation of a nearby matrix.
//!
//! Saad & Schultz (1986), "GMRES: a generalized minimal residual algorithm for solving
//! nonsymmetric linear systems", SIAM J. Sci. Stat. Comput. 7:856–869; Saad (2003),
//! *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM, Algorithm 9.5 (right
//! preconditioning): with `x₀ = 0`, `β = ‖b‖`, `v₁ = b/β`, the Arnoldi process on
//! `A M⁻¹` builds `A M⁻¹ V_m = V_{m+1} H̄_m`; `y_m` minimises `‖β e₁ − H̄_m y‖` (Givens
//! rotations give the residual norm `|g_{m+1}|` at every step without forming `x`), and
//! `x_m = M⁻¹ V_m y_m`. The true residual of `x_m` equals the minimised one, so the
//! stopping test `|g_{m+1}| ≤ tol β` bounds `‖b − A x_m‖ / ‖b‖` directly.
//!
//! Used by [`crate::linear_solver`] with `M` the Cholesky factors of the symmetric part
//! `(K + Kᵀ)/2` of an unsymmetric tangent: when the skew part is small beside the mass
//! term (small time steps), a few iterations replace an LU factorisation.

/// Workspace of [`Gmres::solve`], reused between solves (no allocation once sized).
#[derive(Debug, Default)]
pub struct Gmres {
    /// Krylov basis `v_1 … v_{m+1}`, column after column.
    basis: Vec<f64>,
    /// Hessenberg matrix `H̄`, column-major `(m+1) × m`.
    hessenberg: Vec<f64>,
    /// Givens rotations (cos, sin).
    rotations: Vec<(f64, f64)>,
    /// Rotated right-hand side `g`.
    g: Vec<f64>,
    /// Scratch vectors.
    w: Vec<f64>,
    z: Vec<f64>,
}

/// Outcome of a GMRES solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresReport {
    /// Arnoldi iterations (matrix products = preconditioner applications − 1).
    pub iterations: usize,
    /// Final relative residual `‖b − A x‖ / ‖b‖`.
    pub relative_residual: f64,
    /// Whether it reached the tolerance.
    pub converged: bool,
}

impl Gmres {
    /// Solves `A x = b` with at most `max_iterations` Arnoldi steps to the relative residual
    /// `tolerance`. `b` holds the right-hand side on entry and, if converged, `x` on exit
    /// (it is left unchanged otherwise). `matvec(x, y)` writes `y = A x`;
    /// `precondition(z)` overwrites `z` with `M⁻¹ z`.
    pub fn solve(
        &mut self,
        b: &mut [f64],
        max_iterations: usize,
        tolerance: f64,
        mut matvec: impl FnMut(&[f64], &mut [f64]),
        mut precondition: impl FnMut(&mut [f64]),
    ) -> GmresReport {
        let n = b.len();
        let m = max_iterations.max(1);
        self.basis.resize((m + 1) * n, 0.0);
        self.hessenberg.resize((m + 1) * m, 0.0);
        self.rotations.resize(m, (1.0, 0.0));
        self.g.resize(m + 1, 0.0);
        self.w.resize(n, 0.0);
        self.z.resize(n, 0.0);
        let beta = norm(b);
        if beta == 0.0 || !beta.is_finite() {
            return GmresReport { iterations: 0, relative_residual: 0.0, converged: beta == 0.0 };
        }
        self.g.fill(0.0);
        self.g[0] = beta;
        for (v, &bi) in self.basis[..n].iter_mut().zip(b.iter()) {
            *v = bi / beta;
        }
        let mut k = 0;
        let mut residual = beta;
        while k < m {
            // w = A M⁻¹ v_k
            self.z.copy_from_slice(&self.basis[k * n..(k + 1) * n]);
            precondition(&mut self.z);
            matvec(&self.z, &mut self.w);
            // modified Gram–Schmidt
            let h = &mut self.hessenberg[k * (m + 1)..(k + 1) * (m + 1)];
            for (i, hi) in h.iter_mut().enumerate().take(k + 1) {
                let v = &self.basis[i * n..(i + 1) * n];
                let dot: f64 = v.iter().zip(&self.w).map(|(a, b)| a * b).sum();
                *hi = dot;
                for (w, vi) in self.w.iter_mut().zip(v) {
                    *w -= dot * vi;
                }
            }
            let h_next = norm(&self.w);
            h[k + 1] = h_next;
            if h_next > 0.0 {
                for (v, w) in self.basis[(k + 1) * n..(k + 2) * n].iter_mut().zip(&self.w) {
                    *v = w / h_next;
                }
            }
            // apply the earlier rotations to the new column, then a new one
            for (i, &(c, s)) in self.rotations.iter().enumerate().take(k) {
                let (a, b) = (h[i], h[i + 1]);
                h[i] = c * a + s * b;
                h[i + 1] = -s * a + c * b;
            }
            let r = h[k].hypot(h[k + 1]);
            let (c, s) = if r > 0.0 { (h[k] / r, h[k + 1] / r) } else { (1.0, 0.0) };
            self.rotations[k] = (c, s);
            h[k] = r;
            h[k + 1] = 0.0;
            let gk = self.g[k];
            self.g[k] = c * gk;
            self.g[k + 1] = -s * gk;
            residual = self.g[k + 1].abs();
            k += 1;
            if residual <= tolerance * beta || h_next == 0.0 {
                break;
            }
        }
        let relative_residual = residual / beta;
        let converged = relative_residual <= tolerance && relative_residual.is_finite();
        if converged {
            // back substitution H y = g (upper triangular k × k), then x = M⁻¹ V y
            let mut y = [0.0; 64];
            let mut y_heap = Vec::new();
            let y: &mut [f64] = if k <= y.len() {
                &mut y[..k]
            } else {
                y_heap.resize(k, 0.0);
                &mut y_heap
            };
            for i in (0..k).rev() {
                let mut v = self.g[i];
                for (j, yj) in y.iter().enumerate().skip(i + 1) {
                    v -= self.hessenberg[j * (m + 1) + i] * yj;
                }
                y[i] = v / self.hessenberg[i * (m + 1) + i];
            }
            self.z.fill(0.0);
            for (j, yj) in y.iter().enumerate() {
                for (z, v) in self.z.iter_mut().zip(&self.basis[j * n..(j + 1) * n]) {
                    *z += yj * v;
                }
            }
            precondition(&mut self.z);
            b.copy_from_slice(&self.z);
        }
        GmresReport { iterations: k, relative_residual, converged }
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A nonsymmetric tridiagonal test matrix (convection–diffusion stencil).
    fn matvec(x: &[f64], y: &mut [f64], shift: f64) {
        let n = x.len();
        for i in 0..n {
            let mut v = (2.0 + shift) * x[i];
            if i > 0 {
                v -= 1.3 * x[i - 1];
            }
            if i + 1 < n {
                v -= 0.7 * x[i + 1];
            }
            y[i] = v;
        }
    }

    #[test]
    fn converges_to_the_solution_and_reports_its_true_residual() {
        let n = 200;
        let exact: Vec<f64> = (0..n).map(|i| (0.1 * i as f64).sin()).collect();
        let mut b = vec![0.0; n];
        matvec(&exact, &mut b, 0.5);
        // preconditioner: the diagonal of a perturbed matrix (a stale factorisation)
        let mut gm = Gmres::default();
        let r = gm.solve(&mut b, 60, 1e-12, |x, y| matvec(x, y, 0.5), |z| z.iter_mut().for_each(|v| *v /= 2.4));
        let mut ax = vec![0.0; n];
        matvec(&b, &mut ax, 0.5);
        let mut rhs = vec![0.0; n];
        matvec(&exact, &mut rhs, 0.5);
        let true_res = ax.iter().zip(&rhs).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt() / norm(&rhs);
        let err = b.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        println!(
            "GMRES: {} iterations, reported residual {:.2e}, true {:.2e}, max error {err:.2e}",
            r.iterations, r.relative_residual, true_res
        );
        assert!(r.converged && r.relative_residual <= 1e-12 && true_res <= 1e-11 && err < 1e-10);
    }

    #[test]
    fn an_exact_preconditioner_converges_in_one_iteration() {
        // M = A for a diagonal A
        let n = 50;
        let d: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let b0 = b.clone();
        let mut gm = Gmres::default();
        let r = gm.solve(
            &mut b,
            10,
            1e-14,
            |x, y| y.iter_mut().zip(x).zip(&d).for_each(|((y, x), d)| *y = d * x),
            |z| z.iter_mut().zip(&d).for_each(|(z, d)| *z /= d),
        );
        assert_eq!(r.iterations, 1);
        for i in 0..n {
            assert!((b[i] * d[i] - b0[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn leaves_the_right_hand_side_when_it_does_not_converge() {
        let n = 100;
        let mut b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
        let b0 = b.clone();
        let mut gm = Gmres::default();
        let r = gm.solve(&mut b, 3, 1e-14, |x, y| matvec(x, y, 0.0), |_| {});
        assert!(!r.converged && r.iterations == 3);
        assert_eq!(b, b0);
    }
}
