//! The assembled model behind the FMU.
