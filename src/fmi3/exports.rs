//! The FMI 3.0 entry points, generic over a model. Each translates FMI 3.0's arguments (arrays,
//! one-byte Booleans, the experiment passed to `fmi3EnterInitializationMode`) and hands the call
//! to the same [`Instance`] the FMI 2.0 layer uses: one state machine, one table of allowed
//! calls, one set of checks, one FMU-state format. Instances made here log through FMI 3.0's
//! `logMessage` callback ([`Sink::Fmi3`]).
//! [`export_fmi3!`](crate::export_fmi3) emits the `#[no_mangle]` functions.

use std::os::raw::c_char;

use super::ffi::*;
use super::variables::{fmi3_type_name, Fmi3Table, TIME_VALUE_REFERENCE};
use crate::fmi2::calls::Interface;
use crate::fmi2::exports::{self as fmi2, with_instance};
use crate::fmi2::ffi::{Fmi2Component, Fmi2Status, FMI2_FALSE, FMI2_TRUE};
use crate::fmi2::instance::{c_str, Instance};
use crate::fmi2::logging::{guarded, Logger, Sink};
use crate::fmi2::variables::Value;
use crate::fmi2::FmuModel;

/// The FMI 3.0 status of the shared core's FMI 2.0 status (the first five are the same numbers;
/// the core never returns `fmi2Pending`).
pub fn status(s: Fmi2Status) -> Fmi3Status {
    match s {
        Fmi2Status::Ok => Fmi3Status::Ok,
        Fmi2Status::Warning => Fmi3Status::Warning,
        Fmi2Status::Discard => Fmi3Status::Discard,
        Fmi2Status::Error | Fmi2Status::Pending => Fmi3Status::Error,
        Fmi2Status::Fatal => Fmi3Status::Fatal,
    }
}

/// A C array argument as a slice: empty for n = 0, `None` for NULL with n > 0.
unsafe fn slice<'a, T>(ptr: *const T, n: usize) -> Option<&'a [T]> {
    match (n, ptr.is_null()) {
        (0, _) => Some(&[]),
        (_, true) => None,
        _ => Some(std::slice::from_raw_parts(ptr, n)),
    }
}

unsafe fn slice_mut<'a, T>(ptr: *mut T, n: usize) -> Option<&'a mut [T]> {
    match (n, ptr.is_null()) {
        (0, _) => Some(&mut []),
        (_, true) => None,
        _ => Some(std::slice::from_raw_parts_mut(ptr, n)),
    }
}

/// What an FMI 3.0 value reference stands for in a get or set call.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Element {
    /// The independent variable.
    Time,
    /// An FMI 2.0 scalar, by its value reference.
    Scalar(u32),
}

/// Expands FMI 3.0 value references into FMI 2.0 scalars, checking that each one is known and of
/// `type_name`, and that `n_values` is the number of values they hold.
fn expand<M: FmuModel>(
    table: &Fmi3Table,
    function: &str,
    type_name: &str,
    vrs: &[u32],
    n_values: usize,
) -> Result<Vec<Element>, String> {
    let variables = M::variables();
    let mut out = Vec::with_capacity(n_values);
    for &vr in vrs {
        if vr == TIME_VALUE_REFERENCE {
            if type_name != "Float64" {
                return Err(format!(
                    "{function}: value reference {vr} is 'time', a Float64, not a {type_name}"
                ));
            }
            out.push(Element::Time);
            continue;
        }
        let Some(v) = table.get(vr) else {
            return Err(format!("{function}: unknown value reference {vr}"));
        };
        let first = &variables[v.first];
        let found = fmi3_type_name(&first.kind);
        if found != type_name {
            return Err(format!(
                "{function}: value reference {vr} is '{}', a {found}, not a {type_name}",
                v.name
            ));
        }
        out.extend((0..v.len).map(|k| Element::Scalar(variables[v.first + k].value_reference)));
    }
    if out.len() != n_values {
        return Err(format!(
            "{function}: nValues is {n_values}, but the {} value references hold {} values",
            vrs.len(),
            out.len()
        ));
    }
    Ok(out)
}

