//! The `extern "C"` entry points. [`export_fmi2_cosimulation!`](crate::export_fmi2_cosimulation)
//! emits one `#[no_mangle]` function per FMI 2.0 function (Co-Simulation and Model Exchange), each forwarding to a
//! generic function here. Every entry point checks its pointers (instances and FMU states carry a
//! magic number), runs under [`guarded`], and turns a panic into `fmi2Fatal` with a log line: a
//! panic must never unwind into the host, and its message goes to the FMU's logger, not to the
//! host's stderr.

use super::ffi::*;
use super::fmu_state::SavedState;
use super::instance::{c_str, Instance};
use super::logging::guarded;
use super::variables::Value;
use super::{FmuModel, Interface};

/// Runs `f` on the instance behind `c`, with the checks and the panic guard every call needs.
///
/// # Safety
/// `c` is NULL or a pointer returned by `fmi2Instantiate` of this library.
pub unsafe fn with_instance<M: FmuModel>(
    c: Fmi2Component,
    function: &str,
    f: impl FnOnce(&mut Instance<M>) -> Fmi2Status,
) -> Fmi2Status {
    let ptr = c as *mut Instance<M>;
    if c.is_null() || !Instance::is_instance(ptr) {
        return Fmi2Status::Error;
    }
    match guarded(|| f(&mut *ptr)) {
        Ok(status) => status,
        Err(what) => {
            // The logger only reads the name and callbacks, which a panic cannot have broken.
            let inst = &mut *ptr;
            inst.fatal(&format!("{function}: internal error: {what}"))
        }
    }
}

/// The FMU state behind `state`, or an `fmi2Error` naming the argument when it is NULL or not an
/// FMU state of this library (freed already, say, or an instance pointer).
///
/// # Safety
/// `state` is NULL or points to at least 8 readable bytes.
unsafe fn fmu_state<'a, M: FmuModel>(
    inst: &mut Instance<M>,
    function: &str,
    state: Fmi2FmuState,
) -> Result<&'a mut SavedState<M::State>, Fmi2Status> {
    let ptr = state as *mut SavedState<M::State>;
    if state.is_null() {
        Err(inst.error(&format!("{function}: argument 'FMUstate' is NULL")))
    } else if !SavedState::is_saved_state(ptr) {
        Err(inst.error(&format!(
            "{function}: argument 'FMUstate' is not an FMU state of this FMU (freed already?)"
        )))
    } else {
        Ok(&mut *ptr)
    }
}

/// A C array argument as a slice: empty for n = 0, an error for NULL with n > 0.
unsafe fn slice<'a, T>(ptr: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if ptr.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts(ptr, n))
    }
}

unsafe fn slice_mut<'a, T>(ptr: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if ptr.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts_mut(ptr, n))
    }
}

macro_rules! null_check {
    ($inst:expr, $function:expr, $($arg:ident),+) => {
        $(
            let Some($arg) = $arg else {
                return $inst.error(&format!("{}: argument '{}' is NULL", $function, stringify!($arg)));
            };
        )+
    };
}

