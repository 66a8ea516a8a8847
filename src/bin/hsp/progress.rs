//! A progress line for long commands: shown only when stdout is a terminal and only once the
//! command has run for a second, redrawn at most ten times a second, erased when done. Piped or
//! redirected output never sees it.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

const DELAY: Duration = Duration::from_secs(1);
const REDRAW: Duration = Duration::from_millis(100);

/// A progress line labelled `what`.
pub struct Progress {
    what: &'static str,
    enabled: bool,
    start: Instant,
    drawn: Option<Instant>,
}

impl Progress {
    pub fn new(what: &'static str) -> Self {
        Progress {
            what,
            enabled: std::io::stdout().is_terminal(),
            start: Instant::now(),
            drawn: None,
        }
    }

    /// Reports the fraction done (0 to 1).
    pub fn update(&mut self, fraction: f64) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        let elapsed = now - self.start;
        if elapsed < DELAY || self.drawn.is_some_and(|d| now - d < REDRAW) {
            return;
        }
        let f = fraction.clamp(0.0, 1.0);
        let left = if f > 0.0 {
            format!(", {:.0} s left", elapsed.as_secs_f64() * (1.0 - f) / f)
        } else {
            String::new()
        };
        print!(
            "\r{}: {:5.1} % ({:.1} s{left})\x1b[K",
            self.what,
            100.0 * f,
            elapsed.as_secs_f64()
        );
        let _ = std::io::stdout().flush();
        self.drawn = Some(now);
    }
}

impl Drop for Progress {
    /// Erases the line, so the summary that follows starts on a clean line.
    fn drop(&mut self) {
        if self.drawn.is_some() {
            print!("\r\x1b[K");
            let _ = std::io::stdout().flush();
        }
    }
}
