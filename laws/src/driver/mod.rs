//! Material-point test driver: one integration point of any law driven along a laboratory
//! path (drained/undrained triaxial compression or extension, oedometer, isotropic
//! compression, simple shear, or a user table of strain increments), read from a JSON path
//! file ([`spec`]) and written as `path.csv`.
//!
//! **Mixed control.** Each step prescribes some components of `F` and some diagonal
//! components of the Cauchy stress `σ = P Fᵀ/J`; the unknown diagonal components `F_aa`
//! are found by a local Newton iteration with the Jacobian
//! `∂σ_aa/∂F_bb = (Σ_k A_{ak,bb} F_ak + P_ab δ_ab)/J − σ_aa F⁻¹_bb`
//! built from the law's consistent tangent `A = ∂P/∂F`. The history is committed (copied)
//! only after each step has converged, exactly as a finite-element code does.
//!
//! **Output** (`path.csv`, one row per step, row 0 = start of the stage): `step`,
//! `axial_strain` (`ε_yy`), `volumetric_strain` (`ln J`), `shear_strain`
//! (`ε_q = √(2/3) ‖dev ε‖`), `gamma_xy` (`2 ε_xy`), all Hencky strains `ε = ½ ln(ΔF ΔFᵀ)` of
//! `ΔF = F F₀⁻¹` measured from the start of the stage (after consolidation) and extension
//! positive; `J = det F`; `p = −tr σ/3` (compression positive), `q = √(3 J₂)`;
//! `sigma_xx … sigma_xz` (Cauchy, Pa, tension positive); then the law's state variables.

pub mod spec;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::Matrix3;
use thiserror::Error;

use crate::spectral::Spectral;
use crate::{idx, ConstitutiveLaw, Kinematics, LawError, ParameterError, TangentRequest};
pub use spec::{Drainage, InitialStress, Loading, PathFile, PathSpec};

/// A failure of the material-point driver. `Display` is a one-line message.
#[derive(Debug, Error)]
pub enum DriverError {
    /// The path file could not be read.
    #[error("cannot read {}: {source}", file.display())]
    Read {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The output could not be written.
    #[error("cannot write {}: {source}", file.display())]
    Write {
        /// The file or directory.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Malformed JSON, a missing or unknown key, or a value outside its range.
    #[error("{json_path}: {problem}")]
    Input {
        /// JSON path of the offending value, e.g. `path.steps`.
        json_path: String,
        /// What is wrong with it.
        problem: String,
    },
    /// The law failed at a step.
    #[error("step {step}: {source}")]
    Law {
        /// Step of the stage (consolidation steps are numbered 0).
        step: usize,
        /// The law's error.
        source: LawError,
    },
    /// The mixed stress/strain control did not converge.
    #[error("step {step}: mixed stress/strain control did not converge (residual {residual:.3e} Pa)")]
    ControlNotConverged {
        /// Step of the stage.
        step: usize,
        /// Largest stress residual left, in Pa.
        residual: f64,
    },
}

impl DriverError {
    fn input(json_path: impl Into<String>, problem: impl Into<String>) -> Self {
        Self::Input { json_path: json_path.into(), problem: problem.into() }
    }
}

impl From<ParameterError> for DriverError {
    fn from(e: ParameterError) -> Self {
        Self::input(format!("material.{}", e.parameter), e.problem)
    }
}

/// The table of a driven path: column names and one row per step.
#[derive(Debug, Clone)]
pub struct PathTable {
    /// Column names (see the module doc).
    pub columns: Vec<String>,
    /// Rows of values, in column order.
    pub rows: Vec<Vec<f64>>,
}

impl PathTable {
    /// The values of one column, if it exists.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.columns.iter().position(|n| n == name)?;
        Some(self.rows.iter().map(|r| r[c]).collect())
    }

    /// The table as CSV text.
    pub fn to_csv(&self) -> String {
        let mut s = self.columns.join(",");
        s.push('\n');
        for row in &self.rows {
            for (i, v) in row.iter().enumerate() {
                if i > 0 {
                    s.push(',');
                }
                if i == 0 {
                    let _ = write!(s, "{}", *v as usize);
                } else {
                    let _ = write!(s, "{v:e}");
                }
            }
            s.push('\n');
        }
        s
    }
}

/// What a driven path produced.
#[derive(Debug, Clone)]
pub struct PathSummary {
    /// Name of the law.
    pub law: &'static str,
    /// The path file's description.
    pub description: String,
    /// Number of rows written (steps of the stage + the initial row).
    pub rows: usize,
    /// Largest deviator stress q over the path, in Pa.
    pub peak_q: f64,
    /// Final mean stress p (compression positive), in Pa.
    pub final_p: f64,
    /// Final deviator stress q, in Pa.
    pub final_q: f64,
    /// The CSV file written.
    pub csv: PathBuf,
}

/// Parses a path file's text; errors name the JSON path of the offending value.
pub fn parse_path_file(text: &str) -> Result<PathFile, DriverError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        DriverError::input(if path.is_empty() { ".".to_string() } else { path }, e.into_inner().to_string())
    })
}

