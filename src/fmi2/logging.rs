//! What the FMU tells its environment: the logger with its categories, numbers printed short, and
//! the panic hook that keeps panic messages off the host's stderr.
//!
//! Both FMI layers share it: a [`Logger`] sends to an FMI 2.0 logger callback or to an FMI 3.0
//! `logMessage` callback ([`Sink`]). The shared core writes its messages once, naming the FMI 2.0
//! functions; for an FMI 3.0 instance [`fmi3_names`] renames them at the boundary
//! (`fmi2GetFMUstate` becomes `fmi3GetFMUState`, `fmi2GetReal` `fmi3GetFloat64`, ...), so a user
//! of either version reads the names of the functions they called.

use std::cell::{Cell, RefCell};
use std::ffi::CString;
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

use super::ffi::{Fmi2CallbackFunctions, Fmi2Status};
use super::LogCategory;
use crate::fmi3::ffi::{Fmi3InstanceEnvironment, Fmi3LogMessageCallback, Fmi3Status};

/// Where messages go: the callback of the FMI version the instance was made by.
#[derive(Clone, Copy)]
pub enum Sink {
    /// FMI 2.0: `fmi2CallbackLogger`, a printf-style function that gets the instance name.
    Fmi2(Fmi2CallbackFunctions),
    /// FMI 3.0: `fmi3LogMessageCallback`, plain text and no instance name.
    Fmi3 {
        environment: Fmi3InstanceEnvironment,
        log_message: Fmi3LogMessageCallback,
    },
}

/// The environment's side: logger callback, instance name and which categories it wants.
pub struct Logger {
    instance_name: CString,
    sink: Sink,
    /// Which debug categories are on, indexed by `LogCategory as usize`.
    enabled: [bool; LogCategory::ALL.len()],
}

impl Logger {
    pub fn new(instance_name: &str, callbacks: Fmi2CallbackFunctions, logging_on: bool) -> Self {
        Self::with_sink(instance_name, Sink::Fmi2(callbacks), logging_on)
    }

    pub fn with_sink(instance_name: &str, sink: Sink, logging_on: bool) -> Self {
        Logger {
            instance_name: CString::new(instance_name.replace('\0', " ")).unwrap_or_default(),
            sink,
            // fmi2Instantiate's loggingOn switches every category (FMI 2.0.4, 2.1.5).
            enabled: [logging_on; LogCategory::ALL.len()],
        }
    }

    /// Whether a message of `category` would reach the environment: warnings, discards, errors
    /// and fatal errors always do (as in the Reference FMUs), the other categories when they are
    /// on or `logAll` is. Ask before formatting a message that costs something to build.
    pub fn enabled(&self, category: LogCategory) -> bool {
        let always = matches!(
            category,
            LogCategory::StatusWarning
                | LogCategory::StatusDiscard
                | LogCategory::StatusError
                | LogCategory::StatusFatal
        );
        always || self.enabled[category as usize] || self.enabled[LogCategory::All as usize]
    }

    /// Switches categories on or off: all of them when `categories` is empty.
    pub fn switch(&mut self, on: bool, categories: &[LogCategory]) {
        if categories.is_empty() {
            self.enabled = [on; LogCategory::ALL.len()];
        }
        for &c in categories {
            self.enabled[c as usize] = on;
        }
    }

    /// Sends a message to the environment's logger if its category is enabled.
    pub fn log(&self, status: Fmi2Status, category: LogCategory, message: &str) {
        if !self.enabled(category) {
            return;
        }
        let category = CString::new(category.name()).unwrap_or_default();
        match self.sink {
            Sink::Fmi2(callbacks) => {
                let Some(logger) = callbacks.logger else {
                    return;
                };
                // The logger's message is a printf format. Importers that format it and importers
                // that print it as it is both exist; passing the message itself, with '%' doubled,
                // reads right in the first and nearly right in the second, and never lets a '%' in
                // a message be taken for a conversion.
                let message = shorten_numbers(message)
                    .replace('\0', " ")
                    .replace('%', "%%");
                let message = CString::new(message).unwrap_or_default();
                unsafe {
                    logger(
                        callbacks.component_environment,
                        self.instance_name.as_ptr(),
                        status,
                        category.as_ptr(),
                        message.as_ptr(),
                    );
                }
            }
            Sink::Fmi3 {
                environment,
                log_message,
            } => {
                let Some(log_message) = log_message else {
                    return;
                };
                let status = match status {
                    Fmi2Status::Ok | Fmi2Status::Pending => Fmi3Status::Ok,
                    Fmi2Status::Warning => Fmi3Status::Warning,
                    Fmi2Status::Discard => Fmi3Status::Discard,
                    Fmi2Status::Error => Fmi3Status::Error,
                    Fmi2Status::Fatal => Fmi3Status::Fatal,
                };
                let message = fmi3_names(&shorten_numbers(message)).replace('\0', " ");
                let message = CString::new(message).unwrap_or_default();
                unsafe { log_message(environment, status, category.as_ptr(), message.as_ptr()) };
            }
        }
    }
}

