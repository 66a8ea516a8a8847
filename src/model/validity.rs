//! The validity monitors at the communication points: one warning per quantity the first time it
//! leaves the linear model's range (the quantities and their limits are in
//! [`crate::fragments::validity`]).

use crate::fmu::Values;
use crate::fragments::validity::{Limits, Monitor};

use super::variables::idx;

/// The FMU variable of a monitor's output.
pub fn index(monitor: Monitor) -> usize {
    match monitor {
        Monitor::TipRatio => idx::PLATE_W_TIP_RATIO,
        Monitor::PlateStress => idx::PLATE_STRESS,
        Monitor::BarStress => idx::TORSION_BAR_STRESS,
        Monitor::SpinRatio => idx::HUB_OMEGA_RATIO,
    }
}

/// Which monitors have warned since the simulation started.
#[derive(Clone, Debug, Default)]
pub struct ValidityWatch {
    warned: [bool; Monitor::ALL.len()],
}

impl ValidityWatch {
    /// Forgets the warnings given (a new simulation).
    pub fn reset(&mut self) {
        self.warned = Default::default();
    }

    /// Whether `monitor` has warned (the outputs of the others are those the caller must bring
    /// up to date before [`ValidityWatch::check`]).
    pub fn has_warned(&self, monitor: Monitor) -> bool {
        let k = Monitor::ALL.iter().position(|&m| m == monitor);
        k.is_some_and(|k| self.warned[k])
    }

    /// Checks the monitors' outputs in `values` at time `t`; `warn` gets the message of each
    /// monitor out of range for the first time.
    pub fn check(
        &mut self,
        values: &Values,
        t: f64,
        limits: &Limits,
        mut warn: impl FnMut(String),
    ) {
        for (k, m) in Monitor::ALL.into_iter().enumerate() {
            if self.warned[k] {
                continue;
            }
            let v = values.real(index(m));
            if m.exceeded(v, limits) {
                self.warned[k] = true;
                warn(m.message(v, t, limits));
            }
        }
    }
}
