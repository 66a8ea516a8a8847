//! FMU states: saving the instance, and restoring a state only after checking it as strictly as
//! fresh input (the state machine's state, the experiment, the times, every value, and the
//! model's own part).

use super::super::calls::{Interface, MachineState::*, Operation, RESTORABLE};
use super::super::fmu_state::{SavedState, Snapshot};
use super::super::logging::Short;
use super::super::variables::check_value;
use super::super::{FmuModel, Status};
use super::{check_experiment, time_slack, Instance};

impl<M: FmuModel> Instance<M> {
    /// The checks every FMU-state function shares: not in Model Exchange, and allowed in this
    /// state.
    pub fn check_fmu_state_call(&mut self) -> Result<(), Status> {
        if self.interface == Interface::ModelExchange && self.state != Fatal {
            // The importer's solver holds the continuous states: save them there.
            let flag = self.vocabulary.can_get_and_set_fmu_state;
            return Err(self.refuse(&format!(
                "not supported in Model Exchange ({flag} is false there)"
            )));
        }
        self.allowed(Operation::FmuState)
    }

    /// Saves the instance into an FMU state.
    pub fn save(&mut self) -> SavedState<M::State> {
        self.model.refresh(&mut self.values, None);
        SavedState::new(Snapshot {
            guid: M::GUID.to_string(),
            state: self.state,
            time: self.time,
            last_successful_time: self.last_successful_time,
            experiment: self.experiment,
            values: self.values.clone(),
            needs_initialize: self.needs_initialize,
            model: self.model.save_state(),
        })
    }

    /// Checks the generic part of an FMU state as strictly as fresh input: the state it was taken
    /// in, the experiment, the times and every value (type, range, the model's own checks).
    fn check_snapshot(s: &Snapshot<M::State>, model: &M) -> Result<(), String> {
        if !RESTORABLE.contains(s.state) {
            return Err(format!(
                "the FMU state was taken in state '{}', from which the simulation cannot go on",
                s.state.name()
            ));
        }
        check_experiment(&s.experiment).map_err(|m| format!("its experiment: {m}"))?;
        let e = &s.experiment;
        let after_start = matches!(s.state, StepComplete | StepFailed | Terminated);
        let times_ok = s.time.is_finite()
            && s.last_successful_time.to_bits() == s.time.to_bits()
            && if after_start {
                s.time >= e.start_time
                    && e.stop_time
                        .is_none_or(|stop| s.time <= stop + time_slack(stop))
            } else {
                s.time == e.start_time
            };
        if !times_ok {
            return Err(format!(
                "its time {} (last successful time {}) does not fit its state '{}' and startTime {}",
                Short(s.time),
                Short(s.last_successful_time),
                s.state.name(),
                Short(e.start_time)
            ));
        }
        let variables = M::variables();
        if s.values.len() != variables.len() {
            return Err(format!(
                "it has {} variables, this FMU {}",
                s.values.len(),
                variables.len()
            ));
        }
        for (i, var) in variables.iter().enumerate() {
            let value = s.values.get(i);
            check_value(var, value)?;
            if var.settable_before_initialization() {
                model.check(i, value)?;
            }
        }
        Ok(())
    }

    /// Restores an FMU state: the state is validated as strictly as fresh input before anything
    /// of the instance changes; a state that fails leaves the instance in the error state.
    pub fn restore(&mut self, saved: &SavedState<M::State>) -> Status {
        let s = &saved.snapshot;
        if let Err(msg) = Self::check_snapshot(s, &self.model) {
            return self.refuse(&format!("invalid FMU state: {msg}"));
        }
        let initialized = matches!(s.state, StepComplete | StepFailed | Terminated);
        let time = initialized.then_some(s.time);
        // The current values complete, whether the model takes up the state or refuses it.
        self.model.refresh(&mut self.values, None);
        if let Err(msg) = self
            .model
            .restore_state(&s.model, &s.values, &s.experiment, time)
        {
            return self.refuse(&format!("invalid FMU state: {msg}"));
        }
        self.state = s.state;
        self.time = s.time;
        self.last_successful_time = s.last_successful_time;
        self.experiment = s.experiment;
        self.values = s.values.clone();
        self.needs_initialize = s.needs_initialize && !initialized;
        Status::Ok
    }
}
