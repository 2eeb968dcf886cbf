//! `loam fit`: calibration of a constitutive law to laboratory curves.
//!
//! A fit file ([`spec`]) names a law with starting values, the parameters `θ` to fit with
//! bounds `[a_j, b_j]`, and laboratory tests: each a `loam law` path ([`loam_laws::driver`])
//! with measured curves `y_tci` at abscissae `x_ti` (test t, curve c, point i). The fit
//! minimises the weighted, scaled sum of squares
//!
//! $$S(θ) = Σ_{t,c,i} r_{tci}^2, \qquad r_{tci} = \sqrt{w_t}\,\frac{\hat y_{tc}(x_{ti}; θ) − y_{tci}}{s_{tc}},
//! \qquad s_{tc} = \max_i |y_{tci}|,$$
//!
//! where `ŷ_tc(x; θ)` is the driver's curve (one material point along the test's path with
//! the parameters θ) interpolated linearly at the measured abscissa, in the CSV's units and
//! sign. The scale `s_tc` makes curves of different units (q in kPa, ε_v in %) commensurable.
//!
//! **Generic over the law.** A parameter is a numeric key of the material block: the block
//! with the key set to `θ_j` is read as a case file's material (same checks, same errors),
//! so every law of `loam-laws` is fitted by the same code.
//!
//! **Solver.** MINPACK's Levenberg–Marquardt (Moré 1978, doi:10.1007/BFb0067700) from the
//! `levenberg-marquardt` crate: a trust region on the Gauss–Newton step with scaled,
//! pivoted QR.
//!
//! **Bounds** by the transformation of MINUIT (James & Roos 1975, doi:10.1016/0010-4655(75)90039-9):
//! the solver moves an unbounded `u_j` and
//!
//! $$θ_j = a_j + \tfrac12 (b_j − a_j)(1 + \sin u_j), \qquad
//! \frac{∂θ_j}{∂u_j} = \tfrac12 (b_j − a_j) \cos u_j,$$
//!
//! so every trial point lies in the bounds. A parameter that ends at a bound (within 1e-3 of
//! its range) is reported: the bound, not the data, chose it.
//!
//! **Derivatives** of the residuals by finite differences in θ: central
//! `∂r/∂θ_j ≈ (r(θ + h_j e_j) − r(θ − h_j e_j))/(2 h_j)`, with
//! `h_j = h max(|θ_j|, 1e-3 (b_j − a_j))` (`h` = `solver.finite_difference_step`, default
//! 1e-6: it balances the truncation error `O(h²)` against the driver's round-off `O(ε/h)`;
//! against the closed form of a Hencky test the error is below 1e-7 of the column's scale,
//! `tests/fit.rs`); one-sided inside the bounds where `θ_j ± h_j` would leave them. The
//! solver's Jacobian is `∂r/∂u = ∂r/∂θ · diag(∂θ/∂u)`.
//!
//! **Uncertainty** at the optimum `θ̂` ([`stats`]), from the Jacobian `J = ∂r/∂θ` in the
//! physical parameters: with `m` residuals and `n` parameters,
//!
//! $$s^2 = \frac{S(\hat θ)}{m − n}, \qquad C = s^2 (J^\top J)^{-1}, \qquad
//! θ_j ∈ \hat θ_j ± t_{0.975,\,m−n} \sqrt{C_{jj}}, \qquad ρ_{jk} = \frac{C_{jk}}{\sqrt{C_{jj} C_{kk}}},$$
//!
//! the 95 % intervals with Student's t quantile (linearised model, independent residuals of
//! equal variance after weighting and scaling). `(JᵀJ)⁻¹` is taken from the singular value
//! decomposition of J; a J whose smallest singular value is below 1e-10 of its largest is
//! reported with the parameter the data cannot determine.
//!
//! **Reach of the law.** When a curve's residuals keep their sign over long runs (the
//! Wald–Wolfowitz runs test, `z < −3`) and its misfit is above 1 % of the curve's largest
//! value, the misfit is systematic: the law cannot follow that curve (e.g. a peak and
//! softening that Mohr–Coulomb without softening cannot give). The fit says so.

