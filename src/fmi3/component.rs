//! The FMI 3.0 FMU as a WebAssembly component, after the draft FMI layered standard for
//! WebAssembly, fmi-ls-wasm (<https://github.com/modelica/fmi-ls-wasm>): built for
//! `wasm32-wasip2`, the component exports the draft's `common`, `co-simulation` and
//! `model-exchange` interfaces (`src/fmi3/wit/`) and imports its `callbacks`.
//!
//! Each method of the draft's instance resources is one call of this crate's own FMI 3.0 C ABI
//! ([`crate::fmi3_exports`], the functions the native FMI 3.0 FMU exports), made in-process:
//! the same state machine, checks, log messages, FMU-state format and numbers as the native FMU.
//! What is translated here is only the shape of the arguments: lists for pointer and length
//! pairs, results for out-arguments, a serialised FMU state for the state handle, and the
//! instance's name for the instance environment of the log callback.
//!
//! The draft's results carry values or a status, not both: a call answering OK or Warning returns
//! its values, one answering Discard, Error or Fatal returns that status (its log message says
//! why).

use std::ffi::{c_char, c_void, CStr, CString};
use std::ptr::{null, null_mut};

use crate::fmi3::ffi::{Fmi3Instance, Fmi3InstanceEnvironment, Fmi3Status, Fmi3String};
use crate::fmi3::variables::TIME_VALUE_REFERENCE;
use crate::fmi3_exports as abi;

wit_bindgen::generate!({
    world: "co-simulation-and-model-exchange-fmu",
    path: "src/fmi3/wit",
});

use exports::fmi::fmi3::co_simulation::{self as cs, DoStepResult};
use exports::fmi::fmi3::model_exchange::{self as me, CompletedStepResult};
use fmi::fmi3::callbacks;
use fmi::fmi3::types::{
    DiscreteStatesInfo, IntervalFraction, IntervalQualifier, Status, VariableDependency,
};

/// The component: its exports are implemented on this type.
struct Component;

export!(Component);

impl exports::fmi::fmi3::common::Guest for Component {
    fn get_version() -> String {
        // SAFETY: fmi3GetVersion returns a static NUL-terminated string.
        unsafe { CStr::from_ptr(abi::fmi3GetVersion()) }
            .to_string_lossy()
            .into_owned()
    }
}

impl cs::Guest for Component {
    type CoSimulationInstance = Instance;
}

impl me::Guest for Component {
    type ModelExchangeInstance = Instance;
}

/// One instance of the C ABI, freed with the resource, and the name its log lines carry (as a C
/// string, whose buffer stays where it is while the instance lives: the C ABI keeps its address as
/// the instance environment).
pub struct Instance {
    c: Fmi3Instance,
    _name: CString,
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: `c` came from an fmi3Instantiate* call and is freed once, here.
        unsafe { abi::fmi3FreeInstance(self.c) }
    }
}

/// The log callback the C ABI calls: the instance's name from the environment, then the host's
/// `log-message`.
unsafe extern "C" fn log_message(
    environment: Fmi3InstanceEnvironment,
    status: Fmi3Status,
    category: Fmi3String,
    message: Fmi3String,
) {
    // SAFETY: the environment is the name of an instance, a C string that outlives its C
    // instance; the C ABI passes NUL-terminated strings or null.
    let (name, category, message) = unsafe {
        (
            text(environment.cast::<c_char>().cast_const()),
            text(category),
            text(message),
        )
    };
    callbacks::log_message(&name, wit_status(status), &category, &message);
}

/// A C string as text ("" for null).
///
/// # Safety
/// `s` null or NUL-terminated.
unsafe fn text(s: *const c_char) -> String {
    if s.is_null() {
        String::new()
    } else {
        // SAFETY: by this function's contract.
        unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
    }
}

fn wit_status(s: Fmi3Status) -> Status {
    match s {
        Fmi3Status::Ok => Status::Ok,
        Fmi3Status::Warning => Status::Warning,
        Fmi3Status::Discard => Status::Discard,
        Fmi3Status::Error => Status::Error,
        Fmi3Status::Fatal => Status::Fatal,
    }
}