/// # Safety
/// As `fmi2Instantiate`: the strings are NULL or NUL-terminated, `functions` NULL or valid.
pub unsafe fn instantiate<M: FmuModel>(
    instance_name: Fmi2String,
    fmu_type: Fmi2Type,
    guid: Fmi2String,
    resource_location: Fmi2String,
    functions: *const Fmi2CallbackFunctions,
    _visible: Fmi2Boolean,
    logging_on: Fmi2Boolean,
) -> Fmi2Component {
    let result = guarded(|| {
        if functions.is_null() || (*functions).logger.is_none() {
            // Without a logger there is nobody to tell.
            return std::ptr::null_mut();
        }
        let callbacks = *functions;
        let name = c_str(instance_name).unwrap_or("");
        let guid = c_str(guid).unwrap_or("");
        let resources = c_str(resource_location);
        let interface = match fmu_type {
            FMI2_CO_SIMULATION => Interface::CoSimulation,
            FMI2_MODEL_EXCHANGE => Interface::ModelExchange,
            other => {
                let logger = super::logging::Logger::new(name, callbacks, true);
                logger.log(
                    Fmi2Status::Error,
                    super::LogCategory::StatusError,
                    &format!("fmi2Instantiate: fmuType {other} is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)"),
                );
                return std::ptr::null_mut();
            }
        };
        let logging_on = logging_on != FMI2_FALSE;
        match Instance::<M>::new(name, guid, resources, callbacks, logging_on, interface) {
            Ok(inst) => {
                inst.log_call(|| {
                    format!(
                        "fmi2Instantiate(instanceName=\"{name}\", fmuType={})",
                        interface.name()
                    )
                });
                Box::into_raw(Box::new(inst)) as Fmi2Component
            }
            Err((logger, message)) => {
                logger.log(Fmi2Status::Error, super::LogCategory::StatusError, &message);
                std::ptr::null_mut()
            }
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// `c` is NULL or from `fmi2Instantiate`, not yet freed.
pub unsafe fn free_instance<M: FmuModel>(c: Fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = guarded(|| {
        if Instance::is_instance(c as *const Instance<M>) {
            let inst = &mut *(c as *mut Instance<M>);
            inst.log_call(|| "fmi2FreeInstance()".into());
            inst.invalidate();
            drop(Box::from_raw(c as *mut Instance<M>));
        }
    });
}

/// # Safety
/// As `fmi2SetDebugLogging`.
pub unsafe fn set_debug_logging<M: FmuModel>(
    c: Fmi2Component,
    logging_on: Fmi2Boolean,
    n: usize,
    categories: *const Fmi2String,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SetDebugLogging", |inst| {
        let categories = slice(categories, n);
        null_check!(inst, "fmi2SetDebugLogging", categories);
        let mut names = Vec::with_capacity(n);
        for &p in categories {
            match c_str(p) {
                Some(s) => names.push(s),
                None => {
                    return inst.error("fmi2SetDebugLogging: a category name is NULL or not UTF-8")
                }
            }
        }
        inst.set_debug_logging(logging_on != FMI2_FALSE, &names)
    })
}

/// # Safety
/// As `fmi2SetupExperiment`.
pub unsafe fn setup_experiment<M: FmuModel>(
    c: Fmi2Component,
    tolerance_defined: Fmi2Boolean,
    tolerance: Fmi2Real,
    start_time: Fmi2Real,
    stop_time_defined: Fmi2Boolean,
    stop_time: Fmi2Real,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SetupExperiment", |inst| {
        inst.log_call(|| {
            format!("fmi2SetupExperiment(toleranceDefined={tolerance_defined}, tolerance={tolerance}, startTime={start_time}, stopTimeDefined={stop_time_defined}, stopTime={stop_time})")
        });
        inst.setup_experiment(
            (tolerance_defined != FMI2_FALSE).then_some(tolerance),
            start_time,
            (stop_time_defined != FMI2_FALSE).then_some(stop_time),
        )
    })
}

/// # Safety
/// As the FMI function of the same name.
pub unsafe fn simple_call<M: FmuModel>(
    c: Fmi2Component,
    function: &'static str,
    f: fn(&mut Instance<M>) -> Fmi2Status,
) -> Fmi2Status {
    with_instance::<M>(c, function, |inst| {
        inst.log_call(|| format!("{function}()"));
        f(inst)
    })
}

/// # Safety
/// As `fmi2GetReal` and siblings: arrays hold `n` elements.
pub unsafe fn get_values<M: FmuModel, T>(
    c: Fmi2Component,
    function: &'static str,
    type_name: &'static str,
    vr: *const Fmi2ValueReference,
    n: usize,
    value: *mut T,
    convert: impl Fn(&Value) -> T,
) -> Fmi2Status {
    with_instance::<M>(c, function, |inst| {
        let (vr, value) = (slice(vr, n), slice_mut(value, n));
        null_check!(inst, function, vr, value);
        inst.log_call(|| format!("{function}(vr={vr:?})"));
        inst.get(function, type_name, vr, value, convert)
    })
}