pub mod data;
pub mod output;
pub mod spec;
pub mod stats;

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, TerminationReason};
use loam_laws::driver::{DriverError, PathFile, PathTable};
use loam_laws::MaterialSpec;
use nalgebra::{DMatrix, DVector};
use nalgebra_lm as lm;
use serde_json::{Map, Value};

use crate::case::CaseError;
pub use spec::{Column, FitFile, FitParameter, LabTest, SolverSettings, Unit};

/// Why `loam fit` failed before or outside the solver. `Display` is one line.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// Malformed fit file or data (a key, or a CSV line): exit code 2.
    #[error("{0}")]
    Input(CaseError),
    /// The material point cannot follow a test's path at the starting parameters: exit code 1.
    #[error("tests[{test}] ({name}): at the starting parameters: {message}")]
    Start {
        /// Index of the test.
        test: usize,
        /// Its name.
        name: String,
        /// The driver's error.
        message: String,
    },
    /// An output file could not be written: exit code 1.
    #[error("cannot write {}: {reason}", file.display())]
    Write {
        /// The file.
        file: PathBuf,
        /// Why.
        reason: String,
    },
}

impl FitError {
    fn input(location: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Input(CaseError::new(location, message))
    }

    /// Exit code of the CLI: 2 bad input, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            FitError::Input(_) => 2,
            _ => 1,
        }
    }
}

/// A fitted parameter as prepared: bounds and starting value.
#[derive(Debug, Clone)]
pub struct Parameter {
    /// The material key.
    pub name: String,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// Starting value (from the material block).
    pub initial: f64,
}

impl Parameter {
    /// `θ(u)` of the bound transformation (module doc).
    pub fn theta(&self, u: f64) -> f64 {
        (self.min + 0.5 * (self.max - self.min) * (1.0 + u.sin())).clamp(self.min, self.max)
    }

    /// `∂θ/∂u`.
    pub fn dtheta_du(&self, u: f64) -> f64 {
        0.5 * (self.max - self.min) * u.cos()
    }

    /// `u(θ)`, the inverse of [`Parameter::theta`] on `[−π/2, π/2]`.
    pub fn u(&self, theta: f64) -> f64 {
        (2.0 * (theta - self.min) / (self.max - self.min) - 1.0).clamp(-1.0, 1.0).asin()
    }

    /// Whether `theta` lies within 1e-3 of the range from a bound.
    pub fn at_bound(&self, theta: f64) -> bool {
        let tol = 1e-3 * (self.max - self.min);
        theta - self.min <= tol || self.max - theta <= tol
    }
}

/// A measured curve of a test, in the CSV's units and sign.
#[derive(Debug, Clone)]
pub struct Curve {
    /// The column spec.
    pub column: Column,
    /// Measured values `y_tci`.
    pub y: Vec<f64>,
    /// Scale `s_tc = max |y|`.
    pub scale: f64,
}

/// A test as prepared: its path file (material set per evaluation) and measured data.
#[derive(Debug, Clone)]
pub struct Test {
    /// The test spec.
    pub spec: LabTest,
    /// Measured abscissae `x_ti`.
    pub x: Vec<f64>,
    /// Measured curves.
    pub curves: Vec<Curve>,
}

/// The prepared problem: material block, parameters and tests. Evaluations are pure
/// functions of θ (each runs the driver afresh).
#[derive(Debug, Clone)]
pub struct Problem {
    /// The material block with the starting values.
    pub material: Map<String, Value>,
    /// The law's name.
    pub law: String,
    /// The fitted parameters.
    pub parameters: Vec<Parameter>,
    /// The tests.
    pub tests: Vec<Test>,
    /// Solver settings.
    pub solver: SolverSettings,
}

