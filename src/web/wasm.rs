//! The functions the `.wasm` exports, called by `docs/web/hsp.js`: plain numbers and pointers into
//! the module's memory (no bindings generator, so that the page needs nothing but the `.wasm`
//! and the script). Texts go both ways as UTF-8 in memory: JavaScript writes its JSON into a
//! buffer from [`hsp_alloc`]; a function that answers with text leaves it in a buffer whose
//! address and length [`hsp_text_ptr`] and [`hsp_text_len`] give, valid until the next call.
//!
//! Statuses are the core's, numbered as FMI numbers them: 0 ok, 1 warning, 2 discard, 3 error
//! (the text buffer then holds the message). A panic aborts (WebAssembly has no unwinding): the
//! module traps, JavaScript sees a `RuntimeError`, and [`hsp_panic_message`] tells what
//! happened; the page then makes a new module instance.

use std::cell::RefCell;

use super::{variables_json, Simulation};
use crate::model::presets::presets_json;

thread_local! {
    static TEXT: RefCell<String> = const { RefCell::new(String::new()) };
    static PANIC: RefCell<String> = const { RefCell::new(String::new()) };
}

fn answer(text: String) -> usize {
    let len = text.len();
    TEXT.with(|t| *t.borrow_mut() = text);
    len
}

fn status(result: Result<bool, String>) -> i32 {
    match result {
        Ok(false) => 0,
        Ok(true) => 1,
        Err(message) => {
            answer(message);
            3
        }
    }
}

/// # Safety
/// `ptr` and `len` describe UTF-8 written by JavaScript into a buffer from [`hsp_alloc`].
unsafe fn text<'a>(ptr: *const u8, len: usize) -> Result<&'a str, String> {
    if ptr.is_null() {
        return Err("no text given".into());
    }
    // SAFETY: the caller's contract.
    let bytes = unsafe { std::slice::from_raw_parts(ptr, len) };
    std::str::from_utf8(bytes).map_err(|e| format!("the text is not UTF-8: {e}"))
}

/// # Safety
/// `sim` is null or a pointer from [`hsp_new`] not yet freed.
unsafe fn simulation<'a>(sim: *mut Simulation) -> Result<&'a mut Simulation, String> {
    // SAFETY: the caller's contract.
    unsafe { sim.as_mut() }.ok_or_else(|| "no simulation (null handle)".to_string())
}

/// `len` bytes for JavaScript to write into, aligned for f64 (freed with [`hsp_dealloc`]).
#[no_mangle]
pub extern "C" fn hsp_alloc(len: usize) -> *mut u8 {
    let words = len.div_ceil(8).max(1);
    let mut buffer = vec![0u64; words].into_boxed_slice();
    let ptr = buffer.as_mut_ptr();
    std::mem::forget(buffer);
    ptr.cast()
}

/// Frees a buffer from [`hsp_alloc`].
///
/// # Safety
/// `ptr` and `len` are those of one [`hsp_alloc`] call, not yet freed.
#[no_mangle]
pub unsafe extern "C" fn hsp_dealloc(ptr: *mut u8, len: usize) {
    if !ptr.is_null() {
        let words = len.div_ceil(8).max(1);
        // SAFETY: the caller's contract: this is the boxed slice hsp_alloc leaked.
        drop(unsafe {
            Box::from_raw(std::ptr::slice_from_raw_parts_mut(ptr.cast::<u64>(), words))
        });
    }
}

/// Where the last text answer is.
#[no_mangle]
pub extern "C" fn hsp_text_ptr() -> *const u8 {
    TEXT.with(|t| t.borrow().as_ptr())
}

/// The length of the last text answer in bytes.
#[no_mangle]
pub extern "C" fn hsp_text_len() -> usize {
    TEXT.with(|t| t.borrow().len())
}

/// The variable table as JSON (see [`variables_json`]); returns its length.
#[no_mangle]
pub extern "C" fn hsp_variables() -> usize {
    answer(variables_json().to_string())
}

/// The presets as JSON; returns its length.
#[no_mangle]
pub extern "C" fn hsp_presets() -> usize {
    answer(presets_json().to_string())
}

