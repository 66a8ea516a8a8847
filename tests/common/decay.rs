//! A tiny test model for the generic FMI layers on their own (`fmi2_layer.rs`, `fmi3_layer.rs`):
//! dx/dt = -k x, with a switch that makes it fail or panic, what the shipped model cannot provoke
//! on purpose; and the child process that shows a panic prints nothing to stderr.

#![allow(dead_code)]

use hydraulic_slewing_plate::fmu::{
    Causality, Experiment, FmuModel, Kind, StepFailure, StepLog, Values, Variability, Variable,
};

/// dx/dt = -k x from x(0) = 1, integrated exactly. `mode` 1 makes do_step fail at
/// t_start + (t_end - t_start)/2; mode 2 makes it panic.
pub struct Decay {
    x: f64,
    t: f64,
}

pub const VARS: [Variable; 3] = [
    Variable {
        name: "k",
        value_reference: 1,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        kind: Kind::Real {
            start: Some(2.0),
            min: Some(0.0),
            max: None,
        },
        unit: None,
        description: "rate",
    },
    Variable {
        name: "mode",
        value_reference: 2,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        kind: Kind::Integer {
            start: Some(0),
            min: Some(0),
            max: Some(2),
        },
        unit: None,
        description: "0 normal, 1 fail, 2 panic",
    },
    Variable {
        name: "x",
        value_reference: 3,
        causality: Causality::Output,
        variability: Variability::Continuous,
        kind: Kind::Real {
            start: None,
            min: None,
            max: None,
        },
        unit: None,
        description: "state",
    },
];

impl FmuModel for Decay {
    type State = (f64, f64);
    const MODEL_IDENTIFIER: &'static str = "Decay";
    const GUID: &'static str = "{decay}";

    fn variables() -> &'static [Variable] {
        &VARS
    }
    fn index_of(vr: u32) -> Option<usize> {
        VARS.iter().position(|v| v.value_reference == vr)
    }
    fn new() -> Self {
        Decay { x: 1.0, t: 0.0 }
    }
    fn initialize(
        &mut self,
        values: &mut Values,
        e: &Experiment,
        _log: &mut StepLog,
    ) -> Result<(), String> {
        self.x = 1.0;
        self.t = e.start_time;
        values.set_real(2, self.x);
        Ok(())
    }
    fn do_step(
        &mut self,
        values: &mut Values,
        t0: f64,
        t1: f64,
        _log: &mut StepLog,
    ) -> Result<(), StepFailure> {
        let k = values.real(0);
        let end = match values.integer(1) {
            0 => t1,
            1 => t0 + (t1 - t0) / 2.0,
            _ => panic!("deliberate panic in do_step"),
        };
        self.x *= (-k * (end - self.t)).exp();
        self.t = end;
        values.set_real(2, self.x);
        if end < t1 {
            return Err(StepFailure {
                last_successful_time: end,
                message: "deliberate failure".into(),
            });
        }
        Ok(())
    }
    fn save_state(&self) -> (f64, f64) {
        (self.x, self.t)
    }
    fn restore_state(
        &mut self,
        s: &(f64, f64),
        _: &Values,
        _: &Experiment,
        _: Option<f64>,
    ) -> Result<(), String> {
        (self.x, self.t) = *s;
        Ok(())
    }
}

/// Runs the test `test` of this test binary alone in a child process (with `child_variable` set;
/// in that child this does nothing, so that the calling test does not recurse) and asserts that
/// it passed and that nothing of a panic reached the child's stderr: the panic hook keeps
/// "panicked at" and the panic's message off the host's stderr.
pub fn passes_with_nothing_on_stderr(test: &str, child_variable: &str) {
    if std::env::var_os(child_variable).is_some() {
        return;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", test, "--nocapture"])
        .env(child_variable, "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("1 passed"), "{stdout}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!stderr.contains("deliberate panic"), "{stderr}");
}