/// The draft's result for a call with out-values: the values after OK or Warning, else the status.
fn answer<T>(s: Fmi3Status, values: T) -> Result<T, Status> {
    match s {
        Fmi3Status::Ok | Fmi3Status::Warning => Ok(values),
        other => Err(wit_status(other)),
    }
}

/// A string as a C string for the ABI; `None` for one with an interior NUL, which the caller
/// refuses.
fn c_string(s: &str) -> Option<CString> {
    CString::new(s).ok()
}

/// The number of values that `vrs` hold (an array variable holds several); an unknown value
/// reference counts one, and the ABI names it in its refusal.
fn count(vrs: &[u32]) -> usize {
    let table = abi::table();
    vrs.iter()
        .map(|&vr| {
            if vr == TIME_VALUE_REFERENCE {
                1
            } else {
                table.get(vr).map_or(1, |v| v.len)
            }
        })
        .sum()
}

type Getter<T> = unsafe extern "C" fn(Fmi3Instance, *const u32, usize, *mut T, usize) -> Fmi3Status;
type Setter<T> =
    unsafe extern "C" fn(Fmi3Instance, *const u32, usize, *const T, usize) -> Fmi3Status;

impl Instance {
    /// Instantiates through `make`, which gets the name, token and resource path as C strings
    /// and the environment; `None` (with the ABI's log line) when it refuses.
    fn new(
        name: &str,
        token: &str,
        resources: &str,
        make: impl FnOnce(Fmi3String, Fmi3String, Fmi3String, Fmi3InstanceEnvironment) -> Fmi3Instance,
    ) -> Option<Instance> {
        let (name, token, resources) = (c_string(name)?, c_string(token)?, c_string(resources)?);
        let environment = name.as_ptr().cast_mut().cast::<c_void>();
        let c = make(
            name.as_ptr(),
            token.as_ptr(),
            resources.as_ptr(),
            environment,
        );
        (!c.is_null()).then_some(Instance { c, _name: name })
    }

    fn get<T: Copy + Default>(&self, f: Getter<T>, vrs: &[u32]) -> Result<Vec<T>, Status> {
        let mut values = vec![T::default(); count(vrs)];
        // SAFETY: the pointers and lengths are those of live vectors.
        let s = unsafe {
            f(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                values.as_mut_ptr(),
                values.len(),
            )
        };
        answer(s, values)
    }

    fn set<T>(&self, f: Setter<T>, vrs: &[u32], values: &[T]) -> Status {
        // SAFETY: the pointers and lengths are those of live slices.
        wit_status(unsafe {
            f(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                values.as_ptr(),
                values.len(),
            )
        })
    }

    fn call(&self, f: unsafe extern "C" fn(Fmi3Instance) -> Fmi3Status) -> Status {
        // SAFETY: `c` is a live instance.
        wit_status(unsafe { f(self.c) })
    }

    fn get_booleans(&self, vrs: &[u32]) -> Result<Vec<bool>, Status> {
        self.get::<u8>(abi::fmi3GetBoolean, vrs)
            .map(|v| v.into_iter().map(|b| b != 0).collect())
    }

    fn set_booleans(&self, vrs: &[u32], values: &[bool]) -> Status {
        let bytes: Vec<u8> = values.iter().map(|&b| u8::from(b)).collect();
        self.set::<u8>(abi::fmi3SetBoolean, vrs, &bytes)
    }

    fn get_strings(&self, vrs: &[u32]) -> Result<Vec<String>, Status> {
        let mut pointers: Vec<Fmi3String> = vec![null(); count(vrs)];
        // SAFETY: the pointers and lengths are those of live vectors.
        let s = unsafe {
            abi::fmi3GetString(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                pointers.as_mut_ptr(),
                pointers.len(),
            )
        };
        answer(s, ())?;
        // SAFETY: the ABI returned NUL-terminated strings it keeps until the next call.
        Ok(pointers.iter().map(|&p| unsafe { text(p) }).collect())
    }

    fn set_strings(&self, vrs: &[u32], values: &[String]) -> Status {
        let owned: Option<Vec<_>> = values.iter().map(|s| c_string(s)).collect();
        let Some(owned) = owned else {
            return Status::Error;
        };
        let pointers: Vec<Fmi3String> = owned.iter().map(|s| s.as_ptr()).collect();
        self.set(abi::fmi3SetString, vrs, &pointers)
    }