/// What `fmi3InstantiateCoSimulation` and `fmi3InstantiateModelExchange` share: the logger on
/// FMI 3.0's callback, the instance with its interface, or NULL with a log line saying why
/// (`refusal`, or the checks of [`Instance::with_logger`]).
///
/// # Safety
/// Strings NULL or NUL-terminated.
#[allow(clippy::too_many_arguments)]
unsafe fn instantiate<M: FmuModel>(
    function: &str,
    interface: Interface,
    refusal: Option<&str>,
    instance_name: Fmi3String,
    token: Fmi3String,
    resource_path: Fmi3String,
    logging_on: bool,
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
) -> Fmi3Instance {
    let result = guarded(|| {
        let name = c_str(instance_name).unwrap_or("");
        let sink = Sink::Fmi3 {
            environment,
            log_message,
        };
        let logger = Logger::with_sink(name, sink, logging_on);
        let refuse = |logger: &Logger, message: &str| {
            logger.log(
                Fmi2Status::Error,
                crate::fmi2::LogCategory::StatusError,
                message,
            );
            std::ptr::null_mut()
        };
        if let Some(why) = refusal {
            return refuse(&logger, &format!("{function}: {why}"));
        }
        let token = c_str(token).unwrap_or("");
        // FMI 3.0 passes the resources folder as a path (FMI 2.0: a URI).
        let resources = c_str(resource_path)
            .filter(|p| !p.is_empty())
            .map(std::path::PathBuf::from);
        match Instance::<M>::with_logger(name, token, resources, logger, interface) {
            Ok(inst) => {
                inst.log_call(|| format!("{function}(instanceName=\"{name}\")"));
                Box::into_raw(Box::new(inst)) as Fmi3Instance
            }
            Err((logger, message)) => refuse(&logger, &message),
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// `fmi3InstantiateCoSimulation`. `earlyReturnAllowed` and the required intermediate variables
/// are accepted and unused: the FMU never returns early and never calls back.
///
/// The FMI 2.0 type name the shared core checks for an FMI 3.0 type the model has (the inverse
/// of [`fmi3_type_name`]); `expand` has already refused every other type.
fn fmi2_type_name(fmi3: &str) -> &'static str {
    match fmi3 {
        "Float64" => "Real",
        "Int32" => "Integer",
        "Boolean" => "Boolean",
        "String" => "String",
        _ => "",
    }
}

/// # Safety
/// As `fmi3InstantiateCoSimulation`: strings NULL or NUL-terminated.
#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate_co_simulation<M: FmuModel>(
    instance_name: Fmi3String,
    token: Fmi3String,
    resource_path: Fmi3String,
    logging_on: bool,
    event_mode_used: bool,
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
) -> Fmi3Instance {
    let refusal = event_mode_used.then_some(
        "eventModeUsed = true, but this FMU has no event mode (hasEventMode = false): the model has no events",
    );
    instantiate::<M>(
        "fmi3InstantiateCoSimulation",
        Interface::CoSimulation,
        refusal,
        instance_name,
        token,
        resource_path,
        logging_on,
        environment,
        log_message,
    )
}

/// `fmi3InstantiateModelExchange`.
///
/// # Safety
/// As `fmi3InstantiateModelExchange`: strings NULL or NUL-terminated.
pub unsafe fn instantiate_model_exchange<M: FmuModel>(
    instance_name: Fmi3String,
    token: Fmi3String,
    resource_path: Fmi3String,
    logging_on: bool,
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
) -> Fmi3Instance {
    instantiate::<M>(
        "fmi3InstantiateModelExchange",
        Interface::ModelExchange,
        None,
        instance_name,
        token,
        resource_path,
        logging_on,
        environment,
        log_message,
    )
}

/// # Safety
/// As `fmi3EnterInitializationMode`.
pub unsafe fn enter_initialization_mode<M: FmuModel>(
    c: Fmi3Instance,
    tolerance_defined: bool,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> Fmi3Status {
    status(with_instance::<M>(
        c,
        "fmi3EnterInitializationMode",
        |inst| {
            inst.log_call(|| {
            format!("fmi3EnterInitializationMode(toleranceDefined={tolerance_defined}, tolerance={tolerance}, startTime={start_time}, stopTimeDefined={stop_time_defined}, stopTime={stop_time})")
        });
            // FMI 3.0 passes the experiment here; FMI 2.0 had fmi2SetupExperiment before it.
            let s = inst.setup_experiment(
                tolerance_defined.then_some(tolerance),
                start_time,
                stop_time_defined.then_some(stop_time),
            );
            if s != Fmi2Status::Ok {
                return s;
            }
            inst.enter_initialization_mode()
        },
    ))
}

/// # Safety
/// As `fmi3SetDebugLogging`.
pub unsafe fn set_debug_logging<M: FmuModel>(
    c: Fmi3Instance,
    logging_on: bool,
    n: usize,
    categories: *const Fmi3String,
) -> Fmi3Status {
    let on = if logging_on { FMI2_TRUE } else { FMI2_FALSE };
    status(fmi2::set_debug_logging::<M>(c, on, n, categories))
}

/// The getters for the types the model has: `fmi3GetFloat64`, `fmi3GetInt32`, `fmi3GetBoolean`.
///
/// # Safety
/// As `fmi3GetFloat64`: `vrs` holds `n_vrs` elements, `values` `n_values`.
#[allow(clippy::too_many_arguments)]
pub unsafe fn get_values<M: FmuModel, T: Copy + Default>(
    table: &Fmi3Table,
    c: Fmi3Instance,
    function: &'static str,
    type_name: &'static str,
    vrs: *const Fmi3ValueReference,
    n_vrs: usize,
    values: *mut T,
    n_values: usize,
    convert: impl Fn(&Value) -> T,
) -> Fmi3Status {
    status(with_instance::<M>(c, function, |inst| {
        let (Some(vrs), Some(values)) = (slice(vrs, n_vrs), slice_mut(values, n_values)) else {
            return inst.error(&format!(
                "{function}: argument 'valueReferences' or 'values' is NULL"
            ));
        };
        inst.log_call(|| format!("{function}(vr={vrs:?})"));
        let elements = match expand::<M>(table, function, type_name, vrs, n_values) {
            Ok(e) => e,
            Err(msg) => return inst.error(&msg),
        };
        let scalars: Vec<u32> = elements
            .iter()
            .filter_map(|e| match e {
                Element::Scalar(vr) => Some(*vr),
                Element::Time => None,
            })
            .collect();
        let mut got = vec![T::default(); scalars.len()];
        let fmi2_type = fmi2_type_name(type_name);
        let s = inst.get(function, fmi2_type, &scalars, &mut got, &convert);
        if s != Fmi2Status::Ok {
            return s;
        }
        let time = convert(&Value::Real(inst.time()));
        let mut got = got.into_iter();
        for (slot, e) in values.iter_mut().zip(&elements) {
            *slot = match e {
                Element::Time => time,
                Element::Scalar(_) => got.next().unwrap_or_default(),
            };
        }
        Fmi2Status::Ok
    }))
}

/// The setters: `fmi3SetFloat64`, `fmi3SetInt32`, `fmi3SetBoolean`.
///
/// # Safety
/// As `fmi3SetFloat64`: `vrs` holds `n_vrs` elements, `values` `n_values`.
#[allow(clippy::too_many_arguments)]
pub unsafe fn set_values<M: FmuModel, T: Copy>(
    table: &Fmi3Table,
    c: Fmi3Instance,
    function: &'static str,
    type_name: &'static str,
    vrs: *const Fmi3ValueReference,
    n_vrs: usize,
    values: *const T,
    n_values: usize,
    convert: impl Fn(T) -> Value,
) -> Fmi3Status {
    status(with_instance::<M>(c, function, |inst| {
        let (Some(vrs), Some(values)) = (slice(vrs, n_vrs), slice(values, n_values)) else {
            return inst.error(&format!(
                "{function}: argument 'valueReferences' or 'values' is NULL"
            ));
        };
        let elements = match expand::<M>(table, function, type_name, vrs, n_values) {
            Ok(e) => e,
            Err(msg) => return inst.error(&msg),
        };
        let mut scalars = Vec::with_capacity(elements.len());
        for e in &elements {
            match e {
                Element::Scalar(vr) => scalars.push(*vr),
                Element::Time => {
                    return inst.error(&format!(
                        "{function}: 'time' is the independent variable and cannot be set"
                    ))
                }
            }
        }
        let new: Vec<Value> = values.iter().map(|&v| convert(v)).collect();
        inst.log_call(|| format!("{function}(vr={vrs:?}, value={new:?})"));
        let fmi2_type = fmi2_type_name(type_name);
        inst.set(function, fmi2_type, &scalars, new)
    }))
}

/// A getter or setter of a type the model has no variable of (`fmi3GetFloat32`, `fmi3SetInt8`,
/// ...): no value reference can be right, and an empty call is a no-op.
///
/// # Safety
/// As the FMI function: `vrs` holds `n_vrs` elements.
pub unsafe fn no_such_type<M: FmuModel>(
    table: &Fmi3Table,
    c: Fmi3Instance,
    function: &'static str,
    type_name: &'static str,
    vrs: *const Fmi3ValueReference,
    n_vrs: usize,
) -> Fmi3Status {
    status(with_instance::<M>(c, function, |inst| {
        if let Err(s) = inst.allowed(function, crate::fmi2::calls::Operation::GetValues) {
            return s;
        }
        let Some(vrs) = slice(vrs, n_vrs) else {
            return inst.error(&format!("{function}: argument 'valueReferences' is NULL"));
        };
        match vrs.first() {
            None => Fmi2Status::Ok,
            Some(&vr) => {
                let msg = expand::<M>(table, function, type_name, &[vr], 1)
                    .err()
                    .unwrap_or_else(|| {
                        format!("{function}: value reference {vr} is not a {type_name}")
                    });
                inst.error(&msg)
            }
        }
    }))
}

/// # Safety
/// As `fmi3GetString`: the strings stay valid until the next call on the instance.
pub unsafe fn get_string<M: FmuModel>(
    table: &Fmi3Table,
    c: Fmi3Instance,
    vrs: *const Fmi3ValueReference,
    n_vrs: usize,
    values: *mut Fmi3String,
    n_values: usize,
) -> Fmi3Status {
    status(with_instance::<M>(c, "fmi3GetString", |inst| {
        let (Some(vr_slice), Some(out)) = (slice(vrs, n_vrs), slice_mut(values, n_values)) else {
            return inst.error("fmi3GetString: argument 'valueReferences' or 'values' is NULL");
        };
        let elements = match expand::<M>(table, "fmi3GetString", "String", vr_slice, n_values) {
            Ok(e) => e,
            Err(msg) => return inst.error(&msg),
        };
        let scalars: Vec<u32> = elements
            .iter()
            .filter_map(|e| match e {
                Element::Scalar(vr) => Some(*vr),
                Element::Time => None,
            })
            .collect();
        inst.get_strings(&scalars, out)
    }))
}

/// # Safety
/// As `fmi3DoStep`: the four out-arguments point to writable memory.
#[allow(clippy::too_many_arguments)]
pub unsafe fn do_step<M: FmuModel>(
    c: Fmi3Instance,
    current_communication_point: f64,
    step_size: f64,
    _no_set_fmu_state_prior: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Fmi3Status {
    status(with_instance::<M>(c, "fmi3DoStep", |inst| {
        if event_handling_needed.is_null()
            || terminate_simulation.is_null()
            || early_return.is_null()
            || last_successful_time.is_null()
        {
            return inst.error("fmi3DoStep: argument 'eventHandlingNeeded', 'terminateSimulation', 'earlyReturn' or 'lastSuccessfulTime' is NULL");
        }
        inst.log_call(|| {
            format!("fmi3DoStep(currentCommunicationPoint={current_communication_point}, communicationStepSize={step_size})")
        });
        let s = inst.do_step(current_communication_point, step_size);
        // The model has no events, never asks to stop and never returns early.
        *event_handling_needed = false;
        *terminate_simulation = false;
        *early_return = false;
        *last_successful_time = inst.time();
        s
    }))
}

/// # Safety
/// As `fmi3GetFMUState`.
pub unsafe fn get_fmu_state<M: FmuModel>(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
    status(fmi2::get_fmu_state::<M>(c as Fmi2Component, state))
}

/// # Safety
/// As `fmi3SetFMUState`.
pub unsafe fn set_fmu_state<M: FmuModel>(c: Fmi3Instance, state: Fmi3FmuState) -> Fmi3Status {
    status(fmi2::set_fmu_state::<M>(c, state))
}

/// # Safety
/// As `fmi3FreeFMUState`.
pub unsafe fn free_fmu_state<M: FmuModel>(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
    status(fmi2::free_fmu_state::<M>(c, state))
}

/// # Safety
/// As `fmi3SerializedFMUStateSize`.
pub unsafe fn serialized_size<M: FmuModel>(
    c: Fmi3Instance,
    state: Fmi3FmuState,
    size: *mut usize,
) -> Fmi3Status {
    status(fmi2::serialized_size::<M>(c, state, size))
}

/// # Safety
/// As `fmi3SerializeFMUState`: `bytes` holds `size` bytes.
pub unsafe fn serialize<M: FmuModel>(
    c: Fmi3Instance,
    state: Fmi3FmuState,
    bytes: *mut Fmi3Byte,
    size: usize,
) -> Fmi3Status {
    status(fmi2::serialize::<M>(c, state, bytes as *mut c_char, size))
}

/// # Safety
/// As `fmi3DeserializeFMUState`: `bytes` holds `size` bytes.
pub unsafe fn deserialize<M: FmuModel>(
    c: Fmi3Instance,
    bytes: *const Fmi3Byte,
    size: usize,
    state: *mut Fmi3FmuState,
) -> Fmi3Status {
    status(fmi2::deserialize::<M>(
        c,
        bytes as *const c_char,
        size,
        state,
    ))
}

/// A function of FMI 3.0 this FMU does not offer (its capability is false in the XML).
///
/// # Safety
/// `c` as for every call.
pub unsafe fn unsupported<M: FmuModel>(
    c: Fmi3Instance,
    function: &'static str,
    why: &'static str,
) -> Fmi3Status {
    status(fmi2::unsupported::<M>(c, function, why))
}

/// # Safety
/// As `fmi3UpdateDiscreteStates`: the six out-arguments point to writable memory.
pub unsafe fn update_discrete_states<M: FmuModel>(
    c: Fmi3Instance,
    discrete_states_need_update: *mut bool,
    terminate_simulation: *mut bool,
    nominals_changed: *mut bool,
    values_changed: *mut bool,
    next_event_time_defined: *mut bool,
    next_event_time: *mut f64,
) -> Fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    status(with_instance::<M>(c, F, |inst| {
        let outs = [
            discrete_states_need_update,
            terminate_simulation,
            nominals_changed,
            values_changed,
            next_event_time_defined,
        ];
        if outs.iter().any(|p| p.is_null()) || next_event_time.is_null() {
            return inst.error(&format!("{F}: an out-argument is NULL"));
        }
        inst.log_call(|| format!("{F}()"));
        let mut info = crate::fmi2::ffi::Fmi2EventInfo {
            new_discrete_states_needed: FMI2_FALSE,
            terminate_simulation: FMI2_FALSE,
            nominals_of_continuous_states_changed: FMI2_FALSE,
            values_of_continuous_states_changed: FMI2_FALSE,
            next_event_time_defined: FMI2_FALSE,
            next_event_time: 0.0,
        };
        let s = inst.new_discrete_states(&mut info);
        if s == Fmi2Status::Ok {
            *discrete_states_need_update = info.new_discrete_states_needed != FMI2_FALSE;
            *terminate_simulation = info.terminate_simulation != FMI2_FALSE;
            *nominals_changed = info.nominals_of_continuous_states_changed != FMI2_FALSE;
            *values_changed = info.values_of_continuous_states_changed != FMI2_FALSE;
            *next_event_time_defined = info.next_event_time_defined != FMI2_FALSE;
            *next_event_time = info.next_event_time;
        }
        s
    }))
}

/// # Safety
/// As `fmi3CompletedIntegratorStep`.
pub unsafe fn completed_integrator_step<M: FmuModel>(
    c: Fmi3Instance,
    enter_event_mode: *mut bool,
    terminate_simulation: *mut bool,
) -> Fmi3Status {
    const F: &str = "fmi3CompletedIntegratorStep";
    status(with_instance::<M>(c, F, |inst| {
        if enter_event_mode.is_null() || terminate_simulation.is_null() {
            return inst.error(&format!(
                "{F}: argument 'enterEventMode' or 'terminateSimulation' is NULL"
            ));
        }
        match inst.completed_integrator_step() {
            Ok((event, terminate)) => {
                *enter_event_mode = event;
                *terminate_simulation = terminate;
                Fmi2Status::Ok
            }
            Err(s) => s,
        }
    }))
}

/// # Safety
/// As `fmi3GetNumberOfContinuousStates` and `fmi3GetNumberOfEventIndicators`.
pub unsafe fn get_number<M: FmuModel>(
    c: Fmi3Instance,
    function: &'static str,
    n: *mut usize,
    value: usize,
) -> Fmi3Status {
    status(with_instance::<M>(c, function, |inst| {
        if n.is_null() {
            return inst.error(&format!("{function}: the out-argument is NULL"));
        }
        if let Err(s) = inst.allowed(function, crate::fmi2::calls::Operation::GetNominals) {
            return s;
        }
        *n = value;
        Fmi2Status::Ok
    }))
}

/// The FMI 2.0 value references of FMI 3.0 Float64 value references (arrays expanded), for the
/// derivative functions; `time` is neither a known nor an unknown of a derivative.
fn expand_reals<M: FmuModel>(
    table: &Fmi3Table,
    function: &str,
    what: &str,
    vrs: &[u32],
    n_values: usize,
) -> Result<Vec<u32>, String> {
    let elements = expand::<M>(table, function, "Float64", vrs, n_values)
        .map_err(|m| m.replace("nValues", what))?;
    elements
        .into_iter()
        .map(|e| match e {
            Element::Scalar(vr) => Ok(vr),
            Element::Time => Err(format!(
                "{function}: 'time' (value reference {TIME_VALUE_REFERENCE}) is neither a known nor an unknown of a partial derivative"
            )),
        })
        .collect()
}

/// `fmi3GetDirectionalDerivative` (`adjoint` false): `sensitivity = J seed`, and
/// `fmi3GetAdjointDerivative` (`adjoint` true): `sensitivity = J^T seed`, with `J` the exact
/// Jacobian of the unknowns (outputs, state derivatives) with respect to the knowns (inputs,
/// continuous states). The adjoint takes one directional derivative per known, a column of `J`
/// each: the model's dual numbers carry one direction at a time.
///
/// # Safety
/// As the FMI functions: each array holds the number of elements its count says.
#[allow(clippy::too_many_arguments)]
pub unsafe fn partial_derivative<M: FmuModel>(
    table: &Fmi3Table,
    c: Fmi3Instance,
    adjoint: bool,
    unknowns: *const Fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const Fmi3ValueReference,
    n_knowns: usize,
    seed: *const f64,
    n_seed: usize,
    sensitivity: *mut f64,
    n_sensitivity: usize,
) -> Fmi3Status {
    let function = if adjoint {
        "fmi3GetAdjointDerivative"
    } else {
        "fmi3GetDirectionalDerivative"
    };
    status(with_instance::<M>(c, function, |inst| {
        let (Some(u), Some(k), Some(seed), Some(out)) = (
            slice(unknowns, n_unknowns),
            slice(knowns, n_knowns),
            slice(seed, n_seed),
            slice_mut(sensitivity, n_sensitivity),
        ) else {
            return inst.error(&format!(
                "{function}: argument 'unknowns', 'knowns', 'seed' or 'sensitivity' is NULL"
            ));
        };
        inst.log_call(|| format!("{function}(unknowns={u:?}, knowns={k:?}, seed={seed:?})"));
        // The seed runs over the knowns (directional) or the unknowns (adjoint), the
        // sensitivity over the other.
        let (n_u, n_k) = if adjoint {
            (n_seed, n_sensitivity)
        } else {
            (n_sensitivity, n_seed)
        };
        let (seed_name, sens_name) = ("nSeed", "nSensitivity");
        let (u_count, k_count) = if adjoint {
            (seed_name, sens_name)
        } else {
            (sens_name, seed_name)
        };
        let u2 = match expand_reals::<M>(table, function, u_count, u, n_u) {
            Ok(v) => v,
            Err(m) => return inst.error(&m),
        };
        let k2 = match expand_reals::<M>(table, function, k_count, k, n_k) {
            Ok(v) => v,
            Err(m) => return inst.error(&m),
        };
        if !adjoint {
            return inst.directional_derivative(&u2, &k2, seed, out);
        }
        // The state and causality checks run before the loop over the knowns: with none, the
        // loop would not run them.
        if let Err(s) = inst.check_derivative_call(&u2, &k2) {
            return s;
        }
        let mut direction = vec![0.0; k2.len()];
        let mut column = vec![0.0; u2.len()];
        for j in 0..k2.len() {
            direction.fill(0.0);
            direction[j] = 1.0;
            let s = inst.directional_derivative(&u2, &k2, &direction, &mut column);
            if s != Fmi2Status::Ok {
                return s;
            }
            out[j] = column.iter().zip(seed).map(|(a, b)| a * b).sum();
        }
        if let Some(j) = out.iter().position(|v| !v.is_finite()) {
            return inst.error(&format!("{function}: sensitivity[{j}] is not finite"));
        }
        Fmi2Status::Ok
    }))
}

/// Logs why an instantiation is refused and returns NULL.
///
/// # Safety
/// `name` is NULL or NUL-terminated; `log` NULL or a valid callback.
pub unsafe fn refuse_instantiation(
    name: Fmi3String,
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
    message: &str,
) -> Fmi3Instance {
    let _ = guarded(|| {
        let sink = Sink::Fmi3 {
            environment,
            log_message,
        };
        Logger::with_sink(c_str(name).unwrap_or(""), sink, true).log(
            Fmi2Status::Error,
            crate::fmi2::LogCategory::StatusError,
            message,
        );
    });
    std::ptr::null_mut()
}

/// `fmi3GetVersion`'s string.
pub const VERSION: &std::ffi::CStr = c"3.0";

/// Reads a one-byte C `bool` without assuming it holds 0 or 1 (any other byte would be undefined
/// behaviour as a Rust `bool`).
pub fn boolean(byte: u8) -> Value {
    Value::Boolean(byte != 0)
}

/// Emits an FMI 3.0 getter and setter pair for a type the model has no variable of (used by
/// [`export_fmi3!`](crate::export_fmi3); `x`, `M` and `table` are those of its module).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_no_such_type {
    ($get:ident, $set:ident, $t:ty, $name:literal) => {
        #[no_mangle]
        pub unsafe extern "C" fn $get(
            c: Fmi3Instance,
            vr: *const Fmi3ValueReference,
            nvr: usize,
            _v: *mut $t,
            _nv: usize,
        ) -> Fmi3Status {
            x::no_such_type::<M>(table(), c, stringify!($get), $name, vr, nvr)
        }
        #[no_mangle]
        pub unsafe extern "C" fn $set(
            c: Fmi3Instance,
            vr: *const Fmi3ValueReference,
            nvr: usize,
            _v: *const $t,
            _nv: usize,
        ) -> Fmi3Status {
            x::no_such_type::<M>(table(), c, stringify!($set), $name, vr, nvr)
        }
    };
}

/// Emits an FMI 3.0 function this FMU does not offer, answering fmi3Error with `$why` (used by
/// [`export_fmi3!`](crate::export_fmi3)).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_unsupported {
    ($why:literal, $name:ident, $($arg:ty),*) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: Fmi3Instance, $(_: $arg),*) -> Fmi3Status {
            x::unsupported::<M>(c, stringify!($name), $why)
        }
    };
}

