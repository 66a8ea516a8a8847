//! The one table of which call is allowed in which state, in the manner of the Modelica Reference
//! FMUs' `MASK_fmi2*` defines: each state is a bit, each operation has a mask of the states it is
//! allowed in, and [`Instance::allowed`](super::instance::Instance::allowed) is the only place that
//! consults it.
//!
//! The states and operations are named for what they are, not for an FMI version: FMI 2.0
//! co-simulation (section 4.2.4 of FMI 2.0.4, figure 9 and its table) uses the step states, FMI
//! 2.0 Model Exchange (section 3.2.3, figure 6 and its table) the event and continuous-time modes;
//! both share the rules that are the same in every version (getters after instantiation, setters
//! not after termination, nothing after a fatal error but freeing the instance). An FMI 3.0 layer
//! adds its own states (configuration mode, say) as further bits and its own rows.
//!
//! Which interface an operation belongs to is a second, separate rule ([`Operation::interface`]):
//! an instance made for Model Exchange refuses `fmi2DoStep`, one made for co-simulation refuses
//! `fmi2SetTime`, before the state is looked at.

use serde::{Deserialize, Serialize};

/// The states of an FMU instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MachineState {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
    /// Model Exchange: discrete states may change (after initialisation and at events).
    EventMode,
    /// Model Exchange: the importer's solver integrates the continuous states.
    ContinuousTimeMode,
}

impl MachineState {
    pub const ALL: [MachineState; 9] = [
        MachineState::Instantiated,
        MachineState::InitializationMode,
        MachineState::StepComplete,
        MachineState::StepFailed,
        MachineState::EventMode,
        MachineState::ContinuousTimeMode,
        MachineState::Terminated,
        MachineState::Error,
        MachineState::Fatal,
    ];

    /// The state's name in log messages.
    pub fn name(self) -> &'static str {
        match self {
            MachineState::Instantiated => "instantiated",
            MachineState::InitializationMode => "initialization mode",
            MachineState::StepComplete => "step complete",
            MachineState::StepFailed => "step failed",
            MachineState::Terminated => "terminated",
            MachineState::Error => "error",
            MachineState::Fatal => "fatal",
            MachineState::EventMode => "event mode",
            MachineState::ContinuousTimeMode => "continuous-time mode",
        }
    }

    /// The state's bit in a [`StateMask`].
    pub const fn bit(self) -> StateMask {
        StateMask(1 << self as u16)
    }
}

/// A set of [`MachineState`]s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateMask(u16);

impl StateMask {
    pub const fn contains(self, state: MachineState) -> bool {
        self.0 & state.bit().0 != 0
    }

    const fn or(self, other: StateMask) -> StateMask {
        StateMask(self.0 | other.0)
    }
}

use MachineState::*;

const INSTANTIATED: StateMask = Instantiated.bit();
const INITIALIZATION_MODE: StateMask = InitializationMode.bit();
const STEP_COMPLETE: StateMask = StepComplete.bit();
const STEP_FAILED: StateMask = StepFailed.bit();
const TERMINATED: StateMask = Terminated.bit();
const ERROR: StateMask = Error.bit();
const EVENT_MODE: StateMask = EventMode.bit();
const CONTINUOUS_TIME_MODE: StateMask = ContinuousTimeMode.bit();
/// Model Exchange after initialisation, before termination.
const ME_RUNNING: StateMask = EVENT_MODE.or(CONTINUOUS_TIME_MODE);

/// Every state but fatal (the Reference FMUs' `MASK_fmi2SetDebugLogging`).
const NOT_FATAL: StateMask = INSTANTIATED
    .or(INITIALIZATION_MODE)
    .or(STEP_COMPLETE)
    .or(STEP_FAILED)
    .or(ME_RUNNING)
    .or(TERMINATED)
    .or(ERROR);
/// Where values can be read: once initialisation mode is entered, and on after an error.
const READABLE: StateMask = INITIALIZATION_MODE
    .or(STEP_COMPLETE)
    .or(STEP_FAILED)
    .or(ME_RUNNING)
    .or(TERMINATED)
    .or(ERROR);
/// Where the status of the last step can be asked for.
const AFTER_A_STEP: StateMask = STEP_COMPLETE.or(STEP_FAILED).or(TERMINATED);

