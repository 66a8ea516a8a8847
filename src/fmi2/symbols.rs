//! The `#[no_mangle]` symbols of the FMI 2.0 C API, emitted by
//! [`export_fmi2_cosimulation!`](crate::export_fmi2_cosimulation) in the crate that builds the
//! cdylib: one `extern "C"` function per FMI 2.0 function, each forwarding to
//! [`entries`](super::entries).

/// Emits the FMI 2.0 C API (Co-Simulation and Model Exchange in one binary) for a model type
/// implementing [`FmuModel`](crate::fmu::FmuModel). Call it once, in the crate that builds the
/// cdylib.
#[macro_export]
macro_rules! export_fmi2_cosimulation {
    ($model:ty) => {
        /// The `fmi2*` functions of the FMU, callable from Rust too (tests use them in-process).
        ///
        /// Safety: each has the contract the FMI 2.0 standard gives the C function of its name.
        #[allow(clippy::missing_safety_doc)]
        pub mod fmi2_exports {
            use $crate::fmi2::entries as x;
            use $crate::fmi2::ffi::*;
            use $crate::fmu::calls::Operation;
            use $crate::fmu::variables::Value;
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
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::set_debug_logging::<M>(c, on, n, cats) }
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
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::instantiate::<M>(name, kind, guid, res, f, visible, logging) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::free_instance::<M>(c) }
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
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::setup_experiment::<M>(c, tol_def, tol, start, stop_def, stop) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi2EnterInitializationMode", |i| {
                        i.enter_initialization_mode()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi2ExitInitializationMode", |i| {
                        i.exit_initialization_mode()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Terminate(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::simple_call::<M>(c, "fmi2Terminate", |i| i.terminate()) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Reset(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::simple_call::<M>(c, "fmi2Reset", |i| i.reset()) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetReal(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Real,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, Fmi2Real>(c, "fmi2GetReal", "Real", vr, n, v, |v| match v {
                        Value::Real(x) => *x,
                        _ => 0.0,
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetInteger(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Integer,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, Fmi2Integer>(c, "fmi2GetInteger", "Integer", vr, n, v, |v| {
                        match v {
                            Value::Integer(x) => *x,
                            _ => 0,
                        }
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBoolean(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, Fmi2Boolean>(c, "fmi2GetBoolean", "Boolean", vr, n, v, |v| {
                        match v {
                            Value::Boolean(true) => FMI2_TRUE,
                            _ => FMI2_FALSE,
                        }
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetString(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *mut Fmi2String,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::get_string::<M>(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetReal(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Real,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, Fmi2Real>(c, "fmi2SetReal", "Real", vr, n, v, |v| {
                        Some(Value::Real(v))
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetInteger(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Integer,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, Fmi2Integer>(c, "fmi2SetInteger", "Integer", vr, n, v, |v| {
                        Some(Value::Integer(v))
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetBoolean(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2Boolean,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, Fmi2Boolean>(c, "fmi2SetBoolean", "Boolean", vr, n, v, |v| {
                        Some(Value::Boolean(v != FMI2_FALSE))
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetString(
                c: Fmi2Component,
                vr: *const Fmi2ValueReference,
                n: usize,
                v: *const Fmi2String,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, Fmi2String>(c, "fmi2SetString", "String", vr, n, v, |p| {
                        x::string_value(p)
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetFMUstate(
                c: Fmi2Component,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::get::<M>(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetFMUstate(
                c: Fmi2Component,
                s: Fmi2FmuState,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::set::<M>(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeFMUstate(
                c: Fmi2Component,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::free::<M>(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
                c: Fmi2Component,
                s: Fmi2FmuState,
                size: *mut usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::serialized_size::<M>(c, s, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(
                c: Fmi2Component,
                s: Fmi2FmuState,
                bytes: *mut Fmi2Byte,
                size: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::serialize::<M>(c, s, bytes, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
                c: Fmi2Component,
                bytes: *const Fmi2Byte,
                size: usize,
                s: *mut Fmi2FmuState,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::fmu_state::deserialize::<M>(c, bytes, size, s) }
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
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::get_directional_derivative::<M>(c, u, nu, z, nz, dv, dz) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterEventMode(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::simple_call::<M>(c, "fmi2EnterEventMode", |i| i.enter_event_mode()) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2NewDiscreteStates(
                c: Fmi2Component,
                info: *mut Fmi2EventInfo,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::new_discrete_states::<M>(c, info) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi2EnterContinuousTimeMode", |i| {
                        i.enter_continuous_time_mode()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
                c: Fmi2Component,
                no_prior: Fmi2Boolean,
                enter_event_mode: *mut Fmi2Boolean,
                terminate: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::completed_integrator_step::<M>(c, no_prior, enter_event_mode, terminate)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetTime(c: Fmi2Component, t: Fmi2Real) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::set_time::<M>(c, t) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetContinuousStates(
                c: Fmi2Component,
                v: *const Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::set_continuous_states::<M>(c, v, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetDerivatives(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(
                        c,
                        ("fmi2GetDerivatives", "derivatives"),
                        v,
                        n,
                        |i, a, o| i.derivatives(Operation::GetDerivatives, a, o),
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetEventIndicators(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::get_event_indicators::<M>(c, v, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetContinuousStates(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(c, ("fmi2GetContinuousStates", "x"), v, n, |i, a, o| {
                        i.continuous_states(a, o)
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
                c: Fmi2Component,
                v: *mut Fmi2Real,
                n: usize,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(
                        c,
                        ("fmi2GetNominalsOfContinuousStates", "x_nominal"),
                        v,
                        n,
                        |i, a, o| i.nominals_of_continuous_states(a, o),
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: Fmi2Component,
                _vr: *const Fmi2ValueReference,
                _n: usize,
                _order: *const Fmi2Integer,
                _v: *const Fmi2Real,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2SetRealInputDerivatives",
                        "canInterpolateInputs is false",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: Fmi2Component,
                _vr: *const Fmi2ValueReference,
                _n: usize,
                _order: *const Fmi2Integer,
                _v: *mut Fmi2Real,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2GetRealOutputDerivatives",
                        "maxOutputDerivativeOrder is 0",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DoStep(
                c: Fmi2Component,
                t: Fmi2Real,
                h: Fmi2Real,
                no_prior: Fmi2Boolean,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::do_step::<M>(c, t, h, no_prior) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CancelStep(c: Fmi2Component) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi2CancelStep", "fmi2DoStep never returns fmi2Pending")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2Status,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi2GetStatus", "fmi2DoStep never returns fmi2Pending")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealStatus(
                c: Fmi2Component,
                k: Fmi2StatusKind,
                v: *mut Fmi2Real,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::get_real_status::<M>(c, k, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2Integer,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2GetIntegerStatus",
                        "there is no Integer status in FMI 2.0",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(
                c: Fmi2Component,
                k: Fmi2StatusKind,
                v: *mut Fmi2Boolean,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe { x::get_boolean_status::<M>(c, k, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStringStatus(
                c: Fmi2Component,
                _k: Fmi2StatusKind,
                _v: *mut Fmi2String,
            ) -> Fmi2Status {
                // SAFETY: the importer keeps the FMI 2.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(
                        c,
                        "fmi2GetStringStatus",
                        "fmi2DoStep never returns fmi2Pending",
                    )
                }
            }
        }
    };
}
