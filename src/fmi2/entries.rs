//! The FMI 2.0 entry points, generic over a model: each turns FMI 2.0's arguments into the core's
//! (`int` Booleans, the `fmi2Type`, the resources URI, status kinds, `fmi2EventInfo`) and its
//! status back. [`export_fmi2_cosimulation!`](crate::export_fmi2_cosimulation) emits one
//! `#[no_mangle]` function per FMI 2.0 function forwarding here; the FMU-state functions go
//! straight to the core's [`fmu_states`](crate::fmu::boundary::fmu_states).

use super::ffi::*;
use super::logger::{Fmi2Sink, VOCABULARY};
use crate::fmu::boundary::{
    self as core, c_str, file_uri_to_path, instantiate as make, slice, slice_mut, with_instance,
};
use crate::fmu::instance::Instance;
use crate::fmu::logging::Logger;
use crate::fmu::variables::Value;
use crate::fmu::{FmuModel, Interface, Status};

/// Refuses a NULL array argument with a message naming it (by its name in the standard).
macro_rules! null_check {
    ($inst:expr, $($arg:ident),+) => {
        $(
            let Some($arg) = $arg else {
                return $inst.refuse(&format!("argument '{}' is NULL", stringify!($arg)));
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
    const F: &str = "fmi2Instantiate";
    // SAFETY: `functions` is NULL or valid, by this function's contract.
    if functions.is_null() || unsafe { (*functions).logger.is_none() } {
        // Without a logger there is nobody to tell.
        return std::ptr::null_mut();
    }
    // SAFETY: as above.
    let callbacks = unsafe { *functions };
    make::<M>(|| {
        // SAFETY: the strings are NULL or NUL-terminated, by this function's contract.
        let (name, guid, resources) = unsafe {
            (
                c_str(instance_name).unwrap_or(""),
                c_str(guid).unwrap_or(""),
                c_str(resource_location),
            )
        };
        let sink = Box::new(Fmi2Sink::new(callbacks, name));
        let logger = Logger::new(sink, logging_on != FMI2_FALSE);
        let interface = match fmu_type {
            FMI2_CO_SIMULATION => Interface::CoSimulation,
            FMI2_MODEL_EXCHANGE => Interface::ModelExchange,
            other => {
                let why = format!("{F}: fmuType {other} is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)");
                return Err((logger, why));
            }
        };
        let resources = resources.and_then(file_uri_to_path);
        let inst = Instance::new(F, &VOCABULARY, name, guid, resources, logger, interface)?;
        inst.log_call(|| format!("{F}(instanceName=\"{name}\", fmuType={})", interface.name()));
        Ok(inst)
    })
}

/// # Safety
/// As `fmi2SetDebugLogging`.
pub unsafe fn set_debug_logging<M: FmuModel>(
    c: Fmi2Component,
    logging_on: Fmi2Boolean,
    n: usize,
    categories: *const Fmi2String,
) -> Fmi2Status {
    // SAFETY: as the C function's contract: `categories` holds `n` strings.
    let status = unsafe {
        with_instance::<M>(c, "fmi2SetDebugLogging", |inst| {
            let categories = slice(categories, n);
            null_check!(inst, categories);
            let mut names = Vec::with_capacity(n);
            for &p in categories {
                match c_str(p) {
                    Some(s) => names.push(s),
                    None => return inst.refuse("a category name is NULL or not UTF-8"),
                }
            }
            inst.set_debug_logging(logging_on != FMI2_FALSE, &names)
        })
    };
    status.into()
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
    const F: &str = "fmi2SetupExperiment";
    // SAFETY: as the C function's contract.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            inst.log_call(|| {
                format!("{F}(toleranceDefined={tolerance_defined}, tolerance={tolerance}, startTime={start_time}, stopTimeDefined={stop_time_defined}, stopTime={stop_time})")
            });
            inst.setup_experiment(
                (tolerance_defined != FMI2_FALSE).then_some(tolerance),
                start_time,
                (stop_time_defined != FMI2_FALSE).then_some(stop_time),
            )
        })
    };
    status.into()
}