/// Largest path file read by [`run_path_file`]: 16 MiB (a table of 100 000 strain
/// increments is about 10 MB).
pub const MAX_PATH_FILE_BYTES: u64 = 16 << 20;

/// Most steps of a path (`path.steps`, or rows of `path.increments`): a million steps of one
/// material point is beyond any laboratory test, and the table of results is kept in memory
/// (issue 16: `"steps": 1000000000` grew to 8 GB).
pub const MAX_PATH_STEPS: usize = 1_000_000;

/// Reads the path file `path` (at most [`MAX_PATH_FILE_BYTES`]), drives the material point
/// and writes `out_dir/path.csv`.
pub fn run_path_file(path: &Path, out_dir: &Path) -> Result<PathSummary, DriverError> {
    let read_error = |source| DriverError::Read { file: path.into(), source };
    let mut text = String::new();
    let file = std::fs::File::open(path).map_err(read_error)?;
    std::io::Read::read_to_string(&mut std::io::Read::take(file, MAX_PATH_FILE_BYTES + 1), &mut text)
        .map_err(read_error)?;
    if text.len() as u64 > MAX_PATH_FILE_BYTES {
        return Err(read_error(std::io::Error::other(format!(
            "larger than the limit of {} MiB for a path file",
            MAX_PATH_FILE_BYTES >> 20
        ))));
    }
    let file = parse_path_file(&text)?;
    run_parsed_path(&file, out_dir)
}

/// Drives the material point of a parsed path file and writes `out_dir/path.csv`.
pub fn run_parsed_path(file: &PathFile, out_dir: &Path) -> Result<PathSummary, DriverError> {
    let law = file.material.build()?;
    if law.elastic_lame().0.is_infinite() {
        return Err(DriverError::input(
            "material.poisson_ratio",
            "0.5 (incompressible) needs the mixed u–p formulation of a domain; a material point path takes ν < 0.5",
        ));
    }
    let table = run_path(law.as_ref(), file)?;
    std::fs::create_dir_all(out_dir).map_err(|source| DriverError::Write { file: out_dir.into(), source })?;
    let csv = out_dir.join("path.csv");
    std::fs::write(&csv, table.to_csv()).map_err(|source| DriverError::Write { file: csv.clone(), source })?;
    let p = table.column("p").unwrap_or_default();
    let q = table.column("q").unwrap_or_default();
    Ok(PathSummary {
        law: law.name(),
        description: file.description.clone(),
        rows: table.rows.len(),
        peak_q: q.iter().cloned().fold(0.0, f64::max),
        final_p: p.last().copied().unwrap_or(0.0),
        final_q: q.last().copied().unwrap_or(0.0),
        csv,
    })
}

/// Number of steps of a consolidation stage (isotropic or oedometric ramp to the stress
/// the test starts from).
const CONSOLIDATION_STEPS: usize = 20;

