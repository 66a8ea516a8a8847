//! The FMI 2.0 C ABI, Co-Simulation and Model Exchange, over the version-neutral core
//! ([`crate::fmu`]): FMI 2.0's C types, its arguments turned into the core's, and the exported
//! symbols; nothing else. A model implementing [`FmuModel`](crate::fmu::FmuModel) is exported
//! by [`export_fmi2_cosimulation!`](crate::export_fmi2_cosimulation).
//!
//! - [`ffi`]: the C types, written by hand, and the status map.
//! - [`logger`]: `fmi2CallbackLogger` as the core's log sink, and FMI 2.0's words in messages.
//! - [`entries`]: the generic entry points, one per FMI 2.0 function.
//! - [`symbols`]: the macro that emits the `fmi2*` symbols.

pub mod entries;
pub mod ffi;
pub mod logger;
pub mod symbols;