/// FMI 2.0 names that are not the FMI 3.0 name with `fmi3` for `fmi2`.
const FMI3_RENAMED: [(&str, &str); 14] = [
    ("fmi2Instantiate", "fmi3Instantiate"),
    ("fmi2SetupExperiment", "fmi3EnterInitializationMode"),
    ("fmi2GetReal", "fmi3GetFloat64"),
    ("fmi2SetReal", "fmi3SetFloat64"),
    ("fmi2GetInteger", "fmi3GetInt32"),
    ("fmi2SetInteger", "fmi3SetInt32"),
    ("fmi2GetFMUstate", "fmi3GetFMUState"),
    ("fmi2SetFMUstate", "fmi3SetFMUState"),
    ("fmi2FreeFMUstate", "fmi3FreeFMUState"),
    ("fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize"),
    ("fmi2SerializeFMUstate", "fmi3SerializeFMUState"),
    ("fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"),
    ("fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"),
    ("fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates"),
];

/// Renames the FMI 2.0 function and status names in a message of the shared core to their FMI 3.0
/// names (`fmi2DoStep` -> `fmi3DoStep`, `fmi2GetReal` -> `fmi3GetFloat64`, `fmi2OK` -> `fmi3OK`).
pub fn fmi3_names(message: &str) -> String {
    let mut out = String::with_capacity(message.len() + 16);
    let mut rest = message;
    while let Some(at) = rest.find("fmi2") {
        out.push_str(&rest[..at]);
        let word = &rest[at..];
        let end = word
            .find(|c: char| !c.is_ascii_alphanumeric() && c != '_')
            .unwrap_or(word.len());
        let name = &word[..end];
        match FMI3_RENAMED.iter().find(|(old, _)| *old == name) {
            Some((_, new)) => out.push_str(new),
            None => {
                out.push_str("fmi3");
                out.push_str(&name[4..]);
            }
        }
        rest = &word[end..];
    }
    out.push_str(rest);
    out
}

/// A number printed short: as Rust prints it (shortest round trip) between 1e-4 and 1e15, in
/// exponent form outside, so that `1e-300` takes 6 characters, not 302.
#[derive(Clone, Copy, Debug)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-4..1e15).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Rewrites every decimal number longer than 24 characters in `message` as [`Short`] does: the
/// guard at the C boundary for messages of lower layers that print numbers in full.
pub fn shorten_numbers(message: &str) -> String {
    const LONG: usize = 24;
    let bytes = message.as_bytes();
    let mut out = String::with_capacity(message.len());
    let mut i = 0;
    while i < bytes.len() {
        let number_start = bytes[i].is_ascii_digit()
            || (bytes[i] == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word = i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        if number_start && !after_word {
            // Digits with at most one decimal point followed by a digit.
            let mut j = i + 1;
            let mut point = false;
            while j < bytes.len() {
                let digit_after = bytes.get(j + 1).is_some_and(u8::is_ascii_digit);
                if bytes[j].is_ascii_digit() {
                    j += 1;
                } else if bytes[j] == b'.' && !point && digit_after {
                    point = true;
                    j += 1;
                } else {
                    break;
                }
            }
            let token = &message[i..j];
            match token.parse::<f64>() {
                Ok(v) if token.len() > LONG => out.push_str(&Short(v).to_string()),
                _ => out.push_str(token),
            }
            i = j;
        } else {
            let c = message[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

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
    fn short_numbers() {
        assert_eq!(Short(1e-300).to_string(), "1e-300");
        assert_eq!(Short(-1e300).to_string(), "-1e300");
        assert_eq!(Short(0.05).to_string(), "0.05");
        assert_eq!(Short(1.5e15).to_string(), "1.5e15");
        assert_eq!(Short(0.0).to_string(), "0");
        assert_eq!(Short(f64::NAN).to_string(), "NaN");
    }

    #[test]
    fn long_numbers_in_messages_are_shortened() {
        let long = format!("x = {} and y = {}, x1 = 2", 1e-300, -1e300);
        assert_eq!(shorten_numbers(&long), "x = 1e-300 and y = -1e300, x1 = 2");
        assert_eq!(
            shorten_numbers("t = 0.001: 12 steps"),
            "t = 0.001: 12 steps"
        );
        assert_eq!(shorten_numbers("plate.f[12] é"), "plate.f[12] é");
        let range = format!("(0..{}, 0..{})", 1.41, 1e-49);
        assert_eq!(shorten_numbers(&range), "(0..1.41, 0..1e-49)");
    }

    #[test]
    fn fmi3_messages_name_fmi3_functions() {
        assert_eq!(
            fmi3_names(
                "fmi2GetReal: bad; fmi2DoStep returned fmi2Error, see fmi2DeSerializeFMUstate."
            ),
            "fmi3GetFloat64: bad; fmi3DoStep returned fmi3Error, see fmi3DeserializeFMUState."
        );
        assert_eq!(fmi3_names("no names"), "no names");
    }

    #[test]
    fn a_guarded_panic_is_recorded_with_its_place() {
        let err = guarded(|| -> u8 { panic!("boom {}", 1) }).unwrap_err();
        assert!(err.starts_with("boom 1 (at src/fmi2/logging.rs:"), "{err}");
        assert_eq!(guarded(|| 3), Ok(3));
    }
}
