//! The FMI 3.0 entry points, generic over a model. Each translates FMI 3.0's arguments (arrays of
//! array variables, one-byte Booleans, the experiment passed to `fmi3EnterInitializationMode`,
//! the out-arguments of `fmi3DoStep` and `fmi3UpdateDiscreteStates`) into the core's and hands
//! the call to the same [`Instance`] the FMI 2.0 layer uses: one state machine, one table of
//! allowed calls, one set of checks, one FMU-state format. Instances made here log through FMI
//! 3.0's `logMessage` callback ([`Fmi3Sink`]). [`export_fmi3!`](crate::export_fmi3) emits the
//! `#[no_mangle]` functions.

use super::ffi::*;
use super::logger::{Fmi3Sink, VOCABULARY};
use super::variables::{fmi3_reaches, fmi3_type_name, Fmi3Table, TIME_VALUE_REFERENCE};
use crate::fmu::boundary::{
    self as core, c_str, instantiate as make, slice, slice_mut, with_instance,
};
use crate::fmu::calls::Operation;
use crate::fmu::instance::Instance;
use crate::fmu::logging::Logger;
use crate::fmu::variables::Value;
use crate::fmu::{FmuModel, Interface, Status};

/// What an FMI 3.0 value reference stands for in a get or set call.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Element {
    /// The independent variable.
    Time,
    /// A scalar of the variable table, by its value reference.
    Scalar(u32),
}

/// The scalar value references among `elements` (`time` left out).
fn scalars(elements: &[Element]) -> Vec<u32> {
    elements
        .iter()
        .filter_map(|e| match e {
            Element::Scalar(vr) => Some(*vr),
            Element::Time => None,
        })
        .collect()
}

/// Expands FMI 3.0 value references into the scalars of the variable table, checking that each one is known and of
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
        if !fmi3_reaches(type_name, &first.kind) {
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
/// (`refusal`, or the checks of [`Instance::new`]).
///
/// # Safety
/// Strings NULL or NUL-terminated.
#[allow(clippy::too_many_arguments)]
unsafe fn instantiate<M: FmuModel>(
    function: &'static str,
    interface: Interface,
    refusal: Option<&str>,
    instance_name: Fmi3String,
    token: Fmi3String,
    resource_path: Fmi3String,
    logging_on: bool,
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
) -> Fmi3Instance {
    make::<M>(|| {
        // SAFETY: the strings are NULL or NUL-terminated, by this function's contract.
        let (name, token, resources) = unsafe {
            (
                c_str(instance_name).unwrap_or(""),
                c_str(token).unwrap_or(""),
                c_str(resource_path),
            )
        };
        let sink = Box::new(Fmi3Sink {
            environment,
            log_message,
        });
        let logger = Logger::new(sink, logging_on);
        if let Some(why) = refusal {
            return Err((logger, format!("{function}: {why}")));
        }
        // FMI 3.0 passes the resources folder as a path (FMI 2.0: a URI).
        let resources = resources
            .filter(|p| !p.is_empty())
            .map(std::path::PathBuf::from);
        let inst = Instance::new(
            function,
            &VOCABULARY,
            name,
            token,
            resources,
            logger,
            interface,
        )?;
        inst.log_call(|| format!("{function}(instanceName=\"{name}\")"));
        Ok(inst)
    })
}

/// The variable table's type name (the model description's Real, Integer, ...) of an FMI 3.0 type
/// the model has (the inverse of [`fmi3_type_name`]); `expand` has already refused every other
/// type.
fn table_type_name(fmi3: &str) -> &'static str {
    match fmi3 {
        "Float64" => "Real",
        // An Enumeration's values are Integers (reached through Int64, or Int32).
        "Int32" | "Int64" => "Integer",
        "Boolean" => "Boolean",
        "String" => "String",
        _ => "",
    }
}

