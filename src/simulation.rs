//! The steppable simulation: one API for the CLI run loop, tests and the FMU.
//!
//! A [`Simulation`] advances a loaded case step by step to any requested time, using the
//! case's step and halving it (up to `analysis.max_step_cuts` times) when Newton fails;
//! results do not depend on who drives it.

use std::path::{Path, PathBuf};

use loam_coupling::interface::InterfaceSummary;
use loam_fem::amplitude::Amplitude;
use loam_fem::convergence::BlockNorms;
use loam_fem::model::{Model, PhaseTimings, StepError};
use loam_fem::newton::TangentReuse;

use crate::case::{Case, CaseError};
use crate::model_builder::{build_model, InputSlot, ModelInput, ModelOutput};
use crate::monitor::Monitor;

/// Why a run stopped early. A failure before the first step (the consistent initial
/// acceleration, `time_step` 0) says so rather than quoting a step of length 0.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error("{}: {source}", self.when())]
pub struct RunError {
    /// Index of the step that failed (1-based).
    pub step: usize,
    /// Time of the last converged state.
    pub time: f64,
    /// Smallest step tried.
    pub time_step: f64,
    /// Step cuts tried.
    pub cuts: u32,
    /// The last failure.
    pub source: StepError,
}

impl RunError {
    /// Where the run stopped, for the message.
    fn when(&self) -> String {
        if self.time_step == 0.0 {
            format!(
                "step {} (t = {:.6e} s, computing the initial acceleration before the first step)",
                self.step, self.time
            )
        } else {
            format!(
                "step {} (t = {:.6e} s, Δt = {:.3e} s after {} cuts)",
                self.step, self.time, self.time_step, self.cuts
            )
        }
    }
}

/// A rejected [`Simulation::set_input`].
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum InputError {
    /// No input of that name in `fmu.inputs`.
    #[error("no input named '{name}' (the case's fmu.inputs declare: {declared})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The declared input names, comma-separated.
        declared: String,
    },
    /// NaN or infinite value.
    #[error("input '{name}' must be finite, got {value}")]
    NotFinite {
        /// Input name.
        name: String,
        /// The value.
        value: f64,
    },
}

/// Counters of a run.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunStats {
    /// Converged steps (sub-steps included).
    pub steps: usize,
    /// Newton iterations (linear solves).
    pub iterations: usize,
    /// Step cuts after failures.
    pub cuts: usize,
    /// Augmented-Lagrangian updates (each a further Newton solve of its step).
    #[serde(default)]
    pub augmentations: usize,
    /// Accumulated phase timings.
    pub timings: PhaseTimings,
    /// Largest converged residual per block (soil, interface, structure) over the run.
    pub max_block_residuals: BlockNorms,
    /// Converged residual per block of the last step.
    pub last_block_residuals: BlockNorms,
}

/// What one call to [`Simulation::step`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepSummary {
    /// Newton iterations summed over sub-steps.
    pub iterations: usize,
    /// Sub-steps taken (1 without cuts).
    pub substeps: usize,
    /// Final residual norm of the last sub-step.
    pub residual: f64,
    /// Newton iterations of the last sub-step.
    pub last_iterations: usize,
    /// Of those, the iterations with a new tangent ([`loam_fem::model::StepReport::tangents`]).
    pub last_tangents: usize,
    /// Length of the last sub-step (s).
    pub last_time_step: f64,
    /// Converged residual per block (soil, interface, structure) of the last sub-step.
    pub block_residual: BlockNorms,
    /// Local time-integration error of the last sub-step.
    pub time_error: loam_fem::model::TimeError,
}

