//! A minimal FMI 2.0 importer for `hsp run` and the benchmarks: unpacks the `.fmu`, `dlopen`s its
//! shared object and calls it through the C ABI, exactly as an importing tool would (co-simulation;
//! a Model Exchange instance for a caller that looks up the functions it needs with
//! [`Fmu::symbol`]).

use std::ffi::{c_void, CStr, CString};
use std::os::raw::{c_char, c_int, c_uint};
use std::path::{Path, PathBuf};

use hydraulic_slewing_plate::fmi2::ffi::{
    Fmi2CallbackFunctions, Fmi2Component, Fmi2Status, Fmi2Type, FMI2_CO_SIMULATION, FMI2_FALSE,
    FMI2_MODEL_EXCHANGE, FMI2_TRUE,
};
use hydraulic_slewing_plate::fmu::Kind;
use hydraulic_slewing_plate::model::variables::{vr, GUID, MODEL_IDENTIFIER, VARIABLES};

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const Fmi2CallbackFunctions,
    c_int,
    c_int,
) -> Fmi2Component;
type Setup = unsafe extern "C" fn(Fmi2Component, c_int, f64, f64, c_int, f64) -> Fmi2Status;
type Simple = unsafe extern "C" fn(Fmi2Component) -> Fmi2Status;
type GetReal = unsafe extern "C" fn(Fmi2Component, *const c_uint, usize, *mut f64) -> Fmi2Status;
type SetReal = unsafe extern "C" fn(Fmi2Component, *const c_uint, usize, *const f64) -> Fmi2Status;
type GetInteger =
    unsafe extern "C" fn(Fmi2Component, *const c_uint, usize, *mut c_int) -> Fmi2Status;
type SetInteger =
    unsafe extern "C" fn(Fmi2Component, *const c_uint, usize, *const c_int) -> Fmi2Status;
type SetBoolean =
    unsafe extern "C" fn(Fmi2Component, *const c_uint, usize, *const c_int) -> Fmi2Status;
type DoStep = unsafe extern "C" fn(Fmi2Component, f64, f64, c_int) -> Fmi2Status;
type Free = unsafe extern "C" fn(Fmi2Component);

/// The logger. FMI's logger is variadic, which stable Rust cannot define; this FMU passes its
/// message as the format with '%' doubled and no further arguments, so a five-argument function
/// receives all of it.
unsafe extern "C" fn logger(
    _env: *mut c_void,
    name: *const c_char,
    status: Fmi2Status,
    category: *const c_char,
    format: *const c_char,
) {
    let s = |p: *const c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: a non-null string argument of the logger is NUL-terminated (FMI 2.0).
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let message = s(format).replace("%%", "%");
    if status == Fmi2Status::Warning {
        // Kept for the summary of the run (the validity monitors' warnings, say).
        if let Ok(mut w) = WARNINGS.lock() {
            w.push(message);
            return;
        }
    }
    eprintln!("[{}] {:?} {}: {}", s(name), status, s(category), message);
}

/// The warnings the FMU logged, in order.
static WARNINGS: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

/// Takes the warnings the FMU has logged so far.
pub fn take_warnings() -> Vec<String> {
    WARNINGS
        .lock()
        .map(|mut w| std::mem::take(&mut *w))
        .unwrap_or_default()
}

/// The exported symbol `name` of the library `handle`, as a `T`.
///
/// # Safety
///
/// `handle` comes from `dlopen` and `T` is the function-pointer type of the symbol.
unsafe fn sym<T: Copy>(handle: *mut c_void, name: &str) -> Result<T, String> {
    let c = CString::new(name).map_err(|e| e.to_string())?;
    // SAFETY: a handle from dlopen and a NUL-terminated name.
    let p = unsafe { libc::dlsym(handle, c.as_ptr()) };
    if p.is_null() {
        return Err(format!("the FMU does not export {name}"));
    }
    // SAFETY: the caller names a symbol whose type is `T`, a function pointer.
    Ok(unsafe { std::mem::transmute_copy(&p) })
}

/// An unpacked FMU with its library loaded.
pub struct Fmu {
    handle: *mut c_void,
    dir: PathBuf,
    instantiate: Instantiate,
    setup: Setup,
    enter_init: Simple,
    exit_init: Simple,
    terminate: Simple,
    get_real: GetReal,
    set_real: SetReal,
    get_integer: GetInteger,
    set_integer: SetInteger,
    set_boolean: SetBoolean,
    do_step: DoStep,
    free: Free,
}

/// `Ok` for a status of at most Warning, else an error naming the call `what`.
pub fn check(status: Fmi2Status, what: &str) -> Result<(), String> {
    if status <= Fmi2Status::Warning {
        Ok(())
    } else {
        Err(format!("{what} returned {status:?}"))
    }
}

