//! Statistics at the optimum: the residual variance, the covariance `s²(JᵀJ)⁻¹` of the
//! linearised model, the 95 % confidence intervals with Student's t quantile, the
//! correlation matrix, the misfit per test and curve, and the runs test that tells a
//! systematic misfit from noise (module doc of [`super`]).

use nalgebra::DMatrix;

use super::Problem;

/// What the data say about the fitted parameters.
#[derive(Debug, Clone)]
pub struct Statistics {
    /// Residual sum of squares `S(θ̂)`.
    pub sum_of_squares: f64,
    /// Number of residuals `m`.
    pub residuals: usize,
    /// Degrees of freedom `m − n`.
    pub dof: usize,
    /// Student's t quantile `t_{0.975, m−n}` of the intervals.
    pub t_quantile: f64,
    /// Standard errors `√C_jj` (NaN where undetermined).
    pub standard_errors: Vec<f64>,
    /// Correlation matrix `ρ_jk` (NaN where undetermined).
    pub correlation: DMatrix<f64>,
    /// A parameter that the data cannot determine (J rank-deficient), if any.
    pub undetermined: Option<usize>,
    /// Smallest over largest singular value of J.
    pub condition: f64,
    /// Misfit per test and curve: the rms of `(ŷ − y)/s_tc` (unweighted), a fraction.
    pub rms: Vec<Vec<f64>>,
    /// Per test and curve: the runs test's `z` of the residual signs (NaN when fewer than 2
    /// of each sign).
    pub runs_z: Vec<Vec<f64>>,
}

impl Statistics {
    /// The statistics of `problem` at residuals `r` and Jacobian `jacobian` (∂r/∂θ).
    pub fn new(problem: &Problem, r: &[f64], jacobian: Option<&DMatrix<f64>>) -> Self {
        let n = problem.parameters.len();
        let m = r.len();
        let sum_of_squares: f64 = r.iter().map(|v| v * v).sum();
        let dof = m.saturating_sub(n);
        let s2 = if dof > 0 { sum_of_squares / dof as f64 } else { f64::NAN };
        let mut standard_errors = vec![f64::NAN; n];
        let mut correlation = DMatrix::from_element(n, n, f64::NAN);
        let mut undetermined = None;
        let mut condition = f64::NAN;
        if let Some(j) = jacobian.filter(|j| j.nrows() == m && m > 0) {
            let svd = j.clone().svd(false, true);
            let v_t = svd.v_t.expect("SVD asked for V");
            let (smax, (kmin, smin)) = (
                svd.singular_values.max(),
                svd.singular_values.iter().copied().enumerate().fold((0, f64::INFINITY), |a, (k, s)| {
                    if s < a.1 {
                        (k, s)
                    } else {
                        a
                    }
                }),
            );
            condition = if smax > 0.0 { smin / smax } else { 0.0 };
            if condition < 1e-10 {
                undetermined = Some(v_t.row(kmin).iamax_full().1);
            } else {
                // C = s² V Σ⁻² Vᵀ
                let inv_s2 = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / (s * s)));
                let c = v_t.transpose() * inv_s2 * &v_t * s2;
                for a in 0..n {
                    standard_errors[a] = c[(a, a)].sqrt();
                    for b in 0..n {
                        correlation[(a, b)] = c[(a, b)] / (c[(a, a)] * c[(b, b)]).sqrt();
                    }
                }
            }
        }
        let (mut rms, mut runs_z) = (Vec::new(), Vec::new());
        let mut k = 0;
        for test in &problem.tests {
            let w = test.spec.weight.sqrt();
            let (mut rt, mut zt) = (Vec::new(), Vec::new());
            for _ in &test.curves {
                let e: Vec<f64> = r[k..k + test.x.len()].iter().map(|v| v / w).collect();
                k += test.x.len();
                rt.push((e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt());
                zt.push(runs_z_score(&e));
            }
            rms.push(rt);
            runs_z.push(zt);
        }
        Self {
            sum_of_squares,
            residuals: m,
            dof,
            t_quantile: student_t_975(dof),
            standard_errors,
            correlation,
            undetermined,
            condition,
            rms,
            runs_z,
        }
    }

    /// Half-width of the 95 % interval of parameter `j`: `t √C_jj`.
    pub fn half_width(&self, j: usize) -> f64 {
        self.t_quantile * self.standard_errors[j]
    }

    /// Warnings for curves whose misfit is systematic: runs test `z < −3` and rms misfit
    /// above 1 % of the curve's largest value (module doc of [`super`]).
    pub fn systematic_misfits(&self, problem: &Problem) -> Vec<String> {
        let mut out = Vec::new();
        for (t, test) in problem.tests.iter().enumerate() {
            for (c, curve) in test.curves.iter().enumerate() {
                let (z, rms) = (self.runs_z[t][c], self.rms[t][c]);
                if z < -3.0 && rms > 0.01 {
                    out.push(format!(
                        "test {} ({}): the fitted {} misses the measured curve systematically (rms {:.1} % of its largest value; the residuals keep their sign over long runs, runs test z = {z:.1}): the curve lies outside the reach of {} with these fixed parameters (e.g. a peak and softening need mohr_coulomb_softening)",
                        t,
                        test.spec.name,
                        curve.column.quantity,
                        100.0 * rms,
                        problem.law
                    ));
                }
            }
        }
        out
    }
}

