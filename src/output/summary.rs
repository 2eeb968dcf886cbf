//! `summary.json`: the run report that a batch user or a script reads instead of parsing
//! the terminal.
//!
//! Written when the run starts (`"status": "running"`, so that an interrupted run still says
//! what it was: case, formulation, thickness) and rewritten when it ends, whether it
//! finished, came to rest or stopped on a step that failed (results so far are kept), or was
//! interrupted, also by a second signal that abandons the step in progress
//! ([`crate::interrupt`]: the report of the last converged step, marked interrupted):
//!
//! ```json
//! {
//!   "case": "collapse_bui2008_quad", "case_file": "/…/cases/collapse_bui2008_quad.json",
//!   "version": "0.1.0", "threads": 2,
//!   "formulation": "plane_strain", "thickness": 1.0,
//!   "status": "at_rest",
//!   "end": { "reason": "at rest (analysis.stop_at_rest) at t = 0.68 s", "time": 0.68, "end_time": 2.0 },
//!   "steps": 781,
//!   "newton": { "iterations": 4711, "step_cuts": 3, "augmentations": 0,
//!               "residual_per_block": { "last": [2.1e-7, 3.0e-9, 1.1e-8], "max": [6.9e-2, 3.0e-5, 2.3e-5] } },
//!   "linear_solver": { "factorisations": 4711, "krylov_solves": 0, "krylov_iterations": 0 },
//!   "wall_time": { "total": 53.1, "search": 1.2, "pattern": 0.4, "assembly": 20.3,
//!                  "factorisation": 25.0, "symbolic": 0.3, "solve": 2.1, "commit": 0.5,
//!                  "output": 1.0, "other": 2.6 },
//!   "memory": { "peak_rss_mb": 61.2, "matrix_nonzeros": 151234, "factor_entries": null },
//!   "monitors": { "runout": 0.416, "height_at_wall": 0.1002 },
//!   "monitor_units": { "runout": "m", "height_at_wall": "m" }
//! }
//! ```
//!
//! `wall_time` is in seconds: the model's phases ([`PhaseTimings`], accumulated over the
//! steps, the failed attempts of cut steps included; `symbolic` is part of `factorisation`),
//! `output` the writing of results, and `other` the rest of `total` (monitors, set-up, the
//! explanation of a failure). `newton` also gives
//! the converged residual norms per block of the monolithic system (soil, interface,
//! structure: the rows of grid, shared and FEM nodes) of the last step and the largest over
//! the run.

use std::path::{Path, PathBuf};

use loam_fem::formulation::Formulation;
use loam_fem::model::PhaseTimings;
use serde::{Deserialize, Serialize};

use crate::model_builder::monitor_unit;
use crate::simulation::Simulation;

/// File name of the report in the output directory.
pub const SUMMARY_FILE: &str = "summary.json";

/// How a run stands or why it ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Started; not ended (or the process was stopped from outside).
    Running,
    /// Reached the end time.
    Finished,
    /// Ended early because the bodies came to rest (`analysis.stop_at_rest`).
    AtRest,
    /// A step failed after all cuts; results up to `end.time` are written.
    Failed,
    /// Writing the results failed.
    OutputError,
    /// Interrupted (SIGINT/SIGTERM) after a converged step; a checkpoint was written.
    Interrupted,
}

/// Why the run ended, and when.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunEndReport {
    /// One line: the end time reached, rest, or the failure with its step and residual.
    pub reason: String,
    /// Time of the last converged state (s).
    pub time: f64,
    /// End time of the case (s).
    pub end_time: f64,
}

/// Newton counters, and the converged residual norms per block of the monolithic system.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NewtonReport {
    /// Newton iterations (linear solves) over the converged steps.
    pub iterations: usize,
    /// Step halvings after failed steps.
    pub step_cuts: usize,
    /// Augmented-Lagrangian updates of contacts (`interfaces[].gap_tolerance`), each
    /// followed by a further Newton solve of its step.
    #[serde(default)]
    pub augmentations: usize,
    /// Converged residual norms (N) per block, of the last step and the largest over the
    /// run: soil (grid nodes), interface (shared nodes), structure (FEM nodes).
    #[serde(default)]
    pub residual_per_block: BlockResiduals,
}

fn blocks(b: loam_fem::convergence::BlockNorms) -> [f64; 3] {
    [b.soil, b.interface, b.structure]
}