/// A case being run.
pub struct Simulation {
    /// The case as loaded.
    pub case: Case,
    /// The case's file, canonical (`None` where it cannot be resolved, e.g. a case not read
    /// from a file), as `summary.json` reports it.
    pub case_file: Option<PathBuf>,
    /// The model.
    pub model: Model,
    /// Monitors in case order.
    pub monitors: Vec<Monitor>,
    /// Steps completed (of the case's step size).
    pub step: usize,
    /// Counters.
    pub stats: RunStats,
    /// Whether the consistent initial acceleration has been computed (at the first step,
    /// so that inputs set before it, e.g. in FMI initialisation mode, are taken into account).
    initialised: bool,
    /// Named inputs (`fmu.inputs`) in declaration order.
    pub inputs: Vec<ModelInput>,
    /// Value of each input while set (`None`: the target's own amplitude applies).
    pub input_values: Vec<Option<f64>>,
    /// Named outputs (`fmu.outputs`, or every monitor) in declaration order.
    pub outputs: Vec<ModelOutput>,
    /// The interfaces between soil and structures.
    pub interfaces: Vec<InterfaceSummary>,
    /// The rigid domains (what `loam check` reports).
    pub rigid_bodies: Vec<crate::model_builder::RigidSummary>,
    /// Length of the next step taken by [`Simulation::step`] (the case's `time_step`, or
    /// what adaptive step control made of it).
    pub time_step: f64,
    /// Largest total kinetic energy seen (for `analysis.stop_at_rest`).
    peak_kinetic_energy: f64,
    /// Since when the kinetic energy has stayed below the rest threshold.
    rest_since: Option<f64>,
    /// Whether `analysis.stop_at_rest` has ended the run.
    pub at_rest: bool,
    /// The monitors' values of their last evaluation ([`Simulation::monitor_values`]).
    last_monitor_values: std::sync::Mutex<Vec<f64>>,
}

/// What a [`Simulation`] carries from step to step beside the model: counters and step
/// control, for checkpoints.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SimulationState {
    /// Steps completed.
    pub step: usize,
    /// Counters.
    pub stats: RunStats,
    /// Whether the initial acceleration has been computed.
    pub initialised: bool,
    /// Values of the inputs, while set.
    pub input_values: Vec<Option<f64>>,
    /// Length of the next step.
    pub time_step: f64,
    /// Largest kinetic energy so far.
    pub peak_kinetic_energy: f64,
    /// Since when the kinetic energy has stayed below the rest threshold.
    pub rest_since: Option<f64>,
    /// Whether the rest criterion ended the run.
    pub at_rest: bool,
}

impl Simulation {
    /// The simulation's state beside the model ([`Simulation::restore_state`]).
    pub fn save_state(&self) -> SimulationState {
        SimulationState {
            step: self.step,
            stats: self.stats.clone(),
            initialised: self.initialised,
            input_values: self.input_values.clone(),
            time_step: self.time_step,
            peak_kinetic_energy: self.peak_kinetic_energy,
            rest_since: self.rest_since,
            at_rest: self.at_rest,
        }
    }

    /// Restores a state of [`Simulation::save_state`] and the model's into a simulation
    /// built from the same case (inputs set again to their saved values).
    pub fn restore_state(&mut self, state: SimulationState, model: loam_fem::model::ModelState) -> Result<(), String> {
        if state.input_values.len() != self.inputs.len() {
            return Err(format!("{} inputs saved, the case has {}", state.input_values.len(), self.inputs.len()));
        }
        self.model.restore_state(model)?;
        for (k, v) in state.input_values.iter().enumerate() {
            if let Some(v) = v {
                self.set_input_at(k, *v).map_err(|e| e.to_string())?;
            }
        }
        self.step = state.step;
        self.stats = state.stats;
        self.initialised = state.initialised;
        self.time_step = state.time_step;
        self.peak_kinetic_energy = state.peak_kinetic_energy;
        self.rest_since = state.rest_since;
        self.at_rest = state.at_rest;
        Ok(())
    }

    /// Loads, checks and builds a case file.
    pub fn from_file(path: &Path) -> Result<Self, CaseError> {
        Self::new(Case::load(path)?)
    }

    /// Checks and builds a parsed case.
    pub fn new(case: Case) -> Result<Self, CaseError> {
        let built = build_model(&case)?;
        let case_time_step = case.analysis.time_step;
        let case_file = std::fs::canonicalize(case.directory.join(format!("{}.json", case.name))).ok();
        Ok(Self {
            case,
            case_file,
            model: built.model,
            monitors: built.monitors,
            step: 0,
            stats: RunStats::default(),
            initialised: false,
            input_values: vec![None; built.inputs.len()],
            inputs: built.inputs,
            outputs: built.outputs,
            interfaces: built.interfaces,
            rigid_bodies: built.rigid_bodies,
            time_step: case_time_step,
            peak_kinetic_energy: 0.0,
            rest_since: None,
            at_rest: false,
            last_monitor_values: Default::default(),
        })
    }