/// A failed evaluation of the simulated curves: the test and the reason.
#[derive(Debug, Clone)]
pub struct EvalError {
    /// Index of the test.
    pub test: usize,
    /// Bad input (a JSON path in the message) rather than a point that cannot follow the path.
    pub input: bool,
    /// One-line message.
    pub message: String,
}

impl Problem {
    /// Prepares `file` (read from the directory `base`): checks the parameters and their
    /// bounds, reads and checks the measured CSV files.
    pub fn new(file: &FitFile, base: &Path) -> Result<Self, FitError> {
        let law = match file.material.get("law") {
            Some(Value::String(s)) => s.clone(),
            _ => return Err(FitError::input("material.law", "must name the law, e.g. \"mohr_coulomb\"")),
        };
        if file.fit.is_empty() {
            return Err(FitError::input("fit", "must name at least one parameter to fit"));
        }
        let mut parameters: Vec<Parameter> = Vec::new();
        for (j, p) in file.fit.iter().enumerate() {
            let at = |key: &str| format!("fit[{j}]{key}");
            if parameters.iter().any(|q| q.name == p.name) {
                return Err(FitError::input(at(".name"), format!("`{}` is fitted twice", p.name)));
            }
            let initial = match file.material.get(&p.name) {
                Some(Value::Number(n)) => n.as_f64().unwrap_or(f64::NAN),
                Some(_) => {
                    return Err(FitError::input(
                        at(".name"),
                        format!("material.{} is not a number: only numeric parameters can be fitted", p.name),
                    ))
                }
                None => {
                    let keys: Vec<&str> =
                        file.material.iter().filter(|(_, v)| v.is_number()).map(|(k, _)| k.as_str()).collect();
                    return Err(FitError::input(
                        at(".name"),
                        format!(
                            "`{}` is not a key of the material block (its numeric keys: {})",
                            p.name,
                            keys.join(", ")
                        ),
                    ));
                }
            };
            if !(p.min.is_finite() && p.max.is_finite() && p.min < p.max) {
                return Err(FitError::input(at(""), format!("needs finite min < max, got [{}, {}]", p.min, p.max)));
            }
            if !(p.min..=p.max).contains(&initial) {
                return Err(FitError::input(
                    at(""),
                    format!("the starting value material.{} = {initial} lies outside [{}, {}]", p.name, p.min, p.max),
                ));
            }
            parameters.push(Parameter { name: p.name.clone(), min: p.min, max: p.max, initial });
        }
        if file.tests.is_empty() {
            return Err(FitError::input("tests", "must hold at least one test"));
        }
        let s = &file.solver;
        if s.max_iterations == 0 {
            return Err(FitError::input("solver.max_iterations", "must be at least 1"));
        }
        if !(s.tolerance > 0.0 && s.tolerance < 1.0) {
            return Err(FitError::input("solver.tolerance", format!("must lie in (0, 1), got {}", s.tolerance)));
        }
        if !(s.finite_difference_step > 0.0 && s.finite_difference_step <= 0.1) {
            return Err(FitError::input(
                "solver.finite_difference_step",
                format!("must lie in (0, 0.1], got {}", s.finite_difference_step),
            ));
        }
        let tests =
            file.tests.iter().enumerate().map(|(t, spec)| read_test(t, spec, base)).collect::<Result<_, _>>()?;
        let problem = Self { material: file.material.clone(), law, parameters, tests, solver: s.clone() };
        // The starting point: the material block must be valid, every path followed, every
        // quantity present and every measured abscissa reached.
        let theta0 = problem.initial();
        if let Err(e) = problem.fitted(&theta0) {
            return Err(if e.input {
                FitError::Input(match e.message.split_once(": ") {
                    Some((location, message)) => CaseError::new(location, message),
                    None => CaseError::new("", e.message),
                })
            } else {
                FitError::Start { test: e.test, name: problem.tests[e.test].spec.name.clone(), message: e.message }
            });
        }
        Ok(problem)
    }

