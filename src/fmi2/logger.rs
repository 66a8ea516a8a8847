//! FMI 2.0's logger callback as the core's [`LogSink`], and the words of FMI 2.0 in the core's
//! messages.

use std::ffi::CString;

use super::ffi::{Fmi2CallbackFunctions, Fmi2Status};
use crate::fmu::instance::Vocabulary;
use crate::fmu::logging::LogSink;
use crate::fmu::Status;

/// FMI 2.0's words in the core's messages.
pub static VOCABULARY: Vocabulary = Vocabulary {
    fatal: "fmi2Fatal",
    free_instance: "fmi2FreeInstance",
    fmu_state: "FMUstate",
    can_get_and_set_fmu_state: "canGetAndSetFMUstate",
};

/// `fmi2CallbackLogger` with the instance name it is called with.
pub struct Fmi2Sink {
    pub callbacks: Fmi2CallbackFunctions,
    pub instance_name: CString,
}

impl Fmi2Sink {
    pub fn new(callbacks: Fmi2CallbackFunctions, instance_name: &str) -> Self {
        Fmi2Sink {
            callbacks,
            instance_name: CString::new(instance_name.replace('\0', " ")).unwrap_or_default(),
        }
    }
}

impl LogSink for Fmi2Sink {
    fn send(&self, status: Status, category: &str, message: &str) {
        let Some(logger) = self.callbacks.logger else {
            return;
        };
        // The logger's message is a printf format. Importers that format it and importers that
        // print it as it is both exist; passing the message itself, with '%' doubled, reads
        // right in the first and nearly right in the second, and never lets a '%' in a message
        // be taken for a conversion.
        let message = CString::new(message.replace('%', "%%")).unwrap_or_default();
        let category = CString::new(category).unwrap_or_default();
        // SAFETY: the importer's callback, with the five fixed arguments of
        // `fmi2CallbackLogger` as NUL-terminated strings that outlive the call, and no variadic
        // arguments (the message contains no conversion).
        unsafe {
            logger(
                self.callbacks.component_environment,
                self.instance_name.as_ptr(),
                Fmi2Status::from(status),
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}