    /// Rebuilds the model from the stored case: time 0, inputs unset, counters cleared.
    pub fn reset(&mut self) -> Result<(), CaseError> {
        *self = Self::new(self.case.clone())?;
        Ok(())
    }

    /// Names of the inputs (`fmu.inputs`), in declaration order.
    pub fn input_names(&self) -> Vec<&str> {
        self.inputs.iter().map(|i| i.name.as_str()).collect()
    }

    /// Sets input `name` to `value`: from the next step on, `value` replaces the amplitude
    /// factor of the input's target (load, boundary condition or gravity) and holds until
    /// the next call. Rejects unknown names and NaN or infinite values, leaving the state
    /// unchanged.
    pub fn set_input(&mut self, name: &str, value: f64) -> Result<(), InputError> {
        let k = self
            .inputs
            .iter()
            .position(|i| i.name == name)
            .ok_or_else(|| InputError::Unknown { name: name.to_string(), declared: self.input_names().join(", ") })?;
        self.set_input_at(k, value)
    }

    /// [`Simulation::set_input`] by position in [`Simulation::input_names`].
    ///
    /// # Panics
    /// If `k` is out of range.
    pub fn set_input_at(&mut self, k: usize, value: f64) -> Result<(), InputError> {
        if !value.is_finite() {
            return Err(InputError::NotFinite { name: self.inputs[k].name.clone(), value });
        }
        let amplitude = Amplitude::Constant(value);
        match self.inputs[k].slot {
            InputSlot::Load(i) => self.model.loads[i].amplitude = amplitude,
            InputSlot::Constraint(i) => self.model.constraints[i].amplitude = amplitude,
            InputSlot::Gravity => self.model.gravity.1 = amplitude,
        }
        self.input_values[k] = Some(value);
        Ok(())
    }

    /// Current value of input `k`: the value last set, or else its target's amplitude at
    /// the committed time.
    pub fn input_value_at(&self, k: usize) -> f64 {
        self.input_values[k].unwrap_or_else(|| {
            let t = self.time();
            match self.inputs[k].slot {
                InputSlot::Load(i) => self.model.loads[i].amplitude.at(t),
                InputSlot::Constraint(i) => self.model.constraints[i].amplitude.at(t),
                InputSlot::Gravity => self.model.gravity.1.at(t),
            }
        })
    }

    /// Values of the outputs at the committed state, in declaration order.
    pub fn output_values(&self) -> Vec<f64> {
        self.outputs.iter().map(|o| self.monitors[o.monitor].evaluate(&self.model)).collect()
    }

    /// Time of the committed state.
    pub fn time(&self) -> f64 {
        self.model.time
    }

    /// End time of the case.
    pub fn end_time(&self) -> f64 {
        self.case.analysis.end_time
    }

    /// Whether the end time has been reached, or the bodies came to rest
    /// (`analysis.stop_at_rest`).
    pub fn finished(&self) -> bool {
        self.at_rest || self.time() >= self.end_time() - 1e-9 * self.case.analysis.time_step
    }

    /// Number of steps the case takes (with adaptive steps: at the first step's length).
    pub fn total_steps(&self) -> usize {
        (self.end_time() / self.case.analysis.time_step - 1e-9).ceil() as usize
    }

    /// Whether the model couples soil and structures (its Newton log has several blocks).
    pub fn is_coupled(&self) -> bool {
        !self.interfaces.is_empty()
    }

    /// Monitor names, in column order.
    pub fn monitor_names(&self) -> Vec<&str> {
        self.monitors.iter().map(|m| m.name.as_str()).collect()
    }

    /// Monitor values at the committed state.
    ///
    /// Where the model's points are distributed over ranks this is a collective (every rank
    /// evaluates the monitors at the same steps: the results writers do).
    pub fn monitor_values(&self) -> Vec<f64> {
        let values: Vec<f64> = self.monitors.iter().map(|m| m.evaluate(&self.model)).collect();
        self.last_monitor_values.lock().unwrap_or_else(|e| e.into_inner()).clone_from(&values);
        values
    }