/// # Safety
/// As `fmi2SetReal` and siblings: arrays hold `n` elements.
pub unsafe fn set_values<M: FmuModel, T: Copy>(
    c: Fmi2Component,
    function: &'static str,
    type_name: &'static str,
    vr: *const Fmi2ValueReference,
    n: usize,
    value: *const T,
    convert: impl Fn(T) -> Option<Value>,
) -> Fmi2Status {
    with_instance::<M>(c, function, |inst| {
        let (vr, value) = (slice(vr, n), slice(value, n));
        null_check!(inst, function, vr, value);
        let mut values = Vec::with_capacity(n);
        for &v in value {
            match convert(v) {
                Some(v) => values.push(v),
                None => return inst.error(&format!("{function}: a value is NULL or not UTF-8")),
            }
        }
        inst.log_call(|| format!("{function}(vr={vr:?}, value={values:?})"));
        inst.set(function, type_name, vr, values)
    })
}

/// # Safety
/// As `fmi2GetString`.
pub unsafe fn get_string<M: FmuModel>(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    n: usize,
    value: *mut Fmi2String,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2GetString", |inst| {
        let (vr, value) = (slice(vr, n), slice_mut(value, n));
        null_check!(inst, "fmi2GetString", vr, value);
        inst.get_strings(vr, value)
    })
}

/// # Safety
/// As `fmi2GetFMUstate`.
pub unsafe fn get_fmu_state<M: FmuModel>(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
    with_instance::<M>(c, "fmi2GetFMUstate", |inst| {
        if state.is_null() {
            return inst.error("fmi2GetFMUstate: argument 'FMUstate' is NULL");
        }
        if let Err(s) = inst.check_fmu_state_call("fmi2GetFMUstate") {
            return s;
        }
        inst.log_call(|| "fmi2GetFMUstate()".into());
        if (*state).is_null() {
            *state = Box::into_raw(Box::new(inst.save())) as Fmi2FmuState;
        } else {
            // A state handed back to be overwritten (FMI 2.0.4, 2.1.8).
            match fmu_state(inst, "fmi2GetFMUstate", *state) {
                Ok(old) => *old = inst.save(),
                Err(s) => return s,
            }
        }
        Fmi2Status::Ok
    })
}

/// # Safety
/// As `fmi2SetFMUstate`: `state` from `fmi2GetFMUstate` or `fmi2DeSerializeFMUstate` of this FMU.
pub unsafe fn set_fmu_state<M: FmuModel>(c: Fmi2Component, state: Fmi2FmuState) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SetFMUstate", |inst| {
        if let Err(s) = inst.check_fmu_state_call("fmi2SetFMUstate") {
            return s;
        }
        let saved = match fmu_state(inst, "fmi2SetFMUstate", state) {
            Ok(saved) => saved,
            Err(s) => return s,
        };
        inst.log_call(|| "fmi2SetFMUstate()".into());
        inst.restore(saved)
    })
}

/// # Safety
/// As `fmi2FreeFMUstate`.
pub unsafe fn free_fmu_state<M: FmuModel>(
    c: Fmi2Component,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2FreeFMUstate", |inst| {
        if state.is_null() {
            return inst.error("fmi2FreeFMUstate: argument 'FMUstate' is NULL");
        }
        if let Err(s) = inst.check_fmu_state_call("fmi2FreeFMUstate") {
            return s;
        }
        inst.log_call(|| "fmi2FreeFMUstate()".into());
        if !(*state).is_null() {
            match fmu_state(inst, "fmi2FreeFMUstate", *state) {
                Ok(saved) => {
                    saved.invalidate();
                    drop(Box::from_raw(saved as *mut SavedState<M::State>));
                }
                Err(s) => return s,
            }
            *state = std::ptr::null_mut();
        }
        Fmi2Status::Ok
    })
}