/// Converged residual norms per block (see [`NewtonReport`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BlockResiduals {
    /// Of the last converged step: `[soil, interface, structure]`.
    pub last: [f64; 3],
    /// Largest over the converged steps: `[soil, interface, structure]`.
    pub max: [f64; 3],
}

/// Linear-solver counters.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LinearSolverReport {
    /// Numeric factorisations.
    pub factorisations: usize,
    /// Solves with the kept factors of an earlier tangent (`solver.tangent_reuse`).
    #[serde(default)]
    pub reused_factorisations: usize,
    /// Solves done by a Krylov method (GMRES of `symmetric_part_gmres`, or PETSc's).
    pub krylov_solves: usize,
    /// Krylov iterations of those solves (failed ones included).
    pub krylov_iterations: usize,
    /// Saddle-point systems (mixed u–p) solved by LU, after a symmetric indefinite
    /// factorisation that failed or on an unsymmetric matrix (the others by `L B Lᵀ`).
    #[serde(default)]
    pub saddle_point_lu: usize,
    /// Saddle-point systems whose symmetric indefinite factorisation failed.
    #[serde(default)]
    pub ldlt_failures: usize,
    /// Sparsity patterns on which the LU on the symmetric pattern (restricted pivoting) met
    /// a small pivot or an inaccurate solve, so that LU with partial pivoting took over.
    #[serde(default)]
    pub pattern_lu_failures: usize,
    /// PETSc solves in which GAMG did not converge, after which MUMPS's LU took over (the
    /// `petsc` solver without a preconditioner in `solver.petsc_options`).
    #[serde(default)]
    pub gamg_failures: usize,
}

/// Memory of the run (issue 30): what the process held at its peak beside the sizes of the
/// global matrix and its factor, so that a user can see what a larger case will need.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MemoryReport {
    /// Peak resident set size of the process so far (MB; `VmHWM` of `/proc/self/status`;
    /// absent where the system does not report it).
    pub peak_rss_mb: Option<f64>,
    /// Nonzeros of the global matrix of the current sparsity pattern.
    pub matrix_nonzeros: usize,
    /// Entries of the last Cholesky-type factor (`L Lᵀ`, `L D Lᵀ`, `L B Lᵀ`) of the pattern;
    /// absent when the last factorisation was an LU (faer does not report its size).
    pub factor_entries: Option<usize>,
}

impl MemoryReport {
    /// The memory of `sim` now (the peak resident set read from `/proc` when `read_peak`).
    pub fn of(sim: &Simulation, read_peak: bool) -> Self {
        Self {
            peak_rss_mb: if read_peak { peak_rss_mb() } else { None },
            matrix_nonzeros: sim.model.nnz(),
            factor_entries: sim.model.factor_entries(),
        }
    }
}

/// `VmHWM` of `/proc/self/status` in MB.
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Wall time per phase (s).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct WallTimeReport {
    /// From the start of the run loop to its end.
    pub total: f64,
    /// Domains' per-step preparation (point search, projection to the grid).
    pub search: f64,
    /// Sparsity patterns and DOF maps.
    pub pattern: f64,
    /// Element kernels and gather.
    pub assembly: f64,
    /// Of `assembly`: the element kernels of each domain of the model (bodies, structures,
    /// interfaces, walls), by name in model order; the rest of `assembly` is the gather into
    /// the system. Absent in reports of runs before it was measured.
    #[serde(default)]
    pub kernels_by_domain: NamedValues<f64>,
    /// Symbolic and numeric factorisation.
    pub factorisation: f64,
    /// Of `factorisation`: symbolic analyses.
    pub symbolic: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Commit of converged steps (convective phase).
    pub commit: f64,
    /// Writing `monitors.csv` and the VTK files.
    pub output: f64,
    /// The rest of `total`: failed Newton attempts, monitors, set-up.
    pub other: f64,
}

impl WallTimeReport {
    /// The phases of `t`, `output` and the rest of `total`.
    pub fn new(total: f64, t: &PhaseTimings, output: f64) -> Self {
        let accounted = t.search + t.pattern + t.assembly + t.factorisation + t.solve + t.commit + output;
        Self {
            total,
            search: t.search,
            pattern: t.pattern,
            assembly: t.assembly,
            kernels_by_domain: NamedValues::default(),
            factorisation: t.factorisation,
            symbolic: t.symbolic,
            solve: t.solve,
            commit: t.commit,
            output,
            other: (total - accounted).max(0.0),
        }
    }
}

