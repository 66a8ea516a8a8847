//! Co-Simulation: the communication step and the status of the last one.

use super::super::calls::{MachineState::*, Operation};
use super::super::logging::Short;
use super::super::{FmuModel, LogCategory, Status};
use super::{time_slack, Instance};

impl<M: FmuModel> Instance<M> {
    /// The communication step from `current_communication_point` over `step_size`, with the
    /// inputs held. A step the model cannot complete is discarded: the instance keeps the last
    /// time it reached, with its outputs, and enters the step-failed state.
    pub fn do_step(&mut self, current_communication_point: f64, step_size: f64) -> Status {
        if let Err(s) = self.allowed(Operation::DoStep) {
            return s;
        }
        if !(step_size.is_finite() && step_size > 0.0) {
            return self.refuse(&format!(
                "communicationStepSize must be positive and finite, got {}",
                Short(step_size)
            ));
        }
        // Any positive step that advances time is taken, however short: the standard allows it
        // and a master that aligns its times in floating point makes such steps. The solver's
        // minimum step bounds only the steps its error control chooses; a step shorter than it
        // is one step of the method at that size (see `Integrator::advance_past`).
        if !current_communication_point.is_finite()
            || (current_communication_point - self.time).abs() > time_slack(self.time)
        {
            return self.refuse(&format!(
                "currentCommunicationPoint {} does not match the FMU's time {}",
                Short(current_communication_point),
                Short(self.time)
            ));
        }
        let t_end = current_communication_point + step_size;
        // Near large times a small step vanishes in round-off: the FMU's time cannot advance.
        if t_end <= self.time {
            return self.refuse(&format!(
                "communicationStepSize {} cannot advance the time {} in double precision (t + h rounds to t)",
                Short(step_size),
                Short(self.time)
            ));
        }
        if let Some(stop) = self.experiment.stop_time {
            if t_end > stop + time_slack(stop) {
                return self.refuse(&format!(
                    "the step to {} goes past stopTime {}",
                    Short(t_end),
                    Short(stop)
                ));
            }
        }
        let logger = &self.logger;
        let mut log = |category: LogCategory, message: &dyn Fn() -> String| {
            logger.model_log(category, message)
        };
        let result = self
            .model
            .do_step(&mut self.values, self.time, t_end, &mut log);
        match result {
            Ok(()) => {
                if let Some(bad) = self.non_finite_result() {
                    // The model should have discarded the step; never hand out OK with it.
                    return self.refuse(&format!("{bad} is not finite at t = {}", Short(t_end)));
                }
                self.time = t_end;
                self.last_successful_time = t_end;
                Status::Ok
            }
            Err(failure) => {
                self.time = failure.last_successful_time;
                self.last_successful_time = failure.last_successful_time;
                self.state = StepFailed;
                let f = self.function;
                self.logger.log(
                    Status::Discard,
                    LogCategory::StatusDiscard,
                    &format!(
                        "{f}: step from {} to {} discarded at t = {}: {}",
                        Short(current_communication_point),
                        Short(t_end),
                        Short(failure.last_successful_time),
                        failure.message
                    ),
                );
                Status::Discard
            }
        }
    }

    /// The last time a step reached (FMI 2.0's `fmi2GetRealStatus(fmi2LastSuccessfulTime)`).
    pub fn last_successful_time(&mut self) -> Result<f64, Status> {
        self.allowed(Operation::GetStatus)?;
        Ok(self.last_successful_time)
    }

    /// Whether the FMU asks to end the simulation (FMI 2.0's
    /// `fmi2GetBooleanStatus(fmi2Terminated)`): never; a discarded step can be retried from a
    /// restored FMU state.
    pub fn terminated_status(&mut self) -> Result<bool, Status> {
        self.allowed(Operation::GetStatus)?;
        Ok(false)
    }
}