    fn enter_initialization_mode(
        &self,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Status {
        // SAFETY: `c` is a live instance.
        wit_status(unsafe {
            abi::fmi3EnterInitializationMode(
                self.c,
                u8::from(tolerance.is_some()),
                tolerance.unwrap_or(0.0),
                start,
                u8::from(stop.is_some()),
                stop.unwrap_or(0.0),
            )
        })
    }

    fn set_debug_logging(&self, on: bool, categories: &[String]) -> Status {
        let owned: Option<Vec<_>> = categories.iter().map(|s| c_string(s)).collect();
        let Some(owned) = owned else {
            return Status::Error;
        };
        let pointers: Vec<Fmi3String> = owned.iter().map(|s| s.as_ptr()).collect();
        // SAFETY: the pointers are those of live C strings.
        wit_status(unsafe {
            abi::fmi3SetDebugLogging(self.c, u8::from(on), pointers.len(), pointers.as_ptr())
        })
    }

    fn update_discrete_states(&self) -> Result<DiscreteStatesInfo, Status> {
        let mut flags = [false; 5];
        let mut next = 0.0;
        let [a, b, c, d, e] = &mut flags;
        // SAFETY: the out-pointers are live locals.
        let s = unsafe { abi::fmi3UpdateDiscreteStates(self.c, a, b, c, d, e, &mut next) };
        answer(
            s,
            DiscreteStatesInfo {
                new_discrete_states_needed: flags[0],
                terminate_simulation: flags[1],
                nominals_of_continuous_states_changed: flags[2],
                values_of_continuous_states_changed: flags[3],
                next_event_time_defined: flags[4],
                next_event_time: next,
            },
        )
    }

    /// fmi3GetFMUState, serialised at once, and the ABI's state freed.
    fn get_fmu_state(&self) -> Result<Vec<u8>, Status> {
        let mut state = null_mut();
        // SAFETY: `c` is live and the out-pointers are live locals; the state is freed below.
        unsafe {
            let s = abi::fmi3GetFMUState(self.c, &mut state);
            if !matches!(s, Fmi3Status::Ok | Fmi3Status::Warning) {
                return Err(wit_status(s));
            }
            let mut size = 0;
            let mut s = abi::fmi3SerializedFMUStateSize(self.c, state, &mut size);
            let mut bytes = vec![0u8; size];
            if matches!(s, Fmi3Status::Ok | Fmi3Status::Warning) {
                s = abi::fmi3SerializeFMUState(self.c, state, bytes.as_mut_ptr(), size);
            }
            abi::fmi3FreeFMUState(self.c, &mut state);
            answer(s, bytes)
        }
    }

    /// fmi3DeserializeFMUState, then fmi3SetFMUState, and the ABI's state freed.
    fn set_fmu_state(&self, bytes: &[u8]) -> Status {
        let mut state = null_mut();
        // SAFETY: `c` is live, `bytes` a live slice; the state is freed below.
        unsafe {
            let mut s =
                abi::fmi3DeserializeFMUState(self.c, bytes.as_ptr(), bytes.len(), &mut state);
            if matches!(s, Fmi3Status::Ok | Fmi3Status::Warning) {
                s = abi::fmi3SetFMUState(self.c, state);
                abi::fmi3FreeFMUState(self.c, &mut state);
            }
            wit_status(s)
        }
    }

    fn partial_derivative(
        &self,
        adjoint: bool,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
    ) -> Result<Vec<f64>, Status> {
        let f = if adjoint {
            abi::fmi3GetAdjointDerivative
        } else {
            abi::fmi3GetDirectionalDerivative
        };
        let mut sensitivity = vec![0.0; count(if adjoint { knowns } else { unknowns })];
        // SAFETY: the pointers and lengths are those of live vectors.
        let s = unsafe {
            f(
                self.c,
                unknowns.as_ptr(),
                unknowns.len(),
                knowns.as_ptr(),
                knowns.len(),
                seed.as_ptr(),
                seed.len(),
                sensitivity.as_mut_ptr(),
                sensitivity.len(),
            )
        };
        answer(s, sensitivity)
    }

    /// A function this FMU does not offer (clocks, binaries, dependencies, output derivatives):
    /// the ABI's own refusal, with its log message, through `f`.
    fn refused(&self, f: impl FnOnce(Fmi3Instance) -> Fmi3Status) -> Status {
        wit_status(f(self.c))
    }
}

/// The getter and setter of each numeric type: one call of the ABI's function of that type.
macro_rules! numeric_methods {
    ($(($get:ident, $set:ident, $t:ty, $abi_get:ident, $abi_set:ident)),* $(,)?) => {
        $(
            fn $get(&self, value_references: Vec<u32>) -> Result<Vec<$t>, Status> {
                self.get(abi::$abi_get, &value_references)
            }
            fn $set(&self, value_references: Vec<u32>, values: Vec<$t>) -> Status {
                self.set(abi::$abi_set, &value_references, &values)
            }
        )*
    };
}

/// What a refused call answers: its status, or its status as the error of a result.
trait Refusal {
    fn refusal(status: Status) -> Self;
}

impl Refusal for Status {
    fn refusal(status: Status) -> Self {
        status
    }
}

impl<T> Refusal for Result<T, Status> {
    fn refusal(status: Status) -> Self {
        Err(status)
    }
}

/// The clock functions (the model has no clocks): each the ABI's own refusal, its arrays null.
macro_rules! clock_methods {
    ($(fn $name:ident($($arg:ident: $t:ty)?) -> $ret:ty = $abi:ident($($null:expr),*);)*) => {
        $(
            fn $name(&self, value_references: Vec<u32>, $($arg: $t)?) -> $ret {
                let vrs = value_references;
                // SAFETY: the ABI refuses before touching its arrays: the model has no clocks.
                Refusal::refusal(self.refused(|c| unsafe {
                    abi::$abi(c, vrs.as_ptr(), vrs.len(), $($null),*)
                }))
            }
        )*
    };
}

/// The methods both resources have, written once (the draft declares them twice, once per
/// instance kind).
macro_rules! shared_methods {
    () => {
        fn set_debug_logging(&self, logging_on: bool, categories: Vec<String>) -> Status {
            Instance::set_debug_logging(self, logging_on, &categories)
        }
        fn enter_initialization_mode(
            &self,
            tolerance: Option<f64>,
            start_time: f64,
            stop_time: Option<f64>,
        ) -> Status {
            Instance::enter_initialization_mode(self, tolerance, start_time, stop_time)
        }
        fn exit_initialization_mode(&self) -> Status {
            self.call(abi::fmi3ExitInitializationMode)
        }
        fn enter_event_mode(&self) -> Status {
            self.call(abi::fmi3EnterEventMode)
        }
        fn update_discrete_states(&self) -> Result<DiscreteStatesInfo, Status> {
            Instance::update_discrete_states(self)
        }
        fn terminate(&self) -> Status {
            self.call(abi::fmi3Terminate)
        }
        fn reset(&self) -> Status {
            self.call(abi::fmi3Reset)
        }
        fn enter_configuration_mode(&self) -> Status {
            self.call(abi::fmi3EnterConfigurationMode)
        }
        fn exit_configuration_mode(&self) -> Status {
            self.call(abi::fmi3ExitConfigurationMode)
        }
        numeric_methods! {
            (get_float32, set_float32, f32, fmi3GetFloat32, fmi3SetFloat32),
            (get_float64, set_float64, f64, fmi3GetFloat64, fmi3SetFloat64),
            (get_int8, set_int8, i8, fmi3GetInt8, fmi3SetInt8),
            (get_int16, set_int16, i16, fmi3GetInt16, fmi3SetInt16),
            (get_int32, set_int32, i32, fmi3GetInt32, fmi3SetInt32),
            (get_int64, set_int64, i64, fmi3GetInt64, fmi3SetInt64),
            (get_uint8, set_uint8, u8, fmi3GetUInt8, fmi3SetUInt8),
            (get_uint16, set_uint16, u16, fmi3GetUInt16, fmi3SetUInt16),
            (get_uint32, set_uint32, u32, fmi3GetUInt32, fmi3SetUInt32),
            (get_uint64, set_uint64, u64, fmi3GetUInt64, fmi3SetUInt64),
        }
        fn get_boolean(&self, value_references: Vec<u32>) -> Result<Vec<bool>, Status> {
            self.get_booleans(&value_references)
        }
        fn get_string(&self, value_references: Vec<u32>) -> Result<Vec<String>, Status> {
            self.get_strings(&value_references)
        }
        fn get_binary(&self, value_references: Vec<u32>) -> Result<Vec<Vec<u8>>, Status> {
            let vrs = value_references;
            // SAFETY: the ABI refuses before touching the out-arrays (the model has no Binary).
            Err(self.refused(|c| unsafe {
                abi::fmi3GetBinary(c, vrs.as_ptr(), vrs.len(), null_mut(), null_mut(), 0)
            }))
        }
        fn get_clock(&self, value_references: Vec<u32>) -> Result<Vec<bool>, Status> {
            let vrs = value_references;
            // SAFETY: the ABI refuses before touching the out-array (the model has no Clock).
            Err(self
                .refused(|c| unsafe { abi::fmi3GetClock(c, vrs.as_ptr(), vrs.len(), null_mut()) }))
        }
        fn set_boolean(&self, value_references: Vec<u32>, values: Vec<bool>) -> Status {
            self.set_booleans(&value_references, &values)
        }
        fn set_string(&self, value_references: Vec<u32>, values: Vec<String>) -> Status {
            self.set_strings(&value_references, &values)
        }
        fn set_binary(&self, value_references: Vec<u32>, values: Vec<Vec<u8>>) -> Status {
            let (vrs, n) = (value_references, values.len());
            // SAFETY: the ABI refuses before reading the arrays (the model has no Binary).
            self.refused(|c| unsafe {
                abi::fmi3SetBinary(c, vrs.as_ptr(), vrs.len(), null(), null(), n)
            })
        }
        fn set_clock(&self, value_references: Vec<u32>, _values: Vec<bool>) -> Status {
            let vrs = value_references;
            // SAFETY: the ABI refuses before reading the array (the model has no Clock).
            self.refused(|c| unsafe { abi::fmi3SetClock(c, vrs.as_ptr(), vrs.len(), null()) })
        }
        fn get_number_of_variable_dependencies(&self, vr: u32) -> Result<u64, Status> {
            // SAFETY: the ABI refuses before touching the out-argument.
            Err(self.refused(|c| unsafe {
                abi::fmi3GetNumberOfVariableDependencies(c, vr, null_mut())
            }))
        }
        fn get_variable_dependencies(
            &self,
            dependent: u32,
        ) -> Result<Vec<VariableDependency>, Status> {
            // SAFETY: the ABI refuses before touching the out-arrays.
            Err(self.refused(|c| unsafe {
                abi::fmi3GetVariableDependencies(
                    c,
                    dependent,
                    null_mut(),
                    null_mut(),
                    null_mut(),
                    null_mut(),
                    0,
                )
            }))
        }
        fn get_fmu_state(&self) -> Result<Vec<u8>, Status> {
            Instance::get_fmu_state(self)
        }
        fn set_fmu_state(&self, state: Vec<u8>) -> Status {
            Instance::set_fmu_state(self, &state)
        }
        fn get_directional_derivative(
            &self,
            unknowns: Vec<u32>,
            knowns: Vec<u32>,
            seed: Vec<f64>,
        ) -> Result<Vec<f64>, Status> {
            self.partial_derivative(false, &unknowns, &knowns, &seed)
        }
        fn get_adjoint_derivative(
            &self,
            unknowns: Vec<u32>,
            knowns: Vec<u32>,
            seed: Vec<f64>,
        ) -> Result<Vec<f64>, Status> {
            self.partial_derivative(true, &unknowns, &knowns, &seed)
        }
        clock_methods! {
            fn get_interval_decimal() -> Result<Vec<(f64, IntervalQualifier)>, Status>
                = fmi3GetIntervalDecimal(null_mut(), null_mut());
            fn get_interval_fraction() -> Result<Vec<(IntervalFraction, IntervalQualifier)>, Status>
                = fmi3GetIntervalFraction(null_mut(), null_mut(), null_mut());
            fn get_shift_decimal() -> Result<Vec<f64>, Status>
                = fmi3GetShiftDecimal(null_mut());
            fn get_shift_fraction() -> Result<Vec<IntervalFraction>, Status>
                = fmi3GetShiftFraction(null_mut(), null_mut());
            fn set_interval_decimal(_intervals: Vec<f64>) -> Status
                = fmi3SetIntervalDecimal(null());
            fn set_interval_fraction(_intervals: Vec<IntervalFraction>) -> Status
                = fmi3SetIntervalFraction(null(), null());
            fn set_shift_decimal(_shifts: Vec<f64>) -> Status = fmi3SetShiftDecimal(null());
            fn set_shift_fraction(_shifts: Vec<IntervalFraction>) -> Status
                = fmi3SetShiftFraction(null(), null());
        }
        fn evaluate_discrete_states(&self) -> Status {
            self.call(abi::fmi3EvaluateDiscreteStates)
        }
        fn enter_step_mode(&self) -> Status {
            self.call(abi::fmi3EnterStepMode)
        }
        fn get_output_derivatives(&self, requests: Vec<(u32, u32)>) -> Result<Vec<f64>, Status> {
            let vrs: Vec<u32> = requests.iter().map(|r| r.0).collect();
            let orders: Vec<i32> = requests.iter().map(|r| r.1 as i32).collect();
            // SAFETY: the ABI refuses before touching the out-array (maxOutputDerivativeOrder 0).
            Err(self.refused(|c| unsafe {
                abi::fmi3GetOutputDerivatives(
                    c,
                    vrs.as_ptr(),
                    vrs.len(),
                    orders.as_ptr(),
                    null_mut(),
                    0,
                )
            }))
        }
    };
}

impl cs::GuestCoSimulationInstance for Instance {
    #[allow(clippy::too_many_arguments)]
    fn instantiate_co_simulation(
        instance_name: String,
        instantiation_token: String,
        resource_path: String,
        visible: bool,
        logging_on: bool,
        event_mode_used: bool,
        early_return_allowed: bool,
        required_intermediate_variables: Vec<u32>,
    ) -> Option<cs::CoSimulationInstance> {
        let vrs = required_intermediate_variables;
        Instance::new(
            &instance_name,
            &instantiation_token,
            &resource_path,
            |n, t, r, env| {
                // SAFETY: the strings are live C strings, the environment the instance's name.
                unsafe {
                    abi::fmi3InstantiateCoSimulation(
                        n,
                        t,
                        r,
                        u8::from(visible),
                        u8::from(logging_on),
                        u8::from(event_mode_used),
                        u8::from(early_return_allowed),
                        vrs.as_ptr(),
                        vrs.len(),
                        env,
                        Some(log_message),
                        None,
                    )
                }
            },
        )
        .map(cs::CoSimulationInstance::new)
    }