/// Emits the FMI 3.0 C API (Co-Simulation and Model Exchange; the Scheduled Execution, clock and
/// configuration functions answer fmi3Error, as the capability flags say) for a model type implementing
/// [`FmuModel`](crate::fmi2::FmuModel). Call it once, in the crate that builds the cdylib, beside
/// [`export_fmi2_cosimulation!`](crate::export_fmi2_cosimulation): the function names do not
/// clash, so one binary serves both FMUs.
#[macro_export]
macro_rules! export_fmi3 {
    ($model:ty) => {
        /// The `fmi3*` functions of the FMU, callable from Rust too (tests use them in-process).
        ///
        /// Safety: each has the contract the FMI 3.0 standard gives the C function of its name.
        #[allow(clippy::missing_safety_doc, clippy::too_many_arguments)]
        pub mod fmi3_exports {
            use $crate::fmi2::variables::Value;
            use $crate::fmi3::exports as x;
            use $crate::fmi3::ffi::*;
            use $crate::fmi3::variables::Fmi3Table;
            type M = $model;

            /// The model's FMI 3.0 variables, grouped once per process.
            fn table() -> &'static Fmi3Table {
                static TABLE: std::sync::OnceLock<Fmi3Table> = std::sync::OnceLock::new();
                TABLE.get_or_init(|| {
                    Fmi3Table::new(
                        <M as $crate::fmi2::FmuModel>::variables(),
                        <M as $crate::fmi2::FmuModel>::continuous_states(),
                    )
                })
            }


            #[no_mangle]
            pub extern "C" fn fmi3GetVersion() -> *const std::os::raw::c_char {
                x::VERSION.as_ptr()
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetDebugLogging(
                c: Fmi3Instance,
                on: Fmi3Boolean,
                n: usize,
                cats: *const Fmi3String,
            ) -> Fmi3Status {
                x::set_debug_logging::<M>(c, truthy(on), n, cats)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
                name: Fmi3String,
                token: Fmi3String,
                resources: Fmi3String,
                _visible: Fmi3Boolean,
                logging_on: Fmi3Boolean,
                event_mode_used: Fmi3Boolean,
                _early_return_allowed: Fmi3Boolean,
                _required: *const Fmi3ValueReference,
                _n_required: usize,
                env: Fmi3InstanceEnvironment,
                log: Fmi3LogMessageCallback,
                _intermediate: Fmi3IntermediateUpdateCallback,
            ) -> Fmi3Instance {
                x::instantiate_co_simulation::<M>(
                    name,
                    token,
                    resources,
                    truthy(logging_on),
                    truthy(event_mode_used),
                    env,
                    log,
                )
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateModelExchange(
                name: Fmi3String,
                token: Fmi3String,
                resources: Fmi3String,
                _visible: Fmi3Boolean,
                logging_on: Fmi3Boolean,
                env: Fmi3InstanceEnvironment,
                log: Fmi3LogMessageCallback,
            ) -> Fmi3Instance {
                x::instantiate_model_exchange::<M>(name, token, resources, truthy(logging_on), env, log)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
                name: Fmi3String,
                _token: Fmi3String,
                _resources: Fmi3String,
                _visible: Fmi3Boolean,
                _logging_on: Fmi3Boolean,
                env: Fmi3InstanceEnvironment,
                log: Fmi3LogMessageCallback,
                _clock: Fmi3ClockUpdateCallback,
                _lock: Fmi3PreemptionCallback,
                _unlock: Fmi3PreemptionCallback,
            ) -> Fmi3Instance {
                x::refuse_instantiation(name, env, log, "fmi3InstantiateScheduledExecution: this FMU does not offer scheduled execution")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeInstance(c: Fmi3Instance) {
                $crate::fmi2::exports::free_instance::<M>(c)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterInitializationMode(
                c: Fmi3Instance,
                tol_defined: Fmi3Boolean,
                tol: f64,
                start: f64,
                stop_defined: Fmi3Boolean,
                stop: f64,
            ) -> Fmi3Status {
                x::enter_initialization_mode::<M>(c, truthy(tol_defined), tol, start, truthy(stop_defined), stop)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitInitializationMode(c: Fmi3Instance) -> Fmi3Status {
                x::status($crate::fmi2::exports::simple_call::<M>(
                    c,
                    "fmi3ExitInitializationMode",
                    |i| i.exit_initialization_mode(),
                ))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Terminate(c: Fmi3Instance) -> Fmi3Status {
                x::status($crate::fmi2::exports::simple_call::<M>(c, "fmi3Terminate", |i| {
                    i.terminate()
                }))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Reset(c: Fmi3Instance) -> Fmi3Status {
                x::status($crate::fmi2::exports::simple_call::<M>(c, "fmi3Reset", |i| {
                    i.reset()
                }))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterEventMode(c: Fmi3Instance) -> Fmi3Status {
                // Model Exchange has an event mode (after initialisation); co-simulation with
                // eventModeUsed = false has none, and the shared core refuses it there.
                x::status($crate::fmi2::exports::simple_call::<M>(c, "fmi3EnterEventMode", |i| {
                    i.enter_event_mode()
                }))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterStepMode(c: Fmi3Instance) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3EnterStepMode", "only for eventModeUsed = true, which this FMU refuses")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterConfigurationMode(c: Fmi3Instance) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3EnterConfigurationMode", "the FMU has no structural parameters")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitConfigurationMode(c: Fmi3Instance) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3ExitConfigurationMode", "the FMU has no structural parameters")
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFloat64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut f64,
                nv: usize,
            ) -> Fmi3Status {
                x::get_values::<M, f64>(table(), c, "fmi3GetFloat64", "Float64", vr, nvr, v, nv, |v| match v {
                    Value::Real(x) => *x,
                    _ => 0.0,
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFloat64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const f64,
                nv: usize,
            ) -> Fmi3Status {
                x::set_values::<M, f64>(table(), c, "fmi3SetFloat64", "Float64", vr, nvr, v, nv, Value::Real)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetInt32(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut i32,
                nv: usize,
            ) -> Fmi3Status {
                x::get_values::<M, i32>(table(), c, "fmi3GetInt32", "Int32", vr, nvr, v, nv, |v| match v {
                    Value::Integer(x) => *x,
                    _ => 0,
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetInt32(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const i32,
                nv: usize,
            ) -> Fmi3Status {
                x::set_values::<M, i32>(table(), c, "fmi3SetInt32", "Int32", vr, nvr, v, nv, Value::Integer)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetBoolean(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut u8,
                nv: usize,
            ) -> Fmi3Status {
                x::get_values::<M, u8>(table(), c, "fmi3GetBoolean", "Boolean", vr, nvr, v, nv, |v| {
                    u8::from(matches!(v, Value::Boolean(true)))
                })
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetBoolean(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const u8,
                nv: usize,
            ) -> Fmi3Status {
                x::set_values::<M, u8>(table(), c, "fmi3SetBoolean", "Boolean", vr, nvr, v, nv, x::boolean)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetString(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut Fmi3String,
                nv: usize,
            ) -> Fmi3Status {
                x::get_string::<M>(table(), c, vr, nvr, v, nv)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetString(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *const Fmi3String,
                _nv: usize,
            ) -> Fmi3Status {
                x::no_such_type::<M>(table(), c, "fmi3SetString", "String", vr, nvr)
            }
            $crate::__fmi3_no_such_type!(fmi3GetFloat32, fmi3SetFloat32, f32, "Float32");
            $crate::__fmi3_no_such_type!(fmi3GetInt8, fmi3SetInt8, i8, "Int8");
            $crate::__fmi3_no_such_type!(fmi3GetUInt8, fmi3SetUInt8, u8, "UInt8");
            $crate::__fmi3_no_such_type!(fmi3GetInt16, fmi3SetInt16, i16, "Int16");
            $crate::__fmi3_no_such_type!(fmi3GetUInt16, fmi3SetUInt16, u16, "UInt16");
            $crate::__fmi3_no_such_type!(fmi3GetUInt32, fmi3SetUInt32, u32, "UInt32");
            $crate::__fmi3_no_such_type!(fmi3GetInt64, fmi3SetInt64, i64, "Int64");
            $crate::__fmi3_no_such_type!(fmi3GetUInt64, fmi3SetUInt64, u64, "UInt64");
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetBinary(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _sizes: *mut usize,
                _v: *mut Fmi3Binary,
                _nv: usize,
            ) -> Fmi3Status {
                x::no_such_type::<M>(table(), c, "fmi3GetBinary", "Binary", vr, nvr)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetBinary(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _sizes: *const usize,
                _v: *const Fmi3Binary,
                _nv: usize,
            ) -> Fmi3Status {
                x::no_such_type::<M>(table(), c, "fmi3SetBinary", "Binary", vr, nvr)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetClock(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *mut Fmi3Clock,
            ) -> Fmi3Status {
                x::no_such_type::<M>(table(), c, "fmi3GetClock", "Clock", vr, nvr)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetClock(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *const Fmi3Clock,
            ) -> Fmi3Status {
                x::no_such_type::<M>(table(), c, "fmi3SetClock", "Clock", vr, nvr)
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
                c: Fmi3Instance,
                _vr: Fmi3ValueReference,
                _n: *mut usize,
            ) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3GetNumberOfVariableDependencies", "the dependencies are in <ModelStructure> of modelDescription.xml")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetVariableDependencies(
                c: Fmi3Instance,
                _dependent: Fmi3ValueReference,
                _element_dependent: *mut usize,
                _independents: *mut Fmi3ValueReference,
                _element_independents: *mut usize,
                _kinds: *mut Fmi3DependencyKind,
                _n: usize,
            ) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3GetVariableDependencies", "the dependencies are in <ModelStructure> of modelDescription.xml")
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFMUState(c: Fmi3Instance, s: *mut Fmi3FmuState) -> Fmi3Status {
                x::get_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFMUState(c: Fmi3Instance, s: Fmi3FmuState) -> Fmi3Status {
                x::set_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeFMUState(c: Fmi3Instance, s: *mut Fmi3FmuState) -> Fmi3Status {
                x::free_fmu_state::<M>(c, s)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
                c: Fmi3Instance,
                s: Fmi3FmuState,
                size: *mut usize,
            ) -> Fmi3Status {
                x::serialized_size::<M>(c, s, size)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializeFMUState(
                c: Fmi3Instance,
                s: Fmi3FmuState,
                bytes: *mut Fmi3Byte,
                size: usize,
            ) -> Fmi3Status {
                x::serialize::<M>(c, s, bytes, size)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3DeserializeFMUState(
                c: Fmi3Instance,
                bytes: *const Fmi3Byte,
                size: usize,
                s: *mut Fmi3FmuState,
            ) -> Fmi3Status {
                x::deserialize::<M>(c, bytes, size, s)
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
                c: Fmi3Instance,
                unknowns: *const Fmi3ValueReference,
                nu: usize,
                knowns: *const Fmi3ValueReference,
                nk: usize,
                seed: *const f64,
                ns: usize,
                sensitivity: *mut f64,
                nsens: usize,
            ) -> Fmi3Status {
                x::partial_derivative::<M>(table(), c, false, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetAdjointDerivative(
                c: Fmi3Instance,
                unknowns: *const Fmi3ValueReference,
                nu: usize,
                knowns: *const Fmi3ValueReference,
                nk: usize,
                seed: *const f64,
                ns: usize,
                sensitivity: *mut f64,
                nsens: usize,
            ) -> Fmi3Status {
                x::partial_derivative::<M>(table(), c, true, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetOutputDerivatives(
                c: Fmi3Instance,
                _vr: *const Fmi3ValueReference,
                _nvr: usize,
                _orders: *const i32,
                _v: *mut f64,
                _nv: usize,
            ) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3DoStep(
                c: Fmi3Instance,
                t: f64,
                h: f64,
                no_prior: Fmi3Boolean,
                event: *mut bool,
                terminate: *mut bool,
                early: *mut bool,
                last: *mut f64,
            ) -> Fmi3Status {
                x::do_step::<M>(c, t, h, truthy(no_prior), event, terminate, early, last)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ActivateModelPartition(
                c: Fmi3Instance,
                _clock: Fmi3ValueReference,
                _t: f64,
            ) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3ActivateModelPartition", "the FMU does not offer scheduled execution")
            }

            $crate::__fmi3_unsupported!("the model has no clocks", fmi3GetIntervalDecimal, *const Fmi3ValueReference, usize, *mut f64, *mut Fmi3IntervalQualifier);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3GetIntervalFraction, *const Fmi3ValueReference, usize, *mut u64, *mut u64, *mut Fmi3IntervalQualifier);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3GetShiftDecimal, *const Fmi3ValueReference, usize, *mut f64);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3GetShiftFraction, *const Fmi3ValueReference, usize, *mut u64, *mut u64);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3SetIntervalDecimal, *const Fmi3ValueReference, usize, *const f64);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3SetIntervalFraction, *const Fmi3ValueReference, usize, *const u64, *const u64);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3SetShiftDecimal, *const Fmi3ValueReference, usize, *const f64);
            $crate::__fmi3_unsupported!("the model has no clocks", fmi3SetShiftFraction, *const Fmi3ValueReference, usize, *const u64, *const u64);
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(c: Fmi3Instance) -> Fmi3Status {
                x::unsupported::<M>(c, "fmi3EvaluateDiscreteStates", "the model has no discrete states")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
                c: Fmi3Instance,
                need_update: *mut bool,
                terminate: *mut bool,
                nominals_changed: *mut bool,
                values_changed: *mut bool,
                next_defined: *mut bool,
                next: *mut f64,
            ) -> Fmi3Status {
                x::update_discrete_states::<M>(c, need_update, terminate, nominals_changed, values_changed, next_defined, next)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: Fmi3Instance) -> Fmi3Status {
                x::status($crate::fmi2::exports::simple_call::<M>(c, "fmi3EnterContinuousTimeMode", |i| {
                    i.enter_continuous_time_mode()
                }))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
                c: Fmi3Instance,
                _no_prior: Fmi3Boolean,
                enter_event_mode: *mut bool,
                terminate: *mut bool,
            ) -> Fmi3Status {
                x::completed_integrator_step::<M>(c, enter_event_mode, terminate)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetTime(c: Fmi3Instance, time: f64) -> Fmi3Status {
                x::status($crate::fmi2::exports::set_time::<M>(c, time))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetContinuousStates(c: Fmi3Instance, xs: *const f64, n: usize) -> Fmi3Status {
                x::status($crate::fmi2::exports::set_continuous_states::<M>(c, xs, n))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(c: Fmi3Instance, dx: *mut f64, n: usize) -> Fmi3Status {
                x::status($crate::fmi2::exports::get_state_array::<M>(c, ("fmi3GetContinuousStateDerivatives", "derivatives"), dx, n, |i, o| i.derivatives(o)))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStates(c: Fmi3Instance, xs: *mut f64, n: usize) -> Fmi3Status {
                x::status($crate::fmi2::exports::get_state_array::<M>(c, ("fmi3GetContinuousStates", "continuousStates"), xs, n, |i, o| i.continuous_states(o)))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(c: Fmi3Instance, xs: *mut f64, n: usize) -> Fmi3Status {
                x::status($crate::fmi2::exports::get_state_array::<M>(c, ("fmi3GetNominalsOfContinuousStates", "nominals"), xs, n, |i, o| {
                    i.nominals_of_continuous_states(o)
                }))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetEventIndicators(c: Fmi3Instance, z: *mut f64, n: usize) -> Fmi3Status {
                x::status($crate::fmi2::exports::get_event_indicators::<M>(c, z, n))
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: Fmi3Instance, n: *mut usize) -> Fmi3Status {
                let count = <M as $crate::fmi2::FmuModel>::continuous_states().len();
                x::get_number::<M>(c, "fmi3GetNumberOfContinuousStates", n, count)
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(c: Fmi3Instance, n: *mut usize) -> Fmi3Status {
                x::get_number::<M>(c, "fmi3GetNumberOfEventIndicators", n, 0)
            }
        }
    };
}