    /// The monitors' values for a report: evaluated now, or, where the model's points are
    /// distributed (evaluating them is then a collective that only the results writers make),
    /// those of their last evaluation (none before the first).
    pub fn monitor_values_for_report(&self) -> Vec<f64> {
        if self.model.has_distributed_points() {
            self.last_monitor_values.lock().unwrap_or_else(|e| e.into_inner()).clone()
        } else {
            self.monitor_values()
        }
    }

    /// One step of length [`Simulation::time_step`] (shortened to land on the end time);
    /// then adaptive step control chooses the next length and the rest criterion is checked.
    pub fn step(&mut self) -> Result<StepSummary, RunError> {
        self.step_observed(&mut |_| {})
    }

    /// [`Simulation::step`], calling `on_substep` after every converged sub-step of a cut
    /// step that is not its last (each is a step of its own: [`Simulation::step`] counts
    /// it), so that a caller can write its results before the next sub-step is tried.
    pub fn step_observed(&mut self, on_substep: &mut (dyn FnMut(&Simulation) + Send)) -> Result<StepSummary, RunError> {
        let mut target = (self.time() + self.time_step).min(self.end_time());
        if let Some(t) = self.next_output_time() {
            target = target.min(t);
        }
        let shortened = target < self.time() + self.time_step;
        let summary = in_pool(|| self.advance_step_to_here(target, on_substep))?;
        if let Some(adaptive) = self.case.analysis.adaptive {
            if !(shortened && summary.substeps == 1) {
                // Newton iterations with a new tangent: all of them under full Newton; under
                // modified Newton the cheap ones with kept factors do not shorten the step
                let k = summary.last_tangents.max(1) as f64;
                let by_iterations = (adaptive.target_iterations as f64 / k).sqrt();
                let mut factor = match adaptive.error_tolerance {
                    // the local error sets the step (cubic in Δt); the iterations only cap it
                    Some(tolerance) => {
                        let error = summary.time_error.rms;
                        let by_error = if error > 0.0 { 0.9 * (tolerance / error).cbrt() } else { adaptive.growth };
                        if by_iterations < 1.0 {
                            by_error.min(by_iterations)
                        } else {
                            by_error
                        }
                    }
                    None => by_iterations,
                }
                .clamp(0.5, adaptive.growth);
                // under modified Newton a step of the same length keeps the factors valid into
                // the next step: changes within ±20 % are not made
                if self.case.solver.tangent_reuse == TangentReuse::Auto && (0.8..=1.25).contains(&factor) {
                    factor = 1.0;
                }
                self.time_step =
                    (summary.last_time_step * factor).clamp(adaptive.min_time_step, adaptive.max_time_step);
            }
        }
        self.check_rest();
        Ok(summary)
    }

    /// The first of `output.times` after the committed time, on which [`Simulation::step`]
    /// lands.
    pub fn next_output_time(&self) -> Option<f64> {
        let eps = 1e-9 * self.case.analysis.time_step;
        self.case.output.times.iter().copied().find(|&t| t > self.time() + eps)
    }

    /// Whether the committed time is one of `output.times` (within 1e-9 of the case's step).
    pub fn at_output_time(&self) -> bool {
        let eps = 1e-9 * self.case.analysis.time_step;
        self.case.output.times.iter().any(|&t| (t - self.time()).abs() <= eps)
    }

    /// `analysis.stop_at_rest`: the kinetic energy has stayed below its threshold long enough.
    fn check_rest(&mut self) {
        let Some(rest) = self.case.analysis.stop_at_rest else { return };
        let kinetic = self.model.kinetic_energy();
        self.peak_kinetic_energy = self.peak_kinetic_energy.max(kinetic);
        let t = self.time();
        if t >= rest.min_time && kinetic <= rest.kinetic_energy_ratio * self.peak_kinetic_energy {
            let since = *self.rest_since.get_or_insert(t);
            self.at_rest = t - since >= rest.duration;
        } else {
            self.rest_since = None;
        }
    }

    /// Advances to `target` (> current time) in one step, cutting it on failure (every
    /// converged sub-step counts as a step). Runs on Loam's thread pool (`in_pool`).
    pub fn advance_step_to(&mut self, target: f64) -> Result<StepSummary, RunError> {
        in_pool(|| self.advance_step_to_here(target, &mut |_| {}))
    }

