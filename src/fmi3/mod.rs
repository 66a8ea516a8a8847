//! The FMI 3.0 C ABI, Co-Simulation and Model Exchange, over the same version-neutral core
//! ([`crate::fmu`]) as the FMI 2.0 layer: the instance and its state machine (with the one table
//! of allowed calls), the argument and value checks, the logger and panic guard, and the
//! FMU-state format are the core's. What is FMI-3-specific lives here:
//!
//! - [`ffi`]: the C types of FMI 3.0, written by hand, and the status map;
//! - [`logger`]: `fmi3LogMessageCallback` as the core's log sink, and FMI 3.0's words in messages;
//! - [`variables`]: the FMI 3.0 view of the variable table (arrays such as the 12
//!   accelerometers, the independent variable `time`);
//! - [`entries`]: the generic entry points, one per FMI 3.0 function;
//! - [`symbols`]: [`export_fmi3!`](crate::export_fmi3), which emits the `fmi3*` symbols;
//! - `component` (built for `wasm32-wasip2` only): the same functions as a WebAssembly component
//!   after the draft layered standard fmi-ls-wasm, its interfaces in `src/fmi3/wit/`.
//!
//! The FMI 3.0 `modelDescription.xml` is written by `modelDescription/fmi3.py` from the FMI 2.0
//! one, and the same binary serves both FMUs.

#[cfg(all(target_arch = "wasm32", target_os = "wasi"))]
pub mod component;
pub mod entries;
pub mod ffi;
pub mod logger;
pub mod symbols;
pub mod variables;