    /// The starting values θ₀.
    pub fn initial(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.initial).collect()
    }

    /// Number of residuals `m`.
    pub fn residual_count(&self) -> usize {
        self.tests.iter().map(|t| t.x.len() * t.curves.len()).sum()
    }

    /// The material block with the parameters set to `theta`.
    pub fn material_block(&self, theta: &[f64]) -> Map<String, Value> {
        let mut m = self.material.clone();
        for (p, v) in self.parameters.iter().zip(theta) {
            m.insert(p.name.clone(), Value::from(*v));
        }
        m
    }

    /// Runs test `t` with `material`: the driver's table.
    fn run(&self, t: usize, material: &MaterialSpec) -> Result<PathTable, EvalError> {
        let spec = &self.tests[t].spec;
        let fail = |e: DriverError| {
            let input = matches!(e, DriverError::Input { .. });
            let message = match &e {
                DriverError::Input { json_path, problem } if !json_path.starts_with("material") => {
                    format!("tests[{t}].{json_path}: {problem}")
                }
                _ => e.to_string(),
            };
            EvalError { test: t, input, message: crate::input::compact_numbers(&message) }
        };
        let law = material.build().map_err(|e| fail(e.into()))?;
        let file = PathFile {
            description: spec.name.clone(),
            material: material.clone(),
            initial_stress: spec.initial_stress,
            time_step: spec.time_step,
            path: spec.path.clone(),
        };
        loam_laws::driver::run_path(law.as_ref(), &file).map_err(fail)
    }

    /// The simulated curves `ŷ_tc(x_ti; θ)` of every test, in the CSV's units and sign.
    pub fn fitted(&self, theta: &[f64]) -> Result<Vec<Vec<Vec<f64>>>, EvalError> {
        let block = Value::Object(self.material_block(theta));
        let material: MaterialSpec = crate::input::from_value(&block).map_err(|e| EvalError {
            test: 0,
            input: true,
            message: format!("material{}{}: {}", if e.location.is_empty() { "" } else { "." }, e.location, e.message),
        })?;
        (0..self.tests.len())
            .map(|t| {
                let table = self.run(t, &material)?;
                self.interpolate(t, &table)
            })
            .collect()
    }

    /// The simulated curves of test `t` at its measured abscissae.
    fn interpolate(&self, t: usize, table: &PathTable) -> Result<Vec<Vec<f64>>, EvalError> {
        let test = &self.tests[t];
        let err = |message: String| EvalError { test: t, input: true, message };
        let column = |c: &Column, key: &str| {
            let values = table.column(&c.quantity).ok_or_else(|| {
                err(format!(
                    "tests[{t}].{key}.quantity: no column `{}` in the driver's output of {} (columns: {})",
                    c.quantity,
                    self.law,
                    table.columns.join(", ")
                ))
            })?;
            let stress = spec::is_stress_quantity(&c.quantity);
            if stress != c.unit.is_stress() {
                return Err(err(format!(
                    "tests[{t}].{key}.unit: `{}` is {}, so its unit must be {}, got \"{}\"",
                    c.quantity,
                    if stress { "a stress" } else { "dimensionless" },
                    if stress { "\"Pa\", \"kPa\" or \"MPa\"" } else { "\"1\" or \"%\"" },
                    c.unit.label()
                )));
            }
            Ok(values.iter().map(|x| c.sign * x / c.unit.factor()).collect::<Vec<f64>>())
        };
        let mut xs = column(&test.spec.x, "x")?;
        let mut ys: Vec<Vec<f64>> = test
            .curves
            .iter()
            .enumerate()
            .map(|(c, curve)| column(&curve.column, &format!("curves[{c}]")))
            .collect::<Result<_, _>>()?;
        if xs.len() >= 2 && xs[xs.len() - 1] < xs[0] {
            xs.reverse();
            ys.iter_mut().for_each(|y| y.reverse());
        }
        if xs.windows(2).any(|w| w[1] <= w[0]) {
            return Err(err(format!(
                "tests[{t}].x.quantity: `{}` does not grow monotonically along the path, so the measured points cannot be located on it",
                test.spec.x.quantity
            )));
        }
        let (lo, hi) = (xs[0], xs[xs.len() - 1]);
        let tol = 1e-9 * (hi - lo).abs().max(f64::MIN_POSITIVE);
        let unit = test.spec.x.unit.label();
        let mut out = vec![Vec::with_capacity(test.x.len()); test.curves.len()];
        for &x in &test.x {
            if x < lo - tol || x > hi + tol {
                return Err(err(format!(
                    "tests[{t}].path: the simulated {} spans [{}, {}] {unit}, the measured point x = {x} {unit} lies outside: extend the path",
                    test.spec.x.quantity,
                    output::round(lo) + 0.0,
                    output::round(hi) + 0.0
                )));
            }
            let k = xs.partition_point(|v| *v < x).clamp(1, xs.len() - 1);
            let s = ((x - xs[k - 1]) / (xs[k] - xs[k - 1])).clamp(0.0, 1.0);
            for (c, y) in ys.iter().enumerate() {
                out[c].push(y[k - 1] + s * (y[k] - y[k - 1]));
            }
        }
        Ok(out)
    }

    /// The residual vector `r(θ)` (module doc), test by test, curve by curve, point by point.
    pub fn residuals(&self, theta: &[f64]) -> Result<Vec<f64>, EvalError> {
        let fitted = self.fitted(theta)?;
        Ok(self.residuals_of(&fitted))
    }

    /// The residuals of simulated curves `fitted` ([`Problem::fitted`]).
    pub fn residuals_of(&self, fitted: &[Vec<Vec<f64>>]) -> Vec<f64> {
        let mut r = Vec::with_capacity(self.residual_count());
        for (test, sim) in self.tests.iter().zip(fitted) {
            let w = test.spec.weight.sqrt();
            for (curve, y_sim) in test.curves.iter().zip(sim) {
                r.extend(curve.y.iter().zip(y_sim).map(|(y, ys)| w * (ys - y) / curve.scale));
            }
        }
        r
    }

    /// The finite-difference step `h_j` of parameter `j` at `theta_j` (module doc).
    pub fn step(&self, j: usize, theta_j: f64) -> f64 {
        let p = &self.parameters[j];
        self.solver.finite_difference_step * theta_j.abs().max(1e-3 * (p.max - p.min))
    }

    /// The Jacobian `∂r/∂θ` (m × n) at `theta` by finite differences (module doc): central,
    /// or one-sided inside the bounds (also where one side cannot be evaluated).
    pub fn jacobian(&self, theta: &[f64]) -> Result<DMatrix<f64>, EvalError> {
        let m = self.residual_count();
        let mut jac = DMatrix::zeros(m, theta.len());
        let mut r0: Option<Vec<f64>> = None;
        for (j, p) in self.parameters.iter().enumerate() {
            let h = self.step(j, theta[j]);
            let at = |v: f64| {
                let mut th = theta.to_vec();
                th[j] = v;
                self.residuals(&th)
            };
            let up = if theta[j] + h <= p.max { Some(at(theta[j] + h)) } else { None };
            let down = if theta[j] - h >= p.min { Some(at(theta[j] - h)) } else { None };
            let col: Vec<f64> = match (up, down) {
                (Some(Ok(u)), Some(Ok(d))) => u.iter().zip(&d).map(|(u, d)| (u - d) / (2.0 * h)).collect(),
                (Some(Ok(u)), _) => {
                    let r = match &r0 {
                        Some(r) => r,
                        None => r0.insert(self.residuals(theta)?),
                    };
                    u.iter().zip(r).map(|(u, r)| (u - r) / h).collect()
                }
                (_, Some(Ok(d))) => {
                    let r = match &r0 {
                        Some(r) => r,
                        None => r0.insert(self.residuals(theta)?),
                    };
                    r.iter().zip(&d).map(|(r, d)| (r - d) / h).collect()
                }
                (Some(Err(e)), _) | (_, Some(Err(e))) => return Err(e),
                (None, None) => {
                    return Err(EvalError {
                        test: 0,
                        input: true,
                        message: format!(
                            "fit[{j}]: the range [{}, {}] is narrower than the finite-difference step",
                            p.min, p.max
                        ),
                    })
                }
            };
            jac.set_column(j, &DVector::from_vec(col));
        }
        Ok(jac)
    }
}