/// `fmi3InstantiateCoSimulation`. `earlyReturnAllowed` and the required intermediate variables
/// are accepted and unused: the FMU never returns early and never calls back.
///
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
    // SAFETY: the strings are NULL or NUL-terminated, by this function's contract.
    unsafe {
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
    // SAFETY: the strings are NULL or NUL-terminated, by this function's contract.
    unsafe {
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
    const F: &str = "fmi3EnterInitializationMode";
    // SAFETY: as the C function's contract.
    let status = unsafe {
        with_instance::<M>(c, F, |inst| {
            inst.log_call(|| {
                format!("{F}(toleranceDefined={tolerance_defined}, tolerance={tolerance}, startTime={start_time}, stopTimeDefined={stop_time_defined}, stopTime={stop_time})")
            });
            // FMI 3.0 passes the experiment here; FMI 2.0 had fmi2SetupExperiment before it.
            let s = inst.setup_experiment(
                tolerance_defined.then_some(tolerance),
                start_time,
                stop_time_defined.then_some(stop_time),
            );
            if s != Status::Ok {
                return s;
            }
            inst.enter_initialization_mode()
        })
    };
    status.into()
}

/// # Safety
/// As `fmi3SetDebugLogging`: `categories` holds `n` strings.
pub unsafe fn set_debug_logging<M: FmuModel>(
    c: Fmi3Instance,
    logging_on: bool,
    n: usize,
    categories: *const Fmi3String,
) -> Fmi3Status {
    // SAFETY: as this function's contract.
    let status = unsafe {
        with_instance::<M>(c, "fmi3SetDebugLogging", |inst| {
            let Some(categories) = slice(categories, n) else {
                return inst.refuse("argument 'categories' is NULL");
            };
            let mut names = Vec::with_capacity(n);
            for &p in categories {
                match c_str(p) {
                    Some(s) => names.push(s),
                    None => return inst.refuse("a category name is NULL or not UTF-8"),
                }
            }
            inst.set_debug_logging(logging_on, &names)
        })
    };
    status.into()
}

/// The getters for the types the model has: `fmi3GetFloat64`, `fmi3GetInt32`, `fmi3GetInt64`
/// (Enumerations), `fmi3GetBoolean`.
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
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let (Some(vrs), Some(values)) = (slice(vrs, n_vrs), slice_mut(values, n_values)) else {
                return inst.refuse("argument 'valueReferences' or 'values' is NULL");
            };
            inst.log_call(|| format!("{function}(vr={vrs:?})"));
            let elements = match expand::<M>(table, function, type_name, vrs, n_values) {
                Ok(e) => e,
                Err(msg) => return inst.error(&msg),
            };
            let scalars = scalars(&elements);
            let mut got = vec![T::default(); scalars.len()];
            let s = inst.get(table_type_name(type_name), &scalars, &mut got, &convert);
            if s != Status::Ok {
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
            Status::Ok
        })
    }
    .into()
}

/// The setters: `fmi3SetFloat64`, `fmi3SetInt32`, `fmi3SetInt64` (Enumerations), `fmi3SetBoolean`.
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
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let (Some(vrs), Some(values)) = (slice(vrs, n_vrs), slice(values, n_values)) else {
                return inst.refuse("argument 'valueReferences' or 'values' is NULL");
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
                        return inst.refuse("'time' is the independent variable and cannot be set")
                    }
                }
            }
            let new: Vec<Value> = values.iter().map(|&v| convert(v)).collect();
            inst.log_call(|| format!("{function}(vr={vrs:?}, value={new:?})"));
            inst.set(table_type_name(type_name), &scalars, new)
        })
    }
    .into()
}

