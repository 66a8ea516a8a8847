//! The FMI 2.0 driver of `driver.rs` ([`V2`], over the library's exported `fmi2*` entry points,
//! called in-process exactly as an importer that has loaded the library would, with a log of its
//! own per instance) answering in `Fmi2Status`, with what FMI 2.0 alone has.

#![allow(dead_code)]

use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;

#[path = "driver.rs"]
mod driver;
#[allow(unused_imports)]
pub use driver::{blob, find_key, payload};
use driver::{Driver, Kind, Native, V2};

/// One log line: status and message.
pub type Line = (Fmi2Status, String);

/// An instance with its log; freed on drop.
pub type Fmu = Native<V2>;

impl Native<V2> {
    pub fn new() -> Fmu {
        Native(V2::new(Kind::CoSimulation))
    }

    /// An instance for Model Exchange.
    pub fn model_exchange() -> Fmu {
        Native(V2::new(Kind::ModelExchange))
    }

    pub fn of_type(fmu_type: Fmi2Type) -> Fmu {
        Native(V2::of_type(fmu_type))
    }

    /// The log lines so far.
    pub fn log(&self) -> Vec<Line> {
        let lines = self.0.log().into_iter();
        lines.map(|(s, m)| (s.into(), m)).collect()
    }

    pub fn get_integer(&self, name: &str) -> (Fmi2Status, i32) {
        let mut v = 0;
        let s = unsafe { fmi2GetInteger(self.c, &Self::vr(name), 1, &mut v) };
        (s, v)
    }

    pub fn setup(&self, start: f64) -> Fmi2Status {
        unsafe { fmi2SetupExperiment(self.c, FMI2_FALSE, 0.0, start, FMI2_FALSE, 0.0) }
    }

    /// `fmi2EnterInitializationMode` (after [`Fmu::setup`]).
    pub fn enter(&self) -> Fmi2Status {
        self.0.enter_initialization_mode().into()
    }

    pub fn last_successful_time(&self) -> (Fmi2Status, f64) {
        let (s, t) = self.0.last_successful_time();
        (s.into(), t)
    }
}

/// Takes FMU states from point `k` on, calling `advance(k)` to step one point further each time,
/// until a state's payload holds `key` (by the time point `limit`): the point reached, that state
/// and its payload.
pub fn until_state_holds(
    f: &Fmu,
    mut k: usize,
    key: &str,
    limit: usize,
    mut advance: impl FnMut(usize),
) -> (usize, Fmi2FmuState, serde_json::Value) {
    let quoted = format!("\"{key}\"");
    loop {
        let (s, saved) = f.get_state();
        assert_eq!(s, Fmi2Status::Ok);
        let p = payload(&f.serialize(saved));
        if p.to_string().contains(&quoted) {
            return (k, saved, p);
        }
        f.free_state(saved);
        assert!(
            k < limit,
            "no FMU state holds \"{key}\" at any point up to {limit}"
        );
        advance(k);
        k += 1;
    }
}