/// Reads test `t`'s CSV and checks its columns, units, weight.
fn read_test(t: usize, spec: &LabTest, base: &Path) -> Result<Test, FitError> {
    let at = |key: &str| format!("tests[{t}].{key}");
    if !(spec.weight > 0.0 && spec.weight.is_finite()) {
        return Err(FitError::input(at("weight"), format!("must be > 0, got {}", spec.weight)));
    }
    if spec.curves.is_empty() {
        return Err(FitError::input(at("curves"), "must hold at least one measured column"));
    }
    let columns = std::iter::once(("x".to_string(), &spec.x))
        .chain(spec.curves.iter().enumerate().map(|(c, col)| (format!("curves[{c}]"), col)));
    let file = base.join(&spec.data);
    let table = data::Table::read(&file).map_err(FitError::Input)?;
    let mut values: Vec<Vec<f64>> = Vec::new();
    for (key, col) in columns {
        if col.sign != 1.0 && col.sign != -1.0 {
            return Err(FitError::input(at(&format!("{key}.sign")), format!("must be 1 or -1, got {}", col.sign)));
        }
        let k = table.column(&col.column).ok_or_else(|| {
            FitError::input(
                at(&format!("{key}.column")),
                format!("no column `{}` in {} (columns: {})", col.column, file.display(), table.names.join(", ")),
            )
        })?;
        values.push(table.rows.iter().map(|(_, r)| r[k]).collect());
    }
    let x = values.remove(0);
    let curves: Vec<Curve> = spec
        .curves
        .iter()
        .zip(values)
        .enumerate()
        .map(|(c, (column, y))| {
            let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if scale == 0.0 {
                return Err(FitError::input(
                    at(&format!("curves[{c}]")),
                    format!("column `{}` of {} is zero throughout: nothing to fit", column.column, file.display()),
                ));
            }
            Ok(Curve { column: column.clone(), y, scale })
        })
        .collect::<Result<_, _>>()?;
    Ok(Test { spec: spec.clone(), x, curves })
}

