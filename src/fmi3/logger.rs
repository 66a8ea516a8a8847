//! FMI 3.0's `logMessage` callback as the core's [`LogSink`], and the words of FMI 3.0 in the
//! core's messages.

use std::ffi::CString;

use super::ffi::{Fmi3InstanceEnvironment, Fmi3LogMessageCallback, Fmi3Status};
use crate::fmu::instance::Vocabulary;
use crate::fmu::logging::LogSink;
use crate::fmu::Status;

/// FMI 3.0's words in the core's messages.
pub static VOCABULARY: Vocabulary = Vocabulary {
    fatal: "fmi3Fatal",
    free_instance: "fmi3FreeInstance",
    fmu_state: "FMUState",
    can_get_and_set_fmu_state: "canGetAndSetFMUState",
};

/// `fmi3LogMessageCallback` with the environment pointer it is called with (plain text, no
/// instance name).
pub struct Fmi3Sink {
    pub environment: Fmi3InstanceEnvironment,
    pub log_message: Fmi3LogMessageCallback,
}

impl LogSink for Fmi3Sink {
    fn send(&self, status: Status, category: &str, message: &str) {
        let Some(log_message) = self.log_message else {
            return;
        };
        let message = CString::new(message).unwrap_or_default();
        let category = CString::new(category).unwrap_or_default();
        // SAFETY: the importer's callback, with its environment pointer and NUL-terminated
        // strings that outlive the call.
        unsafe {
            log_message(
                self.environment,
                Fmi3Status::from(status),
                category.as_ptr(),
                message.as_ptr(),
            )
        };
    }
}
