//! The C types of FMI 3.0 (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`), written by hand.

use std::os::raw::{c_char, c_void};

use crate::fmu::Status;

pub type Fmi3Instance = *mut c_void;
pub type Fmi3InstanceEnvironment = *mut c_void;
pub type Fmi3FmuState = *mut c_void;
pub type Fmi3ValueReference = u32;
pub type Fmi3Float32 = f32;
pub type Fmi3Float64 = f64;
pub type Fmi3Int8 = i8;
pub type Fmi3UInt8 = u8;
pub type Fmi3Int16 = i16;
pub type Fmi3UInt16 = u16;
pub type Fmi3Int32 = i32;
pub type Fmi3UInt32 = u32;
pub type Fmi3Int64 = i64;
pub type Fmi3UInt64 = u64;
/// C's `bool`, one byte (unlike FMI 2.0's `int`), taken as the byte the caller passed: a Rust
/// `bool` holding any byte other than 0 or 1 is undefined behaviour, and C code can pass one (a
/// `bool` filled from an integer, a struct's padding). Every scalar Boolean argument of the
/// `fmi3*` functions has this type and is read with [`truthy`].
pub type Fmi3Boolean = u8;

/// C's truthiness: any nonzero byte is true.
pub fn truthy(b: Fmi3Boolean) -> bool {
    b != 0
}
pub type Fmi3Char = c_char;
pub type Fmi3String = *const c_char;
pub type Fmi3Byte = u8;
pub type Fmi3Binary = *const u8;
pub type Fmi3Clock = bool;

/// `fmi3Status`, ordered by severity; the same numbers as FMI 2.0's first five.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Fmi3Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

/// `fmi3DependencyKind`.
pub type Fmi3DependencyKind = std::os::raw::c_int;
/// `fmi3IntervalQualifier`.
pub type Fmi3IntervalQualifier = std::os::raw::c_int;

/// `fmi3LogMessageCallback`. Unlike FMI 2.0's logger it is not variadic and gets no instance
/// name: the message is plain text.
pub type Fmi3LogMessageCallback = Option<
    unsafe extern "C" fn(
        environment: Fmi3InstanceEnvironment,
        status: Fmi3Status,
        category: Fmi3String,
        message: Fmi3String,
    ),
>;

/// `fmi3IntermediateUpdateCallback` (never called: `providesIntermediateUpdate` is false).
pub type Fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        Fmi3InstanceEnvironment,
        Fmi3Float64,
        Fmi3Boolean,
        Fmi3Boolean,
        Fmi3Boolean,
        Fmi3Boolean,
        *mut Fmi3Boolean,
        *mut Fmi3Float64,
    ),
>;

/// `fmi3ClockUpdateCallback` (scheduled execution, not offered).
pub type Fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(Fmi3InstanceEnvironment)>;
/// `fmi3LockPreemptionCallback` and `fmi3UnlockPreemptionCallback` (scheduled execution).
pub type Fmi3PreemptionCallback = Option<unsafe extern "C" fn()>;

/// The FMI 3.0 status of the core's status (the same five numbers).
impl From<Status> for Fmi3Status {
    fn from(s: Status) -> Self {
        match s {
            Status::Ok => Fmi3Status::Ok,
            Status::Warning => Fmi3Status::Warning,
            Status::Discard => Fmi3Status::Discard,
            Status::Error => Fmi3Status::Error,
            Status::Fatal => Fmi3Status::Fatal,
        }
    }
}