/// The operations of the FMI C API that depend on the state. The exported function names map onto
/// these (several functions of a version may share one operation, e.g. all getters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operation {
    SetDebugLogging,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    /// `fmi2GetReal` and its siblings.
    GetValues,
    /// `fmi2SetReal` and its siblings (which variables may be set in which state is a further
    /// rule of the variable's causality and variability).
    SetValues,
    /// `fmi2GetFMUstate`, `fmi2SetFMUstate`, `fmi2FreeFMUstate`, `fmi2SerializedFMUstateSize`,
    /// `fmi2SerializeFMUstate`, `fmi2DeSerializeFMUstate`.
    FmuState,
    DoStep,
    /// `fmi2GetRealStatus`, `fmi2GetBooleanStatus`.
    GetStatus,
    /// `fmi2GetDirectionalDerivative`.
    DirectionalDerivative,
    /// `fmi2SetTime`.
    SetTime,
    /// `fmi2SetContinuousStates`.
    SetContinuousStates,
    /// `fmi2GetContinuousStates`, `fmi2GetEventIndicators`.
    GetContinuousStates,
    /// `fmi2GetDerivatives`.
    GetDerivatives,
    /// `fmi3GetContinuousStateDerivatives`: the derivatives where FMI 3.0 allows them, in
    /// initialization mode too (FMI 3.0, section 2.3.3, "State: Initialization Mode").
    GetDerivativesWithInitialization,
    /// `fmi2GetNominalsOfContinuousStates`.
    GetNominals,
    /// `fmi2EnterEventMode`.
    EnterEventMode,
    /// `fmi2NewDiscreteStates`.
    NewDiscreteStates,
    /// `fmi2EnterContinuousTimeMode`.
    EnterContinuousTimeMode,
    /// `fmi2CompletedIntegratorStep`.
    CompletedIntegratorStep,
    /// A function the FMU does not support; it answers with an error in every state.
    Unsupported,
}

/// The interface an FMU instance was made for (`fmi2Instantiate`'s `fmuType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Interface {
    ModelExchange,
    CoSimulation,
}

impl Interface {
    /// The name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Interface::ModelExchange => "Model Exchange",
            Interface::CoSimulation => "Co-Simulation",
        }
    }
}

impl Operation {
    /// The states the operation is allowed in (FMI 2.0.4, the tables of sections 3.2.3 and
    /// 4.2.4; the Reference FMUs' `MASK_fmi2*`).
    pub const fn allowed_in(self) -> StateMask {
        match self {
            Operation::SetDebugLogging | Operation::Reset | Operation::FmuState => NOT_FATAL,
            Operation::SetupExperiment | Operation::EnterInitializationMode => INSTANTIATED,
            Operation::ExitInitializationMode => INITIALIZATION_MODE,
            Operation::Terminate => STEP_COMPLETE.or(STEP_FAILED).or(ME_RUNNING),
            Operation::GetValues => READABLE,
            Operation::SetValues => INSTANTIATED
                .or(INITIALIZATION_MODE)
                .or(STEP_COMPLETE)
                .or(ME_RUNNING),
            Operation::DoStep => STEP_COMPLETE,
            Operation::GetStatus => AFTER_A_STEP,
            Operation::DirectionalDerivative => READABLE,
            Operation::SetTime => ME_RUNNING,
            Operation::SetContinuousStates | Operation::CompletedIntegratorStep => {
                CONTINUOUS_TIME_MODE
            }
            Operation::GetContinuousStates => {
                INITIALIZATION_MODE.or(ME_RUNNING).or(TERMINATED).or(ERROR)
            }
            Operation::GetDerivatives => ME_RUNNING.or(TERMINATED).or(ERROR),
            Operation::GetDerivativesWithInitialization => {
                INITIALIZATION_MODE.or(ME_RUNNING).or(TERMINATED).or(ERROR)
            }
            Operation::GetNominals => INSTANTIATED.or(ME_RUNNING).or(TERMINATED).or(ERROR),
            Operation::EnterEventMode => ME_RUNNING,
            Operation::NewDiscreteStates | Operation::EnterContinuousTimeMode => EVENT_MODE,
            Operation::Unsupported => NOT_FATAL,
        }
    }

