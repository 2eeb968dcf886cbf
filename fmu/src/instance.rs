//! One FMU instance: a [`Simulation`] of the packaged case, the FMI mode it is in, and the
//! importer's logger. Safe Rust; `ffi` turns C arguments into calls on it.

use std::ffi::{c_char, c_void, CString};
use std::path::Path;

use loam::fmu_package::{fmu_variables, Causality, FmuManifest, FmuVariable, MANIFEST};
use loam::simulation::Simulation;

/// `fmi3Status` (FMI 3.0 section 2.2.3 "Status Returned by Functions").
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(C)]
pub enum Status {
    /// `fmi3OK`.
    Ok = 0,
    /// `fmi3Warning`.
    Warning = 1,
    /// `fmi3Discard`: the step did not reach its end; the state is the last converged one.
    Discard = 2,
    /// `fmi3Error`: the call failed; the instance is still usable (e.g. after a reset).
    Error = 3,
    /// `fmi3Fatal`.
    Fatal = 4,
}

/// `fmi3LogMessageCallback`.
pub type LogMessage = extern "C" fn(env: *mut c_void, status: Status, category: *const c_char, message: *const c_char);

/// The importer's `logMessage` callback (FMI 3.0 section 3.2.1 "Creation, Destruction
/// and Logging of FMU Instances"):
/// errors and discards always go to it; `logInfo` messages only with debug logging on.
pub struct Logger {
    /// Callback (none: messages are dropped).
    pub callback: Option<LogMessage>,
    /// `instanceEnvironment`, passed back untouched.
    pub environment: *mut c_void,
    /// Debug logging on (`fmi3SetDebugLogging`).
    pub debug: bool,
}

impl Logger {
    /// Sends `message` with `status` (category `logStatusError`, `logStatusDiscard` or
    /// `logInfo`).
    pub fn log(&self, status: Status, message: &str) {
        let category = match status {
            Status::Error | Status::Fatal => "logStatusError",
            Status::Discard | Status::Warning => "logStatusDiscard",
            Status::Ok => {
                if !self.debug {
                    return;
                }
                "logInfo"
            }
        };
        if let Some(cb) = self.callback {
            let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
            let cat = CString::new(category).unwrap_or_default();
            cb(self.environment, status, cat.as_ptr(), msg.as_ptr());
        }
    }
}

/// FMI mode of an instance (FMI 3.0 section 4.2 "Co-Simulation State Machine").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// After instantiation or reset.
    Instantiated,
    /// Between `fmi3EnterInitializationMode` and `fmi3ExitInitializationMode`.
    Initialization,
    /// Stepping.
    Step,
    /// After `fmi3Terminate`.
    Terminated,
}

/// An instance of the packaged case.
pub struct Instance {
    /// `instanceName`.
    pub name: String,
    /// The case being run.
    pub sim: Simulation,
    /// Variables by value reference.
    pub vars: Vec<FmuVariable>,
    /// Mode.
    pub mode: Mode,
    /// The importer's logger.
    pub logger: Logger,
}

/// FMI 3.0 passes `resourcePath` as a native path with a trailing separator; accept a
/// `file://` URI as well.
fn resource_dir(resource_path: &str) -> &Path {
    let p = resource_path.strip_prefix("file://").unwrap_or(resource_path);
    Path::new(p)
}