impl Fmu {
    /// Unpacks `fmu` into a fresh temporary folder and loads its shared object.
    pub fn load(fmu: &Path) -> Result<Fmu, String> {
        // One folder per load, so that a process can load two FMUs side by side.
        static LOADED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = LOADED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("hsp-run-{}-{n}", std::process::id()));
        let file = std::fs::File::open(fmu).map_err(|e| format!("{}: {e}", fmu.display()))?;
        let mut archive =
            zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", fmu.display()))?;
        archive
            .extract(&dir)
            .map_err(|e| format!("unpacking {}: {e}", fmu.display()))?;
        let so = dir.join(format!("binaries/linux64/{MODEL_IDENTIFIER}.so"));
        let path = CString::new(so.to_string_lossy().as_bytes()).map_err(|e| e.to_string())?;
        // SAFETY: dlopen of a path we just wrote; RTLD_LOCAL keeps its symbols apart from ours.
        let handle = unsafe { libc::dlopen(path.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if handle.is_null() {
            let err = unsafe { CStr::from_ptr(libc::dlerror()) }
                .to_string_lossy()
                .into_owned();
            return Err(format!("dlopen {}: {err}", so.display()));
        }
        // SAFETY: the symbols are the FMI 2.0 functions with the signatures above.
        unsafe {
            Ok(Fmu {
                instantiate: sym(handle, "fmi2Instantiate")?,
                setup: sym(handle, "fmi2SetupExperiment")?,
                enter_init: sym(handle, "fmi2EnterInitializationMode")?,
                exit_init: sym(handle, "fmi2ExitInitializationMode")?,
                terminate: sym(handle, "fmi2Terminate")?,
                get_real: sym(handle, "fmi2GetReal")?,
                set_real: sym(handle, "fmi2SetReal")?,
                get_integer: sym(handle, "fmi2GetInteger")?,
                set_integer: sym(handle, "fmi2SetInteger")?,
                set_boolean: sym(handle, "fmi2SetBoolean")?,
                do_step: sym(handle, "fmi2DoStep")?,
                free: sym(handle, "fmi2FreeInstance")?,
                handle,
                dir,
            })
        }
    }

    /// Another exported function of the loaded library (an FMI 3.0 one, say).
    ///
    /// # Safety
    ///
    /// `T` must be the function-pointer type of the symbol `name`.
    #[allow(dead_code)] // bench-latency's FMI 3.0 calls; `hsp` needs none
    pub unsafe fn symbol<T: Copy>(&self, name: &str) -> Result<T, String> {
        // SAFETY: the handle came from dlopen; the caller vouches for `T`.
        unsafe { sym(self.handle, name) }
    }

    /// Instantiates a co-simulation slave.
    pub fn instantiate(&self, name: &str) -> Result<Instance<'_>, String> {
        self.instantiate_as(name, FMI2_CO_SIMULATION)
    }

    /// Instantiates a Model Exchange model.
    #[allow(dead_code)] // bench-model-exchange's; `hsp` needs none
    pub fn instantiate_model_exchange(&self, name: &str) -> Result<Instance<'_>, String> {
        self.instantiate_as(name, FMI2_MODEL_EXCHANGE)
    }

    fn instantiate_as(&self, name: &str, interface: Fmi2Type) -> Result<Instance<'_>, String> {
        let callbacks = Fmi2CallbackFunctions::with_plain_logger(logger, std::ptr::null_mut());
        let name = CString::new(name).map_err(|e| e.to_string())?;
        let guid = CString::new(GUID).map_err(|e| e.to_string())?;
        let resources = CString::new(format!("file://{}/resources", self.dir.display()))
            .map_err(|e| e.to_string())?;
        // SAFETY: fmi2Instantiate of the loaded FMU with NUL-terminated strings and callbacks that outlive the call.
        let c = unsafe {
            (self.instantiate)(
                name.as_ptr(),
                interface,
                guid.as_ptr(),
                resources.as_ptr(),
                &callbacks,
                FMI2_FALSE,
                FMI2_FALSE,
            )
        };
        if c.is_null() {
            return Err("fmi2Instantiate returned NULL".into());
        }
        Ok(Instance { fmu: self, c })
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: the handle came from dlopen and no symbol of it is used after the drop.
        unsafe { libc::dlclose(self.handle) };
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// One instance of a loaded FMU.
pub struct Instance<'a> {
    fmu: &'a Fmu,
    c: Fmi2Component,
}

