//! Instances of the FMU are independent of each other, whatever thread runs them.
//!
//! The tests drive the exported FMI 2.0 C functions in-process, exactly as an importer that has
//! loaded the library would, and prove that
//! * 64 instances stepped concurrently from 8 threads (8 instances each, stepped interleaved, with
//!   different `r` and `controller.A1`) produce, bit for bit, the `y_pot` trajectory of the same
//!   experiment run alone on one thread: no shared mutable state, no thread-dependent arithmetic;
//! * two instances interleaved on one thread, one created late and freed early, do not affect
//!   each other.

use std::ffi::{c_void, CString};
use std::os::raw::c_char;
use std::sync::Barrier;

use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::model::variables::{vr, GUID};

// The library's exported `fmi2*` entry points (`#[no_mangle] extern "C"`), called as an importer
// that has loaded the library would.
use hydraulic_slewing_plate::fmi2_exports::{
    fmi2DoStep, fmi2EnterInitializationMode, fmi2ExitInitializationMode, fmi2FreeInstance,
    fmi2GetReal, fmi2Instantiate, fmi2SetReal, fmi2SetupExperiment, fmi2Terminate,
};

/// Communication step and number of steps: 0.2 s in 1 ms steps.
const H: f64 = 1e-3;
const STEPS: usize = 200;

/// FMI's logger is variadic, which stable Rust cannot define; this FMU passes its message as the
/// format with no further arguments, so a five-argument function receives all of it.
unsafe extern "C" fn logger(
    _env: *mut c_void,
    _name: *const c_char,
    status: Fmi2Status,
    _category: *const c_char,
    message: *const c_char,
) {
    if !message.is_null() {
        let m = std::ffi::CStr::from_ptr(message).to_string_lossy();
        eprintln!("FMU {status:?}: {m}");
    }
}

fn callbacks() -> Fmi2CallbackFunctions {
    Fmi2CallbackFunctions::with_plain_logger(logger, std::ptr::null_mut())
}

fn ok(status: Fmi2Status, what: &str) {
    assert_eq!(status, Fmi2Status::Ok, "{what}");
}

/// One experiment: reference `r` [V] and error amplifier gain `controller.A1`.
#[derive(Clone, Copy, Debug)]
struct Config {
    r: f64,
    a1: f64,
}

/// The 64 experiments: every one differs from the others in `r`, `A1` or both.
fn configs() -> Vec<Config> {
    (0..64)
        .map(|i| Config {
            // Never 0: a zero reference would give y = 0 whatever A1 is.
            r: (0.2 + 0.2 * (i % 9) as f64) * if i % 2 == 0 { 1.0 } else { -1.0 },
            a1: 1.0 + 0.125 * (i / 4) as f64,
        })
        .collect()
}

/// An initialised co-simulation instance, freed on drop. Not `Send` (it holds a raw pointer),
/// so every instance lives and dies on the thread that created it.
struct Sim {
    c: Fmi2Component,
    t: f64,
}

impl Sim {
    fn new(name: &str, cfg: Config) -> Sim {
        let cb = callbacks();
        let name = CString::new(name).unwrap();
        let guid = CString::new(GUID).unwrap();
        // SAFETY: valid NUL-terminated strings and callbacks; the FMU copies what it keeps.
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                std::ptr::null(),
                &cb,
                FMI2_FALSE,
                FMI2_FALSE,
            )
        };
        assert!(!c.is_null(), "fmi2Instantiate returned NULL");
        let sim = Sim { c, t: 0.0 };
        sim.set(vr::CONTROLLER_A1, cfg.a1);
        // SAFETY: `c` is a live instance.
        unsafe {
            ok(
                fmi2SetupExperiment(c, FMI2_FALSE, 0.0, 0.0, FMI2_TRUE, STEPS as f64 * H),
                "fmi2SetupExperiment",
            );
            ok(
                fmi2EnterInitializationMode(c),
                "fmi2EnterInitializationMode",
            );
        }
        sim.set(vr::R, cfg.r);
        // SAFETY: as above.
        unsafe { ok(fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode") };
        sim
    }

    fn set(&self, vr: u32, v: f64) {
        // SAFETY: one value reference, one value.
        ok(unsafe { fmi2SetReal(self.c, &vr, 1, &v) }, "fmi2SetReal");
    }

    fn get(&self, vr: u32) -> f64 {
        let mut v = f64::NAN;
        // SAFETY: one value reference, one value.
        ok(
            unsafe { fmi2GetReal(self.c, &vr, 1, &mut v) },
            "fmi2GetReal",
        );
        v
    }

    /// One communication step; returns `y_pot` at its end.
    fn step(&mut self) -> f64 {
        // SAFETY: `c` is a live, initialised instance.
        ok(
            unsafe { fmi2DoStep(self.c, self.t, H, FMI2_TRUE) },
            "fmi2DoStep",
        );
        // The next communication point as an importer computes it: a multiple of H, not a sum.
        self.t = H * ((self.t / H).round() + 1.0);
        self.get(vr::Y_POT)
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        // SAFETY: `c` is live and freed exactly once.
        unsafe {
            fmi2Terminate(self.c);
            fmi2FreeInstance(self.c);
        }
    }
}