impl Instance {
    /// Loads the case named by `resources/loam_fmu.json`, checks the instantiation token
    /// and sets every input to its start value (`fmi3InstantiateCoSimulation`).
    pub fn new(name: &str, token: &str, resource_path: &str, logger: Logger) -> Result<Self, (Logger, String)> {
        let dir = resource_dir(resource_path);
        let manifest_path = dir.join(MANIFEST);
        let manifest: FmuManifest = match std::fs::read_to_string(&manifest_path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
        {
            Ok(m) => m,
            Err(e) => return Err((logger, format!("{}: {e}", manifest_path.display()))),
        };
        if manifest.instantiation_token != token {
            return Err((
                logger,
                format!(
                    "instantiation token {token} does not match the packaged case's {}",
                    manifest.instantiation_token
                ),
            ));
        }
        let sim = match Simulation::from_file(&dir.join(&manifest.case)) {
            Ok(s) => s,
            Err(e) => return Err((logger, format!("case: {e}"))),
        };
        let vars = fmu_variables(&sim);
        let mut instance = Instance { name: name.to_string(), sim, vars, mode: Mode::Instantiated, logger };
        instance.apply_start_values();
        Ok(instance)
    }

    fn apply_start_values(&mut self) {
        for k in 0..self.sim.inputs.len() {
            let start = self.sim.inputs[k].start;
            // start values were checked finite when the case was built
            let _ = self.sim.set_input_at(k, start);
        }
    }

    /// Logs `message` with `status` and returns `status`.
    pub fn fail(&self, status: Status, message: &str) -> Status {
        self.logger.log(status, &format!("{}: {message}", self.name));
        status
    }

    /// `fmi3EnterInitializationMode`: Loam cases start at t = 0.
    pub fn enter_initialization(&mut self, start_time: f64) -> Status {
        if self.mode != Mode::Instantiated {
            return self.fail(Status::Error, &format!("fmi3EnterInitializationMode in mode {:?}", self.mode));
        }
        if start_time != 0.0 {
            return self
                .fail(Status::Error, &format!("startTime must be 0 (the case starts at t = 0), got {start_time}"));
        }
        self.mode = Mode::Initialization;
        Status::Ok
    }

    /// `fmi3ExitInitializationMode`.
    pub fn exit_initialization(&mut self) -> Status {
        if self.mode != Mode::Initialization {
            return self.fail(Status::Error, &format!("fmi3ExitInitializationMode in mode {:?}", self.mode));
        }
        self.mode = Mode::Step;
        Status::Ok
    }

    /// `fmi3DoStep`: advances from `t` (must be the instance's time) by `h` > 0 with the
    /// case's steps and cuts ([`Simulation::advance_to`]). Returns the status and the
    /// time reached: on non-convergence `Discard` at the last converged time.
    pub fn do_step(&mut self, t: f64, h: f64) -> (Status, f64) {
        let now = self.sim.time();
        if self.mode != Mode::Step {
            return (self.fail(Status::Error, &format!("fmi3DoStep in mode {:?}", self.mode)), now);
        }
        if !(h.is_finite() && h > 0.0) {
            return (self.fail(Status::Error, &format!("communicationStepSize must be > 0 and finite, got {h}")), now);
        }
        // a communication step of more steps than the case allows a whole run would hold the
        // host for ever (issue 16: a step of 1e300 s)
        let dt = self.sim.case.analysis.time_step;
        let limit = self.sim.case.limits.steps;
        if h / dt > limit as f64 {
            return (
                self.fail(
                    Status::Error,
                    &format!(
                        "communicationStepSize {h:e} s takes {:.3e} steps of {dt:e} s, more than the case's limits.steps = {limit}",
                        h / dt
                    ),
                ),
                now,
            );
        }
        let eps = 1e-9 * self.sim.case.analysis.time_step;
        if !t.is_finite() || (t - now).abs() > eps.max(1e-12 * now.abs()) {
            return (
                self.fail(Status::Error, &format!("currentCommunicationPoint {t} is not the FMU's time {now}")),
                now,
            );
        }
        let before = (self.sim.stats.steps, self.sim.stats.iterations);
        // the steps run on a thread of rayon's pool, where the parallel loops inside them run
        // without waking a worker and sleeping on each (the host calls from its own thread)
        let sim = &mut self.sim;
        match rayon::scope(|_| sim.advance_to(t + h)) {
            Ok(()) => {
                self.logger.log(
                    Status::Ok,
                    &format!(
                        "{}: t = {:.6e} s: {} steps, {} Newton iterations",
                        self.name,
                        self.sim.time(),
                        self.sim.stats.steps - before.0,
                        self.sim.stats.iterations - before.1
                    ),
                );
                (Status::Ok, self.sim.time())
            }
            Err(e) => (self.fail(Status::Discard, &format!("step did not converge: {e}")), self.sim.time()),
        }
    }

    /// `fmi3GetFloat64`.
    pub fn get_float64(&self, vrs: &[u32], values: &mut [f64]) -> Status {
        if vrs.len() != values.len() {
            return self.fail(Status::Error, "fmi3GetFloat64: nValues must equal nValueReferences");
        }
        let outputs = if vrs.iter().any(|&vr| self.var(vr).is_some_and(|v| v.causality == Causality::Output)) {
            self.sim.output_values()
        } else {
            Vec::new()
        };
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            let Some(v) = self.var(vr) else {
                return self
                    .fail(Status::Error, &format!("fmi3GetFloat64: no Float64 variable with value reference {vr}"));
            };
            *value = match v.causality {
                Causality::Independent => self.sim.time(),
                Causality::Input => self.sim.input_value_at(v.index),
                Causality::Output => outputs[v.index],
            };
        }
        Status::Ok
    }

    /// `fmi3SetFloat64`: inputs only, finite values only; a rejected value leaves every
    /// input unchanged.
    pub fn set_float64(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if vrs.len() != values.len() {
            return self.fail(Status::Error, "fmi3SetFloat64: nValues must equal nValueReferences");
        }
        if self.mode == Mode::Terminated {
            return self.fail(Status::Error, "fmi3SetFloat64 after fmi3Terminate");
        }
        for (&vr, &value) in vrs.iter().zip(values) {
            match self.var(vr) {
                Some(v) if v.causality == Causality::Input => {
                    if !value.is_finite() {
                        return self.fail(Status::Error, &format!("input '{}' must be finite, got {value}", v.name));
                    }
                }
                Some(v) => return self.fail(Status::Error, &format!("variable '{}' is not an input", v.name)),
                None => return self.fail(Status::Error, &format!("no Float64 variable with value reference {vr}")),
            }
        }
        for (&vr, &value) in vrs.iter().zip(values) {
            let k = self.vars[vr as usize].index;
            if let Err(e) = self.sim.set_input_at(k, value) {
                return self.fail(Status::Error, &e.to_string());
            }
        }
        Status::Ok
    }

    /// `fmi3Reset`: the case rebuilt at t = 0, inputs at their start values.
    pub fn reset(&mut self) -> Status {
        if let Err(e) = self.sim.reset() {
            return self.fail(Status::Error, &format!("reset: {e}"));
        }
        self.apply_start_values();
        self.mode = Mode::Instantiated;
        Status::Ok
    }

    /// `fmi3Terminate`.
    pub fn terminate(&mut self) -> Status {
        self.mode = Mode::Terminated;
        Status::Ok
    }

    fn var(&self, vr: u32) -> Option<&FmuVariable> {
        self.vars.get(vr as usize).filter(|v| v.value_reference == vr)
    }
}
