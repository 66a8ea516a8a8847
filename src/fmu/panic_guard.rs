//! The panic guard of the C boundary: a panic inside an FMU call must never unwind into the host,
//! and its message goes to the FMU's logger, not to the host's stderr. [`guarded`] runs a call
//! with panics caught; the hook installed once per process records the message and place of a
//! panic inside a guarded call and leaves panics elsewhere in the host to the hook that was there
//! before.

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    /// Whether this thread is inside an FMU call (where a panic is ours to report).
    static IN_CALL: Cell<bool> = const { Cell::new(false) };
    /// The message and place of the last panic inside an FMU call on this thread.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

static HOOK: Once = Once::new();

/// Installs, once per process, a panic hook that records panics inside FMU calls for the FMU's
/// logger instead of printing them to stderr; panics elsewhere in the host go to the hook that was
/// there before.
pub fn install_panic_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if IN_CALL.try_with(Cell::get).unwrap_or(false) {
                let what = info
                    .payload()
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| info.payload().downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".into());
                let message = match info.location() {
                    Some(l) => format!("{what} (at {}:{})", l.file(), l.line()),
                    None => what,
                };
                let _ = LAST_PANIC.try_with(|p| *p.borrow_mut() = Some(message));
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `f` with panics caught and recorded by the hook: `Err` carries the panic's message and
/// place. Calls nest (a guarded call inside another keeps the outer one guarded).
pub fn guarded<R>(f: impl FnOnce() -> R) -> Result<R, String> {
    install_panic_hook();
    let outer = IN_CALL.with(|c| c.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_CALL.with(|c| c.set(outer));
    result.map_err(|payload| {
        LAST_PANIC
            .with(|p| p.borrow_mut().take())
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_guarded_panic_is_recorded_with_its_place() {
        let err = guarded(|| -> u8 { panic!("boom {}", 1) }).unwrap_err();
        assert!(
            err.starts_with("boom 1 (at src/fmu/panic_guard.rs:"),
            "{err}"
        );
        assert_eq!(guarded(|| 3), Ok(3));
    }
}
