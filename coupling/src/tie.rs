//! Non-conforming tie of a structure facet to the soil grid (issue 25, first law): the
//! element block of one interface quadrature point.
//!
//! A point of a structure facet sits at `x = Σ_a φ_a (X_a + u_a)` (facet functions `φ_a`,
//! reference positions `X_a`, structure displacements `u_a`) and is located in the fixed,
//! unmoved grid, whose functions there are `N_I(x)`. The gap is the soil's displacement at
//! the point minus the structure's,
//!
//! ```text
//! g = g₀ + Σ_I N_I(x) u_I − Σ_a φ_a u_a,
//! ```
//!
//! (`g₀` a gap carried in, e.g. the committed gap when `u` are the increments of a step) and
//! the tie is the penalty energy `Π = ½ β w |g|²` (β the penalty per unit area, w the
//! point's weight: Gauss weight × facet Jacobian, reference configuration). Its residual is
//! `f_I = β w N_I g` on the grid nodes and `f_a = −β w φ_a g` on the facet nodes (the traction
//! on the structure is `t = β g = β (u_grid(x) − u_S)`). The tangent is the exact second
//! derivative of `Π`, including the change of `N_I(x)` with the structure's motion
//! (`∂x/∂u_b = φ_b I`):
//!
//! ```text
//! ∂g/∂u_J = N_J I,   ∂g/∂u_b = (H − I) φ_b,   H = Σ_I u_I ⊗ ∇N_I,
//! K = β w [ (∂g/∂u)ᵀ (∂g/∂u) + Σ_k g_k ∂²g_k/∂u² ],
//! ∂²g_k/∂u_Jk ∂u_bj = ∂_j N_J φ_b,   ∂²g_k/∂u_bi ∂u_cj = Σ_I u_Ik ∂_ij N_I φ_b φ_c,
//! ```
//!
//! so it is symmetric, and the second derivatives `∂_ij N_I` of the grid functions enter
//! (non-zero for the bilinear basis: `∂_xy N_I`).

pub use loam_mpm::grid::GridFunction;

