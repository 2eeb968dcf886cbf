//! The exported FMI 3.0 functions (FMI 3.0 chapter 2.3 "FMI Application Programming
//! Interface" and chapter 4 "FMI for Co-Simulation").
//!
//! C types by hand: `fmi3Instance` = `*mut c_void`, `fmi3Status` = [`Status`] (C enum,
//! `int`), `fmi3Boolean` = `bool` (C `_Bool`), `fmi3ValueReference` = `u32`,
//! `fmi3Float64` = `f64`, `fmi3String` = `*const c_char`, `size_t` = `usize`, the
//! callbacks as `Option` of `extern "C" fn` types. `scripts/check_fmi_header.py` (run by
//! `scripts/test.sh`) compiles every signature here against the standard's
//! `fmi3Functions.h`, so a type that differs fails the test suite.
//!
//! Implemented: `fmi3GetVersion`, `fmi3SetDebugLogging`, `fmi3InstantiateCoSimulation`,
//! `fmi3FreeInstance`, `fmi3EnterInitializationMode`, `fmi3ExitInitializationMode`,
//! `fmi3DoStep`, `fmi3GetFloat64`, `fmi3SetFloat64`, `fmi3Reset`, `fmi3Terminate`. Every
//! other function of the standard is exported too (importers such as fmpy resolve all
//! of them when loading) and returns `fmi3Error` with a log message, or `NULL` for the
//! other instantiate functions.
#![allow(unsafe_code)]