/// A call with no arguments but the instance.
///
/// # Safety
/// As the FMI function of the same name.
pub unsafe fn simple_call<M: FmuModel>(
    c: Fmi2Component,
    function: &'static str,
    f: fn(&mut Instance<M>) -> Status,
) -> Fmi2Status {
    // SAFETY: as this function's contract.
    unsafe { crate::fmu::boundary::simple_call::<M>(c, function, f) }.into()
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
    // SAFETY: as this function's contract.
    let status = unsafe {
        with_instance::<M>(c, function, |inst| {
            let (vr, value) = (slice(vr, n), slice_mut(value, n));
            null_check!(inst, vr, value);
            inst.log_call(|| format!("{function}(vr={vr:?})"));
            inst.get(type_name, vr, value, convert)
        })
    };
    status.into()
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
    // SAFETY: as this function's contract.
    let status = unsafe {
        with_instance::<M>(c, function, |inst| {
            let (vr, value) = (slice(vr, n), slice(value, n));
            null_check!(inst, vr, value);
            let mut values = Vec::with_capacity(n);
            for &v in value {
                match convert(v) {
                    Some(v) => values.push(v),
                    None => return inst.refuse("a value is NULL or not UTF-8"),
                }
            }
            inst.log_call(|| format!("{function}(vr={vr:?}, value={values:?})"));
            inst.set(type_name, vr, values)
        })
    };
    status.into()
}

/// # Safety
/// As `fmi2GetString`.
pub unsafe fn get_string<M: FmuModel>(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    n: usize,
    value: *mut Fmi2String,
) -> Fmi2Status {
    // SAFETY: as the C function's contract.
    let status = unsafe {
        with_instance::<M>(c, "fmi2GetString", |inst| {
            let (vr, value) = (slice(vr, n), slice_mut(value, n));
            null_check!(inst, vr, value);
            inst.get_strings(vr, value)
        })
    };
    status.into()
}

/// Reads a C string argument of a setter.
///
/// # Safety
/// `p` is NULL or NUL-terminated.
pub unsafe fn string_value(p: Fmi2String) -> Option<Value> {
    // SAFETY: as this function's contract.
    unsafe { c_str(p) }.map(|s| Value::String(s.to_string()))
}

/// # Safety
/// As `fmi2DoStep`.
pub unsafe fn do_step<M: FmuModel>(
    c: Fmi2Component,
    current_communication_point: Fmi2Real,
    step_size: Fmi2Real,
    _no_set_fmu_state_prior: Fmi2Boolean,
) -> Fmi2Status {
    const F: &str = "fmi2DoStep";
    // SAFETY: as the C function's contract.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            inst.log_call(|| {
                format!("{F}(currentCommunicationPoint={current_communication_point}, communicationStepSize={step_size})")
            });
            inst.do_step(current_communication_point, step_size)
        })
    };
    status.into()
}

/// # Safety
/// As `fmi2SetTime`.
pub unsafe fn set_time<M: FmuModel>(c: Fmi2Component, time: Fmi2Real) -> Fmi2Status {
    // SAFETY: as this function's contract.
    unsafe { core::set_time::<M>(c, "fmi2SetTime", time) }.into()
}

/// # Safety
/// As `fmi2SetContinuousStates`: `x` holds `nx` elements.
pub unsafe fn set_continuous_states<M: FmuModel>(
    c: Fmi2Component,
    x: *const Fmi2Real,
    nx: usize,
) -> Fmi2Status {
    let function = ("fmi2SetContinuousStates", "x");
    // SAFETY: as this function's contract.
    unsafe { core::set_continuous_states::<M>(c, function, x, nx) }.into()
}

