//! The FMI 3.0 C ABI, generic over the same [`FmuModel`](crate::fmi2::FmuModel) as the FMI 2.0
//! layer and sharing its core: the instance and its state machine (with the one table of allowed
//! calls), the argument and value checks, the logger and panic guard, and the FMU-state format.
//! What is FMI-3-specific lives here:
//!
//! - [`ffi`]: the C types of FMI 3.0, written by hand;
//! - [`variables`]: the FMI 3.0 view of the variable table (arrays such as the 12
//!   accelerometers, the independent variable `time`);
//! - [`exports`]: the `fmi3*` entry points and [`export_fmi3!`](crate::export_fmi3).
//!
//! The FMI 3.0 `modelDescription.xml` is written by `modelDescription/fmi3.py` from the FMI 2.0
//! one, and the same binary serves both FMUs.

pub mod exports;
pub mod ffi;
pub mod variables;