    shared_methods!();

    fn set_input_derivatives(&self, _requests: Vec<(u32, u32)>, _values: Vec<f64>) -> Status {
        // FMI 3.0 has no fmi3SetInputDerivatives (the draft's interface has the method): the
        // FMU's capability flag canInterpolateInputs is false, so an importer never calls it.
        // SAFETY: `c` is a live instance.
        let s = unsafe {
            crate::fmi3::entries::unsupported::<abi::M>(
                self.c,
                "set-input-derivatives",
                "FMI 3.0 has no such function and canInterpolateInputs is false",
            )
        };
        wit_status(s)
    }

    fn do_step(
        &self,
        current_communication_point: f64,
        communication_step_size: f64,
        no_set_fmu_state_prior_to_current_point: bool,
    ) -> Result<DoStepResult, Status> {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
        // SAFETY: `c` is live and the out-pointers are live locals.
        let s = unsafe {
            abi::fmi3DoStep(
                self.c,
                current_communication_point,
                communication_step_size,
                u8::from(no_set_fmu_state_prior_to_current_point),
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        };
        answer(
            s,
            DoStepResult {
                last_successful_time: last,
                event_handling_needed: event,
                terminate_simulation: terminate,
                early_return: early,
            },
        )
    }
}

impl me::GuestModelExchangeInstance for Instance {
    fn instantiate_model_exchange(
        instance_name: String,
        instantiation_token: String,
        resource_path: String,
        visible: bool,
        logging_on: bool,
    ) -> Option<me::ModelExchangeInstance> {
        Instance::new(
            &instance_name,
            &instantiation_token,
            &resource_path,
            |n, t, r, env| {
                // SAFETY: the strings are live C strings, the environment the instance's name.
                unsafe {
                    abi::fmi3InstantiateModelExchange(
                        n,
                        t,
                        r,
                        u8::from(visible),
                        u8::from(logging_on),
                        env,
                        Some(log_message),
                    )
                }
            },
        )
        .map(me::ModelExchangeInstance::new)
    }