    fn advance_step_to_here(
        &mut self,
        target: f64,
        on_substep: &mut (dyn FnMut(&Simulation) + Send),
    ) -> Result<StepSummary, RunError> {
        if !self.initialised {
            self.model.initialise_acceleration().map_err(|source| RunError {
                step: self.step + 1,
                time: self.time(),
                time_step: 0.0,
                cuts: 0,
                source,
            })?;
            self.initialised = true;
        }
        let mut dt = target - self.time();
        let mut cuts = 0u32;
        let mut summary = StepSummary::default();
        let eps = 1e-12 * self.case.analysis.time_step;
        while self.time() < target - eps {
            let h = dt.min(target - self.time());
            match self.model.solve_step(h) {
                Ok(report) => {
                    summary.iterations += report.iterations;
                    summary.substeps += 1;
                    summary.residual = report.residuals.last().copied().unwrap_or(0.0);
                    summary.last_iterations = report.iterations;
                    summary.last_tangents = report.tangents;
                    summary.last_time_step = h;
                    summary.block_residual = report.block_residuals.last().copied().unwrap_or_default();
                    summary.time_error = report.time_error;
                    self.stats.max_block_residuals = self.stats.max_block_residuals.max(summary.block_residual);
                    self.stats.last_block_residuals = summary.block_residual;
                    self.stats.steps += 1;
                    self.stats.iterations += report.iterations;
                    self.stats.augmentations += report.augmentations;
                    self.stats.timings += report.timings;
                    if self.time() < target - eps {
                        // a converged sub-step of a cut step: a step of its own
                        self.step += 1;
                        on_substep(self);
                    }
                }
                Err(source) => {
                    self.stats.timings += self.model.take_failed_step_timings();
                    // fixed steps: at most `max_step_cuts` halvings; adaptive: down to
                    // `min_time_step`; none where a shorter step cannot help
                    let exhausted = !source.is_retryable()
                        || match self.case.analysis.adaptive {
                            Some(a) => h / 2.0 < a.min_time_step * (1.0 - 1e-9),
                            None => cuts >= self.case.analysis.max_step_cuts,
                        };
                    if exhausted {
                        return Err(RunError { step: self.step + 1, time: self.time(), time_step: h, cuts, source });
                    }
                    cuts += 1;
                    self.stats.cuts += 1;
                    dt = h / 2.0;
                }
            }
        }
        self.step += 1;
        Ok(summary)
    }

    /// Advances to time `t` with the case's step size (the last step shortened to land on
    /// `t`). Steps end where [`Simulation::step`]'s do (`time + Δt`, cut at the end time)
    /// whenever `t` lies on that grid within 1e-9 Δt, so that a driver stepping by
    /// multiples of Δt (an FMU's communication steps) reproduces a CLI run exactly.
    pub fn advance_to(&mut self, t: f64) -> Result<(), RunError> {
        let dt = self.case.analysis.time_step;
        let eps = 1e-9 * dt;
        while self.time() < t - eps {
            let mut target = self.time() + dt;
            if self.time() < self.end_time() - eps {
                target = target.min(self.end_time());
            }
            if target > t + eps {
                target = t;
            }
            self.advance_step_to(target)?;
        }
        Ok(())
    }
}

/// Runs `op` on a thread of a rayon pool. The parallel loops of a step called from a thread
/// outside every pool (a test, an FMU's host) each hand their work to the global pool and
/// block until it is done, and the workers fall asleep between the many short loops of an
/// iteration: measured on the footing of benchmark 11 (h = B/10, 2 threads), 55.9 s outside a
/// pool against 17.0 s inside one. Called from a pool's thread (`loam run` installs one with
/// its `--threads`), `op` runs where it is; otherwise on a pool of Loam's own, one thread per
/// core, made once (or, if it cannot be made, right here).
fn in_pool<R: Send>(op: impl FnOnce() -> R + Send) -> R {
    static POOL: std::sync::OnceLock<Option<rayon::ThreadPool>> = std::sync::OnceLock::new();
    if rayon::current_thread_index().is_some() {
        return op();
    }
    match POOL.get_or_init(|| rayon::ThreadPoolBuilder::new().build().ok()) {
        Some(pool) => pool.install(op),
        None => op(),
    }
}
