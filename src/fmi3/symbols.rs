//! The `#[no_mangle]` symbols of the FMI 3.0 C API, emitted by [`export_fmi3!`](crate::export_fmi3)
//! in the crate that builds the cdylib: one `extern "C"` function per FMI 3.0 function, each
//! reading its scalar Booleans as bytes ([`truthy`](super::ffi::truthy)) and forwarding to
//! [`entries`](super::entries).

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
            // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
            // the contract of the entry point it forwards to.
            unsafe {
                x::no_such_type::<M>(table(), c, stringify!($get), x::Access::Get, $name, vr, nvr)
            }
        }
        #[no_mangle]
        pub unsafe extern "C" fn $set(
            c: Fmi3Instance,
            vr: *const Fmi3ValueReference,
            nvr: usize,
            _v: *const $t,
            _nv: usize,
        ) -> Fmi3Status {
            // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
            // the contract of the entry point it forwards to.
            unsafe {
                x::no_such_type::<M>(table(), c, stringify!($set), x::Access::Set, $name, vr, nvr)
            }
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
            // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
            // the contract of the entry point it forwards to.
            unsafe {
                x::unsupported::<M>(c, stringify!($name), $why)
            }
        }
    };
}

/// Emits the FMI 3.0 C API (Co-Simulation and Model Exchange; the Scheduled Execution, clock and
/// configuration functions answer fmi3Error, as the capability flags say) for a model type implementing
/// [`FmuModel`](crate::fmu::FmuModel). Call it once, in the crate that builds the cdylib, beside
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
            use $crate::fmu::calls::Operation;
            use $crate::fmu::variables::Value;
            use $crate::fmi3::entries as x;
            use $crate::fmi3::ffi::*;
            use $crate::fmi3::variables::Fmi3Table;
            pub type M = $model;

            /// The model's FMI 3.0 variables, grouped once per process.
            pub fn table() -> &'static Fmi3Table {
                static TABLE: std::sync::OnceLock<Fmi3Table> = std::sync::OnceLock::new();
                TABLE.get_or_init(|| {
                    Fmi3Table::new(
                        <M as $crate::fmu::FmuModel>::variables(),
                        <M as $crate::fmu::FmuModel>::continuous_states(),
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_debug_logging::<M>(c, truthy(on), n, cats)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::instantiate_model_exchange::<M>(name, token, resources, truthy(logging_on), env, log)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
                _name: Fmi3String,
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
                x::refuse_instantiation::<M>(env, log, "fmi3InstantiateScheduledExecution: this FMU does not offer scheduled execution")
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeInstance(c: Fmi3Instance) {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::free_instance::<M>(c)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::enter_initialization_mode::<M>(c, truthy(tol_defined), tol, start, truthy(stop_defined), stop)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitInitializationMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(
                        c,
                        "fmi3ExitInitializationMode",
                        |i| i.exit_initialization_mode(),
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Terminate(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi3Terminate", |i| {
                        i.terminate()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Reset(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi3Reset", |i| {
                        i.reset()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterEventMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    // Model Exchange has an event mode (after initialisation); co-simulation with
                    // eventModeUsed = false has none, and the shared core refuses it there.
                    x::simple_call::<M>(c, "fmi3EnterEventMode", |i| {
                        i.enter_event_mode()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterStepMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3EnterStepMode", "only for eventModeUsed = true, which this FMU refuses")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterConfigurationMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3EnterConfigurationMode", "the FMU has no structural parameters")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitConfigurationMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3ExitConfigurationMode", "the FMU has no structural parameters")
                }
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFloat64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut f64,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, f64>(table(), c, "fmi3GetFloat64", "Float64", vr, nvr, v, nv, |v| match v {
                        Value::Real(x) => *x,
                        _ => 0.0,
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFloat64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const f64,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, f64>(table(), c, "fmi3SetFloat64", "Float64", vr, nvr, v, nv, Value::Real)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetInt32(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut i32,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, i32>(table(), c, "fmi3GetInt32", "Int32", vr, nvr, v, nv, |v| match v {
                        Value::Integer(x) => *x,
                        _ => 0,
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetInt32(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const i32,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, i32>(table(), c, "fmi3SetInt32", "Int32", vr, nvr, v, nv, Value::Integer)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetBoolean(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut u8,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, u8>(table(), c, "fmi3GetBoolean", "Boolean", vr, nvr, v, nv, |v| {
                        u8::from(matches!(v, Value::Boolean(true)))
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetBoolean(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const u8,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, u8>(table(), c, "fmi3SetBoolean", "Boolean", vr, nvr, v, nv, x::boolean)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetString(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut Fmi3String,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_string::<M>(table(), c, vr, nvr, v, nv)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetString(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *const Fmi3String,
                _nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::no_such_type::<M>(table(), c, "fmi3SetString", x::Access::Set, "String", vr, nvr)
                }
            }
            $crate::__fmi3_no_such_type!(fmi3GetFloat32, fmi3SetFloat32, f32, "Float32");
            $crate::__fmi3_no_such_type!(fmi3GetInt8, fmi3SetInt8, i8, "Int8");
            $crate::__fmi3_no_such_type!(fmi3GetUInt8, fmi3SetUInt8, u8, "UInt8");
            $crate::__fmi3_no_such_type!(fmi3GetInt16, fmi3SetInt16, i16, "Int16");
            $crate::__fmi3_no_such_type!(fmi3GetUInt16, fmi3SetUInt16, u16, "UInt16");
            $crate::__fmi3_no_such_type!(fmi3GetUInt32, fmi3SetUInt32, u32, "UInt32");
            // Enumerations (FMI 3.0 reaches them through Int64; values outside i32 are no item,
            // and saturate into a value the item check refuses).
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetInt64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *mut i64,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_values::<M, i64>(table(), c, "fmi3GetInt64", "Int64", vr, nvr, v, nv, |v| match v {
                        Value::Integer(x) => i64::from(*x),
                        _ => 0,
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetInt64(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                v: *const i64,
                nv: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_values::<M, i64>(table(), c, "fmi3SetInt64", "Int64", vr, nvr, v, nv, |v| {
                        Value::Integer(v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32)
                    })
                }
            }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::no_such_type::<M>(table(), c, "fmi3GetBinary", x::Access::Get, "Binary", vr, nvr)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::no_such_type::<M>(table(), c, "fmi3SetBinary", x::Access::Set, "Binary", vr, nvr)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetClock(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *mut Fmi3Clock,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::no_such_type::<M>(table(), c, "fmi3GetClock", x::Access::Get, "Clock", vr, nvr)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetClock(
                c: Fmi3Instance,
                vr: *const Fmi3ValueReference,
                nvr: usize,
                _v: *const Fmi3Clock,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::no_such_type::<M>(table(), c, "fmi3SetClock", x::Access::Set, "Clock", vr, nvr)
                }
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
                c: Fmi3Instance,
                _vr: Fmi3ValueReference,
                _n: *mut usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3GetNumberOfVariableDependencies", "the dependencies are in <ModelStructure> of modelDescription.xml")
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3GetVariableDependencies", "the dependencies are in <ModelStructure> of modelDescription.xml")
                }
            }

            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFMUState(c: Fmi3Instance, s: *mut Fmi3FmuState) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::get::<M>(c, s)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFMUState(c: Fmi3Instance, s: Fmi3FmuState) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::set::<M>(c, s)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeFMUState(c: Fmi3Instance, s: *mut Fmi3FmuState) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::free::<M>(c, s)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
                c: Fmi3Instance,
                s: Fmi3FmuState,
                size: *mut usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::serialized_size::<M>(c, s, size)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializeFMUState(
                c: Fmi3Instance,
                s: Fmi3FmuState,
                bytes: *mut Fmi3Byte,
                size: usize,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::serialize::<M>(c, s, bytes, size)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3DeserializeFMUState(
                c: Fmi3Instance,
                bytes: *const Fmi3Byte,
                size: usize,
                s: *mut Fmi3FmuState,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::fmu_state::deserialize::<M>(c, bytes, size, s)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::partial_derivative::<M>(table(), c, false, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::partial_derivative::<M>(table(), c, true, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0")
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::do_step::<M>(c, t, h, truthy(no_prior), event, terminate, early, last)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ActivateModelPartition(
                c: Fmi3Instance,
                _clock: Fmi3ValueReference,
                _t: f64,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3ActivateModelPartition", "the FMU does not offer scheduled execution")
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::unsupported::<M>(c, "fmi3EvaluateDiscreteStates", "the model has no discrete states")
                }
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
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::update_discrete_states::<M>(c, need_update, terminate, nominals_changed, values_changed, next_defined, next)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: Fmi3Instance) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::simple_call::<M>(c, "fmi3EnterContinuousTimeMode", |i| {
                        i.enter_continuous_time_mode()
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
                c: Fmi3Instance,
                _no_prior: Fmi3Boolean,
                enter_event_mode: *mut bool,
                terminate: *mut bool,
            ) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::completed_integrator_step::<M>(c, enter_event_mode, terminate)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetTime(c: Fmi3Instance, time: f64) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_time::<M>(c, time)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetContinuousStates(c: Fmi3Instance, xs: *const f64, n: usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::set_continuous_states::<M>(c, xs, n)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(c: Fmi3Instance, dx: *mut f64, n: usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(c, ("fmi3GetContinuousStateDerivatives", "derivatives"), dx, n, |i, a, o| i.derivatives(Operation::GetDerivativesWithInitialization, a, o))
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStates(c: Fmi3Instance, xs: *mut f64, n: usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(c, ("fmi3GetContinuousStates", "continuousStates"), xs, n, |i, a, o| i.continuous_states(a, o))
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(c: Fmi3Instance, xs: *mut f64, n: usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_state_array::<M>(c, ("fmi3GetNominalsOfContinuousStates", "nominals"), xs, n, |i, a, o| {
                        i.nominals_of_continuous_states(a, o)
                    })
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetEventIndicators(c: Fmi3Instance, z: *mut f64, n: usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_event_indicators::<M>(c, z, n)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: Fmi3Instance, n: *mut usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    let count = <M as $crate::fmu::FmuModel>::continuous_states().len();
                    x::get_number::<M>(c, "fmi3GetNumberOfContinuousStates", n, count)
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(c: Fmi3Instance, n: *mut usize) -> Fmi3Status {
                // SAFETY: the importer keeps the FMI 3.0 contract of this function, which is
                // the contract of the entry point it forwards to.
                unsafe {
                    x::get_number::<M>(c, "fmi3GetNumberOfEventIndicators", n, 0)
                }
            }
        }
    };
}
