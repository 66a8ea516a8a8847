//! No heap allocation per `fmi2DoStep` in the steady state (issue 10): a counting global
//! allocator counts the allocations this thread makes in `fmi2DoStep` and in the `fmi2GetReal`
//! of every Real output after it (what an importer's recorder does) over 100 communication
//! steps after a warm-up, with logging off, through the exported C entry points. Before each
//! step the test also sets an input that changes at every communication point (so every step
//! starts after a zero-order-hold jump), uncounted: the setter still builds its vector of new
//! values, all or none of which it sets. Every configuration
//! of the benchmark's kinds is checked with both methods: a constant Jacobian (the LOES, whose J
//! and factorisations are kept) and one evaluated and factorised at every step (the servo valve).
//!
//! The FMI 3.0 entry point `fmi3DoStep`, a thin layer over the same core, is held to the same rule.
//!
//! The count is per thread (the test harness runs other tests on other threads), and only
//! allocations are counted: a reallocation that grows a buffer counts too.

#[path = "common/fmu.rs"]
mod fmu;
#[path = "common/fmu3.rs"]
mod fmu3;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmi2_exports::{fmi2GetReal, fmi2SetReal};
use hydraulic_slewing_plate::fmu::{Causality, Kind};
use hydraulic_slewing_plate::model::variables::VARIABLES;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
    /// While set, every allocation prints its backtrace (`ZERO_ALLOCATION_TRACE=1`, to find them).
    static TRACE: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    // try_with: the thread-local may be gone while a thread shuts down.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    if TRACE.try_with(|t| t.replace(false)).unwrap_or(false) {
        eprintln!("ALLOCATION {}", std::backtrace::Backtrace::force_capture());
        TRACE.with(|t| t.set(true));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

const STEP: f64 = 1e-3;
const WARM_UP: usize = 300;
const MEASURED: usize = 100;

/// Allocations made by `MEASURED` steps after `WARM_UP` steps of the configuration `sets`
/// (integer and boolean parameters by name) with method `method` (1 Rodas5P, 2 Radau5, 3 the
/// real-time fixed-step Rodas5P).
fn allocations_per_run(sets: &[(&str, i32)], method: i32) -> u64 {
    let fmu = Fmu::new();
    for &(name, v) in sets {
        let status = if name == "controller.saturation" || name == "hydraulics.motor_coupled" {
            fmu.set_boolean(name, v != 0)
        } else {
            fmu.set_integer(name, v)
        };
        assert_eq!(status, Fmi2Status::Ok, "setting {name}");
    }
    assert_eq!(fmu.set_integer("solver.method", method), Fmi2Status::Ok);
    assert_eq!(fmu.init(0.0), Fmi2Status::Ok);
    // Every Real output, fetched after each step as an importer's recorder does.
    let outputs: Vec<u32> = VARIABLES
        .iter()
        .filter(|v| matches!(v.causality, Causality::Output) && matches!(v.kind, Kind::Real { .. }))
        .map(|v| v.value_reference)
        .collect();
    let mut values = vec![0.0; outputs.len()];
    let r = Fmu::vr("r");
    let trace = std::env::var_os("ZERO_ALLOCATION_TRACE").is_some();
    let mut counted = 0;
    for k in 0..WARM_UP + MEASURED {
        let t = k as f64 * STEP;
        // A reference that keeps changing (a new input at every communication point).
        let u = if k == 0 {
            1.0
        } else {
            1.0 + 0.1 * (t * 7.0).sin()
        };
        let status = unsafe { fmi2SetReal(fmu.c, &r, 1, &u) };
        assert_eq!(status, Fmi2Status::Ok);
        let measure = k >= WARM_UP;
        let before = allocations();
        TRACE.with(|t| t.set(trace && measure));
        let step = fmu.step(t, STEP);
        let get =
            unsafe { fmi2GetReal(fmu.c, outputs.as_ptr(), outputs.len(), values.as_mut_ptr()) };
        TRACE.with(|t| t.set(false));
        if measure {
            counted += allocations() - before;
        }
        assert_eq!(step, Fmi2Status::Ok, "step {k}");
        assert_eq!(get, Fmi2Status::Ok);
    }
    counted
}

const LOES_COUPLED: &[(&str, i32)] = &[
    ("hydraulics.model", 1),
    ("controller.saturation", 0),
    ("hydraulics.motor_coupled", 1),
];
const SERVO_VALVE_COUPLED: &[(&str, i32)] =
    &[("hydraulics.model", 2), ("hydraulics.motor_coupled", 1)];

#[test]
fn loes_coupled_steps_without_allocating() {
    for method in [1, 2] {
        let n = allocations_per_run(LOES_COUPLED, method);
        assert_eq!(n, 0, "method {method}: {n} allocations in {MEASURED} steps");
    }
}

#[test]
fn servo_valve_coupled_steps_without_allocating() {
    for method in [1, 2] {
        let n = allocations_per_run(SERVO_VALVE_COUPLED, method);
        assert_eq!(n, 0, "method {method}: {n} allocations in {MEASURED} steps");
    }
}

/// The real-time method (`solver.method = 3`) with 4 fixed substeps per communication step: its
/// step allocates nothing either, for a constant Jacobian and for one refactorised at every step.
#[test]
fn real_time_method_steps_without_allocating() {
    for config in [LOES_COUPLED, SERVO_VALVE_COUPLED] {
        let sets: Vec<(&str, i32)> = config
            .iter()
            .copied()
            .chain([("solver.substeps", 4)])
            .collect();
        let n = allocations_per_run(&sets, 3);
        assert_eq!(n, 0, "{config:?}: {n} allocations in {MEASURED} steps");
    }
}

#[test]
fn the_counter_sees_allocations() {
    // The test above could pass with a counter that never counts: it must see this one.
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 100]);
    assert!(allocations() > before);
    drop(v);
}

#[test]
fn fmi3_do_step_does_not_allocate_either() {
    use hydraulic_slewing_plate::fmi3::ffi::Fmi3Status;
    let fmu = fmu3::Fmu3::new();
    assert_eq!(fmu.set_integer("hydraulics.model", 2), Fmi3Status::Ok);
    assert_eq!(fmu.init(0.0), Fmi3Status::Ok);
    let mut counted = 0;
    for k in 0..WARM_UP + MEASURED {
        let t = k as f64 * STEP;
        assert_eq!(
            fmu.set_real("r", 1.0 + 0.1 * (t * 7.0).sin()),
            Fmi3Status::Ok
        );
        let before = allocations();
        let step = fmu.step(t, STEP);
        if k >= WARM_UP {
            counted += allocations() - before;
        }
        assert_eq!(step, Fmi3Status::Ok, "step {k}");
    }
    assert_eq!(
        counted, 0,
        "{counted} allocations in {MEASURED} fmi3DoStep calls"
    );
}