/// The message of the panic that aborted the module, if one did; returns its length.
#[no_mangle]
pub extern "C" fn hsp_panic_message() -> usize {
    answer(PANIC.with(|p| p.borrow().clone()))
}

/// A new simulation from `{"preset": NAME, "settings": {NAME: VALUE, ...}}` (both optional;
/// values as numbers, booleans or enumeration item names). Null on failure, with the message as
/// the text answer.
///
/// # Safety
/// As [`text`].
#[no_mangle]
pub unsafe extern "C" fn hsp_new(ptr: *const u8, len: usize) -> *mut Simulation {
    install_panic_hook();
    // SAFETY: the caller's contract.
    let made = unsafe { text(ptr, len) }.and_then(|json| {
        let (preset, settings) = super::parse_request(json)?;
        Simulation::new(&preset, &settings)
    });
    match made {
        Ok(sim) => Box::into_raw(Box::new(sim)),
        Err(message) => {
            answer(message);
            std::ptr::null_mut()
        }
    }
}

/// Frees a simulation.
///
/// # Safety
/// `sim` is null or a pointer from [`hsp_new`] not yet freed.
#[no_mangle]
pub unsafe extern "C" fn hsp_free(sim: *mut Simulation) {
    if !sim.is_null() {
        // SAFETY: the caller's contract.
        drop(unsafe { Box::from_raw(sim) });
    }
}

/// Back to t = 0 with the same preset and settings.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_reset(sim: *mut Simulation) -> i32 {
    // SAFETY: the caller's contract.
    status(unsafe { simulation(sim) }.and_then(|s| s.reset().map(|_| false)))
}

/// The simulated time \[s\] (NaN for a null handle).
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_time(sim: *mut Simulation) -> f64 {
    // SAFETY: the caller's contract.
    unsafe { simulation(sim) }.map_or(f64::NAN, |s| s.time())
}

/// Sets a Real input or tunable parameter by value reference.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_set_real(sim: *mut Simulation, vr: u32, value: f64) -> i32 {
    // SAFETY: the caller's contract.
    status(unsafe { simulation(sim) }.and_then(|s| s.set_real(vr, value).map(|_| false)))
}

/// One communication step of `h` seconds.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_step(sim: *mut Simulation, h: f64) -> i32 {
    // SAFETY: the caller's contract.
    status(unsafe { simulation(sim) }.and_then(|s| s.step(h)))
}

/// Reads `n` Reals by value reference (`vrs`, `n` u32) into `out` (`n` f64).
///
/// # Safety
/// As [`hsp_free`]; `vrs` and `out` point to `n` values each in the module's memory.
#[no_mangle]
pub unsafe extern "C" fn hsp_get_reals(
    sim: *mut Simulation,
    vrs: *const u32,
    n: usize,
    out: *mut f64,
) -> i32 {
    if vrs.is_null() || out.is_null() {
        return status(Err("get: null array".into()));
    }
    // SAFETY: the caller's contract.
    let (vrs, out) = unsafe {
        (
            std::slice::from_raw_parts(vrs, n),
            std::slice::from_raw_parts_mut(out, n),
        )
    };
    // SAFETY: the caller's contract.
    status(unsafe { simulation(sim) }.and_then(|s| s.get_reals(vrs, out).map(|_| false)))
}

/// Runs `n` communication steps (see [`Simulation::run`]): the input `input_vr` from `inputs`
/// (`n` f64) before each, the `nvr` Reals `vrs` after each into `out` (`n nvr` f64, row by row);
/// the number of steps done goes to `done`.
///
/// # Safety
/// As [`hsp_free`]; the pointers point to as many values as said, in the module's memory.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn hsp_run(
    sim: *mut Simulation,
    h: f64,
    input_vr: u32,
    inputs: *const f64,
    n: usize,
    vrs: *const u32,
    nvr: usize,
    out: *mut f64,
    done: *mut u32,
) -> i32 {
    if inputs.is_null() || vrs.is_null() || out.is_null() || done.is_null() {
        return status(Err("run: null array".into()));
    }
    // SAFETY: the caller's contract.
    let (inputs, vrs, out) = unsafe {
        (
            std::slice::from_raw_parts(inputs, n),
            std::slice::from_raw_parts(vrs, nvr),
            std::slice::from_raw_parts_mut(out, n.saturating_mul(nvr)),
        )
    };
    // SAFETY: the caller's contract.
    let (steps, result) = match unsafe { simulation(sim) } {
        Ok(s) => s.run(h, input_vr, inputs, vrs, out),
        Err(e) => (0, Err(e)),
    };
    // SAFETY: the caller's contract.
    unsafe { done.write(steps as u32) };
    status(result)
}