/// The Model Exchange getters of a Real array of the states' size: `fmi2GetContinuousStates`,
/// `fmi2GetDerivatives`, `fmi2GetNominalsOfContinuousStates`; `argument` is the array's name.
///
/// # Safety
/// `out` holds `n` elements.
pub unsafe fn get_state_array<M: FmuModel>(
    c: Fmi2Component,
    function: (&'static str, &'static str),
    out: *mut Fmi2Real,
    n: usize,
    f: fn(&mut Instance<M>, &'static str, &mut [f64]) -> Status,
) -> Fmi2Status {
    // SAFETY: as this function's contract.
    unsafe { core::get_state_array::<M>(c, function, out, n, f) }.into()
}

/// # Safety
/// As `fmi2GetEventIndicators`.
pub unsafe fn get_event_indicators<M: FmuModel>(
    c: Fmi2Component,
    indicators: *mut Fmi2Real,
    ni: usize,
) -> Fmi2Status {
    let function = ("fmi2GetEventIndicators", "eventIndicators", "ni");
    // SAFETY: as this function's contract.
    unsafe { core::get_event_indicators::<M>(c, function, indicators, ni) }.into()
}

/// # Safety
/// As `fmi2NewDiscreteStates`.
pub unsafe fn new_discrete_states<M: FmuModel>(
    c: Fmi2Component,
    info: *mut Fmi2EventInfo,
) -> Fmi2Status {
    const F: &str = "fmi2NewDiscreteStates";
    // SAFETY: as the C function's contract: `info` NULL or writable.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            if info.is_null() {
                return inst.refuse("argument 'eventInfo' is NULL");
            }
            inst.log_call(|| format!("{F}()"));
            match inst.update_discrete_states() {
                Ok(e) => {
                    *info = Fmi2EventInfo {
                        new_discrete_states_needed: fmi2_boolean(e.discrete_states_need_update),
                        terminate_simulation: fmi2_boolean(e.terminate_simulation),
                        nominals_of_continuous_states_changed: fmi2_boolean(
                            e.nominals_of_continuous_states_changed,
                        ),
                        values_of_continuous_states_changed: fmi2_boolean(
                            e.values_of_continuous_states_changed,
                        ),
                        next_event_time_defined: fmi2_boolean(e.next_event_time.is_some()),
                        next_event_time: e.next_event_time.unwrap_or(0.0),
                    };
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    };
    status.into()
}

/// # Safety
/// As `fmi2CompletedIntegratorStep`.
pub unsafe fn completed_integrator_step<M: FmuModel>(
    c: Fmi2Component,
    _no_set_fmu_state_prior: Fmi2Boolean,
    enter_event_mode: *mut Fmi2Boolean,
    terminate_simulation: *mut Fmi2Boolean,
) -> Fmi2Status {
    const F: &str = "fmi2CompletedIntegratorStep";
    // SAFETY: as the C function's contract: the out-arguments NULL or writable.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            if enter_event_mode.is_null() || terminate_simulation.is_null() {
                return inst.refuse("argument 'enterEventMode' or 'terminateSimulation' is NULL");
            }
            inst.log_call(|| format!("{F}()"));
            match inst.completed_integrator_step() {
                Ok((event, terminate)) => {
                    *enter_event_mode = fmi2_boolean(event);
                    *terminate_simulation = fmi2_boolean(terminate);
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    };
    status.into()
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
    // SAFETY: as this function's contract.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            let vUnknown_ref = slice(unknown_vrs, n_unknown);
            let vKnown_ref = slice(known_vrs, n_known);
            let dvKnown = slice(dv_known, n_known);
            let dvUnknown = slice_mut(dv_unknown, n_unknown);
            // The arguments by their names in the standard, for the message.
            null_check!(inst, vUnknown_ref, vKnown_ref, dvKnown, dvUnknown);
            let (v_unknown_ref, v_known_ref, dv_known, dv_unknown) =
                (vUnknown_ref, vKnown_ref, dvKnown, dvUnknown);
            inst.log_call(|| format!("{F}(vUnknown_ref={v_unknown_ref:?}, vKnown_ref={v_known_ref:?}, dvKnown={dv_known:?})"));
            inst.directional_derivative("dvKnown", v_unknown_ref, v_known_ref, dv_known, dv_unknown)
        })
    };
    status.into()
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
    // SAFETY: as this function's contract.
    unsafe { with_instance::<M>(c, function, |inst| inst.unsupported(why)) }.into()
}