/// How the solver ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// Converged: the relative reduction of S or the step fell below the tolerance, or the
    /// residuals are orthogonal to the Jacobian's columns.
    Converged(String),
    /// Not converged: why. The best point so far is reported and written.
    NotConverged(String),
}

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The best parameters found `θ̂`.
    pub theta: Vec<f64>,
    /// How the solver ended.
    pub status: Status,
    /// Jacobian evaluations (Levenberg–Marquardt iterations).
    pub iterations: usize,
    /// Residual evaluations of the solver (each runs every test once).
    pub evaluations: usize,
    /// Wall-clock time of the solver, s.
    pub seconds: f64,
    /// Statistics at `θ̂`.
    pub stats: stats::Statistics,
    /// The simulated curves at `θ̂`.
    pub fitted: Vec<Vec<Vec<f64>>>,
    /// Warnings: parameters at a bound, systematic misfits, trial points the law refused.
    pub warnings: Vec<String>,
}

/// The least-squares problem in the unbounded `u` as the solver sees it. Residuals are
/// evaluated in `set_params`; a trial point that the driver cannot follow gets large
/// residuals ([`FAILED_RESIDUAL`]), so that the trust region shrinks away from it.
struct Solver<'a> {
    problem: &'a Problem,
    u: lm::DVector<f64>,
    r: lm::DVector<f64>,
    best: (Vec<f64>, f64),
    jacobians: Cell<usize>,
    jacobian_error: std::cell::RefCell<Option<String>>,
    failures: usize,
    last_failure: Option<String>,
}