/// # Safety
/// As `fmi2SerializedFMUstateSize`.
pub unsafe fn serialized_size<M: FmuModel>(
    c: Fmi2Component,
    state: Fmi2FmuState,
    size: *mut usize,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SerializedFMUstateSize", |inst| {
        if size.is_null() {
            return inst.error("fmi2SerializedFMUstateSize: argument 'size' is NULL");
        }
        if let Err(s) = inst.check_fmu_state_call("fmi2SerializedFMUstateSize") {
            return s;
        }
        let saved = match fmu_state(inst, "fmi2SerializedFMUstateSize", state) {
            Ok(saved) => saved,
            Err(s) => return s,
        };
        match saved.serialized() {
            Ok(bytes) => {
                *size = bytes.len();
                Fmi2Status::Ok
            }
            Err(msg) => inst.error(&format!("fmi2SerializedFMUstateSize: {msg}")),
        }
    })
}

/// # Safety
/// As `fmi2SerializeFMUstate`: `bytes` holds `size` bytes.
pub unsafe fn serialize<M: FmuModel>(
    c: Fmi2Component,
    state: Fmi2FmuState,
    bytes: *mut Fmi2Byte,
    size: usize,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SerializeFMUstate", |inst| {
        if bytes.is_null() {
            return inst.error("fmi2SerializeFMUstate: argument 'serializedState' is NULL");
        }
        if let Err(s) = inst.check_fmu_state_call("fmi2SerializeFMUstate") {
            return s;
        }
        let saved = match fmu_state(inst, "fmi2SerializeFMUstate", state) {
            Ok(saved) => saved,
            Err(s) => return s,
        };
        match saved.serialized() {
            Ok(data) if data.len() <= size => {
                std::ptr::copy_nonoverlapping(data.as_ptr(), bytes as *mut u8, data.len());
                Fmi2Status::Ok
            }
            Ok(data) => {
                let need = data.len();
                inst.error(&format!(
                    "fmi2SerializeFMUstate: buffer of {size} bytes is too small, {need} needed"
                ))
            }
            Err(msg) => inst.error(&format!("fmi2SerializeFMUstate: {msg}")),
        }
    })
}

/// # Safety
/// As `fmi2DeSerializeFMUstate`: `bytes` holds `size` bytes.
pub unsafe fn deserialize<M: FmuModel>(
    c: Fmi2Component,
    bytes: *const Fmi2Byte,
    size: usize,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2DeSerializeFMUstate", |inst| {
        if state.is_null() || (bytes.is_null() && size > 0) {
            return inst.error(
                "fmi2DeSerializeFMUstate: argument 'serializedState' or 'FMUstate' is NULL",
            );
        }
        if let Err(s) = inst.check_fmu_state_call("fmi2DeSerializeFMUstate") {
            return s;
        }
        let data = slice(bytes as *const u8, size).unwrap_or_default();
        match SavedState::<M::State>::deserialize(data, M::GUID) {
            Ok(saved) => {
                *state = Box::into_raw(Box::new(saved)) as Fmi2FmuState;
                Fmi2Status::Ok
            }
            Err(msg) => inst.error(&format!("fmi2DeSerializeFMUstate: {msg}")),
        }
    })
}

/// # Safety
/// As `fmi2DoStep`.
pub unsafe fn do_step<M: FmuModel>(
    c: Fmi2Component,
    current_communication_point: Fmi2Real,
    step_size: Fmi2Real,
    _no_set_fmu_state_prior: Fmi2Boolean,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2DoStep", |inst| {
        inst.log_call(|| {
            format!("fmi2DoStep(currentCommunicationPoint={current_communication_point}, communicationStepSize={step_size})")
        });
        inst.do_step(current_communication_point, step_size)
    })
}

/// # Safety
/// As `fmi2SetTime`.
pub unsafe fn set_time<M: FmuModel>(c: Fmi2Component, time: Fmi2Real) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SetTime", |inst| {
        inst.log_call(|| format!("fmi2SetTime(time={time})"));
        inst.set_time(time)
    })
}