/// # Safety
/// As `fmi2GetRealStatus`.
pub unsafe fn get_real_status<M: FmuModel>(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Real,
) -> Fmi2Status {
    // SAFETY: as the C function's contract: `value` NULL or writable.
    let status = unsafe {
        with_instance::<M>(c, "fmi2GetRealStatus", |inst| {
            if value.is_null() {
                return inst.refuse("argument 'value' is NULL");
            }
            if kind != FMI2_LAST_SUCCESSFUL_TIME {
                return inst.refuse(&format!("status kind {kind} is not a Real status"));
            }
            match inst.last_successful_time() {
                Ok(t) => {
                    *value = t;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    };
    status.into()
}

/// # Safety
/// As `fmi2GetBooleanStatus`.
pub unsafe fn get_boolean_status<M: FmuModel>(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Boolean,
) -> Fmi2Status {
    // SAFETY: as the C function's contract: `value` NULL or writable.
    let status = unsafe {
        with_instance::<M>(c, "fmi2GetBooleanStatus", |inst| {
            if value.is_null() {
                return inst.refuse("argument 'value' is NULL");
            }
            if kind != FMI2_TERMINATED {
                return inst.refuse(&format!("status kind {kind} is not a Boolean status"));
            }
            match inst.terminated_status() {
                Ok(t) => {
                    *value = fmi2_boolean(t);
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    };
    status.into()
}

/// # Safety
/// As `fmi2FreeInstance`.
pub unsafe fn free_instance<M: FmuModel>(c: Fmi2Component) {
    // SAFETY: as this function's contract.
    unsafe { crate::fmu::boundary::free_instance::<M>(c, "fmi2FreeInstance") }
}

/// The FMU-state functions: the core's, under FMI 2.0's names and status.
pub mod fmu_state {
    use super::super::ffi::*;
    use crate::fmu::boundary::fmu_states as core;
    use crate::fmu::FmuModel;

    /// # Safety
    /// As `fmi2GetFMUstate`.
    pub unsafe fn get<M: FmuModel>(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
        // SAFETY: as this function's contract.
        unsafe { core::get::<M>(c, "fmi2GetFMUstate", state) }.into()
    }

    /// # Safety
    /// As `fmi2SetFMUstate`.
    pub unsafe fn set<M: FmuModel>(c: Fmi2Component, state: Fmi2FmuState) -> Fmi2Status {
        // SAFETY: as this function's contract.
        unsafe { core::set::<M>(c, "fmi2SetFMUstate", state) }.into()
    }

    /// # Safety
    /// As `fmi2FreeFMUstate`.
    pub unsafe fn free<M: FmuModel>(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
        // SAFETY: as this function's contract.
        unsafe { core::free::<M>(c, "fmi2FreeFMUstate", state) }.into()
    }

    /// # Safety
    /// As `fmi2SerializedFMUstateSize`.
    pub unsafe fn serialized_size<M: FmuModel>(
        c: Fmi2Component,
        state: Fmi2FmuState,
        size: *mut usize,
    ) -> Fmi2Status {
        // SAFETY: as this function's contract.
        unsafe { core::serialized_size::<M>(c, "fmi2SerializedFMUstateSize", state, size) }.into()
    }

    /// # Safety
    /// As `fmi2SerializeFMUstate`: `bytes` holds `size` bytes.
    pub unsafe fn serialize<M: FmuModel>(
        c: Fmi2Component,
        state: Fmi2FmuState,
        bytes: *mut Fmi2Byte,
        size: usize,
    ) -> Fmi2Status {
        // SAFETY: as this function's contract (`fmi2Byte` is a `char`, one byte).
        unsafe { core::serialize::<M>(c, "fmi2SerializeFMUstate", state, bytes.cast(), size) }
            .into()
    }

    /// # Safety
    /// As `fmi2DeSerializeFMUstate`: `bytes` holds `size` bytes.
    pub unsafe fn deserialize<M: FmuModel>(
        c: Fmi2Component,
        bytes: *const Fmi2Byte,
        size: usize,
        state: *mut Fmi2FmuState,
    ) -> Fmi2Status {
        // SAFETY: as this function's contract.
        unsafe { core::deserialize::<M>(c, "fmi2DeSerializeFMUstate", bytes.cast(), size, state) }
            .into()
    }
}

/// The static strings of `fmi2GetTypesPlatform` and `fmi2GetVersion`.
pub const TYPES_PLATFORM: &std::ffi::CStr = c"default";
pub const VERSION: &std::ffi::CStr = c"2.0";