/// Whether a value function of a type the FMU has no variable of gets or sets
/// ([`no_such_type`]): it is allowed where the getters, or the setters, are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    Get,
    Set,
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
    access: Access,
    type_name: &'static str,
    vrs: *const Fmi3ValueReference,
    n_vrs: usize,
) -> Fmi3Status {
    // A setter is allowed where the setters of the FMU's types are (Instantiated included), a
    // getter where the getters are: the answer then names the value reference and its type
    // (fuzz finding F3: a setter answered "illegal call sequence" in Instantiated).
    let operation = match access {
        Access::Get => Operation::GetValues,
        Access::Set => Operation::SetValues,
    };
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if let Err(s) = inst.allowed(operation) {
                return s;
            }
            let Some(vrs) = slice(vrs, n_vrs) else {
                return inst.refuse("argument 'valueReferences' is NULL");
            };
            match vrs.first() {
                None => Status::Ok,
                Some(&vr) => {
                    let msg = expand::<M>(table, function, type_name, &[vr], 1)
                        .err()
                        .unwrap_or_else(|| {
                            format!("{function}: value reference {vr} is not a {type_name}")
                        });
                    inst.error(&msg)
                }
            }
        })
    }
    .into()
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
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, "fmi3GetString", |inst| {
            let (Some(vr_slice), Some(out)) = (slice(vrs, n_vrs), slice_mut(values, n_values))
            else {
                return inst.refuse("argument 'valueReferences' or 'values' is NULL");
            };
            let elements = match expand::<M>(table, "fmi3GetString", "String", vr_slice, n_values) {
                Ok(e) => e,
                Err(msg) => return inst.error(&msg),
            };
            let scalars = scalars(&elements);
            inst.get_strings(&scalars, out)
        })
    }
    .into()
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
    // SAFETY: as this function's contract.
    unsafe { with_instance::<M>(c, "fmi3DoStep", |inst| {
        if event_handling_needed.is_null()
            || terminate_simulation.is_null()
            || early_return.is_null()
            || last_successful_time.is_null()
        {
            return inst.refuse("argument 'eventHandlingNeeded', 'terminateSimulation', 'earlyReturn' or 'lastSuccessfulTime' is NULL");
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
    }) }.into()
}

/// The FMU-state functions: the core's, under FMI 3.0's names and status.
pub mod fmu_state {
    use super::super::ffi::*;
    use crate::fmu::boundary::fmu_states as core;
    use crate::fmu::FmuModel;