/// Maximum Newton iterations of the mixed control per step.
const MAX_CONTROL_ITERATIONS: usize = 50;

/// The mixed control has converged when its largest stress residual is below this fraction
/// of the step's stress scale ([`Point::stress_scale`]).
const CONTROL_TOLERANCE: f64 = 1e-10;

/// Strain whose elastic stress `M ε` bounds the stress scale of the mixed control from
/// below: with [`CONTROL_TOLERANCE`] the residual must reach `1e-14 M`, a strain error of
/// `1e-14`, two orders above the round-off of the stress update (`≈ 1e-16 M`).
const CONTROL_STRAIN_SCALE: f64 = 1e-4;

/// One material point with its committed and trial history.
struct Point<'a> {
    law: &'a dyn ConstitutiveLaw,
    F: Matrix3<f64>,
    sigma: Matrix3<f64>,
    committed: Vec<f64>,
    trial: Vec<f64>,
    dt: f64,
}

/// What one step prescribes: `F` entries not stress-controlled are taken from `F`; the
/// diagonal entries with `Some(σ_aa)` are unknown and carry that Cauchy stress.
struct Control {
    F: Matrix3<f64>,
    stress: [Option<f64>; 3],
}

fn cauchy(P: &Matrix3<f64>, F: &Matrix3<f64>) -> Matrix3<f64> {
    P * F.transpose() / F.determinant()
}

/// Stress residual of a trial `F`: the response, the Cauchy stress and the residual of each
/// group of tied unknowns (mean of the group's `σ_aa` minus the target).
struct Evaluation {
    response: crate::StressResponse,
    sigma: Matrix3<f64>,
    residual: Vec<f64>,
    norm: f64,
}

