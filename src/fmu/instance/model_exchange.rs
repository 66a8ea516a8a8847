//! Model Exchange: the time, the continuous states, their derivatives and nominals, and the event
//! modes (FMI 2.0.4 section 3.2; FMI 3.0 section 3.2). The model has no event indicators and no
//! discrete states: its limits are smooth laws.

use super::super::calls::{MachineState::*, Operation};
use super::super::logging::Short;
use super::super::{FmuModel, LogCategory, Status};
use super::Instance;

/// What the event update tells the importer (`fmi2EventInfo`; the out-arguments of
/// `fmi3UpdateDiscreteStates`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventInfo {
    pub discrete_states_need_update: bool,
    pub terminate_simulation: bool,
    pub nominals_of_continuous_states_changed: bool,
    pub values_of_continuous_states_changed: bool,
    /// The time of the next time event, if there is one.
    pub next_event_time: Option<f64>,
}

impl<M: FmuModel> Instance<M> {
    /// Checks that an array argument (named `what` in the called function) has as many elements
    /// as the model has continuous states.
    fn check_state_count(&mut self, what: &str, n: usize) -> Result<(), Status> {
        let nx = M::continuous_states().len();
        if n == nx {
            Ok(())
        } else {
            Err(self.refuse(&format!(
                "argument '{what}' has {n} elements, but the model has {nx} continuous states"
            )))
        }
    }

    /// Sets the time.
    pub fn set_time(&mut self, time: f64) -> Status {
        if let Err(s) = self.allowed(Operation::SetTime) {
            return s;
        }
        if !time.is_finite() {
            return self.refuse(&format!("time {} is not finite", Short(time)));
        }
        self.time = time;
        self.last_successful_time = time;
        self.needs_evaluate = true;
        Status::Ok
    }

    /// Sets the continuous states (the argument named `what`): every state is set, or none.
    pub fn set_continuous_states(&mut self, what: &str, x: &[f64]) -> Status {
        if let Err(s) = self.allowed(Operation::SetContinuousStates) {
            return s;
        }
        if let Err(s) = self.check_state_count(what, x.len()) {
            return s;
        }
        let states = M::continuous_states();
        if let Some((k, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            let name = M::variables()[states[k].0].name;
            return self.refuse(&format!("{what}[{k}] ('{name}') = {v} is not finite"));
        }
        for (&(state, _), &v) in states.iter().zip(x) {
            self.values.set_real(state, v);
        }
        self.needs_evaluate = true;
        Status::Ok
    }

    /// Reads the continuous states into `x` (the argument named `what`).
    pub fn continuous_states(&mut self, what: &str, x: &mut [f64]) -> Status {
        if let Err(s) = self.allowed(Operation::GetContinuousStates) {
            return s;
        }
        if let Err(s) = self.check_state_count(what, x.len()) {
            return s;
        }
        if let Err(s) = self.bring_up_to_date() {
            return s;
        }
        for (slot, &(state, _)) in x.iter_mut().zip(M::continuous_states()) {
            *slot = self.values.real(state);
        }
        Status::Ok
    }

    /// Reads the state derivatives into `dx` (the argument named `what`), as `operation` allows
    /// (FMI 3.0 allows them in initialization mode too): [`Status::Discard`] when a derivative is
    /// not finite (the importer's solver should retry with a smaller step, FMI 2.0.4 section
    /// 2.1.3).
    pub fn derivatives(&mut self, operation: Operation, what: &str, dx: &mut [f64]) -> Status {
        if let Err(s) = self.allowed(operation) {
            return s;
        }
        if let Err(s) = self.check_state_count(what, dx.len()) {
            return s;
        }
        if let Err(s) = self.bring_up_to_date() {
            return s;
        }
        if self.state == InitializationMode {
            // The initial point: the model built from the parameters, at the start time.
            if let Err(msg) = self.model.evaluate(&mut self.values, self.time) {
                return self.refuse(&msg);
            }
            self.needs_evaluate = false;
        }
        for (slot, &(_, derivative)) in dx.iter_mut().zip(M::continuous_states()) {
            *slot = self.values.real(derivative);
        }
        if let Some(k) = dx.iter().position(|d| !d.is_finite()) {
            let f = self.function;
            let name = M::variables()[M::continuous_states()[k].1].name;
            self.logger.log(
                Status::Discard,
                LogCategory::StatusDiscard,
                &format!(
                    "{f}: {name} = {} is not finite at t = {}; retry with a smaller step",
                    dx[k],
                    Short(self.time)
                ),
            );
            return Status::Discard;
        }
        Status::Ok
    }

    /// The nominal value of each continuous state, into `out` (the argument named `what`): 1
    /// before the model is built (its nominals follow from the parameters), the model's nominals
    /// after.
    pub fn nominals_of_continuous_states(&mut self, what: &str, out: &mut [f64]) -> Status {
        if let Err(s) = self.allowed(Operation::GetNominals) {
            return s;
        }
        if let Err(s) = self.check_state_count(what, out.len()) {
            return s;
        }
        if self.state == Instantiated {
            out.fill(1.0);
        } else {
            self.model.nominals(out);
        }
        Status::Ok
    }

    /// The event indicators (the argument named `what`, `n` of them): the model has none.
    pub fn event_indicators(&mut self, what: &str, n: usize) -> Status {
        if let Err(s) = self.allowed(Operation::GetContinuousStates) {
            return s;
        }
        if n != 0 {
            return self.refuse(&format!(
                "argument '{what}' is {n}, but the model has no event indicators (numberOfEventIndicators = 0)"
            ));
        }
        Status::Ok
    }

    /// Enters event mode.
    pub fn enter_event_mode(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::EnterEventMode) {
            return s;
        }
        self.state = EventMode;
        Status::Ok
    }

    /// The event update: the model has no discrete states and no time events, so nothing
    /// changes.
    pub fn update_discrete_states(&mut self) -> Result<EventInfo, Status> {
        self.allowed(Operation::NewDiscreteStates)?;
        Ok(EventInfo::default())
    }

    /// Enters continuous-time mode.
    pub fn enter_continuous_time_mode(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::EnterContinuousTimeMode) {
            return s;
        }
        self.state = ContinuousTimeMode;
        Status::Ok
    }

    /// The end of an integrator step: `(enterEventMode, terminateSimulation)`, never either (no
    /// step events, no end the model asks for).
    pub fn completed_integrator_step(&mut self) -> Result<(bool, bool), Status> {
        self.allowed(Operation::CompletedIntegratorStep)?;
        Ok((false, false))
    }
}