/// The reference: the experiment alone, start to end, on the calling thread.
fn alone(cfg: Config) -> Vec<f64> {
    let mut sim = Sim::new("alone", cfg);
    (0..STEPS).map(|_| sim.step()).collect()
}

fn bits(y: &[f64]) -> Vec<u64> {
    y.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn sixty_four_instances_on_eight_threads_match_single_threaded_runs() {
    let configs = configs();
    let reference: Vec<Vec<f64>> = configs.iter().map(|&c| alone(c)).collect();

    // Different parameters must give different trajectories, or the comparison proves little.
    let finals: std::collections::HashSet<u64> =
        reference.iter().map(|y| y[STEPS - 1].to_bits()).collect();
    assert_eq!(
        finals.len(),
        configs.len(),
        "experiments are not all distinct"
    );

    let threads = 8;
    let per_thread = configs.len() / threads;
    // All threads step at the same time, to maximise the overlap of the instances' work.
    let barrier = Barrier::new(threads);
    let concurrent: Vec<Vec<f64>> = std::thread::scope(|s| {
        let handles: Vec<_> = configs
            .chunks(per_thread)
            .enumerate()
            .map(|(k, chunk)| {
                let barrier = &barrier;
                s.spawn(move || {
                    let mut sims: Vec<Sim> = chunk
                        .iter()
                        .enumerate()
                        .map(|(j, &c)| Sim::new(&format!("t{k}i{j}"), c))
                        .collect();
                    let mut out = vec![Vec::with_capacity(STEPS); sims.len()];
                    barrier.wait();
                    // Interleaved: every instance advances one step before any takes the next.
                    for _ in 0..STEPS {
                        for (sim, y) in sims.iter_mut().zip(out.iter_mut()) {
                            y.push(sim.step());
                        }
                    }
                    out
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a stepping thread panicked"))
            .collect()
    });

    assert_eq!(concurrent.len(), reference.len());
    for (i, (c, r)) in concurrent.iter().zip(&reference).enumerate() {
        assert_eq!(
            bits(c),
            bits(r),
            "instance {i} ({:?}) differs from its single-threaded run",
            configs[i]
        );
    }
}

#[test]
fn two_interleaved_instances_on_one_thread_do_not_affect_each_other() {
    let ca = Config { r: 1.0, a1: 2.0 };
    let cb = Config { r: -0.7, a1: 3.0 };
    let (ya_ref, yb_ref) = (alone(ca), alone(cb));

    let mut a = Sim::new("a", ca);
    let mut ya = Vec::with_capacity(STEPS);
    // A runs alone for a while, so B is born while A is mid-simulation.
    for _ in 0..50 {
        ya.push(a.step());
    }
    let mut b = Sim::new("b", cb);
    let mut yb = Vec::with_capacity(STEPS);
    for _ in 50..150 {
        ya.push(a.step());
        yb.push(b.step());
        // Reads of the other instance between steps must not disturb it either.
        let _ = (a.get(vr::P_LOAD), b.get(vr::Q_VALVE));
    }
    // B runs ahead alone, then A finishes after B is freed.
    for _ in 100..STEPS {
        yb.push(b.step());
    }
    drop(b);
    for _ in 150..STEPS {
        ya.push(a.step());
    }

    assert_eq!(bits(&ya), bits(&ya_ref), "instance a was disturbed by b");
    assert_eq!(bits(&yb), bits(&yb_ref), "instance b was disturbed by a");
    assert_ne!(bits(&ya), bits(&yb));
}