impl Point<'_> {
    fn evaluate(
        &mut self,
        F: &Matrix3<f64>,
        groups: &[(Vec<usize>, f64)],
        step: usize,
    ) -> Result<Evaluation, DriverError> {
        let kin = Kinematics {
            deformation_gradient: *F,
            previous_deformation_gradient: self.F,
            time_step: self.dt,
            tangent: TangentRequest::Full,
        };
        let response = self
            .law
            .stress_response(&kin, &self.committed, &mut self.trial)
            .map_err(|source| DriverError::Law { step, source })?;
        let sigma = cauchy(&response.first_piola, F);
        let residual: Vec<f64> = groups
            .iter()
            .map(|(members, target)| {
                members.iter().map(|&a| sigma[(a, a)]).sum::<f64>() / members.len() as f64 - target
            })
            .collect();
        let norm = residual.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        Ok(Evaluation { response, sigma, residual, norm })
    }

    /// The stress (Pa) against which the residual of the mixed control is measured: the
    /// largest of the committed stress, the stress targets of `control`, and the law's
    /// constrained modulus `M = λ + 2μ` times [`CONTROL_STRAIN_SCALE`] (the converged
    /// trial stress is added at each check). The last term keeps it from vanishing where
    /// the stresses do (an unconfined test starts at σ = 0: relative to 1 Pa, the round-off
    /// of `M ε`, about `1e-16 M`, could never converge; issue 31).
    fn stress_scale(&self, control: &Control) -> f64 {
        let (lambda, mu) = self.law.elastic_lame();
        let stiffness = (lambda + 2.0 * mu) * CONTROL_STRAIN_SCALE;
        let stiffness = if stiffness.is_finite() { stiffness } else { 0.0 };
        control.stress.iter().flatten().fold(self.sigma.amax(), |m, s| m.max(s.abs())).max(stiffness).max(1.0)
    }

    /// One step under `control`: Newton with backtracking on the unknown diagonal entries of
    /// `F`. Components with equal targets and equal current stretches are tied (they stay
    /// equal, as the lateral stretches of an axisymmetric triaxial specimen): this keeps the
    /// system regular where a perfectly plastic law has a singular tangent (edge of the
    /// Mohr–Coulomb pyramid).
    fn step(&mut self, control: &Control, step: usize) -> Result<(), DriverError> {
        let mut F = control.F;
        let mut groups: Vec<(Vec<usize>, f64)> = Vec::new();
        for a in 0..3 {
            let Some(target) = control.stress[a] else {
                continue;
            };
            F[(a, a)] = self.F[(a, a)];
            let tied = groups.iter_mut().find(|(m, t)| {
                *t == target && (self.F[(m[0], m[0])] - self.F[(a, a)]).abs() <= 1e-12 * self.F[(a, a)].abs()
            });
            match tied {
                Some((members, _)) => members.push(a),
                None => groups.push((vec![a], target)),
            }
        }
        let scale = self.stress_scale(control);
        let mut cur = self.evaluate(&F, &groups, step)?;
        for _ in 0..MAX_CONTROL_ITERATIONS {
            if cur.norm <= CONTROL_TOLERANCE * scale.max(cur.sigma.amax()) {
                self.F = F;
                self.sigma = cur.sigma;
                self.committed.copy_from_slice(&self.trial);
                return Ok(());
            }
            let n = groups.len();
            let j = F.determinant();
            let f_inv =
                F.try_inverse().ok_or(DriverError::Law { step, source: LawError::InvertedDeformation { det_f: j } })?;
            let (A, P, sigma) = (&cur.response.tangent, &cur.response.first_piola, &cur.sigma);
            let dsigma = |a: usize, b: usize| {
                let dp_f: f64 = (0..3).map(|k| A[(idx(a, k), idx(b, b))] * F[(a, k)]).sum();
                let p_term = if a == b { P[(a, b)] } else { 0.0 };
                (dp_f + p_term) / j - sigma[(a, a)] * f_inv[(b, b)]
            };
            let jac = nalgebra::DMatrix::from_fn(n, n, |r, c| {
                let (rows, cols) = (&groups[r].0, &groups[c].0);
                rows.iter().map(|&a| cols.iter().map(|&b| dsigma(a, b)).sum::<f64>()).sum::<f64>() / rows.len() as f64
            });
            let rhs = nalgebra::DVector::from_iterator(n, cur.residual.iter().map(|v| -v));
            let delta = jac.lu().solve(&rhs).ok_or(DriverError::ControlNotConverged { step, residual: cur.norm })?;
            let mut t = 1.0;
            loop {
                let mut cand = F;
                for (g, (members, _)) in groups.iter().enumerate() {
                    for &a in members {
                        cand[(a, a)] += t * delta[g];
                    }
                }
                let next = self.evaluate(&cand, &groups, step)?;
                if next.norm < cur.norm || t < 1e-3 {
                    F = cand;
                    cur = next;
                    break;
                }
                t *= 0.5;
            }
        }
        Err(DriverError::ControlNotConverged { step, residual: cur.norm })
    }
}

fn check(json_path: &str, ok: bool, problem: impl FnOnce() -> String) -> Result<(), DriverError> {
    if ok {
        Ok(())
    } else {
        Err(DriverError::input(json_path, problem()))
    }
}

fn check_steps(steps: usize) -> Result<(), DriverError> {
    check("path.steps", (1..=MAX_PATH_STEPS).contains(&steps), || {
        format!("must lie in [1, {MAX_PATH_STEPS}], got {steps}")
    })
}

fn check_strain(key: &str, value: f64, max: f64) -> Result<(), DriverError> {
    check(&format!("path.{key}"), value > 0.0 && value <= max, || format!("must lie in (0, {max}], got {value}"))
}

fn check_pressure(key: &str, value: f64) -> Result<(), DriverError> {
    check(key, value >= 0.0 && value.is_finite(), || format!("must be >= 0 Pa (compression positive), got {value}"))
}