use std::ffi::{c_char, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::instance::{Instance, LogMessage, Logger, Status};

/// `fmi3IntermediateUpdateCallback` (not called: intermediate updates are not supported).
pub type IntermediateUpdate = extern "C" fn(
    env: *mut c_void,
    time: f64,
    set_requested: bool,
    get_allowed: bool,
    finished: bool,
    can_return_early: bool,
    early_return_requested: *mut bool,
    early_return_time: *mut f64,
);

/// `fmi3ClockUpdateCallback` (scheduled execution; not provided).
pub type ClockUpdate = extern "C" fn(env: *mut c_void);

/// `fmi3LockPreemptionCallback` and `fmi3UnlockPreemptionCallback` (scheduled execution;
/// not provided).
pub type Preemption = extern "C" fn();

/// Text of a C string, or `default` for NULL.
///
/// # Safety
/// `p` is NULL or a NUL-terminated string valid for the call.
unsafe fn c_str(p: *const c_char, default: &str) -> String {
    if p.is_null() {
        default.to_string()
    } else {
        CStr::from_ptr(p).to_string_lossy().into_owned()
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Runs `f` on the instance behind `instance`, catching panics: NULL gives `fmi3Error`,
/// a panic `fmi3Error` with a log message.
///
/// # Safety
/// `instance` is NULL or a pointer returned by [`fmi3InstantiateCoSimulation`] and not
/// yet freed, used by one thread at a time (FMI 3.0 section 2.2.4).
unsafe fn with_instance(instance: *mut c_void, f: impl FnOnce(&mut Instance) -> Status) -> Status {
    if instance.is_null() {
        return Status::Error;
    }
    let inst = &mut *(instance as *mut Instance);
    match catch_unwind(AssertUnwindSafe(|| f(&mut *inst))) {
        Ok(s) => s,
        Err(payload) => {
            let msg = format!("internal error: {}; reset or free the instance", panic_message(&*payload));
            catch_unwind(AssertUnwindSafe(|| inst.fail(Status::Error, &msg))).unwrap_or(Status::Error)
        }
    }
}

/// A slice from a C array; empty for `n = 0` (the pointer may then be NULL).
///
/// # Safety
/// `p` points to `n` valid elements when `n > 0`.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts(p, n))
    }
}

/// `fmi3GetVersion`: "3.0".
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// `fmi3SetDebugLogging`: switches the `logInfo` messages (per step: steps taken, Newton
/// iterations); errors and discards are always logged.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: *mut c_void,
    logging_on: bool,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Status {
    with_instance(instance, |i| {
        i.logger.debug = logging_on;
        Status::Ok
    })
}

/// `fmi3InstantiateCoSimulation`: loads the packaged case from `resourcePath`; NULL (and
/// a log message) if the manifest, the token or the case is wrong. Event mode, early
/// return and intermediate updates are not supported (the model description says so).
///
/// # Safety
/// FMI calling rules: strings NUL-terminated, `log_message` callable or NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    _event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate_variables: *const u32,
    _n_required_intermediate_variables: usize,
    instance_environment: *mut c_void,
    log_message: Option<LogMessage>,
    _intermediate_update: Option<IntermediateUpdate>,
) -> *mut c_void {
    let result = catch_unwind(AssertUnwindSafe(|| {
        let name = c_str(instance_name, "loam");
        let logger = Logger { callback: log_message, environment: instance_environment, debug: logging_on };
        if resource_path.is_null() {
            logger.log(Status::Error, &format!("{name}: resourcePath is NULL; the case is in the FMU's resources/"));
            return std::ptr::null_mut();
        }
        let token = c_str(instantiation_token, "");
        let resources = c_str(resource_path, "");
        match Instance::new(&name, &token, &resources, logger) {
            Ok(i) => {
                faer::set_global_parallelism(faer::Par::Seq);
                Box::into_raw(Box::new(i)) as *mut c_void
            }
            Err((logger, msg)) => {
                logger.log(Status::Error, &format!("{name}: {msg}"));
                std::ptr::null_mut()
            }
        }
    }));
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi3InstantiateModelExchange`: not provided (co-simulation only); returns NULL.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Option<LogMessage>,
) -> *mut c_void {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let logger = Logger { callback: log_message, environment: instance_environment, debug: false };
        logger.log(Status::Error, &format!("{}: Loam FMUs are co-simulation only", c_str(instance_name, "loam")));
    }));
    std::ptr::null_mut()
}

/// `fmi3InstantiateScheduledExecution`: not provided; returns NULL.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    visible: bool,
    logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Option<LogMessage>,
    _clock_update: Option<ClockUpdate>,
    _lock_preemption: Option<Preemption>,
    _unlock_preemption: Option<Preemption>,
) -> *mut c_void {
    fmi3InstantiateModelExchange(
        instance_name,
        instantiation_token,
        resource_path,
        visible,
        logging_on,
        instance_environment,
        log_message,
    )
}

/// `fmi3FreeInstance`.
///
/// # Safety
/// `instance` is NULL or from [`fmi3InstantiateCoSimulation`], not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: *mut c_void) {
    if !instance.is_null() {
        let _ = catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(instance as *mut Instance))));
    }
}

/// `fmi3EnterInitializationMode`: `startTime` must be 0; tolerance and stop time are not
/// used (the case's Newton tolerances apply; the FMU may run past the case's end time).
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: *mut c_void,
    _tolerance_defined: bool,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: bool,
    _stop_time: f64,
) -> Status {
    with_instance(instance, |i| i.enter_initialization(start_time))
}

/// `fmi3ExitInitializationMode`.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: *mut c_void) -> Status {
    with_instance(instance, |i| i.exit_initialization())
}

/// `fmi3DoStep` (FMI 3.0 section 4.2.1 "State: Step Mode"): advances by
/// `communicationStepSize` with the case's steps and cuts. A step that does not converge
/// gives `fmi3Discard` with `lastSuccessfulTime` the last converged time and
/// `terminateSimulation` true; a non-positive step or a communication point that is not
/// the FMU's time gives `fmi3Error`.
///
/// # Safety
/// FMI calling rules: the output pointers are valid or NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: *mut c_void,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Status {
    with_instance(instance, |i| {
        let (status, reached) = i.do_step(current_communication_point, communication_step_size);
        if !event_handling_needed.is_null() {
            *event_handling_needed = false;
        }
        if !terminate_simulation.is_null() {
            *terminate_simulation = status == Status::Discard;
        }
        if !early_return.is_null() {
            *early_return = false;
        }
        if !last_successful_time.is_null() {
            *last_successful_time = reached;
        }
        status
    })
}

/// `fmi3GetFloat64`: `time`, inputs (their current values) and outputs (monitors at the
/// committed state).
///
/// # Safety
/// FMI calling rules: arrays of the given lengths.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: *mut c_void,
    value_references: *const u32,
    n_value_references: usize,
    values: *mut f64,
    n_values: usize,
) -> Status {
    with_instance(instance, |i| {
        let Some(vrs) = slice(value_references, n_value_references) else {
            return i.fail(Status::Error, "fmi3GetFloat64: valueReferences is NULL");
        };
        if n_values > 0 && values.is_null() {
            return i.fail(Status::Error, "fmi3GetFloat64: values is NULL");
        }
        let out: &mut [f64] = if n_values == 0 { &mut [] } else { std::slice::from_raw_parts_mut(values, n_values) };
        i.get_float64(vrs, out)
    })
}

/// `fmi3SetFloat64`: inputs only; NaN and infinite values give `fmi3Error` and change
/// nothing.
///
/// # Safety
/// FMI calling rules: arrays of the given lengths.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: *mut c_void,
    value_references: *const u32,
    n_value_references: usize,
    values: *const f64,
    n_values: usize,
) -> Status {
    with_instance(instance, |i| match (slice(value_references, n_value_references), slice(values, n_values)) {
        (Some(vrs), Some(vals)) => i.set_float64(vrs, vals),
        _ => i.fail(Status::Error, "fmi3SetFloat64: NULL array"),
    })
}

/// `fmi3Reset`: back to the instantiated state at t = 0 with inputs at their start values.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: *mut c_void) -> Status {
    with_instance(instance, |i| i.reset())
}

/// `fmi3Terminate`.
///
/// # Safety
/// FMI calling rules.
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: *mut c_void) -> Status {
    with_instance(instance, |i| i.terminate())
}

/// Exports FMI functions this FMU does not provide: each logs and returns `fmi3Error`.
/// Only the first argument (the instance) is read, which every C calling convention
/// allows whatever the caller passes after it.
macro_rules! unsupported {
    ($($name:ident),* $(,)?) => {$(
        #[doc = concat!("`", stringify!($name), "`: not provided by Loam FMUs; returns `fmi3Error`.")]
        ///
        /// # Safety
        /// FMI calling rules.
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: *mut c_void) -> Status {
            with_instance(instance, |i| {
                i.fail(Status::Error, concat!(stringify!($name), " is not supported by Loam FMUs"))
            })
        }
    )*};
}

unsupported!(
    fmi3EnterEventMode,
    fmi3GetFloat32,
    fmi3GetInt8,
    fmi3GetUInt8,
    fmi3GetInt16,
    fmi3GetUInt16,
    fmi3GetInt32,
    fmi3GetUInt32,
    fmi3GetInt64,
    fmi3GetUInt64,
    fmi3GetBoolean,
    fmi3GetString,
    fmi3GetBinary,
    fmi3GetClock,
    fmi3SetFloat32,
    fmi3SetInt8,
    fmi3SetUInt8,
    fmi3SetInt16,
    fmi3SetUInt16,
    fmi3SetInt32,
    fmi3SetUInt32,
    fmi3SetInt64,
    fmi3SetUInt64,
    fmi3SetBoolean,
    fmi3SetString,
    fmi3SetBinary,
    fmi3SetClock,
    fmi3GetNumberOfVariableDependencies,
    fmi3GetVariableDependencies,
    fmi3GetFMUState,
    fmi3SetFMUState,
    fmi3FreeFMUState,
    fmi3SerializedFMUStateSize,
    fmi3SerializeFMUState,
    fmi3DeserializeFMUState,
    fmi3GetDirectionalDerivative,
    fmi3GetAdjointDerivative,
    fmi3EnterConfigurationMode,
    fmi3ExitConfigurationMode,
    fmi3GetIntervalDecimal,
    fmi3GetIntervalFraction,
    fmi3GetShiftDecimal,
    fmi3GetShiftFraction,
    fmi3SetIntervalDecimal,
    fmi3SetIntervalFraction,
    fmi3SetShiftDecimal,
    fmi3SetShiftFraction,
    fmi3EvaluateDiscreteStates,
    fmi3UpdateDiscreteStates,
    fmi3EnterContinuousTimeMode,
    fmi3CompletedIntegratorStep,
    fmi3SetTime,
    fmi3SetContinuousStates,
    fmi3GetContinuousStateDerivatives,
    fmi3GetEventIndicators,
    fmi3GetContinuousStates,
    fmi3GetNominalsOfContinuousStates,
    fmi3GetNumberOfEventIndicators,
    fmi3GetNumberOfContinuousStates,
    fmi3EnterStepMode,
    fmi3GetOutputDerivatives,
    fmi3ActivateModelPartition,
);
