//! Getting and setting variables: value references resolved and type-checked, setters checked
//! against causality, variability, range and the model's own rules before anything changes, and
//! getters that never hand out a non-finite Real with OK.

use std::ffi::CString;

use super::super::calls::{Interface, MachineState::*, Operation};
use super::super::logging::Short;
use super::super::variables::{check_value, Value};
use super::super::{FmuModel, LogCategory, Status};
use super::Instance;

impl<M: FmuModel> Instance<M> {
    /// Resolves value references to table positions, checking each one's type.
    pub(super) fn resolve(&mut self, vrs: &[u32], type_name: &str) -> Result<Vec<usize>, Status> {
        vrs.iter()
            .map(|&vr| self.resolve_one(vr, type_name))
            .collect()
    }

    /// The table position of one value reference, checking its type.
    fn resolve_one(&mut self, vr: u32, type_name: &str) -> Result<usize, Status> {
        let Some(index) = M::index_of(vr) else {
            return Err(self.refuse(&format!("unknown value reference {vr}")));
        };
        let var = &M::variables()[index];
        if var.kind.value_type() != type_name {
            return Err(self.refuse(&format!(
                "value reference {vr} is '{}', a {}, not a {type_name}",
                var.name,
                var.kind.value_type()
            )));
        }
        Ok(index)
    }

    /// The getters (`fmi2GetReal`, `fmi3GetFloat64` and their siblings) for variables of
    /// `type_name` (the model description's type: Real, Integer, Boolean, String).
    ///
    /// A Real that is not finite is never handed out with OK: the call returns
    /// [`Status::Discard`] with a message naming the variable (and, in Model Exchange, the
    /// continuous state farthest outside its nominal range, which the importer set).
    pub fn get<T>(
        &mut self,
        type_name: &str,
        vrs: &[u32],
        out: &mut [T],
        convert: impl Fn(&Value) -> T,
    ) -> Status {
        if let Err(s) = self.allowed(Operation::GetValues) {
            return s;
        }
        // Every reference is checked before anything is read; then each is looked up again
        // rather than collected, so that a getter called after every step allocates nothing.
        for &vr in vrs {
            if let Err(s) = self.resolve_one(vr, type_name) {
                return s;
            }
        }
        if let Err(s) = self.bring_up_to_date() {
            return s;
        }
        let mut non_finite = None;
        for (slot, &vr) in out.iter_mut().zip(vrs) {
            if let Some(index) = M::index_of(vr) {
                self.model.refresh(&mut self.values, Some(index));
                let value = self.values.get(index);
                if matches!(value, Value::Real(v) if !v.is_finite()) && non_finite.is_none() {
                    non_finite = Some(index);
                }
                *slot = convert(value);
            }
        }
        match non_finite {
            None => Status::Ok,
            Some(index) => self.discard_non_finite(index),
        }
    }

    /// Logs that variable `index` is not finite, with what made it so, and returns
    /// [`Status::Discard`] (the state machine stays where it is: the importer may set other
    /// states, restore an FMU state or reset).
    fn discard_non_finite(&mut self, index: usize) -> Status {
        let f = self.function;
        let name = M::variables()[index].name;
        let value = self.values.real(index);
        let cause = match (self.interface, self.state) {
            (_, Error) => "the instance is in the error state after a failed call".to_string(),
            (_, StepFailed) => format!(
                "the last step was discarded at t = {}",
                Short(self.last_successful_time)
            ),
            (Interface::ModelExchange, _) => self.farthest_state(),
            (Interface::CoSimulation, _) => format!("at t = {}", Short(self.time)),
        };
        self.logger.log(
            Status::Discard,
            LogCategory::StatusDiscard,
            &format!("{f}: {name} = {value} is not finite; {cause}"),
        );
        Status::Discard
    }

    /// Model Exchange: the continuous state the importer set farthest outside its nominal
    /// magnitude, as a sentence for a message.
    fn farthest_state(&mut self) -> String {
        let states = M::continuous_states();
        let mut nominals = vec![1.0; states.len()];
        if self.state != Instantiated {
            self.model.nominals(&mut nominals);
        }
        let ratio = |k: usize| (self.values.real(states[k].0) / nominals[k]).abs();
        let worst = (0..states.len()).max_by(|&a, &b| ratio(a).total_cmp(&ratio(b)));
        match worst {
            Some(k) => {
                let state = states[k].0;
                format!(
                    "the continuous states set by the importer make it so at t = {}: the farthest from its nominal {} is x[{k}] ('{}') = {}",
                    Short(self.time),
                    Short(nominals[k]),
                    M::variables()[state].name,
                    Short(self.values.real(state))
                )
            }
            None => format!("at t = {}", Short(self.time)),
        }
    }

    /// The setters (`fmi2SetReal`, `fmi3SetFloat64` and their siblings). Either every value is set
    /// or none.
    pub fn set(&mut self, type_name: &str, vrs: &[u32], new: Vec<Value>) -> Status {
        if let Err(s) = self.allowed(Operation::SetValues) {
            return s;
        }
        let indices = match self.resolve(vrs, type_name) {
            Ok(i) => i,
            Err(s) => return s,
        };
        let running = matches!(self.state, StepComplete | EventMode | ContinuousTimeMode);
        for (&index, value) in indices.iter().zip(&new) {
            let var = &M::variables()[index];
            let allowed = if running {
                var.settable_during_simulation()
            } else {
                var.settable_before_initialization()
            };
            if !allowed {
                let when = if running {
                    "after initialization"
                } else {
                    "at all"
                };
                return self.refuse(&format!(
                    "variable '{}' (causality {:?}, variability {:?}) cannot be set {when}",
                    var.name, var.causality, var.variability
                ));
            }
            let checked = check_value(var, value).and_then(|_| self.model.check(index, value));
            if let Err(msg) = checked {
                return self.refuse(&msg);
            }
        }
        for (index, value) in indices.into_iter().zip(new) {
            self.values.set(index, value);
        }
        if !running {
            self.needs_initialize = true;
        }
        self.needs_evaluate = true;
        Status::Ok
    }

    /// Before values are read: builds the model in initialisation mode, and in Model Exchange
    /// evaluates it at the current time, states and inputs if any changed.
    pub(super) fn bring_up_to_date(&mut self) -> Result<(), Status> {
        if self.state == InitializationMode {
            self.ensure_initialized()?;
        }
        let evaluated = match self.interface {
            Interface::ModelExchange => {
                matches!(self.state, EventMode | ContinuousTimeMode | Terminated)
            }
            Interface::CoSimulation => false,
        };
        if evaluated && self.needs_evaluate {
            if let Err(msg) = self.model.evaluate(&mut self.values, self.time) {
                return Err(self.refuse(&msg));
            }
            self.needs_evaluate = false;
        }
        Ok(())
    }

    /// The String getter: the pointers stay valid until the next call on this instance.
    pub fn get_strings(&mut self, vrs: &[u32], out: &mut [*const std::os::raw::c_char]) -> Status {
        let mut texts = vec![String::new(); vrs.len()];
        let status = self.get("String", vrs, &mut texts, |v| match v {
            Value::String(s) => s.clone(),
            _ => String::new(),
        });
        if status != Status::Ok {
            return status;
        }
        self.string_buffer = texts
            .into_iter()
            .map(|t| CString::new(t.replace('\0', " ")).unwrap_or_default())
            .collect();
        for (slot, s) in out.iter_mut().zip(&self.string_buffer) {
            *slot = s.as_ptr();
        }
        Status::Ok
    }
}