/// # Safety
/// As `fmi2SetContinuousStates`: `x` holds `nx` elements.
pub unsafe fn set_continuous_states<M: FmuModel>(
    c: Fmi2Component,
    x: *const Fmi2Real,
    nx: usize,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2SetContinuousStates", |inst| {
        let x = slice(x, nx);
        null_check!(inst, "fmi2SetContinuousStates", x);
        inst.log_call(|| format!("fmi2SetContinuousStates(x={x:?})"));
        inst.set_continuous_states(x)
    })
}

/// The Model Exchange getters of a Real array of the states' size: `fmi2GetContinuousStates`,
/// `fmi2GetDerivatives`, `fmi2GetNominalsOfContinuousStates`.
///
/// # Safety
/// `out` holds `n` elements.
pub unsafe fn get_state_array<M: FmuModel>(
    c: Fmi2Component,
    (function, argument): (&'static str, &'static str),
    out: *mut Fmi2Real,
    n: usize,
    f: fn(&mut Instance<M>, &mut [f64]) -> Fmi2Status,
) -> Fmi2Status {
    with_instance::<M>(c, function, |inst| {
        let Some(out) = slice_mut(out, n) else {
            return inst.error(&format!("{function}: argument '{argument}' is NULL"));
        };
        inst.log_call(|| format!("{function}(n={n})"));
        f(inst, out)
    })
}

/// # Safety
/// As `fmi2GetEventIndicators`.
pub unsafe fn get_event_indicators<M: FmuModel>(
    c: Fmi2Component,
    indicators: *mut Fmi2Real,
    ni: usize,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2GetEventIndicators", |inst| {
        let indicators = slice_mut(indicators, ni);
        null_check!(inst, "fmi2GetEventIndicators", indicators);
        inst.log_call(|| format!("fmi2GetEventIndicators(ni={ni})"));
        inst.event_indicators(indicators.len())
    })
}

/// # Safety
/// As `fmi2NewDiscreteStates`.
pub unsafe fn new_discrete_states<M: FmuModel>(
    c: Fmi2Component,
    info: *mut Fmi2EventInfo,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2NewDiscreteStates", |inst| {
        if info.is_null() {
            return inst.error("fmi2NewDiscreteStates: argument 'eventInfo' is NULL");
        }
        inst.log_call(|| "fmi2NewDiscreteStates()".into());
        inst.new_discrete_states(&mut *info)
    })
}

/// # Safety
/// As `fmi2CompletedIntegratorStep`.
pub unsafe fn completed_integrator_step<M: FmuModel>(
    c: Fmi2Component,
    _no_set_fmu_state_prior: Fmi2Boolean,
    enter_event_mode: *mut Fmi2Boolean,
    terminate_simulation: *mut Fmi2Boolean,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2CompletedIntegratorStep", |inst| {
        if enter_event_mode.is_null() || terminate_simulation.is_null() {
            return inst.error(
                "fmi2CompletedIntegratorStep: argument 'enterEventMode' or 'terminateSimulation' is NULL",
            );
        }
        inst.log_call(|| "fmi2CompletedIntegratorStep()".into());
        match inst.completed_integrator_step() {
            Ok((event, terminate)) => {
                *enter_event_mode = if event { FMI2_TRUE } else { FMI2_FALSE };
                *terminate_simulation = if terminate { FMI2_TRUE } else { FMI2_FALSE };
                Fmi2Status::Ok
            }
            Err(s) => s,
        }
    })
}

/// # Safety
/// As `fmi2GetDirectionalDerivative`: the unknown arrays hold `n_unknown` elements, the known
/// ones `n_known`.
#[allow(non_snake_case)]
pub unsafe fn get_directional_derivative<M: FmuModel>(
    c: Fmi2Component,
    unknown_vrs: *const Fmi2ValueReference,
    n_unknown: usize,
    known_vrs: *const Fmi2ValueReference,
    n_known: usize,
    dv_known: *const Fmi2Real,
    dv_unknown: *mut Fmi2Real,
) -> Fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    with_instance::<M>(c, F, |inst| {
        let vUnknown_ref = slice(unknown_vrs, n_unknown);
        let vKnown_ref = slice(known_vrs, n_known);
        let dvKnown = slice(dv_known, n_known);
        let dvUnknown = slice_mut(dv_unknown, n_unknown);
        // The arguments by their names in the standard, for the message.
        null_check!(inst, F, vUnknown_ref, vKnown_ref, dvKnown, dvUnknown);
        let (v_unknown_ref, v_known_ref, dv_known, dv_unknown) =
            (vUnknown_ref, vKnown_ref, dvKnown, dvUnknown);
        inst.log_call(|| format!("{F}(vUnknown_ref={v_unknown_ref:?}, vKnown_ref={v_known_ref:?}, dvKnown={dv_known:?})"));
        inst.directional_derivative(v_unknown_ref, v_known_ref, dv_known, dv_unknown)
    })
}

