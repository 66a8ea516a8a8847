//! What every C entry point does the same way in both FMI versions: it checks its instance
//! pointer (instances and FMU states carry a magic number), reads its C arrays and strings,
//! names the called function for the messages, and runs under the panic guard, which turns a
//! panic into [`Status::Fatal`] with a log line: a panic must never unwind into the host.
//!
//! The FMI layers pass their own C types in as plain pointers ([`Handle`] for an instance or an
//! FMU state) and their function names as strings; nothing here knows an FMI version.
//! [`fmu_states`] holds the FMU-state functions, the same in both versions.

pub mod fmu_states;

use std::ffi::{c_void, CStr};
use std::path::PathBuf;

use super::instance::Instance;
use super::logging::Logger;
use super::panic_guard::guarded;
use super::{FmuModel, LogCategory, Status};

/// An instance or FMU-state pointer as the C API passes it (`fmi2Component`, `fmi3Instance`,
/// `fmi2FMUstate`, `fmi3FMUState` are all `void*`).
pub type Handle = *mut c_void;

/// A C array argument as a slice: empty for n = 0, `None` for NULL with n > 0.
///
/// # Safety
/// `ptr` is NULL or points to `n` readable, initialised elements that stay valid and unchanged
/// for `'a`.
pub unsafe fn slice<'a, T>(ptr: *const T, n: usize) -> Option<&'a [T]> {
    match (n, ptr.is_null()) {
        (0, _) => Some(&[]),
        (_, true) => None,
        // SAFETY: non-null, and the caller guarantees `n` valid elements for 'a.
        _ => Some(unsafe { std::slice::from_raw_parts(ptr, n) }),
    }
}

/// A C array out-argument as a mutable slice: empty for n = 0, `None` for NULL with n > 0.
///
/// # Safety
/// `ptr` is NULL or points to `n` writable elements, not aliased elsewhere for `'a`.
pub unsafe fn slice_mut<'a, T>(ptr: *mut T, n: usize) -> Option<&'a mut [T]> {
    match (n, ptr.is_null()) {
        (0, _) => Some(&mut []),
        (_, true) => None,
        // SAFETY: non-null, and the caller guarantees `n` exclusive elements for 'a.
        _ => Some(unsafe { std::slice::from_raw_parts_mut(ptr, n) }),
    }
}

/// Reads a C string argument, `None` for NULL or text that is not UTF-8.
///
/// # Safety
/// `ptr` is NULL or a valid NUL-terminated string.
pub unsafe fn c_str<'a>(ptr: *const std::os::raw::c_char) -> Option<&'a str> {
    if ptr.is_null() {
        None
    } else {
        // SAFETY: non-null, and the caller guarantees a NUL-terminated string.
        unsafe { CStr::from_ptr(ptr) }.to_str().ok()
    }
}

/// Runs `f` on the instance behind `c` for the C function `function`, with the checks and the
/// panic guard every call needs: [`Status::Error`] for a pointer that is not a live instance of
/// this library, [`Status::Fatal`] with a log line for a panic.
///
/// # Safety
/// `c` is NULL or a pointer returned by an instantiation function of this library.
pub unsafe fn with_instance<M: FmuModel>(
    c: Handle,
    function: &'static str,
    f: impl FnOnce(&mut Instance<M>) -> Status,
) -> Status {
    let ptr = c as *mut Instance<M>;
    // SAFETY: a non-null pointer from the importer points at least to the 8 bytes of an
    // instance's magic number (the contract of the C API).
    if c.is_null() || !unsafe { Instance::is_instance(ptr) } {
        return Status::Error;
    }
    // SAFETY: the magic number says this is a live instance of this library; the importer
    // does not call it from two threads at once (FMI 2.0.4, 2.1.3; FMI 3.0, 2.2.1).
    let inst = unsafe { &mut *ptr };
    inst.begin_call(function);
    match guarded(|| f(inst)) {
        Ok(status) => status,
        Err(what) => {
            // SAFETY: as above; the guarded borrow has ended. The logger only reads the sink
            // and its switches, which a panic cannot have broken.
            let inst = unsafe { &mut *ptr };
            inst.fatal(&format!("{function}: internal error: {what}"))
        }
    }
}

/// Logs the call (under `logCalls`) and runs an operation with no arguments.
///
/// # Safety
/// As [`with_instance`].
pub unsafe fn simple_call<M: FmuModel>(
    c: Handle,
    function: &'static str,
    f: fn(&mut Instance<M>) -> Status,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            inst.log_call(|| format!("{function}()"));
            f(inst)
        })
    }
}