    shared_methods!();

    fn enter_continuous_time_mode(&self) -> Status {
        self.call(abi::fmi3EnterContinuousTimeMode)
    }

    fn set_time(&self, time: f64) -> Status {
        // SAFETY: `c` is a live instance.
        wit_status(unsafe { abi::fmi3SetTime(self.c, time) })
    }

    fn set_continuous_states(&self, continuous_states: Vec<f64>) -> Status {
        let x = continuous_states;
        // SAFETY: the pointer and length are those of a live vector.
        wit_status(unsafe { abi::fmi3SetContinuousStates(self.c, x.as_ptr(), x.len()) })
    }

    fn get_continuous_state_derivatives(&self) -> Result<Vec<f64>, Status> {
        self.state_array(abi::fmi3GetContinuousStateDerivatives)
    }

    fn get_event_indicators(&self) -> Result<Vec<f64>, Status> {
        let mut z: Vec<f64> = Vec::new();
        // SAFETY: the model has no event indicators: an empty array.
        let s = unsafe { abi::fmi3GetEventIndicators(self.c, z.as_mut_ptr(), 0) };
        answer(s, z)
    }

    fn get_continuous_states(&self) -> Result<Vec<f64>, Status> {
        self.state_array(abi::fmi3GetContinuousStates)
    }