/// A function this FMU declares it does not support (capability flag false in the XML).
///
/// # Safety
/// `c` as for every call.
pub unsafe fn unsupported<M: FmuModel>(
    c: Fmi2Component,
    function: &'static str,
    why: &'static str,
) -> Fmi2Status {
    with_instance::<M>(c, function, |inst| {
        if let Err(s) = inst.allowed(function, super::calls::Operation::Unsupported) {
            return s;
        }
        inst.error(&format!("{function}: not supported: {why}"))
    })
}

/// # Safety
/// As `fmi2GetRealStatus`.
pub unsafe fn get_real_status<M: FmuModel>(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Real,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2GetRealStatus", |inst| {
        if value.is_null() {
            return inst.error("fmi2GetRealStatus: argument 'value' is NULL");
        }
        if kind != FMI2_LAST_SUCCESSFUL_TIME {
            return inst.error(&format!(
                "fmi2GetRealStatus: status kind {kind} is not a Real status"
            ));
        }
        match inst.last_successful_time() {
            Ok(t) => {
                *value = t;
                Fmi2Status::Ok
            }
            Err(s) => s,
        }
    })
}

/// # Safety
/// As `fmi2GetBooleanStatus`.
pub unsafe fn get_boolean_status<M: FmuModel>(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Boolean,
) -> Fmi2Status {
    with_instance::<M>(c, "fmi2GetBooleanStatus", |inst| {
        if value.is_null() {
            return inst.error("fmi2GetBooleanStatus: argument 'value' is NULL");
        }
        if kind != FMI2_TERMINATED {
            return inst.error(&format!(
                "fmi2GetBooleanStatus: status kind {kind} is not a Boolean status"
            ));
        }
        match inst.terminated_status() {
            Ok(t) => {
                *value = if t { FMI2_TRUE } else { FMI2_FALSE };
                Fmi2Status::Ok
            }
            Err(s) => s,
        }
    })
}

/// The static strings of `fmi2GetTypesPlatform` and `fmi2GetVersion`.
pub const TYPES_PLATFORM: &std::ffi::CStr = c"default";
pub const VERSION: &std::ffi::CStr = c"2.0";

/// Reads a C string argument of a setter.
///
/// # Safety
/// `p` is NULL or NUL-terminated.
pub unsafe fn string_value(p: Fmi2String) -> Option<Value> {
    c_str(p).map(|s| Value::String(s.to_string()))
}

