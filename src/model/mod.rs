//! The assembled model behind the FMU.
pub mod variables;