/// The initial Cauchy stress of a path file.
fn initial_stress(spec: &Option<InitialStress>) -> Result<Option<Matrix3<f64>>, DriverError> {
    Ok(match *spec {
        None => None,
        Some(InitialStress::Isotropic(p)) => {
            check_pressure("initial_stress.isotropic", p)?;
            Some(Matrix3::identity() * -p)
        }
        Some(InitialStress::Geostatic { vertical_stress, k0 }) => {
            check_pressure("initial_stress.geostatic.vertical_stress", vertical_stress)?;
            check("initial_stress.geostatic.k0", k0 > 0.0 && k0.is_finite(), || format!("must be > 0, got {k0}"))?;
            Some(Matrix3::from_diagonal(&nalgebra::Vector3::new(
                -k0 * vertical_stress,
                -vertical_stress,
                -k0 * vertical_stress,
            )))
        }
        Some(InitialStress::Components(s)) => {
            check("initial_stress.components", s.iter().all(|v| v.is_finite()), || "must be finite".into())?;
            Some(Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]))
        }
    })
}

/// Drives `law` along the path of `file` and returns the output table.
pub fn run_path(law: &dyn ConstitutiveLaw, file: &PathFile) -> Result<PathTable, DriverError> {
    let dt = file.time_step.unwrap_or(0.0);
    check("time_step", dt >= 0.0 && dt.is_finite(), || format!("must be >= 0 s, got {dt}"))?;
    let mut committed = vec![0.0; law.state_len()];
    match initial_stress(&file.initial_stress)? {
        Some(s) => law
            .initialise_state_at_stress(&s, &mut committed)
            .map_err(|e| DriverError::input("initial_stress", e.to_string()))?,
        None => law.initialise_state(&mut committed),
    }
    let mut point =
        Point { law, F: Matrix3::identity(), sigma: Matrix3::zeros(), trial: committed.clone(), committed, dt };
    // Stress at rest.
    point.step(&Control { F: Matrix3::identity(), stress: [None; 3] }, 0)?;

    let ramp = |point: &mut Point, target: [Option<f64>; 3]| -> Result<(), DriverError> {
        let start = point.sigma;
        for k in 1..=CONSOLIDATION_STEPS {
            let t = k as f64 / CONSOLIDATION_STEPS as f64;
            let stress = [0, 1, 2].map(|a| target[a].map(|s| start[(a, a)] + t * (s - start[(a, a)])));
            point.step(&Control { F: point.F, stress }, 0)?;
        }
        Ok(())
    };

    let mut steps: Vec<Control> = Vec::new();
    let F0;
    match &file.path {
        &PathSpec::Triaxial { drainage, loading, confining_pressure, axial_strain, steps: n } => {
            check_pressure("path.confining_pressure", confining_pressure)?;
            check_strain("axial_strain", axial_strain, 1.0)?;
            check_steps(n)?;
            ramp(&mut point, [Some(-confining_pressure); 3])?;
            F0 = point.F;
            let sign = if loading == Loading::Compression { -1.0 } else { 1.0 };
            for k in 1..=n {
                let ea = sign * axial_strain * k as f64 / n as f64;
                let mut F = F0;
                F[(1, 1)] = F0[(1, 1)] * ea.exp();
                let stress = match drainage {
                    Drainage::Drained => [Some(-confining_pressure), None, Some(-confining_pressure)],
                    Drainage::Undrained => {
                        F[(0, 0)] = F0[(0, 0)] * (-0.5 * ea).exp();
                        F[(2, 2)] = F0[(2, 2)] * (-0.5 * ea).exp();
                        [None; 3]
                    }
                };
                steps.push(Control { F, stress });
            }
        }
        &PathSpec::Oedometric { axial_strain, steps: n } => {
            check_strain("axial_strain", axial_strain, 1.0)?;
            check_steps(n)?;
            F0 = point.F;
            for k in 1..=n {
                let mut F = F0;
                F[(1, 1)] = F0[(1, 1)] * (-axial_strain * k as f64 / n as f64).exp();
                steps.push(Control { F, stress: [None; 3] });
            }
        }
        &PathSpec::IsotropicCompression { final_pressure, steps: n } => {
            check("path.final_pressure", final_pressure > 0.0 && final_pressure.is_finite(), || {
                format!("must be > 0 Pa (compression positive), got {final_pressure}")
            })?;
            check_steps(n)?;
            F0 = point.F;
            let start = point.sigma;
            for k in 1..=n {
                let t = k as f64 / n as f64;
                let stress = [0, 1, 2].map(|a| Some(start[(a, a)] + t * (-final_pressure - start[(a, a)])));
                steps.push(Control { F: F0, stress });
            }
        }
        &PathSpec::SimpleShear { shear_strain, steps: n, vertical_stress } => {
            check_strain("shear_strain", shear_strain, 10.0)?;
            check_steps(n)?;
            if let Some(v) = vertical_stress {
                check_pressure("path.vertical_stress", v)?;
                ramp(&mut point, [None, Some(-v), None])?;
            }
            F0 = point.F;
            for k in 1..=n {
                let mut dF = Matrix3::identity();
                dF[(0, 1)] = shear_strain * k as f64 / n as f64;
                let F = dF * F0;
                steps.push(Control { F, stress: [None, vertical_stress.map(|v| -v), None] });
            }
        }
        PathSpec::StrainIncrements { increments } => {
            check("path.increments", !increments.is_empty(), || "must hold at least one increment".into())?;
            check("path.increments", increments.len() <= MAX_PATH_STEPS, || {
                format!("must hold at most {MAX_PATH_STEPS} increments, got {}", increments.len())
            })?;
            F0 = point.F;
            let mut F = F0;
            for (k, d) in increments.iter().enumerate() {
                check(&format!("path.increments[{k}]"), d.iter().all(|v| v.is_finite()), || "must be finite".into())?;
                F = (Matrix3::identity() + Matrix3::from_row_slice(d)) * F;
                steps.push(Control { F, stress: [None; 3] });
            }
        }
    }

    let mut columns: Vec<String> = [
        "step",
        "axial_strain",
        "volumetric_strain",
        "shear_strain",
        "gamma_xy",
        "J",
        "p",
        "q",
        "sigma_xx",
        "sigma_yy",
        "sigma_zz",
        "sigma_xy",
        "sigma_yz",
        "sigma_xz",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    columns.extend(law.state_variables().iter().map(|s| s.to_string()));
    let F0_inv = F0
        .try_inverse()
        .ok_or(DriverError::Law { step: 0, source: LawError::InvertedDeformation { det_f: F0.determinant() } })?;
    let mut rows = vec![row(&point, 0, &F0_inv)?];
    for (k, control) in steps.iter().enumerate() {
        point.step(control, k + 1)?;
        rows.push(row(&point, k + 1, &F0_inv)?);
    }
    Ok(PathTable { columns, rows })
}

/// One output row (module doc).
fn row(point: &Point, step: usize, F0_inv: &Matrix3<f64>) -> Result<Vec<f64>, DriverError> {
    let dF = point.F * F0_inv;
    let det = dF.determinant();
    let spec = Spectral::of(&(dF * dF.transpose()))
        .filter(|s| s.values.iter().all(|v| *v > 0.0))
        .ok_or(DriverError::Law { step, source: LawError::InvertedDeformation { det_f: det } })?;
    let eps = spec.compose(spec.values.map(|v| 0.5 * v.ln()));
    let s = &point.sigma;
    let p = -s.trace() / 3.0;
    let dev_norm = |m: &Matrix3<f64>| (m - Matrix3::identity() * (m.trace() / 3.0)).norm();
    let q = (1.5f64).sqrt() * dev_norm(s);
    let mut r = vec![
        step as f64,
        eps[(1, 1)],
        det.ln(),
        (2.0f64 / 3.0).sqrt() * dev_norm(&eps),
        2.0 * eps[(0, 1)],
        point.F.determinant(),
        p,
        q,
        s[(0, 0)],
        s[(1, 1)],
        s[(2, 2)],
        s[(0, 1)],
        s[(1, 2)],
        s[(0, 2)],
    ];
    let mut out = vec![0.0; point.law.state_variables().len()];
    point.law.state_output(&point.committed, &mut out);
    r.extend(out);
    Ok(r)
}