/// The plate's deflection on an `nx` x `ny` grid into `out` (`nx ny` f64), see
/// [`Simulation::deflection`].
///
/// # Safety
/// As [`hsp_free`]; `out` points to `nx ny` f64 in the module's memory.
#[no_mangle]
pub unsafe extern "C" fn hsp_deflection(
    sim: *mut Simulation,
    nx: usize,
    ny: usize,
    out: *mut f64,
) -> i32 {
    if out.is_null() {
        return status(Err("deflection: null array".into()));
    }
    // SAFETY: the caller's contract.
    let out = unsafe { std::slice::from_raw_parts_mut(out, nx.saturating_mul(ny)) };
    // SAFETY: the caller's contract.
    status(unsafe { simulation(sim) }.and_then(|s| s.deflection(nx, ny, out).map(|_| false)))
}

/// What [`hsp_deflection`] multiplies, as the text `{"coordinates": [VR, ...], "map": [...]}`
/// (see [`Simulation::deflection_map`]); status 0 with it as the text answer, 3 with the message.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_deflection_map(sim: *mut Simulation, nx: usize, ny: usize) -> i32 {
    // SAFETY: the caller's contract.
    let made = unsafe { simulation(sim) }.and_then(|s| s.deflection_map(nx, ny));
    match made {
        Ok((coordinates, map)) => {
            answer(serde_json::json!({"coordinates": coordinates, "map": map}).to_string());
            0
        }
        Err(message) => status(Err(message)),
    }
}

/// The SSP 1.0 parameter set of `{"preset", "settings", "name", "description"}` (see
/// [`super::parameter_set_json`]); status 0 with the `.ssv`'s text as the text answer, 3 with
/// the message.
///
/// # Safety
/// As [`text`].
#[no_mangle]
pub unsafe extern "C" fn hsp_parameter_set(ptr: *const u8, len: usize) -> i32 {
    // SAFETY: the caller's contract.
    match unsafe { text(ptr, len) }.and_then(super::parameter_set_json) {
        Ok(set) => {
            answer(set);
            0
        }
        Err(message) => status(Err(message)),
    }
}

/// The plate's size as the text `[a, b]` \[m\]; returns its length (0 before the model is built).
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_plate_size(sim: *mut Simulation) -> usize {
    // SAFETY: the caller's contract.
    match unsafe { simulation(sim) }.ok().and_then(|s| s.plate_size()) {
        Some((a, b)) => answer(serde_json::json!([a, b]).to_string()),
        None => answer(String::new()),
    }
}

/// The validity monitors as JSON, `[{"variable", "limit"}]` (see [`Simulation::monitors`]);
/// returns its length.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_monitors(sim: *mut Simulation) -> usize {
    // SAFETY: the caller's contract.
    let monitors = unsafe { simulation(sim) }.map_or_else(|_| Vec::new(), |s| s.monitors());
    let list: Vec<serde_json::Value> = monitors
        .into_iter()
        .map(|(variable, limit)| serde_json::json!({"variable": variable, "limit": limit}))
        .collect();
    answer(serde_json::Value::from(list).to_string())
}

/// The messages logged since the last call, as a JSON list of `{status, category, message}`;
/// returns its length.
///
/// # Safety
/// As [`hsp_free`].
#[no_mangle]
pub unsafe extern "C" fn hsp_messages(sim: *mut Simulation) -> usize {
    // SAFETY: the caller's contract.
    let messages = unsafe { simulation(sim) }.map_or_else(|_| Vec::new(), |s| s.take_messages());
    answer(serde_json::to_string(&messages).unwrap_or_default())
}

/// Keeps a panic's message and place for [`hsp_panic_message`] (the module traps right after).
fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            PANIC.with(|p| *p.borrow_mut() = info.to_string());
        }))
    });
}