/// The element block of one tie point. DOFs are ordered grid nodes first (`2 I + k`), then
/// facet nodes (`2 (n + a) + k`), `n = grid.len()`. Returns the residual (the internal force
/// `∂Π/∂u`) and the row-major tangent `∂²Π/∂u²`, and the gap `g`. `initial_gap` is `g₀`.
/// Functions given with zero gradient and hessian make the point fixed in the grid (its
/// `N_I` do not follow the structure): the tangent is then `β w (∂g/∂u)ᵀ(∂g/∂u)` with
/// `∂g/∂u_b = −φ_b I`.
pub fn tie_point_block(
    grid: &[GridFunction],
    initial_gap: [f64; 2],
    grid_displacement: &[[f64; 2]],
    facet_functions: &[f64],
    facet_displacement: &[[f64; 2]],
    penalty: f64,
    weight: f64,
) -> (Vec<f64>, Vec<f64>, [f64; 2]) {
    let n = grid.len();
    let m = facet_functions.len();
    let dofs = 2 * (n + m);
    let mut gap = initial_gap;
    let mut h = [[0.0; 2]; 2];
    for (f, u) in grid.iter().zip(grid_displacement) {
        for k in 0..2 {
            gap[k] += f.value * u[k];
            for j in 0..2 {
                h[k][j] += u[k] * f.gradient[j];
            }
        }
    }
    for (phi, u) in facet_functions.iter().zip(facet_displacement) {
        for k in 0..2 {
            gap[k] -= phi * u[k];
        }
    }
    // Jacobian of the gap: column per DOF, row per component.
    let mut dg = vec![[0.0; 2]; dofs];
    for (i, f) in grid.iter().enumerate() {
        for k in 0..2 {
            dg[2 * i + k][k] = f.value;
        }
    }
    for (a, phi) in facet_functions.iter().enumerate() {
        for j in 0..2 {
            for k in 0..2 {
                let delta = if k == j { 1.0 } else { 0.0 };
                dg[2 * (n + a) + j][k] = (h[k][j] - delta) * phi;
            }
        }
    }
    let scale = penalty * weight;
    let residual: Vec<f64> = dg.iter().map(|c| scale * (c[0] * gap[0] + c[1] * gap[1])).collect();
    let mut tangent = vec![0.0; dofs * dofs];
    for p in 0..dofs {
        for q in 0..dofs {
            tangent[p * dofs + q] = scale * (dg[p][0] * dg[q][0] + dg[p][1] * dg[q][1]);
        }
    }
    // g_k ∂²g_k: grid–facet cross terms and facet–facet terms.
    let mut add = |p: usize, q: usize, v: f64| {
        tangent[p * dofs + q] += v;
        if p != q {
            tangent[q * dofs + p] += v;
        }
    };
    for (i, f) in grid.iter().enumerate() {
        for (a, phi) in facet_functions.iter().enumerate() {
            for k in 0..2 {
                for j in 0..2 {
                    add(2 * i + k, 2 * (n + a) + j, scale * gap[k] * f.gradient[j] * phi);
                }
            }
        }
    }
    let mut second = [[0.0; 2]; 2];
    for (f, u) in grid.iter().zip(grid_displacement) {
        let hess = [[f.hessian[0], f.hessian[1]], [f.hessian[1], f.hessian[2]]];
        for i in 0..2 {
            for j in 0..2 {
                second[i][j] += (gap[0] * u[0] + gap[1] * u[1]) * hess[i][j];
            }
        }
    }
    for (b, phi_b) in facet_functions.iter().enumerate() {
        for (c, phi_c) in facet_functions.iter().enumerate() {
            for i in 0..2 {
                for j in 0..2 {
                    tangent[(2 * (n + b) + i) * dofs + 2 * (n + c) + j] += scale * second[i][j] * phi_b * phi_c;
                }
            }
        }
    }
    (residual, tangent, gap)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bilinear functions of a unit-free cell `[0, h]²` with their derivatives at `x`.
    fn bilinear(x: [f64; 2], h: f64) -> Vec<GridFunction> {
        let (s, t) = (x[0] / h, x[1] / h);
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(a, b)| {
                let (fs, dfs) = if a == 0.0 { (1.0 - s, -1.0 / h) } else { (s, 1.0 / h) };
                let (ft, dft) = if b == 0.0 { (1.0 - t, -1.0 / h) } else { (t, 1.0 / h) };
                GridFunction { value: fs * ft, gradient: [dfs * ft, fs * dft], hessian: [0.0, dfs * dft, 0.0] }
            })
            .collect()
    }

    /// A two-node facet point at ξ (linear facet functions) in a bilinear cell: residual and
    /// tangent, the point located again from the displaced facet.
    fn block(u: &[f64], xi: f64) -> (Vec<f64>, Vec<f64>) {
        let reference = [[0.03, 0.02], [0.07, 0.09]];
        let phi = [1.0 - xi, xi];
        let grid_u: Vec<[f64; 2]> = (0..4).map(|i| [u[2 * i], u[2 * i + 1]]).collect();
        let facet_u: Vec<[f64; 2]> = (0..2).map(|a| [u[8 + 2 * a], u[9 + 2 * a]]).collect();
        let mut x = [0.0; 2];
        for a in 0..2 {
            for k in 0..2 {
                x[k] += phi[a] * (reference[a][k] + facet_u[a][k]);
            }
        }
        let (r, k, _) = tie_point_block(&bilinear(x, 0.1), [0.0; 2], &grid_u, &phi, &facet_u, 3.0e7, 0.02);
        (r, k)
    }

    #[test]
    fn tangent_matches_central_differences_including_the_moving_point() {
        let u: Vec<f64> =
            [0.004, -0.002, 0.006, 0.001, -0.003, 0.005, 0.002, -0.004, 0.001, 0.003, -0.002, 0.004].to_vec();
        let (_, tangent) = block(&u, 0.3);
        let dofs = u.len();
        let step = 1e-7;
        let mut worst: f64 = 0.0;
        let norm = tangent.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for q in 0..dofs {
            let (mut plus, mut minus) = (u.clone(), u.clone());
            plus[q] += step;
            minus[q] -= step;
            let (rp, _) = block(&plus, 0.3);
            let (rm, _) = block(&minus, 0.3);
            for p in 0..dofs {
                let fd = (rp[p] - rm[p]) / (2.0 * step);
                worst = worst.max((fd - tangent[p * dofs + q]).abs() / norm);
            }
        }
        println!("tie point tangent vs central differences: max relative error {worst:.2e}");
        assert!(worst < 1e-6, "relative error {worst:.2e}");
    }

    #[test]
    fn equal_displacements_give_no_gap_and_balanced_forces() {
        let u: Vec<f64> = (0..12).map(|i| if i % 2 == 0 { 0.01 } else { -0.02 }).collect();
        let (residual, _) = block(&u, 0.6);
        assert!(residual.iter().all(|r| r.abs() < 1e-6), "{residual:?}");
    }
}
