//! The status every call of the core returns, whatever FMI version the importer speaks. Each FMI
//! layer maps it onto its own status type once (`From<Status>` in its `ffi`); the core never
//! returns FMI 2.0's `fmi2Pending` (no asynchronous steps), so there is nothing to disagree on.

/// The outcome of a call, ordered by severity (the first five statuses of FMI 2.0 and FMI 3.0,
/// which both number them 0 to 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Done as asked.
    Ok,
    /// Done, with something the user should know logged.
    Warning,
    /// Not done, or done with results that should not be used (a discarded step); the instance
    /// can go on from its last good state.
    Discard,
    /// Refused or failed; the instance is in the error state, from which only a reset, the
    /// FMU-state functions, the getters and freeing lead on.
    Error,
    /// The instance cannot go on (a panic caught at the boundary); only freeing it is allowed.
    Fatal,
}