/// Instantiates under the panic guard: `make` builds the instance (or says why not, with the
/// logger to say it through); the result is the handle to return, NULL on refusal.
pub fn instantiate<M: FmuModel>(
    make: impl FnOnce() -> Result<Instance<M>, (Logger, String)>,
) -> Handle {
    let result = guarded(|| match make() {
        Ok(inst) => {
            // Under logCalls: which sources the binary was built from (the marker is also how a
            // test tells a stale packaged binary, see tools/source_hash.rs).
            inst.log_call(|| format!("built from {}", crate::SOURCE_MARKER));
            Box::into_raw(Box::new(inst)) as Handle
        }
        Err((logger, message)) => {
            logger.log(Status::Error, LogCategory::StatusError, &message);
            std::ptr::null_mut()
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// Frees an instance (a NULL pointer or one that is not a live instance is ignored).
///
/// # Safety
/// `c` is NULL or from an instantiation function of this library, not used again after.
pub unsafe fn free_instance<M: FmuModel>(c: Handle, function: &'static str) {
    if c.is_null() {
        return;
    }
    let _ = guarded(|| {
        let ptr = c as *mut Instance<M>;
        // SAFETY: non-null, at least 8 readable bytes by the C API's contract.
        if unsafe { Instance::is_instance(ptr) } {
            // SAFETY: a live instance of this library, made by `Box::into_raw` in
            // `instantiate`; it is invalidated before the box is dropped, so a later use of the
            // dangling pointer is refused while the memory is still ours.
            let inst = unsafe { &mut *ptr };
            inst.log_call(|| format!("{function}()"));
            inst.invalidate();
            // SAFETY: as above: made by `Box::into_raw`, dropped once.
            drop(unsafe { Box::from_raw(ptr) });
        }
    });
}

/// Sets the time (`fmi2SetTime`, `fmi3SetTime`).
///
/// # Safety
/// As [`with_instance`].
pub unsafe fn set_time<M: FmuModel>(c: Handle, function: &'static str, time: f64) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            inst.log_call(|| format!("{function}(time={time})"));
            inst.set_time(time)
        })
    }
}

/// Sets the continuous states from the C array `x` of `n` elements, named `argument` in the
/// called function.
///
/// # Safety
/// As [`with_instance`]; `x` NULL or `n` readable numbers.
pub unsafe fn set_continuous_states<M: FmuModel>(
    c: Handle,
    (function, argument): (&'static str, &'static str),
    x: *const f64,
    n: usize,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let Some(x) = slice(x, n) else {
                return inst.refuse(&format!("argument '{argument}' is NULL"));
            };
            inst.log_call(|| format!("{function}({argument}={x:?})"));
            inst.set_continuous_states(argument, x)
        })
    }
}

/// The Model Exchange getters of a Real array of the states' size (the continuous states, their
/// derivatives, their nominals): `out` holds `n` elements and is named `argument` in the called
/// function; `f` fills it.
///
/// # Safety
/// As [`with_instance`]; `out` NULL or `n` writable numbers.
pub unsafe fn get_state_array<M: FmuModel>(
    c: Handle,
    (function, argument): (&'static str, &'static str),
    out: *mut f64,
    n: usize,
    f: fn(&mut Instance<M>, &'static str, &mut [f64]) -> Status,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            let Some(out) = slice_mut(out, n) else {
                return inst.refuse(&format!("argument '{argument}' is NULL"));
            };
            inst.log_call(|| format!("{function}(n={n})"));
            f(inst, argument, out)
        })
    }
}

/// The event indicators: the array `z` of `n` elements, named (`array`, `count`) in the called
/// function.
///
/// # Safety
/// As [`with_instance`]; `z` NULL or `n` writable numbers.
pub unsafe fn get_event_indicators<M: FmuModel>(
    c: Handle,
    (function, array, count): (&'static str, &'static str, &'static str),
    z: *mut f64,
    n: usize,
) -> Status {
    // SAFETY: as this function's contract.
    unsafe {
        with_instance::<M>(c, function, |inst| {
            if slice_mut(z, n).is_none() {
                return inst.refuse(&format!("argument '{array}' is NULL"));
            }
            inst.log_call(|| format!("{function}({count}={n})"));
            inst.event_indicators(count, n)
        })
    }
}

/// Turns a `file:` resource URI into a path: `file:///a/b`, `file://localhost/a/b` and `file:/a/b`,
/// with percent-decoding. Anything else gives `None`.
pub fn file_uri_to_path(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = if let Some(r) = rest.strip_prefix("//") {
        // Authority: empty or localhost.
        let slash = r.find('/')?;
        let (host, p) = r.split_at(slash);
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return None;
        }
        p
    } else {
        rest
    };
    let bytes = path.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    Some(PathBuf::from(String::from_utf8(decoded).ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris() {
        assert_eq!(
            file_uri_to_path("file:///tmp/a%20b/"),
            Some(PathBuf::from("/tmp/a b/"))
        );
        assert_eq!(
            file_uri_to_path("file:/tmp/x"),
            Some(PathBuf::from("/tmp/x"))
        );
        assert_eq!(
            file_uri_to_path("file://localhost/tmp"),
            Some(PathBuf::from("/tmp"))
        );
        assert_eq!(file_uri_to_path("http://x/y"), None);
        assert_eq!(file_uri_to_path("file:///bad%2"), None);
    }
}
