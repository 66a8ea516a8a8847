//! The FMI 3.0 driver of `driver.rs` ([`V3`], over the library's exported `fmi3*` entry points,
//! co-simulation, called in-process exactly as an importer that has loaded the library would,
//! with a log of its own per instance) answering in `Fmi3Status`, with what FMI 3.0 alone has:
//! the twin of `fmu.rs`.

#![allow(dead_code)]

use hydraulic_slewing_plate::fmi3::ffi::*;

// A test binary may include `fmu.rs` too, and with it a second copy of `driver.rs`.
#[allow(clippy::duplicate_mod)]
#[path = "driver.rs"]
mod driver;
use driver::{Driver, Kind, Native, V3};

/// One log line: status, category and message.
pub type Line = (Fmi3Status, String, String);

fn native(lines: Vec<driver::Line>) -> Vec<Line> {
    lines
        .into_iter()
        .map(|(s, c, m)| (s.into(), c, m))
        .collect()
}

/// An FMI 3.0 co-simulation instance with its log; freed on drop.
pub type Fmu3 = Native<V3>;

impl Native<V3> {
    pub fn new() -> Fmu3 {
        Self::try_new(false).expect("fmi3InstantiateCoSimulation returned NULL")
    }

    /// The instance, or the log when instantiation returned NULL.
    pub fn try_new(event_mode_used: bool) -> Result<Fmu3, Vec<Line>> {
        Self::try_new_bytes(0, u8::from(event_mode_used))
    }

    /// As [`Fmu3::try_new`], with `loggingOn` and `eventModeUsed` passed as the bytes given
    /// (C's `bool` arguments: an importer may pass any byte).
    pub fn try_new_bytes(logging_on: u8, event_mode_used: u8) -> Result<Fmu3, Vec<Line>> {
        match V3::instantiate(Kind::CoSimulation, logging_on, event_mode_used) {
            Ok(v) => Ok(Native(v)),
            Err(lines) => Err(native(lines)),
        }
    }

    /// A Model Exchange instance, with `loggingOn` passed as the byte given.
    pub fn model_exchange_bytes(logging_on: u8) -> Result<Fmu3, Vec<Line>> {
        match V3::instantiate(Kind::ModelExchange, logging_on, 0) {
            Ok(v) => Ok(Native(v)),
            Err(lines) => Err(native(lines)),
        }
    }

    pub fn log(&self) -> Vec<Line> {
        native(self.0.lines())
    }

    /// `fmi3EnterInitializationMode` with the experiment starting at `start`.
    pub fn enter(&self, start: f64) -> Fmi3Status {
        self.0.enter(start).into()
    }

    /// lastSuccessfulTime of the last step that returned OK or Discard.
    pub fn last_successful_time(&self) -> f64 {
        self.0.last_successful_time().1
    }
}