    fn get_nominals_of_continuous_states(&self) -> Result<Vec<f64>, Status> {
        self.state_array(abi::fmi3GetNominalsOfContinuousStates)
    }

    fn get_number_of_event_indicators(&self) -> Result<u64, Status> {
        self.number(abi::fmi3GetNumberOfEventIndicators)
    }

    fn get_number_of_continuous_states(&self) -> Result<u64, Status> {
        self.number(abi::fmi3GetNumberOfContinuousStates)
    }

    fn completed_integrator_step(
        &self,
        no_set_fmu_state_prior_to_current_point: bool,
    ) -> Result<CompletedStepResult, Status> {
        let (mut event, mut terminate) = (false, false);
        // SAFETY: `c` is live and the out-pointers are live locals.
        let s = unsafe {
            abi::fmi3CompletedIntegratorStep(
                self.c,
                u8::from(no_set_fmu_state_prior_to_current_point),
                &mut event,
                &mut terminate,
            )
        };
        answer(
            s,
            CompletedStepResult {
                enter_event_mode: event,
                terminate_simulation: terminate,
            },
        )
    }
}

impl Instance {
    /// A number the ABI writes to an out-argument.
    fn number(
        &self,
        f: unsafe extern "C" fn(Fmi3Instance, *mut usize) -> Fmi3Status,
    ) -> Result<u64, Status> {
        let mut n = 0usize;
        // SAFETY: `c` is live and the out-pointer a live local.
        let s = unsafe { f(self.c, &mut n) };
        answer(s, n as u64)
    }

    /// An array of one value per continuous state.
    fn state_array(
        &self,
        f: unsafe extern "C" fn(Fmi3Instance, *mut f64, usize) -> Fmi3Status,
    ) -> Result<Vec<f64>, Status> {
        let n = self.number(abi::fmi3GetNumberOfContinuousStates)? as usize;
        let mut values = vec![0.0; n];
        // SAFETY: the pointer and length are those of a live vector.
        let s = unsafe { f(self.c, values.as_mut_ptr(), values.len()) };
        answer(s, values)
    }
}