impl Instance<'_> {
    /// The instance's `fmi2Component`, for the functions a caller looks up with
    /// [`Fmu::symbol`].
    #[allow(dead_code)] // bench-model-exchange's; `hsp` needs none
    pub fn component(&self) -> Fmi2Component {
        self.c
    }

    pub fn setup(&self, tolerance: Option<f64>, start: f64, stop: f64) -> Result<(), String> {
        let tol_def = if tolerance.is_some() {
            FMI2_TRUE
        } else {
            FMI2_FALSE
        };
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe {
                (self.fmu.setup)(
                    self.c,
                    tol_def,
                    tolerance.unwrap_or(0.0),
                    start,
                    FMI2_TRUE,
                    stop,
                )
            },
            "fmi2SetupExperiment",
        )
    }
    pub fn enter_initialization(&self) -> Result<(), String> {
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.enter_init)(self.c) },
            "fmi2EnterInitializationMode",
        )
    }
    pub fn exit_initialization(&self) -> Result<(), String> {
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.exit_init)(self.c) },
            "fmi2ExitInitializationMode",
        )
    }
    pub fn terminate(&self) -> Result<(), String> {
        // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
        check(unsafe { (self.fmu.terminate)(self.c) }, "fmi2Terminate")
    }
    pub fn get_reals(&self, vrs: &[u32]) -> Result<Vec<f64>, String> {
        let mut out = vec![0.0; vrs.len()];
        self.get_reals_into(vrs, &mut out)?;
        Ok(out)
    }
    /// `fmi2GetReal` into `out` (as long as `vrs`), allocating nothing.
    pub fn get_reals_into(&self, vrs: &[u32], out: &mut [f64]) -> Result<(), String> {
        assert_eq!(vrs.len(), out.len(), "one value per reference");
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.get_real)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) },
            "fmi2GetReal",
        )
    }
    pub fn set_real(&self, vr: u32, v: f64) -> Result<(), String> {
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.set_real)(self.c, &vr, 1, &v) },
            "fmi2SetReal",
        )
    }
    pub fn get_integers(&self, vrs: &[u32]) -> Result<Vec<i32>, String> {
        let mut out = vec![0; vrs.len()];
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.get_integer)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) },
            "fmi2GetInteger",
        )?;
        Ok(out)
    }
    pub fn set_integer(&self, vr: u32, v: i32) -> Result<(), String> {
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.set_integer)(self.c, &vr, 1, &v) },
            "fmi2SetInteger",
        )
    }
    pub fn set_boolean(&self, vr: u32, v: bool) -> Result<(), String> {
        let v = if v { FMI2_TRUE } else { FMI2_FALSE };
        check(
            // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
            unsafe { (self.fmu.set_boolean)(self.c, &vr, 1, &v) },
            "fmi2SetBoolean",
        )
    }
    /// Sets a variable from a command line's `NAME=VALUE`, by its type in the variable table.
    pub fn set_from_text(&self, assignment: &str) -> Result<(), String> {
        let (name, text) = assignment
            .split_once('=')
            .ok_or_else(|| format!("--set '{assignment}': expected NAME=VALUE"))?;
        let (name, text) = (name.trim(), text.trim());
        let var = VARIABLES
            .iter()
            .find(|v| v.name == name)
            .ok_or_else(|| format!("--set: unknown variable '{name}'"))?;
        let bad = || format!("--set {name}: '{text}' is not a {}", var.kind.type_name());
        let vr = var.value_reference;
        match var.kind {
            Kind::Real { .. } => self.set_real(vr, text.parse().map_err(|_| bad())?),
            Kind::Integer { .. } => self.set_integer(vr, text.parse().map_err(|_| bad())?),
            // An item by its value or its name (`plate.root=2` or `plate.root=Locked`).
            Kind::Enumeration { declared, .. } => {
                let value = text.parse().ok().or_else(|| {
                    let item = declared.items.iter().find(|i| i.name == text);
                    item.map(|i| i.value)
                });
                let bad = || {
                    format!(
                        "--set {name}: '{text}' is not a {} ({})",
                        declared.name,
                        declared.listing()
                    )
                };
                self.set_integer(vr, value.ok_or_else(bad)?)
            }
            Kind::Boolean { .. } => match text {
                "true" | "1" => self.set_boolean(vr, true),
                "false" | "0" => self.set_boolean(vr, false),
                _ => Err(bad()),
            },
            Kind::String { .. } => Err(format!("--set {name}: String variables cannot be set")),
        }
    }

    /// The solver statistics: steps, rejected, f evaluations, Jacobians, LU factorisations.
    pub fn solver_stats(&self) -> Result<Vec<i32>, String> {
        self.get_integers(&[
            vr::SOLVER_STEPS,
            vr::SOLVER_REJECTED,
            vr::SOLVER_F_EVALS,
            vr::SOLVER_JAC_EVALS,
            vr::SOLVER_LU,
        ])
    }

    pub fn do_step(&self, t: f64, h: f64) -> Result<(), String> {
        // The message is formatted only on failure: a step allocates nothing here.
        check(self.do_step_status(t, h), "fmi2DoStep").map_err(|e| format!("{e} at t = {t}"))
    }

    /// `fmi2DoStep`'s status alone (what a latency measurement times).
    #[inline]
    pub fn do_step_status(&self, t: f64, h: f64) -> Fmi2Status {
        // SAFETY: a function of the loaded FMU with its live instance and arguments that outlive the call.
        unsafe { (self.fmu.do_step)(self.c, t, h, FMI2_TRUE) }
    }
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        // SAFETY: an instance of this FMU, freed once, here, on drop.
        unsafe { (self.fmu.free)(self.c) };
    }
}