    /// # Safety
    /// As `fmi3GetFMUState`.
    pub unsafe fn get<M: FmuModel>(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::get::<M>(c, "fmi3GetFMUState", state) }.into()
    }

    /// # Safety
    /// As `fmi3SetFMUState`.
    pub unsafe fn set<M: FmuModel>(c: Fmi3Instance, state: Fmi3FmuState) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::set::<M>(c, "fmi3SetFMUState", state) }.into()
    }

    /// # Safety
    /// As `fmi3FreeFMUState`.
    pub unsafe fn free<M: FmuModel>(c: Fmi3Instance, state: *mut Fmi3FmuState) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::free::<M>(c, "fmi3FreeFMUState", state) }.into()
    }

    /// # Safety
    /// As `fmi3SerializedFMUStateSize`.
    pub unsafe fn serialized_size<M: FmuModel>(
        c: Fmi3Instance,
        state: Fmi3FmuState,
        size: *mut usize,
    ) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::serialized_size::<M>(c, "fmi3SerializedFMUStateSize", state, size) }.into()
    }

    /// # Safety
    /// As `fmi3SerializeFMUState`: `bytes` holds `size` bytes.
    pub unsafe fn serialize<M: FmuModel>(
        c: Fmi3Instance,
        state: Fmi3FmuState,
        bytes: *mut Fmi3Byte,
        size: usize,
    ) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::serialize::<M>(c, "fmi3SerializeFMUState", state, bytes, size) }.into()
    }

    /// # Safety
    /// As `fmi3DeserializeFMUState`: `bytes` holds `size` bytes.
    pub unsafe fn deserialize<M: FmuModel>(
        c: Fmi3Instance,
        bytes: *const Fmi3Byte,
        size: usize,
        state: *mut Fmi3FmuState,
    ) -> Fmi3Status {
        // SAFETY: as this function's contract.
        unsafe { core::deserialize::<M>(c, "fmi3DeserializeFMUState", bytes, size, state) }.into()
    }
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
    // SAFETY: as this function's contract.
    unsafe { with_instance::<M>(c, function, |inst| inst.unsupported(why)) }.into()
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
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, F, |inst| {
            let outs = [
                discrete_states_need_update,
                terminate_simulation,
                nominals_changed,
                values_changed,
                next_event_time_defined,
            ];
            if outs.iter().any(|p| p.is_null()) || next_event_time.is_null() {
                return inst.refuse("an out-argument is NULL");
            }
            inst.log_call(|| format!("{F}()"));
            match inst.update_discrete_states() {
                Ok(e) => {
                    *discrete_states_need_update = e.discrete_states_need_update;
                    *terminate_simulation = e.terminate_simulation;
                    *nominals_changed = e.nominals_of_continuous_states_changed;
                    *values_changed = e.values_of_continuous_states_changed;
                    *next_event_time_defined = e.next_event_time.is_some();
                    *next_event_time = e.next_event_time.unwrap_or(0.0);
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
    .into()
}

/// # Safety
/// As `fmi3CompletedIntegratorStep`.
pub unsafe fn completed_integrator_step<M: FmuModel>(
    c: Fmi3Instance,
    enter_event_mode: *mut bool,
    terminate_simulation: *mut bool,
) -> Fmi3Status {
    const F: &str = "fmi3CompletedIntegratorStep";
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, F, |inst| {
            if enter_event_mode.is_null() || terminate_simulation.is_null() {
                return inst.refuse("argument 'enterEventMode' or 'terminateSimulation' is NULL");
            }
            match inst.completed_integrator_step() {
                Ok((event, terminate)) => {
                    *enter_event_mode = event;
                    *terminate_simulation = terminate;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
    .into()
}

/// # Safety
/// As `fmi3GetNumberOfContinuousStates` and `fmi3GetNumberOfEventIndicators`.
pub unsafe fn get_number<M: FmuModel>(
    c: Fmi3Instance,
    function: &'static str,
    n: *mut usize,
    value: usize,
) -> Fmi3Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if n.is_null() {
                return inst.refuse("the out-argument is NULL");
            }
            if let Err(s) = inst.allowed(Operation::GetNominals) {
                return s;
            }
            *n = value;
            Status::Ok
        })
    }
    .into()
}

/// The scalar value references of FMI 3.0 Float64 value references (arrays expanded), for the
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
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let (Some(u), Some(k), Some(seed), Some(out)) = (
                slice(unknowns, n_unknowns),
                slice(knowns, n_knowns),
                slice(seed, n_seed),
                slice_mut(sensitivity, n_sensitivity),
            ) else {
                return inst
                    .refuse("argument 'unknowns', 'knowns', 'seed' or 'sensitivity' is NULL");
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
                return inst.directional_derivative("seed", &u2, &k2, seed, out);
            }
            // The state and causality checks run before the loop over the knowns: with none, the
            // loop would not run them.
            if let Err(s) = inst.check_derivative_call(&u2, &k2) {
                return s;
            }
            // The seed is checked up front as the directional derivative checks its own: with
            // no knowns the loop below would never look at it.
            if let Some(j) = seed.iter().position(|v| !v.is_finite()) {
                return inst.refuse(&format!("seed[{j}] = {} is not finite", seed[j]));
            }
            let mut direction = vec![0.0; k2.len()];
            let mut column = vec![0.0; u2.len()];
            for j in 0..k2.len() {
                direction.fill(0.0);
                direction[j] = 1.0;
                let s = inst.directional_derivative("seed", &u2, &k2, &direction, &mut column);
                if s != Status::Ok {
                    return s;
                }
                out[j] = column.iter().zip(seed).map(|(a, b)| a * b).sum();
            }
            if let Some(j) = out.iter().position(|v| !v.is_finite()) {
                return inst.refuse(&format!("sensitivity[{j}] is not finite"));
            }
            Status::Ok
        })
    }
    .into()
}

