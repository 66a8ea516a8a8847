//! What the FMU tells its environment: the logger with its categories and numbers printed short.
//!
//! The core writes each message once, with the name of the function the importer called; where it
//! goes is the FMI layer's business: a [`LogSink`] hands it to FMI 2.0's `fmi2CallbackLogger` or
//! FMI 3.0's `logMessage` callback.

use std::fmt;

use super::{LogCategory, Status};

/// Where an instance's messages go: the callback of the FMI version it was made by. The message
/// has its long numbers shortened and no NUL bytes; the sink adds what its C API needs.
pub trait LogSink {
    /// Sends one message of `category` (its `<LogCategories>` name) with `status`.
    fn send(&self, status: Status, category: &str, message: &str);
}

/// The environment's side: where messages go and which categories it wants.
pub struct Logger {
    sink: Box<dyn LogSink>,
    /// Which debug categories are on, indexed by `LogCategory as usize`.
    enabled: [bool; LogCategory::ALL.len()],
}

impl Logger {
    /// A logger with every category on or off (the `loggingOn` argument of instantiation
    /// switches them all: FMI 2.0.4, 2.1.5; FMI 3.0, 2.3.1).
    pub fn new(sink: Box<dyn LogSink>, logging_on: bool) -> Self {
        Logger {
            sink,
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
    /// A message from the model ([`super::StepLog`]): built only when its category is enabled,
    /// logged with status Warning in the warning category and OK in the others.
    pub fn model_log(&self, category: LogCategory, message: &dyn Fn() -> String) {
        if self.enabled(category) {
            let status = if category == LogCategory::StatusWarning {
                Status::Warning
            } else {
                Status::Ok
            };
            self.log(status, category, &message());
        }
    }

    pub fn log(&self, status: Status, category: LogCategory, message: &str) {
        if !self.enabled(category) {
            return;
        }
        let message = shorten_numbers(message).replace('\0', " ");
        self.sink.send(status, category.name(), &message);
    }
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

/// Rewrites every decimal number in `message` that [`Short`] prints in exponent form (nonzero,
/// outside 1e-4 to 1e15) and shorter, so `0.00000000000000000001` becomes `1e-20`: the guard at
/// the boundary for messages of lower layers that print numbers with Rust's `{}`, which never
/// uses an exponent. Numbers in the plain range are already in shortest round-trip form and stay
/// as written (`0.10` from a `{:.2}` stays `0.10`).
pub fn shorten_numbers(message: &str) -> String {
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
            let short = token
                .parse::<f64>()
                .ok()
                .filter(|v| *v != 0.0 && !(1e-4..1e15).contains(&v.abs()))
                .map(|v| Short(v).to_string())
                .filter(|short| short.len() < token.len());
            out.push_str(short.as_deref().unwrap_or(token));
            i = j;
        } else {
            let c = message[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
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
        // Short numbers outside the plain range too (issue 24, N4), and nothing else.
        let tiny = format!("got {}", 1e-20);
        assert_eq!(shorten_numbers(&tiny), "got 1e-20");
        assert_eq!(shorten_numbers("got 0.00001 and 0.10"), "got 1e-5 and 0.10");
        assert_eq!(
            shorten_numbers("000000 1234567890123456"),
            "000000 1234567890123456"
        );
    }
}