/// The content of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Case name (stem of the case file).
    pub case: String,
    /// The case file, absolute (`loam plot` reads its walls); absent for a case not loaded
    /// from a file.
    pub case_file: Option<PathBuf>,
    /// Loam version.
    pub version: String,
    /// Worker threads (per rank).
    pub threads: usize,
    /// MPI ranks of a distributed run (`docs/distributed.md`; 1 on one process).
    #[serde(default = "one_rank")]
    pub ranks: usize,
    /// `plane_strain`, `plane_stress`, `axisymmetric` or `3d`.
    pub formulation: String,
    /// Out-of-plane thickness of plane problems (m).
    pub thickness: f64,
    /// How the run stands or ended.
    pub status: RunStatus,
    /// Why it ended (absent while running).
    pub end: Option<RunEndReport>,
    /// Converged steps (sub-steps included).
    pub steps: usize,
    /// Newton counters.
    pub newton: NewtonReport,
    /// Linear-solver counters.
    pub linear_solver: LinearSolverReport,
    /// Wall time per phase (s).
    pub wall_time: WallTimeReport,
    /// Memory: the process's peak resident set and the sizes of the linear system.
    #[serde(default)]
    pub memory: MemoryReport,
    /// Monitor values at the last converged state, by name in case order (`null` where not
    /// finite).
    pub monitors: NamedValues<Option<f64>>,
    /// SI unit of each monitor (`m`, `N`, `Pa`, `J`, `1`, …); absent for a monitor whose
    /// `scale` is not ±1 (its unit is the case author's, e.g. `q/(B s_u)`).
    pub monitor_units: NamedValues<String>,
    /// Per background grid attached to a structure (by domain name): the worst quality of
    /// its cells over the run and how its mesh motion was widened.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grid_motion: Vec<GridMotionReport>,
    /// A distributed run: what each rank measured of its kernels, its matrix assembly, the
    /// exchange of the points' state and its share of the blocks, in rank order
    /// (docs/distributed.md); while the run goes on, rank 0's alone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub distributed: Vec<loam_fem::ranks::DistributedStats>,
}

/// How an attached grid followed its structure (`grid_motion` of the summary).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridMotionReport {
    /// The MPM domain (grid).
    pub domain: String,
    /// Smallest corner `det J` of a moved cell over its reference value, over the run (1:
    /// undistorted; the band widens below 0.2).
    pub worst_cell_quality: f64,
    /// The mesh motion's reach after each widening, in order.
    pub widened: Vec<String>,
}

/// Values by name, written as a JSON object in their order (monitors in case order).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedValues<T>(pub Vec<(String, T)>);

impl<T> Default for NamedValues<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<T> NamedValues<T> {
    /// The value of `name`.
    pub fn get(&self, name: &str) -> Option<&T> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }
}

impl<T: Serialize> Serialize for NamedValues<T> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for NamedValues<T> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Visitor<T> {
            type Value = NamedValues<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of named values")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut values = Vec::new();
                while let Some(entry) = map.next_entry::<String, T>()? {
                    values.push(entry);
                }
                Ok(NamedValues(values))
            }
        }
        deserializer.deserialize_map(Visitor(std::marker::PhantomData))
    }
}

/// A time in seconds for a message: six significant digits, no trailing zeros (`0.68 s`).
pub fn seconds(t: f64) -> String {
    let digits = (5 - t.abs().log10().floor().max(-12.0) as i32).clamp(0, 17) as usize;
    let s = format!("{t:.digits$}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
    format!("{s} s")
}

/// The case-file name of a formulation.
pub fn formulation_name(f: Formulation) -> &'static str {
    match f {
        Formulation::PlaneStrain => "plane_strain",
        Formulation::PlaneStress => "plane_stress",
        Formulation::Axisymmetric => "axisymmetric",
        Formulation::ThreeD => "3d",
    }
}

/// The `ranks` of a report written before there were ranks.
fn one_rank() -> usize {
    1
}

impl RunSummary {
    /// The report of `sim` as it stands, with `status` and the wall times measured so far.
    pub fn of(sim: &Simulation, status: RunStatus, wall_time: WallTimeReport) -> Self {
        Self::build(sim, status, wall_time, true)
    }

    /// [`RunSummary::of`] without the process's peak memory (`memory.peak_rss_mb` absent,
    /// read by [`RunSummary::read_peak_memory`] when the report is written): the report the
    /// run loop keeps after every step for a second signal ([`crate::interrupt`]), where a
    /// read of `/proc/self/status` per step would be most of a small step's fixed cost.
    pub fn snapshot(sim: &Simulation, status: RunStatus, wall_time: WallTimeReport) -> Self {
        Self::build(sim, status, wall_time, false)
    }