/// Logs why an instantiation is refused and returns NULL.
pub fn refuse_instantiation<M: FmuModel>(
    environment: Fmi3InstanceEnvironment,
    log_message: Fmi3LogMessageCallback,
    message: &str,
) -> Fmi3Instance {
    make::<M>(|| {
        let sink = Box::new(Fmi3Sink {
            environment,
            log_message,
        });
        Err((Logger::new(sink, true), message.to_string()))
    })
}

/// `fmi3GetVersion`'s string.
pub const VERSION: &std::ffi::CStr = c"3.0";

/// Reads a one-byte C `bool` without assuming it holds 0 or 1 (any other byte would be undefined
/// behaviour as a Rust `bool`).
pub fn boolean(byte: u8) -> Value {
    Value::Boolean(super::ffi::truthy(byte))
}

/// A call with no arguments but the instance.
///
/// # Safety
/// As the FMI function of the same name.
pub unsafe fn simple_call<M: FmuModel>(
    c: Fmi3Instance,
    function: &'static str,
    f: fn(&mut Instance<M>) -> Status,
) -> Fmi3Status {
    // SAFETY: as this function's contract.
    unsafe { crate::fmu::boundary::simple_call::<M>(c, function, f) }.into()
}

/// # Safety
/// As `fmi3FreeInstance`.
pub unsafe fn free_instance<M: FmuModel>(c: Fmi3Instance) {
    // SAFETY: as this function's contract.
    unsafe { crate::fmu::boundary::free_instance::<M>(c, "fmi3FreeInstance") }
}

/// # Safety
/// As `fmi3SetTime`.
pub unsafe fn set_time<M: FmuModel>(c: Fmi3Instance, time: f64) -> Fmi3Status {
    // SAFETY: as this function's contract.
    unsafe { core::set_time::<M>(c, "fmi3SetTime", time) }.into()
}

/// # Safety
/// As `fmi3SetContinuousStates`: `x` holds `n` elements.
pub unsafe fn set_continuous_states<M: FmuModel>(
    c: Fmi3Instance,
    x: *const f64,
    n: usize,
) -> Fmi3Status {
    let function = ("fmi3SetContinuousStates", "continuousStates");
    // SAFETY: as this function's contract.
    unsafe { core::set_continuous_states::<M>(c, function, x, n) }.into()
}

/// The Model Exchange getters of a Float64 array of the states' size:
/// `fmi3GetContinuousStates`, `fmi3GetContinuousStateDerivatives`,
/// `fmi3GetNominalsOfContinuousStates`; `argument` is the array's name.
///
/// # Safety
/// `out` holds `n` elements.
pub unsafe fn get_state_array<M: FmuModel>(
    c: Fmi3Instance,
    function: (&'static str, &'static str),
    out: *mut f64,
    n: usize,
    f: fn(&mut Instance<M>, &'static str, &mut [f64]) -> Status,
) -> Fmi3Status {
    // SAFETY: as this function's contract.
    unsafe { core::get_state_array::<M>(c, function, out, n, f) }.into()
}

/// # Safety
/// As `fmi3GetEventIndicators`.
pub unsafe fn get_event_indicators<M: FmuModel>(
    c: Fmi3Instance,
    indicators: *mut f64,
    n: usize,
) -> Fmi3Status {
    let function = (
        "fmi3GetEventIndicators",
        "eventIndicators",
        "nEventIndicators",
    );
    // SAFETY: as this function's contract.
    unsafe { core::get_event_indicators::<M>(c, function, indicators, n) }.into()
}