/// Emits the FMI 2.0 C API (Co-Simulation and Model Exchange in one binary) for a model type
/// implementing [`FmuModel`](crate::fmi2::FmuModel). Call it once, in the crate that builds the
/// cdylib.
#[macro_export]
macro_rules! export_fmi2_cosimulation {
    ($model:ty) => {
        /// The `fmi2*` functions of the FMU, callable from Rust too (tests use them in-process).
        ///
        /// Safety: each has the contract the FMI 2.0 standard gives the C function of its name.
        #[allow(clippy::missing_safety_doc)]
        pub mod fmi2_exports {
            use $crate::fmi2::exports as x;
            use $crate::fmi2::ffi::*;
            use $crate::fmi2::variables::Value;
            type M = $model;

            #[no_mangle]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const std::os::raw::c_char {
                x::TYPES_PLATFORM.as_ptr()
            }
            #[no_mangle]
            pub extern "C" fn fmi2GetVersion() -> *const std::os::raw::c_char {
                x::VERSION.as_ptr()
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetDebugLogging(
                c: Fmi2Component,
                on: Fmi2Boolean,
                n: usize,
                cats: *const Fmi2String,
            ) -> Fmi2Status {
                x::set_debug_logging::<M>(c, on, n, cats)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Instantiate(
                name: Fmi2String,
                kind: Fmi2Type,
                guid: Fmi2String,
                res: Fmi2String,
                f: *const Fmi2CallbackFunctions,
                visible: Fmi2Boolean,
                logging: Fmi2Boolean,
            ) -> Fmi2Component {
                x::instantiate::<M>(name, kind, guid, res, f, visible, logging)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
                x::free_instance::<M>(c)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetupExperiment(
                c: Fmi2Component,
                tol_def: Fmi2Boolean,
                tol: Fmi2Real,
                start: Fmi2Real,
                stop_def: Fmi2Boolean,
                stop: Fmi2Real,
            ) -> Fmi2Status {
                x::setup_experiment::<M>(c, tol_def, tol, start, stop_def, stop)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2EnterInitializationMode", |i| {
                    i.enter_initialization_mode()
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2ExitInitializationMode", |i| {
                    i.exit_initialization_mode()
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Terminate(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2Terminate", |i| i.terminate())
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Reset(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2Reset", |i| i.reset())
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetReal(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Real,
            ) -> Fmi2Status {
                x::get_values::<M, Fmi2Real>(c, "fmi2GetReal", "Real", vr, n, v, |v| match v {
                    Value::Real(x) => *x,
                    _ => 0.0,
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetInteger(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Integer,
            ) -> Fmi2Status {
                x::get_values::<M, Fmi2Integer>(c, "fmi2GetInteger", "Integer", vr, n, v, |v| {
                    match v {
                        Value::Integer(x) => *x,
                        _ => 0,
                    }
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBoolean(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                x::get_values::<M, Fmi2Boolean>(c, "fmi2GetBoolean", "Boolean", vr, n, v, |v| {
                    match v {
                        Value::Boolean(true) => FMI2_TRUE,
                        _ => FMI2_FALSE,
                    }
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetString(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2String,
            ) -> Fmi2Status {
                x::get_string::<M>(c, vr, n, v)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetReal(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Real,
            ) -> Fmi2Status {
                x::set_values::<M, Fmi2Real>(c, "fmi2SetReal", "Real", vr, n, v, |v| {
                    Some(Value::Real(v))
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetInteger(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Integer,
            ) -> Fmi2Status {
                x::set_values::<M, Fmi2Integer>(c, "fmi2SetInteger", "Integer", vr, n, v, |v| {
                    Some(Value::Integer(v))
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetBoolean(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Boolean,
            ) -> Fmi2Status {
                x::set_values::<M, Fmi2Boolean>(c, "fmi2SetBoolean", "Boolean", vr, n, v, |v| {
                    Some(Value::Boolean(v != FMI2_FALSE))
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetString(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2String,
            ) -> Fmi2Status {
                x::set_values::<M, Fmi2String>(c, "fmi2SetString", "String", vr, n, v, |p| unsafe {
                    x::string_value(p)
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetFMUstate(
                c: Fmi2Component,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                x::get_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetFMUstate(
                c: Fmi2Component,
                s: Fmi2FmuState,
            ) -> Fmi2Status {
                x::set_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeFMUstate(
                c: Fmi2Component,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                x::free_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
                c: Fmi2Component,
                s: Fmi2FmuState,
                size: *mut usize,
            ) -> Fmi2Status {
                x::serialized_size::<M>(c, s, size)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(
                c: Fmi2Component,
                s: Fmi2FmuState,
                bytes: *mut Fmi2Byte,
                size: usize,
            ) -> Fmi2Status {
                x::serialize::<M>(c, s, bytes, size)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
                c: Fmi2Component,
                bytes: *const Fmi2Byte,
                size: usize,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                x::deserialize::<M>(c, bytes, size, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
                c: Fmi2Component,
                u: *const Fmi2ValueReference,
                nu: usize,
                z: *const Fmi2ValueReference,
                nz: usize,
                dv: *const Fmi2Real,
                dz: *mut Fmi2Real,
            ) -> Fmi2Status {
                x::get_directional_derivative::<M>(c, u, nu, z, nz, dv, dz)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterEventMode(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2EnterEventMode", |i| i.enter_event_mode())
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2NewDiscreteStates(
                c: Fmi2Component,
                info: *mut Fmi2EventInfo,
            ) -> Fmi2Status {
                x::new_discrete_states::<M>(c, info)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: Fmi2Component) -> Fmi2Status {
                x::simple_call::<M>(c, "fmi2EnterContinuousTimeMode", |i| {
                    i.enter_continuous_time_mode()
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
                c: Fmi2Component,
                no_prior: Fmi2Boolean,
                enter_event_mode: *mut Fmi2Boolean,
                terminate: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                x::completed_integrator_step::<M>(c, no_prior, enter_event_mode, terminate)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetTime(c: Fmi2Component, t: Fmi2Real) -> Fmi2Status {
                x::set_time::<M>(c, t)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetContinuousStates(
                c: Fmi2Component,
                v: *const Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                x::set_continuous_states::<M>(c, v, n)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetDerivatives(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                x::get_state_array::<M>(c, ("fmi2GetDerivatives", "derivatives"), v, n, |i, o| {
                    i.derivatives(o)
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetEventIndicators(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                x::get_event_indicators::<M>(c, v, n)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetContinuousStates(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                x::get_state_array::<M>(c, ("fmi2GetContinuousStates", "x"), v, n, |i, o| {
                    i.continuous_states(o)
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                x::get_state_array::<M>(
                    c,
                    ("fmi2GetNominalsOfContinuousStates", "x_nominal"),
                    v,
                    n,
                    |i, o| i.nominals_of_continuous_states(o),
                )
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: Fmi2Component,
                _vr: *const Fmi2ValueReference,
                _n: usize,
                _order: *const Fmi2Integer,
                _v: *const Fmi2Real,
            ) -> Fmi2Status {
                x::unsupported::<M>(
                    c,
                    "fmi2SetRealInputDerivatives",
                    "canInterpolateInputs is false",
                )
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: Fmi2Component,
                _vr: *const Fmi2ValueReference,
                _n: usize,
                _order: *const Fmi2Integer,
                _v: *mut Fmi2Real,
            ) -> Fmi2Status {
                x::unsupported::<M>(
                    c,
                    "fmi2GetRealOutputDerivatives",
                    "maxOutputDerivativeOrder is 0",
                )
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DoStep(
                c: Fmi2Component,
                t: Fmi2Real,
                h: Fmi2Real,
                no_prior: Fmi2Boolean,
            ) -> Fmi2Status {
                x::do_step::<M>(c, t, h, no_prior)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CancelStep(c: Fmi2Component) -> Fmi2Status {
                x::unsupported::<M>(c, "fmi2CancelStep", "fmi2DoStep never returns fmi2Pending")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2Status,
            ) -> Fmi2Status {
                x::unsupported::<M>(c, "fmi2GetStatus", "fmi2DoStep never returns fmi2Pending")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealStatus(
                c: Fmi2Component,
                k: Fmi2StatusKind,
                v: *mut Fmi2Real,
            ) -> Fmi2Status {
                x::get_real_status::<M>(c, k, v)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2Integer,
            ) -> Fmi2Status {
                x::unsupported::<M>(
                    c,
                    "fmi2GetIntegerStatus",
                    "there is no Integer status in FMI 2.0",
                )
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(
                c: Fmi2Component,
                k: Fmi2StatusKind,
                v: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                x::get_boolean_status::<M>(c, k, v)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStringStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2String,
            ) -> Fmi2Status {
                x::unsupported::<M>(
                    c,
                    "fmi2GetStringStatus",
                    "fmi2DoStep never returns fmi2Pending",
                )
            }
        }
    };
}