/// Residual given to the solver at a trial point that the material point cannot follow:
/// far above any scaled residual of a curve (those are O(1)).
const FAILED_RESIDUAL: f64 = 1e6;

impl Solver<'_> {
    fn theta(&self, u: &lm::DVector<f64>) -> Vec<f64> {
        self.problem.parameters.iter().zip(u.iter()).map(|(p, u)| p.theta(*u)).collect()
    }
}

impl LeastSquaresProblem<f64, lm::Dyn, lm::Dyn> for Solver<'_> {
    type ResidualStorage = lm::VecStorage<f64, lm::Dyn, lm::U1>;
    type JacobianStorage = lm::VecStorage<f64, lm::Dyn, lm::Dyn>;
    type ParameterStorage = lm::VecStorage<f64, lm::Dyn, lm::U1>;

    fn set_params(&mut self, u: &lm::DVector<f64>) {
        self.u = u.clone();
        let theta = self.theta(u);
        match self.problem.residuals(&theta) {
            Ok(r) => {
                let s: f64 = r.iter().map(|v| v * v).sum();
                if s < self.best.1 {
                    self.best = (theta, s);
                }
                self.r = lm::DVector::from_vec(r);
            }
            Err(e) => {
                self.failures += 1;
                self.last_failure = Some(e.message);
                self.r = lm::DVector::from_element(self.problem.residual_count(), FAILED_RESIDUAL);
            }
        }
    }

    fn params(&self) -> lm::DVector<f64> {
        self.u.clone()
    }

    fn residuals(&self) -> Option<lm::DVector<f64>> {
        Some(self.r.clone())
    }

    fn jacobian(&self) -> Option<lm::DMatrix<f64>> {
        self.jacobians.set(self.jacobians.get() + 1);
        let theta = self.theta(&self.u);
        match self.problem.jacobian(&theta) {
            Ok(j) => {
                let (m, n) = j.shape();
                Some(lm::DMatrix::from_fn(m, n, |i, k| j[(i, k)] * self.problem.parameters[k].dtheta_du(self.u[k])))
            }
            Err(e) => {
                *self.jacobian_error.borrow_mut() = Some(e.message);
                None
            }
        }
    }
}