/// The Wald–Wolfowitz runs test on the signs of `e` (in the order of the points):
/// `z = (R − μ)/σ` with `R` the number of runs, `μ = 2 n₊ n₋/N + 1`,
/// `σ² = (μ − 1)(μ − 2)/(N − 1)`. Random signs give `z ~ N(0, 1)`; a systematic misfit
/// (few long runs) a large negative z. NaN with fewer than two residuals of each sign.
pub fn runs_z_score(e: &[f64]) -> f64 {
    let signs: Vec<bool> = e.iter().filter(|v| **v != 0.0).map(|v| *v > 0.0).collect();
    let np = signs.iter().filter(|s| **s).count() as f64;
    let nm = signs.len() as f64 - np;
    if np < 2.0 || nm < 2.0 {
        return f64::NAN;
    }
    let runs = 1.0 + signs.windows(2).filter(|w| w[0] != w[1]).count() as f64;
    let n = np + nm;
    let mu = 2.0 * np * nm / n + 1.0;
    let var = (mu - 1.0) * (mu - 2.0) / (n - 1.0);
    (runs - mu) / var.sqrt()
}

/// Student's t quantile `t_{0.975, ν}` (two-sided 95 %): for ν ≤ 30 the tabulated values
/// (Abramowitz & Stegun 1964, Table 26.10, to 3 decimals), above the Cornish–Fisher expansion
/// around the normal quantile z = 1.959964 (A&S 26.7.5; error below 1e-5 for ν > 30).
/// NaN for ν = 0.
pub fn student_t_975(dof: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
        2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::NAN,
        1..=30 => TABLE[dof - 1],
        _ => {
            let z: f64 = 1.959_963_984_540_054;
            let v = dof as f64;
            let (z3, z5, z7, z9) = (z.powi(3), z.powi(5), z.powi(7), z.powi(9));
            z + (z3 + z) / (4.0 * v)
                + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
                + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v.powi(3))
                + (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z) / (92160.0 * v.powi(4))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// t quantiles against A&S Table 26.10: ν = 40, 60, 120 → 2.021, 2.000, 1.980; ∞ → 1.960.
    #[test]
    fn student_t_against_the_table() {
        for (dof, t) in [(10, 2.228), (31, 2.040), (40, 2.021), (60, 2.000), (120, 1.980), (100_000, 1.960)] {
            let got = student_t_975(dof);
            println!("t_0.975({dof}) = {got:.5} (table {t})");
            assert!((got - t).abs() < 6e-4, "{dof}: {got} vs {t}");
        }
    }

    /// Alternating signs: many runs (z > 0); one sign change: z ≪ 0.
    #[test]
    fn runs_test_tells_noise_from_a_trend() {
        let alternating: Vec<f64> = (0..40).map(|i| if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let trend: Vec<f64> = (0..40).map(|i| i as f64 - 19.5).collect();
        println!("z alternating {:.2}, trend {:.2}", runs_z_score(&alternating), runs_z_score(&trend));
        assert!(runs_z_score(&alternating) > 3.0);
        assert!(runs_z_score(&trend) < -5.0);
        assert!(runs_z_score(&[1.0, 1.0, -1.0]).is_nan());
    }
}