    /// The one interface the operation belongs to, `None` for those of both.
    pub const fn interface(self) -> Option<Interface> {
        match self {
            Operation::DoStep | Operation::GetStatus => Some(Interface::CoSimulation),
            Operation::SetTime
            | Operation::SetContinuousStates
            | Operation::GetContinuousStates
            | Operation::GetDerivatives
            | Operation::GetDerivativesWithInitialization
            | Operation::GetNominals
            | Operation::EnterEventMode
            | Operation::NewDiscreteStates
            | Operation::EnterContinuousTimeMode
            | Operation::CompletedIntegratorStep => Some(Interface::ModelExchange),
            _ => None,
        }
    }

    /// Every operation, for the tests of the table.
    pub const ALL: [Operation; 23] = [
        Operation::SetDebugLogging,
        Operation::SetupExperiment,
        Operation::EnterInitializationMode,
        Operation::ExitInitializationMode,
        Operation::Terminate,
        Operation::Reset,
        Operation::GetValues,
        Operation::SetValues,
        Operation::FmuState,
        Operation::DoStep,
        Operation::GetStatus,
        Operation::DirectionalDerivative,
        Operation::SetTime,
        Operation::SetContinuousStates,
        Operation::GetContinuousStates,
        Operation::GetDerivatives,
        Operation::GetDerivativesWithInitialization,
        Operation::GetNominals,
        Operation::EnterEventMode,
        Operation::NewDiscreteStates,
        Operation::EnterContinuousTimeMode,
        Operation::CompletedIntegratorStep,
        Operation::Unsupported,
    ];
}

/// The states an FMU state may have been taken in and be restored to: a state saved in the error
/// state cannot be continued, and none can be saved in the fatal state.
pub const RESTORABLE: StateMask = INSTANTIATED
    .or(INITIALIZATION_MODE)
    .or(STEP_COMPLETE)
    .or(STEP_FAILED)
    .or(TERMINATED);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_but_freeing_after_fatal() {
        for op in Operation::ALL {
            assert!(!op.allowed_in().contains(Fatal), "{op:?}");
        }
    }

    #[test]
    fn after_an_error_only_reset_fmu_states_and_getters() {
        let allowed: Vec<_> = [
            Operation::SetupExperiment,
            Operation::EnterInitializationMode,
            Operation::ExitInitializationMode,
            Operation::Terminate,
            Operation::SetValues,
            Operation::DoStep,
            Operation::GetStatus,
            Operation::SetTime,
            Operation::SetContinuousStates,
            Operation::EnterEventMode,
            Operation::NewDiscreteStates,
            Operation::EnterContinuousTimeMode,
            Operation::CompletedIntegratorStep,
        ]
        .into_iter()
        .filter(|op| op.allowed_in().contains(Error))
        .collect();
        assert!(allowed.is_empty(), "{allowed:?}");
        assert!(Operation::Reset.allowed_in().contains(Error));
        assert!(Operation::FmuState.allowed_in().contains(Error));
    }

    /// The Model Exchange modes of FMI 2.0.4, figure 6: states are set only in continuous-time
    /// mode, the time in either mode, and the modes lead into each other.
    #[test]
    fn model_exchange_modes() {
        assert!(!Operation::SetContinuousStates
            .allowed_in()
            .contains(EventMode));
        assert!(Operation::SetTime.allowed_in().contains(EventMode));
        assert!(Operation::SetTime.allowed_in().contains(ContinuousTimeMode));
        assert!(Operation::EnterContinuousTimeMode
            .allowed_in()
            .contains(EventMode));
        assert!(!Operation::EnterContinuousTimeMode
            .allowed_in()
            .contains(ContinuousTimeMode));
        assert!(!Operation::DoStep.allowed_in().contains(ContinuousTimeMode));
        assert_eq!(Operation::DoStep.interface(), Some(Interface::CoSimulation));
        assert_eq!(
            Operation::GetDerivatives.interface(),
            Some(Interface::ModelExchange)
        );
        assert_eq!(Operation::DirectionalDerivative.interface(), None);
    }

    #[test]
    fn each_state_has_its_own_bit() {
        let all = MachineState::ALL;
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert!(!a.bit().contains(*b));
            }
            assert!(a.bit().contains(*a));
        }
    }
}