    /// Reads the process's peak resident set now into `memory.peak_rss_mb`.
    pub fn read_peak_memory(&mut self) {
        self.memory.peak_rss_mb = peak_rss_mb();
    }

    fn build(sim: &Simulation, status: RunStatus, mut wall_time: WallTimeReport, read_peak: bool) -> Self {
        let solver = sim.model.solver_timings();
        let mut kernels: Vec<(String, f64)> = Vec::new();
        for (d, seconds) in sim.model.domains.iter().zip(sim.model.kernel_seconds_by_domain()) {
            match kernels.iter_mut().find(|(name, _)| name == d.name()) {
                Some((_, sum)) => *sum += seconds,
                None => kernels.push((d.name().to_string(), seconds)),
            }
        }
        wall_time.kernels_by_domain = NamedValues(kernels);
        let monitors = NamedValues(
            sim.monitors
                .iter()
                .zip(sim.monitor_values_for_report())
                .map(|(m, v)| (m.name.clone(), v.is_finite().then_some(v)))
                .collect(),
        );
        let monitor_units = NamedValues(
            sim.monitors
                .iter()
                .filter(|m| m.scale.abs() == 1.0)
                .map(|m| (m.name.clone(), monitor_unit(&m.kind).to_string()))
                .collect(),
        );
        Self {
            case: sim.case.name.clone(),
            case_file: sim.case_file.clone(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            threads: rayon::current_num_threads(),
            ranks: sim.model.settings.ranks.size(),
            formulation: formulation_name(sim.case.formulation).to_string(),
            thickness: sim.case.thickness,
            status,
            end: None,
            steps: sim.stats.steps,
            newton: NewtonReport {
                iterations: sim.stats.iterations,
                step_cuts: sim.stats.cuts,
                augmentations: sim.stats.augmentations,
                residual_per_block: BlockResiduals {
                    last: blocks(sim.stats.last_block_residuals),
                    max: blocks(sim.stats.max_block_residuals),
                },
            },
            linear_solver: LinearSolverReport {
                factorisations: solver.factorisations,
                reused_factorisations: solver.reused_factors,
                krylov_solves: solver.krylov_solves,
                krylov_iterations: solver.krylov_iterations,
                saddle_point_lu: solver.saddle_point_lu,
                ldlt_failures: solver.ldlt_failures,
                pattern_lu_failures: solver.pattern_lu_failures,
                gamg_failures: solver.gamg_failures,
            },
            wall_time,
            memory: MemoryReport::of(sim, read_peak),
            monitors,
            monitor_units,
            grid_motion: sim
                .model
                .domains
                .iter()
                .filter_map(|d| {
                    d.grid_motion().map(|(worst_cell_quality, widened)| GridMotionReport {
                        domain: d.name().to_string(),
                        worst_cell_quality,
                        widened,
                    })
                })
                .collect(),
            distributed: if sim.model.settings.ranks.is_distributed() {
                let mut stats = loam_fem::ranks::DistributedStats::default();
                loam_fem::ranks::with_stats(|s| stats = *s);
                vec![stats]
            } else {
                Vec::new()
            },
        }
    }

    /// Writes the report to `dir/summary.json` (to a temporary file, then renamed, so that a
    /// reader never sees half a report).
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let path = dir.join(SUMMARY_FILE);
        let tmp = dir.join(format!("{SUMMARY_FILE}.tmp"));
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(&tmp, text + "\n")?;
        std::fs::rename(&tmp, &path)
    }

    /// Reads `dir/summary.json`.
    pub fn read(dir: &Path) -> Result<Self, String> {
        let path = dir.join(SUMMARY_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_values_keep_their_order() {
        let m = NamedValues(vec![("z".to_string(), Some(1.5)), ("a".into(), None), ("m".into(), Some(-2.0))]);
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(text, r#"{"z":1.5,"a":null,"m":-2.0}"#);
        let back: NamedValues<Option<f64>> = serde_json::from_str(&text).unwrap();
        assert_eq!(back, m);
        assert_eq!(back.get("m"), Some(&Some(-2.0)));
    }

    #[test]
    fn seconds_are_short() {
        assert_eq!(seconds(1.0), "1 s");
        assert_eq!(seconds(0.6800000000000005), "0.68 s");
        assert_eq!(seconds(2.5e-4), "0.00025 s");
        assert_eq!(seconds(1234.5678), "1234.57 s");
        assert_eq!(seconds(0.0), "0 s");
    }
}