/// Fits the problem: Levenberg–Marquardt from θ₀, then the statistics at the best point.
pub fn fit(problem: &Problem) -> FitResult {
    let start = Instant::now();
    let theta0 = problem.initial();
    let u0 = lm::DVector::from_iterator(theta0.len(), problem.parameters.iter().zip(&theta0).map(|(p, t)| p.u(*t)));
    let mut solver = Solver {
        problem,
        u: u0.clone(),
        r: lm::DVector::zeros(problem.residual_count()),
        best: (theta0.clone(), f64::INFINITY),
        jacobians: Cell::new(0),
        jacobian_error: Default::default(),
        failures: 0,
        last_failure: None,
    };
    solver.set_params(&u0);
    let s = &problem.solver;
    let (solver, report) = LevenbergMarquardt::new()
        .with_ftol(s.tolerance)
        .with_xtol(s.tolerance)
        .with_gtol(s.tolerance)
        .with_patience(s.max_iterations)
        .minimize(solver);
    let seconds = start.elapsed().as_secs_f64();
    let n = problem.parameters.len();
    let status = match &report.termination {
        TerminationReason::Converged { ftol, xtol } => Status::Converged(
            match (ftol, xtol) {
                (true, true) => "relative reduction of S and relative step below the tolerance",
                (true, false) => "relative reduction of S below the tolerance",
                _ => "relative step below the tolerance",
            }
            .into(),
        ),
        TerminationReason::Orthogonal => Status::Converged("residuals orthogonal to the Jacobian (gradient of S zero)".into()),
        TerminationReason::ResidualsZero => Status::Converged("residuals zero".into()),
        TerminationReason::LostPatience => Status::NotConverged(format!(
            "no convergence within {} residual evaluations (solver.max_iterations = {} per parameter and one)",
            s.max_iterations * (n + 1),
            s.max_iterations
        )),
        TerminationReason::NoImprovementPossible(what) => Status::NotConverged(format!(
            "no further improvement possible in {what} at machine precision (solver.tolerance {} too small for this data?)",
            s.tolerance
        )),
        TerminationReason::User(_) => Status::NotConverged(format!(
            "the Jacobian could not be evaluated: {}",
            solver.jacobian_error.borrow().clone().unwrap_or_default()
        )),
        other => Status::NotConverged(format!("the solver stopped: {other:?}")),
    };
    let theta = solver.best.0.clone();
    let mut warnings = Vec::new();
    let fitted = problem.fitted(&theta).unwrap_or_default();
    let residuals = problem.residuals_of(&fitted);
    let jacobian = problem.jacobian(&theta);
    let stats = stats::Statistics::new(problem, &residuals, jacobian.as_ref().ok());
    if let Err(e) = &jacobian {
        warnings.push(format!(
            "no confidence intervals: the Jacobian at the optimum could not be evaluated: {}",
            e.message
        ));
    }
    if let Some(j) = &stats.undetermined {
        warnings.push(format!(
            "the data cannot determine `{}`: JᵀJ is singular (smallest singular value of J {:.1e} of the largest); fix it or add a test that depends on it",
            problem.parameters[*j].name, stats.condition
        ));
    }
    for (p, v) in problem.parameters.iter().zip(&theta) {
        if p.at_bound(*v) {
            warnings.push(format!(
                "{} = {} ended at its bound [{}, {}]: the bound, not the data, chose it (the curves may lie outside the law's reach)",
                p.name,
                output::round(*v),
                p.min,
                p.max
            ));
        }
    }
    warnings.extend(stats.systematic_misfits(problem));
    if solver.failures > 0 {
        warnings.push(format!(
            "{} trial points could not be followed by the material point and were rejected (last: {})",
            solver.failures,
            solver.last_failure.clone().unwrap_or_default()
        ));
    }
    FitResult {
        theta,
        status,
        iterations: solver.jacobians.get(),
        evaluations: report.number_of_evaluations,
        seconds,
        stats,
        fitted,
        warnings,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound transformation: `θ(u(θ)) = θ` inside the bounds, `∂θ/∂u` against a central
    /// difference, every `u` inside the bounds.
    #[test]
    fn bound_transformation_round_trip_and_derivative() {
        let p = Parameter { name: "friction_angle".into(), min: 15.0, max: 45.0, initial: 30.0 };
        for theta in [15.0, 15.001, 22.5, 30.0, 44.9, 45.0] {
            assert!((p.theta(p.u(theta)) - theta).abs() < 1e-12, "{theta}");
        }
        for u in [-3.0, -1.0, 0.0, 0.4, 1.2, 7.0] {
            let h = 1e-6;
            let fd = (p.theta(u + h) - p.theta(u - h)) / (2.0 * h);
            assert!((fd - p.dtheta_du(u)).abs() < 1e-7 * 15.0, "{u}: {fd} vs {}", p.dtheta_du(u));
            assert!((15.0..=45.0).contains(&p.theta(u)));
        }
        assert!(p.at_bound(15.02) && p.at_bound(44.99) && !p.at_bound(30.0));
    }
}
